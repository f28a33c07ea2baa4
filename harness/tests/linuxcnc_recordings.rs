//! Recordings of LinuxCNC's real motion controller (`testdata/linuxcnc-real/`, issue 13): each is
//! checked with `nc-conform check` against the `linuxcnc` reference with the machine's parameters,
//! the column map and user-level tolerances (0.1 mm, 60 ms), aligned by the checker itself, and
//! must be conformant. A reference that departs from LinuxCNC's motion (G0 per axis instead of one
//! line, G84 feeding out before the spindle is at speed, G99 holes back at the initial level, G33.1
//! stopping at Z) fails here.

use std::path::PathBuf;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_nc-conform");

fn data() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../testdata/linuxcnc-real")
}

fn check(name: &str) -> (i32, String) {
    let d = data();
    let out = Command::new(BIN)
        .current_dir(&d)
        .args(["check", &format!("programs/{name}.ngc"), "--dialect", "linuxcnc"])
        .args(["--params", "linuxcnc-sim.params.yaml", "--map", "linuxcnc-map.yaml"])
        .args(["--trace", &format!("recordings/{name}.csv"), "--tolerances", "user-tolerances.yaml"])
        .output()
        .expect("nc-conform runs");
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    (out.status.code().unwrap_or(-1), text)
}

#[test]
fn every_recording_of_linuxcnc_is_conformant_at_user_tolerances() {
    let mut names: Vec<String> = std::fs::read_dir(data().join("recordings"))
        .unwrap()
        .filter_map(|e| e.ok()?.path().file_stem()?.to_str().map(str::to_string))
        .collect();
    names.sort();
    assert!(names.len() >= 3, "{names:?}");
    let mut bad = Vec::new();
    for n in &names {
        let (code, text) = check(n);
        // Aligned by the checker on the motion itself (the CSV has no M functions or STL).
        assert!(text.contains("aligned on the first spindle start"), "{n}: {text}");
        if code != 0 {
            bad.push(format!("{n}: exit {code}\n{text}"));
        }
    }
    assert!(bad.is_empty(), "{} of {} diverge:\n{}", bad.len(), names.len(), bad.join("\n"));
}

/// The same recordings are not conformant to a reference with LinuxCNC's G0 replaced by per-axis
/// rapids at a third of the rate: the test can fail.
#[test]
fn a_wrong_machine_is_caught() {
    let d = data();
    let params = std::env::temp_dir().join(format!("lcnc-slow-{}.yaml", std::process::id()));
    let base = std::fs::read_to_string(d.join("linuxcnc-sim.params.yaml")).unwrap();
    let slow = base.replace("1828.8", "609.6");
    assert_ne!(base, slow, "the params file names the rapid rate 1828.8");
    std::fs::write(&params, slow).unwrap();
    let out = Command::new(BIN)
        .current_dir(&d)
        .args(["check", "programs/g81.ngc", "--dialect", "linuxcnc", "--map", "linuxcnc-map.yaml"])
        .args(["--params", params.to_str().unwrap(), "--trace", "recordings/g81.csv"])
        .args(["--tolerances", "user-tolerances.yaml"])
        .output()
        .unwrap();
    let _ = std::fs::remove_file(&params);
    assert_eq!(out.status.code(), Some(1), "{}", String::from_utf8_lossy(&out.stdout));
}
