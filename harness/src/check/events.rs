//! Discrete events: every signal edge, M/S/T function and alarm of the reference matched with
//! the recorded ones, in order, each within its time window.
//!
//! The n-th recorded occurrence of an event (same signal and value, same function, same alarm
//! code) is matched with the first unmatched reference occurrence within the window among the
//! next few, else with the next one (a time divergence); reference occurrences skipped over are
//! missing, recorded ones without a partner extra. An event matched with a reference event that
//! comes strictly earlier than the one matched before it is out of order.

use std::collections::{BTreeMap, VecDeque};

use nc_engine::trace::{Event, Signal, Trace};

use super::tolerance::{Tolerances, Topic};

/// What identifies a discrete event.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub enum Key {
    /// A signal edge to this value.
    Edge(Signal, bool),
    /// An M/S/T function.
    Function(char, u32),
    /// An alarm by code.
    Alarm(String),
}

impl Key {
    /// The key of a discrete event (None for samples, blocks, phases, inputs, the end).
    pub fn of(ev: &Event) -> Option<Key> {
        match ev {
            Event::Signal { signal, value } => Some(Key::Edge(*signal, *value)),
            Event::Function { letter, code } => Some(Key::Function(*letter, *code)),
            // A vendor alarm the engine does not know is keyed by its vendor code.
            Event::Alarm(a) => {
                Some(Key::Alarm(crate::import::vendor_code(a).unwrap_or(a.kind.code()).to_string()))
            }
            _ => None,
        }
    }

    /// As text: `RGTAP ↓`, `M29`, `alarm 5002`.
    pub fn describe(&self) -> String {
        match self {
            Key::Edge(s, v) => format!("{} {}", s.name(), if *v { "↑" } else { "↓" }),
            Key::Function(l, c) => format!("{l}{c}"),
            Key::Alarm(c) => format!("alarm {c}"),
        }
    }

    /// The name its time window is configured under.
    pub fn window_name(&self) -> String {
        match self {
            Key::Edge(s, _) => s.name().to_string(),
            Key::Function(l, c) => format!("{l}{c}"),
            Key::Alarm(_) => "alarm".into(),
        }
    }

    /// The topic for attribution.
    pub fn topic(&self) -> Topic {
        match self {
            Key::Edge(s, v) => Topic::Edge(*s, *v),
            Key::Function(l, c) => Topic::Function(*l, *c),
            Key::Alarm(_) => Topic::Alarm,
        }
    }
}

/// A finding of the matcher (turned into a divergence by the caller).
#[derive(Debug, Clone, PartialEq)]
pub enum Finding {
    /// Matched, but outside its window: key, reference time, recorded time, window.
    Late(Key, i64, i64, i64),
    /// A reference event never recorded: key, reference time.
    Missing(Key, i64),
    /// A recorded event the reference does not have: key, recorded time.
    Extra(Key, i64),
    /// Out of order: key, its reference time, recorded time, the event before it (key,
    /// reference time).
    Order(Key, i64, i64, Key, i64),
}

#[derive(Debug, Default)]
struct Queue {
    /// The reference occurrences not yet matched or skipped, in time order: (time, index among
    /// the reference's events).
    refs: VecDeque<(i64, usize)>,
    /// Its index in [`Matcher::names`].
    id: u32,
}

/// How many reference occurrences ahead a recorded event may match.
const LOOK_AHEAD: usize = 4;

/// Matches recorded discrete events against the reference's.
///
/// The reference's events are given one by one ([`Matcher::reference`]), all before the first
/// recorded one or as the comparison advances: a recorded event at `t` is matched as against
/// every reference event once those up to `t` + its window are given (a candidate later than
/// that is outside the window, and the next occurrence is then too far ahead either way).
/// Matched and skipped occurrences are dropped: memory follows the events given and not yet
/// matched, not the run.
#[derive(Debug)]
pub struct Matcher {
    queues: BTreeMap<Key, Queue>,
    /// The distinct keys, by first occurrence.
    names: Vec<Key>,
    /// The reference's times and the matched recorded times, by reference event (kept only for
    /// [`Matcher::marks`]).
    marks: Option<(Vec<i64>, Vec<Option<i64>>)>,
    /// The last event matched: its index, reference time and key (an index into `names`).
    last: Option<(usize, i64, u32)>,
    functions: bool,
    alarms: bool,
    /// Reference occurrences given and not yet matched or skipped, and the most at once.
    waiting: usize,
    /// The most reference occurrences waiting at once (a figure for the memory bound).
    pub peak_waiting: usize,
    /// Events matched.
    pub matched: usize,
    /// Reference discrete events given.
    pub total: usize,
}

impl Matcher {
    /// A matcher over the reference's discrete events.
    pub fn new(reference: &Trace) -> Matcher {
        Matcher::new_filtered(reference, true, true)
    }

    /// A matcher over the reference's discrete events, functions and alarms only when the
    /// recording can carry them; [`Matcher::marks`] kept.
    pub fn new_filtered(reference: &Trace, functions: bool, alarms: bool) -> Matcher {
        let mut m = Matcher::streaming(functions, alarms);
        m.marks = Some((Vec::new(), Vec::new()));
        for e in &reference.events {
            if let Some(k) = Key::of(&e.event) {
                m.reference(k, e.t_us as i64);
            }
        }
        if let Some((r, q)) = &mut m.marks {
            r.shrink_to_fit();
            q.shrink_to_fit();
        }
        m
    }

    /// A matcher given no reference event yet (functions and alarms only when the recording can
    /// carry them), no [`Matcher::marks`] kept.
    pub fn streaming(functions: bool, alarms: bool) -> Matcher {
        Matcher {
            queues: BTreeMap::new(),
            names: Vec::new(),
            marks: None,
            last: None,
            functions,
            alarms,
            waiting: 0,
            peak_waiting: 0,
            matched: 0,
            total: 0,
        }
    }

    /// The next reference event (in the reference's order), key `k` at `t`.
    pub fn reference(&mut self, k: Key, t: i64) {
        let keep = match k {
            Key::Function(..) => self.functions,
            Key::Alarm(_) => self.alarms,
            Key::Edge(..) => true,
        };
        if !keep {
            return;
        }
        let names = &mut self.names;
        let q = self.queues.entry(k).or_insert_with_key(|k| {
            names.push(k.clone());
            Queue { id: (names.len() - 1) as u32, ..Queue::default() }
        });
        q.refs.push_back((t, self.total));
        if let Some((r, q)) = &mut self.marks {
            r.push(t);
            q.push(None);
        }
        self.total += 1;
        self.waiting += 1;
        self.peak_waiting = self.peak_waiting.max(self.waiting);
    }

    /// The matched events so far: (reference time, recorded time), in the reference's order
    /// (none when the matcher keeps no marks).
    pub fn marks(&self) -> Vec<(i64, i64)> {
        let Some((r, q)) = &self.marks else { return Vec::new() };
        r.iter().zip(q).filter_map(|(&r, q)| q.map(|q| (r, q))).collect()
    }

    /// A recorded event at aligned time `t`; findings go to `out`.
    pub fn record(&mut self, key: Key, t: i64, tol: &Tolerances, out: &mut Vec<Finding>) {
        let w = tol.window_us(&key.window_name());
        let Some(q) = self.queues.get_mut(&key) else {
            out.push(Finding::Extra(key, t));
            return;
        };
        let Some(&(first, _)) = q.refs.front() else {
            out.push(Finding::Extra(key, t));
            return;
        };
        let end = LOOK_AHEAD.min(q.refs.len());
        let pick = (0..end).find(|&k| (q.refs[k].0 - t).abs() <= w);
        let k = match pick {
            Some(k) => k,
            // Far from every candidate: extra when the next reference occurrence is still well
            // ahead, else matched late.
            None if first - t > w => {
                out.push(Finding::Extra(key, t));
                return;
            }
            None => 0,
        };
        for _ in 0..k {
            if let Some((skipped, _)) = q.refs.pop_front() {
                out.push(Finding::Missing(key.clone(), skipped));
            }
        }
        let Some((t_ref, idx)) = q.refs.pop_front() else { return };
        self.waiting -= k + 1;
        let id = q.id;
        self.matched += 1;
        if let Some((_, q)) = &mut self.marks {
            q[idx] = Some(t);
        }
        if (t_ref - t).abs() > w {
            out.push(Finding::Late(key.clone(), t_ref, t, w));
        }
        if let Some((li, lt, lk)) = self.last {
            if idx < li && t_ref < lt {
                let before = self.names[lk as usize].clone();
                out.push(Finding::Order(key.clone(), t_ref, t, before, lt));
            }
        }
        if self.last.is_none_or(|(li, _, _)| idx > li) {
            self.last = Some((idx, t_ref, id));
        }
    }

    /// The reference events never matched.
    pub fn finish(self, out: &mut Vec<Finding>) {
        for (k, q) in self.queues {
            for &(t, _) in &q.refs {
                out.push(Finding::Missing(k.clone(), t));
            }
        }
    }
}

/// The reference's discrete events as a whole, read as they stream by: what the comparison
/// needs of them before and besides the matching (the anchor, the events a recording cannot
/// carry, the reference's own handshake faults), so that the list itself need not be kept.
#[derive(Debug, Default, Clone)]
pub struct Summary {
    /// The distinct keys in order of first occurrence: key, its first time, its count.
    pub keys: Vec<(Key, i64, usize)>,
    /// Discrete events (edges, functions, alarms).
    pub total: usize,
    /// The reference's own handshake faults ([`super::handshake::faults_of`]), complete after
    /// [`Summary::finish`].
    pub faults: Vec<super::handshake::Fault>,
    handshake: super::handshake::Handshake,
}

impl Summary {
    /// The summary of a whole trace.
    pub fn of(trace: &Trace) -> Summary {
        let mut s = Summary::default();
        for e in &trace.events {
            s.event(e.t_us as i64, &e.event);
        }
        s.finish();
        s
    }

    /// The next event of the reference, at `t`.
    pub fn event(&mut self, t: i64, ev: &Event) {
        if let Event::Signal { signal, value } = ev {
            self.handshake.edge(t, *signal, *value, &mut self.faults);
        }
        if let Some(k) = Key::of(ev) {
            self.total += 1;
            match self.keys.iter_mut().find(|x| x.0 == k) {
                Some(x) => x.2 += 1,
                None => self.keys.push((k, t, 1)),
            }
        }
    }

    /// The end of the reference.
    pub fn finish(&mut self) {
        std::mem::take(&mut self.handshake).finish(&mut self.faults);
    }

    /// The time of the first occurrence of `k` (None: none).
    pub fn first(&self, k: &Key) -> Option<i64> {
        self.keys.iter().find(|x| &x.0 == k).map(|x| x.1)
    }
}

#[cfg(test)]
mod tests {
    use nc_engine::trace::{Event, Signal, Trace, TraceEvent, TraceMeta};

    use super::{Finding, Key, Matcher};
    use crate::check::Tolerances;

    fn edge(t_us: u64, signal: Signal, value: bool) -> TraceEvent {
        TraceEvent { t_us, event: Event::Signal { signal, value } }
    }

    /// A recorded event matched with a reference event earlier than the one matched before it
    /// is out of order, and the finding names that one (its key kept as an index per event).
    #[test]
    fn out_of_order_names_the_event_matched_before() {
        let meta = TraceMeta { dialect: "fanuc-mill", axes: Vec::new(), period_us: 1000, sample_us: 1000 };
        let events = vec![
            edge(10_000, Signal::Rgtap, true),
            TraceEvent { t_us: 15_000, event: Event::Function { letter: 'M', code: 29 } },
            edge(20_000, Signal::Rtap, true),
            edge(30_000, Signal::Rgtap, false),
        ];
        let mut m = Matcher::new(&Trace { meta, events });
        let tol = Tolerances::default();
        let mut out = Vec::new();
        m.record(Key::Edge(Signal::Rtap, true), 20_000, &tol, &mut out);
        m.record(Key::Edge(Signal::Rgtap, true), 21_000, &tol, &mut out);
        let order: Vec<_> = out.iter().filter(|f| matches!(f, Finding::Order(..))).collect();
        assert_eq!(
            order,
            [&Finding::Order(
                Key::Edge(Signal::Rgtap, true),
                10_000,
                21_000,
                Key::Edge(Signal::Rtap, true),
                20_000
            )]
        );
        assert_eq!(m.matched, 2);
        assert_eq!(m.marks(), [(10_000, 21_000), (20_000, 20_000)]);
    }
}
