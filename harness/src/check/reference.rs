//! The reference side of a comparison: its discrete events (the skeleton), the tap axis and lead
//! for the synchronisation error, its key points, phases and inputs for attribution, in memory;
//! its samples through a sliding [`Window`] (pulled from the run as the comparison advances,
//! dropped behind it), so that memory does not follow the run's length.

use std::cell::RefCell;

use nc_engine::trace::{
    AxisSpec, Event, Phase, Sample, Signal, Trace, TraceEvent, TraceMeta, TraceSink, AXES,
};

use super::keypoints::KeyPoints;
use super::survey::{Skeleton, Source, Survey};
use super::window::{Feed, Window};

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

/// The reference run, indexed.
pub struct Reference<'a> {
    /// Its discrete events (every event but the samples), the end last.
    pub trace: Trace,
    /// The run, replayable.
    pub source: Source<'a>,
    /// Its samples around the comparison's time.
    pub win: RefCell<Window<'a>>,
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
    /// The synchronised moves (rigid strokes, thread passes, encoder-following moves).
    pub sync: Vec<super::sync::Window>,
    /// Events of the run, samples included.
    pub total_events: usize,
    /// Time of its last sample.
    pub last_sample_t: Option<i64>,
    /// The spindle turns at some sample.
    pub spindle_turns: bool,
    /// Each axis moves at some sample.
    pub moves: [bool; AXES],
    /// [`Reference::slim`] dropped the discrete events (or the first pass kept none).
    pub slimmed: bool,
    /// The first pass kept no discrete events: the comparison takes them, the key points, the
    /// synchronised moves and the phases from the samples' feed ([`Window::keyed`]) as it
    /// advances ([`Reference::sync`] and [`Reference::phases`] are empty).
    pub streamed: bool,
    /// The first overload retract's time.
    pub first_overload: Option<i64>,
    /// The reference cuts (a `cutting` phase) at some time.
    pub cuts: bool,
    /// What the comparison needs of the discrete events as a whole.
    pub summary: super::events::Summary,
    /// The envelope's sliding extremes.
    extremes: RefCell<Extremes>,
    /// The index in `sync` of the last [`Reference::sync_index`] (where the next one looks
    /// first).
    sync_hint: std::cell::Cell<usize>,
}

impl std::fmt::Debug for Reference<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Reference").field("tap", &self.tap).field("end_us", &self.end_us).finish()
    }
}

/// The change of a spindle angle from `a0` to `a1` (milli-degrees) over `dt_us`, unwrapped using
/// the speeds at both ends to predict it.
pub fn unwrap_delta(a0: i64, m0: i64, a1: i64, m1: i64, dt_us: i64) -> f64 {
    let expected = (m0 + m1) as f64 / 2.0 * 6.0 * dt_us as f64 / 1e6;
    let raw = (a1 - a0) as f64;
    let diff = rem_turn(raw - expected);
    let diff = if diff > 180_000.0 { diff - 360_000.0 } else { diff };
    expected + diff
}

/// `x.rem_euclid(360_000.0)` (milli-degrees into one turn), bit for bit, without libm's `fmod`
/// when `x` is within a turn either side of 0 (the remainder is then `x` or `x + 360 000`
/// exactly): the angles compared per sample mostly are.
#[inline]
pub fn rem_turn(x: f64) -> f64 {
    const TURN: f64 = 360_000.0;
    if (0.0..TURN).contains(&x) {
        x
    } else if x > -TURN && x < 0.0 {
        x + TURN
    } else {
        x.rem_euclid(TURN)
    }
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

/// The least and greatest value of each axis over a window of sample indices that only moves
/// forward (monotonic queues of indices in the whole run): the envelope's range at each recorded
/// sample in constant time.
#[derive(Default)]
pub struct Extremes {
    /// The window [from, to) of run indices the queues cover.
    from: usize,
    to: usize,
    lo: [std::collections::VecDeque<usize>; AXES],
    hi: [std::collections::VecDeque<usize>; AXES],
}

impl Extremes {
    /// Moves the window to [g0, g1) over the samples of `w` for the axes `slots`.
    fn slide(&mut self, w: &Window, g0: usize, g1: usize, slots: &[usize]) {
        // (Started again, the same extremes, when the window has moved on or dropped the
        // samples the queues begin with.)
        if g0 < self.from || g1 < self.to || g0 > self.to || self.from < w.base {
            *self = Extremes { from: g0, to: g0, ..Extremes::default() };
        }
        let v = |g: usize, k: usize| w.s[g - w.base].axes[k];
        for g in self.to..g1 {
            for &k in slots {
                let x = v(g, k);
                while self.lo[k].back().is_some_and(|&b| v(b, k) >= x) {
                    self.lo[k].pop_back();
                }
                self.lo[k].push_back(g);
                while self.hi[k].back().is_some_and(|&b| v(b, k) <= x) {
                    self.hi[k].pop_back();
                }
                self.hi[k].push_back(g);
            }
        }
        for &k in slots {
            while self.lo[k].front().is_some_and(|&f| f < g0) {
                self.lo[k].pop_front();
            }
            while self.hi[k].front().is_some_and(|&f| f < g0) {
                self.hi[k].pop_front();
            }
        }
        self.from = g0;
        self.to = g1;
    }

    /// The least and greatest value of axis `k` over the window (None: empty).
    fn get(&self, w: &Window, k: usize) -> Option<(i64, i64)> {
        let v = |g: usize| w.s[g - w.base].axes[k];
        Some((v(*self.lo[k].front()?), v(*self.hi[k].front()?)))
    }
}

/// Stops a replay at the first crossing of each detector.
struct Detectors {
    d: Vec<(usize, MotionDetector, Option<i64>)>,
}

impl TraceSink for Detectors {
    fn start(&mut self, _meta: &TraceMeta) {}
    fn event(&mut self, ev: &TraceEvent) {
        if let Event::Sample(s) = &ev.event {
            for (_, d, hit) in self.d.iter_mut().filter(|x| x.2.is_none()) {
                *hit = d.sample(ev.t_us as i64, s);
            }
        }
    }
    fn wants_stop(&self) -> bool {
        self.d.iter().all(|x| x.2.is_some())
    }
}

/// `moves.partition_point(|m| m.t0 <= t)`, looked for from `h` (the last answer) first: the
/// comparison walks forward.
fn next_move(moves: &[super::sync::Window], h: usize, t: i64) -> usize {
    match (moves.get(h), moves.get(h + 1)) {
        (Some(a), Some(b)) if a.t0 <= t && b.t0 > t => h + 1,
        (Some(a), None) if a.t0 <= t => h + 1,
        (_, Some(b)) if b.t0 <= t && moves.get(h + 2).is_none_or(|c| c.t0 > t) => h + 2,
        _ => moves.partition_point(|w| w.t0 <= t),
    }
}

/// The index of the last sample at or before `t` in `w` (None before the first).
fn idx_at(w: &mut Window, t: i64) -> Option<usize> {
    let h = w.hint;
    // The sample at or before `t`: the hint, or one of the next two, else a binary search.
    for k in h..(h + 3).min(w.t.len()) {
        if w.t[k] <= t && w.t.get(k + 1).is_none_or(|&n| n > t) {
            w.hint = k;
            return Some(k);
        }
    }
    let k = w.t.partition_point(|&x| x <= t).checked_sub(1)?;
    w.hint = k;
    Some(k)
}

/// Every axis at `t` in `w`, interpolated (held after the last sample, the first before it).
fn pos_all_in(w: &mut Window, t: i64) -> Option<[f64; AXES]> {
    let i = idx_at(w, t).or(if w.s.is_empty() { None } else { Some(0) })?;
    let a = &w.s[i];
    let mut out = [0.0; AXES];
    match w.s.get(i + 1) {
        Some(n) if w.t[i] <= t => {
            let f = (t - w.t[i]) as f64 / (w.t[i + 1] - w.t[i]).max(1) as f64;
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

impl<'a> Reference<'a> {
    /// The first motion of axis `slot` (see [`MotionDetector`]).
    pub fn first_motion(&self, slot: usize, threshold_nm: i64) -> Option<i64> {
        self.first_change(Watch::Axis(slot), threshold_nm)
    }

    /// The first change of what `watch` watches beyond `threshold` (see [`MotionDetector`]): a
    /// replay of the run up to it.
    pub fn first_change(&self, watch: Watch, threshold: i64) -> Option<i64> {
        let mut d = Detectors { d: vec![(0, MotionDetector::watching(watch, threshold), None)] };
        self.source.replay(&mut d);
        d.d[0].2
    }

    /// The axis (among those `carried` accepts) that moves first in the reference.
    pub fn first_moving_axis(&self, threshold_nm: i64, carried: impl Fn(usize) -> bool) -> Option<usize> {
        let d = self
            .axes()
            .iter()
            .filter(|a| carried(a.index))
            .map(|a| (a.index, MotionDetector::new(a.index, threshold_nm), None))
            .collect();
        let mut d = Detectors { d };
        if d.d.is_empty() {
            return None;
        }
        self.source.replay(&mut d);
        d.d.iter().filter_map(|(slot, _, t)| t.map(|t| (t, *slot))).min().map(|x| x.1)
    }

    /// Indexes `trace` (its samples are read from it as the comparison needs them).
    pub fn new(trace: &'a Trace) -> Reference<'a> {
        Reference::build(Source::Trace(trace), Feed::Trace(trace.events.iter()))
    }

    /// Indexes the run `source` in two passes (its discrete events and tap; its key points and
    /// synchronised moves); its samples come from `feed`, the same run once more.
    pub(crate) fn build(source: Source<'a>, feed: Feed<'a>) -> Reference<'a> {
        let mut sk = Skeleton::default();
        source.replay(&mut sk);
        sk.summary.finish();
        Reference::build_from(source, sk, feed, true)
    }

    /// As [`Reference::build`], its first pass `sk` done already ([`Skeleton::of`]); without
    /// `keep_all`, [`Reference::trace`] keeps only the events the comparison matches (edges,
    /// functions, alarms, the end), not the phases, blocks and inputs (which the scenario's
    /// temporal rules need).
    pub(crate) fn build_from(
        source: Source<'a>,
        mut sk: Skeleton,
        feed: Feed<'a>,
        keep_all: bool,
    ) -> Reference<'a> {
        let tap = sk.tap();
        // Planned, and the phases and inputs listed, as the first pass read the events.
        debug_assert!(!(keep_all && sk.is_lean()), "a lean skeleton has no phases or blocks to keep");
        let mut plan = sk.plan();
        let phases = std::mem::take(&mut sk.phases);
        let inputs = std::mem::take(&mut sk.inputs);
        let mut trace = sk.trace();
        if !keep_all && !sk.is_lean() {
            // Phases, blocks and inputs are read (plan, phases, inputs): only the scenario's
            // temporal rules need them again.
            trace
                .events
                .retain(|e| !matches!(e.event, Event::Phase(_) | Event::Block { .. } | Event::Input { .. }));
            trace.events.shrink_to_fit();
        }
        // The second pass, read in the first when it could be; else run now (it takes the
        // plan's intervals: the windows are built from `plan.raw`). Lean, the synchronised moves
        // and key points are read alongside the comparison (`sync_stream`, `keypoints_cmp`).
        let streamed = sk.is_lean();
        debug_assert!(!(streamed && sk.has_lead_blocks()), "lead blocks are planned from a whole first pass");
        let (keys, sync) = if streamed {
            (KeyPoints::default(), Vec::new())
        } else {
            let (keys, spans, parts) = match sk.fused_survey(tap, &plan) {
                Some((keys, spans)) => {
                    plan.spans = Vec::new();
                    (keys, spans, Vec::new())
                }
                None => {
                    let (spans, lead) = (std::mem::take(&mut plan.spans), std::mem::take(&mut plan.lead));
                    let mut sv = Survey::new(tap, spans, lead, &trace.meta.axes);
                    source.replay(&mut sv);
                    sv.finish()
                }
            };
            (keys, super::sync::build(plan, spans, parts, tap, &trace.meta.axes))
        };
        let win = Window::with_keyed(feed, streamed, tap, &trace.meta);
        Reference {
            trace,
            source,
            win: RefCell::new(win),
            tap,
            keys,
            end_us: sk.end_us,
            phases,
            inputs,
            sync,
            total_events: sk.total,
            last_sample_t: sk.last_sample_t,
            spindle_turns: sk.spindle_turns,
            moves: sk.moves,
            slimmed: streamed,
            streamed,
            first_overload: sk.first_overload,
            cuts: sk.cuts,
            summary: std::mem::take(&mut sk.summary),
            extremes: RefCell::new(Extremes::default()),
            sync_hint: std::cell::Cell::new(0),
        }
    }

    /// Drops the discrete events from [`Reference::trace`] (its end stays) and returns them:
    /// memory no longer follows the number of holes. [`Reference::edges`] replays the run for
    /// them when needed.
    pub fn slim(&mut self) -> Trace {
        let end: Vec<TraceEvent> = self
            .trace
            .events
            .last()
            .filter(|e| matches!(e.event, Event::End(_)))
            .cloned()
            .into_iter()
            .collect();
        self.slimmed = true;
        Trace { meta: self.trace.meta.clone(), events: std::mem::replace(&mut self.trace.events, end) }
    }

    /// The edges of `s` in the reference (replayed when [`Reference::slim`] dropped them).
    pub fn edges(&self, s: Signal) -> Vec<(u64, bool)> {
        if !self.slimmed {
            return self.trace.edges(s).collect();
        }
        struct Edges(Signal, Vec<(u64, bool)>);
        impl TraceSink for Edges {
            fn event(&mut self, ev: &TraceEvent) {
                if let Event::Signal { signal, value } = ev.event {
                    if signal == self.0 {
                        self.1.push((ev.t_us, value));
                    }
                }
            }
        }
        let mut e = Edges(s, Vec::new());
        self.source.replay(&mut e);
        e.1
    }

    /// Nothing before `floor` will be looked up any more: the samples before it may go (and,
    /// streamed, the synchronised moves and phases).
    pub fn forget_before(&self, floor: i64) {
        let mut w = self.win.borrow_mut();
        w.prune(floor);
        if self.streamed && w.moves.front().is_some_and(|m| m.t1 < floor)
            || w.phases.get(1).is_some_and(|p| p.0 <= floor)
        {
            w.prune_moves(floor);
        }
    }

    /// The axis that travels furthest over [t0, t1] (None: none moves).
    pub fn furthest_axis(&self, t0: i64, t1: i64) -> Option<usize> {
        let mut w = self.win.borrow_mut();
        w.ensure(t1);
        let i0 = w.t.partition_point(|&x| x < t0);
        let i1 = w.t.partition_point(|&x| x <= t1);
        let seg = w.s.get(i0..i1.max(i0))?;
        let mut travel = [0i64; AXES];
        for p in seg.windows(2) {
            for (a, tr) in travel.iter_mut().enumerate() {
                *tr += (p[1].axes[a] - p[0].axes[a]).abs();
            }
        }
        let slot = (0..AXES).max_by_key(|&a| travel[a])?;
        (travel[slot] > 0).then_some(slot)
    }

    /// The index of the synchronised move in force at `t` (None: none), among all the run's
    /// ([`Reference::sync_window`]).
    pub fn sync_index(&self, t: i64) -> Option<usize> {
        if self.streamed {
            let mut w = self.win.borrow_mut();
            w.ensure_moves(t);
            let base = w.moves_base;
            let h = self.sync_hint.get().saturating_sub(base);
            // Contiguous (`window::add_moves`); else the lookup is over the first part.
            let moves = w.moves.as_slices().0;
            let k = next_move(moves, h, t);
            self.sync_hint.set(base + k.saturating_sub(1));
            return k.checked_sub(1).filter(|&i| t <= moves[i].t1).map(|i| base + i);
        }
        let h = self.sync_hint.get();
        let k = next_move(&self.sync, h, t);
        self.sync_hint.set(k.saturating_sub(1));
        k.checked_sub(1).filter(|&i| t <= self.sync[i].t1)
    }

    /// The synchronised move `k` of [`Reference::sync_index`].
    pub fn sync_window(&self, k: usize) -> super::sync::Window {
        if self.streamed {
            let w = self.win.borrow();
            return w.moves[k - w.moves_base];
        }
        self.sync[k]
    }

    /// Whether what attribution needs at `t` (the phase, the synchronised move) is still held:
    /// streamed, those of times the comparison has passed are dropped.
    pub fn holds_context_at(&self, t: i64) -> bool {
        !self.streamed || t >= self.win.borrow().held_from
    }

    /// The axes of the trace.
    pub fn axes(&self) -> &[AxisSpec] {
        &self.trace.meta.axes
    }

    /// A value read from samples, interpolated linearly at `t` (held after the last sample).
    pub fn value_at(&self, t: i64, read: impl Fn(&Sample) -> i64) -> Option<f64> {
        let mut w = self.win.borrow_mut();
        w.ensure(t);
        let i = idx_at(&mut w, t).or(if w.s.is_empty() { None } else { Some(0) })?;
        let v0 = read(&w.s[i]) as f64;
        match w.s.get(i + 1) {
            Some(n) if w.t[i] <= t => {
                let f = (t - w.t[i]) as f64 / (w.t[i + 1] - w.t[i]).max(1) as f64;
                Some(v0 + (read(n) as f64 - v0) * f)
            }
            _ => Some(v0),
        }
    }

    /// The spindle angle at `t` (milli-degrees, 0 ≤ a < 360 000), interpolated unwrapped.
    pub fn angle_at(&self, t: i64) -> Option<f64> {
        let mut w = self.win.borrow_mut();
        w.ensure(t);
        let i = idx_at(&mut w, t).or(if w.s.is_empty() { None } else { Some(0) })?;
        let a = match w.cum.get(i + 1) {
            Some(&n) if w.t[i] <= t => {
                let f = (t - w.t[i]) as f64 / (w.t[i + 1] - w.t[i]).max(1) as f64;
                w.cum[i] + (n - w.cum[i]) * f
            }
            _ => w.cum[i],
        };
        Some(rem_turn(a))
    }

    /// Position of `slot` at `t`, interpolated.
    pub fn pos_at(&self, t: i64, slot: usize) -> Option<f64> {
        self.value_at(t, |s| s.axes[slot])
    }

    /// The range (min, max) of `slot` over [t0, t1], ends interpolated.
    pub fn range(&self, t0: i64, t1: i64, slot: usize) -> Option<(f64, f64)> {
        let (lo, hi) = self.range_all(t0, t1)?;
        Some((lo[slot], hi[slot]))
    }

    /// Every axis at `t`, interpolated (as [`Reference::pos_at`], in one search).
    pub fn pos_all(&self, t: i64) -> Option<[f64; AXES]> {
        let mut w = self.win.borrow_mut();
        w.ensure(t);
        pos_all_in(&mut w, t)
    }

    /// The range (min, max) of every axis over [t0, t1], ends interpolated (as
    /// [`Reference::range`], in one pass).
    pub fn range_all(&self, t0: i64, t1: i64) -> Option<([f64; AXES], [f64; AXES])> {
        let mut w = self.win.borrow_mut();
        w.ensure(t1.max(t0));
        let a = pos_all_in(&mut w, t0)?;
        let b = pos_all_in(&mut w, t1)?;
        let (mut lo, mut hi) = ([0.0; AXES], [0.0; AXES]);
        for k in 0..AXES {
            lo[k] = a[k].min(b[k]);
            hi[k] = a[k].max(b[k]);
        }
        let i0 = w.t.partition_point(|&x| x < t0);
        let i1 = w.t.partition_point(|&x| x <= t1);
        for s in &w.s[i0..i1.max(i0)] {
            for k in 0..AXES {
                let v = s.axes[k] as f64;
                lo[k] = lo[k].min(v);
                hi[k] = hi[k].max(v);
            }
        }
        Some((lo, hi))
    }

    /// The position envelope at `t` of the axes `slots` marks: each one's range (min, max) over
    /// [t − w, t + w], ends interpolated, and (with `at_too`) its position at `t`; exactly as
    /// [`Reference::range_all`] and [`Reference::pos_all`] (the other axes are 0), in one pass.
    #[allow(clippy::type_complexity)]
    pub fn envelope(
        &self,
        t: i64,
        w: i64,
        slots: &[usize],
        at_too: bool,
    ) -> Option<([f64; AXES], [f64; AXES], Option<[f64; AXES]>)> {
        let mut win = self.win.borrow_mut();
        let (t0, t1) = (t - w, t + w);
        win.ensure(t1.max(t0));
        if win.s.is_empty() {
            return None;
        }
        let i0 = win.first_at_or_after(t0);
        let i1 = win.first_after(t1);
        // t0 <= t <= t1: the first sample after t is in [i0, i1] (walked from the last one).
        let after_t = at_too.then(|| win.first_after_in(5, t));
        let n = win.t.len();
        // The last sample at or before a time from the first after it (the first sample when
        // none), and the value there: the interpolation's fraction is found once per time, not
        // once per axis (the same arithmetic, so the same values).
        let last_le = |first_after: usize| first_after.saturating_sub(1);
        let frac = |i: usize, x: i64| -> Option<f64> {
            (i + 1 < n && win.t[i] <= x)
                .then(|| (x - win.t[i]) as f64 / (win.t[i + 1] - win.t[i]).max(1) as f64)
        };
        let value = |i: usize, f: Option<f64>, k: usize| -> f64 {
            let v0 = win.s[i].axes[k] as f64;
            match f {
                Some(f) => v0 + (win.s[i + 1].axes[k] as f64 - v0) * f,
                None => v0,
            }
        };
        let ia = last_le(if i0 < n && win.t[i0] == t0 { i0 + 1 } else { i0 });
        let ib = last_le(i1);
        let it = after_t.map(last_le);
        let (fa, fb) = (frac(ia, t0), frac(ib, t1));
        let ft = it.map(|i| frac(i, t));
        let (mut lo, mut hi, mut at) = ([0.0; AXES], [0.0; AXES], [0.0; AXES]);
        let mut ex = self.extremes.borrow_mut();
        ex.slide(&win, win.base + i0, win.base + i1.max(i0), slots);
        for &k in slots {
            let (a, b) = (value(ia, fa, k), value(ib, fb, k));
            let (mut l, mut h) = (a.min(b), a.max(b));
            if let Some((x, y)) = ex.get(&win, k) {
                l = l.min(x as f64);
                h = h.max(y as f64);
            }
            lo[k] = l;
            hi[k] = h;
            if let (Some(i), Some(f)) = (it, ft) {
                at[k] = value(i, f, k);
            }
        }
        Some((lo, hi, it.map(|_| at)))
    }

    /// The range (min, max) of the spindle speed over the samples within [t0, t1], milli-rpm
    /// (None: no sample there).
    pub fn speed_range(&self, t0: i64, t1: i64) -> Option<(i64, i64)> {
        let mut w = self.win.borrow_mut();
        w.ensure(t1);
        let i0 = w.t.partition_point(|&x| x < t0);
        let i1 = w.t.partition_point(|&x| x <= t1);
        let seg = &w.s[i0..i1.max(i0)];
        let lo = seg.iter().map(|q| q.spindle_mrpm).min()?;
        let hi = seg.iter().map(|q| q.spindle_mrpm).max()?;
        Some((lo, hi))
    }

    /// Runs `f` on the samples of the window that covers [lo, hi] (times, samples, cumulative
    /// spindle angles, milli-degrees), every sample in [lo, hi] included, with the indices of
    /// the first sample at or after `lo`, the first after `hi` and the first after `t`.
    pub fn with_samples<R>(
        &self,
        lo: i64,
        hi: i64,
        t: i64,
        f: impl FnOnce(&[i64], &[Sample], &[f64], [usize; 3]) -> R,
    ) -> R {
        let mut w = self.win.borrow_mut();
        w.ensure(hi);
        let at = [w.first_at_or_after_in(2, lo), w.first_after_in(3, hi), w.first_after_in(4, t)];
        f(&w.t, &w.s, &w.cum, at)
    }

    /// The phase in force at `t`.
    pub fn phase_at(&self, t: i64) -> Phase {
        if self.streamed {
            let mut w = self.win.borrow_mut();
            w.ensure(t);
            let k = w.phases.partition_point(|p| p.0 <= t);
            return k.checked_sub(1).map_or(Phase::Idle, |i| w.phases[i].1);
        }
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
        self.first_overload.is_some_and(|tp| tp <= t)
    }
}

#[cfg(test)]
mod tests {
    use super::rem_turn;

    #[test]
    fn rem_turn_is_rem_euclid_bit_for_bit() {
        let turn = 360_000.0f64;
        let mut xs = vec![
            0.0,
            -0.0,
            turn,
            -turn,
            turn - 1e-9,
            -turn + 1e-9,
            -1e-300,
            1e-300,
            -5e-324,
            179_999.5,
            -180_000.0,
            2.0 * turn,
            -2.0 * turn,
            1e17,
            -1e17,
            f64::MAX,
            f64::MIN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        let mut r = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..200_000 {
            r ^= r << 13;
            r ^= r >> 7;
            r ^= r << 17;
            let u = (r >> 11) as f64 / (1u64 << 53) as f64;
            xs.push((u - 0.5) * 6.0 * turn);
            xs.push(f64::from_bits(r));
        }
        for x in xs {
            assert_eq!(rem_turn(x).to_bits(), x.rem_euclid(turn).to_bits(), "{x:e}");
        }
    }
}
