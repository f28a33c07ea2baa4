//! Tapping with the tap axis following the spindle's encoder, the spindle in speed mode (KND
//! G93, seed 001): cut at lead × the spindle's speed; at the end point the spindle brakes and the
//! tap follows it (overshoot = lead × revolutions turned while braking, within an allowance);
//! once the drive reports zero speed the spindle turns the other way and the tap returns behind
//! it to the start point, where both stop; after zero speed again the spindle resumes its
//! earlier direction. Rules KND-G93-* in `docs/rules/knd-lathe.md`.
//!
//! The dialect positions to the start point; this builder takes over there and ends there.

use crate::alarm::AlarmKind;
use crate::plan::{Follow, FollowKind, SpindleEffect, Step};
use crate::trace::{Phase, Signal};
use crate::units::{Micros, Nm};

/// One G93 hole.
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
    /// Spindle brake time, µs.
    pub brake_us: Micros,
    /// How far past the end point the braking tap may go, nm.
    pub allowance_nm: Nm,
    /// The CNC's timer for zero speed after each stop, µs.
    pub zsp_timeout_us: Micros,
    /// Reversals take up the tap axis' backlash (KND P003 RVDL).
    pub backlash: bool,
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
            encoder_bound: true,
        })
    };
    let zsp = Step::AwaitSignal {
        signal: Signal::Zsp,
        value: true,
        timeout_us: c.zsp_timeout_us,
        alarm: AlarmKind::ZeroSpeedNotReported,
    };
    out.push(Step::HoldSuppress(true));
    out.push(Step::Phase(Phase::Cutting));
    out.push(follow(c.end, FollowKind::Cut, AlarmKind::SpindleNotTurning));
    out.push(follow(
        c.end.saturating_add(dir * c.allowance_nm),
        FollowKind::Brake { brake_us: c.brake_us },
        AlarmKind::TapOvershoot,
    ));
    out.push(Step::Phase(Phase::Dwell));
    out.push(zsp.clone());
    out.push(Step::Phase(Phase::Retract));
    out.push(follow(
        c.start,
        FollowKind::Return { rpm: c.rpm, forward: !c.forward },
        AlarmKind::TapOvershoot,
    ));
    out.push(zsp);
    let (code, effect) = if c.forward { (3, SpindleEffect::Forward) } else { (4, SpindleEffect::Reverse) };
    out.push(Step::Function { letter: 'M', code, effect });
    out.push(Step::HoldSuppress(false));
}

/// One LinuxCNC G33.1 hole (rules LCNC-G331-*): the tap follows the spindle in, the spindle is
/// reversed at the end point and the tap follows it through the reversal (overshoot, at most
/// `overshoot_max` past the end point), then back out to the start point, where the spindle takes
/// its direction again. No zero-speed wait: LinuxCNC reverses without one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReversingTap {
    /// Tap axis slot.
    pub axis: usize,
    /// Start point on the tap axis.
    pub start: Nm,
    /// End point on the tap axis.
    pub end: Nm,
    /// Lead, nm per revolution (> 0).
    pub lead_nm: i64,
    /// Commanded spindle speed, rpm.
    pub rpm: u32,
    /// The spindle's direction before the block (true: M03).
    pub forward: bool,
    /// Time the spindle takes to stop from `rpm` (its speed-mode ramp), µs.
    pub brake_us: Micros,
    /// How far past the end point the tap may follow the reversing spindle, nm.
    pub overshoot_max: Nm,
    /// Raised when the spindle does not turn for the cut.
    pub not_turning: AlarmKind,
    /// Raised when the overshoot reaches `overshoot_max`.
    pub overshoot: AlarmKind,
}

/// Appends the steps of one G33.1 hole, from the start point back to it.
pub fn reversing_tap(c: &ReversingTap, out: &mut Vec<Step>) {
    let dir: Nm = if c.end >= c.start { 1 } else { -1 };
    let follow = |target, kind, alarm| {
        Step::Follow(Follow {
            axis: c.axis,
            target,
            lead_nm: c.lead_nm,
            backlash: false,
            kind,
            alarm,
            encoder_bound: false,
        })
    };
    out.push(Step::HoldSuppress(true));
    out.push(Step::Phase(Phase::Cutting));
    out.push(follow(c.end, FollowKind::Cut, c.not_turning));
    out.push(follow(
        c.end.saturating_add(dir * c.overshoot_max),
        FollowKind::Brake { brake_us: c.brake_us },
        c.overshoot,
    ));
    out.push(Step::Phase(Phase::Retract));
    out.push(follow(c.start, FollowKind::Return { rpm: c.rpm, forward: !c.forward }, c.overshoot));
    let (code, effect) = if c.forward { (3, SpindleEffect::Forward) } else { (4, SpindleEffect::Reverse) };
    out.push(Step::Function { letter: 'M', code, effect });
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
            zsp_timeout_us: 5_000_000,
            backlash: true,
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
