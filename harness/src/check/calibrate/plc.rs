//! The PLC's answers as the edges stream by: each "from" edge waits for the next "to" edge, and
//! the delay between them is kept (strobe → FIN, SPPOS → SPPOSA, ...). An M19's strobe is told
//! apart: its FIN comes when the orientation is complete.

use std::collections::VecDeque;

use nc_engine::trace::Signal;

use super::Bounded;

/// Edges waiting for their answer, at most (older ones are dropped).
const PENDING: usize = 64;

/// One measured answer: (parameter id, from edges, to edge, text).
pub type Pair = (&'static str, &'static [(Signal, bool)], (Signal, bool), &'static str);

/// What is measured.
pub const PAIRS: [Pair; 5] = [
    (
        "plc.fin_ms",
        &[(Signal::Mf, true), (Signal::Sf, true), (Signal::Tf, true)],
        (Signal::Fin, true),
        "strobe ↑ → FIN ↑",
    ),
    (
        "plc.fin_fall_ms",
        &[(Signal::Mf, false), (Signal::Sf, false), (Signal::Tf, false)],
        (Signal::Fin, false),
        "strobe ↓ → FIN ↓",
    ),
    ("plc.sppos_reach_ms", &[(Signal::Sppos, true)], (Signal::Spposa, true), "SPPOS ↑ → SPPOSA ↑"),
    ("plc.rgtap_ms", &[(Signal::Spposa, true)], (Signal::Rgtap, true), "SPPOSA ↑ → RGTAP ↑"),
    ("plc.rgtap_fall_ms", &[(Signal::Rtap, false)], (Signal::Rgtap, false), "F76.3 ↓ → RGTAP ↓"),
];

/// The PLC followed through the recording.
pub struct PlcTrack {
    pending: Vec<VecDeque<i64>>,
    /// Delays of each of [`PAIRS`], µs.
    pub delays: Vec<Bounded<f64>>,
    /// M19 strobe ↑ → FIN ↑, µs.
    pub orient: Bounded<f64>,
    orient_pending: Option<i64>,
    /// The last M/S/T function output: (time, letter, code).
    last_function: Option<(i64, char, u32)>,
}

impl Default for PlcTrack {
    fn default() -> Self {
        PlcTrack {
            pending: vec![VecDeque::new(); PAIRS.len()],
            delays: (0..PAIRS.len()).map(|_| Bounded::new(65_536)).collect(),
            orient: Bounded::new(4096),
            orient_pending: None,
            last_function: None,
        }
    }
}

impl PlcTrack {
    /// An M, S or T function was output.
    pub fn function(&mut self, t: i64, letter: char, code: u32) {
        self.last_function = Some((t, letter, code));
    }

    /// A signal edge; `turning`: the spindle turns (the last sample).
    pub fn edge(&mut self, t: i64, signal: Signal, value: bool, turning: bool) {
        // An MF rising with its M19 (the function and its strobe come in the same scan).
        let m19 = signal == Signal::Mf
            && value
            && self.last_function.is_some_and(|(tf, l, c)| l == 'M' && c == 19 && t - tf <= 1000);
        if m19 {
            self.orient_pending = Some(t);
        } else if (signal, value) == (Signal::Fin, true) {
            if let Some(t0) = self.orient_pending.take() {
                self.orient.push((t - t0) as f64);
                // Its FIN is not a FIN delay.
                self.pending[0].clear();
            }
        }
        for (k, (_, from, to, _)) in PAIRS.iter().enumerate() {
            if (signal, value) == *to {
                for t0 in self.pending[k].drain(..) {
                    self.delays[k].push((t - t0) as f64);
                }
            }
            // The drive reports position mode only once the spindle has come down at its ramp
            // (seed 000's timing chart; issue 12): an SPPOS raised with the spindle still
            // turning measures the ramp, not the drive.
            if from.contains(&(signal, value)) && !(m19 && k == 0) && !(signal == Signal::Sppos && turning) {
                let q = &mut self.pending[k];
                if q.len() == PENDING {
                    q.pop_front();
                }
                q.push_back(t);
            }
        }
    }
}
