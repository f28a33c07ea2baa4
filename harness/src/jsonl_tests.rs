//! Unit tests of the JSON Lines writer: exact lines, and a round trip through serde_json.

use super::*;
use nc_engine::alarm::AlarmKind;
use nc_engine::trace::{Phase, Signal};
use nc_engine::units::{fixed_string, nm_to_mm_string};
use serde_json::Value;

fn gsk_meta() -> TraceMeta {
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

fn sample(x: i64, z: i64, c: i64, mrpm: i64, mdeg: i64) -> Sample {
    let mut axes = [0; AXES];
    axes[0] = x;
    axes[2] = z;
    axes[5] = c;
    Sample { axes, spindle_mrpm: mrpm, spindle_mdeg: mdeg }
}

fn events() -> Vec<TraceEvent> {
    let mut signals = Signals::default();
    signals.set(Signal::Rgtap, true);
    signals.set(Signal::Zsp, true);
    let ev = |t_us, event| TraceEvent { t_us, event };
    vec![
        ev(0, Event::Block { line: 5, text: "G88 X-50 P3000 F2 (say \"hi\"\\\t)".into() }),
        ev(0, Event::Function { letter: 'M', code: 29 }),
        ev(0, Event::Signal { signal: Signal::Rtap, value: true }),
        ev(1000, Event::Sample(sample(50_000_000, 0, 0, 1_000_000, 12_500))),
        ev(2000, Event::Sample(sample(-1, -12_345_678, 90_000_000_000, -250_500, 359_999))),
        ev(2500, Event::Phase(Phase::Cutting)),
        ev(2600, Event::Input { name: "feed_hold".into(), value: String::new() }),
        ev(2700, Event::Alarm(Alarm::new(AlarmKind::IllegalAxisOperation, "Z moved").at(7, Some(3)))),
        ev(2800, Event::Alarm(Alarm::new(AlarmKind::EmergencyStop, ""))),
        ev(
            3000,
            Event::End(Box::new(EndSummary {
                reason: EndReason::Alarm,
                state: sample(50_000_000, -1_500_000, 0, 0, 0),
                command: [1, 2, 3, 4, 5, 6],
                signals,
                modal: vec!["G00".into(), "G98".into()],
                alarms: 2,
                blocks: 12,
            })),
        ),
    ]
}

fn write_all(meta: &TraceMeta, evs: &[TraceEvent]) -> (String, Option<EndReason>) {
    let mut w = JsonlWriter::new(Vec::new());
    w.start(meta);
    for e in evs {
        w.event(e);
    }
    let end = w.end_reason().cloned();
    (String::from_utf8(w.finish().unwrap()).unwrap(), end)
}

#[test]
fn lines_are_exact() {
    let (text, end) = write_all(&gsk_meta(), &events());
    assert_eq!(end, Some(EndReason::Alarm));
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 11);
    assert_eq!(
        lines[0],
        r#"{"t_us":0,"kind":"meta","dialect":"gsk-lathe","axes":["X","Z","C"],"diameter":["X"],"period_us":1000,"sample_us":1000,"format":"nc-conform-trace/1"}"#
    );
    assert_eq!(lines[1], r#"{"t_us":0,"kind":"block","line":5,"text":"G88 X-50 P3000 F2 (say \"hi\"\\\t)"}"#);
    assert_eq!(lines[2], r#"{"t_us":0,"kind":"function","letter":"M","code":29}"#);
    assert_eq!(lines[3], r#"{"t_us":0,"kind":"signal","name":"F76.3","value":1}"#);
    assert_eq!(
        lines[4],
        r#"{"t_us":1000,"kind":"sample","axes":{"X":50,"Z":0,"C":0},"spindle":{"rpm":1000,"angle_deg":12.5}}"#
    );
    assert_eq!(
        lines[5],
        r#"{"t_us":2000,"kind":"sample","axes":{"X":-0.000001,"Z":-12.345678,"C":90000},"spindle":{"rpm":-250.5,"angle_deg":359.999}}"#
    );
    assert_eq!(lines[6], r#"{"t_us":2500,"kind":"phase","name":"cutting"}"#);
    assert_eq!(lines[7], r#"{"t_us":2600,"kind":"input","name":"feed_hold","value":""}"#);
    assert_eq!(
        lines[8],
        r#"{"t_us":2700,"kind":"alarm","code":"0204","message":"ILLEGAL AXIS OPERATION: Z moved (line 7, column 3)","line":7,"col":3}"#
    );
    assert_eq!(lines[9], r#"{"t_us":2800,"kind":"alarm","code":"NC-1030","message":"EMERGENCY STOP"}"#);
    assert_eq!(
        lines[10],
        concat!(
            r#"{"t_us":3000,"kind":"end","reason":"alarm","axes":{"X":50,"Z":-1.5,"C":0},"#,
            r#""command":{"X":0.000001,"Z":0.000003,"C":0.000006},"spindle":{"rpm":0,"angle_deg":0},"#,
            r#""signals":{"MF":0,"SF":0,"TF":0,"FIN":0,"F76.3":0,"RGTAP":1,"SPPOS":0,"SPPOSA":0,"#,
            r#""RGSPP":0,"RGSPM":0,"SPL":0,"STL":0,"ESP":0,"ZSP":1},"#,
            r#""modal":["G00","G98"],"alarms":2,"blocks":12}"#
        )
    );
}

/// A JSON number equals the decimal text (both parsed the same way; the exact text is checked by
/// `lines_are_exact`).
fn num_eq(v: &Value, text: &str) {
    assert!(v.is_number(), "{v} is not a number");
    assert_eq!(v.as_f64(), text.parse::<f64>().ok(), "{v} vs {text}");
}

/// Every line parses as JSON; its fields are the event's, in the documented order.
#[test]
fn round_trip_through_serde_json() {
    let meta = gsk_meta();
    let evs = events();
    let (text, _) = write_all(&meta, &evs);
    let lines: Vec<&str> = text.lines().collect();
    let first: Value = serde_json::from_str(lines[0]).unwrap();
    assert_eq!(first["kind"], "meta");
    assert_eq!(first["axes"], serde_json::json!(["X", "Z", "C"]));
    for (line, ev) in lines[1..].iter().zip(&evs) {
        let v: Value = serde_json::from_str(line).unwrap_or_else(|e| panic!("{e}: {line}"));
        assert!(line.starts_with(&format!("{{\"t_us\":{},\"kind\":\"", ev.t_us)), "{line}");
        assert_eq!(v["t_us"].as_u64(), Some(ev.t_us));
        match &ev.event {
            Event::Sample(s) => {
                assert_eq!(v["kind"], "sample");
                for a in &meta.axes {
                    num_eq(&v["axes"][a.letter.to_string()], &nm_to_mm_string(s.axes[a.index]));
                }
                num_eq(&v["spindle"]["rpm"], &fixed_string(s.spindle_mrpm, 3));
                num_eq(&v["spindle"]["angle_deg"], &fixed_string(s.spindle_mdeg, 3));
            }
            Event::Signal { signal, value } => {
                assert_eq!(v["kind"], "signal");
                assert_eq!(v["name"], signal.name());
                assert_eq!(v["value"], u8::from(*value));
            }
            Event::Block { line: l, text } => {
                assert_eq!(v["kind"], "block");
                assert_eq!(v["line"], *l);
                assert_eq!(v["text"], text.as_str());
            }
            Event::Function { letter, code } => {
                assert_eq!(v["kind"], "function");
                assert_eq!(v["letter"], letter.to_string());
                assert_eq!(v["code"], *code);
            }
            Event::Alarm(a) => {
                assert_eq!(v["kind"], "alarm");
                assert_eq!(v["code"], a.kind.code());
                assert_eq!(v["message"], a.message());
                assert_eq!(v.get("line").and_then(Value::as_u64), a.line.map(u64::from));
                assert_eq!(v.get("col").and_then(Value::as_u64), a.col.map(u64::from));
            }
            Event::Phase(p) => {
                assert_eq!(v["kind"], "phase");
                assert_eq!(v["name"], p.name());
            }
            Event::Input { name, value } => {
                assert_eq!(v["kind"], "input");
                assert_eq!(v["name"], name.as_str());
                assert_eq!(v["value"], value.as_str());
            }
            Event::End(s) => {
                assert_eq!(v["kind"], "end");
                assert_eq!(v["reason"], s.reason.name());
                assert_eq!(v["alarms"], s.alarms);
                assert_eq!(v["blocks"], s.blocks);
                assert_eq!(v["modal"], serde_json::json!(s.modal));
                let sigs = v["signals"].as_object().unwrap();
                assert_eq!(sigs.len(), Signal::ALL.len());
                for sig in Signal::ALL {
                    assert_eq!(sigs[sig.name()], u8::from(s.signals.get(sig)));
                }
                for a in &meta.axes {
                    let k = a.letter.to_string();
                    num_eq(&v["axes"][&k], &nm_to_mm_string(s.state.axes[a.index]));
                    num_eq(&v["command"][&k], &nm_to_mm_string(s.command[a.index]));
                }
            }
        }
    }
}

#[test]
fn fixed_matches_the_engine_formatting() {
    let mut vals =
        vec![0, 1, -1, 9, 10, 100, 999_999, 1_000_000, -1_000_001, i64::MAX, i64::MIN, i64::MIN + 1];
    let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
    for _ in 0..20_000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let shift = x % 64;
        vals.push((x as i64) >> shift);
    }
    for v in vals {
        for d in [0, 3, 6] {
            let mut b = Vec::new();
            push_fixed(&mut b, v, d);
            assert_eq!(String::from_utf8(b).unwrap(), fixed_string(v, d), "{v} {d}");
        }
        let mut b = Vec::new();
        push_fixed(&mut b, v, 6);
        assert_eq!(String::from_utf8(b).unwrap(), nm_to_mm_string(v));
    }
}

#[test]
fn strings_are_escaped_as_json() {
    for s in ["", "plain", "quote\" back\\ nl\n cr\r tab\t", "\u{1}\u{1f}\u{7f}", "Ø10 — µs", "\u{8}\u{c}"]
    {
        let mut b = Vec::new();
        push_json_str(&mut b, s);
        let text = String::from_utf8(b).unwrap();
        let back: String = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}: {text}"));
        assert_eq!(back, s);
        assert!(!text[1..text.len() - 1].chars().any(|c| c.is_control() && c != '\u{7f}'), "{text}");
    }
}

#[test]
fn no_axes_and_no_samples_still_give_valid_json() {
    let meta = TraceMeta { dialect: "x", axes: Vec::new(), period_us: 0, sample_us: 0 };
    let (text, _) = write_all(&meta, &events()[3..4]);
    for line in text.lines() {
        let _: Value = serde_json::from_str(line).unwrap();
    }
    assert!(text.contains(r#""axes":{}"#), "{text}");
}

/// Large traces go out in chunks and come out whole.
#[test]
fn long_traces_are_written_whole() {
    let mut w = JsonlWriter::new(Vec::new());
    w.start(&gsk_meta());
    let n = 10_000u64;
    for i in 0..n {
        let t_us = i * 1000;
        let i = i as i64;
        w.event(&TraceEvent { t_us, event: Event::Sample(sample(i, -i, 0, 1000, i % 360_000)) });
    }
    let text = String::from_utf8(w.finish().unwrap()).unwrap();
    assert_eq!(text.lines().count() as u64, n + 1);
    assert!(text.ends_with("\n"));
}

/// The first write error is kept and returned by `finish`.
#[test]
fn write_errors_surface_in_finish() {
    struct Broken;
    impl Write for Broken {
        fn write(&mut self, _: &[u8]) -> io::Result<usize> {
            Err(io::Error::new(io::ErrorKind::BrokenPipe, "closed"))
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }
    let mut w = JsonlWriter::new(Broken);
    w.start(&gsk_meta());
    for e in events() {
        w.event(&e);
    }
    assert_eq!(w.finish().err().map(|e| e.kind()), Some(io::ErrorKind::BrokenPipe));
}

/// The numbers of the sample lines ([`fixed_at`], [`digits_at`]) have the text [`push_fixed`] and
/// [`push_u64`] give, for every magnitude and sign.
#[test]
fn sample_numbers_match_the_general_formatting() {
    let mut vals = vec![0, 1, -1, 9, 10, 999, 1000, -1000, 1_000_001, i64::MAX, i64::MIN, i64::MIN + 1];
    let mut x: u64 = 0x2545_f491_4f6c_dd1d;
    for _ in 0..20_000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        vals.push((x as i64) >> (x % 64));
    }
    for v in vals {
        let mut t = [b'#'; 32];
        for d in [0, 3, 6] {
            let n = match d {
                0 => fixed_at::<0>(&mut t, 3, v),
                3 => fixed_at::<3>(&mut t, 3, v),
                _ => fixed_at::<6>(&mut t, 3, v),
            };
            let mut b = Vec::new();
            push_fixed(&mut b, v, d);
            assert_eq!(&t[3..n], &b[..], "{v} {d}");
        }
        let mut b = Vec::new();
        push_u64(&mut b, v as u64);
        let n = digits_at(&mut t, 1, v as u64);
        assert_eq!(&t[1..n], &b[..], "{v}");
    }
}

/// A sample line written by the fast path is the line of the general path, byte for byte
/// (repeated values copied from the cache, changed ones formatted again).
#[test]
fn sample_lines_match_the_general_path() {
    let meta = gsk_meta();
    let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut evs = Vec::new();
    for k in 0..5000u64 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let v = |sh: u64| if x.is_multiple_of(3) { 1_234_567 } else { (x as i64) >> ((x >> sh) % 64) };
        evs.push(TraceEvent {
            t_us: k * 1000 + (x % 7),
            event: Event::Sample(sample(v(1), v(2), v(3), v(4), v(5))),
        });
    }
    let mut fast = JsonlWriter::new(Vec::new());
    let mut general = JsonlWriter::new(Vec::new());
    fast.write_meta(&meta);
    general.write_meta(&meta);
    general.keys = None;
    for e in &evs {
        fast.write_event(e);
        general.write_event(e);
    }
    let (a, b) = (fast.finish().unwrap(), general.finish().unwrap());
    assert!(a.len() > 300_000);
    assert_eq!(String::from_utf8(a).unwrap(), String::from_utf8(b).unwrap());
}
