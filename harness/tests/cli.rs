//! End-to-end tests of the `nc-conform` binary: exit codes, diagnostics, and the trace it writes.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::atomic::{AtomicU32, Ordering};

use serde_json::Value;

const BIN: &str = env!("CARGO_BIN_EXE_nc-conform");

/// A program every dialect runs to its end.
const GOOD: &str = "G0 X50 Z0\nM30\n";

/// A fresh directory for one test's fixtures, removed when dropped.
struct Fixture {
    dir: PathBuf,
}

impl Fixture {
    fn new(name: &str) -> Fixture {
        static N: AtomicU32 = AtomicU32::new(0);
        let n = N.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("nc-conform-cli-{}-{n}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create fixture dir");
        Fixture { dir }
    }

    fn file(&self, name: &str, text: &str) -> PathBuf {
        let p = self.dir.join(name);
        std::fs::write(&p, text).expect("write fixture");
        p
    }
}

impl Drop for Fixture {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

fn nc_conform(args: &[&str]) -> Output {
    Command::new(BIN).args(args).env("NO_COLOR", "1").output().expect("run nc-conform")
}

fn run(program: &Path, dialect: &str, extra: &[&str]) -> Output {
    let mut args = vec!["run", program.to_str().unwrap(), "--dialect", dialect];
    args.extend_from_slice(extra);
    nc_conform(&args)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8(o.stdout.clone()).expect("stdout is UTF-8")
}

/// Parses a JSON Lines trace, checking the shape every line must have; returns the objects.
fn parse_trace(text: &str) -> Vec<Value> {
    let lines: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str::<Value>(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect();
    assert!(lines.len() >= 2, "a trace has at least meta and end:\n{text}");
    let mut last_t = 0;
    for v in &lines {
        let t = v["t_us"].as_u64().unwrap_or_else(|| panic!("t_us is not an integer: {v}"));
        assert!(t >= last_t, "time goes back: {v}");
        last_t = t;
        assert!(v["kind"].is_string(), "no kind: {v}");
    }
    assert_eq!(lines[0]["kind"], "meta");
    assert_eq!(lines[0]["format"], "nc-conform-trace/1");
    assert_eq!(lines.last().unwrap()["kind"], "end");
    assert_eq!(lines.iter().filter(|v| v["kind"] == "end").count(), 1);
    lines
}

#[test]
fn version_prints_the_package_version() {
    let o = nc_conform(&["--version"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(stdout(&o).trim(), format!("nc-conform {}", env!("CARGO_PKG_VERSION")));
}

#[test]
fn run_help_documents_every_flag_and_the_dialects() {
    let o = nc_conform(&["run", "--help"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let help = stdout(&o);
    for flag in ["PROGRAM", "--dialect", "--params", "--sample-us", "--out", "--help"] {
        assert!(help.contains(flag), "{flag} missing from:\n{help}");
    }
    for d in ["gsk-lathe", "fanuc-mill"] {
        assert!(help.contains(d), "{d} missing from:\n{help}");
    }
}

#[test]
fn unknown_dialect_exits_2_and_lists_the_dialects() {
    let f = Fixture::new("dialect");
    let p = f.file("prog.nc", GOOD);
    let o = run(&p, "haas-mill", &[]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("haas-mill"), "{err}");
    assert!(err.contains("gsk-lathe") && err.contains("fanuc-mill"), "{err}");
    assert!(o.stdout.is_empty());
}

#[test]
fn unreadable_program_exits_2_naming_the_file() {
    let f = Fixture::new("unreadable");
    let p = f.dir.join("missing.nc");
    let o = run(&p, "gsk-lathe", &[]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("missing.nc"), "{err}");
    assert!(err.contains("cannot read"), "{err}");
    assert!(o.stdout.is_empty());
}

#[test]
fn parse_error_exits_2_with_file_line_col_and_snippet() {
    let f = Fixture::new("parse");
    let p = f.file("prog.nc", "G98\nG0 X50 Z0\n  #1=5\nM30\n");
    let o = run(&p, "gsk-lathe", &[]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("prog.nc:3:3"), "{err}");
    assert!(err.contains('#'), "{err}");
    assert!(err.contains("expected"), "{err}");
    assert!(err.contains("3 |   #1=5"), "source line missing:\n{err}");
    assert!(o.stdout.is_empty());
}

#[test]
fn params_unknown_id_exits_2_with_location() {
    let f = Fixture::new("params-id");
    let p = f.file("prog.nc", GOOD);
    let y = f.file("machine.yaml", "params:\n  170: 68\n  9999: 1\n");
    let o = run(&p, "gsk-lathe", &["--params", y.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("machine.yaml:3:3"), "{err}");
    assert!(err.contains("unknown parameter `9999`"), "{err}");
}

#[test]
fn params_out_of_range_exits_2_with_location() {
    let f = Fixture::new("params-range");
    let p = f.file("prog.nc", GOOD);
    let y = f.file("machine.yaml", "params:\n  271: 301\n");
    let o = run(&p, "gsk-lathe", &["--params", y.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("machine.yaml:2:8"), "{err}");
    assert!(err.contains("out of range") && err.contains("0 to 300 %"), "{err}");
}

#[test]
fn params_yaml_syntax_error_exits_2_with_location() {
    let f = Fixture::new("params-syntax");
    let p = f.file("prog.nc", GOOD);
    let y = f.file("machine.yaml", "params:\n  170: 68\n bad: [\n");
    let o = run(&p, "gsk-lathe", &["--params", y.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("machine.yaml:3:"), "{err}");
}

#[test]
fn unreadable_params_file_exits_2_naming_it() {
    let f = Fixture::new("params-missing");
    let p = f.file("prog.nc", GOOD);
    let y = f.dir.join("nope.yaml");
    let o = run(&p, "gsk-lathe", &["--params", y.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("nope.yaml"), "{}", stderr(&o));
}

#[test]
fn valid_program_exits_0_with_a_json_lines_trace() {
    let f = Fixture::new("valid");
    let p = f.file("prog.nc", GOOD);
    let y = f.file("machine.yaml", "params:\n  170: 68\n  \"186.2\": 1\n  34: {X: 0.01, Z: 0.005}\n");
    let o = run(&p, "gsk-lathe", &["--params", y.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let lines = parse_trace(&stdout(&o));
    assert_eq!(lines[0]["dialect"], "gsk-lathe");
    assert_eq!(lines[0]["axes"], serde_json::json!(["X", "Z", "C"]));
    assert_eq!(lines.last().unwrap()["reason"], "program_end");
}

/// Every dialect writes a well-formed trace; how the run ends is the engine's business (exit 0
/// or 1, never 2).
#[test]
fn every_dialect_writes_a_trace() {
    let f = Fixture::new("dialects");
    let p = f.file("prog.nc", "G0 X10\nM30\n");
    for d in ["gsk-lathe", "fanuc-mill"] {
        let o = run(&p, d, &["--sample-us", "0"]);
        assert!(matches!(o.status.code(), Some(0 | 1)), "{d}: {}", stderr(&o));
        let lines = parse_trace(&stdout(&o));
        assert_eq!(lines[0]["dialect"], d);
        assert_eq!(lines[0]["sample_us"], 0);
        assert!(lines.iter().all(|v| v["kind"] != "sample"), "{d}: samples with --sample-us 0");
    }
}

#[test]
fn out_writes_the_trace_to_a_file() {
    let f = Fixture::new("out");
    let p = f.file("prog.nc", GOOD);
    let out = f.dir.join("trace.jsonl");
    let o = run(&p, "gsk-lathe", &["--out", out.to_str().unwrap(), "--sample-us", "2000"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(o.stdout.is_empty());
    let text = std::fs::read_to_string(&out).unwrap();
    let lines = parse_trace(&text);
    assert_eq!(lines[0]["sample_us"], 2000);
    for v in lines.iter().filter(|v| v["kind"] == "sample") {
        assert_eq!(v["t_us"].as_u64().unwrap() % 2000, 0, "{v}");
    }
}

#[test]
fn unwritable_out_exits_2() {
    let f = Fixture::new("out-bad");
    let p = f.file("prog.nc", GOOD);
    let out = f.dir.join("no-such-dir").join("trace.jsonl");
    let o = run(&p, "gsk-lathe", &["--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("trace.jsonl"), "{}", stderr(&o));
}

#[test]
fn the_same_run_gives_the_same_bytes() {
    let f = Fixture::new("determinism");
    let p = f.file("prog.nc", GOOD);
    let a = run(&p, "gsk-lathe", &[]);
    let b = run(&p, "gsk-lathe", &[]);
    assert_eq!(a.status.code(), Some(0), "{}", stderr(&a));
    assert_eq!(a.stdout, b.stdout);
}

#[test]
fn a_program_that_alarms_exits_1() {
    let f = Fixture::new("alarm");
    // An M code must be a whole number.
    let p = f.file("prog.nc", "G0 X10\nM1.5\nM30\n");
    let o = run(&p, "gsk-lathe", &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let lines = parse_trace(&stdout(&o));
    let alarm = lines.iter().find(|v| v["kind"] == "alarm").expect("an alarm line");
    assert_eq!(alarm["code"], "NC-1001", "{alarm}");
    assert!(alarm["message"].as_str().unwrap().starts_with("WORD OUT OF RANGE"), "{alarm}");
    assert_eq!(alarm["line"], 2, "{alarm}");
    assert_eq!(alarm["col"], 1, "{alarm}");
    assert_eq!(lines.last().unwrap()["reason"], "alarm");
}

#[test]
fn the_examples_parse() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join("examples");
    for (file, dialect) in [
        ("gsk_g88_peck.nc", "gsk-lathe"),
        ("gsk_g88_standard.nc", "gsk-lathe"),
        ("gsk_g88_deep_peck.nc", "gsk-lathe"),
        ("fanuc_g84_seed.nc", "fanuc-mill"),
    ] {
        let o = run(&root.join(file), dialect, &["--sample-us", "0"]);
        assert_ne!(o.status.code(), Some(2), "{file}: {}", stderr(&o));
        parse_trace(&stdout(&o));
    }
}
