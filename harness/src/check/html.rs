//! The HTML report: one self-contained page (inline SVG and CSS, no script, no network) that
//! plots the reference and recorded tap position, spindle speed and synchronisation error over
//! time, with every divergence marked and listed.

use std::fmt::Write as _;

use nc_engine::trace::{Event, Signal, Trace};

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

/// Round tick values (steps of 1, 2 or 5 × 10^k) covering [lo, hi], about `n` of them.
pub fn ticks(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) || !lo.is_finite() || !hi.is_finite() {
        return vec![lo];
    }
    let raw = (hi - lo) / n.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * mag).find(|st| *st >= raw).unwrap_or(10.0 * mag);
    let k0 = (lo / step).ceil() as i64;
    let k1 = (hi / step + 1e-9).floor() as i64;
    (k0..=k1.min(k0 + 4 * n as i64 + 2)).map(|k| if k == 0 { 0.0 } else { k as f64 * step }).collect()
}

/// A time tick in ms as text: `250 ms`, `1.5 s`.
fn time_label(ms_value: f64) -> String {
    if ms_value.abs() >= 1000.0 {
        let s = ms_value / 1000.0;
        let t = format!("{s:.3}");
        format!("{} s", t.trim_end_matches('0').trim_end_matches('.'))
    } else {
        format!("{} ms", format!("{ms_value:.3}").trim_end_matches('0').trim_end_matches('.'))
    }
}

/// Markers (time, text) in time order merged where they would overlap (closer than 14 px):
/// (first number, last number, x, the texts joined).
fn clusters(marks: &[(i64, String)], x: impl Fn(i64) -> f64) -> Vec<(usize, usize, f64, String)> {
    let mut out: Vec<(usize, usize, f64, String)> = Vec::new();
    for (k, (t, label)) in marks.iter().enumerate() {
        let xm = x(*t);
        match out.last_mut() {
            Some(c) if (xm - c.2).abs() < 14.0 => {
                c.1 = k;
                c.3.push_str(&format!("\n{}: {label}", k + 1));
            }
            _ => out.push((k, k, xm, format!("{}: {label}", k + 1))),
        }
    }
    out
}

/// The PLC signal lanes: one row per signal with an edge in either trace, the reference's level
/// (blue, above) and the recorded one (orange, below).
fn lanes(reference: &Trace, recorded: &Trace, t0: i64, t1: i64) -> String {
    let row = 18.0;
    let sigs: Vec<Signal> = Signal::ALL
        .iter()
        .copied()
        .filter(|&sg| reference.edges(sg).next().is_some() || recorded.edges(sg).next().is_some())
        .collect();
    if sigs.is_empty() {
        return String::new();
    }
    let h = TOP + row * sigs.len() as f64 + BOTTOM;
    let span = (t1 - t0).max(1) as f64;
    let x = |t: i64| LEFT + (t.clamp(t0, t1) - t0) as f64 / span * (W - LEFT - RIGHT);
    let mut s = format!(
        "<svg id=\"lanes\" class=\"plot\" xmlns=\"http://www.w3.org/2000/svg\" width=\"{W}\" height=\"{h}\" viewBox=\"0 0 {W} {h}\">\n<text x=\"{LEFT}\" y=\"16\" class=\"title\">PLC signals: reference (blue, upper) and recorded (orange, lower)</text>\n"
    );
    for (k, &sg) in sigs.iter().enumerate() {
        let top = TOP + row * k as f64;
        let _ = writeln!(
            s,
            "<g class=\"lane\" data-signal=\"{n}\"><rect x=\"{LEFT}\" y=\"{top}\" width=\"{}\" height=\"{row}\" class=\"frame\"/><text x=\"{}\" y=\"{:.1}\" class=\"tick\" text-anchor=\"end\">{n}</text>",
            W - LEFT - RIGHT,
            LEFT - 6.0,
            top + 13.0,
            n = sg.name()
        );
        for (trace, color, off) in [(reference, "#1f6fd1", 2.0), (recorded, "#e07000", 9.0)] {
            let (hi_y, lo_y) = (top + off, top + off + 6.0);
            let mut d = format!("M{:.1},{lo_y:.1}", x(t0));
            let mut level = false;
            for (t, v) in trace.edges(sg) {
                if v == level {
                    continue;
                }
                let xe = x(t as i64);
                let _ = write!(
                    d,
                    " L{xe:.1},{:.1} L{xe:.1},{:.1}",
                    if level { hi_y } else { lo_y },
                    if v { hi_y } else { lo_y }
                );
                level = v;
            }
            let _ = write!(d, " L{:.1},{:.1}", x(t1), if level { hi_y } else { lo_y });
            let _ = writeln!(s, "<path class=\"series\" d=\"{d}\" stroke=\"{color}\"/>");
        }
        s.push_str("</g>\n");
    }
    s.push_str("</svg>\n");
    s
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
    for v in ticks(lo, hi, 5) {
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{:.1}\" class=\"tick\" text-anchor=\"end\">{}</text>",
            LEFT - 6.0,
            y(v) + 4.0,
            nice(v)
        );
    }
    for v in ticks(t0 as f64 / 1000.0, t1 as f64 / 1000.0, 8) {
        let t = (v * 1000.0).round() as i64;
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{}\" class=\"tick\" text-anchor=\"middle\">{}</text>",
            x(t),
            H - 10.0,
            time_label(v)
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
    for (first, last, xm, label) in clusters(marks, |t| x(t.clamp(t0, t1))) {
        let number =
            if first == last { format!("{}", first + 1) } else { format!("{}–{}", first + 1, last + 1) };
        let _ = writeln!(
            s,
            "<g class=\"divergence\"><title>{}</title><line x1=\"{xm:.1}\" x2=\"{xm:.1}\" y1=\"{TOP}\" y2=\"{}\"/><text x=\"{:.1}\" y=\"{}\">{}</text></g>",
            xml_escape(&label),
            H - BOTTOM,
            xm + 2.0,
            TOP + 10.0,
            number
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
    let samples: Vec<(i64, nc_engine::trace::Sample)> =
        reference.samples().map(|(t, s)| (t as i64, *s)).collect();
    for (t, s) in &samples {
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
        "synchronisation error (mm): position − the reference's at the recorded spindle angle",
        &[syncl],
        t0,
        t1,
        &marks,
        &[-tol, tol],
    ));
    body.push_str(&lanes(reference, &rep.recorded, t0, t1));
    // A zoomed view ± 150 ms around each divergence (merged where they overlap), the first 8.
    let mut zooms: Vec<(i64, i64)> = Vec::new();
    for (t, _) in &marks {
        match zooms.last_mut() {
            Some(z) if *t - 150_000 <= z.1 => z.1 = *t + 150_000,
            _ => zooms.push((*t - 150_000, *t + 150_000)),
        }
    }
    let rec_samples: Vec<(i64, nc_engine::trace::Sample)> = rep
        .recorded
        .events
        .iter()
        .filter_map(|e| match &e.event {
            Event::Sample(x) => Some((e.t_us as i64, *x)),
            _ => None,
        })
        .collect();
    for (k, &(z0, z1)) in zooms.iter().take(8).enumerate() {
        let within = |t: i64| t >= z0 && t <= z1;
        let refw: Vec<_> = samples.iter().filter(|(t, _)| within(*t)).map(|(t, s)| (t, s)).collect();
        let recw: Vec<_> = rec_samples.iter().filter(|(t, _)| within(*t)).collect();
        let zmarks: Vec<(i64, String)> = marks.iter().filter(|m| within(m.0)).cloned().collect();
        let slot = tap.map(|tp| tp.slot).or_else(|| r.furthest_axis(z0, z1));
        if let Some(slot) = slot {
            let l = reference.meta.axes.iter().find(|a| a.index == slot).map_or('?', |a| a.letter);
            let lines = [
                Line {
                    label: "reference",
                    color: "#1f6fd1",
                    points: refw.iter().map(|(t, x)| (**t, x.axes[slot] as f64 / 1e6)).collect(),
                },
                Line {
                    label: "recorded",
                    color: "#e07000",
                    points: recw.iter().map(|(t, x)| (*t, x.axes[slot] as f64 / 1e6)).collect(),
                },
            ];
            body.push_str(&plot(
                &format!("zoom-{}", k + 1),
                &format!("zoom {}: {l} (mm), {} .. {}", k + 1, ms(z0.max(0) as u64), ms(z1.max(0) as u64)),
                &lines,
                z0,
                z1,
                &zmarks,
                &[],
            ));
        }
        let lines = [
            Line {
                label: "reference",
                color: "#1f6fd1",
                points: refw.iter().map(|(t, x)| (**t, x.spindle_mrpm as f64 / 1000.0)).collect(),
            },
            Line {
                label: "recorded",
                color: "#e07000",
                points: recw.iter().map(|(t, x)| (*t, x.spindle_mrpm as f64 / 1000.0)).collect(),
            },
        ];
        body.push_str(&plot(
            &format!("zoom-{}-spindle", k + 1),
            &format!("zoom {}: spindle speed (rpm)", k + 1),
            &lines,
            z0,
            z1,
            &zmarks,
            &[],
        ));
    }
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
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>nc-conform check: {t}</title>\n<style>\nbody{{font-family:sans-serif;margin:16px;color:#222}}\n.verdict{{font-weight:bold;font-size:20px}}\n.CONFORMANT{{color:#187a2f}}.DIVERGENT{{color:#c0161b}}\n.plot{{display:block;margin:8px 0;background:#fff}}\n.frame{{fill:#fafafa;stroke:#999}}\n.series{{fill:none;stroke-width:1.4}}\n.series[data-series=reference]{{stroke-width:4;stroke-opacity:0.45}}\n.limit{{stroke:#c0161b;stroke-dasharray:3 3}}\n.divergence line{{stroke:#c0161b;stroke-width:1;stroke-dasharray:4 2}}\n.divergence text{{fill:#c0161b;font-size:10px}}\n.title{{font-size:13px;font-weight:bold}}\n.tick,.legend{{font-size:11px}}\ntable{{border-collapse:collapse;font-size:12px}}td,th{{border:1px solid #ccc;padding:2px 6px;text-align:left}}\n</style>\n</head>\n<body>\n<h1>nc-conform check</h1>\n<p>{t}</p>\n<p class=\"verdict {verdict}\">{verdict}: {n} divergence(s)</p>\n<p>Aligned on the {anchor} (reference = recorded {off:+} µs). {ev} recorded events, {sm} samples; {mt}/{rt} reference events matched; max sync error {sync}.</p>\n{body}<table id=\"divergences\">\n<tr><th>#</th><th>rule</th><th>check</th><th>time</th><th>what</th><th>expected</th><th>actual</th><th>margin</th></tr>\n{rows}</table>\n</body>\n</html>\n",
        t = xml_escape(&title.replace('\n', " · ")),
        n = rep.divergences.len() + rep.omitted,
        anchor = xml_escape(&rep.anchor),
        off = rep.offset_us,
        ev = f.recorded_events,
        sm = f.recorded_samples,
        mt = f.matched_events,
        rt = f.reference_events,
        sync = if f.sync_samples > 0 { format!("{:.6} mm", f.max_sync_error_mm) } else { "n/a (not compared)".into() },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_markers_never_overlap() {
        assert_eq!(ticks(0.0, 10.0, 5), vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        assert_eq!(ticks(-0.013, 0.031, 8), vec![-0.01, 0.0, 0.01, 0.02, 0.03]);
        assert_eq!(ticks(-0.013, 0.031, 4), vec![0.0, 0.02]);
        assert_eq!(ticks(0.0, 1234.0, 8), (0..=6).map(|k| k as f64 * 200.0).collect::<Vec<_>>());
        assert_eq!(time_label(1500.0), "1.5 s");
        assert_eq!(time_label(250.0), "250 ms");
        let marks: Vec<(i64, String)> = [0, 1, 2, 500, 1000].iter().map(|&t| (t, format!("d{t}"))).collect();
        let c = clusters(&marks, |t| t as f64);
        assert_eq!(c.iter().map(|c| (c.0, c.1)).collect::<Vec<_>>(), vec![(0, 2), (3, 3), (4, 4)]);
        assert!(c[0].3.contains("d0") && c[0].3.contains("d2"));
        for w in c.windows(2) {
            assert!(w[1].2 - w[0].2 >= 14.0);
        }
    }
}
