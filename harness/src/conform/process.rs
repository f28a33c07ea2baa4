//! A controller in another process (any language), over the line protocol of
//! `docs/adapter-protocol.md`: one JSON object per line on its stdin, one answer per line on its
//! stdout, its stderr kept (the tail goes into every error).
//!
//! Every request waits at most the timeout for its answer, and a whole scenario at most the
//! scenario limit. A timeout, an exit, a closed stdin or stdout, a line that is not a JSON object
//! or longer than [`MAX_ANSWER`], an answer that breaks the protocol, advances that make no
//! progress, or an `ok: false` is a [`ControllerError`] of that scenario; the process is then
//! killed and started again (with a new handshake) for the next scenario, so one broken run does
//! not end the suite. What the adapter writes is shown with its control characters escaped.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Read, Write};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use nc_engine::input::{Condition, Input};
use nc_engine::trace::{Event, TraceEvent, TraceMeta};
use nc_engine::units::Micros;
use serde_json::value::RawValue;
use serde_json::{json, Map, Value};

use super::{wire, Advanced, Controller, ControllerError, ErrorKind, Identity, Job, Loaded, PROTOCOL};
use crate::import::{self, Format};

/// How long a failed controller's stderr is read on after it was stopped (a grandchild holding the
/// pipe open must not hold the run).
const STDERR_DRAIN: Duration = Duration::from_millis(500);

/// How much of the controller's stderr is kept (bytes).
const STDERR_KEEP: usize = 4096;
/// The longest answer line shown in an error (characters).
const SHOW: usize = 200;
/// The longest answer line read (bytes), as the JSON Lines importer's longest line: past it the
/// answer is garbage and the adapter is restarted.
pub const MAX_ANSWER: usize = 16 << 20;
/// How many `advance` answers in a row may leave the clock where it was without stopping on a
/// condition or ending.
pub const MAX_IDLE_ADVANCES: u32 = 1000;
/// The longest time one scenario may take by default (`--scenario-timeout-ms`).
pub const DEFAULT_SCENARIO_LIMIT: Duration = Duration::from_secs(600);

/// A running adapter process.
struct Proc {
    child: Child,
    stdin: ChildStdin,
    lines: Receiver<std::io::Result<String>>,
    /// Closed when the stderr reader has read the pipe to its end.
    stderr_done: Receiver<()>,
}

/// A controller behind an adapter program.
pub struct ProcessController {
    argv: Vec<String>,
    timeout: Duration,
    proc: Option<Proc>,
    stderr: Arc<Mutex<VecDeque<u8>>>,
    identity: Option<Identity>,
    meta: Option<TraceMeta>,
    loaded: bool,
    /// The longest time one scenario (from its `load`) may take.
    scenario_limit: Duration,
    /// When the present scenario was loaded.
    scenario_start: Option<Instant>,
    /// The clock of the last `advance` answer, and how many in a row left it unchanged.
    last_now: Option<Micros>,
    idle_advances: u32,
}

/// Splits a command line into words: blanks separate, `'...'` and `"..."` quote, `\` escapes
/// the next character outside single quotes.
///
/// # Errors
///
/// An unclosed quote, or no word at all.
pub fn split_command(line: &str) -> Result<Vec<String>, String> {
    let mut words = Vec::new();
    let mut cur = String::new();
    let mut has = false;
    let mut quote: Option<char> = None;
    let mut chars = line.chars();
    while let Some(c) = chars.next() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some('\''), c) => cur.push(c),
            (_, '\\') => {
                if let Some(n) = chars.next() {
                    cur.push(n);
                }
                has = true;
            }
            (Some(_), c) => cur.push(c),
            (None, '\'' | '"') => {
                quote = Some(c);
                has = true;
            }
            (None, c) if c.is_whitespace() => {
                if has || !cur.is_empty() {
                    words.push(std::mem::take(&mut cur));
                }
                has = false;
            }
            (None, c) => cur.push(c),
        }
    }
    if quote.is_some() {
        return Err(format!("unclosed quote in `{line}`"));
    }
    if has || !cur.is_empty() {
        words.push(cur);
    }
    if words.is_empty() {
        return Err("an empty command".into());
    }
    Ok(words)
}

fn shorten(s: &str) -> String {
    crate::diag::printable(s, SHOW)
}

/// Reads the adapter's stdout line by line into `tx`, each line at most [`MAX_ANSWER`] bytes:
/// a longer one (or one that is not UTF-8) is sent as an error and the reading stops.
fn read_answers(stdout: impl Read, tx: &mpsc::Sender<std::io::Result<String>>) {
    let mut r = BufReader::new(stdout);
    loop {
        let mut buf = Vec::new();
        match (&mut r).take(MAX_ANSWER as u64 + 1).read_until(b'\n', &mut buf) {
            Ok(0) => return,
            Ok(_) if buf.last() == Some(&b'\n') || buf.len() <= MAX_ANSWER => {
                if buf.last() == Some(&b'\n') {
                    buf.pop();
                }
                if buf.last() == Some(&b'\r') {
                    buf.pop();
                }
                let line = String::from_utf8(buf).map_err(|_| {
                    std::io::Error::new(std::io::ErrorKind::InvalidData, "an answer line that is not UTF-8")
                });
                let bad = line.is_err();
                if tx.send(line).is_err() || bad {
                    return;
                }
            }
            Ok(_) => {
                let e = std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!("an answer line longer than {MAX_ANSWER} bytes"),
                );
                let _ = tx.send(Err(e));
                return;
            }
            Err(e) => {
                let _ = tx.send(Err(e));
                return;
            }
        }
    }
}

/// The exit status of an adapter that should have ended: waited for briefly, else killed (an
/// adapter that closed its stdin or stdout may well go on running).
fn exit_status(child: &mut Child) -> String {
    let until = Instant::now() + Duration::from_millis(500);
    loop {
        match child.try_wait() {
            Ok(Some(s)) => return format!("exited ({s})"),
            Ok(None) if Instant::now() < until => std::thread::sleep(Duration::from_millis(10)),
            Ok(None) => {
                let _ = child.kill();
                let _ = child.wait();
                return "closed its pipe but kept running (killed)".into();
            }
            Err(_) => return "exited (unknown status)".into(),
        }
    }
}

impl ProcessController {
    /// A controller run as `argv` (started at the first request), each answer awaited at most
    /// `timeout`.
    pub fn new(argv: Vec<String>, timeout: Duration) -> Self {
        ProcessController {
            argv,
            timeout,
            proc: None,
            stderr: Arc::new(Mutex::new(VecDeque::new())),
            identity: None,
            meta: None,
            loaded: false,
            scenario_limit: DEFAULT_SCENARIO_LIMIT,
            scenario_start: None,
            last_now: None,
            idle_advances: 0,
        }
    }

    /// The same controller with another limit on the time one scenario may take.
    #[must_use]
    pub fn with_scenario_limit(mut self, limit: Duration) -> Self {
        self.scenario_limit = limit;
        self
    }

    /// The last lines of the controller's stderr, control characters escaped.
    pub fn stderr_tail(&self) -> String {
        let buf = self.stderr.lock().map(|b| b.iter().copied().collect::<Vec<u8>>()).unwrap_or_default();
        String::from_utf8_lossy(&buf)
            .lines()
            .map(|l| crate::diag::printable(l, STDERR_KEEP))
            .collect::<Vec<_>>()
            .join("\n")
    }

    fn fail(&mut self, kind: ErrorKind, message: impl Into<String>) -> ControllerError {
        // Every controller error restarts the adapter, `ok: false` included
        // (docs/adapter-protocol.md): the next scenario starts from a fresh handshake. The process
        // is stopped first and its stderr read to the end (at most STDERR_DRAIN), so the tail holds
        // what it wrote before it answered (an `ok: false` read at once used to race the reader).
        if let Some(mut p) = self.proc.take() {
            let _ = p.child.kill();
            let _ = p.child.wait();
            let _ = p.stderr_done.recv_timeout(STDERR_DRAIN);
        }
        self.stop();
        ControllerError { kind, message: message.into(), stderr_tail: self.stderr_tail() }
    }

    /// Kills the process (it is started again at the next request).
    fn stop(&mut self) {
        if let Some(mut p) = self.proc.take() {
            let _ = p.child.kill();
            let _ = p.child.wait();
        }
        self.loaded = false;
        self.scenario_start = None;
    }

    fn start(&mut self) -> Result<(), ControllerError> {
        if self.proc.is_some() {
            return Ok(());
        }
        if let Ok(mut b) = self.stderr.lock() {
            b.clear();
        }
        let mut child = Command::new(&self.argv[0])
            .args(&self.argv[1..])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| {
                ControllerError::new(ErrorKind::Crash, format!("cannot start `{}`: {e}", self.argv.join(" ")))
            })?;
        let stdin = child.stdin.take().expect("piped stdin");
        let stdout = child.stdout.take().expect("piped stdout");
        let mut stderr = child.stderr.take().expect("piped stderr");
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || read_answers(stdout, &tx));
        let keep = Arc::clone(&self.stderr);
        let (done_tx, stderr_done) = mpsc::channel::<()>();
        std::thread::spawn(move || {
            // Dropped when the pipe has been read to its end: `fail` waits for it.
            let _done = done_tx;
            let mut buf = [0u8; 1024];
            while let Ok(n) = stderr.read(&mut buf) {
                if n == 0 {
                    break;
                }
                if let Ok(mut k) = keep.lock() {
                    k.extend(&buf[..n]);
                    while k.len() > STDERR_KEEP {
                        k.pop_front();
                    }
                }
            }
        });
        self.proc = Some(Proc { child, stdin, lines: rx, stderr_done });
        self.hello()
    }

    fn hello(&mut self) -> Result<(), ControllerError> {
        let msg = json!({
            "op": "hello",
            "protocol": PROTOCOL,
            "trace_format": crate::import::jsonl::FORMAT,
            "capabilities": ["stop_on"],
        });
        let line = self.send_raw(&msg)?;
        let o = self.object(&line, &msg)?;
        // The version first: an adapter of another version may refuse the hello with ok: false.
        let theirs = o.get("protocol").and_then(Value::as_str).unwrap_or("(none)").to_string();
        if theirs != PROTOCOL {
            return Err(self.fail(
                ErrorKind::Protocol,
                format!("protocol version mismatch: the harness speaks {PROTOCOL}, the adapter {theirs}"),
            ));
        }
        let o = self.ok(o, &msg)?;
        let text = |k: &str| o.get(k).and_then(Value::as_str).map(|s| crate::diag::printable(s, SHOW));
        let dialects: Option<Vec<String>> = o
            .get("dialects")
            .and_then(Value::as_array)
            .map(|a| a.iter().filter_map(|d| d.as_str().map(|s| crate::diag::printable(s, SHOW))).collect());
        match (text("name"), text("version"), dialects) {
            (Some(name), Some(version), Some(dialects)) => {
                self.identity = Some(Identity { name, version, dialects });
                Ok(())
            }
            _ => Err(self.fail(
                ErrorKind::Protocol,
                "the hello answer needs `name`, `version` (strings) and `dialects` (an array of strings)",
            )),
        }
    }

    /// Sends one message and returns the answer line (started if need be).
    fn send_raw(&mut self, msg: &Value) -> Result<String, ControllerError> {
        let op = msg.get("op").and_then(Value::as_str).unwrap_or("?").to_string();
        let Some(p) = self.proc.as_mut() else {
            return Err(ControllerError::new(ErrorKind::Crash, "the adapter is not running"));
        };
        let mut line = msg.to_string();
        line.push('\n');
        if let Err(e) = p.stdin.write_all(line.as_bytes()).and_then(|_| p.stdin.flush()) {
            let status = exit_status(&mut p.child);
            return Err(self.fail(ErrorKind::Crash, format!("the adapter {status} before `{op}`: {e}")));
        }
        // The answer's wait: the timeout, or what is left of the scenario's time.
        let left = self.scenario_start.map(|s| self.scenario_limit.saturating_sub(s.elapsed()));
        let wait = left.map_or(self.timeout, |l| l.min(self.timeout));
        match p.lines.recv_timeout(wait) {
            Ok(Ok(answer)) => Ok(answer),
            Ok(Err(e)) => Err(self.fail(ErrorKind::Garbage, format!("unreadable answer to `{op}`: {e}"))),
            Err(RecvTimeoutError::Timeout) if wait < self.timeout => Err(self.fail(
                ErrorKind::Timeout,
                format!(
                    "the scenario took longer than {} ms (--scenario-timeout-ms), waiting for `{op}`",
                    self.scenario_limit.as_millis()
                ),
            )),
            Err(RecvTimeoutError::Timeout) => Err(self.fail(
                ErrorKind::Timeout,
                format!("no answer to `{op}` within {} ms", self.timeout.as_millis()),
            )),
            Err(RecvTimeoutError::Disconnected) => {
                let status = exit_status(&mut p.child);
                Err(self.fail(ErrorKind::Crash, format!("the adapter {status} instead of answering `{op}`")))
            }
        }
    }

    /// Sends one message; the answer must be a JSON object with `ok: true`.
    fn send(&mut self, msg: &Value) -> Result<Map<String, Value>, ControllerError> {
        let line = self.send_raw(msg)?;
        let o = self.object(&line, msg)?;
        self.ok(o, msg)
    }

    fn object(&mut self, line: &str, msg: &Value) -> Result<Map<String, Value>, ControllerError> {
        let op = msg.get("op").and_then(Value::as_str).unwrap_or("?");
        match crate::json_keys::from_str(line) {
            Ok(Value::Object(o)) => Ok(o),
            Err(e) if crate::json_keys::is_duplicate(&e) => Err(self.fail(
                ErrorKind::Protocol,
                format!("the answer to `{op}` gives a key twice: {}", crate::json_keys::message(&e)),
            )),
            _ => Err(self.fail(
                ErrorKind::Garbage,
                format!("answer to `{op}` is not a JSON object: {}", shorten(line)),
            )),
        }
    }

    fn ok(&mut self, o: Map<String, Value>, msg: &Value) -> Result<Map<String, Value>, ControllerError> {
        let op = msg.get("op").and_then(Value::as_str).unwrap_or("?");
        match o.get("ok") {
            Some(Value::Bool(true)) => Ok(o),
            Some(Value::Bool(false))
                if op != "load" && o.get("unsupported").is_some_and(Value::is_string) =>
            {
                // The scenario is not applicable: the adapter goes on (no restart).
                let why = o.get("unsupported").and_then(Value::as_str).unwrap_or_default();
                Err(ControllerError::new(ErrorKind::NotApplicable, crate::diag::printable(why, 2 * SHOW)))
            }
            Some(Value::Bool(false)) => {
                let why = o.get("error").and_then(Value::as_str).unwrap_or("(no `error` given)");
                let why = crate::diag::printable(why, 2 * SHOW);
                Err(self.fail(ErrorKind::Failed, format!("`{op}` failed: {why}")))
            }
            _ => Err(self.fail(ErrorKind::Protocol, format!("the answer to `{op}` has no `ok: true|false`"))),
        }
    }

    fn ensure(&mut self) -> Result<(), ControllerError> {
        if self.proc.is_none() {
            self.start()?;
        }
        Ok(())
    }

    /// Events of a `read` answer, checked by the JSON Lines importer.
    fn events(&mut self, line: &str) -> Result<Vec<TraceEvent>, ControllerError> {
        #[derive(serde::Deserialize)]
        struct ReadAnswer<'a> {
            #[serde(borrow)]
            events: Vec<&'a RawValue>,
        }
        let parsed: ReadAnswer = match serde_json::from_str(line) {
            Ok(r) => r,
            Err(e) => {
                return Err(self
                    .fail(ErrorKind::Protocol, format!("the `read` answer needs `events` (an array): {e}")))
            }
        };
        let Some(meta) = &self.meta else {
            return Err(self.fail(ErrorKind::Protocol, "`read` before a successful `load`"));
        };
        let mut text = wire::meta_line(meta);
        for ev in &parsed.events {
            text.push('\n');
            text.push_str(ev.get());
        }
        text.push('\n');
        let has_end = parsed.events.iter().any(|e| e.get().contains("\"end\""));
        let opts = import::Options { format: Some(Format::Jsonl), ..Default::default() };
        let mut out = Vec::with_capacity(parsed.events.len());
        let name = "the `read` answer";
        let reader = import::from_reader(name, Box::new(std::io::Cursor::new(text.into_bytes())), &opts);
        let imp = match reader {
            Ok(i) => i,
            Err(e) => return Err(self.fail(ErrorKind::Protocol, format!("bad events: {}", e.message))),
        };
        for r in imp {
            match r {
                Ok(ev) => out.push(ev),
                Err(e) if e.kind == import::ErrorKind::Truncated && !has_end => break,
                Err(e) => {
                    let exp = e.expected.as_ref().map_or(String::new(), |x| format!("; expected {x}"));
                    // Line 1 is the meta line the harness adds: event k is line k + 1.
                    let msg = format!("bad event {}: {}{exp}", e.line.saturating_sub(1), e.message);
                    return Err(self.fail(ErrorKind::Protocol, msg));
                }
            }
        }
        if has_end && !out.last().is_some_and(|e| matches!(e.event, Event::End(_))) {
            return Err(self.fail(ErrorKind::Protocol, "an event after the `end` event"));
        }
        Ok(out)
    }
}

impl Drop for ProcessController {
    fn drop(&mut self) {
        if self.proc.is_some() {
            let _ = self
                .proc
                .as_mut()
                .map(|p| p.stdin.write_all(b"{\"op\":\"quit\"}\n").and_then(|_| p.stdin.flush()));
            if let Some(p) = self.proc.as_mut() {
                let _ = p.lines.recv_timeout(Duration::from_millis(200));
            }
            self.stop();
        }
    }
}

impl Controller for ProcessController {
    fn identity(&mut self) -> Result<Identity, ControllerError> {
        self.ensure()?;
        self.identity.clone().ok_or_else(|| ControllerError::new(ErrorKind::Protocol, "no hello answer"))
    }

    fn load(&mut self, job: &Job) -> Result<Loaded, ControllerError> {
        self.ensure()?;
        if self.loaded {
            self.send(&json!({ "op": "reset" }))?;
            self.loaded = false;
        }
        self.meta = wire::meta_of(job);
        self.scenario_start = Some(Instant::now());
        self.last_now = None;
        self.idle_advances = 0;
        let msg = wire::load_json(job);
        let line = self.send_raw(&msg)?;
        let o = self.object(&line, &msg)?;
        if o.get("ok") == Some(&Value::Bool(false)) {
            if let Some(r) = o.get("refused").and_then(Value::as_object) {
                let line = r.get("line").and_then(Value::as_u64).unwrap_or(0) as u32;
                let col = r.get("col").and_then(Value::as_u64).map(|c| c as u32);
                let message =
                    crate::diag::printable(r.get("message").and_then(Value::as_str).unwrap_or(""), 2 * SHOW);
                self.loaded = true;
                return Ok(Loaded::Refused { line, col, message });
            }
            if let Some(why) = o.get("unsupported").and_then(Value::as_str) {
                return Ok(Loaded::Unsupported(crate::diag::printable(why, 2 * SHOW)));
            }
        }
        self.ok(o, &msg)?;
        self.loaded = true;
        Ok(Loaded::Ready)
    }

    fn input(&mut self, t_us: Micros, input: &Input) -> Result<(), ControllerError> {
        self.send(&json!({ "op": "input", "t_us": t_us, "input": wire::input_json(input) })).map(|_| ())
    }

    fn advance(&mut self, until_us: Micros, stop_on: &[Condition]) -> Result<Advanced, ControllerError> {
        let conds: Vec<Value> = stop_on.iter().map(wire::condition_json).collect();
        let o = self.send(&json!({ "op": "advance", "until_us": until_us, "stop_on": conds }))?;
        let now_us = o.get("now_us").and_then(Value::as_u64);
        let ended = o.get("ended").and_then(Value::as_bool);
        let stopped_on = match o.get("stopped_on") {
            None | Some(Value::Null) => Ok(None),
            Some(v) => v.as_u64().map(|k| Some(k as usize)).ok_or(()),
        };
        match (now_us, ended, stopped_on) {
            (Some(now_us), Some(ended), Ok(stopped_on)) => {
                // Progress: the clock moves on, a condition stops it, or the run ends.
                if self.last_now.is_some_and(|last| now_us < last) {
                    return Err(self.fail(
                        ErrorKind::Protocol,
                        format!("`advance` answered now_us {now_us}, before the {} of the last answer", self.last_now.unwrap_or(0)),
                    ));
                }
                if !ended && stopped_on.is_none() && self.last_now == Some(now_us) {
                    self.idle_advances += 1;
                    if self.idle_advances >= MAX_IDLE_ADVANCES {
                        return Err(self.fail(
                            ErrorKind::Protocol,
                            format!("{MAX_IDLE_ADVANCES} `advance` answers in a row without progress (now_us stays {now_us}, no stop, no end)"),
                        ));
                    }
                } else {
                    self.idle_advances = 0;
                }
                self.last_now = Some(now_us);
                Ok(Advanced { now_us, stopped_on, ended })
            }
            _ => Err(self.fail(
                ErrorKind::Protocol,
                "the `advance` answer needs `now_us` (integer), `ended` (boolean), `stopped_on` (index or null)",
            )),
        }
    }

    fn read(&mut self) -> Result<Vec<TraceEvent>, ControllerError> {
        let msg = json!({ "op": "read" });
        let line = self.send_raw(&msg)?;
        let o = self.object(&line, &msg)?;
        self.ok(o, &msg)?;
        self.events(&line)
    }
}

#[cfg(test)]
mod tests {
    use super::split_command;

    #[test]
    fn command_lines_split_like_a_shell() {
        assert_eq!(split_command("python3 a.py --port 3").unwrap(), ["python3", "a.py", "--port", "3"]);
        assert_eq!(
            split_command(r#"  "my adapter" 'x y' a\ b "" "#).unwrap(),
            ["my adapter", "x y", "a b", ""]
        );
        assert_eq!(split_command("it's").unwrap_err(), "unclosed quote in `it's`");
        assert_eq!(split_command("   ").unwrap_err(), "an empty command");
    }
}
