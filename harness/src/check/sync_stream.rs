//! The reference's synchronised moves and phases read as the run streams by, for a comparison
//! that keeps no list of them (without temporal rules): the replay alongside the comparison
//! reads them with its samples ([`SyncStream`], sent with the samples' batches), and the
//! comparison holds only those around the recorded time. A divergence found at a time whose
//! moves and phases are no longer held is attributed at the end, in one more replay
//! ([`Sweep`]).
//!
//! The moves are those of `sync::plan` and `sync::build` (the same planner, the same span
//! figures as `survey::track_spans`, the same choice of axis, numbered in time order), given in
//! time order once every move that starts earlier is known.

use std::collections::VecDeque;

use nc_engine::trace::{AxisSpec, Event, Phase, Sample, TraceEvent, TraceMeta, TraceSink};

use super::reference::Tap;
use super::survey::{held, interp, Span};
use super::sync::{Kind, MoveKind, Planner, Window};

/// One synchronised move being read.
struct Track {
    t0: i64,
    /// Its end (`i64::MAX` while open).
    t1: i64,
    which: usize,
    kind: MoveKind,
    span: Span,
    /// Its last sample within it.
    last_in: Option<Sample>,
    /// Its rank among the closings (`u64::MAX` while open).
    seq: u64,
    /// Its figures are complete (a sample past its end was read, or the run ended).
    done: bool,
}

/// Reads the synchronised moves and the phases of a run (see the module's text).
pub(crate) struct SyncStream {
    planner: Planner,
    tap: Option<Tap>,
    axes: Vec<AxisSpec>,
    tracks: Vec<Track>,
    seq: u64,
    prev: Option<(i64, Sample)>,
    counts: [usize; 3],
    t_last: i64,
    ended: bool,
    /// The moves found, in time order, not yet taken.
    pub out: Vec<Window>,
    /// The phases read, not yet taken.
    pub phases: Vec<(i64, Phase)>,
}

impl SyncStream {
    /// A reader for the reference's tap `tap` (a rigid stroke's axis).
    pub(crate) fn new(tap: Option<Tap>) -> SyncStream {
        SyncStream {
            planner: Planner::default(),
            tap,
            axes: Vec::new(),
            tracks: Vec::new(),
            seq: 0,
            prev: None,
            counts: [0; 3],
            t_last: i64::MIN,
            ended: false,
            out: Vec::new(),
            phases: Vec::new(),
        }
    }

    /// Every move starting before this time has been given ([`SyncStream::out`]).
    pub(crate) fn complete(&self) -> i64 {
        if self.ended {
            return i64::MAX;
        }
        self.tracks.iter().map(|x| x.t0).fold(self.t_last, i64::min)
    }

    /// A sample at `t`, `prev` the one before it.
    fn sample(&mut self, t: i64, s: &Sample, prev: Option<(i64, &Sample)>) {
        if self.tracks.is_empty() {
            return;
        }
        let mut done = false;
        for x in self.tracks.iter_mut().filter(|x| !x.done) {
            let o = &mut x.span;
            for (k, tk) in [x.t0, x.t1].into_iter().enumerate() {
                if o.ends[k].is_none() && t > tk {
                    o.ends[k] = Some(match prev {
                        Some((pt, p)) => interp(&(pt, *p), (t, s), tk),
                        None => held(s),
                    });
                }
            }
            if x.t0 <= t && t <= x.t1 {
                if let Some(p) = x.last_in {
                    for (a, tr) in o.travel.iter_mut().enumerate() {
                        *tr += (s.axes[a] - p.axes[a]).abs();
                    }
                }
                x.last_in = Some(*s);
            }
            if t > x.t1 {
                x.done = true;
                done = true;
            }
        }
        if done {
            self.give();
        }
    }

    /// The moves the last discrete event opened or closed, `prev` the last sample before it.
    fn edges(&mut self, prev: Option<(i64, &Sample)>) {
        let edges = self.planner.edges.as_mut().map(std::mem::take).unwrap_or_default();
        for e in &edges {
            if e.open {
                // A sample at the opening's time read before it is the move's first.
                let first = prev.filter(|p| p.0 >= e.t).map(|p| *p.1);
                self.tracks.push(Track {
                    t0: e.t,
                    t1: i64::MAX,
                    which: e.which,
                    kind: e.kind,
                    span: Span::default(),
                    last_in: first,
                    seq: u64::MAX,
                    done: false,
                });
            } else if let Some(x) = self.tracks.iter_mut().find(|x| x.which == e.which && x.seq == u64::MAX) {
                x.t1 = e.t;
                x.seq = self.seq;
                self.seq += 1;
            }
        }
        if let Some(e) = self.planner.edges.as_mut() {
            *e = edges;
            e.clear();
        }
    }

    /// Gives the moves whose figures are complete and before which no other can start.
    fn give(&mut self) {
        loop {
            let key = |x: &Track| (x.t0, x.seq);
            let Some(i) =
                (0..self.tracks.len()).filter(|&i| self.tracks[i].done).min_by_key(|&i| key(&self.tracks[i]))
            else {
                return;
            };
            let k = key(&self.tracks[i]);
            if self.tracks.iter().any(|x| !x.done && key(x) < k) {
                return;
            }
            let x = self.tracks.remove(i);
            let (kind, locked, code) = x.kind;
            let slot = match kind {
                Kind::Stroke => self.tap.map(|tp| tp.slot),
                _ => x.span.furthest(),
            };
            let Some(slot) = slot else { continue };
            let end = |i: usize| x.span.ends[i].map_or(0.0, |e| e[slot]);
            let div = if self.axes.iter().any(|a| a.index == slot && a.diameter) { 2.0 } else { 1.0 };
            self.counts[kind as usize] += 1;
            let n = self.counts[kind as usize];
            self.out.push(Window {
                t0: x.t0,
                t1: x.t1,
                slot,
                div,
                kind,
                locked,
                n,
                code,
                ends: [end(0), end(1)],
            });
        }
    }

    /// The end of the run: the moves still open end with it.
    pub(crate) fn finish(&mut self) {
        let last = self.prev.map(|p| p.1);
        self.finish_after(last.as_ref());
    }

    /// [`SyncStream::finish`], `last` the run's last sample (read by [`SyncStream::event_after`]).
    pub(crate) fn finish_after(&mut self, last: Option<&Sample>) {
        if self.ended {
            return;
        }
        for w in [1, 0] {
            if let Some(x) = self.tracks.iter_mut().find(|x| x.which == w && x.seq == u64::MAX) {
                x.seq = self.seq;
                self.seq += 1;
            }
        }
        let last = last.map(held);
        for x in &mut self.tracks {
            for e in &mut x.span.ends {
                if e.is_none() {
                    *e = last;
                }
            }
            x.done = true;
        }
        self.give();
        self.ended = true;
    }
}

impl SyncStream {
    /// The next event of the run, `prev` the last sample before it (its reader keeps it: no
    /// copy of every sample here).
    pub(crate) fn event_after(&mut self, ev: &TraceEvent, prev: Option<(i64, &Sample)>) {
        let t = ev.t_us as i64;
        self.t_last = t;
        match &ev.event {
            Event::Sample(s) => self.sample(t, s, prev),
            e => {
                if let Event::Phase(p) = e {
                    self.phases.push((t, *p));
                }
                self.planner.event(ev);
                self.edges(prev);
            }
        }
    }
}

impl TraceSink for SyncStream {
    fn start(&mut self, meta: &TraceMeta) {
        self.axes = meta.axes.clone();
        let mut planner = Planner::new(meta.dialect).without_list();
        planner.edges = Some(Vec::new());
        self.planner = planner;
    }
    fn event(&mut self, ev: &TraceEvent) {
        let prev = self.prev;
        self.event_after(ev, prev.as_ref().map(|p| (p.0, &p.1)));
        if let Event::Sample(s) = &ev.event {
            self.prev = Some((ev.t_us as i64, *s));
        }
    }
}

/// What attribution needs of the reference at one time: its phase, and the G code of the
/// synchronised move it is in (`Some(None)`: a move without one, a rigid stroke).
pub(crate) type Moment = (Phase, Option<Option<&'static str>>);

/// The reference's phase and synchronised move at the given times (sorted), read in one more
/// replay.
pub(crate) struct Sweep {
    s: SyncStream,
    times: Vec<i64>,
    next: usize,
    windows: VecDeque<Window>,
    phases: VecDeque<(i64, Phase)>,
    /// The answers, in the order of the times.
    pub out: Vec<Moment>,
}

impl Sweep {
    /// A sweep for the reference's tap `tap` at `times` (sorted).
    pub(crate) fn new(tap: Option<Tap>, times: Vec<i64>) -> Sweep {
        Sweep {
            s: SyncStream::new(tap),
            times,
            next: 0,
            windows: VecDeque::new(),
            phases: VecDeque::new(),
            out: Vec::new(),
        }
    }

    fn answer(&mut self, all: bool) {
        self.windows.extend(self.s.out.drain(..));
        self.phases.extend(self.s.phases.drain(..));
        while let Some(&t) = self.times.get(self.next) {
            if !all && (self.s.complete() <= t || self.s.t_last <= t) {
                return;
            }
            let (w, p) = moment(&self.windows, &self.phases, t);
            // Later times look from here on.
            self.windows.drain(..w);
            self.phases.drain(..p);
            let k = self.windows.partition_point(|x| x.t0 <= t);
            let sync = k.checked_sub(1).filter(|&i| t <= self.windows[i].t1).map(|i| self.windows[i].code);
            let phase = self.phases.iter().take_while(|x| x.0 <= t).last().map_or(Phase::Idle, |x| x.1);
            self.out.push((phase, sync));
            self.next += 1;
        }
    }

    /// Replays `source` until every time is answered.
    pub(crate) fn run(mut self, source: super::survey::Source) -> Vec<Moment> {
        source.replay(&mut self);
        self.s.finish();
        self.answer(true);
        self.out
    }
}

/// How many of `windows` and `phases` come before the last of each at or before `t` (those a
/// later time does not need).
fn moment(windows: &VecDeque<Window>, phases: &VecDeque<(i64, Phase)>, t: i64) -> (usize, usize) {
    let w = windows.partition_point(|x| x.t0 <= t).saturating_sub(1);
    let p = phases.partition_point(|x| x.0 <= t).saturating_sub(1);
    (w, p)
}

impl TraceSink for Sweep {
    fn start(&mut self, meta: &TraceMeta) {
        self.s.start(meta);
    }
    fn event(&mut self, ev: &TraceEvent) {
        self.s.event(ev);
        let due = self.times.get(self.next).is_some_and(|&t| self.s.t_last > t);
        if !matches!(ev.event, Event::Sample(_)) || !self.s.out.is_empty() || due {
            self.answer(false);
        }
    }
    fn wants_stop(&self) -> bool {
        self.next >= self.times.len()
    }
}

#[cfg(test)]
mod tests {
    use super::{Sweep, SyncStream};
    use crate::check::reference::Reference;
    use crate::check::survey::Source;
    use nc_engine::{Machine, RunOptions};

    /// The moves read as the run streams by are those the whole reference gives
    /// (`sync::build` over the first pass's plan), in the same order and numbering, for every
    /// kind of synchronised move but the thread blocks found by their lead (KND, left to the
    /// whole first pass); the phase and the move at every sample time, read by a sweep, are
    /// those of the whole reference.
    #[test]
    fn moves_read_as_the_run_streams_by_are_the_whole_references() {
        for (dialect, text) in crate::check::sync::test_programs() {
            let m = Machine::new(dialect).unwrap();
            let trace = m.run_to_trace(&m.parse(&text).unwrap(), &RunOptions::default());
            let whole = Reference::new(&trace);
            let mut s = SyncStream::new(whole.tap);
            Source::Trace(&trace).replay(&mut s);
            s.finish();
            if dialect == "knd-lathe" {
                continue;
            }
            assert!(!whole.sync.is_empty(), "{dialect}: {text}");
            assert_eq!(format!("{:?}", s.out), format!("{:?}", whole.sync), "{dialect}: {text}");
            let times: Vec<i64> = trace.events.iter().map(|e| e.t_us as i64).step_by(7).collect();
            let moments = Sweep::new(whole.tap, times.clone()).run(Source::Trace(&trace));
            assert_eq!(moments.len(), times.len());
            for (t, (phase, sync)) in times.into_iter().zip(moments) {
                assert_eq!(phase, whole.phase_at(t), "{dialect} at {t}");
                assert_eq!(sync, whole.sync_index(t).map(|k| whole.sync[k].code), "{dialect} at {t}");
            }
        }
    }
}
