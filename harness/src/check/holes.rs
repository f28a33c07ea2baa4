//! A long recording to measure `check` with (issue 14 §4: `examples/check_rss.rs`,
//! `benches/check.rs`): N rigid holes on a fanuc mill (M29, G84, about 530 samples each at 1 ms),
//! and a CSV recorder of a run as a servo trace tool exports it (time, X, Y, Z, spindle speed
//! and angle, a status word of F76.3, RGTAP, RGSPP, RGSPM), with its column map.

use std::io::Write;

use nc_engine::trace::{Event, Signal, Signals, TraceEvent, TraceMeta, TraceSink};

/// The column map of [`Csv`]'s files.
pub const MAP: &str = "time: {column: t_us, unit: us}\naxes:\n  - {axis: X, column: X}\n  - {axis: Y, column: Y}\n  - {axis: Z, column: Z}\nspindle:\n  rpm: {column: S}\n  angle_deg: {column: A}\nsignals:\n  - {signal: F76.3, column: flags, bit: 0}\n  - {signal: RGTAP, column: flags, bit: 1}\n  - {signal: RGSPP, column: flags, bit: 2}\n  - {signal: RGSPM, column: flags, bit: 3}\n";

/// The signals of the status word, bit 0 first.
pub const BITS: [Signal; 4] = [Signal::Rtap, Signal::Rgtap, Signal::Rgspp, Signal::Rgspm];

/// `n` rigid holes on a fanuc mill, 5 mm apart.
pub fn program(n: usize) -> String {
    let mut p = String::from("G90 G00 X0 Y0 Z10\nM29 S2000\nG99 G84 X0 Y0 Z-5 R1 F3000\n");
    for i in 1..n {
        p.push_str(&format!("X{} Y{}\n", (i % 100) * 5, (i / 100) * 5));
    }
    p.push_str("G80\nM30\n");
    p
}

/// Writes the CSV rows of a run: a row per sample with the signal levels then.
pub struct Csv<W: Write> {
    /// Where the rows go.
    pub out: W,
    sig: Signals,
}

impl<W: Write> Csv<W> {
    /// A recorder writing into `out`.
    pub fn new(out: W) -> Self {
        Csv { out, sig: Signals::default() }
    }
}

impl<W: Write> TraceSink for Csv<W> {
    fn start(&mut self, _meta: &TraceMeta) {
        let _ = writeln!(self.out, "t_us,X,Y,Z,S,A,flags");
    }
    fn event(&mut self, ev: &TraceEvent) {
        match &ev.event {
            Event::Signal { signal, value } => self.sig.set(*signal, *value),
            Event::Sample(s) => {
                let flags: u32 = BITS.iter().enumerate().map(|(k, &b)| u32::from(self.sig.get(b)) << k).sum();
                let mm = |v: i64| v as f64 / 1e6;
                let _ = writeln!(
                    self.out,
                    "{},{},{},{},{},{},{}",
                    ev.t_us,
                    mm(s.axes[0]),
                    mm(s.axes[1]),
                    mm(s.axes[2]),
                    s.spindle_mrpm as f64 / 1000.0,
                    s.spindle_mdeg as f64 / 1000.0,
                    flags
                );
            }
            _ => {}
        }
    }
}
