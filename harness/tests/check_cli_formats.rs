//! `nc-conform check` with a CSV trace (and `--map`) and with an MTConnect SHDR trace: a
//! conformant recording in either format passes (with jitter, noise, lost samples, another
//! sample rate and another clock), the reference events the format cannot carry are counted as
//! not comparable and the default anchor falls back to one it carries; a defect exits 1 naming
//! its rule; a malformed row exits 2 and names `file:line:col`.

mod check_util;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use check_util::*;
use nc_engine::trace::{Event, Sample, Signal, Trace, TraceEvent};

const BIN: &str = env!("CARGO_BIN_EXE_nc-conform");
const CLAMP: &str = "scenarios/gsk/clamp/clamp_codes_frame_the_hole.yaml";

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("nc-conform-checkfmt-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn check(args: &[&str]) -> Output {
    Command::new(BIN).current_dir(root()).arg("check").args(args).output().expect("run nc-conform")
}

#[test]
fn csv_malformed_row_exits_2_with_file_line_col() {
    let d = dir("csv");
    let map = d.join("map.yaml");
    std::fs::write(
        &map,
        "time: {column: t_ms, unit: ms}\naxes:\n  - {axis: Z, column: Z}\nsignals:\n  - {signal: RGTAP, column: RGTAP}\n",
    )
    .unwrap();
    let csv = d.join("rec.csv");
    std::fs::write(&csv, "t_ms,Z,RGTAP\n0,0.0,0\n1,-0.1,1\n2,abc,1\n").unwrap();
    let out = check(&[CLAMP, "--trace", csv.to_str().unwrap(), "--map", map.to_str().unwrap()]);
    let e = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{e}");
    assert!(e.contains("rec.csv:4:3"), "{e}");
    assert!(e.contains("not a number"), "{e}");
    // Without --map a CSV trace is an input error too.
    let out = check(&[CLAMP, "--trace", csv.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn shdr_malformed_line_exits_2_with_file_line_col() {
    let d = dir("shdr");
    let shdr = d.join("rec.shdr");
    std::fs::write(
        &shdr,
        "2024-05-01T10:00:00.000000Z|Xact|50|Zact|0|Sspeed|0\n2024-05-01T10:00:00.5Z|Zact|oops\n",
    )
    .unwrap();
    let out = check(&[CLAMP, "--trace", shdr.to_str().unwrap()]);
    let e = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{e}");
    assert!(e.contains("rec.shdr:2:"), "{e}");
}

/// Signals with an edge in `events`, sorted.
fn signals_of(events: &[TraceEvent]) -> Vec<Signal> {
    let mut v: Vec<Signal> = events
        .iter()
        .filter_map(|e| match e.event {
            Event::Signal { signal, .. } => Some(signal),
            _ => None,
        })
        .collect();
    v.sort();
    v.dedup();
    v
}

/// Writes recorded samples and the levels of `sigs` as CSV (time in ms, one row per sample, the
/// levels at that row; the recorder runs on 100 ms after the last event) and its column map.
fn write_csv(d: &Path, axes: &[(char, usize)], sigs: &[Signal], events: &[TraceEvent]) -> (PathBuf, PathBuf) {
    let mut map = String::from("skip_rows: 1\ntime: {column: \"t [ms]\", unit: ms}\naxes:\n");
    for (l, _) in axes {
        writeln!(map, "  - {{axis: {l}, column: \"{l} act\"}}").unwrap();
    }
    map.push_str("spindle:\n  rpm: {column: S}\n  angle_deg: {column: A}\n");
    if !sigs.is_empty() {
        map.push_str("signals:\n");
    }
    for s in sigs {
        writeln!(map, "  - {{signal: {}, column: \"{}\"}}", s.name(), s.name()).unwrap();
    }
    let mut csv = String::from("Trace export v2.1\nt [ms]");
    for (l, _) in axes {
        write!(csv, ";{l} act").unwrap();
    }
    csv.push_str(";S;A");
    for s in sigs {
        write!(csv, ";{}", s.name()).unwrap();
    }
    csv.push('\n');
    map = map.replace("skip_rows: 1\n", "skip_rows: 1\ndelimiter: \";\"\n");
    let mut level = vec![false; sigs.len()];
    let row = |csv: &mut String, t: u64, x: &Sample, level: &[bool]| {
        write!(csv, "{}", t as f64 / 1000.0).unwrap();
        for (_, slot) in axes {
            write!(csv, ";{}", x.axes[*slot] as f64 / 1e6).unwrap();
        }
        write!(csv, ";{};{}", x.spindle_mrpm as f64 / 1e3, x.spindle_mdeg as f64 / 1e3).unwrap();
        for l in level {
            write!(csv, ";{}", u8::from(*l)).unwrap();
        }
        csv.push('\n');
    };
    let mut last = (0, Sample::default(), 1000);
    for e in events {
        match &e.event {
            Event::Signal { signal, value } => {
                let i = sigs.iter().position(|s| s == signal).unwrap();
                level[i] = *value;
            }
            Event::Sample(x) => {
                last = (e.t_us, *x, (e.t_us - last.0).clamp(500, 10_000));
                row(&mut csv, e.t_us, x, &level);
            }
            _ => {}
        }
    }
    let (t_end, x, period) = last;
    for k in 1..=(100_000 / period) {
        row(&mut csv, t_end + k * period, &x, &level);
    }
    let (c, m) = (d.join("rec.csv"), d.join("rec.map.yaml"));
    std::fs::write(&c, csv).unwrap();
    std::fs::write(&m, map).unwrap();
    (c, m)
}

/// An SHDR time stamp `t_us` after 2024-05-01T10:00:00Z.
fn shdr_time(t_us: u64) -> String {
    let s = t_us / 1_000_000;
    format!("2024-05-01T{:02}:{:02}:{:02}.{:06}Z", 10 + s / 3600, s / 60 % 60, s % 60, t_us % 1_000_000)
}

/// Writes the recorded events as MTConnect SHDR lines: positions (`Xact`...), spindle speed and
/// angle, `execution` from STL and SPL, and, with `plc_keys`, the other signals of `sigs` as
/// keys named after them (an adapter publishing PLC bits: all of them in its first line, as an
/// adapter sends its whole state when an agent connects), alarms with `code` as their native
/// code.
fn write_shdr(
    d: &Path,
    axes: &[(char, usize)],
    sigs: &[Signal],
    events: &[TraceEvent],
    plc_keys: bool,
) -> PathBuf {
    let mut out = String::from("* shdrVersion: 2\n");
    out.push_str(&shdr_time(events.first().map_or(0, |e| e.t_us)));
    out.push_str("|avail|AVAILABLE");
    for s in sigs.iter().filter(|s| plc_keys && !matches!(s, Signal::Stl | Signal::Spl)) {
        write!(out, "|{}|OFF", s.name()).unwrap();
    }
    out.push('\n');
    let (mut stl, mut spl) = (false, false);
    for e in events {
        let mut line = shdr_time(e.t_us);
        match &e.event {
            Event::Sample(x) => {
                for (l, slot) in axes {
                    write!(line, "|{l}act|{}", x.axes[*slot] as f64 / 1e6).unwrap();
                }
                write!(
                    line,
                    "|Sspeed|{}|Sangle|{}",
                    x.spindle_mrpm as f64 / 1e3,
                    x.spindle_mdeg as f64 / 1e3
                )
                .unwrap();
            }
            Event::Signal { signal: Signal::Stl, value } => stl = *value,
            Event::Signal { signal: Signal::Spl, value } => spl = *value,
            Event::Signal { signal, value } if plc_keys => {
                write!(line, "|{}|{}", signal.name(), if *value { "ON" } else { "OFF" }).unwrap()
            }
            Event::Alarm(a) => {
                write!(line, "|alarm|{0}|{0}|FAULT|ACTIVE|{1}", a.kind.code(), a.message()).unwrap()
            }
            _ => continue,
        }
        if matches!(e.event, Event::Signal { signal: Signal::Stl | Signal::Spl, .. }) {
            let state = match (stl, spl) {
                (_, true) => "FEED_HOLD",
                (true, false) => "ACTIVE",
                (false, false) => "READY",
            };
            write!(line, "|execution|{state}").unwrap();
        }
        if line.contains('|') {
            out.push_str(&line);
            out.push('\n');
        }
    }
    let p = d.join("rec.shdr");
    std::fs::write(&p, out).unwrap();
    p
}

/// The recording of `events` as CSV in a fresh directory `name`, with the reference's axes and
/// signals mapped.
fn csv_of(name: &str, reference: &Trace, events: &[TraceEvent]) -> (PathBuf, PathBuf) {
    write_csv(&dir(name), &axes_of(reference), &signals_of(&reference.events), events)
}

/// The recording of `events` as SHDR in a fresh directory `name` (see [`write_shdr`]).
fn shdr_of(name: &str, reference: &Trace, events: &[TraceEvent], plc_keys: bool) -> PathBuf {
    write_shdr(&dir(name), &axes_of(reference), &signals_of(&reference.events), events, plc_keys)
}

/// The lines of the `FAIL` divergences in `check`'s summary.
fn fails(out: &Output) -> Vec<String> {
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| l.trim_start().starts_with("FAIL"))
        .map(String::from)
        .collect()
}

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn axes_of(reference: &Trace) -> Vec<(char, usize)> {
    reference.meta.axes.iter().map(|a| (a.letter, a.index)).collect()
}

/// Two recorders unlike the reference's 1 ms samples: the realistic one (4 ms, jitter, noise,
/// one sample in 40 lost, another clock) and a 2.5 ms one with a clock 17 µs off.
const RECORDERS: [Rec; 2] = [Rec::REALISTIC, Rec { sample_us: 2500, shift_us: 17, ..Rec::REALISTIC }];

#[test]
fn conformant_csv_recordings_pass_and_say_what_csv_cannot_carry() {
    for rel in [
        CLAMP,
        "scenarios/gsk/peck/deep_peck_seed_example.yaml",
        "scenarios/fanuc/seed/peck_rigid_example.yaml",
    ] {
        let reference = reference(&scenario(rel));
        for (k, rec) in RECORDERS.iter().enumerate() {
            let (c, m) = csv_of(&format!("csvok{k}"), &reference, &record(&reference, *rec));
            let out = check(&[rel, "--trace", c.to_str().unwrap(), "--map", m.to_str().unwrap()]);
            let text = stdout(&out);
            assert_eq!(out.status.code(), Some(0), "{rel} {rec:?}:\n{text}");
            assert!(text.contains("CONFORMANT"), "{text}");
            // A CSV has no M functions: counted, not reported missing; the anchor falls back to
            // the answer to M29.
            assert!(text.contains("aligned on the first F76.3 = 1"), "{text}");
            assert!(text.contains("not comparable: csv carries no M/S/T functions"), "{text}");
        }
    }
    let reference = reference(&scenario(CLAMP));
    let (c, m) = csv_of("csvok", &reference, &record(&reference, Rec::REALISTIC));
    let (json, junit) = (c.with_extension("json"), c.with_extension("xml"));
    let out = check(&[
        CLAMP,
        "--trace",
        c.to_str().unwrap(),
        "--map",
        m.to_str().unwrap(),
        "--report",
        json.to_str().unwrap(),
        "--junit",
        junit.to_str().unwrap(),
    ]);
    // The reports say it too: JSON `not_comparable`, a skipped JUnit test case.
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["conformant"], true);
    let nc = &v["report"]["not_comparable"][0];
    assert_eq!((nc["what"].as_str(), nc["count"].as_u64()), (Some("M29, M68, M69, M30"), Some(4)), "{v}");
    let x = std::fs::read_to_string(&junit).unwrap();
    assert!(x.contains("failures=\"0\" errors=\"0\" skipped=\"1\""), "{x}");
    assert!(x.contains("<skipped message=\"not comparable: csv carries no M/S/T functions\"/>"), "{x}");
    assert!(
        stdout(&out).contains(
            "  n/a  M29, M68, M69, M30 (4 reference events): not comparable: csv carries no M/S/T functions"
        ),
        "{}",
        stdout(&out)
    );
}

#[test]
fn csv_map_without_the_stroke_signals_leaves_key_points_out_and_anchors_on_motion() {
    // A map of positions and the spindle only: no signal, so the anchor is the tap axis's first
    // motion and the events and key points are not comparable; positions still are.
    let rel = "scenarios/gsk/peck/deep_peck_seed_example.yaml";
    let reference = reference(&scenario(rel));
    let rec: Vec<TraceEvent> = record(&reference, Rec::REALISTIC)
        .into_iter()
        .filter(|e| matches!(e.event, Event::Sample(_)))
        .collect();
    let d = dir("csvbare");
    let (c, m) = write_csv(&d, &axes_of(&reference), &[], &rec);
    let out = check(&[rel, "--trace", c.to_str().unwrap(), "--map", m.to_str().unwrap()]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(text.contains("aligned on the first motion of the tap axis"), "{text}");
    assert!(text.contains("key points (pecks"), "{text}");
    assert!(text.contains("not comparable: csv carries neither RGSPP nor RGSPM"), "{text}");
    assert!(text.contains("F76.3 edges"), "{text}");
    // The same recording with the tap going 0.3 mm too deep is caught by the envelope.
    let tap = nc_conform::check::reference::Reference::new(&reference).tap.unwrap();
    let bottom = rec
        .iter()
        .filter_map(|e| match &e.event {
            Event::Sample(s) => Some(s.axes[tap.slot] * tap.into_sign),
            _ => None,
        })
        .max()
        .unwrap();
    let deeper: Vec<TraceEvent> = rec
        .iter()
        .map(|e| match &e.event {
            Event::Sample(s) if s.axes[tap.slot] * tap.into_sign > bottom - 100_000 => {
                let mut s = *s;
                s.axes[tap.slot] += 300_000 * tap.into_sign;
                TraceEvent { t_us: e.t_us, event: Event::Sample(s) }
            }
            _ => e.clone(),
        })
        .collect();
    let d = dir("csvbaredeep");
    let (c, m) = write_csv(&d, &axes_of(&reference), &[], &deeper);
    let out = check(&[rel, "--trace", c.to_str().unwrap(), "--map", m.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", stdout(&out));
    assert!(fails(&out).iter().any(|l| l.contains("CHK-ENV-01")), "{:#?}", fails(&out));
}

#[test]
fn defective_csv_recording_fails_with_the_right_rule() {
    let reference = reference(&scenario(CLAMP));
    // A defective PLC: F76.3 never rises or falls.
    let mut t = reference.clone();
    t.events.retain(|e| !matches!(e.event, Event::Signal { signal: Signal::Rtap, .. }));
    let (c, m) = csv_of("csvbad", &reference, &record(&t, Rec::REALISTIC));
    let bad = check(&[CLAMP, "--trace", c.to_str().unwrap(), "--map", m.to_str().unwrap()]);
    assert_eq!(bad.status.code(), Some(1), "{}", stdout(&bad));
    let f = fails(&bad);
    assert!(f.iter().any(|l| l.contains("COM-PLC-02") && l.contains("F76.3 ↑ missing")), "{f:#?}");
    // A wrong peck depth in a peck cycle.
    let rel = "scenarios/gsk/peck/deep_peck_seed_example.yaml";
    let s = scenario(rel);
    let reference = check_util::reference(&s);
    let tap = nc_conform::check::reference::Reference::new(&reference).tap.unwrap();
    let cuts = phase_spans(&reference, nc_engine::trace::Phase::Cutting);
    // The tap stops 0.5 mm (as reported) short of the reference's bottom of cut 2 until its
    // retract comes back above that depth.
    let (a, b) = (cuts[1].0, cuts[2].0);
    let mut t = reference.clone();
    let deepest = |tr: &Trace| {
        tr.samples()
            .filter(|(x, _)| *x >= a && *x <= b)
            .map(|(_, s)| s.axes[tap.slot] * tap.into_sign)
            .max()
            .unwrap()
    };
    let limit = deepest(&reference) - 500_000;
    for e in &mut t.events {
        if let Event::Sample(x) = &mut e.event {
            if e.t_us >= a && e.t_us <= b && x.axes[tap.slot] * tap.into_sign > limit {
                x.axes[tap.slot] = limit * tap.into_sign;
            }
        }
    }
    let (c, m) = csv_of("csvpeck", &reference, &record(&t, Rec::REALISTIC));
    let bad = check(&[rel, "--trace", c.to_str().unwrap(), "--map", m.to_str().unwrap()]);
    assert_eq!(bad.status.code(), Some(1), "{}", stdout(&bad));
    let f = fails(&bad);
    assert!(f.iter().any(|l| l.contains("GSK-RT-09 CHK-KEY-02 peck depth #2")), "{f:#?}");
}

#[test]
fn conformant_shdr_recordings_pass() {
    for rel in [CLAMP, "scenarios/gsk/peck/deep_peck_seed_example.yaml"] {
        let reference = reference(&scenario(rel));
        for (k, rec) in RECORDERS.iter().enumerate() {
            // An adapter publishing the PLC bits as keys: everything but the functions compares.
            let p = shdr_of(&format!("shdrok{k}"), &reference, &record(&reference, *rec), true);
            let out = check(&[rel, "--trace", p.to_str().unwrap()]);
            let text = stdout(&out);
            assert_eq!(out.status.code(), Some(0), "{rel} {rec:?}:\n{text}");
            assert!(text.contains("aligned on the first F76.3 = 1"), "{text}");
            assert!(text.contains("not comparable: shdr carries no M/S/T functions"), "{text}");
            assert!(!text.contains("RGSPP edges"), "{text}");
        }
        // A plain adapter: execution state, positions, spindle. The PLC signals and the key
        // points are not comparable; the anchor is the cycle start (execution ACTIVE).
        let p = shdr_of("shdrplain", &reference, &record(&reference, Rec::REALISTIC), false);
        let out = check(&[rel, "--trace", p.to_str().unwrap()]);
        let text = stdout(&out);
        assert_eq!(out.status.code(), Some(0), "{rel}:\n{text}");
        assert!(text.contains("aligned on the first STL = 1"), "{text}");
        assert!(text.contains("not comparable: shdr carries no RGTAP"), "{text}");
        assert!(text.contains("not comparable: shdr carries neither RGSPP nor RGSPM"), "{text}");
    }
}

#[test]
fn defective_shdr_recordings_fail_with_the_right_rule() {
    let reference = reference(&scenario(CLAMP));
    let mut t = reference.clone();
    t.events.retain(|e| !matches!(e.event, Event::Signal { signal: Signal::Rtap, .. }));
    let p = shdr_of("shdrbad", &reference, &record(&t, Rec::REALISTIC), true);
    let out = check(&[CLAMP, "--trace", p.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", stdout(&out));
    let f = fails(&out);
    assert!(f.iter().any(|l| l.contains("COM-PLC-02") && l.contains("F76.3 ↑ missing")), "{f:#?}");
    // A servo alarm with a vendor code the engine does not know, in the middle of the run:
    // imported (NC-1120) and reported as unexpected, not refused.
    let p = shdr_of("shdralarm", &reference, &record(&reference, Rec::REALISTIC), true);
    let text = std::fs::read_to_string(&p).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    let mid = lines.len() / 2;
    let stamp = lines[mid].split('|').next().unwrap().to_string();
    let alarm = format!("{stamp}|system|FAULT|SV0401|||V READY OFF");
    lines.insert(mid + 1, &alarm);
    std::fs::write(&p, lines.join("\n") + "\n").unwrap();
    let out = check(&[CLAMP, "--trace", p.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", stdout(&out));
    let f = fails(&out);
    assert!(f.iter().any(|l| l.contains("CHK-EVT-03 unexpected alarm SV0401")), "{f:#?}");
    assert_eq!(f.len(), 1, "{f:#?}");
    // Feed hold honoured in the cut: execution FEED_HOLD is an SPL edge the reference has not.
    let s = scenario("scenarios/gsk/dry_run/plain_reference_timing.yaml");
    let reference = check_util::reference(&s);
    let (cut, _) = phase_spans(&reference, nc_engine::trace::Phase::Cutting)[0];
    let t = feed_hold_at(&reference, cut + 100_000, 300_000);
    let p = shdr_of("shdrhold", &reference, &record(&t, Rec::REALISTIC), true);
    let out = check(&["scenarios/gsk/dry_run/plain_reference_timing.yaml", "--trace", p.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", stdout(&out));
    let f = fails(&out);
    assert!(f.iter().any(|l| l.contains("GSK-RT-27") && l.contains("SPL ↑ extra")), "{f:#?}");
}
