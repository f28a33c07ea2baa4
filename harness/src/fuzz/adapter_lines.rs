//! Fuzz target `adapter_lines`: the adapter runner of `nc-conform conform` against a fuzzed fake
//! adapter. The input is the adapter's whole output (answer lines built from the protocol's
//! shapes with fuzzed fields, raw fuzzed lines, a last line without its end) and what the adapter
//! does once it has said it all: exit, close its stdout and stay, close its stdin and stay, fall
//! silent, or print one endless line. The fake adapter is a real process (`sh`, writing a file
//! the target wrote), so the runner's pipes, line reader, timeouts and restarts are the ones a
//! vendor's adapter meets.
//!
//! The runner drives a small scenario twice (a failed scenario restarts the adapter). A bug is a
//! panic, an error without a message, or a run that does not end: libFuzzer's `-timeout` and
//! `-rss_limit_mb` catch a hang or an unbounded read.

use std::path::PathBuf;
use std::sync::OnceLock;
use std::time::Duration;

use arbitrary::{Arbitrary, Unstructured};

use crate::conform::process::ProcessController;
use crate::conform::{drive, wire, Controller, PROTOCOL};
use crate::scenario::load::{load_text, Scenario};

/// How long the runner waits for one answer of the fake adapter.
pub const ANSWER_TIMEOUT: Duration = Duration::from_millis(100);

/// One answer line of the fake adapter.
#[derive(Debug, Arbitrary)]
enum Answer {
    /// A good `hello` answer (`dialects` fuzzed in part).
    Hello(bool),
    /// `{"ok":true}`
    Ok,
    /// `{"ok":false,"error":...}`
    Failed(String),
    /// A `load` refusal with its location.
    Refused(u32, u32, String),
    /// `{"ok":false,"unsupported":...}`
    Unsupported(String),
    /// An `advance` answer.
    Advance(u64, bool, Option<u8>),
    /// A `read` answer: the events are raw text inside the array.
    Read(String),
    /// A `read` answer with the reference run's events, the first `n` of them (all from 255 on).
    Reference(u8),
    /// A raw line (any bytes but the line end).
    Raw(Vec<u8>),
    /// Bytes without a line end: the answer goes on in the next one.
    Unended(Vec<u8>),
}

/// What the fake adapter does after its last answer.
#[derive(Debug, Arbitrary)]
enum Then {
    /// Exits.
    Exit,
    /// Closes its stdout, keeps reading its stdin.
    CloseStdout,
    /// Closes its stdin, stays alive (for at most a minute).
    CloseStdin,
    /// Says nothing more, keeps reading its stdin.
    Silent,
    /// Prints one line without end, forever.
    EndlessLine,
}

/// One `adapter_lines` input.
#[derive(Debug, Arbitrary)]
struct FakeAdapter {
    then: Then,
    answers: Vec<Answer>,
}

/// Fuzz target `adapter_lines`: see the module doc.
///
/// # Panics
///
/// On a bug: the runner panics, or reports an error without a message.
pub fn adapter_lines(data: &[u8]) {
    let Ok(fake) = FakeAdapter::arbitrary_take_rest(Unstructured::new(data)) else { return };
    let (dir, scenario, _) = fixtures();
    let argv = fake_adapter(dir, "answers", &fake);
    let mut ctl = ProcessController::new(argv, ANSWER_TIMEOUT);
    let dialects = match ctl.identity() {
        Ok(id) => id.dialects,
        Err(e) => {
            assert!(!e.message.is_empty(), "an adapter error without a message: {e:?}");
            return;
        }
    };
    if !dialects.iter().any(|d| d == scenario.machine.dialect.name()) {
        return;
    }
    let job = drive::job_of(scenario, SCENARIO_PROGRAM.to_string());
    let meta = scenario.machine.run_to_trace(&scenario.program, &scenario.opts).meta;
    for _ in 0..2 {
        if let Err(e) = drive::drive(&mut ctl, scenario, &job, meta.clone()) {
            assert!(!e.message.is_empty(), "an adapter error without a message: {e:?}");
        }
    }
}

/// The program of [`super::SCENARIO`].
const SCENARIO_PROGRAM: &str = "G90 G0 X0 Y0 Z10\nM29 S1000\nG91 G99 G84 X10 R-8 Z-6 F1000 L2\nG80\nM30\n";

/// The scratch directory of this process, the scenario the runner drives and the event lines of
/// its reference run.
fn fixtures() -> &'static (PathBuf, Scenario, Vec<String>) {
    static F: OnceLock<(PathBuf, Scenario, Vec<String>)> = OnceLock::new();
    F.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("nc-conform-fuzz-adapter-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch directory");
        let s = load_text(super::SCENARIO, "fuzz.yaml", &dir).expect("the fixture scenario loads");
        let trace = s.machine.run_to_trace(&s.program, &s.opts);
        let lines = wire::event_lines(&trace.meta, &trace.events);
        (dir, s, lines)
    })
}

/// Writes the fake adapter's answers (`NAME.0`, `NAME.1`, ... in `dir`) and returns its command
/// line: one answer (a file) per request line read, then its last act.
fn fake_adapter(dir: &std::path::Path, name: &str, fake: &FakeAdapter) -> Vec<String> {
    let answers = answer_lines(fake);
    for (i, a) in answers.iter().enumerate() {
        std::fs::write(dir.join(format!("{name}.{i}")), a).expect("scratch file");
    }
    let then = match fake.then {
        Then::Exit => "exit 0",
        Then::CloseStdout => "exec 1>&-; exec cat >/dev/null",
        Then::CloseStdin => "exec 0<&-; exec sleep 60",
        Then::Silent => "while read -r _; do :; done",
        Then::EndlessLine => r"exec tr '\0' x </dev/zero",
    };
    let script =
        format!(r#"i=0; while [ "$i" -lt "$2" ] && read -r _; do cat "$1.$i"; i=$((i+1)); done; {then}"#);
    let base = dir.join(name).display().to_string();
    ["sh".to_string(), "-c".into(), script, "fake-adapter".into(), base, answers.len().to_string()].to_vec()
}

/// The fake adapter's answers, one per request.
fn answer_lines(fake: &FakeAdapter) -> Vec<Vec<u8>> {
    let mut out: Vec<Vec<u8>> = Vec::new();
    for a in &fake.answers {
        let line = match a {
            Answer::Hello(all) => {
                let dialects = if *all { r#"["fanuc-mill","gsk-lathe"]"# } else { r#"["gsk-lathe"]"# };
                format!(r#"{{"ok":true,"protocol":"{PROTOCOL}","name":"fake","version":"0","dialects":{dialects}}}"#)
            }
            Answer::Ok => r#"{"ok":true}"#.to_string(),
            Answer::Failed(why) => serde_json::json!({ "ok": false, "error": why }).to_string(),
            Answer::Refused(line, col, message) => {
                serde_json::json!({ "ok": false, "refused": { "line": line, "col": col, "message": message } })
                    .to_string()
            }
            Answer::Unsupported(why) => serde_json::json!({ "ok": false, "unsupported": why }).to_string(),
            Answer::Advance(now_us, ended, stopped_on) => {
                serde_json::json!({ "ok": true, "now_us": now_us, "ended": ended, "stopped_on": stopped_on })
                    .to_string()
            }
            Answer::Read(events) => format!(r#"{{"ok":true,"events":[{events}]}}"#),
            Answer::Reference(n) => {
                let events = &fixtures().2;
                let n = if *n == u8::MAX { events.len() } else { (*n as usize).min(events.len()) };
                format!(r#"{{"ok":true,"events":[{}]}}"#, events[..n].join(","))
            }
            Answer::Raw(bytes) => {
                let mut l: Vec<u8> = bytes.iter().copied().filter(|&b| b != b'\n').collect();
                l.push(b'\n');
                out.push(l);
                continue;
            }
            Answer::Unended(bytes) => {
                out.push(bytes.iter().copied().filter(|&b| b != b'\n').collect());
                continue;
            }
        };
        out.push(format!("{line}\n").into_bytes());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fake_adapter_answers_in_order() {
        let fake = FakeAdapter {
            then: Then::Exit,
            answers: vec![
                Answer::Ok,
                Answer::Raw(b"a\nb".to_vec()),
                Answer::Reference(1),
                Answer::Unended(b"x".to_vec()),
            ],
        };
        let lines = answer_lines(&fake);
        assert_eq!(lines.len(), 4);
        assert_eq!(lines[0], b"{\"ok\":true}\n");
        assert_eq!(lines[1], b"ab\n");
        assert!(String::from_utf8_lossy(&lines[2]).starts_with(r#"{"ok":true,"events":[{"t_us":0,"#));
        assert_eq!(lines[3], b"x");
    }

    #[test]
    fn a_well_behaved_fake_adapter_runs_the_scenario() {
        // hello, load, an advance to the end, the end event: the runner gets through.
        let answers = vec![
            Answer::Hello(true),
            Answer::Ok,
            Answer::Advance(1_000_000, true, None),
            Answer::Reference(u8::MAX),
        ];
        let fake = FakeAdapter { then: Then::Exit, answers };
        let (dir, scenario, _) = fixtures();
        let argv = fake_adapter(dir, "answers-test", &fake);
        let mut ctl = ProcessController::new(argv, Duration::from_secs(5));
        assert_eq!(ctl.identity().unwrap().name, "fake");
        let job = drive::job_of(scenario, SCENARIO_PROGRAM.to_string());
        let meta = scenario.machine.run_to_trace(&scenario.program, &scenario.opts).meta;
        let driven = drive::drive(&mut ctl, scenario, &job, meta);
        assert!(driven.is_ok(), "{:?}", driven.err());
    }
}
