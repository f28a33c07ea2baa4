//! Invariants: properties every run of the reference engine must have, whatever the program, the
//! parameters and the schedule of inputs and faults (`docs/invariants.md`, ids `INV-01`..).
//!
//! Each invariant is a pure function over one trace (or, for the differential ones, two traces of
//! runs that differ in one input), so that property tests, the fuzzer, the campaign and scenario
//! files (`expect.invariants`) all check the same thing. What a trace cannot tell by itself (the
//! lead of the tap, the alarm an out-of-range word must raise) comes in a [`Context`] from whoever
//! wrote the program.

pub mod physics;

use crate::alarm::AlarmKind;
use crate::trace::{Event, Phase, Sample, Signal, Signals, Trace, AXES};
use crate::units::{Micros, Nm};

/// A named invariant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Invariant {
    /// INV-01: the engine never panics, whatever it is fed.
    NoPanic,
    /// INV-02: the trace is time-ordered and ends with exactly one `end` event.
    TimeOrderedEnds,
    /// INV-03: an out-of-range word raises its alarm at its block, and nothing moves from then on.
    RangeAlarmNoMotion,
    /// INV-04: during rigid tapping, tap travel = lead × spindle revolutions within the tolerance.
    TapSync,
    /// INV-05: feed hold and single block never stop a rigid tap mid-stroke or mid-dwell.
    HoldDeferredInTapping,
    /// INV-06: dry run never changes a rigid tapping stroke.
    DryRunKeepsTapFeed,
    /// INV-07: under machine lock the axes and the tapping spindle stay still while the command
    /// positions advance as without the lock.
    MachineLockStill,
    /// INV-08: after a reset in rigid tapping, F76.3 and RGTAP fall and the spindle returns to its
    /// state before M29.
    ResetRestoresSpindle,
    /// INV-09: after an overload retract begins, the tap never goes deeper.
    OverloadNeverDeeper,
    /// INV-10: the same inputs give the same trace.
    Deterministic,
    /// INV-11: no axis exceeds its speed limit or its acceleration ([`physics`]).
    AxisLimits,
    /// INV-12: no spindle speed change exceeds its ramp, no speed its maximum ([`physics`]).
    SpindleRamp,
    /// INV-13: the spindle's angle advances by the integral of its speed ([`physics`]).
    SpindleAngleIntegral,
    /// INV-14: an axis following a spindle in speed mode never runs ahead of lead × its speed.
    FollowsSpindle,
}

impl Invariant {
    /// Every invariant, in id order.
    pub const ALL: [Invariant; 14] = [
        Invariant::NoPanic,
        Invariant::TimeOrderedEnds,
        Invariant::RangeAlarmNoMotion,
        Invariant::TapSync,
        Invariant::HoldDeferredInTapping,
        Invariant::DryRunKeepsTapFeed,
        Invariant::MachineLockStill,
        Invariant::ResetRestoresSpindle,
        Invariant::OverloadNeverDeeper,
        Invariant::Deterministic,
        Invariant::AxisLimits,
        Invariant::SpindleRamp,
        Invariant::SpindleAngleIntegral,
        Invariant::FollowsSpindle,
    ];

    /// The physics family (INV-11..INV-14), checked by [`physics::check`] on every run.
    pub const PHYSICS: [Invariant; 4] = [
        Invariant::AxisLimits,
        Invariant::SpindleRamp,
        Invariant::SpindleAngleIntegral,
        Invariant::FollowsSpindle,
    ];

    /// The id (`INV-04`).
    pub fn id(self) -> &'static str {
        match self {
            Invariant::NoPanic => "INV-01",
            Invariant::TimeOrderedEnds => "INV-02",
            Invariant::RangeAlarmNoMotion => "INV-03",
            Invariant::TapSync => "INV-04",
            Invariant::HoldDeferredInTapping => "INV-05",
            Invariant::DryRunKeepsTapFeed => "INV-06",
            Invariant::MachineLockStill => "INV-07",
            Invariant::ResetRestoresSpindle => "INV-08",
            Invariant::OverloadNeverDeeper => "INV-09",
            Invariant::Deterministic => "INV-10",
            Invariant::AxisLimits => "INV-11",
            Invariant::SpindleRamp => "INV-12",
            Invariant::SpindleAngleIntegral => "INV-13",
            Invariant::FollowsSpindle => "INV-14",
        }
    }

    /// The name used in scenario files (`tap_sync`).
    pub fn name(self) -> &'static str {
        match self {
            Invariant::NoPanic => "no_panic",
            Invariant::TimeOrderedEnds => "time_ordered_ends",
            Invariant::RangeAlarmNoMotion => "range_alarm_no_motion",
            Invariant::TapSync => "tap_sync",
            Invariant::HoldDeferredInTapping => "hold_deferred_in_tapping",
            Invariant::DryRunKeepsTapFeed => "dry_run_keeps_tap_feed",
            Invariant::MachineLockStill => "machine_lock_still",
            Invariant::ResetRestoresSpindle => "reset_restores_spindle",
            Invariant::OverloadNeverDeeper => "overload_never_deeper",
            Invariant::Deterministic => "deterministic",
            Invariant::AxisLimits => "axis_limits",
            Invariant::SpindleRamp => "spindle_ramp",
            Invariant::SpindleAngleIntegral => "spindle_angle_integral",
            Invariant::FollowsSpindle => "follows_spindle",
        }
    }

    /// Looks an invariant up by name or id.
    pub fn from_name(s: &str) -> Option<Invariant> {
        Invariant::ALL.into_iter().find(|i| i.name() == s || i.id() == s)
    }
}

/// A broken invariant: which, when, and what was seen.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Violation {
    /// Which invariant.
    pub invariant: Invariant,
    /// Time of the first violation, µs.
    pub t_us: Micros,
    /// What was expected and what happened.
    pub detail: String,
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} {} at {:.3} ms: {}",
            self.invariant.id(),
            self.invariant.name(),
            self.t_us as f64 / 1000.0,
            self.detail
        )
    }
}

/// The tap of a rigid tapping program, for [`Invariant::TapSync`] and [`Invariant::OverloadNeverDeeper`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TapSpec {
    /// Axis slot of the tap axis.
    pub axis: usize,
    /// Lead in nm per spindle revolution (magnitude).
    pub lead_nm: Nm,
    /// Allowed |travel − lead × revolutions| in nm.
    pub tolerance_nm: Nm,
}

/// An alarm an out-of-range word must raise, for [`Invariant::RangeAlarmNoMotion`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RangeAlarm {
    /// The alarm.
    pub kind: AlarmKind,
    /// The program line of the block holding the word.
    pub line: u32,
}

/// What the trace alone cannot tell; `None` / `false` switches the dependent check off.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Context {
    /// The tap (axis and lead) of the program's rigid tapping.
    pub tap: Option<TapSpec>,
    /// The program holds one word out of its range, and this is its alarm.
    pub range_alarm: Option<RangeAlarm>,
    /// Spindle speed commanded before M29, milli-rpm signed (0: stopped).
    pub pre_m29_mrpm: Option<i64>,
    /// Feed hold and single block are suppressed in rigid tapping (GSK always; Fanuc with FHD = 0).
    pub hold_suppressed: bool,
}

/// The signals, phase and last sample after each event, for the checks below.
struct Walk<'a> {
    trace: &'a Trace,
    i: usize,
    signals: Signals,
    phase: Phase,
    sample: Option<Sample>,
}

impl<'a> Walk<'a> {
    fn new(trace: &'a Trace) -> Self {
        Walk { trace, i: 0, signals: Signals::default(), phase: Phase::Idle, sample: None }
    }

    /// Applies the next event; returns it with its time.
    fn next(&mut self) -> Option<(Micros, &'a Event)> {
        let ev = self.trace.events.get(self.i)?;
        self.i += 1;
        match &ev.event {
            Event::Signal { signal, value } => self.signals.set(*signal, *value),
            Event::Phase(p) => self.phase = *p,
            Event::Sample(s) => self.sample = Some(*s),
            _ => {}
        }
        Some((ev.t_us, &ev.event))
    }

    fn stroke(&self) -> bool {
        self.signals.get(Signal::Rgspp) || self.signals.get(Signal::Rgspm)
    }
}

/// Every single-trace invariant that `ctx` allows, in id order; empty when all hold.
pub fn check(trace: &Trace, ctx: &Context) -> Vec<Violation> {
    let mut v = Vec::new();
    v.extend(time_ordered_ends(trace));
    if let Some(ra) = ctx.range_alarm {
        v.extend(range_alarm_no_motion(trace, ra));
    }
    if let Some(tap) = ctx.tap {
        v.extend(tap_sync(trace, tap));
    }
    if ctx.hold_suppressed {
        v.extend(hold_deferred_in_tapping(trace));
    }
    v.extend(machine_lock_still(trace));
    v.extend(reset_restores_spindle(trace, ctx.pre_m29_mrpm));
    v.extend(overload_never_deeper(trace, ctx.tap.map(|t| t.axis)));
    v
}

fn violation(invariant: Invariant, t_us: Micros, detail: String) -> Option<Violation> {
    Some(Violation { invariant, t_us, detail })
}

/// INV-02: times never decrease; exactly one `end`, the last event.
pub fn time_ordered_ends(trace: &Trace) -> Option<Violation> {
    let inv = Invariant::TimeOrderedEnds;
    let mut last = 0;
    for (k, e) in trace.events.iter().enumerate() {
        if e.t_us < last {
            return violation(inv, e.t_us, format!("event {k} at {} µs after one at {last} µs", e.t_us));
        }
        last = e.t_us;
        if matches!(e.event, Event::End(_)) && k + 1 != trace.events.len() {
            return violation(inv, e.t_us, format!("`end` is event {k} of {}", trace.events.len()));
        }
    }
    match trace.events.last() {
        Some(e) if matches!(e.event, Event::End(_)) => None,
        _ => violation(inv, last, "the trace does not end with `end`".into()),
    }
}

/// INV-03: when the block with the out-of-range word is reached, the first alarm is the expected
/// one at its line; from the start of that block no axis moves; the run ends on the alarm.
pub fn range_alarm_no_motion(trace: &Trace, ra: RangeAlarm) -> Option<Violation> {
    let inv = Invariant::RangeAlarmNoMotion;
    // Only a block that is reached can raise its alarm (an earlier alarm, reset or emergency
    // stop may end the run before it).
    let start = trace.events.iter().find_map(|e| match &e.event {
        Event::Block { line, .. } if *line == ra.line => Some(e.t_us),
        _ => None,
    })?;
    let want = format!("{} at line {}", ra.kind.code(), ra.line);
    let Some((t, a)) = trace.alarms().next() else {
        return violation(
            inv,
            trace.events.last().map_or(0, |e| e.t_us),
            format!("expected {want}; no alarm"),
        );
    };
    if a.kind != ra.kind || a.line != Some(ra.line) {
        let got = format!("{} at line {}", a.kind.code(), a.line.map_or("-".into(), |l| l.to_string()));
        return violation(inv, t, format!("expected {want}; first alarm {got}"));
    }
    // The first sample at or after the block's start is the reference: a sample at the block's
    // own time shows the state then (samples come before the events of their time).
    let mut at_start: Option<[Nm; AXES]> = None;
    for e in &trace.events {
        if let Event::Sample(s) = &e.event {
            if e.t_us >= start {
                let base = *at_start.get_or_insert(s.axes);
                if s.axes != base {
                    return violation(
                        inv,
                        e.t_us,
                        format!("an axis moved after the block of line {}", ra.line),
                    );
                }
            }
        }
    }
    match trace.end() {
        Some(end) if end.reason.name() == "alarm" => None,
        Some(end) => violation(inv, t, format!("run ended with `{}`, expected `alarm`", end.reason.name())),
        None => None,
    }
}

/// Signed change of the spindle angle between two samples, milli-degrees, unwrapped by the speed.
fn angle_step(a: &Sample, b: &Sample) -> i64 {
    let mut d = b.spindle_mdeg - a.spindle_mdeg;
    let dir = if a.spindle_mrpm + b.spindle_mrpm >= 0 { 1 } else { -1 };
    if dir > 0 && d < 0 {
        d += 360_000;
    } else if dir < 0 && d > 0 {
        d -= 360_000;
    }
    d
}

/// Reported position → physical travel (a lathe's X is reported on the diameter).
fn physical(trace: &Trace, axis: usize, nm: Nm) -> Nm {
    let diameter = trace.meta.axes.iter().any(|a| a.index == axis && a.diameter);
    if diameter {
        nm / 2
    } else {
        nm
    }
}

/// INV-04: within each stroke (RGSPP or RGSPM = 1), for the samples inside it, the tap axis'
/// travel since the stroke's first sample equals lead × revolutions turned since then, within the
/// tolerance. Not checked from the moment a spindle stall acts (the stall alarms own that case).
pub fn tap_sync(trace: &Trace, tap: TapSpec) -> Option<Violation> {
    let inv = Invariant::TapSync;
    let mut w = Walk::new(trace);
    let mut base: Option<(Sample, i64)> = None; // first sample of the stroke, revolutions so far
    let mut prev: Option<Sample> = None;
    while let Some((t, ev)) = w.next() {
        match ev {
            Event::Input { name, .. } if name == "spindle_stall" => return None,
            Event::Sample(s) if w.stroke() => {
                match (&mut base, prev) {
                    (None, _) | (_, None) => base = Some((*s, 0)),
                    (Some((b, turned)), Some(p)) => {
                        *turned += angle_step(&p, s);
                        let travel = (physical(trace, tap.axis, s.axes[tap.axis])
                            - physical(trace, tap.axis, b.axes[tap.axis]))
                        .abs();
                        let expect = (*turned as i128 * tap.lead_nm as i128 / 360_000).unsigned_abs() as i64;
                        if (travel - expect).abs() > tap.tolerance_nm {
                            return violation(
                                inv,
                                t,
                                format!(
                                    "tap travel {travel} nm, lead × revolutions {expect} nm (tolerance {} nm)",
                                    tap.tolerance_nm
                                ),
                            );
                        }
                    }
                }
                prev = Some(*s);
            }
            Event::Sample(s) => {
                base = None;
                prev = Some(*s);
            }
            Event::Signal { signal: Signal::Rgspp | Signal::Rgspm, .. } => base = None,
            _ => {}
        }
    }
    None
}

/// INV-05: SPL (the hold lamp) never rises while a rigid tapping stroke runs (RGSPP or RGSPM =
/// 1) or during the dwell at the bottom in rigid tapping mode (F76.3 = 1).
pub fn hold_deferred_in_tapping(trace: &Trace) -> Option<Violation> {
    let inv = Invariant::HoldDeferredInTapping;
    let mut w = Walk::new(trace);
    loop {
        let before = (w.stroke(), w.phase == Phase::Dwell && w.signals.get(Signal::Rtap));
        let (t, ev) = w.next()?;
        if let Event::Signal { signal: Signal::Spl, value: true } = ev {
            if before.0 {
                return violation(inv, t, "SPL rose during a rigid tapping stroke".into());
            }
            if before.1 {
                return violation(inv, t, "SPL rose during the dwell of a rigid tapping cycle".into());
            }
        }
    }
}

/// INV-07 (single trace): when machine lock is switched on before the first block, no sampled
/// machine position changes while it is on, and the spindle does not turn in a tapping stroke.
pub fn machine_lock_still(trace: &Trace) -> Option<Violation> {
    let inv = Invariant::MachineLockStill;
    let mut w = Walk::new(trace);
    let mut locked = false;
    let mut seen_block = false;
    let mut base: Option<[Nm; AXES]> = None;
    let mut prev: Option<Sample> = None;
    while let Some((t, ev)) = w.next() {
        match ev {
            Event::Block { .. } => seen_block = true,
            Event::Input { name, value } if name == "machine_lock" => {
                let on = value == "on";
                if on && !seen_block && !locked {
                    locked = true;
                    base = prev.map(|p| p.axes);
                } else if !on {
                    return None;
                }
            }
            Event::Sample(s) => {
                if locked {
                    let b = *base.get_or_insert(s.axes);
                    if s.axes != b {
                        return violation(inv, t, "an axis moved under machine lock".into());
                    }
                    if w.stroke() && prev.is_some_and(|p| p.spindle_mdeg != s.spindle_mdeg) {
                        return violation(
                            inv,
                            t,
                            "the spindle turned in a tapping stroke under machine lock".into(),
                        );
                    }
                }
                prev = Some(*s);
            }
            _ => {}
        }
    }
    None
}

/// INV-08: a reset that acts while F76.3 = 1 leaves F76.3 and RGTAP at 0 at the end; when the run
/// ends on that reset, the pre-M29 speed is known and the spindle is not stalled, the final
/// spindle speed is that speed.
pub fn reset_restores_spindle(trace: &Trace, pre_m29_mrpm: Option<i64>) -> Option<Violation> {
    let inv = Invariant::ResetRestoresSpindle;
    let mut w = Walk::new(trace);
    let mut reset_at = None;
    let mut stalled = false;
    while let Some((t, ev)) = w.next() {
        match ev {
            Event::Input { name, value } if name == "spindle_stall" => stalled = value == "on",
            Event::Input { name, .. } if name == "reset" && w.signals.get(Signal::Rtap) => {
                reset_at.get_or_insert(t);
            }
            Event::Alarm(_) if reset_at.is_some() => return None,
            _ => {}
        }
    }
    let t = reset_at?;
    let end = trace.end()?;
    if end.signals.get(Signal::Rtap) || end.signals.get(Signal::Rgtap) {
        return violation(inv, t, "F76.3 or RGTAP still 1 at the end after a reset in rigid tapping".into());
    }
    match pre_m29_mrpm {
        // A stalled spindle cannot turn back (COM-INP-09): only the signals are checked then.
        Some(want) if end.reason.name() == "reset" && !stalled && end.state.spindle_mrpm != want => {
            violation(
                inv,
                t,
                format!("spindle {} mrpm at the end, {} mrpm before M29", end.state.spindle_mrpm, want),
            )
        }
        _ => None,
    }
}

/// INV-09: from the moment phase `overload_retract` is entered, the tap axis never goes further
/// in the direction it was cutting in. The tap axis is `axis`, or else the axis that moved most in
/// the cutting phase before; the direction is that of its travel in that phase.
pub fn overload_never_deeper(trace: &Trace, axis: Option<usize>) -> Option<Violation> {
    let inv = Invariant::OverloadNeverDeeper;
    let mut w = Walk::new(trace);
    let mut cut_start: Option<[Nm; AXES]> = None;
    let mut last: Option<[Nm; AXES]> = None;
    let mut watch: Option<(usize, i64, Nm)> = None; // axis, direction, limit
    while let Some((t, ev)) = w.next() {
        match ev {
            Event::Phase(Phase::Cutting) => cut_start = last,
            Event::Phase(Phase::OverloadRetract) => {
                let (Some(from), Some(now)) = (cut_start, last) else { continue };
                let ax =
                    axis.unwrap_or_else(|| (0..AXES).max_by_key(|&a| (now[a] - from[a]).abs()).unwrap_or(0));
                let dir = (now[ax] - from[ax]).signum();
                if dir != 0 {
                    watch = Some((ax, dir, now[ax]));
                }
            }
            Event::Sample(s) => {
                if let Some((ax, dir, limit)) = watch {
                    if (s.axes[ax] - limit) * dir > 0 {
                        return violation(
                            inv,
                            t,
                            format!(
                                "tap axis at {} nm, deeper than {limit} nm where the overload retract began",
                                s.axes[ax]
                            ),
                        );
                    }
                }
                last = Some(s.axes);
            }
            _ => {}
        }
    }
    None
}

/// INV-10: two runs of the same inputs gave the same events.
pub fn deterministic(a: &Trace, b: &Trace) -> Option<Violation> {
    if a == b {
        return None;
    }
    let k = a
        .events
        .iter()
        .zip(&b.events)
        .position(|(x, y)| x != y)
        .unwrap_or(a.events.len().min(b.events.len()));
    let t = a.events.get(k).or(b.events.get(k)).map_or(0, |e| e.t_us);
    violation(Invariant::Deterministic, t, format!("the traces differ from event {k} on"))
}

/// The (start, end) of every phase interval of `phase`, in order.
fn intervals(trace: &Trace, phase: Phase) -> Vec<(Micros, Micros)> {
    let mut out = Vec::new();
    let mut open: Option<Micros> = None;
    for (t, p) in trace.phases() {
        if let Some(s) = open.take() {
            out.push((s, t));
        }
        if p == phase {
            open = Some(t);
        }
    }
    out
}

/// INV-06: a run with dry run switched on has the same rigid tapping strokes as the same run
/// without: the same number of cutting and dwell phases, each of the same length (when a run is
/// cut by the time limit: the phases both closed, each of the same length).
pub fn dry_run_keeps_tap_feed(plain: &Trace, dry: &Trace) -> Option<Violation> {
    let inv = Invariant::DryRunKeepsTapFeed;
    // A run cut by the time limit has closed fewer phases than it would have: then only the
    // phases both runs closed are compared (the dry run, faster before the cycle, may have closed
    // one more; found by the engine_case fuzz target).
    let cut = |t: &Trace| t.end().is_some_and(|e| e.reason == crate::trace::EndReason::TimeLimit);
    let truncated = cut(plain) || cut(dry);
    for phase in [Phase::Cutting, Phase::Dwell] {
        let (a, b) = (intervals(plain, phase), intervals(dry, phase));
        if a.len() != b.len() && !truncated {
            let t = b.last().map_or(0, |x| x.0);
            return violation(
                inv,
                t,
                format!("{} {} phases under dry run, {} without", b.len(), phase.name(), a.len()),
            );
        }
        for (x, y) in a.iter().zip(&b) {
            if x.1 - x.0 != y.1 - y.0 {
                return violation(
                    inv,
                    y.0,
                    format!(
                        "a {} phase lasts {} µs under dry run, {} µs without",
                        phase.name(),
                        y.1 - y.0,
                        x.1 - x.0
                    ),
                );
            }
        }
    }
    None
}

/// INV-07 (differential): a run under machine lock from the start ends at the same time with the
/// same command positions as the same run without the lock.
pub fn machine_lock_same_commands(plain: &Trace, locked: &Trace) -> Option<Violation> {
    let inv = Invariant::MachineLockStill;
    let (a, b) = (plain.end()?, locked.end()?);
    let (ta, tb) = (plain.events.last()?.t_us, locked.events.last()?.t_us);
    if a.command != b.command {
        return violation(
            inv,
            tb,
            format!("command positions {:?} under machine lock, {:?} without", b.command, a.command),
        );
    }
    if ta != tb {
        return violation(inv, tb, format!("the run ends at {tb} µs under machine lock, {ta} µs without"));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::{EndReason, EndSummary, TraceEvent, TraceMeta};

    fn trace(phases: &[(Micros, Phase)], end: Micros, reason: EndReason) -> Trace {
        let mut events: Vec<TraceEvent> =
            phases.iter().map(|&(t, p)| TraceEvent { t_us: t, event: Event::Phase(p) }).collect();
        let summary = EndSummary {
            reason,
            state: Sample::default(),
            command: [0; AXES],
            signals: Signals::default(),
            modal: Vec::new(),
            alarms: 0,
            blocks: 0,
        };
        events.push(TraceEvent { t_us: end, event: Event::End(Box::new(summary)) });
        Trace { meta: TraceMeta { dialect: "", axes: Vec::new(), period_us: 1000, sample_us: 1000 }, events }
    }

    #[test]
    fn dry_run_compares_the_length_of_every_cut() {
        use Phase::*;
        let plain = trace(&[(10, Cutting), (30, Dwell), (40, Retract)], 50, EndReason::ProgramEnd);
        let same = trace(&[(5, Cutting), (25, Dwell), (35, Retract)], 45, EndReason::ProgramEnd);
        let longer = trace(&[(5, Cutting), (26, Dwell), (36, Retract)], 45, EndReason::ProgramEnd);
        let fewer = trace(&[(5, Idle)], 45, EndReason::ProgramEnd);
        assert_eq!(dry_run_keeps_tap_feed(&plain, &same), None);
        assert!(dry_run_keeps_tap_feed(&plain, &longer).is_some(), "a longer cut is a violation");
        assert!(dry_run_keeps_tap_feed(&plain, &fewer).is_some(), "a missing cut is a violation");
    }

    #[test]
    fn dry_run_at_the_time_limit_compares_the_phases_both_closed() {
        use Phase::*;
        let plain = trace(&[(10, Cutting), (30, Dwell)], 35, EndReason::TimeLimit);
        let dry = trace(&[(5, Cutting), (25, Dwell), (30, Retract)], 35, EndReason::TimeLimit);
        assert_eq!(
            dry_run_keeps_tap_feed(&plain, &dry),
            None,
            "the dwell the plain run did not close is not compared"
        );
        let dry_longer = trace(&[(5, Cutting), (26, Dwell), (30, Retract)], 35, EndReason::TimeLimit);
        assert!(dry_run_keeps_tap_feed(&plain, &dry_longer).is_some(), "closed phases still compare");
    }

    #[test]
    fn every_invariant_has_an_id_and_a_name_that_find_it() {
        for i in Invariant::ALL {
            assert_eq!(Invariant::from_name(i.name()), Some(i));
            assert_eq!(Invariant::from_name(i.id()), Some(i));
        }
    }
}
