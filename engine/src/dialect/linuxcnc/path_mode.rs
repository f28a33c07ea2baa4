//! LinuxCNC's path control mode (G61, G61.1, G64 [P]) as its canonical layer keeps it, passed on
//! to the executor for LinuxCNC 2.9's planner (`Step::PathMode`; DEC-163, DEC-164): G64 at
//! start-up with no tolerance in the planner, though canon keeps 0.001 inch (emccanon.cc
//! INIT_CANON), which rs274 restores after a canned cycle (`cycles.rs`).

use super::machine::{Eb, Machine};
use crate::alarm::Alarm;
use crate::plan::Step;

impl Machine {
    /// G61 / G61.1 (`g` 610, 611): exact path or stop, tolerance 0 (emccanon.cc
    /// SET_MOTION_CONTROL_MODE keeps the tolerance given); G64 (640): continuous with P as the
    /// blend tolerance (0 without P: none).
    pub fn control_mode(&mut self, g: u32, b: &Eb, out: &mut Vec<Step>) -> Result<(), Alarm> {
        if g == 640 {
            let p = match b.get('P') {
                Some(p) if p > 0.0 => self.len(p, 2, b, 'P')?,
                _ => 0,
            };
            self.continuous = true;
            self.tolerance = p;
            self.canon_tolerance = p;
        } else {
            self.continuous = false;
            self.canon_tolerance = 0;
        }
        self.path_mode(self.continuous, out);
        Ok(())
    }

    /// Tells the executor the path control mode from here on, with the planner's blend
    /// tolerance (only for LinuxCNC 2.9's planner, whose half acceleration and blend arcs
    /// depend on them: DEC-163, DEC-164).
    pub fn path_mode(&self, continuous: bool, out: &mut Vec<Step>) {
        if self.cfg.tp_2_9 {
            let tolerance_nm = if continuous { self.tolerance } else { 0 };
            out.push(Step::PathMode { continuous, tolerance_nm });
        }
    }
}
