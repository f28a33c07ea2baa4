//! `nc-conform check` with a CSV trace (and `--map`) and with an MTConnect SHDR trace: a
//! recording written as CSV is read and compared (a defect exits 1 naming its rule), a malformed
//! row exits 2 and names `file:line:col`.

mod check_util;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use check_util::*;
use nc_engine::trace::{Event, Signal, TraceEvent};

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

/// Writes recorded samples and signal levels as CSV (time in µs) and its column map.
fn write_csv(d: &Path, axes: &[(char, usize)], events: &[TraceEvent]) -> (PathBuf, PathBuf) {
    let sigs: Vec<Signal> = {
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
    };
    let mut map = String::from("time: {column: t, unit: us}\naxes:\n");
    for (l, _) in axes {
        writeln!(map, "  - {{axis: {l}, column: {l}}}").unwrap();
    }
    map.push_str("spindle:\n  rpm: {column: S}\n  angle_deg: {column: A}\nsignals:\n");
    for s in &sigs {
        writeln!(map, "  - {{signal: {}, column: \"{}\"}}", s.name(), s.name()).unwrap();
    }
    let mut csv = String::from("t");
    for (l, _) in axes {
        write!(csv, ",{l}").unwrap();
    }
    csv.push_str(",S,A");
    for s in &sigs {
        write!(csv, ",{}", s.name()).unwrap();
    }
    csv.push('\n');
    let mut level = vec![false; sigs.len()];
    for e in events {
        match &e.event {
            Event::Signal { signal, value } => {
                let i = sigs.iter().position(|s| s == signal).unwrap();
                level[i] = *value;
            }
            Event::Sample(x) => {
                write!(csv, "{}", e.t_us).unwrap();
                for (_, slot) in axes {
                    write!(csv, ",{}", x.axes[*slot] as f64 / 1e6).unwrap();
                }
                write!(csv, ",{},{}", x.spindle_mrpm as f64 / 1e3, x.spindle_mdeg as f64 / 1e3).unwrap();
                for l in &level {
                    write!(csv, ",{}", u8::from(*l)).unwrap();
                }
                csv.push('\n');
            }
            _ => {}
        }
    }
    let (c, m) = (d.join("rec.csv"), d.join("rec.map.yaml"));
    std::fs::write(&c, csv).unwrap();
    std::fs::write(&m, map).unwrap();
    (c, m)
}

/// The lines of the `FAIL` divergences in `check`'s summary.
fn fails(out: &Output) -> Vec<String> {
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| l.trim_start().starts_with("FAIL"))
        .map(String::from)
        .collect()
}

#[test]
fn csv_recording_is_compared_and_a_defect_names_its_rule() {
    let s = scenario(CLAMP);
    let reference = reference(&s);
    let axes: Vec<(char, usize)> = reference.meta.axes.iter().map(|a| (a.letter, a.index)).collect();
    let d = dir("csvok");
    let (c, m) = write_csv(&d, &axes, &record(&reference, Rec::REALISTIC));
    let ok = check(&[CLAMP, "--trace", c.to_str().unwrap(), "--map", m.to_str().unwrap()]);
    // A CSV carries no M functions: today these (and the M29 anchor) are reported missing, so a
    // CSV recording is never conformant (a known gap). Nothing else diverges.
    let base = fails(&ok);
    assert!(
        base.iter().all(|l| l.contains("CHK-ALIGN-01")
            || (l.contains(" M") && l.contains("missing"))
            || l.contains("SPPOSA ↓ missing")),
        "{base:#?}"
    );
    assert!(!base.iter().any(|l| l.contains("F76.3")), "{base:#?}");
    // A defective PLC: F76.3 never rises or falls.
    let mut t = reference.clone();
    t.events.retain(|e| !matches!(e.event, Event::Signal { signal: Signal::Rtap, .. }));
    let d = dir("csvbad");
    let (c, m) = write_csv(&d, &axes, &record(&t, Rec::REALISTIC));
    let bad = check(&[CLAMP, "--trace", c.to_str().unwrap(), "--map", m.to_str().unwrap()]);
    assert_eq!(bad.status.code(), Some(1));
    let f = fails(&bad);
    assert!(f.iter().any(|l| l.contains("COM-PLC-02") && l.contains("F76.3 ↑ missing")), "{f:#?}");
}
