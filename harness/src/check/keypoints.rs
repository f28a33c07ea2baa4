//! Key points of a tapping cycle, read the same way from the reference and from a recorded trace
//! (streaming, one segment per stroke): each peck's depth, each retract height, the hole bottom,
//! the pause at the bottom of each cut (dwell and reversal), the return level when F76.3 falls,
//! the number of pecks and of spindle reversals.
//!
//! A segment starts when RGSPP or RGSPM rises and lasts until the next stroke starts or F76.3
//! falls; its extreme along the direction into the hole is its depth (a cut) or its height (a
//! retract). Depths are `into_sign` × position, in reported nm.

use nc_engine::trace::{Event, Signal, Signals};

use super::reference::Tap;

/// One stroke and what follows it until the next one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// A cut into the hole (the first stroke's signal) or a retract.
    pub into: bool,
    /// When the stroke signal rose.
    pub t_start: i64,
    /// When it fell.
    pub t_stop: Option<i64>,
    /// Deepest and shallowest depth seen (None: no sample).
    pub deepest: Option<i64>,
    /// Shallowest depth.
    pub shallowest: Option<i64>,
    /// Half the travel between the deepest sample and its neighbours: how far the true extreme
    /// may lie beyond it between samples.
    pub deep_unc: i64,
    /// The same for the shallowest sample.
    pub shallow_unc: i64,
}

/// The key points of one trace.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct KeyPoints {
    /// Every stroke segment, in order.
    pub segments: Vec<Segment>,
    /// Each F76.3 fall: time, the tap's depth at the last sample before it, and half the travel
    /// to the sample after it (the uncertainty).
    pub returns: Vec<(i64, Option<i64>, i64)>,
    /// Spindle reversals (sign changes of the speed) while F76.3 = 1, those in the last
    /// [`SETTLE_US`] before F76.3 falls left out (a fall recorded a PLC scan late must not count
    /// the spindle's restart after the cycle as a reversal in it).
    pub reversals: u32,
}

impl KeyPoints {
    /// Depth reached by each cut (the time its stroke ended, depth, uncertainty).
    pub fn pecks(&self) -> Vec<(i64, Option<i64>, i64)> {
        self.segments
            .iter()
            .filter(|s| s.into)
            .map(|s| (s.t_stop.unwrap_or(s.t_start), s.deepest, s.deep_unc))
            .collect()
    }
    /// Height reached by each retract (the time its stroke ended, depth, uncertainty).
    pub fn retracts(&self) -> Vec<(i64, Option<i64>, i64)> {
        self.segments
            .iter()
            .filter(|s| !s.into)
            .map(|s| (s.t_stop.unwrap_or(s.t_start), s.shallowest, s.shallow_unc))
            .collect()
    }
    /// The pause at the bottom of each cut followed by a retract: from the cut's end to the
    /// retract's start (the dwell P plus the reversal), with the time of the cut's end.
    pub fn pauses(&self) -> Vec<(i64, i64)> {
        self.segments
            .windows(2)
            .filter(|w| w[0].into && !w[1].into)
            .filter_map(|w| w[0].t_stop.map(|t| (t, w[1].t_start - t)))
            .collect()
    }
    /// The deepest point of all cuts.
    pub fn bottom(&self) -> Option<i64> {
        self.segments.iter().filter(|s| s.into).filter_map(|s| s.deepest).max()
    }
}

/// Reversals this close before F76.3 falls are not counted, µs.
pub const SETTLE_US: i64 = 20_000;

/// Most segments kept (a controller that strokes forever does not fill the memory).
const MAX_SEGMENTS: usize = 100_000;

/// Reads key points from a stream of events.
#[derive(Debug)]
pub struct KeyTracker {
    tap: Option<Tap>,
    sig: Signals,
    keys: KeyPoints,
    cur: Option<Segment>,
    last_depth: Option<i64>,
    last_rpm_sign: i64,
    last_was: (bool, bool),
    return_pending: bool,
    last_reversal: Option<i64>,
    /// F76.3 fell while a cut was still going deeper (a reset stops the tap at its own limits,
    /// issue 12): the cut's depth and the return level are read where the tap stops going deeper,
    /// so that a fall recorded a PLC scan late reads the same point.
    settling: bool,
    /// Segments and returns kept so far, taken or not ([`KeyTracker::take`]): at most
    /// [`MAX_SEGMENTS`] of each.
    closed: usize,
    returned: usize,
}

impl KeyTracker {
    /// A tracker for the reference's tap (none: nothing is tracked).
    pub fn new(tap: Option<Tap>) -> KeyTracker {
        KeyTracker {
            tap,
            sig: Signals::default(),
            keys: KeyPoints::default(),
            cur: None,
            last_depth: None,
            last_rpm_sign: 0,
            last_was: (false, false),
            return_pending: false,
            last_reversal: None,
            settling: false,
            closed: 0,
            returned: 0,
        }
    }

    fn close(&mut self) {
        if let Some(s) = self.cur.take() {
            if self.closed < MAX_SEGMENTS {
                self.keys.segments.push(s);
                self.closed += 1;
            }
        }
    }

    /// Moves the segments and returns read so far that will not change any more into `keys`
    /// (its reversals are left alone: they are known at the end, [`KeyTracker::finish`]): the
    /// key points can be compared stroke by stroke, memory does not follow the strokes.
    pub fn take(&mut self, keys: &mut KeyPoints) {
        keys.segments.append(&mut self.keys.segments);
        // The last return still waits for the sample after it, or for the cut to stop.
        let hold = usize::from(self.return_pending || self.settling).min(self.keys.returns.len());
        let n = self.keys.returns.len() - hold;
        keys.returns.extend(self.keys.returns.drain(..n));
    }

    /// Whether [`KeyTracker::take`] has something to give.
    pub fn has_final(&self) -> bool {
        !self.keys.segments.is_empty() || !self.keys.returns.is_empty()
    }

    /// One event at the aligned time `t`.
    pub fn event(&mut self, t: i64, ev: &Event) {
        let Some(tap) = self.tap else { return };
        match ev {
            Event::Sample(s) => {
                let d = s.axes[tap.slot] * tap.into_sign;
                let prev = self.last_depth;
                let step = self.last_depth.map_or(0, |p| ((d - p).abs() + 1) / 2);
                self.last_depth = Some(d);
                if std::mem::take(&mut self.return_pending) {
                    if let Some(r) = self.keys.returns.last_mut() {
                        r.2 = step;
                    }
                }
                if let Some(c) = &mut self.cur {
                    // The sample after an extreme bounds it from the other side.
                    if self.last_was.0 {
                        c.deep_unc = c.deep_unc.max(step);
                    }
                    if self.last_was.1 {
                        c.shallow_unc = c.shallow_unc.max(step);
                    }
                    self.last_was = (false, false);
                    if c.deepest.is_none_or(|x| d > x) {
                        c.deepest = Some(d);
                        c.deep_unc = step;
                        self.last_was.0 = true;
                    }
                    if c.shallowest.is_none_or(|x| d < x) {
                        c.shallowest = Some(d);
                        c.shallow_unc = step;
                        self.last_was.1 = true;
                    }
                }
                if self.settling && prev.is_some_and(|p| d <= p) {
                    self.settling = false;
                    let deepest = self.cur.and_then(|c| c.deepest);
                    self.close();
                    if let (Some(r), Some(x)) = (self.keys.returns.last_mut(), deepest) {
                        r.1 = Some(x);
                    }
                }
                if self.sig.get(Signal::Rtap) {
                    let sign = s.spindle_mrpm.signum();
                    if sign != 0 {
                        if self.last_rpm_sign != 0 && sign != self.last_rpm_sign {
                            self.keys.reversals += 1;
                            self.last_reversal = Some(t);
                        }
                        self.last_rpm_sign = sign;
                    }
                }
            }
            Event::Signal { signal, value } => {
                let was = self.sig.get(*signal);
                self.sig.set(*signal, *value);
                match (signal, value) {
                    (Signal::Rgspp | Signal::Rgspm, true) if !was => {
                        self.settling = false;
                        self.close();
                        let d = self.last_depth;
                        self.cur = Some(Segment {
                            into: *signal == tap.in_signal,
                            t_start: t,
                            t_stop: None,
                            deepest: d,
                            shallowest: d,
                            deep_unc: 0,
                            shallow_unc: 0,
                        });
                        self.last_was = (true, true);
                    }
                    (Signal::Rgspp | Signal::Rgspm, false) if was => {
                        if let Some(c) = &mut self.cur {
                            c.t_stop.get_or_insert(t);
                        }
                    }
                    (Signal::Rtap, false) if was => {
                        if self.last_reversal.take().is_some_and(|r| t - r < SETTLE_US) {
                            self.keys.reversals -= 1;
                        }
                        // A cut still going deeper is read on until the tap stops going deeper.
                        let going_deeper = self.cur.is_some_and(|c| c.into && c.t_stop.is_none());
                        if going_deeper {
                            self.settling = true;
                        } else {
                            self.close();
                        }
                        if self.returned < MAX_SEGMENTS {
                            self.keys.returns.push((t, self.last_depth, 0));
                            self.returned += 1;
                            self.return_pending = true;
                        }
                        self.last_rpm_sign = 0;
                    }
                    _ => {}
                }
            }
            _ => {}
        }
    }

    /// The key points.
    pub fn finish(mut self) -> KeyPoints {
        self.close();
        self.keys
    }
}
