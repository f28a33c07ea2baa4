//! Tapping with the tap axis following the spindle's encoder, the spindle in speed mode (KND
//! G93, seed 001; LinuxCNC G33.1): cut at lead × the spindle's speed (LinuxCNC: from its next
//! index pulse), reaching the end point still locked to it; there the spindle brakes (KND) or
//! reverses (LinuxCNC) and the tap follows it (overshoot = lead × revolutions turned meanwhile,
//! within an allowance); on KND once the drive reports zero speed the spindle turns the other way
//! and the tap returns behind it to the start point, where both stop, and the spindle then
//! resumes its earlier direction; LinuxCNC follows the reversed spindle out through the start,
//! where the spindle is commanded its earlier direction again and turns through zero, follows it
//! past the start until it turns the other way and moves back unsynchronised (DEC-87, DEC-149).
//! Rules KND-G93-* in
//! `docs/rules/knd-lathe.md`, LCNC-G331-* in `docs/rules/linuxcnc.md`.
//!
//! The dialect positions to the start point; this builder takes over there and ends there.

use crate::alarm::AlarmKind;
use crate::plan::{Follow, FollowKind, SpindleEffect, Step};
use crate::trace::{Phase, Signal};
use crate::units::{Micros, Nm};

/// One hole tapped behind the spindle's encoder.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FollowTap {
    /// Tap axis slot.
    pub axis: usize,
    /// Start point on the tap axis.
    pub start: Nm,
    /// End point on the tap axis.
    pub end: Nm,
    /// Lead, nm per revolution (> 0).
    pub lead_nm: i64,
    /// Commanded spindle speed, rpm (the return runs at it).
    pub rpm: u32,
    /// The spindle's direction before the block (true: M03).
    pub forward: bool,
    /// Time the spindle takes from `rpm` to rest (brake time, or its speed-mode ramp), µs.
    pub brake_us: Micros,
    /// How far past the end point the braking tap may go, nm.
    pub allowance_nm: Nm,
    /// The CNC's timer for zero speed (ZSP) after each stop, µs; `None`: the spindle reverses
    /// without waiting for zero speed (LinuxCNC G33.1).
    pub zsp_timeout_us: Option<Micros>,
    /// Reversals take up the tap axis' backlash (KND P003 RVDL).
    pub backlash: bool,
    /// A stall stops the tap and a brake cut short at the allowance goes on braking the spindle
    /// (KND, see [`Follow::encoder_bound`]).
    pub encoder_bound: bool,
    /// Raised when the spindle does not turn for the cut.
    pub not_turning: AlarmKind,
    /// Raised when the overshoot reaches `allowance_nm`.
    pub overshoot: AlarmKind,
    /// LinuxCNC's way: the cut starts at the spindle's next index pulse, and the way out follows
    /// the reversed spindle through the start, brakes with it past the start and moves back
    /// unsynchronised (instead of the return to rest at the start).
    pub linuxcnc: bool,
}

/// Appends the steps of one hole, from the start point back to it.
pub fn follow_tap(c: &FollowTap, out: &mut Vec<Step>) {
    let dir: Nm = if c.end >= c.start { 1 } else { -1 };
    let follow = |target, kind, alarm| {
        Step::Follow(Follow {
            axis: c.axis,
            target,
            lead_nm: c.lead_nm,
            backlash: c.backlash,
            kind,
            alarm,
            encoder_bound: c.encoder_bound,
            index: c.linuxcnc,
        })
    };
    let zsp = c.zsp_timeout_us.map(|timeout_us| Step::AwaitSignal {
        signal: Signal::Zsp,
        value: true,
        timeout_us,
        alarm: AlarmKind::ZeroSpeedNotReported,
    });
    out.push(Step::HoldSuppress(true));
    out.push(Step::Phase(Phase::Cutting));
    out.push(follow(c.end, FollowKind::Cut, c.not_turning));
    out.push(follow(
        c.end.saturating_add(dir * c.allowance_nm),
        FollowKind::Brake { brake_us: c.brake_us },
        c.overshoot,
    ));
    if let Some(zsp) = &zsp {
        out.push(Step::Phase(Phase::Dwell));
        out.push(zsp.clone());
    }
    out.push(Step::Phase(Phase::Retract));
    let (code, effect) = if c.forward { (3, SpindleEffect::Forward) } else { (4, SpindleEffect::Reverse) };
    if c.linuxcnc {
        // Out behind the reversed spindle through the start, where the spindle is commanded its
        // own sense again (tp.c RETRACTION -> FINAL_REVERSAL: it turns through zero without a
        // stop); the tap follows it past the start (the same allowance) until it turns the other
        // way, then goes back unsynchronised (shared/linuxcnc-real README items 5 and 7; the
        // recordings' speed command flips as the tap passes the start, DEC-149).
        out.push(follow(c.start, FollowKind::Through { rpm: c.rpm, forward: !c.forward }, c.overshoot));
        out.push(Step::FunctionWithMotion { letter: 'M', code, effect });
        out.push(follow(c.start.saturating_sub(dir * c.allowance_nm), FollowKind::Reversal, c.overshoot));
        // The move back is no longer synchronised (tp.c FINAL_REVERSAL clears the segment's
        // `synchronized`), so a feed hold acts in it: one pending since the tap began holds it
        // before it starts, one given during it stops it at the axis' acceleration; cycle start
        // carries it on (tpGetFeedScale pauses unsynchronised segments only; DEC-157).
        out.push(Step::HoldSuppress(false));
        out.push(follow(c.start, FollowKind::Unsynced, c.overshoot));
        out.push(Step::AwaitFunction);
    } else {
        out.push(follow(c.start, FollowKind::Return { rpm: c.rpm, forward: !c.forward }, c.overshoot));
        out.extend(zsp);
        out.push(Step::Function { letter: 'M', code, effect });
    }
    out.push(Step::HoldSuppress(false));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cut_brake_wait_return_wait_resume() {
        let c = FollowTap {
            axis: 2,
            start: 5_000_000,
            end: -20_000_000,
            lead_nm: 1_500_000,
            rpm: 300,
            forward: true,
            brake_us: 200_000,
            allowance_nm: 50_000_000,
            zsp_timeout_us: Some(5_000_000),
            backlash: true,
            encoder_bound: true,
            not_turning: AlarmKind::SpindleNotTurning,
            overshoot: AlarmKind::TapOvershoot,
            linuxcnc: false,
        };
        let mut v = Vec::new();
        follow_tap(&c, &mut v);
        let kinds: Vec<_> = v
            .iter()
            .filter_map(|s| match s {
                Step::Follow(f) => Some((f.target, f.kind)),
                _ => None,
            })
            .collect();
        assert_eq!(
            kinds,
            vec![
                (-20_000_000, FollowKind::Cut),
                (-70_000_000, FollowKind::Brake { brake_us: 200_000 }),
                (5_000_000, FollowKind::Return { rpm: 300, forward: false }),
            ]
        );
        assert_eq!(v.iter().filter(|s| matches!(s, Step::AwaitSignal { .. })).count(), 2);
        assert!(v.contains(&Step::Function { letter: 'M', code: 3, effect: SpindleEffect::Forward }));
    }
}
