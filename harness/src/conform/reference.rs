//! The reference engine as a [`Controller`].
//!
//! The engine runs a program from start to end in one call and cannot be paused, so this
//! controller re-runs it deterministically: it keeps the inputs given so far as an
//! [`InputSchedule`], runs the engine with them, and hands over the trace piece by piece.
//!
//! Stopping on a condition uses the engine's own triggers: to find the *m*-th onset of a
//! condition, a *probe* run adds an input on that condition (`optional_stop off`, whose only
//! visible effect is its `input` event); the first event where the probe run differs from the
//! plain run is the probe, and everything before it happened before the condition's onset was
//! acted on. An input given while stopped there is recorded as an input on that same condition
//! and occurrence (with the delay to its time), so the next run takes exactly the path a
//! scenario's `when:` input takes in the engine: the reference through the harness gives the
//! same trace as the scenario run. Before handing over more events every re-run is checked to
//! repeat what was already handed over.

use nc_engine::input::{Condition, Input, InputSchedule, ScheduledInput, Trigger};
use nc_engine::trace::{Event, TraceEvent};
use nc_engine::units::Micros;
use nc_engine::{Machine, Program, RunOptions};

use super::{Advanced, Controller, ControllerError, ErrorKind, Identity, Job, Loaded};

/// A loaded job.
#[derive(Debug)]
struct Run {
    machine: Machine,
    program: Program,
    opts: RunOptions,
    /// The plain run with the inputs so far (None: to be re-run).
    events: Option<Vec<TraceEvent>>,
    /// The run before the last input, until the re-run has repeated what it handed over.
    stale: Option<Vec<TraceEvent>>,
    /// Events handed over by `advance` (a prefix of `events`).
    produced: usize,
    /// Events read.
    read: usize,
    /// The clock.
    now: Micros,
    /// Onsets seen so far of each condition stopped on.
    onsets: Vec<(Condition, u32)>,
    /// The condition and occurrence it stands stopped on.
    stopped: Option<(Condition, u32)>,
}

/// The reference engine behind the [`Controller`] trait.
#[derive(Debug, Default)]
pub struct Reference {
    run: Option<Run>,
    literal: bool,
}

impl Reference {
    /// A reference controller with nothing loaded.
    pub fn new() -> Self {
        Reference::default()
    }

    /// A reference controller that applies every input at its literal `t_us`, as a controller
    /// that knows nothing of conditions does (only an input at the clock while stopped is tied
    /// to the stopping event, as the protocol says): it must give the same trace as
    /// [`Reference::new`], which holds `now_us` to the protocol's time semantics.
    pub fn literal() -> Self {
        Reference { run: None, literal: true }
    }

    fn loaded(&mut self) -> Result<&mut Run, ControllerError> {
        self.run.as_mut().ok_or_else(|| ControllerError::new(ErrorKind::Protocol, "no program loaded"))
    }
}

fn engine_run(machine: &Machine, program: &Program, opts: &RunOptions) -> Vec<TraceEvent> {
    machine.run_to_trace(program, opts).events
}

impl Run {
    fn events(&mut self) -> &Vec<TraceEvent> {
        if self.events.is_none() {
            self.events = Some(engine_run(&self.machine, &self.program, &self.opts));
        }
        self.events.as_ref().expect("just run")
    }

    /// The plain run, checked to repeat the events handed over before the last input.
    fn checked(&mut self) -> Result<Vec<TraceEvent>, ControllerError> {
        let n = self.produced;
        let events = self.events().clone();
        if let Some(old) = self.stale.take() {
            if events.get(..n) != old.get(..n) {
                return Err(ControllerError::new(
                    ErrorKind::Failed,
                    "the re-run with the new input differs from the events already handed over",
                ));
            }
        }
        Ok(events)
    }

    /// Index and time of the probe event for the `m`-th onset of `c` (None: it never begins to
    /// hold). The probe acts at the onset's own time: the time of the event that made the
    /// condition hold (an axis crossing's exact time).
    fn probe(&mut self, c: &Condition, m: u32) -> Option<(usize, Micros)> {
        let mut opts = self.opts.clone();
        opts.inputs.inputs.push(ScheduledInput {
            trigger: Trigger::When { condition: c.clone(), occurrence: m, delay_us: 0 },
            input: Input::OptionalStop(false),
        });
        let probed = engine_run(&self.machine, &self.program, &opts);
        let plain = self.events();
        plain
            .iter()
            .zip(&probed)
            .position(|(a, b)| a != b)
            .filter(|&i| matches!(&probed[i].event, Event::Input { name, .. } if name == "optional_stop"))
            .map(|i| (i, probed[i].t_us))
    }

    fn onsets_of(&self, c: &Condition) -> u32 {
        self.onsets.iter().find(|(k, _)| k == c).map_or(0, |(_, n)| *n)
    }
}

impl Controller for Reference {
    fn identity(&mut self) -> Result<Identity, ControllerError> {
        Ok(Identity {
            name: "nc-conform reference".into(),
            version: env!("CARGO_PKG_VERSION").into(),
            dialects: nc_engine::dialect_names().iter().map(|s| s.to_string()).collect(),
        })
    }

    fn load(&mut self, job: &Job) -> Result<Loaded, ControllerError> {
        self.run = None;
        let Some(mut machine) = Machine::new(&job.dialect) else {
            return Ok(Loaded::Unsupported(format!("unknown dialect `{}`", job.dialect)));
        };
        for p in &job.params {
            machine.params.set(&p.id, p.axis, p.value).map_err(|e| {
                ControllerError::new(ErrorKind::Failed, format!("parameter {}: {}", p.id, e.message))
            })?;
        }
        let program = match machine.parse(&job.program) {
            Ok(p) => p,
            Err(e) => return Ok(Loaded::Refused { line: e.line, col: Some(e.col), message: e.message }),
        };
        let opts = RunOptions {
            sample_us: job.sample_us,
            time_limit_us: job.time_limit_us,
            auto_cycle_start: job.auto_cycle_start,
            inputs: InputSchedule::default(),
            ..RunOptions::default()
        };
        self.run = Some(Run {
            machine,
            program,
            opts,
            events: None,
            stale: None,
            produced: 0,
            read: 0,
            now: 0,
            onsets: Vec::new(),
            stopped: None,
        });
        Ok(Loaded::Ready)
    }

    fn input(&mut self, t_us: Micros, input: &Input) -> Result<(), ControllerError> {
        let literal = self.literal;
        let run = self.loaded()?;
        if t_us < run.now {
            return Err(ControllerError::new(
                ErrorKind::Failed,
                format!("input {} at {t_us} µs is in the past (clock {} µs)", input.name(), run.now),
            ));
        }
        let trigger = match &run.stopped {
            Some((c, m)) if !literal || t_us == run.now => {
                Trigger::When { condition: c.clone(), occurrence: *m, delay_us: t_us - run.now }
            }
            _ => Trigger::At(t_us),
        };
        run.opts.inputs.inputs.push(ScheduledInput { trigger, input: input.clone() });
        if let Some(old) = run.events.take() {
            run.stale.get_or_insert(old);
        }
        Ok(())
    }

    fn advance(&mut self, until_us: Micros, stop_on: &[Condition]) -> Result<Advanced, ControllerError> {
        let run = self.loaded()?;
        let produced = run.produced;
        let events = run.checked()?;
        // The earliest onset of a stop condition at or after the present position.
        let mut best: Option<(usize, Micros, usize, u32)> = None;
        for (k, c) in stop_on.iter().enumerate() {
            let m = run.onsets_of(c) + 1;
            if let Some((p, t)) = run.probe(c, m) {
                if p >= produced && t < until_us && best.is_none_or(|(bp, _, _, _)| p < bp) {
                    best = Some((p, t, k, m));
                }
            }
        }
        let end_at = events.iter().position(|e| e.t_us >= until_us).unwrap_or(events.len());
        let adv = match best {
            Some((p, t, k, m)) => {
                let c = stop_on[k].clone();
                match run.onsets.iter_mut().find(|(x, _)| *x == c) {
                    Some(slot) => slot.1 = m,
                    None => run.onsets.push((c.clone(), m)),
                }
                run.produced = p;
                // The onset's time, not that of the next event of the plain run (DEC-100).
                run.now = t;
                run.stopped = Some((c, m));
                Advanced { now_us: run.now, stopped_on: Some(k), ended: false }
            }
            None => {
                run.produced = end_at.max(produced);
                run.stopped = None;
                let ended = run.produced == events.len()
                    && events.last().is_some_and(|e| matches!(e.event, Event::End(_)));
                run.now = if ended { events.last().map_or(until_us, |e| e.t_us) } else { until_us };
                Advanced { now_us: run.now, stopped_on: None, ended }
            }
        };
        Ok(adv)
    }

    fn read(&mut self) -> Result<Vec<TraceEvent>, ControllerError> {
        let run = self.loaded()?;
        let (from, to) = (run.read, run.produced);
        let out = run.events().get(from..to).map(<[TraceEvent]>::to_vec).unwrap_or_default();
        run.read = to;
        Ok(out)
    }
}
