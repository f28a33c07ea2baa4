//! Drilling, boring and conventional tapping cycles (Fanuc G73, G74/G84 without rigid mode, G76,
//! G81..G89): the body of one hole, from the R level back to the R level.
//!
//! The dialect positions to the hole and to R (and afterwards returns to the initial level under
//! G98); this builder owns what happens in between, each cycle's whole story in one match arm.
//! The spindle is in speed mode throughout: the feed is an ordinary cutting feed (per minute or per
//! revolution), not synchronised to the spindle angle (that is [`super::rigid_tap`]).
//!
//! Simplifications (documented in `docs/`):
//! - G73 retracts and G83 clearances use the fixed amount the caller passes in `d`;
//! - G76 and G87 do not model the shift away from the bore wall (Q/I/J);
//! - G87 back boring is modelled as a plain feed to the bottom and back (no orientation, no
//!   rapid down past the bore); G88's manual retract (feed hold + jog) is not modelled: the
//!   tool rapids out after the dwell and spindle stop;
//! - G86, G88 and G76 restart the spindle in the direction it had before the cycle.

use crate::plan::{Feed, More, Pos, SpindleEffect, Step, PECKS_PER_CHUNK};
use crate::trace::Phase;
use crate::units::{Micros, Nm};

/// Which cycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DrillKind {
    /// G81: feed to the bottom, rapid out.
    Drill,
    /// G82: feed to the bottom, dwell, rapid out.
    SpotFace,
    /// G83: deep-hole peck: feed `q`, rapid out to R, rapid back down to `d` short of the depth
    /// reached, feed on by `q` (+ `d`), ... until the bottom; dwell; rapid out.
    DeepPeck,
    /// G73: high-speed peck: feed `q`, rapid back by `d`, feed on, ... until the bottom; dwell;
    /// rapid out.
    HighSpeedPeck,
    /// G85: feed in, feed out.
    Bore,
    /// G86: feed in, spindle stop, rapid out, spindle restart.
    BoreStop,
    /// G87 back boring, simplified: feed in, feed out.
    BackBore,
    /// G88: feed in, dwell, spindle stop, rapid out, spindle restart.
    BoreManual,
    /// G89: feed in, dwell, feed out.
    BoreDwell,
    /// G76 fine boring: feed in, dwell, spindle orientation, rapid out, spindle restart.
    FineBore,
    /// G84 (right hand) / G74 (left hand) with the spindle in speed mode: feed in, dwell, spindle
    /// stop and reverse, feed out, spindle stop and back to its direction.
    Tap {
        /// G84: the spindle turns forward (M03) while cutting.
        right_hand: bool,
    },
}

/// One hole of a drilling, boring or conventional tapping cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrillCycle {
    /// Which cycle.
    pub kind: DrillKind,
    /// Tool (drilling) axis slot.
    pub axis: usize,
    /// Where the tool stands when the body starts: over the hole at the R level.
    pub at_r: Pos,
    /// Hole bottom on the tool axis.
    pub bottom: Nm,
    /// Cutting feed.
    pub feed: Feed,
    /// Dwell at the bottom (cycles that dwell; 0: none).
    pub dwell_us: Micros,
    /// Depth of each peck (G73, G83), nm (> 0); ignored by the other cycles.
    pub q: Nm,
    /// G73: retract after each peck; G83: clearance above the depth reached before feeding again.
    pub d: Nm,
    /// Direction the spindle turns in before the cycle (true: forward, M03): the direction G86,
    /// G88 and G76 restart it in.
    pub spindle_forward: bool,
}

/// An M function with its spindle effect.
pub fn spindle_m(code: u32) -> Step {
    let effect = match code {
        3 => SpindleEffect::Forward,
        4 => SpindleEffect::Reverse,
        5 => SpindleEffect::Stop,
        19 => SpindleEffect::Orient,
        _ => SpindleEffect::None,
    };
    Step::Function { letter: 'M', code, effect }
}

/// Appends the body of one hole: from the R level (`at_r`) back to the R level.
pub fn drill(c: &DrillCycle, out: &mut Vec<Step>) {
    let r = c.at_r[c.axis];
    let dir: Nm = if c.bottom >= r { 1 } else { -1 };
    let depth = (c.bottom - r).abs();
    // A position `reached` below R (towards the bottom) on the tool axis.
    let at = |reached: Nm| {
        let mut p = c.at_r;
        p[c.axis] = r + dir * reached;
        p
    };
    let feed_to = |reached: Nm| Step::Feed { target: at(reached), feed: c.feed };
    let rapid_to = |reached: Nm| Step::Rapid { target: at(reached) };
    let dwell = |out: &mut Vec<Step>| {
        if c.dwell_us > 0 {
            out.push(Step::Phase(Phase::Dwell));
            out.push(Step::Dwell { us: c.dwell_us });
        }
    };
    let restart = if c.spindle_forward { 3 } else { 4 };
    let cut = |out: &mut Vec<Step>| {
        out.push(Step::Phase(Phase::Cutting));
        out.push(feed_to(depth));
    };
    match c.kind {
        DrillKind::Drill => {
            cut(out);
            out.push(Step::Phase(Phase::Retract));
            out.push(rapid_to(0));
        }
        DrillKind::SpotFace => {
            cut(out);
            dwell(out);
            out.push(Step::Phase(Phase::Retract));
            out.push(rapid_to(0));
        }
        DrillKind::DeepPeck | DrillKind::HighSpeedPeck => {
            pecks(c, 0, out);
            dwell(out);
            out.push(Step::Phase(Phase::Retract));
            out.push(rapid_to(0));
        }
        DrillKind::Bore | DrillKind::BackBore => {
            cut(out);
            out.push(Step::Phase(Phase::Retract));
            out.push(feed_to(0));
        }
        DrillKind::BoreDwell => {
            cut(out);
            dwell(out);
            out.push(Step::Phase(Phase::Retract));
            out.push(feed_to(0));
        }
        DrillKind::BoreStop | DrillKind::BoreManual => {
            cut(out);
            if c.kind == DrillKind::BoreManual {
                dwell(out);
            }
            out.push(spindle_m(5));
            out.push(Step::Phase(Phase::Retract));
            out.push(rapid_to(0));
            out.push(spindle_m(restart));
        }
        DrillKind::FineBore => {
            cut(out);
            dwell(out);
            out.push(spindle_m(19));
            out.push(Step::Phase(Phase::Retract));
            out.push(rapid_to(0));
            out.push(spindle_m(restart));
        }
        DrillKind::Tap { right_hand } => {
            let (cutting, back) = if right_hand { (3, 4) } else { (4, 3) };
            // Seed 003: feed hold does not stop the machine until the return is complete.
            out.push(Step::HoldSuppress(true));
            cut(out);
            dwell(out);
            out.push(spindle_m(5));
            out.push(spindle_m(back));
            out.push(Step::Phase(Phase::Retract));
            out.push(feed_to(0));
            out.push(spindle_m(5));
            out.push(spindle_m(cutting));
            out.push(Step::HoldSuppress(false));
        }
    }
}

/// Appends the pecks of a G73 / G83 hole from depth `reached` (below R) to the bottom: at most
/// [`PECKS_PER_CHUNK`] cuts, the rest as a [`Step::More`].
pub(crate) fn pecks(c: &DrillCycle, mut reached: Nm, out: &mut Vec<Step>) {
    let r = c.at_r[c.axis];
    let dir: Nm = if c.bottom >= r { 1 } else { -1 };
    let depth = (c.bottom - r).abs();
    let at = |reached: Nm| {
        let mut p = c.at_r;
        p[c.axis] = r + dir * reached;
        p
    };
    let deep = c.kind == DrillKind::DeepPeck;
    // The dialect refuses q <= 0 (FAN-CYC-13); should one come anyway, one cut to the bottom.
    let q = if c.q > 0 { c.q } else { Nm::MAX / 4 };
    for _ in 0..PECKS_PER_CHUNK {
        out.push(Step::Phase(Phase::Cutting));
        if deep && reached > 0 {
            out.push(Step::Rapid { target: at((reached - c.d).max(0)) });
        }
        reached = reached.saturating_add(q).min(depth);
        out.push(Step::Feed { target: at(reached), feed: c.feed });
        if reached >= depth {
            return;
        }
        out.push(Step::Phase(Phase::Retract));
        out.push(Step::Rapid { target: at(if deep { 0 } else { (reached - c.d).max(0) }) });
    }
    out.push(Step::More(Box::new(More::Drill { cycle: *c, reached })));
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    const MM: Nm = 1_000_000;

    fn cycle(kind: DrillKind) -> DrillCycle {
        DrillCycle {
            kind,
            axis: 2,
            at_r: [10 * MM, 20 * MM, 2 * MM, 0, 0, 0],
            bottom: -10 * MM,
            feed: Feed::PerMin(100.0 * MM as f64),
            dwell_us: 500_000,
            q: 5 * MM,
            d: MM,
            spindle_forward: true,
        }
    }

    /// Each step as a short string: `F-10` feed to Z-10, `R2` rapid to Z2, `M5`, `D500000`, phases by
    /// their first letter in brackets.
    fn story(steps: &[Step]) -> Vec<String> {
        steps
            .iter()
            .map(|s| match s {
                Step::Feed { target, .. } => format!("F{}", target[2] / MM),
                Step::Rapid { target } => format!("R{}", target[2] / MM),
                Step::Function { letter, code, .. } => format!("{letter}{code}"),
                Step::Dwell { us } => format!("D{us}"),
                Step::Phase(p) => format!("[{}]", p.name()),
                Step::HoldSuppress(b) => format!("H{}", u8::from(*b)),
                other => format!("{other:?}"),
            })
            .collect()
    }

    #[rstest]
    #[case::g81(DrillKind::Drill, "[cutting] F-10 [retract] R2")]
    #[case::g82(DrillKind::SpotFace, "[cutting] F-10 [dwell] D500000 [retract] R2")]
    #[case::g85(DrillKind::Bore, "[cutting] F-10 [retract] F2")]
    #[case::g87(DrillKind::BackBore, "[cutting] F-10 [retract] F2")]
    #[case::g89(DrillKind::BoreDwell, "[cutting] F-10 [dwell] D500000 [retract] F2")]
    #[case::g86(DrillKind::BoreStop, "[cutting] F-10 M5 [retract] R2 M3")]
    #[case::g88(DrillKind::BoreManual, "[cutting] F-10 [dwell] D500000 M5 [retract] R2 M3")]
    #[case::g76(DrillKind::FineBore, "[cutting] F-10 [dwell] D500000 M19 [retract] R2 M3")]
    #[case::g84(
        DrillKind::Tap { right_hand: true },
        "H1 [cutting] F-10 [dwell] D500000 M5 M4 [retract] F2 M5 M3 H0"
    )]
    #[case::g74(
        DrillKind::Tap { right_hand: false },
        "H1 [cutting] F-10 [dwell] D500000 M5 M3 [retract] F2 M5 M4 H0"
    )]
    fn bodies(#[case] kind: DrillKind, #[case] want: &str) {
        let mut v = Vec::new();
        drill(&cycle(kind), &mut v);
        assert_eq!(story(&v).join(" "), want);
    }

    #[test]
    fn deep_peck_returns_to_r_and_comes_back_short_of_the_depth() {
        // R2 → Z-10: 12 mm, q = 5, d = 1: cut to -3, out, down to -2, cut to -8, out, down to -7,
        // cut to -10, dwell, out.
        let mut v = Vec::new();
        drill(&cycle(DrillKind::DeepPeck), &mut v);
        assert_eq!(
            story(&v).join(" "),
            "[cutting] F-3 [retract] R2 [cutting] R-2 F-8 [retract] R2 [cutting] R-7 F-10 \
             [dwell] D500000 [retract] R2"
        );
    }

    #[test]
    fn high_speed_peck_backs_off_by_d() {
        let mut c = cycle(DrillKind::HighSpeedPeck);
        c.dwell_us = 0;
        let mut v = Vec::new();
        drill(&c, &mut v);
        assert_eq!(
            story(&v).join(" "),
            "[cutting] F-3 [retract] R-2 [cutting] F-8 [retract] R-7 [cutting] F-10 [retract] R2"
        );
    }

    #[test]
    fn many_pecks_expand_to_the_same_story_as_few() {
        // 12 mm at q = 0.1 mm: 120 cuts, planned a chunk at a time; expanded, each G83 peck
        // comes back to 1 mm short of the depth reached and cuts 0.1 mm deeper.
        let mut c = cycle(DrillKind::DeepPeck);
        c.q = MM / 10;
        let mut v = Vec::new();
        drill(&c, &mut v);
        assert!(v.iter().any(|s| matches!(s, Step::More(_))));
        let all = crate::plan::expand_all(v);
        let feeds: Vec<Nm> = all
            .iter()
            .filter_map(|s| match s {
                Step::Feed { target, .. } => Some(target[2]),
                _ => None,
            })
            .collect();
        assert_eq!(feeds.len(), 120);
        for (k, z) in feeds.iter().enumerate() {
            assert_eq!(*z, 2 * MM - (k as Nm + 1) * MM / 10);
        }
        assert_eq!(story(&all[all.len() - 4..]).join(" "), "[dwell] D500000 [retract] R2");
    }

    #[test]
    fn restart_follows_the_spindle_direction_and_upward_holes_work() {
        let mut c = cycle(DrillKind::BoreStop);
        c.spindle_forward = false;
        c.bottom = 12 * MM;
        let mut v = Vec::new();
        drill(&c, &mut v);
        assert_eq!(story(&v).join(" "), "[cutting] F12 M5 [retract] R2 M4");
    }

    #[test]
    fn other_axes_stay_over_the_hole() {
        let mut v = Vec::new();
        drill(&cycle(DrillKind::Drill), &mut v);
        for s in &v {
            if let Step::Feed { target, .. } | Step::Rapid { target } = s {
                assert_eq!((target[0], target[1]), (10 * MM, 20 * MM));
            }
        }
    }
}
