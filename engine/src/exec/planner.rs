//! LinuxCNC 2.9's trajectory planner, where it departs from the exact stop the executor models
//! otherwise (`PlantConfig::parabolic_half_accel`, `nc.trajectory_planner` 209, DEC-163).
//!
//! In 2.9 a move added under G64 gets the parabolic end condition (tc.c `tcSetupState`), and
//! every segment whose end condition is parabolic runs at half its acceleration for its whole
//! length (tc.c `tcGetOverallMaxAccel`: "scaled down by 1/2 so that the sum of the two does not
//! exceed the maximum", applied whether a blend follows or not). The end condition changes only
//! when the next move enters the planner's queue (tp.c `tpAddLine`: `handleModeChange`,
//! `tcFlagEarlyStop` and the blend arc or tangent set it to stop or tangent), so a move keeps it
//! when nothing follows it in the queue: the next command is one the task carries out only once
//! the motion has ended (emctaskmain.cc `emcTaskCheckPreconditions`: a rigid tap, a spindle,
//! coolant or tool command, a dwell, a stop, the program end). LinuxCNC fixed it after 2.9
//! (#4220: half acceleration only during an actual blend), which the default follows.
//!
//! Not modelled (L-124): the blends themselves (2.9's blend arc between two G64 moves, tp.c
//! `tpCreateLineLineBlend`; its parabolic blend, `tpDoParabolicBlending`): such a pair stops
//! exactly here, at full acceleration.

use std::collections::VecDeque;

use super::Exec;
use crate::alarm::Alarm;
use crate::plan::Step;

/// Blocks read ahead at most to find the next move (blocks that queue nothing, such as `G91`
/// or an o-word line, are looked through).
const LOOK_AHEAD_BLOCKS: usize = 16;

/// What a step is to LinuxCNC's planner queue.
enum Queue {
    /// Enters it as a move that the present move's end condition is decided against.
    Move,
    /// Waits for the motion to end before the task carries it out (a queue buster).
    Buster,
    /// Neither (modal bookkeeping, a phase, the at-speed wait of the next move).
    Quiet,
}

fn queue_of(s: &Step) -> Queue {
    match s {
        Step::Rapid { .. } | Step::Feed { .. } | Step::Arc { .. } | Step::Thread(_) | Step::More(_) => {
            Queue::Move
        }
        Step::Phase(_)
        | Step::HoldSuppress(_)
        | Step::OverrideLock(_)
        | Step::PathMode { .. }
        | Step::Css(_)
        | Step::Overload(_)
        | Step::AwaitAtSpeed
        | Step::SingleBlockStop
        | Step::Report(_) => Queue::Quiet,
        // G33.1 (RIGID_TAP), functions, dwells, stops, the end.
        _ => Queue::Buster,
    }
}

/// Blocks interpreted ahead of their turn, with what the interpreter made of each.
pub(super) type Ahead = VecDeque<Result<Vec<Step>, Alarm>>;

impl Exec<'_> {
    /// The acceleration factor of the move about to start: ½ for LinuxCNC 2.9's G64 move that no
    /// move follows in the planner's queue, 1 otherwise. Under single block the task gives
    /// motion one line at a time: nothing follows.
    pub(super) fn planner_accel_scale(&mut self) -> f64 {
        if !self.cfg.parabolic_half_accel || !self.path_continuous {
            return 1.0;
        }
        if !self.single_block && self.next_move_queued() {
            1.0
        } else {
            0.5
        }
    }

    /// Whether a move follows the present one before any queue buster: looks through the steps
    /// queued, then reads blocks ahead (kept in `ahead` until their turn).
    fn next_move_queued(&mut self) -> bool {
        for s in &self.steps {
            match queue_of(s) {
                Queue::Move => return true,
                Queue::Buster => return false,
                Queue::Quiet => {}
            }
        }
        for k in 0..LOOK_AHEAD_BLOCKS {
            if k == self.ahead.len() {
                let Some(block) = self.program.blocks.get(self.pc + k) else { return false };
                let mut out = Vec::new();
                let read = self.interp.block(block, &mut out).map(|()| out);
                self.ahead.push_back(read);
            }
            let Ok(steps) = &self.ahead[k] else { return false };
            for s in steps {
                match queue_of(s) {
                    Queue::Move => return true,
                    Queue::Buster => return false,
                    Queue::Quiet => {}
                }
            }
        }
        false
    }
}
