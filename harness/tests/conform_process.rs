//! `nc-conform conform` against adapter processes: the Python example adapter (examples/), the
//! reference behind `nc-conform serve`, and broken adapters (a crash, a hang, garbage output, a
//! wrong protocol version), each of which must fail its scenario with the controller's stderr
//! while the suite goes on with the next scenario.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_nc-conform")
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn conform(adapter: &str, extra: &[&str]) -> Output {
    Command::new(bin())
        .current_dir(root())
        .args(["conform", "--adapter", adapter])
        .args(extra)
        .output()
        .expect("nc-conform runs")
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// A temporary directory of this test run.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("nc-conform-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A Python adapter that proxies to `nc-conform serve` but misbehaves as `mode` says.
fn broken_adapter(dir: &Path, mode: &str) -> String {
    let script = r#"
import json, subprocess, sys, os, time
mode, marker, nc = sys.argv[1], sys.argv[2], sys.argv[3]
serve = subprocess.Popen([nc, "serve"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
first = not os.path.exists(marker)
loads = 0
for line in sys.stdin:
    req = json.loads(line)
    op = req["op"]
    loads += op == "load"
    if op == "input" and mode == "na" and loads == 1:
        print(json.dumps({"ok": False, "unsupported": "not applicable: no feed hold switch"}), flush=True)
        continue
    if op == "hello" and mode == "old":
        print(json.dumps({"ok": True, "protocol": "nc-conform-adapter/0", "name": "old", "version": "0", "dialects": []}), flush=True)
        continue
    if op == "load" and first:
        open(marker, "w").close()
        if mode == "crash":
            sys.stderr.write("boom: the toy controller lost its axis card\n"); sys.stderr.flush()
            os._exit(3)
    if op == "advance" and first and mode == "hang":
        sys.stderr.write("stuck waiting for the servo\n"); sys.stderr.flush()
        time.sleep(30)
    if op == "read" and first and mode == "garbage":
        sys.stderr.write("debug print went to stdout\n"); sys.stderr.flush()
        print("axis Z at -12.5", flush=True)
        continue
    serve.stdin.write(line); serve.stdin.flush()
    sys.stdout.write(serve.stdout.readline()); sys.stdout.flush()
"#;
    let path = dir.join("adapter.py");
    std::fs::write(&path, script).unwrap();
    format!("python3 {} {mode} {} {}", path.display(), dir.join("marker").display(), bin())
}

const TWO: [&str; 4] = ["--filter", "gsk/feed_hold/during_cutting", "--filter", "gsk/feed_hold/during_dwell"];

#[test]
fn the_python_example_adapter_passes_and_skips_the_dialects_it_does_not_run() {
    let dir = scratch("python");
    let junit = dir.join("junit.xml");
    let report = dir.join("report.json");
    let adapter =
        format!("python3 examples/python-adapter/toy_adapter.py --nc-conform {} --dialects gsk-lathe", bin());
    let o = conform(
        &adapter,
        &[
            "--filter",
            "gsk/feed_hold/",
            "--filter",
            "fanuc/feed_hold/rigid",
            "--junit",
            junit.to_str().unwrap(),
            "--report",
            report.to_str().unwrap(),
        ],
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert!(t.contains("toy-python 0.1"), "{t}");
    assert!(t.contains("ok   scenarios/gsk/feed_hold/during_cutting.yaml"), "{t}");
    assert!(t.contains("skip scenarios/fanuc/feed_hold/"), "{t}");
    assert!(t.contains("GSK-RT-27"), "the summary per rule id: {t}");
    assert!(t.contains("0 failed"), "{t}");
    let xml = std::fs::read_to_string(&junit).unwrap();
    assert!(xml.contains("<skipped message=\"the controller does not run dialect fanuc-mill\"/>"), "{xml}");
    assert!(xml.contains("name=\"scenarios/gsk/feed_hold/during_cutting.yaml\" time=\""), "{xml}");
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(json["failed"], 0);
    assert!(!json["rules"]["GSK-RT-27"]["passed"].as_array().unwrap().is_empty());
}

/// Runs the two scenarios on an adapter that misbehaves on the first: it must fail with every
/// text of `says` (the error and the adapter's stderr), and the second must pass after a restart.
fn first_fails_and_the_suite_goes_on(mode: &str, extra: &[&str], says: &[&str]) {
    let dir = scratch(mode);
    let mut args = TWO.to_vec();
    args.extend(extra);
    let o = conform(&broken_adapter(&dir, mode), &args);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("FAIL scenarios/gsk/feed_hold/during_cutting.yaml"), "{t}");
    for s in says {
        assert!(t.contains(s), "`{s}` missing from: {t}");
    }
    assert!(t.contains("ok   scenarios/gsk/feed_hold/during_dwell.yaml"), "restarted for the next: {t}");
}

/// An input the controller cannot honour (`unsupported` to `input`, docs/adapter-protocol.md):
/// the scenario is not applicable (skipped, never passed nor failed) and the same adapter process
/// goes on with the next scenario (it would refuse that one's inputs too if it were restarted).
#[test]
fn an_input_the_controller_cannot_honour_makes_the_scenario_not_applicable() {
    let dir = scratch("na");
    let junit = dir.join("junit.xml");
    let mut args = TWO.to_vec();
    args.extend(["--junit", junit.to_str().unwrap()]);
    let o = conform(&broken_adapter(&dir, "na"), &args);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert!(t.contains("skip scenarios/gsk/feed_hold/during_cutting.yaml"), "{t}");
    assert!(t.contains("not applicable: no feed hold switch"), "{t}");
    assert!(t.contains("ok   scenarios/gsk/feed_hold/during_dwell.yaml"), "not restarted: {t}");
    assert!(t.contains("1 passed, 0 failed, 1 skipped"), "{t}");
    let xml = std::fs::read_to_string(&junit).unwrap();
    assert!(xml.contains("<skipped message=\"not applicable: no feed hold switch\"/>"), "{xml}");
}

#[test]
fn a_crash_fails_its_scenario_with_the_stderr_and_the_suite_goes_on() {
    first_fails_and_the_suite_goes_on(
        "crash",
        &[],
        &["crash: the adapter exited (exit status: 3)", "boom: the toy controller lost its axis card"],
    );
}

#[test]
fn a_hang_times_out_and_the_suite_goes_on() {
    first_fails_and_the_suite_goes_on(
        "hang",
        &["--timeout-ms", "3000"],
        &["timeout: no answer to `advance` within 3000 ms", "stuck waiting for the servo"],
    );
}

#[test]
fn garbage_output_fails_its_scenario_and_the_suite_goes_on() {
    first_fails_and_the_suite_goes_on(
        "garbage",
        &[],
        &[
            "garbage output: answer to `read` is not a JSON object: axis Z at -12.5",
            "debug print went to stdout",
        ],
    );
}

#[test]
fn a_protocol_version_mismatch_is_a_clear_input_error() {
    let dir = scratch("old");
    let o = conform(&broken_adapter(&dir, "old"), &TWO);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(2), "{t}");
    assert!(
        t.contains("protocol version mismatch: the harness speaks nc-conform-adapter/1, the adapter nc-conform-adapter/0"),
        "{t}"
    );
}

#[test]
fn input_errors_exit_2() {
    let o = conform("", &[]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let o = conform(&format!("{} serve", bin()), &["--scenarios", "no/such/dir"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("not a directory of scenarios"));
    let o = conform(&format!("{} serve", bin()), &["--filter", "no-scenario-has-this"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("no scenario file matches"));
    let o = conform("/no/such/adapter-program", &TWO);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("cannot start `/no/such/adapter-program`"), "{}", text(&o));
}
