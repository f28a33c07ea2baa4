//! One spindle-synchronised thread pass (`Step::Thread`), the single step every threading cycle is
//! built from (GSK G92.3, Heidenhain cycle 832, LinuxCNC G33 and G76, KND G32 and G92): the pass
//! starts where the spindle's angle passes its one-revolution signal plus the pass' phase; from
//! there the drive axis (`along`) travels `lead·n + dlead·n²/2` after `n` revolutions, locked to
//! the spindle's angle after a catch-up ramp ([`PassLaw::Locked`]) or reaching that law's speed
//! with the cutting feed's acceleration ([`PassLaw::Accelerated`]); the infeed axis (`across`) is
//! a function of the drive axis through the pass' knots (tapers, run-outs, chamfers), blended at
//! each knot within its acceleration (DEC-146); any other axis
//! moves linearly with the drive axis. The executor (`exec/thread.rs`) carries it out.
//!
//! Knows no G code: a cycle builder or a dialect fills it in.

use super::Pos;
use crate::alarm::AlarmKind;
use crate::units::Nm;

/// How the drive axis follows the spindle's angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PassLaw {
    /// Exactly at the position the spindle's angle gives (GSK G92.3, GSK-G923-07, variable lead
    /// allowed), reached with a catch-up ramp that starts a constant lag before the start angle
    /// and left with a deceleration to rest at the end point (DEC-146); a fastest lead × speed
    /// above the maximum cutting feed, or a lead change faster than the axis can follow, raises
    /// NC-1077.
    Locked,
    /// The axis accelerates with the cutting feed's acceleration to exactly lead × the spindle's
    /// speed, cruises at it and decelerates to the end point (seed 001: "在螺纹切削开始及结束部分,
    /// 一般由于升降速的原因会出现导程不正确部分"; HDH-C832-05; LinuxCNC's position-synchronised
    /// moves). The lead must be constant (`dlead_nm` 0).
    Accelerated {
        /// With `Some((approach, overrun))`, the distances before and after the thread in which the
        /// ramps must fit (else NC-1078), and a speed above the maximum cutting feed is an alarm
        /// (NC-1077); with `None` the speed is limited to the maximum cutting feed.
        room: Option<(Nm, Nm)>,
    },
    /// LinuxCNC's pass through its tapers (G76 with L, DEC-147): each segment between knots is
    /// a synchronised move of its own that ends at rest (LinuxCNC's exact stop between
    /// non-tangent segments); the first starts at the index as `Accelerated { room: None }`, each
    /// next one at once as [`PassLaw::Tracking`].
    Segments,
    /// [`PassLaw::Segments`] whose first segment tracks too: the run began with an earlier
    /// synchronised move (LinuxCNC's G76 entry taper: its infeed along X at the taper's lead,
    /// interp_convert.cc `threading_pass`, before the angled entry).
    SegmentsTracking,
    /// A synchronised segment after the first of a run (DEC-147): it waits neither for a steady
    /// speed nor for the index, and from rest catches up with the law the first segment settled
    /// on (lead × revolutions since its start − its ramp's lag), as LinuxCNC's position
    /// synchronisation tracks it: the spindle's speed plus √(error × acceleration).
    Tracking,
}

/// Where a thread retract goes on feed hold: the short axis back to the cycle start, then the
/// long axis; the control then holds, and cycle start cuts the interrupted pass again.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThreadRetract {
    /// The cycle's start point.
    pub cycle_start: Pos,
    /// The short axis slot (retracted first).
    pub short_axis: usize,
}

/// One synchronised thread pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThreadPass {
    /// End of the pass, physical nm (axes other than `along` and `across` move linearly to it).
    pub target: Pos,
    /// The drive axis: the lead is measured along it (the longer travel).
    pub along: usize,
    /// The infeed axis, a function of the drive axis through `knots`.
    pub across: usize,
    /// (drive axis, infeed axis) positions, nm; the first is the pass' start (its infeed value is
    /// replaced by where the tool stands), the drive axis moving one way only; linear between
    /// knots, constant beyond the last.
    pub knots: [(f64, f64); 4],
    /// Knots used (2..=4).
    pub n: usize,
    /// The segment that is the thread proper (knots `thread` to `thread + 1`): its blends never
    /// round it (DEC-146); the others are entries, run-outs and overruns.
    pub thread: usize,
    /// Lead at the start of the pass, nm per revolution along `along` (> 0).
    pub lead_nm: f64,
    /// Change of the lead per revolution, nm/rev² (signed; 0: constant lead).
    pub dlead_nm: f64,
    /// Where the pass starts in the spindle's turn: this fraction of a revolution after the
    /// one-revolution signal, in the sense the spindle turns (0 ≤ phase < 1).
    pub phase_rev: f64,
    /// How the drive axis follows the spindle.
    pub law: PassLaw,
    /// Feed hold during the pass retracts at once (thread retract) instead of finishing it.
    pub retract: Option<ThreadRetract>,
    /// Raised when the spindle is not turning when the pass starts.
    pub alarm: AlarmKind,
}

impl ThreadPass {
    /// A straight pass from `from` to `to` at a constant `lead_nm` per revolution measured along
    /// the straight line's path (`along_path`) or along its longer axis: the drive axis is the axis
    /// of the longest travel, the infeed axis the next longest of `axes`. None when the two
    /// points are the same.
    pub fn line(from: Pos, to: Pos, axes: [usize; 2], lead_nm: f64, along_path: bool) -> Option<ThreadPass> {
        let d = |i: usize| (to[i] as f64 - from[i] as f64).abs();
        let (along, across) = if d(axes[1]) > d(axes[0]) { (axes[1], axes[0]) } else { (axes[0], axes[1]) };
        let len = (0..from.len()).map(|i| d(i) * d(i)).sum::<f64>().sqrt();
        if d(along) == 0.0 {
            return None;
        }
        let lead = if along_path { lead_nm * d(along) / len } else { lead_nm };
        let mut knots = [(0.0, 0.0); 4];
        knots[0] = (from[along] as f64, from[across] as f64);
        knots[1] = (to[along] as f64, to[across] as f64);
        Some(ThreadPass {
            target: to,
            along,
            across,
            knots,
            n: 2,
            thread: 0,
            lead_nm: lead,
            dlead_nm: 0.0,
            phase_rev: 0.0,
            law: PassLaw::Accelerated { room: None },
            retract: None,
            alarm: AlarmKind::FeedZero,
        })
    }

    /// Whether its first segment tracks the run before it instead of waiting for the index.
    pub fn tracks_first(&self) -> bool {
        self.law == PassLaw::SegmentsTracking
    }

    /// The drive axis' travel from the pass' start to its end, nm.
    pub fn travel(&self) -> f64 {
        (self.knots[self.n - 1].0 - self.knots[0].0).abs()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_taper_line_is_driven_by_its_longer_axis_and_its_lead_measured_along_the_path_or_that_axis() {
        let from = [10_000_000, 0, 0, 0, 0, 0];
        let to = [13_000_000, 0, -4_000_000, 0, 0, 0];
        let p = ThreadPass::line(from, to, [0, 2], 1_000_000.0, true).unwrap();
        assert_eq!((p.along, p.across), (2, 0));
        // 5 mm of path for 4 mm of Z: 1 mm per revolution along the path is 0.8 mm along Z.
        assert!((p.lead_nm - 800_000.0).abs() < 1e-6, "{}", p.lead_nm);
        assert_eq!(p.travel(), 4_000_000.0);
        let q = ThreadPass::line(from, to, [0, 2], 1_000_000.0, false).unwrap();
        assert_eq!(q.lead_nm, 1_000_000.0);
        assert!(ThreadPass::line(from, from, [0, 2], 1.0, true).is_none());
    }
}
