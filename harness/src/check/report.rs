//! Reports of a comparison: the human summary (with a timing diagram of both traces around the
//! first divergence), JSON (serde_json) and JUnit XML (written by hand).

use std::fmt::Write as _;

use nc_engine::trace::{Signal, Trace};

use super::Report;
use crate::render::timing::{timing_diagram, DiagramSpec};
use crate::scenario::timeline::{fixed, ms};

/// The families of checks, for JUnit test cases: (id prefix, name).
pub const FAMILIES: [(&str, &str); 7] = [
    ("CHK-ALIGN", "alignment on the anchor"),
    ("CHK-EVT", "discrete events: order and time"),
    ("CHK-KEY", "key points: pecks, depths, dwells, return level"),
    ("CHK-SYNC", "synchronisation error"),
    ("CHK-ENV", "position envelope"),
    ("CHK-END", "final state"),
    ("CHK-RULE", "the scenario's temporal rules"),
];

fn at(t: Option<i64>) -> String {
    t.map_or("-".into(), |t| ms(t.max(0) as u64))
}

/// The human summary: header, figures, every divergence, and the diagrams.
pub fn summary(rep: &Report, reference: &Trace, title: &str) -> String {
    let mut s = String::new();
    let f = &rep.figures;
    let _ = writeln!(s, "{title}");
    let _ = writeln!(
        s,
        "aligned on the {} (reference = recorded {:+} µs; fit {}); {} recorded events, {} samples; {}/{} reference events matched; max sync error {}; pecks {} reference, {} recorded",
        rep.anchor,
        rep.offset_us,
        match f.fit_rms_mm {
            Some(rms) => format!("positions rms {} mm over {} values", fixed((rms * 1e6).round() as i64, 6), f.fit_values),
            None => "n/a: no position compared".into(),
        },
        f.recorded_events,
        f.recorded_samples,
        f.matched_events,
        f.reference_events,
        if f.sync_samples > 0 {
            format!("{} mm ({} samples)", fixed((f.max_sync_error_mm * 1e6).round() as i64, 6), f.sync_samples)
        } else {
            "n/a (not compared)".into()
        },
        f.pecks.0,
        f.pecks.1
    );
    for v in rep.rules.iter().filter(|v| v.pass) {
        let _ = writeln!(s, "  ok   {} {}", v.rule, v.what);
    }
    for n in &rep.not_comparable {
        let _ = writeln!(s, "  n/a  {}: not comparable: {}", not_comparable_what(n), n.reason);
    }
    if rep.conformant() {
        let _ = writeln!(s, "CONFORMANT: no divergence");
        return s;
    }
    let sorted = rep.sorted();
    let _ = writeln!(s, "DIVERGENT: {} divergence(s)", sorted.len() + rep.omitted);
    for d in &sorted {
        let _ = writeln!(
            s,
            "  FAIL {} {} {} at {}: expected {}; actual {}; margin {}",
            d.rule,
            d.check,
            d.what,
            at(d.t_us),
            d.expected,
            d.actual,
            d.margin
        );
    }
    if rep.omitted > 0 {
        let by: Vec<String> = rep.omitted_by_check.iter().map(|(k, n)| format!("{k}: {n}")).collect();
        let _ = writeln!(s, "  ... and {} more ({})", rep.omitted, by.join(", "));
    }
    if let Some(t) = sorted.first().and_then(|d| d.t_us) {
        let spec = excerpt_spec(reference, &rep.recorded, t);
        let _ = writeln!(s, "\nAround the first divergence ({}), reference:", at(Some(t)));
        s.push_str(&timing_diagram(reference, &spec));
        let _ = writeln!(s, "recorded (aligned):");
        s.push_str(&timing_diagram(&rep.recorded, &spec));
    }
    s
}

/// `M29, M30 (2 reference events)`, or the check alone when it counts no events.
fn not_comparable_what(n: &super::NotComparable) -> String {
    if n.count == 0 {
        n.what.clone()
    } else {
        format!("{} ({} reference event{})", n.what, n.count, if n.count == 1 { "" } else { "s" })
    }
}

/// The diagram window around `t`: the signals that change in either trace, the tap axis and the
/// spindle, 150 ms either side.
pub fn excerpt_spec(reference: &Trace, recorded: &Trace, t: i64) -> DiagramSpec {
    let from = (t - 150_000).max(0) as u64;
    let to = (t + 150_000).max(1) as u64;
    let changes = |tr: &Trace, s: Signal| tr.edges(s).any(|(te, _)| te >= from && te <= to);
    let signals: Vec<Signal> =
        Signal::ALL.iter().copied().filter(|&s| changes(reference, s) || changes(recorded, s)).collect();
    let tap = super::reference::Reference::new(reference).tap;
    let axes =
        reference.meta.axes.iter().filter(|a| tap.is_some_and(|tp| tp.slot == a.index)).copied().collect();
    DiagramSpec { signals, axes, spindle: true, width: 72, from_us: Some(from), to_us: Some(to) }
}

/// The report as JSON.
pub fn json(rep: &Report, reference_name: &str, recorded_name: &str) -> String {
    let v = serde_json::json!({
        "format": "nc-conform-check/1",
        "reference": reference_name,
        "recorded": recorded_name,
        "conformant": rep.conformant(),
        "report": rep,
    });
    serde_json::to_string_pretty(&v).unwrap_or_default() + "\n"
}

/// XML text escaping.
pub fn xml_escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&apos;"),
            c if (c as u32) < 0x20 && !matches!(c, '\n' | '\t' | '\r') => o.push(' '),
            c => o.push(c),
        }
    }
    o
}

/// The report as JUnit XML: one passing test case per family of checks without divergence, one
/// failing test case per divergence, one test case per scenario rule verdict.
pub fn junit(rep: &Report, suite: &str) -> String {
    let mut cases = String::new();
    let mut tests = 0;
    let mut failures = 0;
    for (prefix, name) in FAMILIES {
        let ds: Vec<_> = rep.sorted().into_iter().filter(|d| d.check.starts_with(prefix)).collect();
        if prefix == "CHK-RULE" {
            for v in &rep.rules {
                tests += 1;
                let _ = write!(
                    cases,
                    "    <testcase classname=\"{}\" name=\"{}\"",
                    xml_escape(&v.rule),
                    xml_escape(&format!("CHK-RULE-01 scenario {}", v.what))
                );
                if v.pass {
                    cases.push_str("/>\n");
                } else {
                    failures += 1;
                    let msg = format!(
                        "at {}: expected {}; actual {}",
                        at(v.t_us.map(|t| t as i64)),
                        v.expected,
                        v.actual
                    );
                    let _ = write!(
                        cases,
                        ">\n      <failure type=\"CHK-RULE-01\" message=\"{}\"/>\n    </testcase>\n",
                        xml_escape(&msg)
                    );
                }
            }
            continue;
        }
        if ds.is_empty() {
            tests += 1;
            let _ = writeln!(cases, "    <testcase classname=\"{prefix}\" name=\"{}\"/>", xml_escape(name));
        }
        for d in ds {
            tests += 1;
            failures += 1;
            let msg = format!(
                "{} at {}: expected {}; actual {}; margin {}",
                d.what,
                at(d.t_us),
                d.expected,
                d.actual,
                d.margin
            );
            let _ = write!(
                cases,
                "    <testcase classname=\"{}\" name=\"{}\">\n      <failure type=\"{}\" message=\"{}\"/>\n    </testcase>\n",
                xml_escape(&d.rule),
                xml_escape(&format!("{} {} at {}", d.check, d.what, at(d.t_us))),
                xml_escape(&d.check),
                xml_escape(&msg)
            );
        }
    }
    let skipped = rep.not_comparable.len();
    for n in &rep.not_comparable {
        tests += 1;
        let _ = write!(
            cases,
            "    <testcase classname=\"not-comparable\" name=\"{}\">\n      <skipped message=\"{}\"/>\n    </testcase>\n",
            xml_escape(&not_comparable_what(n)),
            xml_escape(&format!("not comparable: {}", n.reason))
        );
    }
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites name=\"nc-conform check\" tests=\"{tests}\" failures=\"{failures}\" skipped=\"{skipped}\" time=\"{time:.3}\">\n  <testsuite name=\"{}\" tests=\"{tests}\" failures=\"{failures}\" errors=\"0\" skipped=\"{skipped}\" time=\"{time:.3}\">\n{cases}  </testsuite>\n</testsuites>\n",
        xml_escape(suite),
        time = rep.seconds
    )
}
