//! Plan: what a block or a cycle becomes — a sequence of [`Step`]s (motions, dwells, PLC actions,
//! waits) that the executor carries out in order.
//!
//! Each cycle's whole story is one builder in its own file ([`rigid_tap`], [`drill`]); the executor
//! has no cycle-specific code.

pub mod drill;
pub mod follow_tap;
pub mod rigid_tap;
pub mod thread;
pub mod thread_832;
pub mod thread_g76;
pub mod thread_pass;

pub use thread_pass::{PassLaw, ThreadPass, ThreadRetract};

use crate::alarm::{Alarm, AlarmKind};
use crate::input::CurrentSource;
use crate::trace::{Phase, Signal, AXES};
use crate::units::{Micros, Nm};

/// Physical positions of every axis slot (radius for a lathe's X), nm or nano-degrees.
pub type Pos = [Nm; AXES];

/// A feed rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Feed {
    /// nm per minute along the path.
    PerMin(f64),
    /// nm per spindle revolution along the path.
    PerRev(f64),
}

/// The plane of an arc or of a drilling cycle (the tool axis is normal to it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plane {
    /// G17: XY, tool along Z.
    Xy,
    /// G18: ZX, tool along Y.
    Zx,
    /// G19: YZ, tool along X.
    Yz,
}

impl Plane {
    /// The two axis slots of the plane (first, second) and the normal axis.
    pub fn axes(self) -> (usize, usize, usize) {
        match self {
            Plane::Xy => (0, 1, 2),
            Plane::Zx => (2, 0, 1),
            Plane::Yz => (1, 2, 0),
        }
    }
}

/// Constant surface speed in force (KND G96): the spindle speed follows the X diameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Css {
    /// Surface speed, m/min.
    pub m_min: u32,
    /// The G50 S speed limit, rpm (0: none given, only the machine's).
    pub limit_rpm: u32,
    /// Machine X (radius, nm) of the spindle's centre line: the program's X0.
    pub x_zero: Nm,
}

impl Css {
    /// The speed for machine X `x` (radius, nm), rpm: 1000 · v / (π · diameter in mm), clamped by
    /// the G50 S limit and `max_rpm`; on the centre line, the clamp.
    pub fn rpm(&self, x: Nm, max_rpm: u32) -> f64 {
        let limit = if self.limit_rpm > 0 { self.limit_rpm.min(max_rpm) } else { max_rpm } as f64;
        let dia_mm = 2.0 * (x - self.x_zero).unsigned_abs() as f64 / 1e6;
        if dia_mm == 0.0 {
            return limit;
        }
        (1000.0 * self.m_min as f64 / (std::f64::consts::PI * dia_mm)).min(limit)
    }
}

/// What an M function does to the spindle model when it is output.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SpindleEffect {
    /// Nothing.
    None,
    /// M03: turn forward at the commanded speed.
    Forward,
    /// M04: turn in reverse at the commanded speed.
    Reverse,
    /// M05: stop.
    Stop,
    /// M19: orient, coming to rest on a whole turn (angle 0); FIN when complete.
    Orient,
    /// S word: new commanded speed, rpm.
    Speed(u32),
}

/// One synchronised (rigid) tapping stroke: the tap axis follows the spindle, travel = lead ×
/// revolutions, both under one acceleration profile.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TapMove {
    /// Tap axis slot.
    pub axis: usize,
    /// End of the stroke on the tap axis (physical nm).
    pub target: Nm,
    /// Lead in nm per revolution (> 0).
    pub lead_nm: i64,
    /// Programmed spindle speed, rpm (> 0).
    pub rpm: u32,
    /// Spindle direction during this stroke: true = forward (M03 sense).
    pub spindle_forward: bool,
    /// Speed override of this stroke in % (extraction override on retracts), 100 = none.
    pub override_pct: u32,
    /// Cutting stroke (into the material) rather than a retract.
    pub cutting: bool,
}

/// One motion of an axis that follows the spindle's encoder while the spindle is in speed mode
/// (not position mode): travel = lead × the revolutions the spindle turns. No rigid tapping
/// signals (RGSPP/RGSPM) are involved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Follow {
    /// The following axis slot.
    pub axis: usize,
    /// Where the axis goes (`Cut`, `Return`), or the farthest it may go (`Brake`).
    pub target: Nm,
    /// Lead, nm per revolution (> 0).
    pub lead_nm: i64,
    /// Whether a reversal of the axis takes up its backlash first (while the spindle turns).
    pub backlash: bool,
    /// What the spindle does meanwhile.
    pub kind: FollowKind,
    /// `Cut`: raised when the spindle is not turning; `Brake`: raised when the axis reaches
    /// `target` before the spindle has stopped.
    pub alarm: AlarmKind,
    /// The axis is tied to the encoder to the end (KND G93): a spindle stall stops it at once
    /// (`SpindleNotTurning`), and a spindle whose braking the axis cannot follow any farther
    /// (`Brake` cut short) goes on braking to rest.
    pub encoder_bound: bool,
    /// `Cut`: start at the spindle's next index pulse (LinuxCNC: a synchronised move waits for
    /// `spindle.N.index-enable` to clear).
    pub index: bool,
}

/// What the spindle does while an axis follows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FollowKind {
    /// The spindle keeps turning at its speed; the axis runs at lead × that speed (with the
    /// cutting feed's acceleration) to the target.
    Cut,
    /// The spindle brakes from its present speed to rest in `brake_us`; the axis follows it,
    /// overshooting by lead × the revolutions turned while braking.
    Brake {
        /// Brake time, µs.
        brake_us: Micros,
    },
    /// The spindle, at rest, turns at `rpm` (`forward`: M03 sense) with its speed-mode
    /// acceleration; the axis follows it to the target, where both come to rest.
    Return {
        /// Speed, rpm.
        rpm: u32,
        /// Direction.
        forward: bool,
    },
    /// The spindle, from rest, is commanded to `rpm` (`forward`: M03 sense) at its speed-mode
    /// ramp; the axis follows it, locked, through the target without stopping (a `Brake` carries
    /// it on): LinuxCNC's G33.1 way out.
    Through {
        /// Speed, rpm.
        rpm: u32,
        /// Direction.
        forward: bool,
    },
    /// The spindle, already commanded its other sense, ramps through zero; the axis follows it,
    /// braking behind it, to the instant it turns the other way, overshooting by lead × the
    /// revolutions turned meanwhile (LinuxCNC's G33.1 past the start: the spindle is not brought
    /// to rest).
    Reversal,
    /// The axis alone, unsynchronised, to the target at its rapid rate and time constant; the
    /// spindle keeps its own state (LinuxCNC's final move back to the G33.1 start).
    Unsynced,
}

/// The overload watch of a GSK rigid tapping cycle (word D or parameter 271).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OverloadWatch {
    /// Threshold, % of rated current.
    pub threshold_pct: u32,
    /// Which motor (parameter 186 bit 5).
    pub source: CurrentSource,
    /// The current must stay above the threshold this long (parameter 270).
    pub delay_us: Micros,
    /// Where the tap retracts to (the cycle's start point on the tap axis).
    pub return_to: Nm,
}

/// One thing the executor does.
#[derive(Debug, Clone, PartialEq)]
pub enum Step {
    /// The machining phase changes (reported in the trace).
    Phase(Phase),
    /// Positioning: each axis at its own rapid rate, independently.
    Rapid {
        /// End positions.
        target: Pos,
    },
    /// Linear interpolation at a feed.
    Feed {
        /// End positions.
        target: Pos,
        /// Feed rate.
        feed: Feed,
    },
    /// Circular (helical) interpolation.
    Arc {
        /// End positions.
        target: Pos,
        /// Centre in the plane (first, second axis).
        center: [Nm; 2],
        /// Plane.
        plane: Plane,
        /// Clockwise (G02) when seen from the positive normal.
        clockwise: bool,
        /// Feed rate.
        feed: Feed,
    },
    /// Dwell.
    Dwell {
        /// Duration in µs.
        us: Micros,
    },
    /// An M, S or T function: strobe, effect, wait for FIN.
    Function {
        /// `M`, `S` or `T`.
        letter: char,
        /// Its number.
        code: u32,
        /// What it does to the spindle.
        effect: SpindleEffect,
    },
    /// An M, S or T function output together with the motion that follows it: strobe and effect
    /// now, the next step starts at once, the strobe drops when FIN comes (KND-LEX-04).
    FunctionWithMotion {
        /// `M`, `S` or `T`.
        letter: char,
        /// Its number.
        code: u32,
        /// What it does to the spindle.
        effect: SpindleEffect,
    },
    /// Waits until the strobe of the last [`Step::FunctionWithMotion`] has dropped (its FIN came).
    AwaitFunction,
    /// M29: the rigid tapping handshake (F76.3, position mode, RGTAP, FIN).
    RigidEnter {
        /// The M code to output (29, or the value of Fanuc 5210).
        code: u32,
        /// The rigid tapping speed, rpm.
        rpm: u32,
    },
    /// Checks that RGTAP is on; raises `alarm` otherwise.
    RigidCheck {
        /// The dialect's alarm for a missing RGTAP.
        alarm: AlarmKind,
    },
    /// Leaves rigid tapping mode: F76.3 falls; with `wait_rgtap`, the next step waits for RGTAP
    /// to fall (RTCRG = 0).
    RigidExit {
        /// Wait for RGTAP to fall before going on.
        wait_rgtap: bool,
    },
    /// A synchronised tapping stroke.
    Tap(TapMove),
    /// Spindle reference return (orientation) before rigid tapping (GSK RTORI).
    Orient,
    /// Feed hold and single block suppressed (true) or honoured again (false).
    HoldSuppress(bool),
    /// Constant surface speed on (G96, its S or limit changed) or off (G97).
    Css(Option<Css>),
    /// Sets or clears the overload watch.
    Overload(Option<OverloadWatch>),
    /// M00 (optional = false) or M01 (optional = true): program stop.
    Stop {
        /// M01.
        optional: bool,
    },
    /// M02 / M30: end of program.
    End,
    /// Raise an alarm at this point of the execution and stop.
    Alarm(Alarm),
    /// Report an alarm at this point and go on: the motion queued before it still runs (LinuxCNC's
    /// read-ahead finding an error while reading a line ahead of motion, LCNC-LEX-05; a
    /// [`Step::Halt`] follows where the program stops).
    Report(Alarm),
    /// The run ends here on the alarm already reported by a [`Step::Report`] (end reason
    /// `alarm`, no second alarm).
    Halt,
    /// LinuxCNC's path control mode from here on: `continuous` under G64 (the planner may blend
    /// a move's end), false under G61 and G61.1 and inside a canned cycle (rs274 runs a cycle's
    /// moves in G61). Emitted only for LinuxCNC 2.9's planner (`nc.trajectory_planner` 209),
    /// whose half acceleration it decides (`PlantConfig::parabolic_half_accel`, DEC-163).
    PathMode {
        /// G64.
        continuous: bool,
        /// The blend tolerance the planner gives the moves from here on, nm (G64 P; 0: none).
        tolerance_nm: Nm,
    },
    /// An axis locked to a spindle in speed mode (the spindle leads, the axis follows its
    /// encoder): see [`Follow`].
    Follow(Follow),
    /// Waits until `signal` has `value`; raises `alarm` when it has not come `timeout_us` after
    /// the wait began (the CNC's own timer, not the PLC's).
    AwaitSignal {
        /// The signal.
        signal: Signal,
        /// The value awaited.
        value: bool,
        /// The timer, µs.
        timeout_us: Micros,
        /// Raised when the timer runs out.
        alarm: AlarmKind,
    },
    /// A spindle-synchronised thread pass, the one step of every threading cycle (see
    /// [`ThreadPass`]).
    Thread(ThreadPass),
    /// Stop and wait for cycle start, as after a feed hold.
    Hold,
    /// A point inside a block where single block stops (the end of one pass of a multi-pass
    /// cycle).
    SingleBlockStop,
    /// The rest of a peck cycle, expanded into its steps when the executor reaches it (see
    /// [`More`]).
    More(Box<More>),
    /// Feed and spindle overrides held at 100 % (true) or honoured again (false), feed hold
    /// still honoured (LinuxCNC `DISABLE_FEED_OVERRIDE` / `DISABLE_SPEED_OVERRIDE` in G84/G74).
    OverrideLock(bool),
    /// Waits until the spindle is at speed: its speed change under way has ended and it is not
    /// stalled (a stalled spindle never is: the wait lasts); goes on at once when it is. The one
    /// at-speed wait (DEC-143): LinuxCNC's before a spindle-synchronised move (G33, G33.1, each
    /// G76 pass), and the executor's own before the first cutting move after a spindle start
    /// (`PlantConfig::feed_waits_at_speed`).
    AwaitAtSpeed,
}

/// Most pecks a cycle builder plans at once: a hole of more pecks ends its first chunk with a
/// [`Step::More`] that the executor expands into the next chunk when it gets there. A peck
/// cycle can take millions of pecks (a deep hole with a tiny Q), and a run's cost must grow with
/// the events it reaches, never with what it has not reached yet (found by fuzzing: a GSK
/// `G84 Z2500 Q5` planned 500 000 pecks before its first stroke).
pub const PECKS_PER_CHUNK: usize = 16;

/// The pecks of a cycle still to plan: the cycle and the depth reached so far.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum More {
    /// Rigid tapping pecks.
    RigidTap {
        /// The hole.
        cycle: rigid_tap::RigidTap,
        /// Depth below the start level reached so far, nm.
        reached: Nm,
    },
    /// Drilling pecks (G73, G83).
    Drill {
        /// The hole.
        cycle: drill::DrillCycle,
        /// Depth below R reached so far, nm.
        reached: Nm,
    },
    /// Thread passes.
    Thread {
        /// The cycle.
        cycle: thread::ThreadCycle,
        /// The next pass to plan (0-based).
        next: u64,
    },
    /// Thread cutting passes (Heidenhain cycle 832).
    Thread832 {
        /// The cycle.
        cycle: thread_832::ThreadCycle,
        /// Index of the next pass.
        next: u64,
    },
}

impl More {
    /// Appends the next chunk of pecks (ending with another [`Step::More`] when pecks remain).
    pub fn expand(&self, out: &mut Vec<Step>) {
        match self {
            More::RigidTap { cycle, reached } => rigid_tap::pecks(cycle, *reached, out),
            More::Drill { cycle, reached } => drill::pecks(cycle, *reached, out),
            More::Thread { cycle, next } => thread::passes(cycle, *next, out),
            More::Thread832 { cycle, next } => thread_832::passes(cycle, *next, out),
        }
    }
}

/// `steps` with every [`Step::More`] expanded, recursively: the whole plan (for tests and tools
/// that look at a plan rather than run it).
pub fn expand_all(steps: Vec<Step>) -> Vec<Step> {
    let mut out = Vec::with_capacity(steps.len());
    let mut todo: Vec<Step> = steps.into_iter().rev().collect();
    while let Some(s) = todo.pop() {
        match s {
            Step::More(m) => {
                let mut v = Vec::new();
                m.expand(&mut v);
                todo.extend(v.into_iter().rev());
            }
            s => out.push(s),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::Css;

    #[test]
    fn surface_speed_law_and_its_clamps() {
        // X0 of the program at machine radius 10 mm; 150 m/min.
        let css = Css { m_min: 150, limit_rpm: 2000, x_zero: 10_000_000 };
        // Diameter 100 mm (radius 50 mm from the centre line): 1000 x 150 / (pi x 100).
        let r = css.rpm(60_000_000, 3000);
        assert!((r - 477.464_829).abs() < 1e-5, "{r}");
        // Either side of the centre line alike.
        assert_eq!(css.rpm(-40_000_000, 3000), r);
        // Small diameters: the G50 S limit; on the centre line the clamp.
        assert_eq!(css.rpm(20_000_000, 3000), 2000.0);
        assert_eq!(css.rpm(10_000_000, 3000), 2000.0);
        // No G50 S: the machine's limit; a G50 S above it: the machine's.
        assert_eq!(Css { limit_rpm: 0, ..css }.rpm(10_000_000, 3000), 3000.0);
        assert_eq!(Css { limit_rpm: 5000, ..css }.rpm(10_000_000, 3000), 3000.0);
    }
}
