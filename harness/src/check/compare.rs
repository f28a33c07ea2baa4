//! The streaming comparison: recorded events are aligned on the anchor, then each goes through
//! the event matcher, the key-point tracker, the synchronisation error and the position
//! envelope, and into a compact copy (discrete events, samples thinned to the reference's sample
//! period, bounded by the reference's length) on which the scenario's temporal rules run.
//! Memory holds windows and aggregates, never the whole recorded trace.

use nc_engine::trace::{EndSummary, Event, Sample, Signal, Signals, Trace, TraceEvent};

use super::carried::{Carried, NotComparable};
use super::events::{Finding, Key, Matcher};
use super::keypoints::KeyTracker;
use super::keypoints_cmp::KeyCompare;
use super::reference::{MotionDetector, Reference, Watch};
use super::tolerance::{mm_nm, ms_us, Anchor, Context, Tolerances, Topic};
use super::{Divergence, Point, MAX_DIVERGENCES};

mod motion;
mod streamed;
use crate::scenario::timeline::{fixed, ms};

/// Recorded samples kept in the compact copy, at most (the rest are compared and plotted, not
/// kept: memory does not follow the recording's length).
pub const MAX_COMPACT_SAMPLES: usize = 20_000;

/// Recorded events other than samples kept in the compact copy when no temporal rule runs on it,
/// at most.
pub const MAX_COMPACT_EVENTS: usize = 20_000;

/// Recorded events buffered while looking for the anchor, at most.
const MAX_PENDING: usize = 2_000_000;

/// An open run of out-of-tolerance samples (envelope or sync).
#[derive(Debug, Clone)]
struct Run {
    t_first: i64,
    t_worst: i64,
    excess: f64,
    expected: String,
    actual: String,
    samples: u64,
    what: String,
}

impl Run {
    /// A run whose first sample is at `t` (its worst is set by the first excess).
    fn starting(t: i64) -> Run {
        Run {
            t_first: t,
            t_worst: t,
            excess: -1.0,
            expected: String::new(),
            actual: String::new(),
            samples: 0,
            what: String::new(),
        }
    }
}

/// Compares recorded events with the reference, one at a time.
pub struct Comparator<'r, 'a> {
    pub(super) r: &'r Reference<'a>,
    pub(super) tol: Tolerances,
    dialect: String,
    rules: Vec<String>,
    ref_anchor: Option<i64>,
    anchor: Anchor,
    offset: Option<i64>,
    pending: Vec<TraceEvent>,
    matcher: Option<Matcher>,
    /// The widest event window, µs.
    wmax: i64,
    matched: usize,
    keys: KeyTracker,
    /// Both traces' key points compared stroke by stroke.
    keycmp: KeyCompare,
    /// Divergences kept whose rule is found at the end (index, topic, time, an overload retract
    /// begun by their worst point).
    unattributed: Vec<(usize, Topic, i64, bool)>,
    /// The reference's edges of signals a closed recording does not declare (it cannot show
    /// them: never matched): key, how many, the first's time.
    pub(super) absent_refs: Vec<(Key, usize, i64)>,
    /// Where the notes on the synchronisation error go among [`Comparator::not_comparable`],
    /// once the reference's synchronised moves are all read (streamed).
    sync_notes_at: Option<usize>,
    findings: Vec<Finding>,
    sig: Signals,
    /// The synchronised move of the reference being compared (index) and the error at its
    /// first compared sample.
    sync_win: Option<(usize, Option<f64>)>,
    /// From when the synchronised move in `sync_win` is not judged: `event_ms` before the reset
    /// or emergency stop that ends it (`i64::MAX` when none does), found once per move.
    sync_cut_us: i64,
    cur_sync: Option<f64>,
    /// Recorded samples at which the synchronisation was compared.
    pub sync_samples: u64,
    /// How well the alignment fits: the sum of squared position differences (recorded −
    /// reference at the same time, nm²) over the recorded axes and samples within the reference's
    /// run, and their number.
    pub fit: (f64, u64),
    sync_run: Option<Run>,
    env_runs: Vec<Option<Run>>,
    /// Divergences so far.
    pub divergences: Vec<Divergence>,
    /// Divergences left out past [`MAX_DIVERGENCES`].
    pub omitted: usize,
    /// Of those, how many of each check.
    pub omitted_by_check: std::collections::BTreeMap<String, usize>,
    per_check: std::collections::BTreeMap<String, usize>,
    compact: Vec<TraceEvent>,
    had_phases: bool,
    keep_all: bool,
    had_blocks: bool,
    had_functions: bool,
    last_kept: Option<i64>,
    last_sample: Option<(i64, Sample)>,
    alarms: u32,
    /// Plot points of the recorded trace (one per bucket).
    pub series: Vec<Point>,
    bucket_us: i64,
    /// The plot bucket being filled: its start, its points of least and greatest value.
    bucket: Option<(i64, Point, Point)>,
    /// How far back in reference time the comparison still looks (µs).
    floor_us: i64,
    compact_samples: usize,
    /// The envelope's half width (µs), its tolerance (nm) and the axes it compares.
    env_w: i64,
    env_tol: f64,
    env_slots: Vec<usize>,
    /// Recorded events and samples seen.
    pub events_seen: u64,
    /// Recorded samples seen.
    pub samples_seen: u64,
    /// Largest |sync error| in nm.
    pub max_sync_nm: f64,
    /// Largest position excess beyond the envelope, nm.
    pub max_env_nm: f64,
    /// Whether the anchor was found.
    pub anchored: bool,
    last_t: i64,
    /// What the recording can carry.
    pub(super) carried: Carried,
    /// Reference events and checks left out because the recording cannot show them.
    pub not_comparable: Vec<NotComparable>,
    /// Signals the recording showed an edge of.
    pub(super) seen: Signals,
    /// Reference edges never recorded, judged at the end (a signal the recording may not
    /// carry, a pulse between two rows).
    pub(super) missing_edges: Vec<(Key, i64)>,
    /// Reference functions and alarms never recorded, judged at the end (a shift, a truncation).
    pub(super) missing_other: Vec<(Key, i64)>,
    /// Recorded events the reference does not have, judged at the end (a shift).
    pub(super) extras: Vec<(Key, i64)>,
    /// Longest gap between two recorded samples within the reference's run, µs.
    pub(super) max_gap_us: i64,
    last_sample_t: Option<i64>,
    motion: Option<MotionDetector>,
    marks: Vec<(i64, i64)>,
    /// The most reference events waiting in the matcher at once.
    pub peak_waiting: usize,
    /// The most records of the reference held at once by the comparison besides its samples
    /// (events waiting in the matcher, synchronised moves and phases, key points waiting for
    /// their pair; each one's most, summed): a figure for the memory bound.
    pub records_held: usize,
    handshake: super::handshake::Handshake,
    ref_handshake: Vec<super::handshake::Fault>,
}

impl<'r, 'a> Comparator<'r, 'a> {
    /// A comparator against `r`.
    /// A comparator against `r`; `skeleton` is the reference's discrete events (`r.trace`, or
    /// what it held before [`Reference::slim`]), read here only.
    pub fn new(
        r: &'r Reference<'a>,
        skeleton: &Trace,
        tol: Tolerances,
        anchor: Anchor,
        scenario_rules: Vec<String>,
    ) -> Self {
        let threshold = mm_nm(tol.position_mm);
        let rpm_threshold = (tol.speed_rpm.max(0.001) * 1000.0).round() as i64;
        let watch = match anchor {
            Anchor::TapMotion => r
                .tap
                .map(|tp| tp.slot)
                .or_else(|| r.first_moving_axis(threshold, |_| true))
                .map(|slot| (Watch::Axis(slot), threshold)),
            Anchor::SpindleStart => Some((Watch::Spindle, rpm_threshold)),
            _ => None,
        };
        let motion = watch.map(|(w, th)| MotionDetector::watching(w, th));
        let ref_anchor = match &anchor {
            Anchor::Offset(_) => None,
            Anchor::TapMotion | Anchor::SpindleStart => watch.and_then(|(w, th)| r.first_change(w, th)),
            Anchor::Function(l, c) => r.summary.first(&Key::Function(*l, *c)),
            Anchor::Edge(s, v) => r.summary.first(&Key::Edge(*s, *v)),
        };
        let offset = match anchor {
            Anchor::Offset(o) => Some(o),
            _ => None,
        };
        let bucket_us = (r.end_us / 750).max(1000);
        let floor_us = ms_us(tol.envelope_ms.max(tol.event_ms)) + 1;
        let (env_w, env_tol) = (ms_us(tol.envelope_ms), mm_nm(tol.position_mm) as f64);
        Comparator {
            r,
            tol,
            dialect: r.trace.meta.dialect.to_string(),
            rules: scenario_rules,
            ref_anchor,
            anchored: offset.is_some(),
            anchor,
            offset,
            pending: Vec::new(),
            matcher: Some(if r.streamed { Matcher::streaming(true, true) } else { Matcher::new(skeleton) }),
            wmax: 0,
            matched: 0,
            keys: KeyTracker::new(r.tap),
            keycmp: KeyCompare::default(),
            unattributed: Vec::new(),
            absent_refs: Vec::new(),
            sync_notes_at: None,
            findings: Vec::new(),
            sig: Signals::default(),
            sync_win: None,
            sync_cut_us: i64::MAX,
            cur_sync: None,
            sync_samples: 0,
            fit: (0.0, 0),
            sync_run: None,
            env_runs: vec![None; r.axes().len()],
            divergences: Vec::new(),
            omitted: 0,
            omitted_by_check: Default::default(),
            per_check: Default::default(),
            compact: Vec::new(),
            had_phases: false,
            keep_all: true,
            had_blocks: false,
            had_functions: false,
            last_kept: None,
            last_sample: None,
            alarms: 0,
            series: Vec::new(),
            bucket_us,
            bucket: None,
            floor_us,
            compact_samples: 0,
            env_w,
            env_tol,
            env_slots: r.axes().iter().map(|a| a.index).collect(),
            events_seen: 0,
            samples_seen: 0,
            max_sync_nm: 0.0,
            max_env_nm: 0.0,
            last_t: 0,
            carried: Carried::default(),
            not_comparable: Vec::new(),
            seen: Signals::default(),
            missing_edges: Vec::new(),
            missing_other: Vec::new(),
            extras: Vec::new(),
            max_gap_us: 0,
            last_sample_t: None,
            motion,
            marks: Vec::new(),
            peak_waiting: 0,
            records_held: 0,
            handshake: Default::default(),
            ref_handshake: r.summary.faults.clone(),
        }
        .widest_window()
        .reference_keys()
    }

    /// Compares only what `carried` says the recording can show; the reference events it
    /// cannot (functions, alarms) are counted as not comparable.
    pub fn carrying(mut self, carried: Carried, skeleton: &Trace) -> Self {
        let (f, a) = (carried.functions, carried.alarms);
        self.matcher = None; // one matcher in memory at a time
        self.matcher = Some(if self.r.streamed {
            Matcher::streaming(f, a)
        } else {
            Matcher::new_filtered(skeleton, f, a)
        });
        let (notes, at) = super::carried::left_out(self.r, &carried);
        self.not_comparable = notes;
        self.sync_notes_at = at;
        self.env_slots = self.r.axes().iter().map(|a| a.index).filter(|&k| carried.axis(k)).collect();
        self.carried = carried;
        self
    }

    /// Reference events matched (after [`Comparator::finish`]).
    pub fn matched(&self) -> usize {
        self.matched
    }

    /// The offset applied: reference time = recorded time + offset.
    pub fn offset(&self) -> i64 {
        self.offset.unwrap_or(0)
    }

    /// The attribution context at reference time `t`.
    pub fn context(&self, t: i64) -> Context {
        Context {
            dialect: self.dialect.clone(),
            inputs: self.r.inputs_at(t),
            // An overload retract starting within the envelope's slack counts: a late retract
            // shows in the envelope before the reference's retract phase begins.
            overload: self.r.overload_by(t + ms_us(self.tol.envelope_ms).max(ms_us(self.tol.event_ms))),
            scenario_rules: self.rules.clone(),
            phase: Some(self.r.phase_at(t)),
            sync_rule: self
                .r
                .sync_index(t)
                .and_then(|k| super::tolerance::sync_rule(&self.dialect, self.r.sync_window(k).code)),
            in_sync: self.r.sync_index(t).is_some(),
        }
    }

    /// Adds a divergence (the first [`MAX_DIVERGENCES`] are kept); its index when kept.
    pub fn push(&mut self, d: Divergence) -> Option<usize> {
        let n = self.per_check.entry(d.check.clone()).or_insert(0);
        *n += 1;
        if self.divergences.len() < MAX_DIVERGENCES && *n <= super::MAX_PER_CHECK {
            self.divergences.push(d);
            Some(self.divergences.len() - 1)
        } else {
            self.omitted += 1;
            *self.omitted_by_check.entry(d.check).or_insert(0) += 1;
            None
        }
    }

    /// Adds a divergence attributed to the rule that `topic` breaks at reference time `t`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn diverge(
        &mut self,
        topic: Topic,
        check: &'static str,
        what: String,
        t: i64,
        e: String,
        a: String,
        m: String,
    ) {
        let rule = self.attribute_now(topic, t);
        let d = Divergence::found(check, what, t, e, a, m);
        self.push_attributed(d, rule, topic, false);
    }

    /// One recorded event, time as recorded.
    pub fn event(&mut self, ev: TraceEvent) {
        self.events_seen += 1;
        if self.offset.is_none() {
            let crossing = match (&mut self.motion, &ev.event) {
                (Some(d), Event::Sample(s)) => d.sample(ev.t_us as i64, s),
                _ => None,
            };
            if let (Some(tc), Some(ra)) = (crossing, self.ref_anchor) {
                self.motion = None;
                self.offset = Some(ra - tc);
                self.anchored = true;
                for p in std::mem::take(&mut self.pending) {
                    self.aligned(&p);
                }
                self.aligned(&ev);
                return;
            }
            let hit = matches_anchor(&self.anchor, &ev.event);
            match (hit, self.ref_anchor) {
                (true, Some(ra)) => {
                    self.offset = Some(ra - ev.t_us as i64);
                    self.anchored = true;
                }
                _ if self.pending.len() >= MAX_PENDING => self.give_up_anchor(),
                _ => {
                    self.pending.push(ev);
                    return;
                }
            }
            for p in std::mem::take(&mut self.pending) {
                self.aligned(&p);
            }
        }
        self.aligned(&ev);
    }

    /// No anchor: the first recorded event is taken as the reference's time 0.
    fn give_up_anchor(&mut self) {
        let first = self.pending.first().map_or(0, |e| e.t_us as i64);
        self.offset = Some(-first);
        let what = format!("anchor ({})", self.anchor.describe());
        let ra = self.ref_anchor.map_or("absent from the reference too".into(), |t| ms(t.max(0) as u64));
        self.push(Divergence {
            rule: self.rules.first().cloned().unwrap_or_else(|| "COM-TIME-01".into()),
            check: "CHK-ALIGN-01".into(),
            what,
            t_us: self.ref_anchor,
            expected: format!("the anchor in the recorded trace (reference at {ra})"),
            actual: "not found; the first recorded event is taken as time 0".into(),
            margin: "-".into(),
        });
    }

    fn aligned(&mut self, ev: &TraceEvent) {
        let t = ev.t_us as i64 + self.offset();
        self.last_t = self.last_t.max(t);
        let w = self.tol.event_ms;
        if t < -ms_us(w) {
            return; // before the reference's start: not part of the run
        }
        let keep_until = self.r.end_us + self.r.end_us.max(2_000_000);
        match &ev.event {
            Event::Sample(s) => {
                self.samples_seen += 1;
                self.r.forget_before(t - self.floor_us);
                if self.samples_seen.is_multiple_of(128) {
                    // What the replay alongside sent with the samples, taken now and then
                    // (memory; the matcher takes what it needs before each recorded event).
                    self.take_reference_events(None);
                }
                if t >= 0 && t <= self.r.end_us {
                    if let Some(p) = self.last_sample_t {
                        self.max_gap_us = self.max_gap_us.max(t - p);
                    }
                }
                self.last_sample_t = Some(t);
                self.keys.event(t, &ev.event);
                self.sync(t, s);
                self.envelope(t, s);
                self.last_sample = Some((t, *s));
                let period = (self.r.trace.meta.sample_us as i64).max(1000);
                if t <= keep_until
                    && t >= 0
                    && self.compact_samples < MAX_COMPACT_SAMPLES
                    && self.last_kept.is_none_or(|k| t - k >= period)
                {
                    self.last_kept = Some(t);
                    self.compact_samples += 1;
                    self.compact.push(TraceEvent { t_us: t as u64, event: ev.event.clone() });
                }
                if t >= 0 && t <= keep_until {
                    let tap = self.r.tap.map(|tp| s.axes[tp.slot]);
                    self.plot(Point { t, tap, rpm: s.spindle_mrpm, sync_nm: self.cur_sync });
                }
            }
            Event::Signal { signal, value } => {
                if self.sig.get(*signal) == *value {
                    return; // a level repeated, not an edge
                }
                self.sig.set(*signal, *value);
                self.seen.set(*signal, true);
                let mut faults = Vec::new();
                self.handshake.edge(t, *signal, *value, &mut faults);
                super::handshake::report(self, faults);
                self.keys.event(t, &ev.event);
                self.take_recorded_keys();
                self.discrete(t, ev);
            }
            Event::Function { .. } => {
                self.had_functions = true;
                self.discrete(t, ev)
            }
            Event::Alarm(_) => {
                self.alarms += 1;
                self.discrete(t, ev);
            }
            Event::Phase(_) => {
                self.had_phases = true;
                self.keep(t, ev);
            }
            Event::Block { .. } => {
                self.had_blocks = true;
                self.keep(t, ev)
            }
            Event::Input { .. } => self.keep(t, ev),
            Event::End(_) => {}
        }
    }

    /// One plot point: each bucket of the series keeps its points of least and greatest tap
    /// position (spindle speed without a tap), in time order.
    fn plot(&mut self, p: Point) {
        let v = |p: &Point| p.tap.unwrap_or(p.rpm);
        match &mut self.bucket {
            Some((b0, lo, hi)) if p.t - *b0 < self.bucket_us => {
                if v(&p) < v(lo) {
                    *lo = p;
                }
                if v(&p) > v(hi) {
                    *hi = p;
                }
            }
            _ => {
                self.flush_plot();
                self.bucket = Some((p.t, p, p));
            }
        }
    }

    fn flush_plot(&mut self) {
        if let Some((_, lo, hi)) = self.bucket.take() {
            let (a, b) = if lo.t <= hi.t { (lo, hi) } else { (hi, lo) };
            self.series.push(a);
            if b.t != a.t {
                self.series.push(b);
            }
        }
    }

    /// Keeps every discrete event of the recording in the compact copy (the scenario's temporal
    /// rules run on it); without rules, only the first [`MAX_COMPACT_EVENTS`] (for the reports'
    /// diagrams, completed around the divergences by [`super::excerpt`]).
    pub fn keeping_all(mut self, all: bool) -> Self {
        self.keep_all = all;
        self
    }

    fn keep(&mut self, t: i64, ev: &TraceEvent) {
        let cap = if self.keep_all { 4 * self.r.total_events.max(10_000) } else { MAX_COMPACT_EVENTS };
        if t >= 0 && self.compact.len() < cap {
            self.compact.push(TraceEvent { t_us: t as u64, event: ev.event.clone() });
        }
    }

    fn discrete(&mut self, t: i64, ev: &TraceEvent) {
        self.keep(t, ev);
        let Some(key) = Key::of(&ev.event) else { return };
        self.take_reference_events(Some(t));
        if let Some(m) = &mut self.matcher {
            m.record(key, t, &self.tol, &mut self.findings);
        }
        self.flush_findings();
    }

    fn flush_findings(&mut self) {
        for f in std::mem::take(&mut self.findings) {
            match f {
                Finding::Late(k, tr, t, w) => super::shift::shifted(self, &k, tr, t, w),
                Finding::Missing(k @ Key::Edge(..), tr) => self.missing_edges.push((k, tr)),
                Finding::Missing(k, tr) => self.missing_other.push((k, tr)),
                Finding::Extra(k, t) if self.extras.len() < super::MAX_DIVERGENCES => {
                    self.extras.push((k, t))
                }
                Finding::Extra(k, t) => self.report_extra(k, t),
                Finding::Order(k, tr, t, before, tb) => self.diverge(
                    k.topic(),
                    "CHK-EVT-04",
                    format!("{} order", k.describe()),
                    tr,
                    format!(
                        "{} ({}) before {} ({})",
                        k.describe(),
                        ms(tr.max(0) as u64),
                        before.describe(),
                        ms(tb.max(0) as u64)
                    ),
                    format!(
                        "{} recorded at {}, after {}",
                        k.describe(),
                        ms(t.max(0) as u64),
                        before.describe()
                    ),
                    format!("{} out of order", ms((tb - tr) as u64)),
                ),
            }
        }
    }

    /// A recorded event the reference does not have (`CHK-EVT-03`).
    pub(super) fn report_extra(&mut self, k: Key, t: i64) {
        self.diverge(
            k.topic(),
            "CHK-EVT-03",
            match k {
                Key::Alarm(_) => format!("unexpected {}", k.describe()),
                _ => format!("{} extra", k.describe()),
            },
            t,
            format!("no further {}", k.describe()),
            format!("{} at {}", k.describe(), ms(t.max(0) as u64)),
            "-".into(),
        );
    }

    /// The aligned time of the last recorded event.
    pub(super) fn last_recorded_t(&self) -> i64 {
        self.last_t
    }

    /// The scenario's first rule (for findings about the whole recording).
    pub(super) fn rules_first(&self) -> String {
        self.rules.first().cloned().unwrap_or_else(|| "COM-TIME-01".into())
    }

    /// A reference event never recorded (`CHK-EVT-02`).
    pub(super) fn report_missing(&mut self, k: Key, tr: i64) {
        self.diverge(
            k.topic(),
            "CHK-EVT-02",
            format!("{} missing", k.describe()),
            tr,
            format!("{} at {}", k.describe(), ms(tr.max(0) as u64)),
            "never recorded".into(),
            "-".into(),
        );
    }

    /// The reference's own handshake faults (a reset dropping a strobe without FIN).
    pub(super) fn reference_handshake_faults(&self) -> &[super::handshake::Fault] {
        &self.ref_handshake
    }

    /// Whether the recording carries `s` (declares it, or showed an edge of it).
    pub(super) fn carries_signal(&self, s: Signal) -> bool {
        self.carried.declares(s) || self.seen.get(s)
    }

    /// Ends the stream: open runs are closed, unmatched reference events reported, key points
    /// and the final state compared. Returns the compact recorded trace and the pecks of the
    /// reference and of the recording.
    pub fn finish(&mut self) -> (Trace, (usize, usize)) {
        if self.offset.is_none() {
            self.give_up_anchor();
            for p in std::mem::take(&mut self.pending) {
                self.aligned(&p);
            }
        }
        self.flush_plot();
        let mut faults = Vec::new();
        std::mem::take(&mut self.handshake).finish(&mut faults);
        super::handshake::report(self, faults);
        self.close_sync();
        for k in 0..self.env_runs.len() {
            self.close_env(k);
        }
        if self.r.streamed {
            // The rest of the reference's events; its samples only as far as the end's check
            // looks (the final speed, ± the event window around the last recorded sample).
            let last = self.last_sample.map_or(i64::MIN, |x| x.0);
            self.r.win.borrow_mut().drain(last.saturating_add(ms_us(self.tol.event_ms)));
            self.take_reference_events(None);
        }
        if let Some(m) = self.matcher.take() {
            self.matched = m.matched;
            self.peak_waiting = m.peak_waiting;
            self.marks = m.marks();
            m.finish(&mut self.findings);
        }
        self.flush_findings();
        super::shift::resolve(self);
        super::carried::judge_missing_edges(self);
        let mut keys = std::mem::replace(&mut self.keys, KeyTracker::new(None)).finish();
        self.add_keys(1, &mut keys);
        if self.r.streamed {
            self.keycmp.ref_reversals = self.r.win.borrow().reversals.unwrap_or(0);
        }
        if let Some(at) = self.sync_notes_at.take() {
            let count = self.r.win.borrow().moves_count;
            let notes = super::carried::sync_notes(self.r, &self.carried, count.0, |slot| count.1[slot]);
            let at = at.min(self.not_comparable.len());
            self.not_comparable.splice(at..at, notes);
        }
        let pecks = self.keycmp.pecks();
        self.records_held = self.peak_waiting + self.keycmp.peak + self.r.win.borrow().held_peak;
        if super::carried::key_points_comparable(self) {
            std::mem::take(&mut self.keycmp).finish(self, keys.reversals);
        }
        if self.carried.rpm {
            self.end_state();
        }
        self.attribute_late();
        (self.compact_trace(), pecks)
    }

    fn end_state(&mut self) {
        let Some(end) = self.r.trace.end() else { return };
        let Some((t, s)) = self.last_sample else { return };
        // The reference's speed when the recording stops (its final speed after its last
        // sample), over ± the event window: the two clocks are tied by an event recorded within
        // its window, so a spindle still ramping there may be anywhere in that range.
        let w = ms_us(self.tol.event_ms);
        let speed = |x: i64| match self.r.last_sample_t {
            Some(tl) if x < tl => self.r.value_at(x, |q| q.spindle_mrpm).map_or(0, |v| v.round() as i64),
            _ => end.state.spindle_mrpm,
        };
        let (mut lo, mut hi) = (speed(t - w).min(speed(t + w)), speed(t - w).max(speed(t + w)));
        if let Some((a, b)) = self.r.speed_range(t - w, t + w) {
            lo = lo.min(a);
            hi = hi.max(b);
        }
        let want = speed(t);
        let tol = (self.tol.speed_rpm * 1000.0).round() as i64;
        let excess = (lo - s.spindle_mrpm).max(s.spindle_mrpm - hi) - tol;
        if excess > 0 {
            let range = if lo == hi {
                format!("{} rpm ± {}", fixed(want, 3), self.tol.speed_rpm)
            } else {
                format!(
                    "{} rpm ± {} (between {} and {} rpm over ± {} ms)",
                    fixed(want, 3),
                    self.tol.speed_rpm,
                    fixed(lo, 3),
                    fixed(hi, 3),
                    self.tol.event_ms
                )
            };
            self.diverge(
                Topic::End,
                "CHK-END-01",
                "final spindle speed".into(),
                t.min(self.r.end_us),
                range,
                format!("{} rpm", fixed(s.spindle_mrpm, 3)),
                format!("{} rpm", fixed(excess, 3)),
            );
        }
    }

    fn compact_trace(&mut self) -> Trace {
        let mut events = std::mem::take(&mut self.compact);
        // What the recording does not carry and the scenario's rules are framed by (phases,
        // blocks, functions: `while: {phase: ...}`, `after: {block: N}`) comes from the
        // reference, each event moved to the recorded time of a matched event that marks it (an
        // edge at the same reference time): the recording's own boundaries.
        let want = |e: &Event| match e {
            Event::Phase(_) => !self.had_phases,
            Event::Block { .. } => !self.had_blocks,
            Event::Function { .. } => !self.had_functions,
            _ => false,
        };
        let mut prev = 0;
        let room = if self.keep_all { usize::MAX } else { MAX_COMPACT_EVENTS.saturating_sub(events.len()) };
        for e in self.r.trace.events.iter().filter(|e| want(&e.event)).take(room) {
            let t = e.t_us as i64;
            let k = self.marks.partition_point(|m| m.0 < t);
            let at = match self.marks.get(k) {
                Some(&(tr, tq)) if tr == t => tq,
                _ => t,
            };
            prev = at.max(prev).max(0);
            events.push(TraceEvent { t_us: prev as u64, event: e.event.clone() });
        }
        events.sort_by_key(|e| e.t_us);
        let state = self.last_sample.map(|x| x.1).unwrap_or_default();
        let reason = self.r.trace.end().map_or(nc_engine::trace::EndReason::Stopped, |e| e.reason.clone());
        let t_end = self.last_t.max(events.last().map_or(0, |e| e.t_us as i64)).max(0) as u64;
        events.push(TraceEvent {
            t_us: t_end,
            event: Event::End(Box::new(EndSummary {
                reason,
                state,
                command: state.axes,
                signals: self.sig,
                modal: Vec::new(),
                alarms: self.alarms,
                blocks: 0,
            })),
        });
        Trace { meta: self.r.trace.meta.clone(), events }
    }
}

/// Whether `ev` is the anchor.
fn matches_anchor(a: &Anchor, ev: &Event) -> bool {
    match (a, ev) {
        (Anchor::Function(l, c), Event::Function { letter, code }) => l == letter && c == code,
        (Anchor::Edge(s, v), Event::Signal { signal, value }) => s == signal && v == value,
        _ => false,
    }
}
