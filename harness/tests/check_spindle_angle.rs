//! `nc-conform check --spindle-angle`: the reference's spindle starts where the recorded one
//! stood (by default the angle of the recording's first sample), so that the waits for the
//! spindle's index agree. A LinuxCNC G33.1 waits for the next index: a spindle that stood at 250°
//! reaches it 110° later, a reference starting at 0° a whole turn later (100 ms at S600).

use std::path::{Path, PathBuf};
use std::process::Command;

use nc_conform::jsonl::JsonlWriter;
use nc_engine::{Machine, RunOptions};

const BIN: &str = env!("CARGO_BIN_EXE_nc-conform");
const PROGRAM: &str = "G21 G90 M3 S600\nG0 X0 Z5\nG33.1 Z-10 K1\nG0 X10\nM2\n";

fn recorded_at(angle: f64) -> (PathBuf, PathBuf) {
    let d = std::env::temp_dir().join(format!("nc-conform-spindle-angle-{}-{angle}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let m = Machine::new("linuxcnc").unwrap();
    let p = m.parse(PROGRAM).unwrap();
    let mut w = JsonlWriter::new(Vec::new());
    m.run(&p, &RunOptions { spindle_angle_deg: angle, ..RunOptions::default() }, &mut w);
    let (prog, trace) = (d.join("tap.ngc"), d.join("rec.jsonl"));
    std::fs::write(&prog, PROGRAM).unwrap();
    std::fs::write(&trace, w.finish().unwrap()).unwrap();
    (prog, trace)
}

fn check(prog: &Path, trace: &Path, extra: &[&str]) -> (i32, String) {
    let out = Command::new(BIN)
        .args(["check", prog.to_str().unwrap(), "--dialect", "linuxcnc", "--trace", trace.to_str().unwrap()])
        .args(extra)
        .output()
        .unwrap();
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    (out.status.code().unwrap_or(-1), text)
}

#[test]
fn the_reference_spindle_starts_at_the_recorded_angle() {
    let (prog, trace) = recorded_at(250.0);
    let (code, text) = check(&prog, &trace, &[]);
    assert_eq!(code, 0, "{text}");
    assert!(text.contains("reference spindle: starts at 250.000° (the recording's first sample)"), "{text}");
    // At the index instead: the tap starts a turn later than the recording's.
    let (code, text) = check(&prog, &trace, &["--spindle-angle", "0"]);
    assert_eq!(code, 1, "{text}");
    assert!(text.contains("starts at 0.000° (--spindle-angle)"), "{text}");
    // The same angle given by hand.
    assert_eq!(check(&prog, &trace, &["--spindle-angle", "250"]).0, 0);
}

#[test]
fn a_spindle_angle_that_is_not_an_angle_is_an_input_error() {
    let (prog, trace) = recorded_at(0.0);
    for bad in ["400", "north", "NaN"] {
        let (code, text) = check(&prog, &trace, &["--spindle-angle", bad]);
        assert_eq!(code, 2, "{bad}: {text}");
        assert!(text.contains("--spindle-angle"), "{bad}: {text}");
    }
}
