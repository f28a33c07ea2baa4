//! The strobe/FIN handshake of M, S and T functions (COM-PLC-01), checked on the recording
//! itself, independently of the time windows (`CHK-EVT-05`): a strobe (MF, SF, TF) never falls
//! while FIN is 0 (before its FIN), and FIN never falls while a strobe is still 1 (before its
//! strobe). Two edges at the same recorded time are simultaneous (a CSV row cannot order them),
//! and a fault the reference itself shows within the event window (a reset dropping a strobe
//! without FIN) is not the recording's.

use nc_engine::trace::{Event, Signal, Signals, Trace};

/// A handshake fault: the edge that broke it and what it broke.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Fault {
    /// The edge: a strobe falling with FIN at 0, or FIN falling with this strobe at 1.
    pub signal: Signal,
    /// True: a strobe fell before FIN rose; false: FIN fell before the strobe.
    pub strobe_first: bool,
    /// Its time.
    pub t: i64,
}

const STROBES: [Signal; 3] = [Signal::Mf, Signal::Sf, Signal::Tf];

/// Follows the edges of one trace.
#[derive(Debug, Default, Clone)]
pub struct Handshake {
    sig: Signals,
    /// The strobes FIN has answered since they rose.
    acked: Signals,
    /// A fault waiting to see whether the resolving edge comes at the same time.
    pending: Vec<Fault>,
}

impl Handshake {
    /// One edge at time `t`; faults that are certain go to `out`.
    pub fn edge(&mut self, t: i64, signal: Signal, value: bool, out: &mut Vec<Fault>) {
        self.settle(t, out);
        self.sig.set(signal, value);
        match (signal, value) {
            (s, true) if STROBES.contains(&s) => self.acked.set(s, false),
            (s, false) if STROBES.contains(&s) && !self.sig.get(Signal::Fin) && !self.acked.get(s) => {
                self.pending.push(Fault { signal: s, strobe_first: true, t })
            }
            (Signal::Fin, true) => {
                for s in STROBES.into_iter().filter(|&s| self.sig.get(s)) {
                    self.acked.set(s, true);
                }
                self.pending.retain(|f| !(f.strobe_first && f.t == t))
            }
            (Signal::Fin, false) => {
                for s in STROBES.into_iter().filter(|&s| self.sig.get(s)) {
                    self.pending.push(Fault { signal: s, strobe_first: false, t });
                }
            }
            (s, false) if STROBES.contains(&s) => {
                self.pending.retain(|f| !(!f.strobe_first && f.signal == s && f.t == t))
            }
            _ => {}
        }
    }

    /// Faults older than `t` are certain.
    pub fn settle(&mut self, t: i64, out: &mut Vec<Fault>) {
        out.extend(self.pending.iter().filter(|f| f.t < t).cloned());
        self.pending.retain(|f| f.t >= t);
    }

    /// The end of the trace.
    pub fn finish(mut self, out: &mut Vec<Fault>) {
        self.settle(i64::MAX, out);
    }
}

/// The faults of a whole trace (the reference's own).
pub fn faults_of(trace: &Trace) -> Vec<Fault> {
    let mut h = Handshake::default();
    let mut out = Vec::new();
    for e in &trace.events {
        if let Event::Signal { signal, value } = e.event {
            h.edge(e.t_us as i64, signal, value, &mut out);
        }
    }
    h.finish(&mut out);
    out
}

/// Reports the recording's handshake faults that the reference does not show within the event
/// window (`CHK-EVT-05`, attributed like an edge of the strobe: COM-PLC-01).
pub(super) fn report(c: &mut super::compare::Comparator, faults: Vec<Fault>) {
    for f in faults {
        if !c.carries_signal(Signal::Fin) || !c.carries_signal(f.signal) {
            continue;
        }
        let w = super::tolerance::ms_us(c.tol.event_ms);
        if c.reference_handshake_faults()
            .iter()
            .any(|r| r.signal == f.signal && r.strobe_first == f.strobe_first && (r.t - f.t).abs() <= w)
        {
            continue;
        }
        let s = f.signal.name();
        let at = crate::scenario::timeline::ms(f.t.max(0) as u64);
        let (what, expected, actual) = if f.strobe_first {
            (
                format!("{s} ↓ before FIN ↑"),
                format!("{s} falls after FIN rises (at the same time at the earliest)"),
                format!("{s} fell at {at} with FIN = 0"),
            )
        } else {
            (
                format!("FIN ↓ before {s} ↓"),
                format!("FIN falls after {s} falls"),
                format!("FIN fell at {at} with {s} = 1"),
            )
        };
        c.diverge(
            super::tolerance::Topic::Edge(f.signal, false),
            "CHK-EVT-05",
            format!("handshake order: {what}"),
            f.t,
            expected,
            actual,
            "-".into(),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(edges: &[(i64, Signal, bool)]) -> Vec<Fault> {
        let mut h = Handshake::default();
        let mut out = Vec::new();
        for &(t, s, v) in edges {
            h.edge(t, s, v, &mut out);
        }
        h.finish(&mut out);
        out
    }

    #[test]
    fn strobe_before_fin_and_fin_before_strobe_are_faults_simultaneous_edges_are_not() {
        use Signal::{Fin, Mf};
        assert!(run(&[(0, Mf, true), (16, Fin, true), (16, Mf, false), (24, Fin, false)]).is_empty());
        // A CSV row: the fall is delivered before the rise at the same time.
        assert!(run(&[(0, Mf, true), (16, Mf, false), (16, Fin, true), (24, Fin, false)]).is_empty());
        let f = run(&[(0, Mf, true), (6, Mf, false), (16, Fin, true), (24, Fin, false)]);
        assert_eq!(f, vec![Fault { signal: Mf, strobe_first: true, t: 6 }]);
        let f = run(&[(0, Mf, true), (16, Fin, true), (20, Fin, false), (30, Mf, false)]);
        assert_eq!(f, vec![Fault { signal: Mf, strobe_first: false, t: 20 }]);
    }
}
