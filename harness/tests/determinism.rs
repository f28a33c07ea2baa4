//! `nc-conform run --check-determinism` over the whole scenario library and the example programs
//! (issue 4, INV-10): every run writes the same trace twice, so the exit status is never 3.

use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_nc-conform");

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn files(dir: &Path, ext: &[&str], out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    let mut entries: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            files(&p, ext, out);
        } else if p.extension().is_some_and(|e| ext.iter().any(|x| e == *x)) {
            out.push(p);
        }
    }
}

/// Runs the binary with `--check-determinism`; returns the exit code and stderr.
fn check(args: &[&str]) -> (i32, String) {
    let out = Command::new(BIN).args(args).output().expect("run nc-conform");
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn every_scenario_is_deterministic() {
    let mut scenarios = Vec::new();
    files(&root().join("scenarios"), &["yaml", "yml"], &mut scenarios);
    assert!(scenarios.len() > 300, "the scenario library is there ({} files)", scenarios.len());
    let mut bad = Vec::new();
    for s in &scenarios {
        let p = s.to_string_lossy();
        let (code, err) =
            check(&["run", &p, "--check-determinism", "--format", "jsonl", "--out", "/dev/null"]);
        if code != 0 && code != 1 {
            bad.push(format!("{p}: exit {code}: {err}"));
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

#[test]
fn every_example_program_is_deterministic() {
    let mut programs = Vec::new();
    files(&root().join("examples"), &["nc"], &mut programs);
    assert!(!programs.is_empty());
    for p in &programs {
        let p = p.to_string_lossy();
        let name = p.rsplit('/').next().unwrap_or(&p);
        let dialect = if name.starts_with("fanuc") {
            "fanuc-mill"
        } else if name.starts_with("knd") {
            "knd-lathe"
        } else {
            "gsk-lathe"
        };
        let (code, err) =
            check(&["run", &p, "--dialect", dialect, "--check-determinism", "--out", "/dev/null"]);
        assert_eq!(code, 0, "{p}: {err}");
    }
}

#[test]
fn the_flag_keeps_the_usual_exit_status_and_output() {
    let p = root().join("examples/gsk_g88_peck.nc");
    let p = p.to_string_lossy();
    let plain = Command::new(BIN).args(["run", &p, "--dialect", "gsk-lathe"]).output().unwrap();
    let checked = Command::new(BIN)
        .args(["run", &p, "--dialect", "gsk-lathe", "--check-determinism"])
        .output()
        .unwrap();
    assert_eq!(plain.status.code(), checked.status.code());
    assert_eq!(plain.stdout, checked.stdout, "the first run's trace is written as usual");
}

#[test]
fn every_klartext_example_is_deterministic() {
    let mut programs = Vec::new();
    files(&root().join("examples"), &["h"], &mut programs);
    assert!(!programs.is_empty());
    for p in &programs {
        let p = p.to_string_lossy();
        let (code, err) =
            check(&["run", &p, "--dialect", "heidenhain", "--check-determinism", "--out", "/dev/null"]);
        assert_eq!(code, 0, "{p}: {err}");
    }
}
