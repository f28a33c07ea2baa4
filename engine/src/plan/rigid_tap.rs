//! Rigid tapping: the tap axis locked to the spindle, in one of three ways (standard, high-speed
//! peck, peck back to the start level), for GSK G84/G88 and Fanuc G84/G74 alike.
//!
//! The dialect positions to the hole (and to R on a mill); this builder takes over at the start
//! level and ends back at it. Rule ids: GSK-RT-*, FAN-RT-* in `docs/`.

use crate::plan::{OverloadWatch, Step, TapMove};
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
    let dir: Nm = if c.bottom >= c.start { 1 } else { -1 };
    let stroke = |target: Nm, cutting: bool| {
        Step::Tap(TapMove {
            axis: c.axis,
            target,
            lead_nm: c.lead_nm,
            rpm: c.rpm,
            spindle_forward: c.right_hand == cutting,
            override_pct: if cutting { 100 } else { c.extraction_pct },
            cutting,
        })
    };
    out.push(Step::HoldSuppress(true));
    out.push(Step::Overload(c.overload));
    let depth = (c.bottom - c.start).abs();
    let q = match c.peck {
        Peck::None => depth,
        Peck::HighSpeed { q, .. } | Peck::Deep { q } => q.max(1),
    };
    let mut reached: Nm = 0;
    loop {
        reached = (reached + q).min(depth);
        out.push(Step::Phase(Phase::Cutting));
        out.push(stroke(c.start + dir * reached, true));
        if reached >= depth {
            break;
        }
        out.push(Step::Phase(Phase::Retract));
        match c.peck {
            Peck::HighSpeed { d, .. } => out.push(stroke(c.start + dir * (reached - d).max(0), false)),
            Peck::Deep { .. } => out.push(stroke(c.start, false)),
            Peck::None => {}
        }
    }
    out.push(Step::Overload(None));
    if c.dwell_us > 0 {
        out.push(Step::Phase(Phase::Dwell));
        out.push(Step::Dwell { us: c.dwell_us });
    }
    out.push(Step::Phase(Phase::Retract));
    out.push(stroke(c.start, false));
    out.push(Step::HoldSuppress(false));
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
    fn left_hand_cuts_in_reverse() {
        let mut c = cycle(Peck::None);
        c.right_hand = false;
        let mut v = Vec::new();
        rigid_tap(&c, &mut v);
        assert_eq!(strokes(&v), vec![(-25_000_000, true, false), (25_000_000, false, true)]);
    }
}
