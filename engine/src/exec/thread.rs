//! Spindle-synchronised thread passes (`Step::Thread`): the pass waits for the spindle to turn at
//! a steady speed and for its one-revolution signal (plus the pass's phase), starts at the next
//! interpolation tick with the axes where the spindle's angle since the index puts them, and
//! follows that angle exactly; and the thread retract on feed hold.
//!
//! Knows no G code: everything arrives as a [`ThreadMove`].

use super::motion::Path;
use super::{Active, Exec};
use crate::alarm::{Alarm, AlarmKind};
use crate::plan::{Step, ThreadMove};
use crate::trace::Phase;
use crate::units::{ceil_to, Micros};

/// The spindle's angle counts as "at" the index this close to it (degrees): rounding, not a whole
/// turn to wait.
const AT_INDEX_DEG: f64 = 0.5;

impl Exec<'_> {
    /// Starts a thread pass, or first waits for a steady spindle speed and the index.
    pub(super) fn start_thread(&mut self, t: ThreadMove) {
        let now = self.now;
        let period = self.cfg.period_us;
        let (angle, rpm) = self.spindle.at(now);
        if rpm == 0.0 || self.spindle.stalled {
            self.raise(Alarm::new(AlarmKind::FeedZero, "thread cutting with the spindle at rest"));
            return;
        }
        if self.spindle.ramp(now).is_some() {
            // The pass starts once the spindle turns at its speed.
            let ready = ceil_to(self.spindle.ramp_end().max(now + 1), period);
            self.steps.push_front(Step::Thread(t));
            self.active = Active::Until(ready);
            return;
        }
        // Revolutions turned in the running direction since the last index + the pass's phase.
        let turned = angle * rpm.signum() / 360.0 - t.phase_rev;
        let past = turned - turned.floor();
        let rev_us = rpm.abs() / 60e6;
        // Within one tick after the index (+ phase) the pass starts now, the axes where the
        // spindle's angle since the index puts them; otherwise it waits for the next index and
        // starts at the tick that follows it.
        let tick_revs = rev_us * period as f64 + AT_INDEX_DEG / 360.0;
        if past > tick_revs && past * 360.0 < 360.0 - AT_INDEX_DEG {
            let at = now + ((1.0 - past) / rev_us).ceil() as Micros;
            self.steps.push_front(Step::Thread(t));
            self.active = Active::Until(ceil_to(at, period));
            return;
        }
        let n0 = if past * 360.0 >= 360.0 - AT_INDEX_DEG { 0.0 } else { past };
        let start = self.cmd;
        let len = (t.target[t.long_axis] - start[t.long_axis]).unsigned_abs() as f64;
        if len == 0.0 {
            return;
        }
        let runout = t.runout.map(|r| (r.axis, r.amount as f64, (len - r.len as f64).max(0.0)));
        let path = Path::thread(rev_us, n0, t.lead_nm, t.dlead_nm, len, runout, period);
        self.start_motion(t.target, path);
        // The spindle turns in speed mode: machine lock holds the axes, not the spindle.
        if let Some(m) = &mut self.motion {
            m.lock_spindle = false;
        }
    }

    /// Feed hold during a thread pass with thread retract: the thread stops where it is, the
    /// short axis and then the long axis rapid back to the cycle start, the control holds, and
    /// cycle start cuts the interrupted pass again from its cut start. Returns false when the
    /// present motion is not such a pass.
    pub(super) fn thread_retract(&mut self) -> bool {
        let Some(Step::Thread(t)) = self.motion_step.clone() else { return false };
        let Some(r) = t.retract else { return false };
        let Some(m) = &self.motion else { return false };
        if !matches!(m.path, Path::Thread { .. }) {
            return false;
        }
        let cut_start = m.start;
        if let Some(m) = &mut self.motion {
            m.stop_at(self.now, f64::INFINITY, self.cfg.period_us);
        }
        self.end_motion();
        self.active = Active::Idle;
        let here = self.cmd;
        let mut out = here;
        out[r.short_axis] = r.cycle_start[r.short_axis];
        let steps = [
            Step::Phase(Phase::Retract),
            Step::Rapid { target: out },
            Step::Rapid { target: r.cycle_start },
            Step::Hold,
            Step::Phase(Phase::Positioning),
            Step::Rapid { target: cut_start },
            Step::Phase(Phase::Cutting),
            Step::Thread(t),
        ];
        for s in steps.into_iter().rev() {
            self.steps.push_front(s);
        }
        true
    }
}
