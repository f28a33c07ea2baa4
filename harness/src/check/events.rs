//! Discrete events: every signal edge, M/S/T function and alarm of the reference matched with
//! the recorded ones, in order, each within its time window.
//!
//! The n-th recorded occurrence of an event (same signal and value, same function, same alarm
//! code) is matched with the first unmatched reference occurrence within the window among the
//! next few, else with the next one (a time divergence); reference occurrences skipped over are
//! missing, recorded ones without a partner extra. An event matched with a reference event that
//! comes strictly earlier than the one matched before it is out of order.

use std::collections::BTreeMap;

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
    refs: Vec<(i64, usize)>,
    next: usize,
    /// Its index in [`Matcher::names`].
    id: u32,
}

/// How many reference occurrences ahead a recorded event may match.
const LOOK_AHEAD: usize = 4;

/// Matches recorded discrete events against the reference's.
#[derive(Debug)]
pub struct Matcher {
    queues: BTreeMap<Key, Queue>,
    /// The distinct keys, by first occurrence.
    names: Vec<Key>,
    /// Each reference event's key, an index into `names` (memory: one word per event, not a
    /// whole key; a run has few distinct keys).
    keys: Vec<u32>,
    ref_t: Vec<i64>,
    rec_t: Vec<Option<i64>>,
    last: Option<(usize, i64)>,
    /// Events matched.
    pub matched: usize,
    /// Reference discrete events.
    pub total: usize,
}

impl Matcher {
    /// A matcher over the reference's discrete events.
    pub fn new(reference: &Trace) -> Matcher {
        Matcher::new_filtered(reference, |_| true)
    }

    /// A matcher over the reference's discrete events that `keep` accepts (those a recording
    /// can carry).
    pub fn new_filtered(reference: &Trace, keep: impl Fn(&Key) -> bool) -> Matcher {
        let mut queues: BTreeMap<Key, Queue> = BTreeMap::new();
        let mut names = Vec::new();
        let mut keys = Vec::new();
        let mut ref_t = Vec::new();
        for e in &reference.events {
            if let Some(k) = Key::of(&e.event).filter(|k| keep(k)) {
                let q = queues.entry(k).or_insert_with_key(|k| {
                    names.push(k.clone());
                    Queue { id: (names.len() - 1) as u32, ..Queue::default() }
                });
                q.refs.push((e.t_us as i64, keys.len()));
                keys.push(q.id);
                ref_t.push(e.t_us as i64);
            }
        }
        keys.shrink_to_fit();
        ref_t.shrink_to_fit();
        let total = keys.len();
        let rec_t = vec![None; total];
        Matcher { queues, names, keys, ref_t, rec_t, last: None, matched: 0, total }
    }

    /// The matched events so far: (reference time, recorded time), in the reference's order.
    pub fn marks(&self) -> Vec<(i64, i64)> {
        self.ref_t.iter().zip(&self.rec_t).filter_map(|(&r, q)| q.map(|q| (r, q))).collect()
    }

    /// A recorded event at aligned time `t`; findings go to `out`.
    pub fn record(&mut self, key: Key, t: i64, tol: &Tolerances, out: &mut Vec<Finding>) {
        let w = tol.window_us(&key.window_name());
        let Some(q) = self.queues.get_mut(&key) else {
            out.push(Finding::Extra(key, t));
            return;
        };
        if q.next >= q.refs.len() {
            out.push(Finding::Extra(key, t));
            return;
        }
        let end = (q.next + LOOK_AHEAD).min(q.refs.len());
        let pick = (q.next..end).find(|&k| (q.refs[k].0 - t).abs() <= w);
        let k = match pick {
            Some(k) => k,
            // Far from every candidate: extra when the next reference occurrence is still well
            // ahead, else matched late.
            None if q.refs[q.next].0 - t > w => {
                out.push(Finding::Extra(key, t));
                return;
            }
            None => q.next,
        };
        for skipped in q.next..k {
            out.push(Finding::Missing(key.clone(), q.refs[skipped].0));
        }
        q.next = k + 1;
        let (t_ref, idx) = q.refs[k];
        self.matched += 1;
        self.rec_t[idx] = Some(t);
        if (t_ref - t).abs() > w {
            out.push(Finding::Late(key.clone(), t_ref, t, w));
        }
        if let Some((li, lt)) = self.last {
            if idx < li && t_ref < lt {
                let before = self.names[self.keys[li] as usize].clone();
                out.push(Finding::Order(key.clone(), t_ref, t, before, lt));
            }
        }
        if self.last.is_none_or(|(li, _)| idx > li) {
            self.last = Some((idx, t_ref));
        }
    }

    /// The reference events never matched.
    pub fn finish(self, out: &mut Vec<Finding>) {
        for (k, q) in self.queues {
            for &(t, _) in &q.refs[q.next..] {
                out.push(Finding::Missing(k.clone(), t));
            }
        }
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
