//! The reference's samples as a sliding window: pulled on demand from the reference run (a
//! trace in memory, or the engine running on another thread), dropped once the comparison has
//! moved past them. A comparison of any length holds only the samples around the recorded time
//! (± the widest window of the tolerances), never the whole run.

use std::sync::mpsc::{Receiver, SyncSender};

use nc_engine::trace::{Event, Sample, TraceEvent, TraceMeta, TraceSink};

use std::collections::VecDeque;

use nc_engine::trace::{Phase, AXES};

use super::events::Key;
use super::keypoints::{KeyPoints, KeyTracker};
use super::reference::{unwrap_delta, Tap};
use super::sync::Window as Move;
use super::sync_stream::SyncStream;

/// Samples sent at once by a [`ChannelSink`].
const BATCH: usize = 2048;

/// Where the samples come from.
pub(crate) enum Feed<'a> {
    /// The events of a trace in memory.
    Trace(std::slice::Iter<'a, TraceEvent>),
    /// Batches of samples from a reference run on another thread ([`ChannelSink`]).
    Channel(Receiver<Batch>),
    /// Nothing more.
    Done,
}

/// What a [`ChannelSink`] sends at once: samples, and the discrete events among them (edges,
/// functions, alarms) when asked for.
#[derive(Default)]
pub struct Batch {
    /// Samples: time, sample.
    pub samples: Vec<(i64, Sample)>,
    /// Discrete events: time, key.
    pub keyed: Vec<(i64, Key)>,
    /// The reference's key points read so far that will not change (its reversals: at the end).
    pub keys: KeyPoints,
    /// The end of the run: its spindle reversals in rigid tapping (the key points' count).
    pub reversals: Option<u32>,
    /// The synchronised moves found, in time order, and the phases read.
    pub moves: Vec<Move>,
    /// The phases read.
    pub phases: Vec<(i64, Phase)>,
    /// Every move starting before this time has been sent.
    pub complete: i64,
}

/// A window of the reference's samples, in time order.
pub struct Window<'a> {
    /// Sample times, µs.
    pub t: Vec<i64>,
    /// Samples.
    pub s: Vec<Sample>,
    /// The cumulative unwrapped spindle angle at each sample, milli-degrees (from the run's first
    /// sample, as if no sample had been dropped).
    pub cum: Vec<f64>,
    /// The index of the last lookup: recorded times mostly grow, so the next one starts there.
    pub hint: usize,
    /// The last answers of the walking lookups, by slot: [`Window::first_at_or_after`] and
    /// [`Window::first_after`] (0, 1), the sync search (2 to 4), the envelope's own time (5).
    hints: [usize; 6],
    /// Samples dropped so far: the index of `t[0]` in the whole run.
    pub base: usize,
    feed: Feed<'a>,
    last: Option<(i64, Sample, f64)>,
    /// Most samples held at once (a figure for the memory bound).
    pub peak: usize,
    /// The reference's discrete events pulled with the samples and not yet taken (when
    /// `keyed_wanted`): every one before the last sample held has been pulled.
    pub keyed: Vec<(i64, Key)>,
    keyed_wanted: bool,
    /// The reference's key points pulled with the samples and not yet taken (when
    /// `keyed_wanted`), and its reversals once its end is pulled.
    pub keys: KeyPoints,
    /// The reference's spindle reversals in rigid tapping, once its end is pulled.
    pub reversals: Option<u32>,
    /// Reads the key points of a trace in memory.
    tracker: Option<KeyTracker>,
    /// Reads the synchronised moves and phases of a trace in memory.
    stream: Option<SyncStream>,
    /// The reference's synchronised moves pulled (when `keyed_wanted`), in time order, from the
    /// one numbered `moves_base` in the run on: those the comparison may still look up.
    pub moves: VecDeque<Move>,
    /// The index of `moves[0]` among all the moves.
    pub moves_base: usize,
    /// Every move starting before this time has been pulled.
    pub moves_complete: i64,
    /// The moves pulled: how many, how many of each axis.
    pub moves_count: (usize, [usize; AXES]),
    /// The phases pulled that the comparison may still look up (the last before its time on).
    pub phases: VecDeque<(i64, Phase)>,
    /// Moves and phases are held for the times from this one on (older ones were dropped).
    pub held_from: i64,
    /// Most moves and phases held at once (a figure for the memory bound).
    pub held_peak: usize,
    /// Samples after this time are not kept (all but the first: [`Window::drain`]).
    keep_until: i64,
}

impl<'a> Window<'a> {
    /// A window fed by `feed`, that collects the discrete events in [`Window::keyed`] and the
    /// key points (for the reference's tap `tap`) in [`Window::keys`] when `keyed` (read here
    /// from a trace in memory; a [`ChannelSink`] sends them when made to).
    pub(crate) fn with_keyed(feed: Feed<'a>, keyed: bool, tap: Option<Tap>, meta: &TraceMeta) -> Window<'a> {
        let here = keyed && matches!(feed, Feed::Trace(_));
        let tracker = here.then(|| KeyTracker::new(tap));
        let stream = here.then(|| {
            let mut s = SyncStream::new(tap);
            s.start(meta);
            s
        });
        Window {
            t: Vec::new(),
            s: Vec::new(),
            cum: Vec::new(),
            hint: 0,
            hints: [0; 6],
            base: 0,
            feed,
            last: None,
            peak: 0,
            keyed: Vec::new(),
            keyed_wanted: keyed,
            keys: KeyPoints::default(),
            reversals: None,
            tracker,
            stream,
            moves: VecDeque::new(),
            moves_base: 0,
            moves_complete: i64::MIN,
            moves_count: (0, [0; AXES]),
            phases: VecDeque::new(),
            held_from: i64::MIN,
            held_peak: 0,
            keep_until: i64::MAX,
        }
    }

    fn push(&mut self, t: i64, s: Sample) {
        if self.keep_until != i64::MAX && self.last.is_some_and(|l| l.0 > self.keep_until) {
            return;
        }
        let acc = match self.last {
            None => s.spindle_mdeg as f64,
            Some((tp, p, acc)) => {
                acc + unwrap_delta(p.spindle_mdeg, p.spindle_mrpm, s.spindle_mdeg, s.spindle_mrpm, t - tp)
            }
        };
        self.last = Some((t, s, acc));
        self.t.push(t);
        self.s.push(s);
        self.cum.push(acc);
        self.peak = self.peak.max(self.t.len());
    }

    /// Pulls the next samples; false when the run has no more.
    fn pull(&mut self) -> bool {
        match &mut self.feed {
            Feed::Trace(it) => {
                for e in it.by_ref() {
                    if let Some(k) = &mut self.tracker {
                        k.event(e.t_us as i64, &e.event);
                        if k.has_final() {
                            k.take(&mut self.keys);
                        }
                    }
                    if let Some(st) = &mut self.stream {
                        st.event(e);
                        let (moves, phases, complete) =
                            (std::mem::take(&mut st.out), std::mem::take(&mut st.phases), st.complete());
                        let held = (
                            &mut self.moves,
                            &mut self.phases,
                            &mut self.moves_count,
                            &mut self.moves_complete,
                        );
                        add_moves(held, moves, phases, complete);
                        self.held_peak = self.held_peak.max(self.moves.len() + self.phases.len());
                    }
                    if let Event::Sample(s) = &e.event {
                        let (t, s) = (e.t_us as i64, *s);
                        self.push(t, s);
                        return true;
                    }
                    if self.keyed_wanted {
                        if let Some(k) = Key::of(&e.event) {
                            self.keyed.push((e.t_us as i64, k));
                        }
                    }
                }
                if let Some(k) = self.tracker.take() {
                    let mut rest = k.finish();
                    self.keys.segments.append(&mut rest.segments);
                    self.keys.returns.append(&mut rest.returns);
                    self.reversals = Some(rest.reversals);
                }
                if let Some(mut st) = self.stream.take() {
                    st.finish();
                    self.add_moves(std::mem::take(&mut st.out), std::mem::take(&mut st.phases), i64::MAX);
                }
                self.feed = Feed::Done;
                false
            }
            Feed::Channel(rx) => match rx.recv() {
                Ok(batch) => {
                    for (t, s) in batch.samples {
                        self.push(t, s);
                    }
                    self.keyed.extend(batch.keyed);
                    let mut keys = batch.keys;
                    self.keys.segments.append(&mut keys.segments);
                    self.keys.returns.append(&mut keys.returns);
                    if batch.reversals.is_some() {
                        self.reversals = batch.reversals;
                    }
                    self.add_moves(batch.moves, batch.phases, batch.complete);
                    true
                }
                Err(_) => {
                    self.feed = Feed::Done;
                    false
                }
            },
            Feed::Done => false,
        }
    }

    fn add_moves(&mut self, moves: Vec<Move>, phases: Vec<(i64, Phase)>, complete: i64) {
        add_moves(
            (&mut self.moves, &mut self.phases, &mut self.moves_count, &mut self.moves_complete),
            moves,
            phases,
            complete,
        );
        self.held_peak = self.held_peak.max(self.moves.len() + self.phases.len());
    }

    /// Pulls until every synchronised move starting at or before `t` is held (or the run has no
    /// more): the samples up to the end of the move in force at `t` are held too.
    pub fn ensure_moves(&mut self, t: i64) {
        while self.moves_complete <= t {
            if !self.pull() {
                self.moves_complete = i64::MAX;
                break;
            }
        }
    }

    /// Drops the moves and phases that no time from `floor` on looks up (a move ended before it,
    /// the phases before the last one at or before it).
    pub fn prune_moves(&mut self, floor: i64) {
        let mut dropped = false;
        while self.moves.front().is_some_and(|m| m.t1 < floor) {
            self.moves.pop_front();
            self.moves_base += 1;
            dropped = true;
        }
        while self.phases.len() >= 2 && self.phases[1].0 <= floor {
            self.phases.pop_front();
            dropped = true;
        }
        if dropped {
            self.held_from = self.held_from.max(floor);
        }
    }

    /// Pulls until a sample later than `t` is held (or the run has no more).
    pub fn ensure(&mut self, t: i64) {
        while self.t.last().is_none_or(|&l| l <= t) {
            if !self.pull() {
                break;
            }
        }
    }

    /// Pulls the rest of the run, keeping its samples up to `keep_until` and the first after
    /// it (the discrete events all go to [`Window::keyed`]): what comes later is not looked up.
    pub fn drain(&mut self, keep_until: i64) {
        self.keep_until = keep_until;
        while self.pull() {}
    }

    /// Drops the samples before the last one at or before `floor` (nothing at or after `floor`
    /// is looked up any more). Amortised: the front is dropped once it is at least half.
    pub fn prune(&mut self, floor: i64) {
        if self.t.len() < 8192 || self.t[4096] > floor {
            return;
        }
        let k = self.t.partition_point(|&x| x <= floor);
        let drop = k.saturating_sub(1);
        if drop >= 4096 && drop * 2 >= self.t.len() {
            self.t.drain(..drop);
            self.s.drain(..drop);
            self.cum.drain(..drop);
            self.base += drop;
            self.hint = self.hint.saturating_sub(drop);
            for h in &mut self.hints {
                *h = h.saturating_sub(drop);
            }
        }
    }

    /// The index of the first sample at or after `t` (`t.partition_point(|x| x < t)`), found by
    /// walking from the last answer of lookup `slot` (0..5, one per kind of time looked up):
    /// times looked up mostly grow.
    pub fn first_at_or_after_in(&mut self, slot: usize, t: i64) -> usize {
        let k = walk(&self.t, self.hints[slot], |x| x < t);
        self.hints[slot] = k;
        k
    }

    /// The index of the first sample after `t` (`t.partition_point(|x| x <= t)`), as
    /// [`Window::first_at_or_after_in`].
    pub fn first_after_in(&mut self, slot: usize, t: i64) -> usize {
        let k = walk(&self.t, self.hints[slot], |x| x <= t);
        self.hints[slot] = k;
        k
    }

    /// [`Window::first_at_or_after_in`] of the envelope's start.
    pub fn first_at_or_after(&mut self, t: i64) -> usize {
        self.first_at_or_after_in(0, t)
    }

    /// [`Window::first_after_in`] of the envelope's end.
    pub fn first_after(&mut self, t: i64) -> usize {
        self.first_after_in(1, t)
    }
}

/// A sink that sends the samples of a run (and its discrete events when asked), in batches, to
/// a [`Window`] on another thread; it asks the run to stop once the window is gone.
pub struct ChannelSink {
    tx: SyncSender<Batch>,
    buf: Batch,
    keyed: bool,
    /// Reads the key points (when `keyed`).
    tracker: Option<KeyTracker>,
    /// Reads the synchronised moves and the phases (when `keyed`).
    stream: Option<SyncStream>,
    /// The last sample of the batches sent (the one before the next batch's first).
    carry: Option<(i64, Sample)>,
    gone: bool,
}

impl ChannelSink {
    /// A sink sending into `tx`, the discrete events and the key points (for the reference's
    /// tap `tap`) too when `keyed`.
    pub fn new(tx: SyncSender<Batch>, keyed: bool, tap: Option<Tap>) -> ChannelSink {
        let tracker = keyed.then(|| KeyTracker::new(tap));
        let stream = keyed.then(|| SyncStream::new(tap));
        ChannelSink { tx, buf: ChannelSink::batch(), keyed, tracker, stream, carry: None, gone: false }
    }

    fn batch() -> Batch {
        Batch { samples: Vec::with_capacity(BATCH), ..Batch::default() }
    }

    /// Sends what is left, the end of the run.
    pub fn finish(&mut self) {
        if let Some(k) = self.tracker.take() {
            let mut rest = k.finish();
            self.buf.keys.segments.append(&mut rest.segments);
            self.buf.keys.returns.append(&mut rest.returns);
            self.buf.reversals = Some(rest.reversals);
        }
        if let Some(st) = &mut self.stream {
            let last = self.buf.samples.last().or(self.carry.as_ref()).map(|p| p.1);
            st.finish_after(last.as_ref());
        }
        self.flush();
    }

    /// Sends what is read.
    pub fn flush(&mut self) {
        if let Some(k) = &mut self.tracker {
            k.take(&mut self.buf.keys);
        }
        if let Some(last) = self.buf.samples.last() {
            self.carry = Some(*last);
        }
        if let Some(st) = &mut self.stream {
            self.buf.moves.append(&mut st.out);
            self.buf.phases.append(&mut st.phases);
            self.buf.complete = st.complete();
        }
        let empty = self.buf.samples.is_empty()
            && self.buf.keyed.is_empty()
            && self.buf.keys.segments.is_empty()
            && self.buf.keys.returns.is_empty()
            && self.buf.reversals.is_none()
            && self.buf.moves.is_empty()
            && self.buf.phases.is_empty();
        if !empty && !self.gone {
            let b = std::mem::take(&mut self.buf);
            self.gone = self.tx.send(b).is_err();
        }
    }
}

impl TraceSink for ChannelSink {
    fn start(&mut self, meta: &TraceMeta) {
        if let Some(st) = &mut self.stream {
            st.start(meta);
        }
    }
    fn event(&mut self, ev: &TraceEvent) {
        if let Event::Sample(s) = &ev.event {
            // Copied first (the sample the run has just written is read once from its stores).
            self.buf.samples.push((ev.t_us as i64, *s));
            if let Some(k) = &mut self.tracker {
                k.event(ev.t_us as i64, &ev.event);
            }
            if let Some(st) = &mut self.stream {
                let n = self.buf.samples.len();
                let prev = if n >= 2 { self.buf.samples.get(n - 2) } else { self.carry.as_ref() };
                st.event_after(ev, prev.map(|p| (p.0, &p.1)));
            }
            if self.buf.samples.len() >= BATCH {
                self.flush();
                self.buf = ChannelSink::batch();
            }
            return;
        }
        if let Some(k) = &mut self.tracker {
            k.event(ev.t_us as i64, &ev.event);
        }
        if let Some(st) = &mut self.stream {
            let prev = self.buf.samples.last().or(self.carry.as_ref());
            st.event_after(ev, prev.map(|p| (p.0, &p.1)));
        }
        if self.keyed {
            if let Some(k) = Key::of(&ev.event) {
                self.buf.keyed.push((ev.t_us as i64, k));
            }
        }
    }
    fn wants_stop(&self) -> bool {
        self.gone
    }
}

/// The moves, phases, counts and completeness of a [`Window`].
type Held<'w> =
    (&'w mut VecDeque<Move>, &'w mut VecDeque<(i64, Phase)>, &'w mut (usize, [usize; AXES]), &'w mut i64);

/// Adds the moves and phases pulled, every move before `complete` among them.
fn add_moves(held: Held, moves: Vec<Move>, phases: Vec<(i64, Phase)>, complete: i64) {
    let (q, p, count, c) = held;
    for m in &moves {
        count.0 += 1;
        count.1[m.slot] += 1;
    }
    if !moves.is_empty() {
        q.extend(moves);
        // One slice for the lookups (`Reference::sync_index`): a few moves, once a batch.
        q.make_contiguous();
    }
    p.extend(phases);
    *c = complete;
}

/// `v.partition_point(before)` found by walking from `from` (at most 64 steps, else a binary
/// search).
fn walk(v: &[i64], from: usize, before: impl Fn(i64) -> bool) -> usize {
    let mut k = from.min(v.len());
    for _ in 0..64 {
        if k < v.len() && before(v[k]) {
            k += 1;
        } else if k > 0 && !before(v[k - 1]) {
            k -= 1;
        } else {
            return k;
        }
    }
    v.partition_point(|&x| before(x))
}
