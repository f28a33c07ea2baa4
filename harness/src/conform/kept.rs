//! A controller's trace judged again without the controller: the events a process adapter
//! answered to `read` and kept in a file (the LinuxCNC adapter's `--keep`, one event object a
//! line, no `meta` line), read as [`super::process`] reads a `read` answer and judged as
//! [`super::suite::run_one_within`] judges a driven run: the same scenario, reference run,
//! tolerances (the scenario's `.check.yaml`, else the machine's) and [`super::verdict::judge`].
//! So `cargo test` can hold the reference to a real controller's runs where the controller
//! itself cannot run (`testdata/linuxcnc/adapter-runs/`).

use std::path::Path;

use nc_engine::trace::{Event, Trace, TraceEvent};

use super::drive::{self, Driven};
use super::verdict::{judge, ScenarioVerdict};
use super::wire;
use crate::check::Tolerances;
use crate::diag::InputError;
use crate::import::{self, Format};
use crate::scenario::load::Scenario;

/// The verdict `conform` gives scenario `s` (read from `path`) on the events `kept` (the kept
/// file's text; `kept_name` names it in errors), with the machine's tolerances `machine`
/// (`conform --tolerances`; the scenario's own `.check.yaml` wins, as under `conform`). The
/// reference is `s.machine` running `s.program`: a caller may change the machine first (a
/// reference without a fix must then fail on a trace that passes). A first line that is a
/// `meta` line is the file's own and is left out: the events are read under the job's `meta`
/// line, as a `read` answer is.
///
/// # Errors
///
/// The scenario's program or tolerance file cannot be read; an event of the kept text is not a
/// trace event; the events are out of time order or do not end with one `end` event (what
/// `conform` takes as a protocol error).
pub fn judge_kept(
    s: &Scenario,
    path: &Path,
    machine: &Tolerances,
    kept_name: &str,
    kept: &str,
) -> Result<ScenarioVerdict, InputError> {
    let tolerances = super::suite::tolerances_of(path, machine)?;
    let program = drive::program_text(path, &s.name)?;
    let job = drive::job_of(s, program);
    let meta = wire::meta_of(&job).ok_or_else(|| {
        InputError::new(&s.name, "the scenario's dialect or parameters have no trace header")
    })?;
    let body = match kept.split_once('\n') {
        Some((first, rest)) if first.contains("\"kind\":\"meta\"") => rest,
        _ => kept,
    };
    let text = format!("{}\n{body}", wire::meta_line(&meta));
    let opts = import::Options { format: Some(Format::Jsonl), ..Default::default() };
    let reader = import::from_reader(kept_name, Box::new(std::io::Cursor::new(text.into_bytes())), &opts)
        .map_err(|e| InputError::new(kept_name, e.message))?;
    let mut events: Vec<TraceEvent> = Vec::new();
    for r in reader {
        // Line 1 is the meta line added here: event k is line k + 1.
        let ev = r.map_err(|e| {
            InputError::new(kept_name, format!("event {}: {}", e.line.saturating_sub(1), e.message))
        })?;
        // As the harness takes a controller's events (`drive`): in time order, nothing after `end`.
        if let Some(last) = events.last() {
            if matches!(last.event, Event::End(_)) {
                return Err(InputError::new(kept_name, "an event after the `end` event"));
            }
            if ev.t_us < last.t_us {
                let m = format!("events out of time order: {} µs after {} µs", ev.t_us, last.t_us);
                return Err(InputError::new(kept_name, m));
            }
        }
        events.push(ev);
    }
    if !events.last().is_some_and(|e| matches!(e.event, Event::End(_))) {
        return Err(InputError::new(kept_name, "the kept events do not end with an `end` event"));
    }
    let reference = s.machine.run_to_trace(&s.program, &s.opts);
    let driven = Driven::Ran(Trace { meta: reference.meta.clone(), events });
    Ok(judge(s, &driven, &reference, &tolerances))
}
