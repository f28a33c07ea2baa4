//! Key points of the recorded trace against the reference's: number of pecks, each peck depth
//! and retract height, the hole bottom, the pause at the bottom of each cut (the dwell), the
//! return level, the number of spindle reversals.
//!
//! Compared stroke by stroke ([`KeyCompare`]): the n-th peck, retract, return and pause of one
//! trace with the n-th of the other as soon as both are read, each side's unpaired ones waiting;
//! the divergences found wait (at most [`super::MAX_PER_CHECK`] of each check, the rest
//! counted) and are given at the end in the order a comparison of the whole lists gives them, so
//! that memory does not follow the number of strokes.

use std::collections::VecDeque;

use nc_engine::trace::Signal;

use super::compare::Comparator;
use super::keypoints::{KeyPoints, Segment};
use super::tolerance::{mm_nm, ms_us, Topic};
use super::Divergence;
use crate::scenario::timeline::{fixed, ms};

fn mm(nm: i64) -> String {
    format!("{} mm", fixed(nm, 6))
}

fn depth(d: Option<i64>) -> String {
    d.map_or("no sample".into(), mm)
}

/// A point: the time its stroke ended (or the fall), the depth, its uncertainty.
type KeyPoint = (i64, Option<i64>, i64);

/// The reference's side (0) or the recording's (1).
const REF: usize = 0;
const REC: usize = 1;

/// Divergences of one check found so far, the first [`super::MAX_PER_CHECK`] kept.
#[derive(Debug, Default)]
struct Found {
    /// Each with its rule (None: attributed at the end) and topic.
    kept: Vec<(Divergence, Option<String>, Topic)>,
    more: usize,
}

impl Found {
    fn add(&mut self, d: (Divergence, Option<String>, Topic)) {
        if self.kept.len() < super::MAX_PER_CHECK {
            self.kept.push(d);
        } else {
            self.more += 1;
        }
    }

    fn give(self, c: &mut Comparator) {
        let check = self.kept.first().map(|d| d.0.check.clone());
        for (d, rule, topic) in self.kept {
            c.push_attributed(d, rule, topic, false);
        }
        if let Some(check) = check {
            // Past the per-check bound: counted as `push` counts them.
            for _ in 0..self.more {
                c.omit(&check);
            }
        }
    }
}

/// The key points of both traces compared as they are read (see the module's text).
#[derive(Debug, Default)]
pub struct KeyCompare {
    pecks: [VecDeque<KeyPoint>; 2],
    retracts: [VecDeque<KeyPoint>; 2],
    returns: [VecDeque<KeyPoint>; 2],
    pauses: [VecDeque<(i64, i64)>; 2],
    /// Each side's last segment (a pause is a cut's end to the retract's start).
    prev: [Option<Segment>; 2],
    /// Pairs compared so far: pecks, retracts, returns, pauses.
    paired: [usize; 4],
    /// Pecks, segments and returns read on each side.
    n_pecks: [usize; 2],
    n_segments: [usize; 2],
    n_returns: [usize; 2],
    /// Each side's deepest cut: its depth, the uncertainty and time of its first peck that deep.
    bottom: [Option<(i64, i64, i64)>; 2],
    /// The reference's first segment's start, its last peck's and last return's times.
    t0: Option<i64>,
    last_peck: Option<i64>,
    last_return: Option<i64>,
    /// Divergences: peck depths, retract heights, return levels, pauses.
    found: [Found; 4],
    /// The reference's reversals (known at its end).
    pub ref_reversals: u32,
    /// Most points and pauses waiting for their pair at once (a figure for the memory bound).
    pub peak: usize,
}

impl KeyCompare {
    /// Segments read by each side.
    pub fn segments(&self, side: usize) -> usize {
        self.n_segments[side]
    }

    /// Returns read by each side.
    pub fn returns(&self, side: usize) -> usize {
        self.n_returns[side]
    }

    /// Pecks read: (reference, recording).
    pub fn pecks(&self) -> (usize, usize) {
        (self.n_pecks[REF], self.n_pecks[REC])
    }

    /// Segments and returns of the reference (`side` 0) or the recording (1), in their order;
    /// pairs are compared against `c`'s tolerances and the reference's tap.
    pub fn add(&mut self, c: &Comparator, side: usize, keys: &mut KeyPoints) {
        for s in keys.segments.drain(..) {
            self.n_segments[side] += 1;
            if side == REF && self.t0.is_none() {
                self.t0 = Some(s.t_start);
            }
            if let Some(p) = self.prev[side] {
                if p.into && !s.into {
                    if let Some(t) = p.t_stop {
                        self.pauses[side].push_back((t, s.t_start - t));
                    }
                }
            }
            self.prev[side] = Some(s);
            if s.into {
                let p = (s.t_stop.unwrap_or(s.t_start), s.deepest, s.deep_unc);
                self.n_pecks[side] += 1;
                if side == REF {
                    self.last_peck = Some(p.0);
                }
                if let Some(d) = s.deepest {
                    if self.bottom[side].is_none_or(|b| d > b.0) {
                        self.bottom[side] = Some((d, s.deep_unc, p.0));
                    }
                }
                self.pecks[side].push_back(p);
            } else {
                self.retracts[side].push_back((s.t_stop.unwrap_or(s.t_start), s.shallowest, s.shallow_unc));
            }
        }
        for r in keys.returns.drain(..) {
            self.n_returns[side] += 1;
            if side == REF {
                self.last_return = Some(r.0);
            }
            self.returns[side].push_back(r);
        }
        let waiting = |q: &[VecDeque<KeyPoint>; 2]| q[0].len() + q[1].len();
        let pauses = self.pauses[0].len() + self.pauses[1].len();
        let held = waiting(&self.pecks) + waiting(&self.retracts) + waiting(&self.returns) + pauses;
        self.peak = self.peak.max(held);
        self.pair(c);
    }

    fn pair(&mut self, c: &Comparator) {
        let Some(tap) = c.r.tap else { return };
        let tol = mm_nm(c.tol.keypoint_mm);
        let letter = c.r.axes().iter().find(|a| a.index == tap.slot).map_or('?', |a| a.letter);
        // Depths are along the direction into the hole; shown as positions.
        let pos = |d: Option<i64>| d.map(|d| d * tap.into_sign);
        let lists = [
            (0, "CHK-KEY-02", "peck depth", Topic::Pecks),
            (1, "CHK-KEY-03", "retract height", Topic::Pecks),
            (2, "CHK-KEY-05", "return level", Topic::Bottom),
        ];
        for (i, check, what, topic) in lists {
            let q = match i {
                0 => &mut self.pecks,
                1 => &mut self.retracts,
                _ => &mut self.returns,
            };
            while !q[REF].is_empty() && !q[REC].is_empty() {
                let (Some(x), Some(y)) = (q[REF].pop_front(), q[REC].pop_front()) else { break };
                self.paired[i] += 1;
                let k = self.paired[i];
                let (Some(dx), Some(dy)) = (x.1, y.1) else { continue };
                let tol = tol + x.2 + y.2;
                if (dx - dy).abs() > tol {
                    self.found[i].add(divergence(
                        c,
                        topic,
                        check,
                        format!("{what} #{k}"),
                        x.0,
                        format!("{letter} = {} ± {}", depth(pos(x.1)), mm(tol)),
                        format!("{letter} = {}", depth(pos(y.1))),
                        mm((dx - dy).abs() - tol),
                    ));
                }
            }
        }
        let dtol = ms_us(c.tol.dwell_ms);
        while !self.pauses[REF].is_empty() && !self.pauses[REC].is_empty() {
            let (Some(x), Some(y)) = (self.pauses[REF].pop_front(), self.pauses[REC].pop_front()) else {
                break;
            };
            self.paired[3] += 1;
            if (x.1 - y.1).abs() > dtol {
                self.found[3].add(divergence(
                    c,
                    Topic::Dwell,
                    "CHK-KEY-06",
                    format!("pause at the bottom of cut #{} (dwell and reversal)", self.paired[3]),
                    x.0,
                    format!("{} ± {}", ms(x.1.max(0) as u64), ms(dtol as u64)),
                    ms(y.1.max(0) as u64),
                    ms(((x.1 - y.1).abs() - dtol) as u64),
                ));
            }
        }
    }

    /// Gives the divergences at the end, both sides read whole (`rec_reversals`: the
    /// recording's).
    pub fn finish(self, c: &mut Comparator, rec_reversals: u32) {
        let Some(tap) = c.r.tap else { return };
        let tol = mm_nm(c.tol.keypoint_mm);
        let letter = c.r.axes().iter().find(|a| a.index == tap.slot).map_or('?', |a| a.letter);
        let t0 = self.t0.unwrap_or(0);
        let (rp, qp) = self.pecks();
        if rp != qp {
            // The reference's peck after the last pair, else its last one.
            let t = if rp > qp { self.pecks[REF].front().map(|p| p.0) } else { self.last_peck };
            c.diverge(
                Topic::Pecks,
                "CHK-KEY-01",
                "number of pecks".into(),
                t.unwrap_or(t0),
                format!("{rp} cuts"),
                format!("{qp} cuts"),
                format!("{}", (rp as i64 - qp as i64).abs()),
            );
        }
        let [depths, heights, levels, pauses] = self.found;
        depths.give(c);
        heights.give(c);
        // The return level and the reversals need F76.3 (else noted as not comparable).
        let rtap = c.carries_signal(Signal::Rtap);
        if rtap {
            levels.give(c);
        }
        if let (Some(a), Some(b)) = (self.bottom[REF], self.bottom[REC]) {
            let tol = tol + a.1 + b.1;
            if (a.0 - b.0).abs() > tol {
                c.diverge(
                    Topic::Bottom,
                    "CHK-KEY-04",
                    "hole bottom".into(),
                    a.2,
                    format!("{letter} = {} ± {}", mm(a.0 * tap.into_sign), mm(tol)),
                    format!("{letter} = {}", mm(b.0 * tap.into_sign)),
                    mm((a.0 - b.0).abs() - tol),
                );
            }
        }
        pauses.give(c);
        if !rtap {
            return;
        }
        let (rr, qr) = (self.n_returns[REF], self.n_returns[REC]);
        if rr != qr {
            c.diverge(
                Topic::Bottom,
                "CHK-KEY-05",
                "number of returns (F76.3 falls)".into(),
                self.last_return.unwrap_or(t0),
                format!("{rr}"),
                format!("{qr}"),
                format!("{}", (rr as i64 - qr as i64).abs()),
            );
        }
        if self.ref_reversals != rec_reversals {
            c.diverge(
                Topic::Reversals,
                "CHK-KEY-07",
                "spindle reversals in rigid tapping".into(),
                t0,
                format!("{}", self.ref_reversals),
                format!("{rec_reversals}"),
                format!("{}", (self.ref_reversals as i64 - rec_reversals as i64).abs()),
            );
        }
    }
}

/// A divergence attributed as [`Comparator::diverge`] does (its rule, None when found at the
/// end), kept to be given later.
#[allow(clippy::too_many_arguments)]
fn divergence(
    c: &Comparator,
    topic: Topic,
    check: &str,
    what: String,
    t: i64,
    e: String,
    a: String,
    m: String,
) -> (Divergence, Option<String>, Topic) {
    let d = Divergence::found(check, what, t, e, a, m);
    (d, c.attribute_now(topic, t), topic)
}
