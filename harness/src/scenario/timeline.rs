//! The run as a sequence of instants, for checking expectations against a trace.
//!
//! An *instant* is a time at which the trace has anything: a sample, a signal edge, a block, a
//! function, an alarm, a phase change, an input, the end. Every event at the same time belongs to
//! one instant, and the state of an instant is the state **after all the events at that time**
//! (a signal that rises and falls at the same microsecond is 0 at that instant; a phase entered
//! and left at the same microsecond is never the phase of an instant).
//!
//! The state of instant *i*:
//! - signals and phase: after every event up to and including those at *t*; before the first
//!   event every signal is 0 and the phase is `idle`;
//! - machine positions and spindle speed/angle: the latest sample at or before *t* (a sample
//!   stamped *t* shows the machine before the events at *t*, COM-TIME-04), and at the instant of
//!   the `End` event the end summary's final state. `None` before the first sample (or always,
//!   for a trace written with `sample_us = 0`, except at the end);
//! - command positions: the trace records them only in the end summary, so [`Timeline::command`]
//!   is `End.command` at the end instant and the machine position everywhere else (they differ
//!   while an axis moves and under machine lock);
//! - what happened at *t*: [`Timeline::inputs`], [`Timeline::functions`], [`Timeline::blocks`],
//!   [`Timeline::alarms`], read from the trace's events (nothing is copied).
//!
//! Storage is 16 bytes per instant (an index into the borrowed trace's events, the index of the
//! latest sample, the signal bit set and the phase), so a one-hour run sampled at 1 kHz (3.6 M
//! instants) takes about 58 MB beside its trace; building it and every query is linear or
//! logarithmic in the trace length. The trace's events must be in time order, as the engine
//! writes them.
//!
//! Also here: [`State`] patterns (values that must hold together) read on an [`Obs`]ervation of
//! an instant, and how values read in messages (`Z = -12.5 mm`, `rpm 1000`, `354 ms`).

use nc_engine::alarm::Alarm;
use nc_engine::input::Condition;
use nc_engine::trace::{
    AxisSpec, EndSummary, Event, Phase, Sample, Signal, Signals, Trace, TraceEvent, AXES, AXIS_LETTERS,
};
use nc_engine::units::{Micros, Nm};
use std::ops::Range;

/// What [`Timeline::first_departure`] found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Departure<T> {
    /// No instant of the stretches has a sample.
    NoSample,
    /// No departure.
    Never,
    /// The first departure.
    At {
        /// Time of the stretch's reference sample.
        t0: Micros,
        /// The reference value.
        base: T,
        /// Time of the departure.
        t: Micros,
        /// The value then.
        value: T,
    },
}

/// No sample yet.
const NO_SAMPLE: u32 = u32::MAX;

/// One instant: where its events start in the trace, the latest sample, and the state after it.
#[derive(Debug, Clone, Copy)]
struct Instant {
    /// Index of the instant's first event in `trace.events`.
    ev: u32,
    /// Index in `trace.events` of the latest sample at or before the instant ([`NO_SAMPLE`]).
    sample: u32,
    /// Signals after the instant's events.
    signals: Signals,
    /// Phase after the instant's events.
    phase: Phase,
}

/// The run as instants (see the module documentation for what the state of an instant is).
#[derive(Debug, Clone)]
pub struct Timeline<'a> {
    trace: &'a Trace,
    instants: Vec<Instant>,
    end: Option<&'a EndSummary>,
}

impl<'a> Timeline<'a> {
    /// The instants of `trace`, in time order.
    pub fn new(trace: &'a Trace) -> Timeline<'a> {
        let events = &trace.events;
        debug_assert!(events.len() < NO_SAMPLE as usize, "trace too long for u32 indexes");
        let mut instants = Vec::new();
        let mut signals = Signals::default();
        let mut phase = Phase::Idle;
        let mut sample = NO_SAMPLE;
        let mut i = 0;
        while i < events.len() {
            let t = events[i].t_us;
            let start = i;
            while i < events.len() && events[i].t_us == t {
                match &events[i].event {
                    Event::Sample(_) => sample = i as u32,
                    Event::Signal { signal, value } => signals.set(*signal, *value),
                    Event::Phase(p) => phase = *p,
                    _ => {}
                }
                i += 1;
            }
            instants.push(Instant { ev: start as u32, sample, signals, phase });
        }
        Timeline { trace, instants, end: trace.end() }
    }

    /// The trace.
    pub fn trace(&self) -> &'a Trace {
        self.trace
    }

    /// Number of instants.
    pub fn len(&self) -> usize {
        self.instants.len()
    }

    /// Whether the trace has no events at all.
    pub fn is_empty(&self) -> bool {
        self.instants.is_empty()
    }

    /// The end summary, when the trace has one.
    pub fn end(&self) -> Option<&'a EndSummary> {
        self.end
    }

    /// Time of the `End` event.
    pub fn end_time(&self) -> Option<Micros> {
        self.end.and_then(|_| self.trace.events.last()).map(|e| e.t_us)
    }

    /// Whether instant `i` is the one of the `End` event.
    pub fn is_end(&self, i: usize) -> bool {
        self.end.is_some() && i + 1 == self.instants.len()
    }

    /// Time of instant `i`, µs.
    pub fn t_us(&self, i: usize) -> Micros {
        self.trace.events[self.instants[i].ev as usize].t_us
    }

    /// Signals after the events of instant `i`.
    pub fn signals(&self, i: usize) -> Signals {
        self.instants[i].signals
    }

    /// Phase after the events of instant `i`.
    pub fn phase(&self, i: usize) -> Phase {
        self.instants[i].phase
    }

    /// Machine positions and spindle at instant `i`: the latest sample at or before it, or the end
    /// summary's state at the end instant; `None` before the first sample.
    pub fn sample(&self, i: usize) -> Option<&'a Sample> {
        if self.is_end(i) {
            return self.end.map(|e| &e.state);
        }
        self.last_sample(i)
    }

    /// The latest sample at or before instant `i` (at the end instant too: the state before the
    /// events at that time).
    pub fn last_sample(&self, i: usize) -> Option<&'a Sample> {
        match self.instants[i].sample {
            NO_SAMPLE => None,
            k => match &self.trace.events[k as usize].event {
                Event::Sample(s) => Some(s),
                _ => None,
            },
        }
    }

    /// Machine positions at instant `i` (reported units: nm, diameter for a lathe's X).
    pub fn machine(&self, i: usize) -> Option<&'a [Nm; AXES]> {
        self.sample(i).map(|s| &s.axes)
    }

    /// Command positions at instant `i`: `End.command` at the end instant, the machine position
    /// elsewhere (the trace records command positions only at the end).
    pub fn command(&self, i: usize) -> Option<&'a [Nm; AXES]> {
        if self.is_end(i) {
            return self.end.map(|e| &e.command);
        }
        self.machine(i)
    }

    /// Spindle speed at instant `i`, milli-rpm (signed).
    pub fn spindle_mrpm(&self, i: usize) -> Option<i64> {
        self.sample(i).map(|s| s.spindle_mrpm)
    }

    /// Spindle angle at instant `i`, milli-degrees.
    pub fn spindle_mdeg(&self, i: usize) -> Option<i64> {
        self.sample(i).map(|s| s.spindle_mdeg)
    }

    /// Indexes in `trace.events` of the events of instant `i`.
    pub fn event_range(&self, i: usize) -> std::ops::Range<usize> {
        let start = self.instants[i].ev as usize;
        let end = self.instants.get(i + 1).map_or(self.trace.events.len(), |n| n.ev as usize);
        start..end
    }

    /// The events of instant `i`, in trace order.
    pub fn events(&self, i: usize) -> &'a [TraceEvent] {
        &self.trace.events[self.event_range(i)]
    }

    /// The inputs that acted at instant `i` (trace names: `feed_hold`, `reset`, ...).
    pub fn inputs(&self, i: usize) -> impl Iterator<Item = &'a str> + 'a {
        self.events(i).iter().filter_map(|e| match &e.event {
            Event::Input { name, .. } => Some(name.as_str()),
            _ => None,
        })
    }

    /// The M/S/T functions output at instant `i`.
    pub fn functions(&self, i: usize) -> impl Iterator<Item = (char, u32)> + 'a {
        self.events(i).iter().filter_map(|e| match e.event {
            Event::Function { letter, code } => Some((letter, code)),
            _ => None,
        })
    }

    /// The source lines of the blocks started at instant `i`.
    pub fn blocks(&self, i: usize) -> impl Iterator<Item = u32> + 'a {
        self.events(i).iter().filter_map(|e| match e.event {
            Event::Block { line, .. } => Some(line),
            _ => None,
        })
    }

    /// The alarms raised at instant `i`.
    pub fn alarms(&self, i: usize) -> impl Iterator<Item = &'a Alarm> + 'a {
        self.events(i).iter().filter_map(|e| match &e.event {
            Event::Alarm(a) => Some(a),
            _ => None,
        })
    }

    /// The last instant at or before `t_us` (`None` when `t_us` is before the first one).
    pub fn at(&self, t_us: Micros) -> Option<usize> {
        let n = self.instants.partition_point(|ins| self.trace.events[ins.ev as usize].t_us <= t_us);
        n.checked_sub(1)
    }

    /// The instant that holds event `ev` (an index in `trace.events`).
    pub fn instant_of_event(&self, ev: usize) -> usize {
        self.instants.partition_point(|ins| ins.ev as usize <= ev).saturating_sub(1)
    }

    /// Signals and phase just before event `ev` acted: the previous instant's state with the
    /// same-time events the trace lists before `ev` applied.
    pub fn state_before_event(&self, ev: usize) -> (Signals, Phase) {
        let i = self.instant_of_event(ev);
        let (mut signals, mut phase) = match i.checked_sub(1) {
            Some(p) => (self.signals(p), self.phase(p)),
            None => (Signals::default(), Phase::Idle),
        };
        for e in &self.trace.events[self.instants[i].ev as usize..ev] {
            match &e.event {
                Event::Signal { signal, value } => signals.set(*signal, *value),
                Event::Phase(p) => phase = *p,
                _ => {}
            }
        }
        (signals, phase)
    }

    /// The time `condition` begins to hold for the `occurrence`-th time (1 = first; 0 counts as 1).
    ///
    /// - `Signal`: the state after the first instant's events counts as occurrence 1 when the
    ///   signal has the value then; after that, every edge into the value counts (an edge and its
    ///   opposite at the same microsecond too);
    /// - `AxisBelow` / `AxisAbove`: the **machine** position of the samples (the trace has no
    ///   command positions before the end; the engine triggers inputs on the command position),
    ///   nm in reported units, strictly below/above; each time it becomes true counts;
    /// - `Block`: the n-th start of a block on that source line;
    /// - `Phase`: the n-th entry (phase event) into the phase; the power-on `idle` is no entry;
    /// - `Function`: the n-th output of that M/S/T function.
    pub fn first_time(&self, condition: &Condition, occurrence: u32) -> Option<Micros> {
        let n = occurrence.max(1);
        let mut seen = 0u32;
        let mut count = |t: Micros| {
            seen += 1;
            (seen == n).then_some(t)
        };
        let events = &self.trace.events;
        match *condition {
            Condition::Signal { signal, value } => {
                let first = self.instants.first()?;
                if first.signals.get(signal) == value {
                    if let Some(t) = count(self.t_us(0)) {
                        return Some(t);
                    }
                }
                let mut cur = first.signals.get(signal);
                let from = self.instants.get(1).map_or(events.len(), |ins| ins.ev as usize);
                for e in &events[from..] {
                    if let Event::Signal { signal: s, value: v } = e.event {
                        if s == signal && v != cur {
                            cur = v;
                            if v == value {
                                if let Some(t) = count(e.t_us) {
                                    return Some(t);
                                }
                            }
                        }
                    }
                }
                None
            }
            Condition::AxisBelow { axis, nm } => self.axis_time(axis, |x| x < nm, n),
            Condition::AxisAbove { axis, nm } => self.axis_time(axis, |x| x > nm, n),
            Condition::Block { line } => events
                .iter()
                .filter(|e| matches!(e.event, Event::Block { line: l, .. } if l == line))
                .find_map(|e| count(e.t_us)),
            Condition::Phase(p) => {
                events.iter().filter(|e| e.event == Event::Phase(p)).find_map(|e| count(e.t_us))
            }
            Condition::Function { letter, code } => events
                .iter()
                .filter(
                    |e| matches!(e.event, Event::Function { letter: l, code: c } if l == letter && c == code),
                )
                .find_map(|e| count(e.t_us)),
        }
    }

    /// The n-th time the machine position of `axis` begins to satisfy `test`.
    fn axis_time(&self, axis: usize, test: impl Fn(Nm) -> bool, n: u32) -> Option<Micros> {
        let mut seen = 0u32;
        let mut before = false;
        for i in 0..self.instants.len() {
            let now = self.machine(i).is_some_and(|a| axis < AXES && test(a[axis]));
            if now && !before {
                seen += 1;
                if seen == n {
                    return Some(self.t_us(i));
                }
            }
            before = now;
        }
        None
    }

    /// The state of instant `i` as a pattern reads it.
    pub fn obs(&self, i: usize) -> Obs<'a> {
        Obs {
            signals: self.signals(i),
            phase: self.phase(i),
            sample: self.sample(i),
            command: self.command(i),
        }
    }

    /// The state event `ev` met: [`Timeline::state_before_event`], the latest sample at or before
    /// it, and the machine position as the command position.
    pub fn obs_before_event(&self, ev: usize) -> Obs<'a> {
        let (signals, phase) = self.state_before_event(ev);
        let sample = self.last_sample(self.instant_of_event(ev));
        Obs { signals, phase, sample, command: sample.map(|s| &s.axes) }
    }

    /// The maximal stretches of consecutive instants whose state satisfies `pred`.
    pub fn stretches(&self, pred: impl Fn(&Obs) -> bool) -> Vec<Range<usize>> {
        let mut out: Vec<Range<usize>> = Vec::new();
        for i in 0..self.len() {
            if pred(&self.obs(i)) {
                match out.last_mut() {
                    Some(r) if r.end == i => r.end = i + 1,
                    _ => out.push(i..i + 1),
                }
            }
        }
        out
    }

    /// The first sampled instant of `stretches` where `bad(base, value)`, `value` read from the
    /// instant's sample and `base` from the first sampled instant of the same stretch (which is
    /// tested against itself too).
    pub fn first_departure<T: Copy>(
        &self,
        stretches: &[Range<usize>],
        value: impl Fn(&Sample) -> T,
        bad: impl Fn(T, T) -> bool,
    ) -> Departure<T> {
        let mut seen = false;
        for r in stretches {
            let mut base = None;
            for i in r.clone() {
                let Some(s) = self.sample(i) else { continue };
                seen = true;
                let v = value(s);
                let (t0, b) = *base.get_or_insert((self.t_us(i), v));
                if bad(b, v) {
                    return Departure::At { t0, base: b, t: self.t_us(i), value: v };
                }
            }
        }
        if seen {
            Departure::Never
        } else {
            Departure::NoSample
        }
    }

    /// Whether signal `s` rose (an edge to 1 from 0) among the events of instant `i`, starting
    /// from its value at instant `i - 1`.
    pub fn rose(&self, i: usize, s: Signal) -> bool {
        let mut cur = i.checked_sub(1).is_some_and(|p| self.signals(p).get(s));
        for e in self.events(i) {
            if let Event::Signal { signal, value } = e.event {
                if signal == s {
                    if value && !cur {
                        return true;
                    }
                    cur = value;
                }
            }
        }
        false
    }
}

// ---------------------------------------------------------------------------------------------
// State patterns and how values read

/// The unit a value is shown in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unit {
    /// nm shown as mm.
    Mm,
    /// Nano-degrees shown as degrees.
    Deg,
    /// Milli-rpm shown as rpm.
    Rpm,
}

impl Unit {
    /// mm or degrees, for an axis.
    pub fn of(a: &AxisSpec) -> Unit {
        if a.rotary {
            Unit::Deg
        } else {
            Unit::Mm
        }
    }
}

/// `v` (nm, nano-degrees or milli-rpm) as a decimal number of mm, degrees or rpm with its unit.
pub fn show(v: i64, unit: Unit) -> String {
    let (digits, suffix) = match unit {
        Unit::Mm => (6, " mm"),
        Unit::Deg => (6, " deg"),
        Unit::Rpm => (3, ""),
    };
    format!("{}{suffix}", fixed(v, digits))
}

/// An integer with `digits` implied decimals, without trailing zeros (`-12500000, 6` → `-12.5`).
pub fn fixed(v: i64, digits: u32) -> String {
    let p = 10u64.pow(digits);
    let a = v.unsigned_abs();
    let mut s = format!("{}{}", if v < 0 { "-" } else { "" }, a / p);
    let rest = a % p;
    if rest > 0 {
        let frac = format!("{rest:0w$}", w = digits as usize);
        s.push('.');
        s.push_str(frac.trim_end_matches('0'));
    }
    s
}

/// A time in ms.
pub fn ms(t: Micros) -> String {
    format!("{} ms", fixed(t as i64, 3))
}

/// A comparison in engine units.
#[derive(Debug, Clone, PartialEq)]
pub enum Cmp {
    /// This value, within 1 unit (1 nm, 1 milli-rpm).
    Exact(i64),
    /// Strictly below, strictly above, at least, at most.
    Bounds { below: Option<i64>, above: Option<i64>, min: Option<i64>, max: Option<i64> },
}

impl Cmp {
    /// Whether `x` satisfies the comparison.
    pub fn test(&self, x: i64) -> bool {
        match *self {
            Cmp::Exact(v) => x.abs_diff(v) <= 1,
            Cmp::Bounds { below, above, min, max } => {
                below.is_none_or(|b| x < b)
                    && above.is_none_or(|a| x > a)
                    && min.is_none_or(|m| x >= m)
                    && max.is_none_or(|m| x <= m)
            }
        }
    }

    /// Whether `x` satisfies the comparison within `slack` of its values (an exact value within
    /// `slack`, at least 1 unit; each bound moved outwards by `slack`): a controller's value is
    /// judged within the documented tolerance of the expected value (DEC-156).
    pub fn test_within(&self, x: i64, slack: i64) -> bool {
        let s = slack.max(0);
        match *self {
            Cmp::Exact(v) => x.abs_diff(v) <= s.max(1) as u64,
            Cmp::Bounds { below, above, min, max } => {
                let widen = |b: Option<i64>, by: i64| b.map(|b| b.saturating_add(by));
                Cmp::Bounds {
                    below: widen(below, s),
                    above: widen(above, -s),
                    min: widen(min, -s),
                    max: widen(max, s),
                }
                .test(x)
            }
        }
    }

    /// `Z = -12.5 mm`, `Z >= 3 mm, Z < 5 mm`, `rpm 1000`.
    pub fn describe(&self, name: &str, unit: Unit) -> String {
        let eq = if unit == Unit::Rpm { " " } else { " = " };
        match *self {
            Cmp::Exact(v) => format!("{name}{eq}{}", show(v, unit)),
            Cmp::Bounds { below, above, min, max } => {
                let parts = [(above, ">"), (min, ">="), (below, "<"), (max, "<=")];
                let parts: Vec<String> = parts
                    .iter()
                    .filter_map(|(v, op)| v.map(|v| format!("{name} {op} {}", show(v, unit))))
                    .collect();
                parts.join(", ")
            }
        }
    }
}

/// The state at one moment, as a [`State`] pattern reads it.
#[derive(Debug, Clone, Copy)]
pub struct Obs<'t> {
    /// Signals.
    pub signals: Signals,
    /// Phase.
    pub phase: Phase,
    /// Machine positions and spindle (`None`: no sample yet).
    pub sample: Option<&'t Sample>,
    /// Command positions (see [`Timeline::command`]).
    pub command: Option<&'t [Nm; AXES]>,
}

/// One value of a state pattern.
#[derive(Debug, Clone)]
pub enum Item {
    /// A machine (or command) position.
    Axis {
        /// `Z` or `command Z`.
        name: String,
        /// Slot in the position arrays.
        slot: usize,
        /// mm or degrees.
        unit: Unit,
        /// The command position rather than the machine one.
        command: bool,
        /// The comparison, nm or nano-degrees.
        cmp: Cmp,
    },
    /// The spindle speed, milli-rpm.
    Rpm(Cmp),
    /// A signal's value.
    Signal(Signal, bool),
    /// The phase.
    Phase(Phase),
}

impl Item {
    fn value(&self, o: &Obs) -> Option<i64> {
        match self {
            Item::Axis { slot, command: true, .. } => o.command.map(|c| c[*slot]),
            Item::Axis { slot, .. } => o.sample.map(|s| s.axes[*slot]),
            Item::Rpm(_) => o.sample.map(|s| s.spindle_mrpm),
            _ => None,
        }
    }

    /// Whether it holds in `o`.
    pub fn holds(&self, o: &Obs) -> bool {
        match self {
            Item::Axis { cmp, .. } | Item::Rpm(cmp) => self.value(o).is_some_and(|v| cmp.test(v)),
            Item::Signal(s, v) => o.signals.get(*s) == *v,
            Item::Phase(p) => o.phase == *p,
        }
    }

    /// Whether it holds in `o` with positions within `slack.position_nm` and the spindle speed
    /// within `slack.speed_mrpm` of the expected values; signals and phases exact.
    pub fn holds_within(&self, o: &Obs, slack: &Slack) -> bool {
        match self {
            Item::Axis { cmp, .. } => self.value(o).is_some_and(|v| cmp.test_within(v, slack.position_nm)),
            Item::Rpm(cmp) => self.value(o).is_some_and(|v| cmp.test_within(v, slack.speed_mrpm)),
            _ => self.holds(o),
        }
    }

    /// What it expects, with units.
    pub fn expected(&self) -> String {
        match self {
            Item::Axis { name, unit, cmp, .. } => cmp.describe(name, *unit),
            Item::Rpm(cmp) => cmp.describe("rpm", Unit::Rpm),
            Item::Signal(s, v) => format!("{} = {}", s.name(), *v as u8),
            Item::Phase(p) => format!("phase {}", p.name()),
        }
    }

    /// The value `o` has, with units.
    pub fn actual(&self, o: &Obs) -> String {
        let num = |name: &str, unit: Unit, eq: &str| match self.value(o) {
            Some(v) => format!("{name}{eq}{}", show(v, unit)),
            None => format!("{name}: no sample"),
        };
        match self {
            Item::Axis { name, unit, .. } => num(name, *unit, " = "),
            Item::Rpm(_) => num("rpm", Unit::Rpm, " "),
            Item::Signal(s, _) => format!("{} = {}", s.name(), o.signals.get(*s) as u8),
            Item::Phase(_) => format!("phase {}", o.phase.name()),
        }
    }
}

/// How far from an expected value a value may lie and still meet it. The reference is held to
/// [`Slack::EXACT`]; under `conform` a controller to the comparison's tolerances (DEC-156).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Slack {
    /// Positions, nm (nano-degrees on rotary axes).
    pub position_nm: i64,
    /// Spindle speed, milli-rpm.
    pub speed_mrpm: i64,
    /// Spindle angle, milli-degrees (`spindle_still`).
    pub angle_mdeg: i64,
}

impl Slack {
    /// Exact: an exact value within 1 unit, bounds as written, `still` unchanged.
    pub const EXACT: Slack = Slack { position_nm: 0, speed_mrpm: 0, angle_mdeg: 0 };
}

/// A state pattern: values that must hold together.
#[derive(Debug, Clone, Default)]
pub struct State(pub Vec<Item>);

impl State {
    /// Whether every item holds in `o`.
    pub fn holds(&self, o: &Obs) -> bool {
        self.0.iter().all(|i| i.holds(o))
    }
    /// Whether every item holds in `o` within `slack` ([`Item::holds_within`]).
    pub fn holds_within(&self, o: &Obs, slack: &Slack) -> bool {
        self.0.iter().all(|i| i.holds_within(o, slack))
    }
    /// The items expected, `, `-separated.
    pub fn describe(&self) -> String {
        self.0.iter().map(Item::expected).collect::<Vec<_>>().join(", ")
    }
    /// The values `o` has for the items.
    pub fn actual(&self, o: &Obs) -> String {
        self.0.iter().map(|i| i.actual(o)).collect::<Vec<_>>().join(", ")
    }
}

/// A condition as text: `RGTAP = 1`, `Z < -10 mm`, `phase cutting entered (occurrence 2) + 5 ms`.
pub fn describe_condition(c: &Condition, occurrence: u32, delay: Micros, axes: &[AxisSpec]) -> String {
    let mut s = match c {
        Condition::Signal { signal, value } => format!("{} = {}", signal.name(), *value as u8),
        Condition::AxisBelow { axis, nm } | Condition::AxisAbove { axis, nm } => {
            let unit = axes.iter().find(|a| a.index == *axis).map_or(Unit::Mm, Unit::of);
            let op = if matches!(c, Condition::AxisBelow { .. }) { "<" } else { ">" };
            let letter = AXIS_LETTERS.get(*axis).copied().unwrap_or('?');
            format!("{letter} {op} {}", show(*nm, unit))
        }
        Condition::Block { line } => format!("block on line {line} starts"),
        Condition::Phase(p) => format!("phase {} entered", p.name()),
        Condition::Function { letter, code } => format!("{letter}{code} output"),
    };
    if occurrence > 1 {
        s.push_str(&format!(" (occurrence {occurrence})"));
    }
    if delay > 0 {
        s.push_str(&format!(" + {}", ms(delay)));
    }
    s
}
