//! End-to-end tests of `nc-conform check`: exit status 0 / 1 / 2, the summary on standard output
//! with its timing diagram, and the structure of the JSON, JUnit XML and HTML reports.

mod check_util;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use check_util::*;
use nc_conform::jsonl::JsonlWriter;
use nc_engine::trace::{Event, Trace, TraceEvent};

const BIN: &str = env!("CARGO_BIN_EXE_nc-conform");
const CLAMP: &str = "scenarios/gsk/clamp/clamp_codes_frame_the_hole.yaml";

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("nc-conform-check-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Writes a recorded stream as `nc-conform-trace/1` JSON Lines, with the reference's end line.
fn write_jsonl(path: &Path, reference: &Trace, events: &[TraceEvent]) {
    let mut w = JsonlWriter::new(Vec::new());
    w.write_meta(&reference.meta);
    for e in events {
        w.write_event(e);
    }
    let last = events.last().map_or(0, |e| e.t_us);
    let end = reference.events.last().unwrap().event.clone();
    assert!(matches!(end, Event::End(_)));
    w.write_event(&TraceEvent { t_us: last, event: end });
    std::fs::write(path, w.finish().unwrap()).unwrap();
}

fn check(args: &[&str]) -> Output {
    Command::new(BIN).current_dir(root()).arg("check").args(args).output().expect("run nc-conform")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[test]
fn conformant_recording_exits_0_with_reports() {
    let d = dir("ok");
    let s = scenario(CLAMP);
    let reference = reference(&s);
    let trace = d.join("rec.jsonl");
    write_jsonl(&trace, &reference, &record(&reference, Rec::REALISTIC));
    let (json, junit, html) = (d.join("r.json"), d.join("j.xml"), d.join("r.html"));
    let out = check(&[
        CLAMP,
        "--trace",
        trace.to_str().unwrap(),
        "--report",
        json.to_str().unwrap(),
        "--junit",
        junit.to_str().unwrap(),
        "--html",
        html.to_str().unwrap(),
    ]);
    let so = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{so}\n{}", text(&out.stderr));
    assert!(so.contains("CONFORMANT"), "{so}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["format"], "nc-conform-check/1");
    assert_eq!(v["conformant"], true);
    assert_eq!(v["report"]["divergences"].as_array().unwrap().len(), 0);
    assert!(v["report"]["offset_us"].as_i64().unwrap() < -3_000_000);
    let j = std::fs::read_to_string(&junit).unwrap();
    assert!(j.starts_with("<?xml") && j.contains("failures=\"0\"") && j.contains("<testcase"), "{j}");
    let h = std::fs::read_to_string(&html).unwrap();
    assert!(h.contains("CONFORMANT"));
    assert_eq!(h.matches("<svg").count(), 4, "tap, spindle, sync plots and the PLC signal lanes");
    assert!(h.contains("id=\"lanes\"") && h.contains("class=\"lane\" data-signal=\"RGSPP\""), "signal lanes");
}

#[test]
fn divergent_recording_exits_1_and_reports_every_divergence() {
    let d = dir("bad");
    let s = scenario(CLAMP);
    let reference = reference(&s);
    let mut t = reference.clone();
    // A defective PLC: the clamp code M68 is never output, and RGTAP drops 3 ms before F76.3.
    t.events.retain(|e| !matches!(e.event, Event::Function { letter: 'M', code: 68 }));
    let rec = record(&t, Rec::REALISTIC);
    let trace = d.join("rec.jsonl");
    write_jsonl(&trace, &reference, &rec);
    let (json, junit, html) = (d.join("r.json"), d.join("j.xml"), d.join("r.html"));
    let out = check(&[
        CLAMP,
        "--trace",
        trace.to_str().unwrap(),
        "--report",
        json.to_str().unwrap(),
        "--junit",
        junit.to_str().unwrap(),
        "--html",
        html.to_str().unwrap(),
    ]);
    let so = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{so}\n{}", text(&out.stderr));
    assert!(so.contains("DIVERGENT"), "{so}");
    assert!(so.contains("FAIL GSK-RT-11 CHK-EVT-02 M68 missing"), "{so}");
    assert!(so.contains("Around the first divergence") && so.contains("recorded (aligned):"), "{so}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["conformant"], false);
    let ds = v["report"]["divergences"].as_array().unwrap();
    let d0 = ds.iter().find(|d| d["rule"] == "GSK-RT-11").expect("the clamp divergence");
    for k in ["rule", "check", "what", "t_us", "expected", "actual", "margin"] {
        assert!(!d0[k].is_null(), "{k} missing in {d0}");
    }
    let j = std::fs::read_to_string(&junit).unwrap();
    assert!(j.contains("<failure type=\"CHK-EVT-02\"") && j.contains("classname=\"GSK-RT-11\""), "{j}");
    let h = std::fs::read_to_string(&html).unwrap();
    assert!(h.contains("DIVERGENT") && h.contains("class=\"divergence\"") && h.contains("divergence-row"));
    assert!(h.contains("id=\"zoom-1\""), "a zoomed view around the first divergence");
    // Self-contained: no script, no external resource (the only URL is the SVG namespace).
    for bad in ["<script", "src=", "href=", "@import", "url("] {
        assert!(!h.contains(bad), "{bad} in the HTML report");
    }
    assert_eq!(h.matches("http").count(), h.matches("http://www.w3.org/2000/svg").count());
}

#[test]
fn bare_program_with_its_own_trace_is_conformant() {
    let d = dir("prog");
    let trace = d.join("run.jsonl");
    let run = Command::new(BIN)
        .current_dir(root())
        .args(["run", "examples/gsk_g88_standard.nc", "--dialect", "gsk-lathe", "--out"])
        .arg(&trace)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(0));
    let out = check(&[
        "examples/gsk_g88_standard.nc",
        "--dialect",
        "gsk-lathe",
        "--trace",
        trace.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stdout));
}

#[test]
fn input_errors_exit_2_with_a_location() {
    let d = dir("err");
    let bad = d.join("bad.jsonl");
    std::fs::write(
        &bad,
        "{\"t_us\":0,\"kind\":\"meta\",\"dialect\":\"gsk-lathe\",\"axes\":[\"X\",\"Z\",\"C\"],\"diameter\":[\"X\"],\"period_us\":1000,\"sample_us\":1000,\"format\":\"nc-conform-trace/1\"}\n{\"t_us\":5,\"kind\":\"signal\",\"name\":\"NOPE\",\"value\":1}\n",
    )
    .unwrap();
    let out = check(&[CLAMP, "--trace", bad.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let e = text(&out.stderr);
    assert!(e.contains("bad.jsonl:2:"), "{e}");
    let out = check(&[CLAMP, "--trace", d.join("absent.jsonl").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let out = check(&[CLAMP, "--trace", bad.to_str().unwrap(), "--anchor", "nonsense"]);
    assert_eq!(out.status.code(), Some(2));
    let out = check(&["examples/gsk_g88_standard.nc", "--trace", bad.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "a program needs --dialect");
    let tol = d.join("tol.yaml");
    std::fs::write(&tol, "event_ms: 5\nbogus: 1\n").unwrap();
    let out = check(&[CLAMP, "--trace", bad.to_str().unwrap(), "--tolerances", tol.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
}
