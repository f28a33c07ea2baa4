//! The plant model's settings, derived by each dialect from its parameters.

use crate::trace::AXES;
use crate::units::{Micros, Nm};

/// PLC ladder timing (the project's model of a standard ladder; `plc.*` parameters).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlcConfig {
    /// Strobe (MF/SF/TF) to FIN.
    pub fin_us: Micros,
    /// MF falling to FIN falling.
    pub fin_fall_us: Micros,
    /// M29 strobe to the position-mode request to the drive.
    pub sppos_request_us: Micros,
    /// Position-mode request to the drive's "reached" answer.
    pub sppos_reach_us: Micros,
    /// "Reached" to RGTAP and FIN.
    pub rgtap_us: Micros,
    /// F76.3 falling to RGTAP falling (and the position-mode request dropping).
    pub rgtap_fall_us: Micros,
    /// PLC timer for the position-mode answer after M29 (alarm 5002).
    pub m29_timeout_us: Micros,
    /// PLC timer for FIN of any function (alarm NC-1020).
    pub fin_timeout_us: Micros,
    /// How long the drive must see the spindle stopped before it reports zero speed (ZSP).
    pub zsp_us: Micros,
    /// PLC timer for a spindle that does not rotate while it should in rigid tapping (alarm 5074).
    pub spindle_stall_us: Micros,
}

/// Everything the executor needs to know about the machine.
#[derive(Debug, Clone, PartialEq)]
pub struct PlantConfig {
    /// Interpolation period, µs (1, 2, 4 or 8 ms).
    pub period_us: Micros,
    /// Rapid traverse rate per axis, nm/min.
    pub rapid_nm_min: [f64; AXES],
    /// Rapid acceleration time constant per axis (time to reach the rapid rate), µs.
    pub rapid_ramp_us: [Micros; AXES],
    /// Upper limit of the cutting feed, nm/min.
    pub feed_max_nm_min: f64,
    /// Cutting feed acceleration time constant (time to reach `feed_max_nm_min`), µs.
    pub feed_ramp_us: Micros,
    /// Dry run feed rate, nm/min.
    pub dry_run_nm_min: f64,
    /// Backlash per axis, nm (applied on each reversal of the axis).
    pub backlash_nm: [Nm; AXES],
    /// Maximum spindle speed, rpm.
    pub spindle_max_rpm: u32,
    /// Spindle acceleration time constant (0 → maximum speed), µs.
    pub spindle_ramp_us: Micros,
    /// Spindle brake time (a braked spindle from its speed to rest, KND `nc.spindle_brake_ms`),
    /// µs; 0: the spindle has no brake and slows down at its ramp.
    pub spindle_brake_us: Micros,
    /// Maximum spindle speed in rigid tapping, rpm.
    pub rigid_max_rpm: u32,
    /// Rigid tapping time constant at `rigid_max_rpm` (scaled by S / max: constant acceleration), µs.
    pub rigid_ramp_us: Micros,
    /// Feed hold and single block act during rigid tapping (Fanuc 5200#6 FHD); false: they wait
    /// until the return is complete.
    pub hold_in_rigid_tap: bool,
    /// Spindle orientation (reference return) time, µs.
    pub orient_us: Micros,
    /// M06 strobe to FIN (the tool change), µs; 0: the ordinary FIN delay.
    pub tool_change_us: Micros,
    /// Servo excess error limit for the tap axis while moving, nm (alarm 0411).
    pub excess_error_nm: Nm,
    /// G0 is one coordinated straight line: every axis starts and ends together, the path's
    /// speed and acceleration limited by the slowest axis for its share of the path (LinuxCNC's
    /// trajectory planner). False: each axis rapids at its own rate and ends on its own.
    pub coordinated_rapid: bool,
    /// A spindle start (M3/M4) makes the next cutting move (line or arc, not a rapid) wait until
    /// the spindle is at speed (LinuxCNC's motion controller: `atspeed_next_feed`,
    /// `spindle.0.at-speed`): the executor puts a `Step::AwaitAtSpeed` in front of it (DEC-143).
    pub feed_waits_at_speed: bool,
    /// A spindle override acts on the turning spindle at once (speed mode, unless the program
    /// holds the overrides), and the moves that follow the spindle follow it (LinuxCNC: motion
    /// scales the commanded speed in every servo period). False: it acts from the next speed
    /// command (COM-MOT-06).
    pub spindle_override_at_once: bool,
    /// Single block stops before a block that moves the axes, not after every block (LinuxCNC
    /// 2.9's step, L-121): the blocks after a step's last move that move nothing (M2, `G80 M4`,
    /// a dwell) run in that step; the program's first block is a step of its own. False: a stop
    /// after every block (COM-INP-03).
    pub step_stops_before_motion: bool,
    /// Servo periods between the spindle's index pulse and the first period of a move started
    /// on it, after the one the pulse falls in: 0, the next period (the reference's own); 1
    /// (LinuxCNC: the encoder clears `spindle.N.index-enable` after motion has run, and motion
    /// copies the pin into its status after its planner has run, so the planner sees the index
    /// in the second period after it; tp.c tpCheckAtSpeed, control.c; DEC-157).
    pub index_latency_periods: u32,
    /// A synchronised move straight after another (nothing between them but bookkeeping) goes on
    /// with the run's synchronisation instead of waiting for a new index (LinuxCNC: tp.c
    /// `tpActivateSegment` waits for the index only "if we aren't already synced"; two G33 in a
    /// row, DEC-170).
    pub sync_run_continues: bool,
    /// LinuxCNC 2.9's trajectory planner (`nc.trajectory_planner` 209, DEC-163): under G64
    /// (`Step::PathMode`), a rapid, line or arc after which no move enters the planner's queue
    /// (the next command waits for the motion to end: a rigid tap, a spindle or coolant command,
    /// a dwell, a stop, the program end) keeps its parabolic end condition and runs at half its
    /// acceleration for its whole length (tc.c `tcGetOverallMaxAccel`). False: every move at its
    /// full acceleration (LinuxCNC 2.10, and any move that stops exactly).
    pub parabolic_half_accel: bool,
    /// The blend tolerance the planner powers on with, nm (0: none; `Step::PathMode` changes
    /// it): LinuxCNC's startup code's G64 P (`nc.startup_g64_p_mm`, DEC-169).
    pub power_on_tolerance_nm: f64,
    /// The PLC ladder.
    pub plc: PlcConfig,
    /// The override switches' ranges and steps.
    pub overrides: OverrideLimits,
}

/// The range and step of the operator's override switches, from each dialect's documents
/// (`nc.*_override_*` parameters; COM-MOT-07, DEC-112).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OverrideLimits {
    /// Top position of the feed override switch, %.
    pub feed_max_pct: u32,
    /// Step between two positions of the feed override switch, % (1: any whole percent).
    pub feed_step_pct: u32,
    /// Lowest position of the spindle override switch, %.
    pub spindle_min_pct: u32,
    /// Top position of the spindle override switch, %.
    pub spindle_max_pct: u32,
}

impl OverrideLimits {
    /// The feed override a requested value gives: beyond the top position, the top position;
    /// between two positions, the lower one (never faster than asked).
    pub fn feed(&self, pct: u32) -> u32 {
        let v = pct.min(self.feed_max_pct);
        v - v % self.feed_step_pct.max(1)
    }

    /// The spindle override a requested value gives: clamped to the switch's range.
    pub fn spindle(&self, pct: u32) -> u32 {
        pct.min(self.spindle_max_pct).max(self.spindle_min_pct.min(self.spindle_max_pct))
    }
}

#[cfg(test)]
mod tests {
    use super::OverrideLimits;

    /// DEC-112: the KND switch (seed 001, 0..150 % in 10 % steps) and the project default.
    #[test]
    fn override_positions_beyond_and_between() {
        let knd =
            OverrideLimits { feed_max_pct: 150, feed_step_pct: 10, spindle_min_pct: 0, spindle_max_pct: 200 };
        assert_eq!(
            [knd.feed(200), knd.feed(150), knd.feed(75), knd.feed(9), knd.feed(0)],
            [150, 150, 70, 0, 0]
        );
        let lcnc =
            OverrideLimits { feed_max_pct: 120, feed_step_pct: 1, spindle_min_pct: 50, spindle_max_pct: 100 };
        assert_eq!([lcnc.feed(150), lcnc.feed(73)], [120, 73]);
        assert_eq!([lcnc.spindle(20), lcnc.spindle(80), lcnc.spindle(150)], [50, 80, 100]);
    }
}
