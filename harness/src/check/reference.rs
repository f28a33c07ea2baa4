//! The reference side of a comparison, kept in memory: its samples for interpolation and
//! envelopes, the tap axis and lead for the synchronisation error, its discrete events, phases
//! and inputs for attribution.

use nc_engine::trace::{AxisSpec, Event, Phase, Sample, Signal, Signals, Trace, AXES};

use super::keypoints::{KeyPoints, KeyTracker};

/// The tapping axis and its lead, learned from the reference's strokes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tap {
    /// Slot of the tap axis.
    pub slot: usize,
    /// Reported as a diameter (compared as a radius).
    pub diameter: bool,
    /// Physical travel (nm) per signed spindle revolution.
    pub lead_nm: f64,
    /// The stroke signal of the first cut (RGSPP for a right-hand tap).
    pub in_signal: Signal,
    /// +1 when the tap goes into the hole towards +, −1 towards −.
    pub into_sign: i64,
}

/// The reference trace, indexed.
#[derive(Debug)]
pub struct Reference<'a> {
    /// The trace itself.
    pub trace: &'a Trace,
    /// Sample times.
    pub t: Vec<i64>,
    /// Samples, same order.
    pub s: Vec<Sample>,
    /// The tap, if the reference taps with the spindle turning.
    pub tap: Option<Tap>,
    /// Key points of the reference.
    pub keys: KeyPoints,
    /// Time of the end event.
    pub end_us: i64,
    /// Phases by time.
    pub phases: Vec<(i64, Phase)>,
    /// Inputs by time (name, value).
    pub inputs: Vec<(i64, String, String)>,
    /// The cumulative unwrapped spindle angle at each sample, milli-degrees.
    pub cum_mdeg: Vec<f64>,
    /// The synchronised moves (rigid strokes, thread passes, encoder-following moves).
    pub sync: Vec<super::sync::Window>,
    /// The sample index of the last lookup: recorded times mostly grow, so the next lookup
    /// starts there.
    hint: std::cell::Cell<usize>,
}

/// The change of a spindle angle from `a0` to `a1` (milli-degrees) over `dt_us`, unwrapped using
/// the speeds at both ends to predict it.
pub fn unwrap_delta(a0: i64, m0: i64, a1: i64, m1: i64, dt_us: i64) -> f64 {
    let expected = (m0 + m1) as f64 / 2.0 * 6.0 * dt_us as f64 / 1e6;
    let raw = (a1 - a0) as f64;
    let diff = (raw - expected).rem_euclid(360_000.0);
    let diff = if diff > 180_000.0 { diff - 360_000.0 } else { diff };
    expected + diff
}

/// What a [`MotionDetector`] watches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Watch {
    /// An axis' position (slot).
    Axis(usize),
    /// The spindle's speed (its magnitude).
    Spindle,
}

/// Finds the first motion of one axis (or the first start of the spindle) in a stream of
/// samples: the time it first strays more than a threshold from where it stood at the first
/// sample, interpolated between the two samples around the crossing.
#[derive(Debug, Clone, Copy)]
pub struct MotionDetector {
    watch: Watch,
    threshold_nm: i64,
    start: Option<i64>,
    prev: Option<(i64, i64)>,
}

impl MotionDetector {
    /// A detector for axis `slot` (threshold at least 1 nm).
    pub fn new(slot: usize, threshold_nm: i64) -> MotionDetector {
        MotionDetector::watching(Watch::Axis(slot), threshold_nm)
    }

    /// A detector for `watch` (threshold at least 1 unit: nm, milli-rpm).
    pub fn watching(watch: Watch, threshold: i64) -> MotionDetector {
        MotionDetector { watch, threshold_nm: threshold.max(1), start: None, prev: None }
    }

    /// One sample at `t`; the time of the crossing once it is found (then every later call
    /// finds it again from the new sample: call it until the first `Some`).
    pub fn sample(&mut self, t: i64, s: &Sample) -> Option<i64> {
        let p = match self.watch {
            Watch::Axis(slot) => s.axes[slot],
            Watch::Spindle => s.spindle_mrpm.abs(),
        };
        let p0 = *self.start.get_or_insert(p);
        let prev = self.prev.replace((t, p));
        let dev = p - p0;
        if dev.abs() <= self.threshold_nm {
            return None;
        }
        let (tp, pp) = prev?;
        let target = p0 + self.threshold_nm * dev.signum();
        let f = (target - pp) as f64 / (p - pp) as f64;
        Some(tp + (f.clamp(0.0, 1.0) * (t - tp) as f64).round() as i64)
    }
}

impl<'a> Reference<'a> {
    /// The first motion of axis `slot` (see [`MotionDetector`]).
    pub fn first_motion(&self, slot: usize, threshold_nm: i64) -> Option<i64> {
        self.first_change(Watch::Axis(slot), threshold_nm)
    }

    /// The first change of what `watch` watches beyond `threshold` (see [`MotionDetector`]).
    pub fn first_change(&self, watch: Watch, threshold: i64) -> Option<i64> {
        let mut d = MotionDetector::watching(watch, threshold);
        self.t.iter().zip(&self.s).find_map(|(&t, s)| d.sample(t, s))
    }

    /// The axis (among those `carried` accepts) that moves first in the reference.
    pub fn first_moving_axis(&self, threshold_nm: i64, carried: impl Fn(usize) -> bool) -> Option<usize> {
        self.axes()
            .iter()
            .filter(|a| carried(a.index))
            .filter_map(|a| self.first_motion(a.index, threshold_nm).map(|t| (t, a.index)))
            .min()
            .map(|x| x.1)
    }

    /// Indexes `trace`.
    pub fn new(trace: &'a Trace) -> Reference<'a> {
        let mut t = Vec::new();
        let mut s = Vec::new();
        let mut phases = Vec::new();
        let mut inputs = Vec::new();
        for e in &trace.events {
            match &e.event {
                Event::Sample(x) => {
                    t.push(e.t_us as i64);
                    s.push(*x);
                }
                Event::Phase(p) => phases.push((e.t_us as i64, *p)),
                Event::Input { name, value } => inputs.push((e.t_us as i64, name.clone(), value.clone())),
                _ => {}
            }
        }
        let end_us = trace.events.last().map_or(0, |e| e.t_us as i64);
        let tap = find_tap(trace);
        let mut kt = KeyTracker::new(tap);
        for e in &trace.events {
            kt.event(e.t_us as i64, &e.event);
        }
        let cum_mdeg = super::sync::cumulative_angle(&t, &s);
        let mut r = Reference {
            trace,
            t,
            s,
            tap,
            keys: kt.finish(),
            end_us,
            phases,
            inputs,
            cum_mdeg,
            sync: Vec::new(),
            hint: std::cell::Cell::new(0),
        };
        r.sync = super::sync::windows(&r);
        r
    }

    /// The axis that travels furthest over [t0, t1] (None: none moves).
    pub fn furthest_axis(&self, t0: i64, t1: i64) -> Option<usize> {
        let i0 = self.t.partition_point(|&x| x < t0);
        let i1 = self.t.partition_point(|&x| x <= t1);
        let seg = self.s.get(i0..i1.max(i0))?;
        let mut travel = [0i64; AXES];
        for w in seg.windows(2) {
            for (a, tr) in travel.iter_mut().enumerate() {
                *tr += (w[1].axes[a] - w[0].axes[a]).abs();
            }
        }
        let slot = (0..AXES).max_by_key(|&a| travel[a])?;
        (travel[slot] > 0).then_some(slot)
    }

    /// The index in [`Reference::sync`] of the synchronised move in force at `t` (None: none).
    pub fn sync_index(&self, t: i64) -> Option<usize> {
        let k = self.sync.partition_point(|w| w.t0 <= t);
        k.checked_sub(1).filter(|&i| t <= self.sync[i].t1)
    }

    /// The axes of the trace.
    pub fn axes(&self) -> &[AxisSpec] {
        &self.trace.meta.axes
    }

    /// The index of the last sample at or before `t` (None before the first).
    fn idx_at(&self, t: i64) -> Option<usize> {
        let h = self.hint.get();
        // The sample at or before `t`: the hint, or one of the next two, else a binary search.
        for k in h..(h + 3).min(self.t.len()) {
            if self.t[k] <= t && self.t.get(k + 1).is_none_or(|&n| n > t) {
                self.hint.set(k);
                return Some(k);
            }
        }
        let k = self.t.partition_point(|&x| x <= t).checked_sub(1)?;
        self.hint.set(k);
        Some(k)
    }

    /// A value read from samples, interpolated linearly at `t` (held after the last sample).
    pub fn value_at(&self, t: i64, read: impl Fn(&Sample) -> i64) -> Option<f64> {
        let i = self.idx_at(t).or(if self.s.is_empty() { None } else { Some(0) })?;
        let v0 = read(&self.s[i]) as f64;
        match self.s.get(i + 1) {
            Some(n) if self.t[i] <= t => {
                let f = (t - self.t[i]) as f64 / (self.t[i + 1] - self.t[i]).max(1) as f64;
                Some(v0 + (read(n) as f64 - v0) * f)
            }
            _ => Some(v0),
        }
    }

    /// The spindle angle at `t` (milli-degrees, 0 ≤ a < 360 000), interpolated unwrapped.
    pub fn angle_at(&self, t: i64) -> Option<f64> {
        let i = self.idx_at(t).or(if self.s.is_empty() { None } else { Some(0) })?;
        let a = match self.cum_mdeg.get(i + 1) {
            Some(&n) if self.t[i] <= t => {
                let f = (t - self.t[i]) as f64 / (self.t[i + 1] - self.t[i]).max(1) as f64;
                self.cum_mdeg[i] + (n - self.cum_mdeg[i]) * f
            }
            _ => self.cum_mdeg[i],
        };
        Some(a.rem_euclid(360_000.0))
    }

    /// Position of `slot` at `t`, interpolated.
    pub fn pos_at(&self, t: i64, slot: usize) -> Option<f64> {
        self.value_at(t, |s| s.axes[slot])
    }

    /// The range (min, max) of `slot` over [t0, t1], ends interpolated.
    pub fn range(&self, t0: i64, t1: i64, slot: usize) -> Option<(f64, f64)> {
        let a = self.pos_at(t0, slot)?;
        let b = self.pos_at(t1, slot)?;
        let (mut lo, mut hi) = (a.min(b), a.max(b));
        let i0 = self.t.partition_point(|&x| x < t0);
        let i1 = self.t.partition_point(|&x| x <= t1);
        for s in &self.s[i0..i1.max(i0)] {
            let v = s.axes[slot] as f64;
            lo = lo.min(v);
            hi = hi.max(v);
        }
        Some((lo, hi))
    }

    /// Every axis at `t`, interpolated (as [`Reference::pos_at`], in one search).
    pub fn pos_all(&self, t: i64) -> Option<[f64; AXES]> {
        let i = self.idx_at(t).or(if self.s.is_empty() { None } else { Some(0) })?;
        let a = &self.s[i];
        let mut out = [0.0; AXES];
        match self.s.get(i + 1) {
            Some(n) if self.t[i] <= t => {
                let f = (t - self.t[i]) as f64 / (self.t[i + 1] - self.t[i]).max(1) as f64;
                for (k, o) in out.iter_mut().enumerate() {
                    let v0 = a.axes[k] as f64;
                    *o = v0 + (n.axes[k] as f64 - v0) * f;
                }
            }
            _ => {
                for (k, o) in out.iter_mut().enumerate() {
                    *o = a.axes[k] as f64;
                }
            }
        }
        Some(out)
    }

    /// The range (min, max) of every axis over [t0, t1], ends interpolated (as
    /// [`Reference::range`], in one pass).
    pub fn range_all(&self, t0: i64, t1: i64) -> Option<([f64; AXES], [f64; AXES])> {
        let a = self.pos_all(t0)?;
        let b = self.pos_all(t1)?;
        let (mut lo, mut hi) = ([0.0; AXES], [0.0; AXES]);
        for k in 0..AXES {
            lo[k] = a[k].min(b[k]);
            hi[k] = a[k].max(b[k]);
        }
        let i0 = self.t.partition_point(|&x| x < t0);
        let i1 = self.t.partition_point(|&x| x <= t1);
        for s in &self.s[i0..i1.max(i0)] {
            for k in 0..AXES {
                let v = s.axes[k] as f64;
                lo[k] = lo[k].min(v);
                hi[k] = hi[k].max(v);
            }
        }
        Some((lo, hi))
    }

    /// The phase in force at `t`.
    pub fn phase_at(&self, t: i64) -> Phase {
        let k = self.phases.partition_point(|p| p.0 <= t);
        k.checked_sub(1).map_or(Phase::Idle, |i| self.phases[i].1)
    }

    /// The switches and buttons that had acted by `t` and are still on (`dry_run`,
    /// `machine_lock`, `reset`, `feed_hold`).
    pub fn inputs_at(&self, t: i64) -> Vec<String> {
        let mut on: Vec<String> = Vec::new();
        for (ti, name, value) in &self.inputs {
            if *ti > t {
                break;
            }
            on.retain(|n| n != name);
            if value != "off" {
                on.push(name.clone());
            }
        }
        on
    }

    /// Whether an overload retract had started by `t` (within the reference's run).
    pub fn overload_by(&self, t: i64) -> bool {
        self.phases.iter().any(|(tp, p)| *p == Phase::OverloadRetract && *tp <= t)
    }
}

/// The tap axis: the axis that travels furthest while RGSPP or RGSPM is on; its lead from the
/// travel over the signed revolutions of every stroke; the first stroke's signal and direction.
fn find_tap(trace: &Trace) -> Option<Tap> {
    let mut sig = Signals::default();
    let mut first: Option<Signal> = None;
    // Samples inside strokes, grouped in runs of consecutive samples.
    let mut segs: Vec<Vec<(i64, Sample)>> = Vec::new();
    let mut open = false;
    for e in &trace.events {
        match &e.event {
            Event::Signal { signal, value } => {
                if matches!(signal, Signal::Rgspp | Signal::Rgspm) && *value {
                    first.get_or_insert(*signal);
                    open = false; // every stroke is its own segment
                }
                sig.set(*signal, *value);
            }
            Event::Sample(s) => {
                if sig.get(Signal::Rgspp) || sig.get(Signal::Rgspm) {
                    if !open {
                        segs.push(Vec::new());
                        open = true;
                    }
                    if let Some(seg) = segs.last_mut() {
                        seg.push((e.t_us as i64, *s));
                    }
                } else {
                    open = false;
                }
            }
            _ => {}
        }
    }
    let in_signal = first?;
    let mut travel = [0i64; AXES];
    for seg in &segs {
        for w in seg.windows(2) {
            for (a, tr) in travel.iter_mut().enumerate() {
                *tr += (w[1].1.axes[a] - w[0].1.axes[a]).abs();
            }
        }
    }
    let slot = (0..AXES).max_by_key(|&a| travel[a])?;
    if travel[slot] == 0 {
        return None;
    }
    let diameter = trace.meta.axes.iter().any(|a| a.index == slot && a.diameter);
    let (mut lead_sum, mut rev_sum, mut into_sign) = (0f64, 0f64, 0i64);
    for seg in &segs {
        let (Some(a), Some(b)) = (seg.first(), seg.last()) else { continue };
        let r: f64 = seg
            .windows(2)
            .map(|w| {
                let (p, q) = (&w[0].1, &w[1].1);
                unwrap_delta(p.spindle_mdeg, p.spindle_mrpm, q.spindle_mdeg, q.spindle_mrpm, w[1].0 - w[0].0)
            })
            .sum::<f64>()
            / 360_000.0;
        let d = (b.1.axes[slot] - a.1.axes[slot]) as f64;
        if into_sign == 0 && d != 0.0 {
            into_sign = if d > 0.0 { 1 } else { -1 };
        }
        if r.abs() > 0.25 {
            lead_sum += d * r.signum();
            rev_sum += r.abs();
        }
    }
    if rev_sum < 0.25 {
        return None;
    }
    let lead_nm = lead_sum / rev_sum / if diameter { 2.0 } else { 1.0 };
    Some(Tap { slot, diameter, lead_nm, in_signal, into_sign: if into_sign == 0 { 1 } else { into_sign } })
}
