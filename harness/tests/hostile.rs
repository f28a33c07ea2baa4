//! Hostile inputs (issue 15): each ends with exit 1 or 2 and a clear first line on stderr, in
//! under 512 MiB of address space and 60 s, never with a panic, an abort or a hang.
//!
//! Every run goes through `sh -c 'ulimit -v …'`, so an unbounded read or allocation fails the
//! test instead of exhausting the machine, and is killed after 60 s.
#![cfg(unix)]

use std::io::Read as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_nc-conform");

/// The address-space limit of every run, KiB (512 MiB).
const MEMORY_KIB: u64 = 512 * 1024;
/// The time limit of every run.
const TIME_LIMIT: Duration = Duration::from_secs(60);

/// A fresh directory for one test's files, removed when dropped.
struct Dir(PathBuf);

impl Dir {
    fn new(name: &str) -> Dir {
        static N: AtomicU32 = AtomicU32::new(0);
        let n = N.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("nc-conform-hostile-{}-{n}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create test dir");
        Dir(dir)
    }

    fn file(&self, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
        let p = self.0.join(name);
        std::fs::write(&p, text).expect("write test file");
        p
    }
}

impl Drop for Dir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// How a hostile run ended.
struct Ended {
    code: i32,
    stdout: Vec<u8>,
    stderr: String,
}

impl Ended {
    /// The first line on stderr.
    fn first(&self) -> &str {
        self.stderr.lines().next().unwrap_or("")
    }
}

/// Runs the binary bounded in memory and time, with `env` set, in `dir`.
fn run_in(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Ended {
    let mut cmd = Command::new("sh");
    cmd.arg("-c").arg(format!("ulimit -v {MEMORY_KIB}; exec \"$0\" \"$@\"")).arg(BIN).args(args);
    cmd.env_remove("NC_CONFORM_MAX_PROGRAM_MIB").env_remove("NC_CONFORM_MAX_PROGRAM_LINES");
    for (k, v) in env {
        cmd.env(k, v);
    }
    let mut child = cmd
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start nc-conform");
    let mut out = child.stdout.take().expect("stdout");
    let mut err = child.stderr.take().expect("stderr");
    let reader = std::thread::spawn(move || {
        let mut v = Vec::new();
        let _ = out.read_to_end(&mut v);
        v
    });
    let err_reader = std::thread::spawn(move || {
        let mut v = Vec::new();
        let _ = err.read_to_end(&mut v);
        v
    });
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break s;
        }
        if start.elapsed() > TIME_LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            panic!("nc-conform {args:?} ran longer than {TIME_LIMIT:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let stdout = reader.join().expect("stdout reader");
    let stderr = String::from_utf8_lossy(&err_reader.join().expect("stderr reader")).into_owned();
    let code = status.code().unwrap_or_else(|| panic!("nc-conform {args:?} killed by a signal: {stderr}"));
    Ended { code, stdout, stderr }
}

/// Runs a hostile command: it must end with `code` and a first stderr line holding `says`.
fn hostile(dir: &Path, args: &[&str], code: i32, says: &str) -> Ended {
    let e = run_in(dir, args, &[]);
    assert!(!e.stderr.contains("panicked") && !e.stderr.contains("overflow"), "{args:?}: {}", e.stderr);
    assert_eq!(e.code, code, "{args:?}: exit {} with stderr:\n{}", e.code, e.stderr);
    assert!(e.first().contains(says), "{args:?}: first stderr line {:?} lacks {says:?}", e.first());
    e
}

// ---- 1. Aborts: no recursion whose depth follows the input ---------------------------------

#[test]
fn deeply_nested_linuxcnc_expressions_are_refused_as_linuxcnc_does() {
    let d = Dir::new("nesting");
    // The issue's sizes, through the engine's API on a test thread (2 MiB of stack): refused by
    // the line length, never followed by recursion.
    let machine = nc_engine::Machine::new("linuxcnc").expect("linuxcnc");
    let issue = [
        format!("G0 X{}1{}\nM2\n", "[".repeat(12_000), "]".repeat(12_000)),
        format!("G0 X[{}]\nM2\n", vec!["1"; 100_000].join("+")),
        format!("G0 X{}1{}\nM2\n", "sin[".repeat(20_000), "]".repeat(20_000)),
        format!("G0 X{}1\nM2\n", "-".repeat(100_000)),
        format!("G0 X[{}]\nM2\n", vec!["1"; 50_000].join("**")),
    ];
    for text in &issue {
        let e = machine.parse(text).expect_err("refused");
        assert_eq!((e.line, e.col, e.message.as_str()), (1, 253, "Command too long"));
    }
    // Through the command line, under the 64 KiB line cap of program files.
    let cases = [
        ("nest.ngc", format!("G0 X{}1{}\nM2\n", "[".repeat(12_000), "]".repeat(12_000))),
        ("sum.ngc", format!("G0 X[{}]\nM2\n", vec!["1"; 30_000].join("+"))),
        ("sin.ngc", format!("G0 X{}1{}\nM2\n", "sin[".repeat(12_000), "]".repeat(12_000))),
        ("neg.ngc", format!("G0 X{}1\nM2\n", "-".repeat(60_000))),
        ("pow.ngc", format!("G0 X[{}]\nM2\n", vec!["1"; 20_000].join("**"))),
    ];
    for (name, text) in cases {
        d.file(name, text);
        hostile(&d.0, &["run", name, "--dialect", "linuxcnc"], 2, &format!("{name}:1:253: Command too long"));
    }
    // Past the cap: refused by the reader, before the parser.
    d.file("sum100k.ngc", format!("G0 X[{}]\nM2\n", vec!["1"; 100_000].join("+")));
    hostile(
        &d.0,
        &["run", "sum100k.ngc", "--dialect", "linuxcnc"],
        2,
        "sum100k.ngc: line 1 is 200005 bytes long",
    );
}

#[test]
fn a_vcd_of_deeply_nested_scopes_is_refused() {
    let d = Dir::new("vcd");
    d.file("p.nc", "G0 X50 Z0\nM30\n");
    let vcd = format!(
        "$timescale 1us $end\n{}{}$enddefinitions $end\n",
        "$scope module a $end\n".repeat(50_000),
        "$upscope $end\n".repeat(50_000)
    );
    d.file("deep.vcd", vcd);
    hostile(
        &d.0,
        &["check", "p.nc", "--dialect", "gsk-lathe", "--trace", "deep.vcd"],
        2,
        "more than 256 nested $scope commands",
    );
}

// ---- 1. Unbounded reads: every file has a size cap -----------------------------------------

#[test]
fn dev_zero_anywhere_a_file_is_read_is_refused_by_its_cap() {
    let d = Dir::new("zero");
    d.file("p.nc", "G0 X50 Z0\nM30\n");
    d.file("z.yaml", "title: z\nrules: [GSK-RT-01]\ndialect: gsk-lathe\nprogram_file: /dev/zero\n");
    let program_cap = "/dev/zero: larger than the 64 MiB limit for a program; set NC_CONFORM_MAX_PROGRAM_MIB";
    hostile(&d.0, &["run", "/dev/zero", "--dialect", "gsk-lathe"], 2, program_cap);
    hostile(&d.0, &["check", "/dev/zero", "--dialect", "gsk-lathe", "--trace", "p.nc"], 2, program_cap);
    hostile(
        &d.0,
        &["run", "z.yaml"],
        2,
        "program file /dev/zero: larger than the 64 MiB limit for a program",
    );
    let yaml_cap = "/dev/zero: larger than the 4 MiB limit for a YAML file";
    hostile(&d.0, &["run", "p.nc", "--dialect", "gsk-lathe", "--params", "/dev/zero"], 2, yaml_cap);
    hostile(&d.0, &["run", "/dev/zero"], 2, "--dialect");
    let check = ["check", "p.nc", "--dialect", "gsk-lathe", "--trace", "p.nc"];
    hostile(&d.0, &[&check[..], &["--map", "/dev/zero"]].concat(), 2, yaml_cap);
    hostile(&d.0, &[&check[..], &["--tolerances", "/dev/zero"]].concat(), 2, yaml_cap);
    for format in ["jsonl", "shdr", "csv", "vcd"] {
        let e = run_in(
            &d.0,
            &[
                "check",
                "p.nc",
                "--dialect",
                "gsk-lathe",
                "--trace",
                "/dev/zero",
                "--format",
                format,
                "--lenient",
            ],
            &[],
        );
        assert_eq!(e.code, 2, "--format {format}: {}", e.stderr);
        assert!(e.first().starts_with("error: /dev/zero"), "--format {format}: {}", e.stderr);
    }
    hostile(&d.0, &["run", ".", "--dialect", "gsk-lathe"], 2, "it is a directory");
}

#[test]
fn the_program_cap_is_checked_before_reading_and_can_be_raised() {
    let d = Dir::new("cap");
    // A sparse 65 MiB file: refused by its size, without reading it.
    let big = d.0.join("big.nc");
    let f = std::fs::File::create(&big).expect("create");
    f.set_len(65 << 20).expect("size");
    hostile(&d.0, &["run", "big.nc", "--dialect", "gsk-lathe"], 2, "big.nc: larger than the 64 MiB limit");
    // Raised to 1 GiB: read (and refused for what it holds, NUL bytes, not for its size).
    let e =
        run_in(&d.0, &["run", "big.nc", "--dialect", "gsk-lathe"], &[("NC_CONFORM_MAX_PROGRAM_MIB", "1024")]);
    assert!(!e.first().contains("limit"), "{}", e.stderr);
    assert!(matches!(e.code, 1 | 2), "{}", e.stderr);
}

#[test]
fn a_program_of_too_many_lines_is_refused_and_the_cap_can_be_raised() {
    let d = Dir::new("lines");
    d.file("long.nc", "X1\n".repeat(1_000_001));
    hostile(
        &d.0,
        &["run", "long.nc", "--dialect", "gsk-lathe", "--sample-us", "0"],
        2,
        "long.nc: 1000001 lines, more than the 1000000 lines allowed for a program; set NC_CONFORM_MAX_PROGRAM_LINES",
    );
    let e = run_in(
        &d.0,
        &["run", "long.nc", "--dialect", "gsk-lathe", "--sample-us", "0", "--out", "t.jsonl"],
        &[("NC_CONFORM_MAX_PROGRAM_LINES", "1000001")],
    );
    // Read and run (it has no M30: the run ends another way than at the program end).
    assert!(!e.stderr.contains("lines allowed"), "{}", e.stderr);
}

// ---- 1. Runaway runs, and exit 1 says why ---------------------------------------------------

#[test]
fn words_finer_than_the_least_increment_are_range_alarms() {
    let d = Dir::new("tiny");
    let cases = [
        ("gsk-lathe", "M29 S500\nG88 X-50 F0.000001\nM30\n", "g.nc:2: alarm NC-1001"),
        ("gsk-lathe", "G98 G01 Z-10 F0.000001\nM30\n", "g.nc:1: alarm NC-1001"),
        ("knd-lathe", "G98 G01 Z-10 F0.000001\nM30\n", "g.nc:1: alarm NC-1001"),
        ("knd-lathe", "S500 M03\nG32 Z-10 F0.00001\nM30\n", "g.nc:2: alarm NC-1001"),
        ("fanuc-mill", "G94 G01 Z-10 F0.000001\nM30\n", "g.nc:1: alarm NC-1001"),
        ("heidenhain", "BEGIN PGM T MM\nL Z-10 F0.0000001\nEND PGM T MM\n", "g.nc:2: alarm NC-1001"),
    ];
    for (dialect, program, says) in cases {
        d.file("g.nc", program);
        let e = hostile(&d.0, &["run", "g.nc", "--dialect", dialect, "--out", "t.jsonl"], 1, says);
        assert_eq!(e.stderr.lines().count(), 1, "{dialect}: {}", e.stderr);
    }
}

#[test]
fn a_run_ending_on_an_alarm_says_which_and_where() {
    let d = Dir::new("alarm");
    d.file("a.nc", "G98\nG1 Z-1 F60\nG1 Z-2 F0\nM30\n");
    let e = hostile(&d.0, &["run", "a.nc", "--dialect", "gsk-lathe", "--out", "t.jsonl"], 1, "");
    assert_eq!(
        e.stderr, "a.nc:3: alarm NC-1001: WORD OUT OF RANGE: F0: feed must be > 0 in `G1 Z-2 F0`\n",
        "one line: the alarm code, its message and the program line"
    );
}

#[test]
fn time_limit_and_output_budget_stop_runaway_runs() {
    let d = Dir::new("runaway");
    // A legal but endless feed: 10 mm at 0.001 mm/min takes about 7 days.
    d.file("slow.nc", "G98 G01 Z-10 F0.001\nM30\n");
    let e = hostile(
        &d.0,
        &["run", "slow.nc", "--dialect", "gsk-lathe", "--time-limit", "2", "--out", "t.jsonl"],
        1,
        "slow.nc: the run reached its time limit of 2 s of machine time",
    );
    assert_eq!(e.stderr.lines().count(), 1);
    let trace = std::fs::read_to_string(d.0.join("t.jsonl")).expect("trace");
    assert!(trace
        .lines()
        .last()
        .is_some_and(|l| l.contains("\"t_us\":2000000,\"kind\":\"end\",\"reason\":\"time_limit\"")));

    let e = hostile(
        &d.0,
        &["run", "slow.nc", "--dialect", "gsk-lathe", "--max-output-mib", "1", "--out", "t.jsonl"],
        1,
        "slow.nc: the run was stopped when its trace reached 1 MiB (--max-output-mib)",
    );
    assert_eq!(e.stderr.lines().count(), 1);
    let len = std::fs::metadata(d.0.join("t.jsonl")).expect("trace").len();
    assert!((1 << 20..(1 << 20) + (128 << 10)).contains(&len), "{len} bytes");
    let trace = std::fs::read_to_string(d.0.join("t.jsonl")).expect("trace");
    assert!(trace.lines().last().is_some_and(|l| l.contains("\"kind\":\"end\",\"reason\":\"output_limit\"")));

    // A dwell of 27 hours at 1 ms samples runs into the default budget (1 GiB) on stdout:
    // stopped, not written to the end. Standard output is a pipe read to its end here.
    d.file("dwell.nc", "G04 P99999999\nM30\n");
    let e = hostile(
        &d.0,
        &["run", "dwell.nc", "--dialect", "gsk-lathe", "--max-output-mib", "8"],
        1,
        "dwell.nc: the run was stopped when its trace reached 8 MiB",
    );
    assert!(e.stdout.len() < 9 << 20);
}

// ---- 2. The adapter runner: misbehaving adapters fail one scenario, the run goes on ----------

/// The repository root (where `scenarios/` is).
fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// A Python adapter proxying to `nc-conform serve` that misbehaves as `mode` says during the
/// first scenario, and notes every `hello` in `hellos`.
fn misbehaving_adapter(dir: &Path, mode: &str) -> String {
    let script = r#"
import json, subprocess, sys, os, time
mode, marker, nc, hellos = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]
serve = subprocess.Popen([nc, "serve"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
first = not os.path.exists(marker)
def say(obj):
    sys.stdout.write(json.dumps(obj) + "\n"); sys.stdout.flush()
for line in sys.stdin:
    req = json.loads(line)
    op = req["op"]
    if op == "hello":
        open(hellos, "a").write("hello\n")
    if op == "load" and first:
        open(marker, "w").close()
    if first and os.path.exists(marker) and op == "advance":
        if mode == "close_stdout":
            sys.stderr.write("closing stdout\n"); sys.stderr.flush()
            os.close(1); time.sleep(120)
        if mode == "close_stdin":
            os.close(0)
            serve.stdin.write(line); serve.stdin.flush()
            sys.stdout.write(serve.stdout.readline()); sys.stdout.flush()
            time.sleep(120)
        if mode == "long_line":
            sys.stdout.write("x" * (20 << 20)); sys.stdout.flush(); time.sleep(120)
        if mode == "no_newline":
            sys.stdout.write('{"ok": true'); sys.stdout.flush(); time.sleep(120)
        if mode == "idle":
            say({"ok": True, "now_us": 0, "ended": False, "stopped_on": None}); continue
        if mode == "slow":
            time.sleep(0.4)
            say({"ok": True, "now_us": 1, "ended": False, "stopped_on": None}); continue
        if mode == "ok_false":
            sys.stderr.write("servo \x1b[31mred\x1b[0m alarm\n"); sys.stderr.flush()
            say({"ok": False, "error": "servo fault \x1b]0;pwned\x07 on Z"}); continue
    if first and os.path.exists(marker) and op == "read" and mode in ("idle", "slow"):
        say({"ok": True, "events": []}); continue
    serve.stdin.write(line); serve.stdin.flush()
    sys.stdout.write(serve.stdout.readline()); sys.stdout.flush()
"#;
    let path = dir.join("adapter.py");
    std::fs::write(&path, script).expect("write adapter");
    format!(
        "python3 {} {mode} {} {BIN} {}",
        path.display(),
        dir.join("marker").display(),
        dir.join("hellos").display()
    )
}

/// Runs two scenarios on an adapter misbehaving on the first: the first fails saying `says`,
/// the second passes on a restarted adapter (two `hello`s), within the memory and time limits.
fn adapter_fails_one_scenario(mode: &str, extra: &[&str], says: &str) -> Ended {
    let d = Dir::new(mode);
    let adapter = misbehaving_adapter(&d.0, mode);
    let mut args = vec![
        "conform",
        "--adapter",
        &adapter,
        "--filter",
        "gsk/feed_hold/during_cutting",
        "--filter",
        "gsk/feed_hold/during_dwell",
    ];
    args.extend(extra);
    let e = run_in(&root(), &args, &[]);
    let out = String::from_utf8_lossy(&e.stdout).into_owned();
    assert_eq!(e.code, 1, "{mode}: {out}{}", e.stderr);
    assert!(out.contains("FAIL scenarios/gsk/feed_hold/during_cutting.yaml"), "{mode}: {out}");
    assert!(out.contains(says), "{mode}: `{says}` missing from {out}");
    assert!(out.contains("ok   scenarios/gsk/feed_hold/during_dwell.yaml"), "{mode}: the run goes on: {out}");
    assert!(!out.contains('\u{1b}') && !out.contains('\u{7}'), "{mode}: raw control bytes in {out:?}");
    let hellos = std::fs::read_to_string(d.0.join("hellos")).unwrap_or_default();
    assert_eq!(hellos.lines().count(), 2, "{mode}: the adapter is restarted after the failure");
    e
}

#[test]
fn an_adapter_closing_its_stdout_and_staying_alive_is_killed() {
    adapter_fails_one_scenario("close_stdout", &[], "the adapter closed its pipe but kept running (killed)");
}

#[test]
fn an_adapter_closing_its_stdin_and_staying_alive_is_killed() {
    adapter_fails_one_scenario("close_stdin", &[], "the adapter closed its pipe but kept running (killed)");
}

#[test]
fn an_endless_answer_line_is_cut_at_its_cap() {
    adapter_fails_one_scenario("long_line", &[], "an answer line longer than 16777216 bytes");
}

#[test]
fn an_answer_without_its_line_end_times_out() {
    adapter_fails_one_scenario(
        "no_newline",
        &["--timeout-ms", "1500"],
        "no answer to `advance` within 1500 ms",
    );
}

#[test]
fn advances_without_progress_fail_the_scenario() {
    adapter_fails_one_scenario("idle", &[], "1000 `advance` answers in a row without progress");
}

#[test]
fn a_scenario_has_a_time_limit() {
    adapter_fails_one_scenario(
        "slow",
        &["--scenario-timeout-ms", "1500"],
        "the scenario took longer than 1500 ms (--scenario-timeout-ms)",
    );
}

#[test]
fn ok_false_restarts_the_adapter_and_control_bytes_are_escaped() {
    let e = adapter_fails_one_scenario("ok_false", &[], "servo fault \\u{1b}]0;pwned\\u{7} on Z");
    let out = String::from_utf8_lossy(&e.stdout);
    assert!(out.contains("servo \\u{1b}[31mred\\u{1b}[0m alarm"), "the stderr tail, escaped: {out}");
}

// ---- 3. Lesser findings ----------------------------------------------------------------------

#[test]
fn a_period_outside_the_four_is_refused() {
    let d = Dir::new("period");
    d.file("p.nc", "G0 X50 Z0\nM30\n");
    d.file("p.yaml", "params:\n  nc.period_us: 1500\n");
    hostile(
        &d.0,
        &["run", "p.nc", "--dialect", "gsk-lathe", "--params", "p.yaml"],
        2,
        "p.yaml:2:17: parameter nc.period_us (interpolation period) = 1500 is not one of the four periods; expected 1000, 2000, 4000 or 8000 us",
    );
}

#[test]
fn check_says_when_the_trace_is_of_another_dialect() {
    let d = Dir::new("dialect");
    d.file("p.nc", "S500 M03\nG0 X50 Z0\nM30\n");
    let e = run_in(&d.0, &["run", "p.nc", "--dialect", "gsk-lathe", "--out", "gsk.jsonl"], &[]);
    assert_eq!(e.code, 0, "{}", e.stderr);
    hostile(
        &d.0,
        &["check", "p.nc", "--dialect", "fanuc-mill", "--trace", "gsk.jsonl"],
        2,
        "gsk.jsonl: the trace was recorded with dialect gsk-lathe (its meta line), the reference runs fanuc-mill",
    );
}

#[test]
fn empty_traces_and_old_timestamps_are_named_for_what_they_are() {
    let d = Dir::new("empty");
    d.file("p.nc", "S500 M03\nG0 X50 Z0\nM30\n");
    d.file("empty.jsonl", "");
    d.file("blank.csv", "\n \n");
    let check = |trace: &str, extra: &[&str], says: &str| {
        let args = [&["check", "p.nc", "--dialect", "gsk-lathe", "--trace", trace][..], extra].concat();
        hostile(&d.0, &args, 2, says);
    };
    check("empty.jsonl", &[], "empty.jsonl: the file is empty");
    for f in ["jsonl", "csv", "vcd", "shdr"] {
        check("empty.jsonl", &["--format", f], "empty.jsonl: the file is empty");
    }
    check("blank.csv", &[], "blank.csv: the file holds only blank space");
    d.file("old.shdr", "1900-01-01T00:00:00.000Z|execution|ACTIVE\n");
    check("old.shdr", &[], "old.shdr:1:1: bad timestamp `1900-01-01T00:00:00.000Z`; expected YYYY-MM-DDTHH:MM:SS[.ffffff]Z, from 1970 on");
}

#[test]
fn yaml_errors_are_said_in_the_projects_words() {
    let d = Dir::new("yaml");
    d.file("p.nc", "G0 X50 Z0\nM30\n");
    let scenario = "title: t\nrules: [GSK-RT-01]\ndialect: gsk-lathe\nprogram: \"M30\"\n";
    d.file("u64.yaml", format!("{scenario}options:\n  sample_us: -5\n"));
    d.file("dup.yaml", format!("title: u\n{scenario}"));
    let many: String = (0..300_000).map(|i| format!("  x{i}: 1\n")).collect();
    d.file("many.yaml", format!("params:\n{many}"));
    d.file("tol.yaml", "sync_mm: abc\n");
    d.file("trace.jsonl", "{}\n");
    let library = ["invalid u64", "DuplicateKeyPolicy", "budget breached", "invalid floating", "<input>"];
    for (args, says) in [
        (&["run", "u64.yaml"][..], "u64.yaml:6:14: invalid scenario: expected a whole number of 0 or more"),
        (&["run", "dup.yaml"][..], "dup.yaml:2:1: invalid scenario: key `title` given twice"),
        (
            &["run", "p.nc", "--dialect", "gsk-lathe", "--params", "many.yaml"][..],
            "invalid parameter file: the YAML is beyond what the tool reads: too many values",
        ),
        (
            &[
                "check",
                "p.nc",
                "--dialect",
                "gsk-lathe",
                "--trace",
                "trace.jsonl",
                "--tolerances",
                "tol.yaml",
            ][..],
            "tol.yaml:1:10: bad tolerance file: expected a number",
        ),
    ] {
        let e = hostile(&d.0, args, 2, says);
        for l in library {
            assert!(!e.stderr.contains(l), "{args:?}: `{l}` in {}", e.stderr);
        }
    }
}

#[test]
fn echoed_text_is_made_printable_and_short() {
    let d = Dir::new("echo");
    d.file("esc.nc", "G0 X1\n\u{1b}[31mG0\u{1b}]0;pwned\u{7} X1\nM30\n");
    let e = hostile(
        &d.0,
        &["run", "esc.nc", "--dialect", "gsk-lathe"],
        2,
        "esc.nc:2:1: unexpected character `\\u{1b}`",
    );
    assert!(!e.stderr.contains('\u{1b}') && !e.stderr.contains('\u{7}'), "{:?}", e.stderr);
    assert!(e.stderr.contains("2 | ␛[31mG0␛]0;pwned␇ X1"), "{}", e.stderr);
    // A line of 60 006 bytes: the snippet shows a window of it, not the whole line.
    d.file("wide.nc", format!("G0 X1 {}$\n", "Z1 ".repeat(20_000)));
    let e = hostile(&d.0, &["run", "wide.nc", "--dialect", "gsk-lathe"], 2, "wide.nc:1:60007:");
    assert!(e.stderr.len() < 2000, "{} bytes on stderr", e.stderr.len());
    // A line of 2 MB is refused before parsing (a 60 MB one took more than 512 MiB to parse).
    d.file("wider.nc", format!("G0 X1 {}\n", "Z1 ".repeat(700_000)));
    hostile(
        &d.0,
        &["run", "wider.nc", "--dialect", "gsk-lathe"],
        2,
        "wider.nc: line 1 is 2100006 bytes long, more than the 65536 bytes allowed for a line of a program",
    );
    // A scenario naming /etc/passwd as its program: what is echoed of it is one short line.
    if Path::new("/etc/passwd").is_file() {
        d.file("pw.yaml", "title: t\nrules: [GSK-RT-01]\ndialect: gsk-lathe\nprogram_file: /etc/passwd\n");
        let e = run_in(&d.0, &["run", "pw.yaml"], &[]);
        assert_eq!(e.code, 2, "{}", e.stderr);
        assert!(e.stderr.lines().count() <= 4 && e.stderr.len() < 1000, "{}", e.stderr);
    }
}

#[test]
fn json_lines_with_a_key_given_twice_are_refused() {
    let d = Dir::new("dupkey");
    d.file("p.nc", "S500 M03\nG0 X50 Z0\nM30\n");
    let e = run_in(&d.0, &["run", "p.nc", "--dialect", "gsk-lathe", "--out", "t.jsonl"], &[]);
    assert_eq!(e.code, 0, "{}", e.stderr);
    let trace = std::fs::read_to_string(d.0.join("t.jsonl")).expect("trace");
    let mut lines: Vec<String> = trace.lines().map(str::to_string).collect();
    lines[1] = lines[1].replacen("\"kind\":", "\"t_us\":5,\"kind\":", 1);
    d.file("dup.jsonl", lines.join("\n") + "\n");
    hostile(
        &d.0,
        &["check", "p.nc", "--dialect", "gsk-lathe", "--trace", "dup.jsonl"],
        2,
        "dup.jsonl:2:16: a key given twice: duplicate key `t_us`",
    );
}

#[test]
fn runs_held_in_memory_are_bounded() {
    let d = Dir::new("memory");
    d.file("slow.nc", "G98 G01 Z-10 F0.001\nM30\n");
    d.file("t.jsonl", "{}\n");
    hostile(
        &d.0,
        &["check", "slow.nc", "--dialect", "gsk-lathe", "--trace", "t.jsonl"],
        2,
        "slow.nc: the reference run of the program did not end within 1000000 trace events",
    );
    d.file(
        "slow.yaml",
        "title: t\nrules: [GSK-RT-01]\ndialect: gsk-lathe\nprogram: \"M30\"\noptions:\n  time_limit_ms: 604800000\n  sample_us: 1\n",
    );
    hostile(
        &d.0,
        &["run", "slow.yaml"],
        2,
        "slow.yaml: options: time_limit_ms 604800000 at sample_us 1 would hold",
    );
}

// ---- Beyond the list -------------------------------------------------------------------------

#[test]
fn an_alignment_offset_that_would_overflow_is_refused() {
    let d = Dir::new("offset");
    d.file("p.nc", "S500 M03\nG0 X50 Z0\nM30\n");
    let e = run_in(&d.0, &["run", "p.nc", "--dialect", "gsk-lathe", "--out", "t.jsonl"], &[]);
    assert_eq!(e.code, 0, "{}", e.stderr);
    let check = ["check", "p.nc", "--dialect", "gsk-lathe", "--trace", "t.jsonl"];
    hostile(&d.0, &[&check[..], &["--offset-us", "9223372036854775807"]].concat(), 2, "is not in");
    hostile(
        &d.0,
        &[&check[..], &["--anchor", "offset:-9223372036854775808"]].concat(),
        2,
        "--anchor: offset -9223372036854775808 µs is out of range",
    );
}

#[test]
fn serve_reads_its_requests_bounded() {
    let d = Dir::new("serve");
    let mut cmd = Command::new("sh");
    cmd.arg("-c").arg(format!("ulimit -v {MEMORY_KIB}; exec \"$0\" serve < /dev/zero")).arg(BIN);
    let out = cmd.current_dir(&d.0).output().expect("serve");
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stdout).contains("a request line longer than 16777216 bytes"));
}

#[test]
fn a_scenario_directory_with_symbolic_link_loops_is_walked_once() {
    let d = Dir::new("links");
    let dir = d.0.join("s");
    std::fs::create_dir_all(&dir).expect("dir");
    std::os::unix::fs::symlink(".", dir.join("a")).expect("link");
    std::os::unix::fs::symlink(".", dir.join("b")).expect("link");
    // A named pipe called like a scenario is no scenario file (opening it would wait forever).
    let fifo = Command::new("mkfifo").arg(dir.join("pipe.yaml")).status().is_ok_and(|s| s.success());
    let scenario =
        std::fs::read_to_string(root().join("scenarios/gsk/feed_hold/during_dwell.yaml")).expect("scenario");
    std::fs::write(dir.join("one.yaml"), scenario).expect("write");
    let adapter = format!("{BIN} serve");
    let e = run_in(&d.0, &["conform", "--adapter", &adapter, "--scenarios", "s"], &[]);
    let out = String::from_utf8_lossy(&e.stdout);
    assert_eq!(e.code, 0, "{out}{}", e.stderr);
    assert_eq!(out.lines().filter(|l| l.starts_with("ok ")).count(), 1, "{out}");
    assert!(!fifo || !out.contains("pipe.yaml"), "{out}");
}

#[test]
fn a_scenario_run_cannot_be_made_to_hold_unbounded_samples() {
    let d = Dir::new("scenario-samples");
    d.file("s.yaml", "title: t\nrules: [GSK-RT-01]\ndialect: gsk-lathe\nprogram: \"G4 P5000\\nM30\\n\"\n");
    hostile(
        &d.0,
        &["run", "s.yaml", "--sample-us", "1"],
        2,
        "--sample-us: 1 µs samples over the scenario's time limit of 600000 ms",
    );
    hostile(
        &d.0,
        &["run", "s.yaml", "--time-limit", "5"],
        2,
        "--time-limit: a scenario names its own time limit",
    );
}

#[test]
fn check_keeps_a_bounded_number_of_recorded_events() {
    let d = Dir::new("edges");
    d.file("p.nc", "S500 M03\nG0 X50 Z0\nM30\n");
    let e = run_in(&d.0, &["run", "p.nc", "--dialect", "gsk-lathe", "--out", "t.jsonl"], &[]);
    assert_eq!(e.code, 0, "{}", e.stderr);
    let meta = std::fs::read_to_string(d.0.join("t.jsonl"))
        .expect("trace")
        .lines()
        .next()
        .expect("meta")
        .to_string();
    let mut text = meta + "\n";
    for i in 0..1_000_001u64 {
        text.push_str(&format!(
            "{{\"t_us\":{},\"kind\":\"signal\",\"name\":\"MF\",\"value\":{}}}\n",
            i * 10,
            i % 2
        ));
    }
    d.file("edges.jsonl", text);
    hostile(
        &d.0,
        &["check", "p.nc", "--dialect", "gsk-lathe", "--trace", "edges.jsonl"],
        2,
        "edges.jsonl: more than 1000000 recorded events other than samples",
    );
}

/// A scenario whose `program_file` names a named pipe with no writer: refused at once, where it
/// used to wait for ever in `open`.
#[cfg(unix)]
#[test]
fn a_program_file_that_is_a_named_pipe_is_refused() {
    let d = Dir::new("fifo_program");
    let made = Command::new("mkfifo").arg(d.0.join("prog.nc")).status().is_ok_and(|s| s.success());
    if !made {
        eprintln!("skipped: mkfifo is not available here");
        return;
    }
    d.file("s.yaml", "title: a pipe\nrules: [COM-PARSE-05]\ndialect: gsk-lathe\nprogram_file: prog.nc\n");
    hostile(&d.0, &["run", "s.yaml"], 2, "named pipe");
    hostile(&d.0, &["run", "prog.nc", "--dialect", "gsk-lathe"], 2, "named pipe");
}
