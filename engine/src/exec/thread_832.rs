//! A thread pass (`Step::ThreadPass`): the CNC waits for the spindle, turning in speed mode, to reach
//! the pass' start angle, then the pitch axis follows it at lead × its speed (one profile,
//! cruising at exactly that speed) and the infeed axis follows the pitch axis through the pass'
//! knots. Feed override and dry run do not act.
//!
//! Knows no G code or cycle: everything arrives as a [`ThreadPass`] (rules HDH-C832-* in
//! `docs/rules/heidenhain.md` describe the cycle built from them).

use super::motion::Path;
use super::profile::Profile;
use super::{Active, Exec};
use crate::alarm::{Alarm, AlarmKind};
use crate::plan::thread_832::ThreadPass;
use crate::plan::Step;
use crate::units::{ceil_to, Micros};

impl Exec<'_> {
    /// Starts a thread pass, or waits first (for the spindle's ramp to end, for the start angle).
    pub(super) fn start_thread_pass(&mut self, p: ThreadPass) {
        let now = self.now;
        let (angle, rpm) = self.spindle_at(now);
        if rpm == 0.0 || self.spindle.stalled {
            self.raise(Alarm::new(p.alarm, "the spindle is not turning when the thread pass starts"));
            return;
        }
        // A thread is cut at a steady speed: wait for the end of a speed change.
        if self.spindle.ramp(now).is_some() {
            self.steps.push_front(Step::ThreadPass(p));
            self.active = Active::Until(ceil_to(self.spindle.ramp_end().max(now + 1), self.cfg.period_us));
            return;
        }
        let lead = p.lead_nm.max(1) as f64;
        let v = rpm.abs() * lead / 60e6;
        let vmax = self.cfg.feed_max_nm_min / 60e6;
        if v > vmax * (1.0 + 1e-12) {
            self.raise(Alarm::new(
                AlarmKind::ThreadFeedTooHigh,
                format!(
                    "pitch {:.4} mm x {:.0} rpm = {:.0} mm/min, above the maximum cutting feed {:.0} mm/min",
                    lead / 1e6,
                    rpm.abs(),
                    v * 60.0,
                    vmax * 60.0
                ),
            ));
            return;
        }
        let a = vmax / self.cfg.feed_ramp_us.max(1) as f64;
        let ramp = v * v / (2.0 * a);
        let room = p.approach.min(p.overrun) as f64;
        if ramp > room + 0.5 {
            let which = if p.approach <= p.overrun { "approach path" } else { "overrun path" };
            self.raise(Alarm::new(
                AlarmKind::ThreadPathTooShort,
                format!(
                    "the feed axis needs {:.3} mm to reach or leave {:.0} mm/min; the {which} is {:.3} mm",
                    ramp / 1e6,
                    v * 60.0,
                    room / 1e6
                ),
            ));
            return;
        }
        if !p.armed {
            // Wait for the start angle, in the sense the spindle turns (HDH-C832-10).
            let target = p.angle_mdeg as f64 / 1000.0;
            let delta = if rpm > 0.0 { target - angle } else { angle - target }.rem_euclid(360.0);
            let dt = (delta / (rpm.abs() * 6e-6)).round() as Micros;
            if dt > 0 {
                self.steps.push_front(Step::ThreadPass(ThreadPass { armed: true, ..p }));
                self.active = Active::Until(now + dt);
                return;
            }
        }
        let start = self.cmd;
        let (a0, _) = p.knots[0];
        let mut knots = [(0.0, 0.0); 4];
        for (k, &(ak, ck)) in p.knots[..p.n].iter().enumerate() {
            knots[k] = (((ak - a0).abs()) as f64, ck as f64);
        }
        knots[0].1 = start[p.across] as f64;
        let (a_end, c_end) = p.knots[p.n - 1];
        let dist = (a_end - start[p.along]).unsigned_abs() as f64;
        let dir = if a_end >= start[p.along] { 1.0 } else { -1.0 };
        let offset = now % self.cfg.period_us.max(1);
        let profile = Profile::thread(dist, v, a, self.cfg.period_us, offset);
        let mut target = start;
        target[p.along] = a_end;
        target[p.across] = c_end;
        for axis in [p.along, p.across] {
            let d = target[axis] - start[axis];
            if d != 0 {
                self.backlash(axis, d.signum() as i8);
            }
        }
        self.start_motion(
            target,
            Path::ThreadPass { profile, along: p.along, across: p.across, knots, n: p.n, dir },
        );
        if let Some(m) = &mut self.motion {
            // The spindle is in speed mode: machine lock holds the axes, not the spindle.
            m.lock_spindle = false;
        }
    }
}
