//! `nc-conform run SCENARIO.yaml`: verdicts and exit codes (0 all hold, 1 one fails, 2 input
//! error) and the trace formats (`--format jsonl|vcd|timing`).

use std::path::PathBuf;
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_nc-conform");

fn fixture(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("nc-conform-scn-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(format!("{name}.yaml"));
    std::fs::write(&p, text).unwrap();
    p
}

fn run(path: &PathBuf, extra: &[&str]) -> Output {
    Command::new(BIN).arg("run").arg(path).args(extra).env("NO_COLOR", "1").output().unwrap()
}

const PASSING: &str = r#"title: a rigid tap reaches its bottom
rules: [GSK-RT-07]
dialect: gsk-lathe
program: |
  G98;
  G0 X50 Z0;
  M29 S1000;
  G84 Z-5 F1;
  G80;
  M30;
expect:
  alarms: []
  end: {reason: program_end, state: {axes: {Z: 0}}}
  reached:
    - rule: GSK-RT-07
      state: {axes: {Z: -5}}
"#;

#[test]
fn a_passing_scenario_prints_its_verdicts_and_exits_0() {
    let p = fixture("pass", PASSING);
    let o = run(&p, &[]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{out}");
    assert!(out.contains("ok   GSK-RT-07"), "{out}");
    // Three expectations and the physics invariants INV-11..INV-13 that every scenario keeps.
    assert!(out.contains("ok   INV-11 invariant axis_limits"), "{out}");
    assert!(out.contains("6 passed, 0 failed"), "{out}");
}

#[test]
fn a_failing_expectation_exits_1_with_rule_time_expected_and_actual() {
    let p = fixture("fail", &PASSING.replace("state: {axes: {Z: -5}}", "state: {axes: {Z: -6}}"));
    let o = run(&p, &[]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(out.contains("FAIL GSK-RT-07 reached"), "{out}");
    assert!(out.contains("expected") && out.contains("actual"), "{out}");
}

#[test]
fn a_bad_scenario_exits_2_with_file_line_col() {
    let p = fixture("bad", &PASSING.replace("  alarms: []", "  alarms: []\n  colour: red"));
    let o = run(&p, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("bad.yaml:13:"), "{err}");
    assert!(err.contains("colour"), "{err}");
    let p = fixture("badsig", &PASSING.replace("state: {axes: {Z: -5}}", "state: {signals: {RGTAPP: 1}}"));
    let o = run(&p, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("badsig.yaml:16:25") && err.contains("RGTAPP") && err.contains("RGTAP"), "{err}");
}

#[test]
fn a_program_syntax_error_is_located_in_the_yaml_file() {
    let p = fixture("syntax", &PASSING.replace("G84 Z-5 F1;", "G84 Z-5 F1 #3;"));
    let o = run(&p, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("syntax.yaml:8:14:"), "{err}");
}

#[test]
fn formats_write_the_trace_and_keep_the_verdict_exit_code() {
    let p = fixture("formats", PASSING);
    let o = run(&p, &["--format", "jsonl"]);
    assert_eq!(o.status.code(), Some(0));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.lines().next().unwrap().contains("\"kind\":\"meta\""));
    assert!(text.lines().last().unwrap().contains("\"kind\":\"end\""));
    let o = run(&p, &["--format", "vcd"]);
    assert_eq!(o.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&o.stdout).contains("$timescale"));
    let o = run(&p, &["--format", "timing"]);
    assert_eq!(o.status.code(), Some(0));
    let diagram = String::from_utf8_lossy(&o.stdout);
    assert!(diagram.lines().all(|l| l.ends_with('|')), "{diagram}");
    let failing = fixture("formats_fail", &PASSING.replace("{axes: {Z: -5}}", "{axes: {Z: -6}}"));
    let o = run(&failing, &["--format", "timing"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("FAIL GSK-RT-07"));
}

#[test]
fn dialect_flag_is_refused_for_a_scenario() {
    let p = fixture("dialect", PASSING);
    let o = run(&p, &["--dialect", "gsk-lathe"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn campaign_runs_reports_coverage_and_exits_0() {
    // issue 4: `nc-conform campaign` (what scripts/campaign runs) prints the seed, the cases, the
    // alarms hit and the reached situations; a clean engine exits 0.
    let dir = std::env::temp_dir().join(format!("nc-campaign-{}", std::process::id()));
    let out = Command::new(BIN)
        .args([
            "campaign",
            "--cases",
            "4",
            "--seed",
            "5",
            "--quiet",
            "--property",
            "range_edges_alarm_without_motion",
        ])
        .args(["--regressions", &dir.to_string_lossy()])
        .output()
        .expect("run");
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
    for want in ["from seed 5", "4 cases", "alarms hit:", "reached:", "target situations"] {
        assert!(text.contains(want), "`{want}` missing from:\n{text}");
    }
    assert!(!dir.exists(), "no regression written without a failure");
}

#[test]
fn campaign_refuses_zero_cases_with_exit_2() {
    let out = Command::new(BIN).args(["campaign", "--cases", "0"]).output().expect("run");
    assert_eq!(out.status.code(), Some(2));
}
