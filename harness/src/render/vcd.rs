//! The VCD (Value Change Dump, IEEE 1364 §18) writer, for waveform viewers such as GTKWave and
//! Surfer.
//!
//! The file is a pure function of the trace (no `$date`; `$version nc-conform`), with
//! `$timescale 1 us` so that times are the trace's `t_us`. Variables, in this order, with
//! identifier codes given in sequence from `!` (one printable character each for the first 94):
//!
//! | scope | variable | type | value |
//! | --- | --- | --- | --- |
//! | `signals` | every signal of [`Signal::ALL`], in its order | `wire 1` | the level; `.` in a name is written `_` (`F76_3`), because viewers take `.` as a scope separator |
//! | `axes` | one per axis of the trace's meta, named by its letter | `real 64` | machine position in mm (degrees for a rotary axis), as reported (diameter for a lathe's X) |
//! | `spindle` | `rpm`, `angle_deg` | `real 64` | signed speed (+ forward) and angle |
//! | `cycle` | `phase` | `reg 8` | 0 idle, 1 positioning, 2 cutting, 3 dwell, 4 retract, 5 overload_retract |
//! | `cycle` | `line` | `integer 32` | source line of the block executing (0 before the first) |
//! | `cycle` | `alarms` | `integer 32` | alarms raised so far |
//!
//! (The phase is a numbered `reg` rather than a `string` variable: `string` is an extension that
//! not every reader accepts.)
//!
//! `$dumpvars` at `#0` gives the initial values: signals 0 (the engine starts with every signal
//! off), phase idle, line and alarms 0, positions and spindle from the first sample (the end state
//! when the trace has none). Then come the changes in the trace's order, each timestamp written
//! once, before its first change; a value is written only when it differs from the last one
//! written for its variable. Signal edges are written one by one, so a pulse of zero width (two
//! edges at the same time) shows as two changes at one timestamp. Reals change only with samples
//! and with the end state, written as exact decimals (`r-12.5 "`). The file ends with a timestamp
//! at the end event's time.

use std::io::{self, Write};

use nc_engine::trace::{Event, Phase, Sample, Signal, Trace};

use crate::jsonl::{push_fixed, push_u64};

/// Bytes gathered before they are written out.
const CHUNK: usize = 64 * 1024;

/// The number of a phase in the `cycle.phase` variable.
pub fn phase_code(p: Phase) -> u8 {
    match p {
        Phase::Idle => 0,
        Phase::Positioning => 1,
        Phase::Cutting => 2,
        Phase::Dwell => 3,
        Phase::Retract => 4,
        Phase::OverloadRetract => 5,
    }
}

/// The variable name of a signal (`F76.3` → `F76_3`).
pub fn signal_var_name(s: Signal) -> String {
    s.name().replace('.', "_")
}

/// The identifier code of the `n`-th variable: base 94 over the printable characters `!`..`~`.
pub fn id_code(mut n: usize) -> String {
    let mut code = Vec::new();
    loop {
        code.push(b'!' + (n % 94) as u8);
        n /= 94;
        if n == 0 {
            break;
        }
        n -= 1;
    }
    code.reverse();
    String::from_utf8(code).unwrap_or_default()
}

/// One real variable: where its value comes from in a sample, and its decimals.
#[derive(Clone, Copy)]
enum RealSrc {
    Axis(usize),
    Rpm,
    Angle,
}

impl RealSrc {
    fn get(self, s: &Sample) -> i64 {
        match self {
            RealSrc::Axis(slot) => s.axes.get(slot).copied().unwrap_or(0),
            RealSrc::Rpm => s.spindle_mrpm,
            RealSrc::Angle => s.spindle_mdeg,
        }
    }

    fn decimals(self) -> u32 {
        match self {
            RealSrc::Axis(_) => 6,
            RealSrc::Rpm | RealSrc::Angle => 3,
        }
    }
}

struct Out<'a, W: Write> {
    out: &'a mut W,
    buf: Vec<u8>,
    /// Time of the last `#t` written.
    written_t: Option<u64>,
    /// Time of the event being written.
    now: u64,
}

impl<W: Write> Out<'_, W> {
    fn stamp(&mut self) {
        if self.written_t != Some(self.now) {
            self.buf.push(b'#');
            push_u64(&mut self.buf, self.now);
            self.buf.push(b'\n');
            self.written_t = Some(self.now);
        }
    }

    fn scalar(&mut self, v: bool, id: &str) {
        self.stamp();
        self.buf.push(if v { b'1' } else { b'0' });
        self.buf.extend_from_slice(id.as_bytes());
        self.buf.push(b'\n');
    }

    fn real(&mut self, v: i64, decimals: u32, id: &str) {
        self.stamp();
        self.buf.push(b'r');
        push_fixed(&mut self.buf, v, decimals);
        self.buf.push(b' ');
        self.buf.extend_from_slice(id.as_bytes());
        self.buf.push(b'\n');
    }

    fn vector(&mut self, v: u64, id: &str) {
        self.stamp();
        self.buf.extend_from_slice(format!("b{v:b} {id}\n").as_bytes());
    }

    fn line(&mut self, s: &str) {
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(b'\n');
    }

    fn maybe_flush(&mut self) -> io::Result<()> {
        if self.buf.len() >= CHUNK {
            self.out.write_all(&self.buf)?;
            self.buf.clear();
        }
        Ok(())
    }
}

/// Writes `trace` as a VCD file (see the module doc for its variables and conventions).
///
/// # Errors
///
/// The first error of `out`.
pub fn write_vcd(trace: &Trace, out: &mut impl Write) -> io::Result<()> {
    let mut o = Out { out, buf: Vec::with_capacity(CHUNK + 4096), written_t: None, now: 0 };
    let mut next_id = 0usize;
    let mut new_id = || {
        next_id += 1;
        id_code(next_id - 1)
    };

    let sig_ids: Vec<String> = Signal::ALL.iter().map(|_| new_id()).collect();
    let mut reals: Vec<(RealSrc, String, String)> = Vec::new();
    for a in &trace.meta.axes {
        reals.push((RealSrc::Axis(a.index), new_id(), a.letter.to_string()));
    }
    reals.push((RealSrc::Rpm, new_id(), "rpm".into()));
    reals.push((RealSrc::Angle, new_id(), "angle_deg".into()));
    let (phase_id, line_id, alarms_id) = (new_id(), new_id(), new_id());

    let m = &trace.meta;
    o.line("$version nc-conform $end");
    o.line(&format!(
        "$comment dialect {} period_us {} sample_us {} $end",
        m.dialect, m.period_us, m.sample_us
    ));
    o.line("$timescale 1 us $end");
    o.line("$scope module signals $end");
    for (s, id) in Signal::ALL.iter().zip(&sig_ids) {
        o.line(&format!("$var wire 1 {id} {} $end", signal_var_name(*s)));
    }
    o.line("$upscope $end");
    let n_axes = trace.meta.axes.len();
    for (i, (_, id, name)) in reals.iter().enumerate() {
        if i == 0 && n_axes > 0 {
            o.line("$scope module axes $end");
        }
        if i == n_axes {
            if n_axes > 0 {
                o.line("$upscope $end");
            }
            o.line("$scope module spindle $end");
        }
        o.line(&format!("$var real 64 {id} {name} $end"));
    }
    o.line("$upscope $end");
    o.line("$scope module cycle $end");
    o.line(&format!("$var reg 8 {phase_id} phase $end"));
    o.line(&format!("$var integer 32 {line_id} line $end"));
    o.line(&format!("$var integer 32 {alarms_id} alarms $end"));
    o.line("$upscope $end");
    o.line("$enddefinitions $end");

    // Initial values.
    let first = trace.samples().next().map(|(_, s)| *s).or_else(|| trace.end().map(|e| e.state));
    let first = first.unwrap_or_default();
    let mut sig_state = [false; Signal::ALL.len()];
    let mut real_state: Vec<i64> = reals.iter().map(|(src, _, _)| src.get(&first)).collect();
    let (mut phase, mut line, mut alarms) = (0u8, 0u64, 0u64);
    o.stamp();
    o.line("$dumpvars");
    for id in &sig_ids {
        o.scalar(false, id);
    }
    for ((src, id, _), v) in reals.iter().zip(&real_state) {
        o.real(*v, src.decimals(), id);
    }
    o.vector(0, &phase_id);
    o.vector(0, &line_id);
    o.vector(0, &alarms_id);
    o.line("$end");

    let sig_index = |s: Signal| Signal::ALL.iter().position(|x| *x == s).unwrap_or(0);
    for e in &trace.events {
        o.now = e.t_us;
        let sample = match &e.event {
            Event::Sample(s) => Some(*s),
            Event::Signal { signal, value } => {
                let i = sig_index(*signal);
                if sig_state[i] != *value {
                    sig_state[i] = *value;
                    o.scalar(*value, &sig_ids[i]);
                }
                None
            }
            Event::Phase(p) => {
                if phase_code(*p) != phase {
                    phase = phase_code(*p);
                    o.vector(u64::from(phase), &phase_id);
                }
                None
            }
            Event::Block { line: l, .. } => {
                if u64::from(*l) != line {
                    line = u64::from(*l);
                    o.vector(line, &line_id);
                }
                None
            }
            Event::Alarm(_) => {
                alarms += 1;
                o.vector(alarms, &alarms_id);
                None
            }
            Event::End(end) => {
                for (i, s) in Signal::ALL.iter().enumerate() {
                    if sig_state[i] != end.signals.get(*s) {
                        sig_state[i] = end.signals.get(*s);
                        o.scalar(sig_state[i], &sig_ids[i]);
                    }
                }
                Some(end.state)
            }
            Event::Function { .. } | Event::Input { .. } => None,
        };
        if let Some(s) = sample {
            for ((src, id, _), last) in reals.iter().zip(real_state.iter_mut()) {
                let v = src.get(&s);
                if v != *last {
                    *last = v;
                    o.real(v, src.decimals(), id);
                }
            }
        }
        o.maybe_flush()?;
    }
    o.stamp();
    o.out.write_all(&o.buf)?;
    o.out.flush()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nc_engine::trace::{AxisSpec, EndReason, EndSummary, Signals, TraceEvent, TraceMeta};

    #[test]
    fn id_codes_are_short_and_distinct() {
        assert_eq!(id_code(0), "!");
        assert_eq!(id_code(93), "~");
        assert_eq!(id_code(94), "!!");
        let all: std::collections::BTreeSet<String> = (0..20_000).map(id_code).collect();
        assert_eq!(all.len(), 20_000);
    }

    fn small_trace() -> Trace {
        let mut s1 = Sample::default();
        s1.axes[2] = -1_500_000;
        s1.spindle_mrpm = 100_000;
        let mut signals = Signals::default();
        signals.set(Signal::Zsp, true);
        let ev = |t_us, event| TraceEvent { t_us, event };
        Trace {
            meta: TraceMeta {
                dialect: "fanuc-mill",
                axes: vec![AxisSpec { letter: 'Z', index: 2, diameter: false, rotary: false }],
                period_us: 1000,
                sample_us: 1000,
            },
            events: vec![
                ev(0, Event::Sample(Sample::default())),
                ev(0, Event::Signal { signal: Signal::Zsp, value: true }),
                ev(0, Event::Block { line: 1, text: "G84".into() }),
                ev(1000, Event::Sample(Sample::default())),
                ev(1500, Event::Phase(Phase::Cutting)),
                ev(1500, Event::Signal { signal: Signal::Rtap, value: true }),
                ev(1500, Event::Signal { signal: Signal::Rtap, value: false }),
                ev(2000, Event::Sample(s1)),
                ev(
                    2500,
                    Event::End(Box::new(EndSummary {
                        reason: EndReason::ProgramEnd,
                        state: s1,
                        command: [0; 6],
                        signals,
                        modal: vec![],
                        alarms: 0,
                        blocks: 1,
                    })),
                ),
            ],
        }
    }

    #[test]
    fn small_trace_gives_exact_text() {
        let mut out = Vec::new();
        write_vcd(&small_trace(), &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        let body = text.split("$enddefinitions $end\n").nth(1).unwrap();
        let want = "#0\n$dumpvars\n0!\n0\"\n0#\n0$\n0%\n0&\n0'\n0(\n0)\n0*\n0+\n0,\n0-\n0.\nr0 /\nr0 0\n\
                    r0 1\nb0 2\nb0 3\nb0 4\n$end\n1.\nb1 3\n#1500\nb10 2\n1%\n0%\n#2000\nr-1.5 /\nr100 0\n#2500\n";
        assert_eq!(body, want);
        assert!(text.contains("$var wire 1 % F76_3 $end\n"));
        assert!(text.contains("$scope module axes $end\n$var real 64 / Z $end\n$upscope $end\n"));
        assert!(!text.contains("$date"));
    }

    #[test]
    fn same_trace_same_bytes() {
        let (mut a, mut b) = (Vec::new(), Vec::new());
        write_vcd(&small_trace(), &mut a).unwrap();
        write_vcd(&small_trace(), &mut b).unwrap();
        assert_eq!(a, b);
    }
}
