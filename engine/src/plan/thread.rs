//! The multi-pass threading cycle of GSK G92.3 (variable lead, equal tip width): every pass runs
//! the same path — rapid along the short axis to the cut start, the spindle-synchronised thread
//! to the cut end (with its run-out), rapid back along the short axis, rapid back along the long
//! axis to the cycle start — and the passes differ only in where they start in the spindle's
//! turn: pass *k* starts `min(k·Q, F−E−A)/F` of a revolution after the one-revolution signal,
//! which moves its groove by `k·Q` along the long axis at the start of the thread (rules
//! GSK-G923-* in `docs/rules/gsk-lathe.md`).
//!
//! Knows no G code: the dialect gives lengths in nm and the options as flags.

use super::{More, PassLaw, Pos, Step, ThreadPass, ThreadRetract, PECKS_PER_CHUNK};
use crate::alarm::AlarmKind;
use crate::trace::Phase;
use crate::units::Nm;

/// One G92.3 cycle, as the dialect worked it out.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThreadCycle {
    /// The cycle's start point (where the block begins and every pass ends).
    pub start: Pos,
    /// The axis of the rapid in to the cut start and out after the thread (X on a lathe).
    pub infeed_axis: usize,
    /// The short axis slot (the run-out's; X unless the taper is steeper than 45°).
    pub short_axis: usize,
    /// The long axis slot (the lead is measured along it).
    pub long_axis: usize,
    /// The infeed axis' position at the cut start (X end + R).
    pub cut_start_infeed: Nm,
    /// The cut end without run-out.
    pub cut_end: Pos,
    /// Lead at the start, nm/rev.
    pub lead_nm: i64,
    /// Lead change per revolution, nm/rev² (signed).
    pub dlead_nm: i64,
    /// Run-out along the short axis (signed, nm) over `runout_len` nm of the long axis.
    pub runout: Nm,
    /// Length of the run-out along the long axis, nm.
    pub runout_len: Nm,
    /// Axial step Q, nm (> 0).
    pub q: Nm,
    /// Groove width the passes add to the tool's: F − E − A, nm (≥ 0).
    pub widen: Nm,
    /// Number of passes.
    pub passes: u64,
    /// Feed hold during a pass retracts at once (thread retract) rather than finishing the pass.
    pub retract_on_hold: bool,
}

impl ThreadCycle {
    /// Passes of `widen` nm in steps of `q`: `widen / q + 1`, a fraction rounded up (the last
    /// pass then moves only by what is left).
    pub fn pass_count(widen: Nm, q: Nm) -> u64 {
        if q <= 0 || widen <= 0 {
            return 1;
        }
        (widen as u64).div_ceil(q as u64) + 1
    }

    /// The fraction of a revolution pass `k` starts after the one-revolution signal.
    pub fn phase(&self, k: u64) -> f64 {
        let shift = (k as i128 * self.q as i128).min(self.widen as i128) as f64;
        shift / self.lead_nm.max(1) as f64
    }

    /// The cut start: the cycle start with the infeed axis at X end + R.
    pub fn cut_start(&self) -> Pos {
        let mut p = self.start;
        p[self.infeed_axis] = self.cut_start_infeed;
        p
    }

    /// The thread pass `k`: from the cut start to the cut end along the straight (or taper)
    /// line, locked to the spindle, the short axis adding the run-out over the last `runout_len`
    /// of the long axis; started `phase(k)` of a turn after the index.
    pub fn pass_move(&self, k: u64) -> ThreadPass {
        let from = self.cut_start();
        let mut target = self.cut_end;
        let (l, s) = (self.long_axis, self.short_axis);
        let len = (target[l] - from[l]).unsigned_abs() as f64;
        let dir = if target[l] >= from[l] { 1.0 } else { -1.0 };
        let mut knots = [(0.0, 0.0); 4];
        knots[0] = (from[l] as f64, from[s] as f64);
        let mut n = 1;
        if self.runout != 0 && self.runout_len > 0 {
            // The line to the cut end, the run-out added linearly over its last part.
            let at = (len - self.runout_len as f64).max(0.0);
            if at > 0.0 {
                let line = (target[s] - from[s]) as f64;
                knots[1] = (from[l] as f64 + dir * at, from[s] as f64 + line * at / len);
                n = 2;
            }
            target[s] += self.runout;
        }
        knots[n] = (target[l] as f64, target[s] as f64);
        ThreadPass {
            target,
            along: l,
            across: s,
            knots,
            n: n + 1,
            thread: 0,
            lead_nm: self.lead_nm as f64,
            dlead_nm: self.dlead_nm as f64,
            phase_rev: self.phase(k),
            law: PassLaw::Locked,
            retract: self
                .retract_on_hold
                .then_some(ThreadRetract { cycle_start: self.start, short_axis: self.infeed_axis }),
            alarm: AlarmKind::FeedZero,
        }
    }
}

/// Appends the whole cycle (its first chunk of passes).
pub fn thread_cycle(c: &ThreadCycle, out: &mut Vec<Step>) {
    passes(c, 0, out);
}

/// Appends passes from `first` on, at most [`PECKS_PER_CHUNK`] of them, then a [`Step::More`]
/// for the rest; ends in the idle phase after the last pass.
pub fn passes(c: &ThreadCycle, first: u64, out: &mut Vec<Step>) {
    let end = c.passes.min(first.saturating_add(PECKS_PER_CHUNK as u64));
    for k in first..end {
        let mv = c.pass_move(k);
        let cut_start = c.cut_start();
        let mut out_short = mv.target;
        out_short[c.infeed_axis] = c.start[c.infeed_axis];
        out.push(Step::Phase(Phase::Positioning));
        out.push(Step::Rapid { target: cut_start });
        out.push(Step::Phase(Phase::Cutting));
        if !c.retract_on_hold {
            out.push(Step::HoldSuppress(true));
        }
        out.push(Step::Thread(mv));
        out.push(Step::Phase(Phase::Retract));
        out.push(Step::Rapid { target: out_short });
        out.push(Step::Rapid { target: c.start });
        // A held-over feed hold acts back at the cycle start, where single block stops too
        // (GSK-G923-12, GSK-G923-13; seed 000 注意事项 6 treats the two as one rule).
        if !c.retract_on_hold {
            out.push(Step::HoldSuppress(false));
        }
        if k + 1 < c.passes {
            out.push(Step::SingleBlockStop);
        }
    }
    if end < c.passes {
        out.push(Step::More(Box::new(More::Thread { cycle: *c, next: end })));
    } else {
        out.push(Step::Phase(Phase::Idle));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::expand_all;
    use crate::trace::AXES;

    fn cycle(widen: Nm, q: Nm) -> ThreadCycle {
        let start = [20_000_000, 0, 5_000_000, 0, 0, 0];
        let mut cut_end = start;
        cut_end[0] = 9_000_000;
        cut_end[2] = -40_000_000;
        ThreadCycle {
            start,
            infeed_axis: 0,
            short_axis: 0,
            long_axis: 2,
            cut_start_infeed: 9_000_000,
            cut_end,
            lead_nm: 4_000_000,
            dlead_nm: 0,
            runout: 0,
            runout_len: 0,
            q,
            widen,
            passes: ThreadCycle::pass_count(widen, q),
            retract_on_hold: false,
        }
    }

    #[test]
    fn pass_count_is_widen_over_q_plus_one_rounded_up() {
        // GSK-G923-05: (F − E − A)/Q + 1.
        assert_eq!(ThreadCycle::pass_count(2_000_000, 500_000), 5);
        assert_eq!(ThreadCycle::pass_count(2_100_000, 500_000), 6);
        assert_eq!(ThreadCycle::pass_count(0, 500_000), 1);
    }

    #[test]
    fn the_last_pass_moves_only_by_what_is_left() {
        let c = cycle(2_100_000, 500_000);
        assert_eq!(c.phase(0), 0.0);
        assert_eq!(c.phase(1), 0.125);
        assert_eq!(c.phase(5), 2_100_000.0 / 4_000_000.0);
    }

    #[test]
    fn every_pass_returns_to_the_start_and_many_passes_are_planned_in_chunks() {
        let c = cycle(40_000, 1);
        let mut first = Vec::new();
        thread_cycle(&c, &mut first);
        assert!(first.len() < 200, "{}", first.len());
        assert!(matches!(first.last(), Some(Step::More(_))));
        let small = cycle(2_000_000, 500_000);
        let mut v = Vec::new();
        thread_cycle(&small, &mut v);
        let all = expand_all(v);
        let threads = all.iter().filter(|s| matches!(s, Step::Thread(_))).count();
        assert_eq!(threads, 5);
        let rapids: Vec<_> = all
            .iter()
            .filter_map(|s| if let Step::Rapid { target } = s { Some(*target) } else { None })
            .collect();
        assert_eq!(rapids.len(), 15);
        assert_eq!(rapids[2], small.start);
        assert_eq!(rapids[1][0], small.start[0]);
        assert_eq!(rapids[1][2], small.cut_end[2]);
        assert_eq!(rapids[0][2], small.start[2]);
        let _ = AXES;
    }
}
