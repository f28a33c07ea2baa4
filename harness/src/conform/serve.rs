//! The adapter end of the line protocol (`docs/adapter-protocol.md`) for any [`Controller`]:
//! `nc-conform serve` answers with the reference engine, so an adapter in another language can
//! delegate to it, and the protocol is tested from both ends.

use std::io::{BufRead, Read, Write};

use nc_engine::trace::TraceMeta;
use serde_json::{json, Map, Value};

use super::process::MAX_ANSWER;
use super::{wire, Controller, Loaded, PROTOCOL};

/// Answers requests read from `input` on `output` until `quit` or the end of the input.
///
/// # Errors
///
/// Reading or writing failed.
pub fn serve(
    ctl: &mut dyn Controller,
    mut input: impl BufRead,
    mut output: impl Write,
) -> std::io::Result<()> {
    let mut meta: Option<TraceMeta> = None;
    let mut buf = Vec::new();
    loop {
        // One request line, at most MAX_ANSWER bytes: a longer one is answered and ends serving.
        buf.clear();
        if input.by_ref().take(MAX_ANSWER as u64 + 1).read_until(b'\n', &mut buf)? == 0 {
            break;
        }
        if buf.len() > MAX_ANSWER && buf.last() != Some(&b'\n') {
            output.write_all(failure(format!("a request line longer than {MAX_ANSWER} bytes")).as_bytes())?;
            output.write_all(b"\n")?;
            output.flush()?;
            return Err(std::io::Error::new(std::io::ErrorKind::InvalidData, "a request line too long"));
        }
        let line = String::from_utf8_lossy(&buf);
        if line.trim().is_empty() {
            continue;
        }
        let (answer, quit) = match crate::json_keys::from_str(line.trim_end()) {
            Ok(Value::Object(o)) => {
                let op = o.get("op").and_then(Value::as_str).unwrap_or("").to_string();
                (answer(ctl, &op, &o, &mut meta), op == "quit")
            }
            _ => (failure("a request is one JSON object per line"), false),
        };
        output.write_all(answer.as_bytes())?;
        output.write_all(b"\n")?;
        output.flush()?;
        if quit {
            break;
        }
    }
    Ok(())
}

fn failure(why: impl std::fmt::Display) -> String {
    json!({ "ok": false, "error": why.to_string() }).to_string()
}

fn answer(
    ctl: &mut dyn Controller,
    op: &str,
    o: &Map<String, Value>,
    meta: &mut Option<TraceMeta>,
) -> String {
    match op {
        "hello" => {
            let theirs = o.get("protocol").and_then(Value::as_str).unwrap_or("");
            if theirs != PROTOCOL {
                return json!({ "ok": false, "protocol": PROTOCOL, "error": format!("protocol {theirs} is not spoken here; this adapter speaks {PROTOCOL}") }).to_string();
            }
            match ctl.identity() {
                Ok(id) => json!({ "ok": true, "protocol": PROTOCOL, "name": id.name, "version": id.version, "dialects": id.dialects }).to_string(),
                Err(e) => failure(e),
            }
        }
        "load" => {
            let job = match wire::job_from(o) {
                Ok(j) => j,
                Err(e) => return failure(format!("bad load: {e}")),
            };
            *meta = wire::meta_of(&job);
            match ctl.load(&job) {
                Ok(Loaded::Ready) => json!({ "ok": true }).to_string(),
                Ok(Loaded::Refused { line, col, message }) => {
                    json!({ "ok": false, "refused": { "line": line, "col": col, "message": message } })
                        .to_string()
                }
                Ok(Loaded::Unsupported(why)) => json!({ "ok": false, "unsupported": why }).to_string(),
                Err(e) => failure(e),
            }
        }
        "input" => {
            let t = o.get("t_us").and_then(Value::as_u64);
            let input = o.get("input").map(wire::input_from);
            match (t, input) {
                (Some(t), Some(Ok(input))) => match ctl.input(t, &input) {
                    Ok(()) => json!({ "ok": true }).to_string(),
                    Err(e) => failure(e),
                },
                (_, Some(Err(e))) => failure(format!("bad input: {e}")),
                _ => failure("an input request needs `t_us` (integer) and `input` (object)"),
            }
        }
        "advance" => {
            let Some(until) = o.get("until_us").and_then(Value::as_u64) else {
                return failure("an advance request needs `until_us` (integer)");
            };
            let conds = o.get("stop_on").and_then(Value::as_array).map_or(&[][..], Vec::as_slice);
            let stop_on: Result<Vec<_>, String> = conds.iter().map(wire::condition_from).collect();
            match stop_on.map(|s| ctl.advance(until, &s)) {
                Ok(Ok(a)) => {
                    json!({ "ok": true, "now_us": a.now_us, "stopped_on": a.stopped_on, "ended": a.ended })
                        .to_string()
                }
                Ok(Err(e)) => failure(e),
                Err(e) => failure(format!("bad condition: {e}")),
            }
        }
        "read" => match (ctl.read(), meta.as_ref()) {
            (Ok(events), Some(m)) => {
                format!("{{\"ok\":true,\"events\":[{}]}}", wire::event_lines(m, &events).join(","))
            }
            (Ok(_), None) => failure("no program loaded"),
            (Err(e), _) => failure(e),
        },
        "reset" => {
            *meta = None;
            json!({ "ok": true }).to_string()
        }
        "quit" => json!({ "ok": true }).to_string(),
        other => {
            failure(format!("unknown op `{other}`; one of hello, load, input, advance, read, reset, quit"))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::conform::reference::Reference;

    fn talk(requests: &[&str]) -> Vec<Value> {
        let input = requests.join("\n");
        let mut out = Vec::new();
        serve(&mut Reference::new(), input.as_bytes(), &mut out).unwrap();
        String::from_utf8(out).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect()
    }

    #[test]
    fn a_session_answers_every_request_in_order() {
        let a = talk(&[
            r#"{"op":"hello","protocol":"nc-conform-adapter/1"}"#,
            r#"{"op":"load","dialect":"gsk-lathe","program":"G0 Z-5;\nM30;\n","params":[],"sample_us":0,"time_limit_us":10000000,"auto_cycle_start":true}"#,
            r#"{"op":"advance","until_us":10000001,"stop_on":[{"function":"M30"}]}"#,
            r#"{"op":"read"}"#,
            r#"{"op":"advance","until_us":10000001,"stop_on":[]}"#,
            r#"{"op":"jog"}"#,
            "not json",
            r#"{"op":"quit"}"#,
            r#"{"op":"read"}"#,
        ]);
        assert_eq!(a.len(), 8, "nothing is answered after quit: {a:?}");
        assert_eq!(a[0]["name"], "nc-conform reference");
        assert_eq!(a[1], json!({ "ok": true }));
        assert_eq!(a[2]["stopped_on"], 0);
        assert_eq!(a[2]["ended"], false);
        let events = a[3]["events"].as_array().unwrap();
        // The stop comes where the engine acts on M30's output: after it, at the same µs.
        let m30 = events.iter().find(|e| e["kind"] == "function" && e["code"] == 30).expect("M30 read");
        assert_eq!(events.last().unwrap()["t_us"], m30["t_us"]);
        assert!(!events.iter().any(|e| e["kind"] == "end"));
        assert_eq!(a[4]["ended"], true);
        assert!(a[5]["error"].as_str().unwrap().starts_with("unknown op `jog`"));
        assert_eq!(a[6]["error"], "a request is one JSON object per line");
        assert_eq!(a[7], json!({ "ok": true }));
    }

    #[test]
    fn another_protocol_version_is_refused_with_ours() {
        let a = talk(&[r#"{"op":"hello","protocol":"nc-conform-adapter/2"}"#]);
        assert_eq!(a[0]["ok"], false);
        assert_eq!(a[0]["protocol"], PROTOCOL);
    }

    #[test]
    fn a_refused_program_gives_line_and_column() {
        let a = talk(&[
            r#"{"op":"load","dialect":"gsk-lathe","program":"G98;\nG0 X#1;\n","params":[],"sample_us":1000,"time_limit_us":1000000,"auto_cycle_start":true}"#,
        ]);
        assert_eq!(a[0]["refused"]["line"], 2);
        assert_eq!(a[0]["refused"]["col"], 5);
    }
}
