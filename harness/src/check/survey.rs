//! The passes over the reference run that index it without keeping its samples: the first keeps
//! its discrete events (the "skeleton"; lean, a summary of them only) and finds the tap; the
//! second, knowing the tap, reads its key points and the figures of its synchronised moves
//! (`check::sync`; read in the first when it can be, `survey_fused`; lean, alongside the
//! comparison, `check::sync_stream`). The comparison then reads the samples again through a
//! sliding [`super::window::Window`].
//!
//! A [`Source`] is a reference run that can be replayed as often as needed: a trace in memory,
//! or the engine run again (it is deterministic), through the engine's public API.

use nc_engine::trace::{
    Event, Phase, Sample, Signal, Signals, Trace, TraceEvent, TraceMeta, TraceSink, AXES,
};

use super::keypoints::{KeyPoints, KeyTracker};
use super::reference::{unwrap_delta, Tap};

/// A reference run, replayable.
#[derive(Clone, Copy)]
pub enum Source<'a> {
    /// A trace in memory.
    Trace(&'a Trace),
    /// A run into a sink (the engine: `machine.run(&program, &opts, sink)`).
    Run(&'a (dyn Fn(&mut dyn TraceSink) + Sync)),
}

impl Source<'_> {
    /// Replays the run into `sink` (stopping when the sink asks to).
    pub fn replay(&self, sink: &mut dyn TraceSink) {
        match self {
            Source::Trace(t) => {
                sink.start(&t.meta);
                for e in &t.events {
                    if sink.wants_stop() {
                        break;
                    }
                    sink.event(e);
                }
            }
            Source::Run(f) => f(sink),
        }
    }
}

/// The first pass: the discrete events, the tap and what the samples say as a whole.
#[derive(Default)]
pub struct Skeleton {
    /// The header.
    pub meta: Option<TraceMeta>,
    /// Every event but the samples (lean: the end only).
    pub events: Vec<TraceEvent>,
    /// What the comparison needs of the discrete events as a whole (complete at the end).
    pub summary: super::events::Summary,
    /// Every event, samples included.
    pub total: usize,
    /// The time of the last event.
    pub end_us: i64,
    /// The time of the last sample.
    pub last_sample_t: Option<i64>,
    /// The spindle turns at some sample.
    pub spindle_turns: bool,
    /// Each axis is somewhere else than at the first sample at some sample.
    pub moves: [bool; AXES],
    /// The phases by time (lean: none, the comparison reads them alongside).
    pub phases: Vec<(i64, Phase)>,
    /// The first overload retract's time.
    pub first_overload: Option<i64>,
    /// The reference cuts (a `cutting` phase) at some time.
    pub cuts: bool,
    /// The inputs by time (name, value).
    pub inputs: Vec<(i64, String, String)>,
    /// Only the end is kept in `events` (only the scenario's temporal rules need the phases,
    /// blocks and inputs there, which are in their own lists or planned; the edges, functions and
    /// alarms are summed up in `summary` and given to the comparison again by the replay
    /// alongside).
    lean: bool,
    planner: Option<super::sync::Planner>,
    first: Option<Sample>,
    tap: TapFinder,
    /// The second pass read in this one (`None`: not tried, or given up).
    fused: Option<Box<super::survey_fused::Fused>>,
}

impl TraceSink for Skeleton {
    fn start(&mut self, meta: &TraceMeta) {
        self.meta = Some(meta.clone());
        let mut planner = super::sync::Planner::new(meta.dialect);
        if self.fused.is_some() {
            planner.edges = Some(Vec::new());
        }
        if self.lean {
            // The moves are read alongside the comparison: only whether there are lead blocks.
            planner = planner.without_list();
        }
        self.planner = Some(planner);
    }
    fn event(&mut self, ev: &TraceEvent) {
        self.total += 1;
        self.end_us = ev.t_us as i64;
        match &ev.event {
            Event::Sample(s) => {
                let t = ev.t_us as i64;
                self.last_sample_t = Some(t);
                self.spindle_turns |= s.spindle_mrpm != 0;
                let f = self.first.get_or_insert(*s);
                // Axis by axis, an axis known to move not read again: read whole (16-byte
                // loads), the sample the engine has just written stalls (store forwarding).
                for (k, m) in self.moves.iter_mut().enumerate() {
                    if !*m && s.axes[k] != f.axes[k] {
                        *m = true;
                    }
                }
                self.tap.sample(t, s);
                if let Some(f) = &mut self.fused {
                    if !f.sample(t, s, &self.tap, &self.meta) {
                        self.fused = None;
                    }
                }
            }
            e => {
                self.summary.event(ev.t_us as i64, e);
                match e {
                    Event::Signal { signal, value } => self.tap.signal(*signal, *value),
                    Event::Phase(p) => {
                        if *p == Phase::OverloadRetract {
                            self.first_overload.get_or_insert(ev.t_us as i64);
                        }
                        self.cuts |= *p == Phase::Cutting;
                        if !self.lean {
                            self.phases.push((ev.t_us as i64, *p));
                        }
                    }
                    Event::Input { name, value } => {
                        self.inputs.push((ev.t_us as i64, name.clone(), value.clone()))
                    }
                    _ => {}
                }
                let planner = self.planner.get_or_insert_with(Default::default);
                planner.event(ev);
                if let Some(f) = &mut self.fused {
                    let edges = planner.edges.as_mut().map(std::mem::take).unwrap_or_default();
                    if !f.event(ev, &edges, &self.tap, &self.meta) {
                        self.fused = None;
                    }
                    if let Some(e) = planner.edges.as_mut() {
                        *e = edges;
                        e.clear();
                    }
                }
                if !self.lean || matches!(e, Event::End(_)) {
                    self.events.push(ev.clone());
                }
            }
        }
    }
}

impl Skeleton {
    /// The first pass over `source`.
    pub fn of(source: Source) -> Skeleton {
        Skeleton::of_lean(source, false)
    }

    /// [`Skeleton::of`], keeping only the end among [`Skeleton::events`] when `lean` (a
    /// comparison without temporal rules: memory does not follow the number of events).
    pub fn of_lean(source: Source, lean: bool) -> Skeleton {
        // A lean pass reads no key points and no spans (the comparison reads them alongside).
        let fused = (!lean).then(Box::default);
        let mut sk = Skeleton { lean, fused, ..Skeleton::default() };
        source.replay(&mut sk);
        sk.summary.finish();
        sk
    }

    /// Whether the run has thread blocks found by their lead (KND G32 without phases): their
    /// moves are not read alongside the comparison.
    pub fn has_lead_blocks(&self) -> bool {
        self.planner.as_ref().is_some_and(|p| p.has_lead_blocks())
    }

    /// Whether only the end was kept in [`Skeleton::events`].
    pub fn is_lean(&self) -> bool {
        self.lean
    }

    /// The synchronised moves planned from the discrete events read (`sync::plan`).
    pub fn plan(&mut self) -> super::sync::Plan {
        self.planner.take().unwrap_or_default().finish(self.end_us)
    }

    /// The end of the run (None: it has none).
    pub fn end(&self) -> Option<&nc_engine::trace::EndSummary> {
        match self.events.last().map(|e| &e.event) {
            Some(Event::End(s)) => Some(s),
            _ => None,
        }
    }

    /// The discrete events as a trace (its last event the end).
    pub fn trace(&mut self) -> Trace {
        self.events.shrink_to_fit();
        Trace {
            meta: self.meta.clone().unwrap_or(TraceMeta {
                dialect: "",
                axes: Vec::new(),
                period_us: 0,
                sample_us: 0,
            }),
            events: std::mem::take(&mut self.events),
        }
    }

    /// What the second pass ([`Survey`]) would give for `plan` (the key points and the plan's
    /// spans), read in this one; `None` when it could not be (the tap guessed from the first
    /// stroke was not the run's, the plan has lead blocks, or too many events came before the
    /// first stroke): the second pass is then needed. A lean pass reads neither (the comparison
    /// reads them alongside): `None`.
    pub fn fused_survey(
        &mut self,
        tap: Option<Tap>,
        plan: &super::sync::Plan,
    ) -> Option<(KeyPoints, Vec<Span>)> {
        self.fused.take()?.finish(tap, plan)
    }

    /// The tap axis: the axis that travels furthest while RGSPP or RGSPM is on; its lead from the
    /// travel over the signed revolutions of every stroke; the first stroke's signal and
    /// direction.
    pub fn tap(&self) -> Option<Tap> {
        let axes = self.meta.as_ref().map(|m| m.axes.as_slice()).unwrap_or(&[]);
        self.tap.finish(axes)
    }
}

/// One run of consecutive samples inside a stroke.
#[derive(Clone, Copy)]
struct Seg {
    first: Sample,
    last: (i64, Sample),
    rev_mdeg: f64,
}

/// What the closed segments say for each axis that may be the tap's: the signed travel over
/// the revolutions of those with more than a quarter turn, the first direction of travel (in
/// memory the same whatever the number of strokes).
#[derive(Clone, Copy, Default)]
struct LeadSums {
    lead: [f64; AXES],
    rev: f64,
    into: [i64; AXES],
}

impl LeadSums {
    /// Adds one segment (in stroke order: the sums are those of the segments one by one).
    fn add(&mut self, seg: &Seg) {
        let r = seg.rev_mdeg / 360_000.0;
        for slot in 0..AXES {
            let d = (seg.last.1.axes[slot] - seg.first.axes[slot]) as f64;
            if self.into[slot] == 0 && d != 0.0 {
                self.into[slot] = if d > 0.0 { 1 } else { -1 };
            }
            if r.abs() > 0.25 {
                self.lead[slot] += d * r.signum();
            }
        }
        if r.abs() > 0.25 {
            self.rev += r.abs();
        }
    }
}

/// Finds the tap while the run streams by (see [`Skeleton::tap`]).
#[derive(Default)]
pub(super) struct TapFinder {
    sig: Signals,
    first: Option<Signal>,
    /// The segment being read.
    seg: Option<Seg>,
    /// The segments before it.
    sums: LeadSums,
    open: bool,
    travel: [i64; AXES],
}

impl TapFinder {
    fn signal(&mut self, signal: Signal, value: bool) {
        if matches!(signal, Signal::Rgspp | Signal::Rgspm) && value {
            self.first.get_or_insert(signal);
            self.open = false; // every stroke is its own segment
        }
        self.sig.set(signal, value);
    }

    fn sample(&mut self, t: i64, s: &Sample) {
        if !(self.sig.get(Signal::Rgspp) || self.sig.get(Signal::Rgspm)) {
            self.open = false;
            return;
        }
        if !self.open {
            if let Some(done) = self.seg.replace(Seg { first: *s, last: (t, *s), rev_mdeg: 0.0 }) {
                self.sums.add(&done);
            }
            self.open = true;
            return;
        }
        let Some(seg) = &mut self.seg else { return };
        let (tp, p) = seg.last;
        for (a, tr) in self.travel.iter_mut().enumerate() {
            *tr += (s.axes[a] - p.axes[a]).abs();
        }
        seg.rev_mdeg += unwrap_delta(p.spindle_mdeg, p.spindle_mrpm, s.spindle_mdeg, s.spindle_mrpm, t - tp);
        seg.last = (t, *s);
    }

    /// A stroke was read and the tap finder is not inside one now.
    pub(super) fn between_strokes(&self) -> bool {
        self.seg.is_some() && !self.open
    }

    pub(super) fn finish(&self, axes: &[nc_engine::trace::AxisSpec]) -> Option<Tap> {
        let in_signal = self.first?;
        let travel = self.travel;
        let slot = (0..AXES).max_by_key(|&a| travel[a])?;
        if travel[slot] == 0 {
            return None;
        }
        let diameter = axes.iter().any(|a| a.index == slot && a.diameter);
        let mut sums = self.sums;
        if let Some(seg) = &self.seg {
            sums.add(seg);
        }
        let (lead_sum, rev_sum, into_sign) = (sums.lead[slot], sums.rev, sums.into[slot]);
        if rev_sum < 0.25 {
            return None;
        }
        let lead_nm = lead_sum / rev_sum / if diameter { 2.0 } else { 1.0 };
        Some(Tap {
            slot,
            diameter,
            lead_nm,
            in_signal,
            into_sign: if into_sign == 0 { 1 } else { into_sign },
        })
    }
}

/// What the second pass found about one interval [t0, t1] of the reference.
#[derive(Debug, Clone, Default)]
pub struct Span {
    /// Travel of each axis over the samples within it (sum of |steps|), nm.
    pub travel: [i64; AXES],
    /// Every axis at t0 and at t1, interpolated as `Reference::pos_at` does (None: no sample).
    pub ends: [Option<[f64; AXES]>; 2],
}

impl Span {
    /// The axis that travels furthest in it (None: none moves), as `Reference::furthest_axis`.
    pub fn furthest(&self) -> Option<usize> {
        let slot = (0..AXES).max_by_key(|&a| self.travel[a])?;
        (self.travel[slot] > 0).then_some(slot)
    }
}

/// A thread block the reference ran without phase events: its parts where the axis that travels
/// furthest advances `lead_mm` per spindle revolution (see `sync::by_lead`).
#[derive(Debug, Clone)]
pub struct LeadBlock {
    /// Start and end of the block.
    pub t0: i64,
    /// End.
    pub t1: i64,
    /// The block's F, mm per revolution.
    pub lead_mm: f64,
}

/// One locked part of a lead block for one candidate axis: (start, end) at sample times, the
/// span over it.
type LeadPart = (i64, i64, Span);

#[derive(Default, Clone)]
struct LeadState {
    span: Span,
    prev: Option<(i64, Sample, f64)>,
    open: [Option<(i64, Span)>; AXES],
    parts: [Vec<LeadPart>; AXES],
}

/// The second pass: key points and the spans of the synchronised moves.
pub struct Survey {
    keys: KeyTracker,
    spans: Vec<(i64, i64)>,
    out: Vec<Span>,
    /// Spans started and not yet past their end, each with its last sample within it (memory
    /// follows the spans open at once, not all of them).
    active: Vec<(usize, Option<Sample>)>,
    next: usize,
    /// Spans sorted by start (indices into `spans`).
    order: Vec<usize>,
    lead: Vec<LeadBlock>,
    lead_state: Vec<LeadState>,
    div: [f64; AXES],
    prev: Option<(i64, Sample)>,
    cum: Option<(i64, Sample, f64)>,
}

/// `v0 + (v1 − v0) · f` at `t` between the samples `p` (at or before `t`) and `n`, as
/// `Reference::value_at`.
pub(super) fn interp(p: &(i64, Sample), n: (i64, &Sample), t: i64) -> [f64; AXES] {
    let f = (t - p.0) as f64 / (n.0 - p.0).max(1) as f64;
    let mut out = [0.0; AXES];
    for (k, o) in out.iter_mut().enumerate() {
        let v0 = p.1.axes[k] as f64;
        *o = v0 + (n.1.axes[k] as f64 - v0) * f;
    }
    out
}

/// The sample `s` at `t` read into the spans `active` (each with its last sample within it) of
/// `spans`, their figures in `out`; `prev` is the sample before. A span leaves `active` at the
/// first sample past its end.
pub(super) fn track_spans(
    active: &mut Vec<(usize, Option<Sample>)>,
    spans: &[(i64, i64)],
    out: &mut [Span],
    prev: &Option<(i64, Sample)>,
    t: i64,
    s: &Sample,
) {
    active.retain_mut(|(i, in_span)| {
        let i = *i;
        let (t0, t1) = spans[i];
        let o = &mut out[i];
        for (k, tk) in [t0, t1].into_iter().enumerate() {
            if o.ends[k].is_none() && t > tk {
                o.ends[k] = Some(match prev {
                    Some(p) => interp(p, (t, s), tk),
                    None => held(s),
                });
            }
        }
        if t0 <= t && t <= t1 {
            if let Some(p) = in_span {
                for (a, tr) in o.travel.iter_mut().enumerate() {
                    *tr += (s.axes[a] - p.axes[a]).abs();
                }
            }
            *in_span = Some(*s);
        }
        t <= t1
    });
}

pub(super) fn held(s: &Sample) -> [f64; AXES] {
    let mut out = [0.0; AXES];
    for (k, o) in out.iter_mut().enumerate() {
        *o = s.axes[k] as f64;
    }
    out
}

impl Survey {
    /// A pass for the reference's tap, reading the spans `spans` and the lead blocks `lead`.
    pub fn new(
        tap: Option<Tap>,
        spans: Vec<(i64, i64)>,
        lead: Vec<LeadBlock>,
        meta_axes: &[nc_engine::trace::AxisSpec],
    ) -> Survey {
        let mut order: Vec<usize> = (0..spans.len()).collect();
        order.sort_by_key(|&i| spans[i].0);
        let mut div = [1.0; AXES];
        for a in meta_axes.iter().filter(|a| a.diameter) {
            div[a.index] = 2.0;
        }
        Survey {
            keys: KeyTracker::new(tap),
            out: vec![Span::default(); spans.len()],
            spans,
            active: Vec::new(),
            next: 0,
            order,
            lead_state: vec![LeadState::default(); lead.len()],
            lead,
            div,
            prev: None,
            cum: None,
        }
    }

    fn sample(&mut self, t: i64, s: &Sample) {
        while self.next < self.order.len() && self.spans[self.order[self.next]].0 <= t {
            self.active.push((self.order[self.next], None));
            self.next += 1;
        }
        track_spans(&mut self.active, &self.spans, &mut self.out, &self.prev, t, s);
        // Spans that start after the first sample but whose ends come before it cannot occur
        // (they are activated at their start); a span starting before the first sample gets
        // the first sample held for its start (above, `prev` None).
        let acc = match self.cum {
            None => s.spindle_mdeg as f64,
            Some((tp, p, acc)) => {
                acc + unwrap_delta(p.spindle_mdeg, p.spindle_mrpm, s.spindle_mdeg, s.spindle_mrpm, t - tp)
            }
        };
        self.cum = Some((t, *s, acc));
        for (b, st) in self.lead.iter().zip(self.lead_state.iter_mut()) {
            if t < b.t0 || t > b.t1 {
                continue;
            }
            if let Some((tp, p, ap)) = st.prev {
                for (a, tr) in st.span.travel.iter_mut().enumerate() {
                    *tr += (s.axes[a] - p.axes[a]).abs();
                }
                let want = b.lead_mm * 1e6;
                let dr = (acc - ap).abs() / 360_000.0;
                for k in 0..AXES {
                    let dp = (s.axes[k] - p.axes[k]).abs() as f64 / self.div[k];
                    let locked = dp > 100.0 && dr > 1e-6 && ((dp / dr) - want).abs() <= 0.03 * want;
                    match (locked, &mut st.open[k]) {
                        (true, None) => {
                            let mut span = Span { ends: [Some(held(&p)), None], ..Span::default() };
                            for (a, tr) in span.travel.iter_mut().enumerate() {
                                *tr += (s.axes[a] - p.axes[a]).abs();
                            }
                            st.open[k] = Some((tp, span));
                        }
                        (true, Some((_, span))) => {
                            for (a, tr) in span.travel.iter_mut().enumerate() {
                                *tr += (s.axes[a] - p.axes[a]).abs();
                            }
                        }
                        (false, Some(_)) => {
                            if let Some((a0, mut span)) = st.open[k].take() {
                                span.ends[1] = Some(held(&p));
                                st.parts[k].push((a0, tp, span));
                            }
                        }
                        (false, None) => {}
                    }
                }
            }
            st.prev = Some((t, *s, acc));
        }
        self.prev = Some((t, *s));
    }

    /// The key points, the spans (in the order given) and, for each lead block, its locked
    /// parts (start, end, span) of the axis that travels furthest in it.
    pub fn finish(mut self) -> (KeyPoints, Vec<Span>, Vec<Vec<LeadPart>>) {
        let last = self.prev.map(|p| held(&p.1));
        for o in &mut self.out {
            for e in &mut o.ends {
                if e.is_none() {
                    *e = last;
                }
            }
        }
        let mut lead_out = Vec::new();
        for mut st in self.lead_state {
            let Some(slot) = st.span.furthest() else {
                lead_out.push(Vec::new());
                continue;
            };
            let mut parts = std::mem::take(&mut st.parts[slot]);
            if let (Some((a0, mut span)), Some((tl, p, _))) = (st.open[slot].take(), st.prev) {
                span.ends[1] = Some(held(&p));
                parts.push((a0, tl, span));
            }
            parts.retain(|w| w.1 - w.0 >= 20_000);
            lead_out.push(parts);
        }
        (self.keys.finish(), self.out, lead_out)
    }
}

impl TraceSink for Survey {
    fn start(&mut self, _meta: &TraceMeta) {}
    fn event(&mut self, ev: &TraceEvent) {
        let t = ev.t_us as i64;
        self.keys.event(t, &ev.event);
        if let Event::Sample(s) = &ev.event {
            self.sample(t, s);
        }
    }
}
