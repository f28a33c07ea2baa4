//! `nc-conform calibrate`: the machine's own timing, estimated from a recording of a known-good
//! run, written as a parameter file whose comments say where each value came from and how sure it
//! is (`docs/checking.md`, "Calibration").
//!
//! The recording streams by once ([`Calibrator::event`]); memory does not follow its length
//! (each axis keeps the samples of the move under way and the summaries of at most 4096 moves
//! plus its 4096 fastest possible rapids, the spindle the samples of the start under way, the
//! PLC the edges waiting for their answer; every collection of values is a [`Bounded`], an even
//! subsample beyond its size). Estimated, when the recording shows them ([`axis`], [`spindle`],
//! [`plc`]; how moves are told apart: DEC-148):
//! - the rapid rate per axis: the velocity plateau of the fastest moves of the axis that reached
//!   one, a diameter axis as a radius;
//! - the rapid time constant per axis: the rapid rate (else the base one) over the acceleration
//!   fitted on the raw positions of those moves' accelerations and decelerations (√distance from
//!   rest is linear in time), the median;
//! - the cutting time constant: the maximum cutting feed over the acceleration of the moves of
//!   one axis alone that reach a plateau below the rapid rate, their ramps not following the
//!   spindle (cutting feeds, thread passes);
//! - the spindle time constant: the starts from rest in speed mode, their slope from 10 % to
//!   90 % of the speed they reach, scaled to the maximum spindle speed;
//! - the rigid tapping time constant: the same slope in the strokes (RGSPP/RGSPM), scaled to
//!   the rigid tapping maximum speed;
//! - `plc.fin_ms`, `plc.fin_fall_ms`, `plc.sppos_reach_ms`, `plc.rgtap_ms`, `plc.rgtap_fall_ms`:
//!   medians of the PLC's answers ([`plc::PAIRS`]); `nc.orient_ms`: M19 strobe → FIN;
//!   `plc.zsp_ms`: the spindle at rest → ZSP ↑.
//!
//! Only parameters of the dialect's table, under the dialect's own ids (`1620` on a Fanuc, not
//! `nc.rapid_ramp_ms`), within their ranges, are written.

pub mod axis;
pub mod plc;
pub mod spindle;

use std::fmt::Write as _;

use nc_engine::params::ParamKind;
use nc_engine::trace::{AxisSpec, Event, Signal, TraceEvent};
use nc_engine::Machine;

/// One estimated parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// Parameter id (the dialect's).
    pub id: &'static str,
    /// Axis, for a per-axis parameter.
    pub axis: Option<char>,
    /// Value in the parameter's unit.
    pub value: f64,
    /// Where it came from and how sure it is.
    pub note: String,
}

/// At most `cap` values kept: beyond, every other one is dropped and only one value in two
/// (then four, ...) is taken, an even subsample of any number of values.
#[derive(Debug, Clone)]
pub struct Bounded<T> {
    /// The values kept.
    pub values: Vec<T>,
    cap: usize,
    stride: u64,
    seen: u64,
}

impl<T> Default for Bounded<T> {
    fn default() -> Self {
        Bounded::new(4096)
    }
}

impl<T> Bounded<T> {
    /// Empty, keeping at most `cap`.
    pub fn new(cap: usize) -> Self {
        Bounded { values: Vec::new(), cap: cap.max(2), stride: 1, seen: 0 }
    }

    /// Offers one value.
    pub fn push(&mut self, x: T) {
        self.seen += 1;
        if !(self.seen - 1).is_multiple_of(self.stride) {
            return;
        }
        if self.values.len() == self.cap {
            let mut k = 0;
            self.values.retain(|_| {
                k += 1;
                k % 2 == 1
            });
            self.stride *= 2;
            if !(self.seen - 1).is_multiple_of(self.stride) {
                return;
            }
        }
        self.values.push(x);
    }

    /// Values offered in all.
    pub fn seen(&self) -> u64 {
        self.seen
    }
}

/// Median and half the spread of the middle half (None when empty).
fn median_spread(v: &[f64]) -> Option<(f64, f64)> {
    if v.is_empty() {
        return None;
    }
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    let q = |f: f64| v[((v.len() - 1) as f64 * f).round() as usize];
    Some((q(0.5), (q(0.75) - q(0.25)) / 2.0))
}

/// The dialect's id for a quantity: the first of `ids` its table has (the shared `nc.*` id, or
/// the vendor's number).
fn id_of(machine: &Machine, ids: &[&'static str]) -> Option<&'static str> {
    ids.iter().copied().find(|id| machine.params.def(id).is_some())
}

const RAPID: &[&str] = &["nc.rapid_mm_min", "1420"];
const RAPID_RAMP: &[&str] = &["nc.rapid_ramp_ms", "1620"];
const FEED_MAX: &[&str] = &["nc.feed_max_mm_min", "1430"];
const FEED_RAMP: &[&str] = &["nc.feed_ramp_ms", "1622"];
const SPINDLE_MAX: &[&str] = &["nc.spindle_max_rpm", "3716"];
const SPINDLE_RAMP: &[&str] = &["nc.spindle_ramp_ms"];
const RIGID_MAX: &[&str] = &["nc.rt_max_rpm", "5241"];
const RIGID_RAMP: &[&str] = &["nc.rt_ramp_ms", "5261"];

/// The estimator: feed it the recording's events in order, then [`Calibrator::finish`].
pub struct Calibrator<'m> {
    machine: &'m Machine,
    axes: Vec<axis::AxisTrack>,
    spindle: spindle::SpindleTrack,
    plc: plc::PlcTrack,
    rigid: [bool; 2],
    rigid_rose: bool,
    turning: bool,
    samples: u64,
}

impl<'m> Calibrator<'m> {
    /// A calibrator for `machine` (its dialect and base parameters) and the recording's axes.
    pub fn new(machine: &'m Machine, axes: &[AxisSpec]) -> Self {
        Calibrator {
            machine,
            axes: axes
                .iter()
                .filter(|a| !a.rotary)
                .map(|a| axis::AxisTrack::new(a.index, a.letter, a.diameter))
                .collect(),
            spindle: spindle::SpindleTrack::new(),
            plc: plc::PlcTrack::default(),
            rigid: [false; 2],
            rigid_rose: false,
            turning: false,
            samples: 0,
        }
    }

    /// One recorded event (time as recorded, in order).
    pub fn event(&mut self, e: &TraceEvent) {
        // Beyond about 73,000 years the differences of times could overflow: nothing to read.
        let Ok(t) = i64::try_from(e.t_us) else { return };
        if t > i64::MAX / 4 {
            return;
        }
        match &e.event {
            Event::Sample(s) => {
                self.samples += 1;
                let rigid = self.rigid[0] || self.rigid[1] || std::mem::take(&mut self.rigid_rose);
                for a in &mut self.axes {
                    a.sample(t, &s.axes, rigid, s.spindle_mrpm);
                }
                self.spindle.sample(t, s.spindle_mrpm);
                self.turning = s.spindle_mrpm.abs() > 500;
            }
            Event::Signal { signal, value } => {
                if let Some(k) = [Signal::Rgspp, Signal::Rgspm].iter().position(|x| x == signal) {
                    self.rigid[k] = *value;
                    self.rigid_rose |= *value;
                    self.spindle.stroke(t, *value, self.rigid[0] || self.rigid[1]);
                }
                if *signal == Signal::Zsp && *value {
                    self.spindle.zsp_rose(t);
                }
                self.plc.edge(t, *signal, *value, self.turning);
            }
            Event::Function { letter, code } => self.plc.function(t, *letter, *code),
            _ => {}
        }
    }

    /// The estimates, each under the dialect's id, within its range.
    pub fn finish(self) -> Vec<Estimate> {
        let m = self.machine;
        let mut out = Vec::new();
        let mut cuts = Cuts::default();
        for a in &self.axes {
            axis_estimates(m, a, &mut cuts, &mut out);
        }
        cut_estimate(m, &cuts, &mut out);
        spindle_estimates(m, &self.spindle, &mut out);
        for (k, (id, _, _, what)) in plc::PAIRS.iter().enumerate() {
            let d = &self.plc.delays[k];
            if let Some((med, _)) = median_spread(&d.values) {
                let spread = d.values.iter().map(|x| (x - med).abs()).fold(0.0, f64::max);
                out.push(Estimate {
                    id,
                    axis: None,
                    value: (med / 1000.0).round(),
                    note: format!(
                        "median of {} {what} in the recording, spread ± {:.1} ms",
                        d.seen(),
                        spread / 1000.0
                    ),
                });
            }
        }
        if let Some((med, spread)) = median_spread(&self.plc.orient.values) {
            out.push(Estimate {
                id: "nc.orient_ms",
                axis: None,
                value: (med / 1000.0).round(),
                note: format!(
                    "median of {} M19 strobe ↑ → FIN ↑, middle half ± {:.1} ms: the FIN of an M19 comes when the orientation time is over or the spindle is at rest, the later; this is the orientation time, or the time to rest (the same FIN)",
                    self.plc.orient.seen(),
                    spread / 1000.0
                ),
            });
        }
        if let Some((med, spread)) = median_spread(&self.spindle.zsp.values) {
            out.push(Estimate {
                id: "plc.zsp_ms",
                axis: None,
                value: (med / 1000.0).round(),
                note: format!(
                    "median of {} spindle at rest (its deceleration's end, between samples) → ZSP ↑, middle half ± {:.1} ms",
                    self.spindle.zsp.seen(),
                    spread / 1000.0
                ),
            });
        }
        // Only what the dialect has, within range, whole where the parameter is.
        out.retain_mut(|e| {
            if let Some(d) = m.params.def(e.id) {
                if matches!(d.kind, ParamKind::Int | ParamKind::Bit) {
                    e.value = e.value.round();
                }
            }
            let mut p = m.params.clone();
            p.set(e.id, e.axis, e.value).is_ok()
        });
        let _ = self.samples;
        out
    }
}

/// Rapid rate, rapid and cutting time constants of one axis.
fn axis_estimates(m: &Machine, a: &axis::AxisTrack, cuts: &mut Cuts, out: &mut Vec<Estimate>) {
    let moves: Vec<&axis::MoveSummary> = a.moves.values.iter().filter(|s| !s.rigid).collect();
    let Some(top) = a.fastest.iter().map(|s| s.peak).reduce(f64::max) else { return };
    let fast: Vec<_> = a.fastest.iter().filter(|s| s.peak >= 0.98 * top).collect();
    // The rate on the plateaus of those that reached one (a short rapid's triangle peaks below
    // the rate); without any, the base rate, and the time constant from it.
    let (mut travel, mut time, mut spans) = (0.0, 0.0, 0);
    for (d, t) in fast.iter().filter(|s| s.flat).filter_map(|s| s.plateau) {
        travel += d;
        time += t;
        spans += 1;
    }
    let radius = if a.diameter { ", as a radius" } else { "" };
    let Some(rapid_id) = id_of(m, RAPID) else { return };
    let base = m.params.get_axis(rapid_id, Some(a.letter));
    let rate = if spans > 0 && time > 0.0 {
        let rate = travel / time; // nm/s
        out.push(Estimate {
            id: rapid_id,
            axis: Some(a.letter),
            value: (rate / 1e6 * 60.0 * 10.0).round() / 10.0,
            note: format!(
                "travel over time on the velocity plateau of the {spans} fastest {} move(s) ({:.0} ms in all){radius}; sure only if the program has a rapid long enough to reach the rapid rate",
                a.letter,
                time * 1000.0
            ),
        });
        rate
    } else {
        base * 1e6 / 60.0
    };
    let of_rate = if spans > 0 {
        "rapid rate".to_string()
    } else {
        format!(
            "the base rapid rate {base} mm/min (no rapid of {} reached a plateau: not measured)",
            a.letter
        )
    };
    let ramps: Vec<f64> =
        fast.iter().flat_map(|s| s.accel.iter().flatten().map(|acc| rate / acc * 1000.0)).collect();
    if let (Some(id), Some((r, spread))) = (id_of(m, RAPID_RAMP), median_spread(&ramps)) {
        out.push(Estimate {
            id,
            axis: Some(a.letter),
            value: r.round(),
            note: format!(
                "{of_rate} / acceleration, the acceleration fitted on the positions (√distance from rest is linear in time) in {} acceleration(s) and deceleration(s) of the fastest moves: median, middle half ± {spread:.1} ms",
                ramps.len()
            ),
        });
    }
    // Cutting moves: one axis alone, a plateau (the commanded feed reached, not a short rapid's
    // triangle), well below the rapid rate, outside rigid strokes; their ramps that do not
    // follow the spindle.
    for s in moves.iter().filter(|s| s.single && s.flat && s.peak < 0.9 * top) {
        let mut any = false;
        for (acc, follows) in s.accel.iter().zip(s.follows) {
            if let (Some(acc), false) = (acc, follows) {
                cuts.accel.push(*acc);
                any = true;
            }
        }
        if any {
            cuts.peak = cuts.peak.max(s.peak);
            if !cuts.axes.contains(&a.letter) {
                cuts.axes.push(a.letter);
            }
        }
    }
}

/// The ramps of the cutting moves of every axis.
#[derive(Default)]
struct Cuts {
    accel: Vec<f64>,
    peak: f64,
    axes: Vec<char>,
}

/// The cutting time constant: the maximum cutting feed over the cutting moves' acceleration.
fn cut_estimate(m: &Machine, cuts: &Cuts, out: &mut Vec<Estimate>) {
    let (Some(id), Some(fmax)) = (id_of(m, FEED_RAMP), id_of(m, FEED_MAX)) else { return };
    let feed_max = m.params.get(fmax) * 1e6 / 60.0; // nm/s
    let taus: Vec<f64> = cuts.accel.iter().map(|acc| feed_max / acc * 1000.0).collect();
    let Some((tau, spread)) = median_spread(&taus) else { return };
    out.push(Estimate {
        id,
        axis: None,
        value: tau.round(),
        note: format!(
            "{fmax} ({} mm/min, not estimated) / the acceleration fitted on the positions in {} ramp(s) of cutting moves of one axis alone ({}; a plateau below the rapid rate, up to {:.0} mm/min; not following the spindle): median, middle half ± {spread:.1} ms; a slow feed hardly shows it",
            m.params.get(fmax),
            taus.len(),
            cuts.axes.iter().collect::<String>(),
            cuts.peak * 60.0 / 1e6
        ),
    });
}

/// The spindle's and the rigid tapping time constants.
fn spindle_estimates(m: &Machine, s: &spindle::SpindleTrack, out: &mut Vec<Estimate>) {
    for (ids, max_ids, starts, what) in [
        (SPINDLE_RAMP, SPINDLE_MAX, &s.starts, "start(s) from rest in speed mode"),
        (RIGID_RAMP, RIGID_MAX, &s.rigid, "rigid tapping stroke(s) from rest (RGSPP/RGSPM)"),
    ] {
        let (Some(id), Some(max_id)) = (id_of(m, ids), id_of(m, max_ids)) else { continue };
        let max = m.params.get(max_id);
        let slopes: Vec<f64> = starts.values.iter().map(|x| x.slope).collect();
        let Some((slope, spread)) = median_spread(&slopes) else { continue };
        let top = starts.values.iter().map(|x| x.top).fold(0.0, f64::max);
        out.push(Estimate {
            id,
            axis: None,
            value: (max / slope * 1000.0).round(),
            note: format!(
                "{} {what}: {slope:.1} rpm/s (median, middle half ± {spread:.1}) from 10 % to 90 % of the speed reached (up to {top:.0} rpm), scaled to {max_id} {max}",
                starts.seen()
            ),
        });
    }
}

/// Estimates the machine's parameters from a recording held in memory (events as recorded, any
/// clock): [`Calibrator`] over the slice.
pub fn estimate(machine: &Machine, axes: &[AxisSpec], recorded: &[TraceEvent]) -> Vec<Estimate> {
    let mut c = Calibrator::new(machine, axes);
    for e in recorded {
        c.event(e);
    }
    c.finish()
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
    // One key per parameter: a per-axis one lists its estimated axes and the base values of
    // the others under it.
    let base: Vec<(&'static str, Option<char>, f64)> = machine.params.overrides().collect();
    let mut ids: Vec<&'static str> = Vec::new();
    for id in base.iter().map(|b| b.0).chain(estimates.iter().map(|e| e.id)) {
        if !ids.contains(&id) {
            ids.push(id);
        }
    }
    // The base parameters that were not estimated first, then the estimates.
    ids.sort_by_key(|id| estimates.iter().any(|e| e.id == *id));
    for id in ids {
        let per_axis = machine.params.def(id).is_some_and(|d| d.per_axis);
        if !per_axis {
            match estimates.iter().find(|e| e.id == id) {
                Some(e) => writeln!(s, "  {id}: {}   # {}", e.value, e.note),
                None => {
                    let v = base.iter().find(|b| b.0 == id).map_or(0.0, |b| b.2);
                    writeln!(s, "  {id}: {v}   # from the base parameters, not estimated")
                }
            }
            .ok();
            continue;
        }
        let _ = writeln!(s, "  {id}:");
        let mut axes: Vec<char> = base
            .iter()
            .filter(|b| b.0 == id)
            .filter_map(|b| b.1)
            .chain(estimates.iter().filter(|e| e.id == id).filter_map(|e| e.axis))
            .collect();
        axes.sort_unstable();
        axes.dedup();
        for a in axes {
            match estimates.iter().find(|e| e.id == id && e.axis == Some(a)) {
                Some(e) => writeln!(s, "    {a}: {}   # {}", e.value, e.note),
                None => {
                    let v = machine.params.get_axis(id, Some(a));
                    writeln!(s, "    {a}: {v}   # from the base parameters, not estimated")
                }
            }
            .ok();
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::Bounded;

    /// Any number of values fits in the same memory, an even subsample of them all.
    #[test]
    fn bounded_keeps_an_even_subsample_within_its_size() {
        let mut b = Bounded::new(100);
        for k in 0..1_000_000u32 {
            b.push(k);
        }
        assert!(b.values.len() <= 100 && b.values.len() >= 50, "{}", b.values.len());
        assert_eq!(b.seen(), 1_000_000);
        let gaps: Vec<u32> = b.values.windows(2).map(|w| w[1] - w[0]).collect();
        assert!(gaps.iter().all(|&g| g == gaps[0]), "evenly spaced: {gaps:?}");
        assert!(*b.values.last().unwrap() as u64 + gaps[0] as u64 >= 1_000_000 - 1, "up to the end");
    }
}
