//! `nc-conform calibrate`: the machine's own timing, estimated from a recording of a known-good
//! run, written as a parameter file whose comments say where each value came from and how sure it
//! is (`docs/checking.md`, "Calibration").
//!
//! Estimated, when the recording shows them:
//! - `nc.rapid_mm_min` per axis: the velocity plateau of the fastest moves of the axis (the mean
//!   over the part of each move at ≥ 98 % of its peak), a diameter axis as a radius;
//! - `nc.rapid_ramp_ms` per axis: the rapid rate over the acceleration fitted on the raw
//!   positions of those moves' accelerations and decelerations (√distance from rest is linear in
//!   time), the median;
//! - `nc.spindle_ramp_ms`: the spindle's first start from rest (outside rigid strokes), its
//!   slope from 10 % to 90 % of the speed it reaches, scaled to `nc.spindle_max_rpm`;
//! - `plc.fin_ms`, `plc.fin_fall_ms`: the median of strobe ↑ → FIN ↑ and strobe ↓ → FIN ↓;
//!   `plc.sppos_reach_ms` (SPPOS ↑ → SPPOSA ↑, only where the spindle was at rest at SPPOS), `plc.rgtap_ms` (SPPOSA ↑ → RGTAP ↑),
//!   `plc.rgtap_fall_ms` (F76.3 ↓ → RGTAP ↓).
//!
//! Only parameters of the dialect's table, within their ranges, are written.

use std::fmt::Write as _;

use nc_engine::trace::{AxisSpec, Event, Sample, Signal, TraceEvent};
use nc_engine::Machine;

/// One estimated parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// Parameter id.
    pub id: &'static str,
    /// Axis, for a per-axis parameter.
    pub axis: Option<char>,
    /// Value in the parameter's unit.
    pub value: f64,
    /// Where it came from and how sure it is.
    pub note: String,
}

/// Smoothed velocity of one axis: (time at the window's middle, nm/s).
fn velocities(samples: &[(i64, Sample)], value: impl Fn(&Sample) -> f64, window_us: i64) -> Vec<(i64, f64)> {
    let mut out = Vec::with_capacity(samples.len());
    let mut j = 0;
    for i in 0..samples.len() {
        while j < samples.len() && samples[j].0 - samples[i].0 < window_us {
            j += 1;
        }
        if j >= samples.len() {
            break;
        }
        let (t0, t1) = (samples[i].0, samples[j].0);
        let v = (value(&samples[j].1) - value(&samples[i].1)) / ((t1 - t0) as f64 / 1e6);
        out.push(((t0 + t1) / 2, v));
    }
    out
}

/// The moves of one axis in a velocity series: (first index, last index, peak |v|), where
/// |v| stays above `floor`.
fn moves(v: &[(i64, f64)], floor: f64) -> Vec<(usize, usize, f64)> {
    let mut out = Vec::new();
    let mut start: Option<usize> = None;
    for (k, &(_, x)) in v.iter().enumerate() {
        let moving = x.abs() > floor;
        match (moving, start) {
            (true, None) => start = Some(k),
            (false, Some(s)) => {
                let peak = v[s..k].iter().map(|p| p.1.abs()).fold(0.0, f64::max);
                out.push((s, k - 1, peak));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        let peak = v[s..].iter().map(|p| p.1.abs()).fold(0.0, f64::max);
        out.push((s, v.len() - 1, peak));
    }
    out
}

/// The time |v| first crosses `level` going from `from` towards `to` (interpolated).
fn crossing(
    v: &[(i64, f64)],
    range: std::ops::RangeInclusive<usize>,
    level: f64,
    rising: bool,
) -> Option<f64> {
    let idx: Vec<usize> = if rising { range.collect() } else { range.rev().collect() };
    for w in idx.windows(2) {
        let (a, b) = (v[w[0]], v[w[1]]);
        let (xa, xb) = (a.1.abs(), b.1.abs());
        if xa < level && xb >= level {
            let f = (level - xa) / (xb - xa);
            return Some(a.0 as f64 + f * (b.0 - a.0) as f64);
        }
    }
    None
}

fn median(mut v: Vec<i64>) -> Option<i64> {
    v.sort_unstable();
    v.get(v.len() / 2).copied()
}

/// Estimates the machine's parameters from a recording (events as recorded, any clock).
pub fn estimate(machine: &Machine, axes: &[AxisSpec], recorded: &[TraceEvent]) -> Vec<Estimate> {
    let samples: Vec<(i64, Sample)> = recorded
        .iter()
        .filter_map(|e| match &e.event {
            Event::Sample(s) => Some((e.t_us as i64, *s)),
            _ => None,
        })
        .collect();
    let mut out = Vec::new();
    // Axis rapid rates and time constants.
    for a in axes.iter().filter(|a| !a.rotary) {
        let div = if a.diameter { 2.0 } else { 1.0 };
        let v = velocities(&samples, |s| s.axes[a.index] as f64 / div, 8_000);
        let ms = moves(&v, 2e5); // 0.2 mm/s
        let Some(top) = ms.iter().map(|m| m.2).reduce(f64::max) else { continue };
        let fast: Vec<_> = ms.iter().filter(|m| m.2 >= 0.98 * top).collect();
        // The plateau of each fast move: from the first to the last window at >= 95 % of its
        // peak, its travel over its time on the raw samples (a long span: jitter and noise of
        // single samples do not bias it).
        let (mut travel, mut time, mut spans) = (0.0, 0.0, 0);
        for m in &fast {
            let on: Vec<usize> = (m.0..=m.1).filter(|&k| v[k].1.abs() >= 0.95 * m.2).collect();
            let (Some(&k0), Some(&k1)) = (on.first(), on.last()) else { continue };
            let (t0, t1) = (v[k0].0, v[k1].0);
            let i0 = samples.partition_point(|s| s.0 < t0);
            let i1 = samples.partition_point(|s| s.0 <= t1).saturating_sub(1);
            if i1 <= i0 {
                continue;
            }
            let (a0, a1) = (&samples[i0], &samples[i1]);
            travel += ((a1.1.axes[a.index] - a0.1.axes[a.index]) as f64 / div).abs();
            time += (a1.0 - a0.0) as f64 / 1e6;
            spans += 1;
        }
        if spans == 0 || time <= 0.0 {
            continue;
        }
        let rate = travel / time; // nm/s
        let plateau_ms = time * 1000.0;
        let mut ramps = Vec::new();
        for m in &fast {
            // A first guess from the 10 %-90 % time of the smoothed velocity (biased by the
            // velocity's noise), then the acceleration fitted on the raw positions: in a ramp
            // from rest the axis has gone a·t²/2, so √(distance from rest) is a line in time of
            // slope √(a/2), whatever the sample times and their jitter; τ = rate / a.
            let (lo, hi) = (0.1 * rate, 0.9 * rate);
            let guess = match (crossing(&v, m.0..=m.1, lo, true), crossing(&v, m.0..=m.1, hi, true)) {
                (Some(a1), Some(a2)) if a2 > a1 => (a2 - a1) / 0.8,
                _ => continue,
            };
            let (t0, t1) = (v[m.0].0 - 8_000, v[m.1].0 + 8_000);
            let i0 = samples.partition_point(|s| s.0 < t0);
            let i1 = samples.partition_point(|s| s.0 <= t1);
            let (Some(first), Some(last)) = (samples.get(i0), samples.get(i1.saturating_sub(1))) else {
                continue;
            };
            let pos = |s: &Sample| s.axes[a.index] as f64 / div;
            let reach = 0.5 * rate * guess / 1e6 * 0.6; // nm within the ramp
            for rest in [pos(&first.1), pos(&last.1)] {
                let pts: Vec<(f64, f64)> = samples[i0..i1]
                    .iter()
                    .map(|s| (s.0 as f64 / 1e6, (pos(&s.1) - rest).abs()))
                    .filter(|&(_, d)| d >= 50_000.0 && d <= reach)
                    .map(|(t, d)| (t, d.sqrt()))
                    .collect();
                if pts.len() < 4 {
                    continue;
                }
                let n = pts.len() as f64;
                let (mt, my) =
                    (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
                let sxy: f64 = pts.iter().map(|p| (p.0 - mt) * (p.1 - my)).sum();
                let sxx: f64 = pts.iter().map(|p| (p.0 - mt) * (p.0 - mt)).sum();
                if sxx <= 0.0 {
                    continue;
                }
                let k = (sxy / sxx).abs();
                let accel = 2.0 * k * k; // nm/s²
                if accel > 0.0 {
                    ramps.push(rate / accel * 1e6);
                }
            }
        }
        let mm_min = rate / 1e6 * 60.0;
        out.push(Estimate {
            id: "nc.rapid_mm_min",
            axis: Some(a.letter),
            value: (mm_min * 10.0).round() / 10.0,
            note: format!(
                "travel over time on the velocity plateau of the {} fastest {} move(s) ({:.0} ms in all){}; sure only if the program has a rapid long enough to reach the rapid rate",
                spans,
                a.letter,
                plateau_ms,
                if a.diameter { ", as a radius" } else { "" }
            ),
        });
        if !ramps.is_empty() {
            // The median (a move that blends into the next, or pauses above the floor, gives an
            // outlier), and the spread of the middle half.
            ramps.sort_by(f64::total_cmp);
            let q = |f: f64| ramps[((ramps.len() - 1) as f64 * f).round() as usize] / 1000.0;
            let r = q(0.5);
            let spread = (q(0.75) - q(0.25)) / 2.0;
            out.push(Estimate {
                id: "nc.rapid_ramp_ms",
                axis: Some(a.letter),
                value: r.round(),
                note: format!(
                    "rapid rate / acceleration, the acceleration fitted on the positions (√distance from rest is linear in time) in {} acceleration(s) and deceleration(s): median, middle half ± {:.1} ms",
                    ramps.len(),
                    spread
                ),
            });
        }
    }
    // The spindle's first start from rest, outside rigid strokes.
    let stroke_from = recorded
        .iter()
        .find(|e| matches!(e.event, Event::Signal { signal: Signal::Rgspp | Signal::Rgspm, value: true }))
        .map_or(i64::MAX, |e| e.t_us as i64);
    let rpm: Vec<(i64, Sample)> = samples.iter().filter(|s| s.0 < stroke_from).cloned().collect();
    if let Some(k0) = rpm.iter().position(|s| s.1.spindle_mrpm.abs() > 1000) {
        let mut k1 = k0;
        while k1 + 1 < rpm.len() && rpm[k1 + 1].1.spindle_mrpm.abs() > rpm[k1].1.spindle_mrpm.abs() {
            k1 += 1;
        }
        let top = rpm[k1].1.spindle_mrpm.abs() as f64;
        let at = |level: f64| {
            rpm[k0.saturating_sub(1)..=k1].windows(2).find_map(|w| {
                let (a, b) = (w[0].1.spindle_mrpm.abs() as f64, w[1].1.spindle_mrpm.abs() as f64);
                (a < level && b >= level)
                    .then(|| w[0].0 as f64 + (level - a) / (b - a) * (w[1].0 - w[0].0) as f64)
            })
        };
        if let (Some(t1), Some(t2)) = (at(0.1 * top), at(0.9 * top)) {
            if t2 > t1 {
                let slope = 0.8 * top / 1000.0 / ((t2 - t1) / 1e6); // rpm/s
                let max = machine.params.get("nc.spindle_max_rpm");
                out.push(Estimate {
                    id: "nc.spindle_ramp_ms",
                    axis: None,
                    value: (max / slope * 1000.0).round(),
                    note: format!(
                        "the first spindle start from rest: {:.1} rpm/s from 10 % to 90 % of {:.0} rpm, scaled to nc.spindle_max_rpm {max}",
                        slope,
                        top / 1000.0
                    ),
                });
            }
        }
    }
    // PLC answer delays.
    let edges: Vec<(i64, Signal, bool)> = recorded
        .iter()
        .filter_map(|e| match e.event {
            Event::Signal { signal, value } => Some((e.t_us as i64, signal, value)),
            _ => None,
        })
        .collect();
    // The spindle turning at `t` (the last sample at or before it): the drive reports position
    // mode only once the spindle has come down at its ramp (seed 000's timing chart; issue 12),
    // so an SPPOS raised with the spindle still turning measures the ramp, not the drive.
    let turning_at = |t: i64| {
        let k = samples.partition_point(|(ts, _)| *ts <= t);
        k > 0 && samples[k - 1].1.spindle_mrpm.abs() > 500
    };
    let delays = |from: &[(Signal, bool)], to: (Signal, bool)| -> Vec<i64> {
        let mut d = Vec::new();
        for (k, &(t, s, v)) in edges.iter().enumerate() {
            if s == Signal::Sppos && turning_at(t) {
                continue;
            }
            if from.contains(&(s, v)) {
                if let Some(&(tt, _, _)) = edges[k + 1..].iter().find(|e| (e.1, e.2) == to) {
                    d.push(tt - t);
                }
            }
        }
        d
    };
    let strobes_up = [(Signal::Mf, true), (Signal::Sf, true), (Signal::Tf, true)];
    let strobes_down = [(Signal::Mf, false), (Signal::Sf, false), (Signal::Tf, false)];
    for (id, from, to, what) in [
        ("plc.fin_ms", &strobes_up[..], (Signal::Fin, true), "strobe ↑ → FIN ↑"),
        ("plc.fin_fall_ms", &strobes_down[..], (Signal::Fin, false), "strobe ↓ → FIN ↓"),
        ("plc.sppos_reach_ms", &[(Signal::Sppos, true)][..], (Signal::Spposa, true), "SPPOS ↑ → SPPOSA ↑"),
        ("plc.rgtap_ms", &[(Signal::Spposa, true)][..], (Signal::Rgtap, true), "SPPOSA ↑ → RGTAP ↑"),
        ("plc.rgtap_fall_ms", &[(Signal::Rtap, false)][..], (Signal::Rgtap, false), "F76.3 ↓ → RGTAP ↓"),
    ] {
        let d = delays(from, to);
        if let Some(m) = median(d.clone()) {
            let spread = d.iter().map(|x| (x - m).abs()).max().unwrap_or(0);
            out.push(Estimate {
                id,
                axis: None,
                value: (m as f64 / 1000.0).round(),
                note: format!(
                    "median of {} {what} in the recording, spread ± {:.1} ms",
                    d.len(),
                    spread as f64 / 1000.0
                ),
            });
        }
    }
    // Only what the dialect has, within range.
    out.retain(|e| {
        let mut p = machine.params.clone();
        p.set(e.id, e.axis, e.value).is_ok()
    });
    out
}

/// The parameter file: the base parameters' overrides, then every estimate with its note.
pub fn params_file(machine: &Machine, estimates: &[Estimate], source: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# nc-conform calibrate: the {} machine's timing, estimated from {source}",
        machine.dialect.name()
    );
    let _ =
        writeln!(s, "# (a recording of a known-good run). Check the other machines with --params this file.");
    let _ = writeln!(s, "params:");
    let mut done: Vec<&str> = Vec::new();
    for (id, axis, value) in machine.params.overrides() {
        if estimates.iter().any(|e| e.id == id) {
            continue;
        }
        let key = match axis {
            Some(a) => format!("  {id}: {{{a}: {value}}}"),
            None => format!("  {id}: {value}"),
        };
        let _ = writeln!(s, "{key}   # from the base parameters, not estimated");
    }
    for e in estimates {
        if e.axis.is_some() {
            if done.contains(&e.id) {
                continue;
            }
            done.push(e.id);
            let _ = writeln!(s, "  {}:", e.id);
            for x in estimates.iter().filter(|x| x.id == e.id) {
                let _ = writeln!(s, "    {}: {}   # {}", x.axis.unwrap_or('?'), x.value, x.note);
            }
        } else {
            let _ = writeln!(s, "  {}: {}   # {}", e.id, e.value, e.note);
        }
    }
    s
}
