//! One scenario through a [`Controller`]: the job it is given, the inputs at fixed times, then
//! advance and read in turn, stepping from trigger to trigger. An input on a condition (`when:`)
//! is given when the controller reports that the condition began to hold for the n-th time:
//! the controller stops right after the event that made it hold, so the input acts at its exact
//! time (`delay` after it) on the controller's own behaviour.

use std::path::Path;

use nc_engine::input::{Condition, Input, Trigger};
use nc_engine::trace::{Event, Trace, TraceEvent, TraceMeta};
use nc_engine::units::Micros;

use super::{Controller, ControllerError, ErrorKind, Job, Loaded, ParamValue};
use crate::diag::InputError;
use crate::scenario::load::Scenario;
use crate::scenario::schema::ScenarioFile;

/// Most advances of one scenario (a controller that never ends nor moves on is cut off).
pub const MAX_STEPS: usize = 100_000;

/// The program text of a scenario file: inline, or from its `program_file`.
///
/// # Errors
///
/// The file or its program file cannot be read or parsed.
pub fn program_text(path: &Path, name: &str) -> Result<String, InputError> {
    let bytes = crate::input::read_capped(path, crate::input::YAML).map_err(|m| InputError::new(name, m))?;
    let text = String::from_utf8(bytes)
        .map_err(|_| InputError::new(name, "cannot read: stream did not contain valid UTF-8"))?;
    let options = serde_saphyr::options! { strict_booleans: true, with_snippet: false };
    let file: ScenarioFile = serde_saphyr::from_str_with_options(&text, options).map_err(|e| {
        let pe = crate::params_yaml::yaml_error(&text, &e);
        let message = pe.message.replacen("invalid parameter file", "invalid scenario", 1);
        InputError::at(name, &text, pe.span, message, pe.expected)
    })?;
    match (file.program, file.program_file) {
        (Some(p), _) => Ok(p.value),
        (None, Some(f)) => {
            let p = path.parent().unwrap_or(Path::new(".")).join(&f.value);
            crate::input::read_capped(&p, crate::input::PROGRAM)
                .map(crate::input::lossy_text)
                .map_err(|e| InputError::new(name, format!("program file {}: {e}", p.display())))
        }
        (None, None) => Err(InputError::new(name, "the scenario has no program")),
    }
}

/// The job a scenario gives a controller.
pub fn job_of(s: &Scenario, program: String) -> Job {
    Job {
        dialect: s.machine.dialect.name().to_string(),
        program,
        params: s
            .machine
            .params
            .overrides()
            .map(|(id, axis, value)| ParamValue { id: id.to_string(), axis, value })
            .collect(),
        sample_us: s.opts.sample_us,
        time_limit_us: s.opts.time_limit_us,
        auto_cycle_start: s.opts.auto_cycle_start,
    }
}

/// What the controller did with a scenario.
#[derive(Debug)]
pub enum Driven {
    /// It ran: its trace.
    Ran(Trace),
    /// It refused the program.
    Refused {
        /// Line.
        line: u32,
        /// Column.
        col: Option<u32>,
        /// Message.
        message: String,
    },
    /// It does not run this scenario.
    Unsupported(String),
}

/// An input waiting for its condition.
struct Waiting {
    condition: Condition,
    occurrence: u32,
    delay_us: Micros,
    input: Input,
    seen: u32,
}

/// Runs the job on `ctl` with the scenario's inputs; the trace gets `meta`. A controller that
/// answers an input or an advance with `unsupported` ([`ErrorKind::NotApplicable`]) does not run
/// the scenario: [`Driven::Unsupported`].
///
/// # Errors
///
/// The controller failed, or broke the protocol (a stop on a condition it was not given, events
/// out of order, no `end` event).
pub fn drive(
    ctl: &mut dyn Controller,
    s: &Scenario,
    job: &Job,
    meta: TraceMeta,
) -> Result<Driven, ControllerError> {
    match steps(ctl, s, job, meta) {
        // An input or condition the controller cannot honour: not applicable, never passed.
        Err(e) if e.kind == ErrorKind::NotApplicable => Ok(Driven::Unsupported(e.message)),
        other => other,
    }
}

fn steps(
    ctl: &mut dyn Controller,
    s: &Scenario,
    job: &Job,
    meta: TraceMeta,
) -> Result<Driven, ControllerError> {
    match ctl.load(job)? {
        Loaded::Ready => {}
        Loaded::Refused { line, col, message } => return Ok(Driven::Refused { line, col, message }),
        Loaded::Unsupported(why) => return Ok(Driven::Unsupported(why)),
    }
    let mut waiting = Vec::new();
    for si in &s.opts.inputs.inputs {
        match &si.trigger {
            Trigger::At(t) => ctl.input(*t, &si.input)?,
            Trigger::When { condition, occurrence, delay_us } => waiting.push(Waiting {
                condition: condition.clone(),
                occurrence: (*occurrence).max(1),
                delay_us: *delay_us,
                input: si.input.clone(),
                seen: 0,
            }),
        }
    }
    let until = s.opts.time_limit_us.saturating_add(1);
    let mut events: Vec<TraceEvent> = Vec::new();
    for _ in 0..MAX_STEPS {
        let mut stop_on: Vec<Condition> = Vec::new();
        for w in &waiting {
            if !stop_on.contains(&w.condition) {
                stop_on.push(w.condition.clone());
            }
        }
        let adv = ctl.advance(until, &stop_on)?;
        let got = ctl.read()?;
        append(&mut events, got)?;
        if adv.ended {
            return finish(meta, events);
        }
        match adv.stopped_on {
            Some(k) => {
                let c = stop_on.get(k).cloned().ok_or_else(|| {
                    ControllerError::new(
                        ErrorKind::Protocol,
                        format!("stopped on condition {k}, but only {} were given", stop_on.len()),
                    )
                })?;
                let mut fire = Vec::new();
                waiting.retain_mut(|w| {
                    if w.condition != c {
                        return true;
                    }
                    w.seen += 1;
                    if w.seen == w.occurrence {
                        fire.push((adv.now_us + w.delay_us, w.input.clone()));
                        return false;
                    }
                    true
                });
                for (t, input) in fire {
                    ctl.input(t, &input)?;
                }
            }
            None if adv.now_us >= until => {
                return Err(ControllerError::new(
                    ErrorKind::Protocol,
                    format!(
                        "the clock reached {} µs (past the time limit) without an `end` event",
                        adv.now_us
                    ),
                ));
            }
            None => {}
        }
    }
    Err(ControllerError::new(ErrorKind::Protocol, format!("no end after {MAX_STEPS} advances")))
}

/// Appends events read, checking time order and that nothing follows `end`.
fn append(events: &mut Vec<TraceEvent>, got: Vec<TraceEvent>) -> Result<(), ControllerError> {
    for e in got {
        if let Some(last) = events.last() {
            if matches!(last.event, Event::End(_)) {
                return Err(ControllerError::new(ErrorKind::Protocol, "an event after the `end` event"));
            }
            if e.t_us < last.t_us {
                return Err(ControllerError::new(
                    ErrorKind::Protocol,
                    format!("events out of time order: {} µs after {} µs", e.t_us, last.t_us),
                ));
            }
        }
        events.push(e);
    }
    Ok(())
}

fn finish(meta: TraceMeta, events: Vec<TraceEvent>) -> Result<Driven, ControllerError> {
    if !events.last().is_some_and(|e| matches!(e.event, Event::End(_))) {
        return Err(ControllerError::new(ErrorKind::Protocol, "the run ended without an `end` event"));
    }
    Ok(Driven::Ran(Trace { meta, events }))
}
