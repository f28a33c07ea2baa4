//! The event listing: one line per non-sample event, for snapshots and quick reading.
//!
//! Format of a line: the time in ms with three decimals right-aligned in 10 columns, a space,
//! what happened, and ` |` (a visible border, so a change of trailing whitespace in a block's
//! text cannot hide in a snapshot diff):
//!
//! ```text
//!      0.000 block 1 G98; |
//!    354.000 signal RGTAP 1 |
//! ```
//!
//! | event | text |
//! | --- | --- |
//! | block | `block <line> <source text>` |
//! | function | `function M29`, `function S1000` |
//! | signal | `signal F76.3 1` |
//! | alarm | `alarm <code> <message>` (message as [`Alarm::message`](nc_engine::Alarm::message)) |
//! | phase | `phase cutting` |
//! | input | `input feed_hold`, `input machine_lock on` (the value only when not empty) |
//! | end | `end program_end blocks=7 alarms=0 X=50 Z=0 C=0 rpm=0` |
//!
//! The `end` line lists the final machine position of every axis of the trace's meta, in its
//! order, in mm (degrees for a rotary axis) written exactly with no trailing zeros, then the final
//! spindle speed in rpm. Control characters in texts are escaped (`\n`, `\t`) so that every event
//! stays on one line.

use std::fmt::Write as _;

use nc_engine::trace::{Event, Trace};

use super::{fixed, ms3, one_line};

/// The listing of every non-sample event of `trace`, one line each (see the module doc).
pub fn event_listing(trace: &Trace) -> String {
    let mut s = String::new();
    for e in &trace.events {
        let what = match &e.event {
            Event::Sample(_) => continue,
            Event::Signal { signal, value } => format!("signal {} {}", signal.name(), u8::from(*value)),
            Event::Block { line, text } => format!("block {line} {}", one_line(text)),
            Event::Function { letter, code } => format!("function {letter}{code}"),
            Event::Alarm(a) => format!("alarm {} {}", a.kind.code(), one_line(&a.message())),
            Event::Phase(p) => format!("phase {}", p.name()),
            Event::Input { name, value } if value.is_empty() => format!("input {}", one_line(name)),
            Event::Input { name, value } => format!("input {} {}", one_line(name), one_line(value)),
            Event::End(end) => {
                let mut w = format!("end {} blocks={} alarms={}", end.reason.name(), end.blocks, end.alarms);
                for a in &trace.meta.axes {
                    let v = end.state.axes.get(a.index).copied().unwrap_or(0);
                    let _ = write!(w, " {}={}", a.letter, fixed(v, 6));
                }
                let _ = write!(w, " rpm={}", fixed(end.state.spindle_mrpm, 3));
                w
            }
        };
        let _ = writeln!(s, "{:>10} {what} |", ms3(e.t_us));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use nc_engine::alarm::{Alarm, AlarmKind};
    use nc_engine::trace::{
        AxisSpec, EndReason, EndSummary, Phase, Sample, Signal, Signals, TraceEvent, TraceMeta,
    };

    fn meta() -> TraceMeta {
        TraceMeta {
            dialect: "gsk-lathe",
            axes: vec![
                AxisSpec { letter: 'X', index: 0, diameter: true, rotary: false },
                AxisSpec { letter: 'Z', index: 2, diameter: false, rotary: false },
                AxisSpec { letter: 'C', index: 5, diameter: false, rotary: true },
            ],
            period_us: 1000,
            sample_us: 1000,
        }
    }

    fn ev(t_us: u64, event: Event) -> TraceEvent {
        TraceEvent { t_us, event }
    }

    #[test]
    fn every_kind_of_event_has_its_line() {
        let mut state = Sample::default();
        state.axes[0] = 50_000_000;
        state.axes[2] = -1_500_000;
        state.axes[5] = 90_000_000;
        state.spindle_mrpm = -1_000_500;
        let trace = Trace {
            meta: meta(),
            events: vec![
                ev(0, Event::Block { line: 1, text: "G98; ".into() }),
                ev(0, Event::Sample(Sample::default())),
                ev(12, Event::Function { letter: 'M', code: 29 }),
                ev(354_000, Event::Signal { signal: Signal::Rgtap, value: true }),
                ev(354_000, Event::Signal { signal: Signal::Rtap, value: false }),
                ev(400_001, Event::Phase(Phase::OverloadRetract)),
                ev(400_001, Event::Input { name: "feed_hold".into(), value: String::new() }),
                ev(400_001, Event::Input { name: "machine_lock".into(), value: "on".into() }),
                ev(1_234_567, Event::Alarm(Alarm::new(AlarmKind::AxisMoveAfterM29, "Z moved").at(4, None))),
                ev(
                    12_345_678_901,
                    Event::End(Box::new(EndSummary {
                        reason: EndReason::ProgramEnd,
                        state,
                        command: [0; 6],
                        signals: Signals::default(),
                        modal: vec![],
                        alarms: 1,
                        blocks: 7,
                    })),
                ),
            ],
        };
        let want = "     0.000 block 1 G98;  |
     0.012 function M29 |
   354.000 signal RGTAP 1 |
   354.000 signal F76.3 0 |
   400.001 phase overload_retract |
   400.001 input feed_hold |
   400.001 input machine_lock on |
  1234.567 alarm NC-1011 AXIS MOVE BETWEEN M29 AND TAPPING CYCLE: Z moved (line 4) |
12345678.901 end program_end blocks=7 alarms=1 X=50 Z=-1.5 C=90 rpm=-1000.5 |
";
        assert_eq!(event_listing(&trace), want);
    }

    #[test]
    fn multi_line_texts_stay_on_one_line() {
        let trace =
            Trace { meta: meta(), events: vec![ev(5, Event::Block { line: 2, text: "G0\nX1".into() })] };
        assert_eq!(event_listing(&trace), "     0.005 block 2 G0\\nX1 |\n");
    }

    #[test]
    fn samples_only_give_nothing() {
        let trace = Trace { meta: meta(), events: vec![ev(0, Event::Sample(Sample::default()))] };
        assert_eq!(event_listing(&trace), "");
    }
}
