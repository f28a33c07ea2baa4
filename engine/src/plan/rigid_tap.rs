//! Rigid tapping: the tap axis locked to the spindle, in one of three ways (standard, high-speed
//! peck, peck back to the start level), for GSK G84/G88 and Fanuc G84/G74 alike.
//!
//! The dialect positions to the hole (and to R on a mill); this builder takes over at the start
//! level and ends back at it. Rule ids: GSK-RT-*, FAN-RT-* in `docs/`.

use crate::plan::{More, OverloadWatch, Step, TapMove, PECKS_PER_CHUNK};
use crate::trace::Phase;
use crate::units::{Micros, Nm};

/// How the hole is cut.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Peck {
    /// Straight to the bottom.
    None,
    /// Cut `q`, retract `d` (spindle reversed), cut again to the previous depth + `q`, ...
    HighSpeed {
        /// Depth per cut, nm (> 0).
        q: Nm,
        /// Retract after each cut, nm (> 0).
        d: Nm,
    },
    /// Cut `q`, retract to the start level, cut to the previous depth + `q`, ...
    Deep {
        /// Depth per cut, nm (> 0).
        q: Nm,
    },
}

/// One rigid tapping hole.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidTap {
    /// Tap axis slot.
    pub axis: usize,
    /// Start level on the tap axis (GSK: start point; Fanuc: R plane).
    pub start: Nm,
    /// Hole bottom on the tap axis.
    pub bottom: Nm,
    /// Lead, nm per revolution (> 0).
    pub lead_nm: i64,
    /// Spindle speed, rpm (> 0).
    pub rpm: u32,
    /// Right-hand tap: the spindle turns forward while cutting.
    pub right_hand: bool,
    /// Dwell at the bottom.
    pub dwell_us: Micros,
    /// Peck mode.
    pub peck: Peck,
    /// Override of the return strokes, % (100: none).
    pub extraction_pct: u32,
    /// Overload watch during the cut (GSK D / parameter 271).
    pub overload: Option<OverloadWatch>,
}

/// Appends the steps of one hole, from the start level back to the start level.
pub fn rigid_tap(c: &RigidTap, out: &mut Vec<Step>) {
    out.push(Step::HoldSuppress(true));
    out.push(Step::Overload(c.overload));
    pecks(c, 0, out);
    out.push(Step::Overload(None));
    if c.dwell_us > 0 {
        out.push(Step::Phase(Phase::Dwell));
        out.push(Step::Dwell { us: c.dwell_us });
    }
    out.push(Step::Phase(Phase::Retract));
    out.push(stroke(c, c.start, false));
    out.push(Step::HoldSuppress(false));
}

/// One stroke of the hole `c` to `target`: a cut (spindle in the cutting sense) or a retract.
fn stroke(c: &RigidTap, target: Nm, cutting: bool) -> Step {
    Step::Tap(TapMove {
        axis: c.axis,
        target,
        lead_nm: c.lead_nm,
        rpm: c.rpm,
        spindle_forward: c.right_hand == cutting,
        override_pct: if cutting { 100 } else { c.extraction_pct },
        cutting,
    })
}

/// Appends the cuts from depth `reached` (below the start level) to the bottom, with the
/// retracts between them: at most [`PECKS_PER_CHUNK`] cuts, the rest as a [`Step::More`].
pub(crate) fn pecks(c: &RigidTap, mut reached: Nm, out: &mut Vec<Step>) {
    let dir: Nm = if c.bottom >= c.start { 1 } else { -1 };
    let depth = (c.bottom - c.start).abs();
    let q = match c.peck {
        Peck::None => depth,
        Peck::HighSpeed { q, .. } | Peck::Deep { q } => q.max(1),
    };
    for _ in 0..PECKS_PER_CHUNK {
        reached = reached.saturating_add(q).min(depth);
        out.push(Step::Phase(Phase::Cutting));
        out.push(stroke(c, c.start + dir * reached, true));
        if reached >= depth {
            return;
        }
        out.push(Step::Phase(Phase::Retract));
        match c.peck {
            Peck::HighSpeed { d, .. } => out.push(stroke(c, c.start + dir * (reached - d).max(0), false)),
            Peck::Deep { .. } => out.push(stroke(c, c.start, false)),
            Peck::None => {}
        }
    }
    out.push(Step::More(Box::new(More::RigidTap { cycle: *c, reached })));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cycle(peck: Peck) -> RigidTap {
        RigidTap {
            axis: 0,
            start: 25_000_000,
            bottom: -25_000_000,
            lead_nm: 1_000_000,
            rpm: 1000,
            right_hand: true,
            dwell_us: 3_000_000,
            peck,
            extraction_pct: 100,
            overload: None,
        }
    }

    fn strokes(steps: &[Step]) -> Vec<(Nm, bool, bool)> {
        steps
            .iter()
            .filter_map(|s| match s {
                Step::Tap(t) => Some((t.target, t.cutting, t.spindle_forward)),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn standard_cuts_once_dwells_and_returns() {
        let mut v = Vec::new();
        rigid_tap(&cycle(Peck::None), &mut v);
        assert_eq!(strokes(&v), vec![(-25_000_000, true, true), (25_000_000, false, false)]);
        assert!(v.contains(&Step::Dwell { us: 3_000_000 }));
    }

    #[test]
    fn high_speed_peck_retracts_by_d_and_recuts() {
        // 50 mm deep, q = 20 mm, d = 5 mm: cut to 20, back to 15, cut to 40, back to 35, cut to 50.
        let mut v = Vec::new();
        rigid_tap(&cycle(Peck::HighSpeed { q: 20_000_000, d: 5_000_000 }), &mut v);
        let s: Vec<Nm> = strokes(&v).iter().map(|s| s.0).collect();
        assert_eq!(s, vec![5_000_000, 10_000_000, -15_000_000, -10_000_000, -25_000_000, 25_000_000]);
    }

    #[test]
    fn deep_peck_returns_to_start_each_time() {
        let mut v = Vec::new();
        rigid_tap(&cycle(Peck::Deep { q: 20_000_000 }), &mut v);
        let s: Vec<Nm> = strokes(&v).iter().map(|s| s.0).collect();
        assert_eq!(s, vec![5_000_000, 25_000_000, -15_000_000, 25_000_000, -25_000_000, 25_000_000]);
    }

    #[test]
    fn many_pecks_are_planned_a_chunk_at_a_time() {
        // 50 mm at q = 0.1 mm: 500 cuts, planned 16 at a time; the expanded plan cuts 0.1 mm deeper
        // each time and returns to the start level after each cut.
        let mut v = Vec::new();
        rigid_tap(&cycle(Peck::Deep { q: 100_000 }), &mut v);
        let cuts = |v: &[Step]| strokes(v).iter().filter(|s| s.1).count();
        assert_eq!(cuts(&v), crate::plan::PECKS_PER_CHUNK);
        assert_eq!(v.iter().filter(|s| matches!(s, Step::More(_))).count(), 1);
        let all = crate::plan::expand_all(v);
        let s = strokes(&all);
        assert_eq!(s.iter().filter(|s| s.1).count(), 500);
        for (k, cut) in s.iter().filter(|s| s.1).enumerate() {
            assert_eq!(cut.0, 25_000_000 - (k as Nm + 1) * 100_000);
        }
        assert_eq!(s.len(), 1000);
        assert_eq!(all.last(), Some(&Step::HoldSuppress(false)));
        assert!(!all.iter().any(|s| matches!(s, Step::More(_))));
    }

    #[test]
    fn a_hole_of_one_nanometre_pecks_plans_in_constant_space() {
        // 10 m deep at q = 1 nm would be 10^10 pecks: only the first chunk is planned.
        let mut c = cycle(Peck::HighSpeed { q: 1, d: 1 });
        c.bottom = c.start - 10_000_000_000;
        let mut v = Vec::new();
        rigid_tap(&c, &mut v);
        assert!(v.len() < 4 * crate::plan::PECKS_PER_CHUNK + 16, "{} steps", v.len());
    }

    #[test]
    fn left_hand_cuts_in_reverse() {
        let mut c = cycle(Peck::None);
        c.right_hand = false;
        let mut v = Vec::new();
        rigid_tap(&c, &mut v);
        assert_eq!(strokes(&v), vec![(-25_000_000, true, false), (25_000_000, false, true)]);
    }
}
