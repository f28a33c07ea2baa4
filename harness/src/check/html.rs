//! The HTML report: one self-contained page (inline SVG and CSS, no script, no network) that
//! plots the reference and recorded tap position, spindle speed and synchronisation error over
//! time, with every divergence marked and listed.

use std::fmt::Write as _;

use nc_engine::trace::Trace;

use super::reference::Reference;
use super::report::xml_escape;
use super::Report;
use crate::scenario::timeline::ms;

const W: f64 = 1200.0;
const H: f64 = 220.0;
const LEFT: f64 = 80.0;
const RIGHT: f64 = 60.0;
const TOP: f64 = 28.0;
const BOTTOM: f64 = 30.0;

struct Line<'a> {
    label: &'a str,
    color: &'a str,
    points: Vec<(i64, f64)>,
}

fn nice(v: f64) -> String {
    if v.abs() >= 100.0 {
        format!("{v:.0}")
    } else if v.abs() >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.4}")
    }
}

/// One plot as an SVG element.
fn plot(
    id: &str,
    title: &str,
    lines: &[Line],
    t0: i64,
    t1: i64,
    marks: &[(i64, String)],
    hlines: &[f64],
) -> String {
    let vals = lines.iter().flat_map(|l| l.points.iter().map(|p| p.1)).chain(hlines.iter().copied());
    let (mut lo, mut hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        (lo, hi) = (0.0, 1.0);
    }
    if hi - lo < 1e-9 {
        (lo, hi) = (lo - 1.0, hi + 1.0);
    }
    let pad = (hi - lo) * 0.05;
    let (lo, hi) = (lo - pad, hi + pad);
    let span = (t1 - t0).max(1) as f64;
    let x = |t: i64| LEFT + (t - t0) as f64 / span * (W - LEFT - RIGHT);
    let y = |v: f64| TOP + (hi - v) / (hi - lo) * (H - TOP - BOTTOM);
    let mut s = format!(
        "<svg id=\"{id}\" class=\"plot\" xmlns=\"http://www.w3.org/2000/svg\" width=\"{W}\" height=\"{H}\" viewBox=\"0 0 {W} {H}\">\n<text x=\"{LEFT}\" y=\"16\" class=\"title\">{}</text>\n",
        xml_escape(title)
    );
    let _ = writeln!(
        s,
        "<rect x=\"{LEFT}\" y=\"{TOP}\" width=\"{}\" height=\"{}\" class=\"frame\"/>",
        W - LEFT - RIGHT,
        H - TOP - BOTTOM
    );
    for k in 0..=4 {
        let v = lo + (hi - lo) * k as f64 / 4.0;
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{:.1}\" class=\"tick\" text-anchor=\"end\">{}</text>",
            LEFT - 6.0,
            y(v) + 4.0,
            nice(v)
        );
        let t = t0 + ((t1 - t0) as f64 * k as f64 / 4.0) as i64;
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{}\" class=\"tick\" text-anchor=\"middle\">{}</text>",
            x(t),
            H - 10.0,
            ms(t.max(0) as u64)
        );
    }
    for &v in hlines {
        let _ = writeln!(
            s,
            "<line x1=\"{LEFT}\" x2=\"{}\" y1=\"{:.1}\" y2=\"{:.1}\" class=\"limit\"/>",
            W - RIGHT,
            y(v),
            y(v)
        );
    }
    for (k, (t, label)) in marks.iter().enumerate() {
        let xm = x((*t).clamp(t0, t1));
        let _ = writeln!(
            s,
            "<g class=\"divergence\"><title>{}</title><line x1=\"{xm:.1}\" x2=\"{xm:.1}\" y1=\"{TOP}\" y2=\"{}\"/><text x=\"{:.1}\" y=\"{}\">{}</text></g>",
            xml_escape(label),
            H - BOTTOM,
            xm + 2.0,
            TOP + 10.0,
            k + 1
        );
    }
    for (k, l) in lines.iter().enumerate() {
        let mut d = String::new();
        let mut pen = false;
        for &(t, v) in &l.points {
            let _ = write!(d, "{}{:.1},{:.1} ", if pen { "L" } else { "M" }, x(t.clamp(t0, t1)), y(v));
            pen = true;
        }
        let _ = writeln!(
            s,
            "<path class=\"series\" data-series=\"{}\" d=\"{}\" stroke=\"{}\"/>\n<text x=\"{}\" y=\"16\" fill=\"{}\" class=\"legend\">{}</text>",
            xml_escape(l.label),
            d.trim_end(),
            l.color,
            W - RIGHT - 260.0 + 130.0 * k as f64,
            l.color,
            xml_escape(l.label)
        );
    }
    s.push_str("</svg>\n");
    s
}

/// The whole page.
pub fn page(rep: &Report, reference: &Trace, title: &str) -> String {
    let r = Reference::new(reference);
    let t0 = 0i64;
    let t1 = r.end_us.max(rep.series.last().map_or(0, |p| p.t)).max(1);
    let bucket = (t1 / 1500).max(1000);
    let mut ref_pts = Vec::new();
    let mut last: Option<i64> = None;
    for (t, s) in r.t.iter().zip(&r.s) {
        if last.is_none_or(|l| t.saturating_sub(l) >= bucket) {
            ref_pts.push((*t, *s));
            last = Some(*t);
        }
    }
    let tap = r.tap;
    let letter =
        tap.and_then(|tp| reference.meta.axes.iter().find(|a| a.index == tp.slot)).map_or('?', |a| a.letter);
    let marks: Vec<(i64, String)> = rep
        .sorted()
        .iter()
        .filter_map(|d| {
            d.t_us.map(|t| {
                (
                    t,
                    format!(
                        "{} {} {}: expected {}; actual {}",
                        d.rule, d.check, d.what, d.expected, d.actual
                    ),
                )
            })
        })
        .collect();
    let mut body = String::new();
    if let Some(tp) = tap {
        let refl = Line {
            label: "reference",
            color: "#1f6fd1",
            points: ref_pts.iter().map(|(t, s)| (*t, s.axes[tp.slot] as f64 / 1e6)).collect(),
        };
        let recl = Line {
            label: "recorded",
            color: "#e07000",
            points: rep.series.iter().filter_map(|p| p.tap.map(|v| (p.t, v as f64 / 1e6))).collect(),
        };
        body.push_str(&plot(
            "tap",
            &format!("tap position {letter} (mm)"),
            &[refl, recl],
            t0,
            t1,
            &marks,
            &[],
        ));
    }
    let refs = Line {
        label: "reference",
        color: "#1f6fd1",
        points: ref_pts.iter().map(|(t, s)| (*t, s.spindle_mrpm as f64 / 1000.0)).collect(),
    };
    let recs = Line {
        label: "recorded",
        color: "#e07000",
        points: rep.series.iter().map(|p| (p.t, p.rpm as f64 / 1000.0)).collect(),
    };
    body.push_str(&plot("spindle", "spindle speed (rpm)", &[refs, recs], t0, t1, &marks, &[]));
    let tol = rep.tolerances.sync_mm;
    let syncl = Line {
        label: "recorded",
        color: "#e07000",
        points: rep.series.iter().map(|p| (p.t, p.sync_nm.unwrap_or(0.0) / 1e6)).collect(),
    };
    body.push_str(&plot(
        "sync",
        "synchronisation error (mm): tap travel − lead × revolutions",
        &[syncl],
        t0,
        t1,
        &marks,
        &[-tol, tol],
    ));
    let verdict = if rep.conformant() { "CONFORMANT" } else { "DIVERGENT" };
    let mut rows = String::new();
    for (k, d) in rep.sorted().iter().enumerate() {
        let _ = writeln!(
            rows,
            "<tr class=\"divergence-row\"><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            k + 1,
            xml_escape(&d.rule),
            xml_escape(&d.check),
            d.t_us.map_or("-".into(), |t| ms(t.max(0) as u64)),
            xml_escape(&d.what),
            xml_escape(&d.expected),
            xml_escape(&d.actual),
            xml_escape(&d.margin)
        );
    }
    let f = &rep.figures;
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>nc-conform check: {t}</title>\n<style>\nbody{{font-family:sans-serif;margin:16px;color:#222}}\n.verdict{{font-weight:bold;font-size:20px}}\n.CONFORMANT{{color:#187a2f}}.DIVERGENT{{color:#c0161b}}\n.plot{{display:block;margin:8px 0;background:#fff}}\n.frame{{fill:#fafafa;stroke:#999}}\n.series{{fill:none;stroke-width:1.4}}\n.series[data-series=reference]{{stroke-width:4;stroke-opacity:0.45}}\n.limit{{stroke:#c0161b;stroke-dasharray:3 3}}\n.divergence line{{stroke:#c0161b;stroke-width:1;stroke-dasharray:4 2}}\n.divergence text{{fill:#c0161b;font-size:10px}}\n.title{{font-size:13px;font-weight:bold}}\n.tick,.legend{{font-size:11px}}\ntable{{border-collapse:collapse;font-size:12px}}td,th{{border:1px solid #ccc;padding:2px 6px;text-align:left}}\n</style>\n</head>\n<body>\n<h1>nc-conform check</h1>\n<p>{t}</p>\n<p class=\"verdict {verdict}\">{verdict}: {n} divergence(s)</p>\n<p>Aligned on the {anchor} (reference = recorded {off:+} µs). {ev} recorded events, {sm} samples; {mt}/{rt} reference events matched; max sync error {sync:.6} mm.</p>\n{body}<table id=\"divergences\">\n<tr><th>#</th><th>rule</th><th>check</th><th>time</th><th>what</th><th>expected</th><th>actual</th><th>margin</th></tr>\n{rows}</table>\n</body>\n</html>\n",
        t = xml_escape(&title.replace('\n', " · ")),
        n = rep.divergences.len() + rep.omitted,
        anchor = xml_escape(&rep.anchor),
        off = rep.offset_us,
        ev = f.recorded_events,
        sm = f.recorded_samples,
        mt = f.matched_events,
        rt = f.reference_events,
        sync = f.max_sync_error_mm,
    )
}
