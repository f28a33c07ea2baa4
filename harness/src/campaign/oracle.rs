//! The oracle: run a case, twice for determinism and once more for a differential comparison,
//! and check every invariant of `nc_engine::invariants` on what came out.

use std::collections::BTreeSet;
use std::panic::{catch_unwind, AssertUnwindSafe};

use nc_engine::input::{Input, ScheduledInput, Trigger};
use nc_engine::invariants::{self, Context, Invariant, Violation};
use nc_engine::trace::{Event, Signal, Signals};
use nc_engine::{Machine, Micros, Program, RunOptions, Trace};

use super::case::Case;

/// What one case gave.
#[derive(Debug, Default)]
pub struct Report {
    /// Every broken invariant.
    pub violations: Vec<Violation>,
    /// Alarm codes raised.
    pub alarms: BTreeSet<String>,
    /// The situations the case reached (`feed_hold during cutting`, `overload_retract`, ...).
    pub reached: BTreeSet<String>,
    /// How the run ended.
    pub end: String,
}

/// A second run to compare with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CompareRun {
    /// The same run with dry run switched on at this time, µs (INV-06).
    DryRunAt(Micros),
    /// The same run under machine lock from the start (INV-07).
    MachineLock,
}

/// Runs `program`, turning a panic into an INV-01 violation.
pub fn run_guarded(m: &Machine, program: &Program, opts: &RunOptions) -> Result<Trace, Violation> {
    catch_unwind(AssertUnwindSafe(|| m.run_to_trace(program, opts))).map_err(|e| {
        let msg = e
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_else(|| "a panic".into());
        Violation { invariant: Invariant::NoPanic, t_us: 0, detail: format!("the engine panicked: {msg}") }
    })
}

/// Runs `program` and checks every invariant: the single-trace ones that `ctx` allows,
/// determinism (a second run), and the comparison run if one is asked for. Returns the first
/// run's trace (unless it panicked) and the violations.
pub fn check_run(
    m: &Machine,
    program: &Program,
    opts: &RunOptions,
    ctx: &Context,
    compare: Option<CompareRun>,
) -> (Option<Trace>, Vec<Violation>) {
    let trace = match run_guarded(m, program, opts) {
        Ok(t) => t,
        Err(v) => return (None, vec![v]),
    };
    let mut violations = invariants::check(&trace, ctx);
    // Physical plausibility (INV-11..INV-14) on every run, under the machine's own limits.
    violations.extend(invariants::physics::check(&trace, &invariants::physics::Limits::of(m), ctx.tap));
    match run_guarded(m, program, opts) {
        Ok(again) => violations.extend(invariants::deterministic(&trace, &again)),
        Err(v) => violations.push(v),
    }
    if let Some(c) = compare {
        violations.extend(compare_run(m, program, opts, c, &trace));
    }
    (Some(trace), violations)
}

/// The differential invariant of `compare` between `plain` and a second run.
fn compare_run(
    m: &Machine,
    program: &Program,
    opts: &RunOptions,
    compare: CompareRun,
    plain: &Trace,
) -> Option<Violation> {
    let mut other = opts.clone();
    match compare {
        CompareRun::DryRunAt(t) => other.inputs = other.inputs.at(t, Input::DryRun(true)),
        CompareRun::MachineLock => {
            // A case that switches the lock off itself is no longer "the same run under the
            // lock": after the unlock the variant's motors, which never moved, take up backlash
            // where the plain run's do not or the other way round (COM-MOT-03; campaign census
            // seed 7, case 1465, once the motor's own direction was kept through locked motions).
            if opts.inputs.inputs.iter().any(|i| i.input == Input::MachineLock(false)) {
                return None;
            }
            // The lock acts first of everything at t = 0.
            other
                .inputs
                .inputs
                .insert(0, ScheduledInput { trigger: Trigger::At(0), input: Input::MachineLock(true) });
        }
    }
    let variant = match run_guarded(m, program, &other) {
        Ok(t) => t,
        Err(v) => return Some(v),
    };
    match compare {
        CompareRun::DryRunAt(_) => invariants::dry_run_keeps_tap_feed(plain, &variant),
        CompareRun::MachineLock => invariants::machine_lock_same_commands(plain, &variant)
            .or_else(|| invariants::machine_lock_still(&variant)),
    }
}

/// Runs `case` and checks every invariant.
pub fn check_case(case: &Case) -> Report {
    let mut report = Report::default();
    let m = case.machine();
    let (text, _) = case.program_text();
    let program = match catch_unwind(AssertUnwindSafe(|| m.parse(&text))) {
        Ok(Ok(p)) => p,
        Ok(Err(e)) => {
            // Generated programs always parse: a refusal is a generator or parser bug.
            let detail = format!("the generated program was refused: line {}: {}", e.line, e.message);
            report.violations.push(Violation { invariant: Invariant::NoPanic, t_us: 0, detail });
            return report;
        }
        Err(_) => {
            let detail = "the parser panicked".to_string();
            report.violations.push(Violation { invariant: Invariant::NoPanic, t_us: 0, detail });
            return report;
        }
    };
    let (trace, violations) = check_run(&m, &program, &case.options(), &case.context(), case.compare_run());
    report.violations = violations;
    if let Some(t) = trace {
        observe(&t, &mut report);
    }
    report
}

/// Coverage: the alarms and the situations the run reached.
fn observe(trace: &Trace, report: &mut Report) {
    let mut signals = Signals::default();
    let mut phase = "idle";
    for e in &trace.events {
        match &e.event {
            Event::Signal { signal, value } => signals.set(*signal, *value),
            Event::Phase(p) => {
                phase = p.name();
                report.reached.insert(format!("phase {phase}"));
            }
            Event::Input { name, .. } => {
                let rigid = if signals.get(Signal::Rtap) { " in rigid mode" } else { "" };
                report.reached.insert(format!("{name} during {phase}{rigid}"));
            }
            Event::Alarm(a) => {
                report.alarms.insert(a.kind.code().to_string());
            }
            Event::End(end) => report.end = end.reason.name().to_string(),
            _ => {}
        }
    }
}
