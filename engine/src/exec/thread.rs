//! Spindle-synchronised thread passes (`Step::Thread`), the one executor of every threading cycle:
//! the pass waits for the spindle to turn at a steady speed, then for its start angle (the
//! one-revolution signal plus the pass' phase, in the sense the spindle turns); from that instant
//! the drive axis travels as the spindle's angle gives ([`PassLaw`]: locked, or reaching lead ×
//! speed with the cutting feed's acceleration), the infeed axis through the pass' knots; and the
//! thread retract on feed hold. Feed override and dry run do not act.
//!
//! Knows no G code or cycle: everything arrives as a [`ThreadPass`].

use super::motion::{Law, Path};
use super::profile::Profile;
use super::{Active, Exec};
use crate::alarm::{Alarm, AlarmKind};
use crate::plan::{PassLaw, Step, ThreadPass};
use crate::trace::Phase;
use crate::units::{ceil_to, Micros};

impl Exec<'_> {
    /// Starts a thread pass, or waits first (for the spindle's speed change to end, for the start
    /// angle).
    pub(super) fn start_thread(&mut self, p: ThreadPass) {
        let now = self.now;
        let period = self.cfg.period_us.max(1);
        let (angle, rpm) = self.spindle_at(now);
        if rpm == 0.0 || self.spindle.stalled {
            self.raise(Alarm::new(p.alarm, "thread cutting with the spindle at rest"));
            return;
        }
        // A thread is cut at a steady speed: wait for the end of a speed change.
        if self.spindle.ramp(now).is_some() {
            self.steps.push_front(Step::Thread(p));
            self.active = Active::Until(ceil_to(self.spindle.ramp_end().max(now + 1), period));
            return;
        }
        let rev_us = rpm.abs() / 60e6;
        let lead = p.lead_nm.max(1.0);
        let vmax = self.cfg.feed_max_nm_min / 60e6;
        let accel = vmax / self.cfg.feed_ramp_us.max(1) as f64;
        let mut v = rpm.abs() * lead / 60e6;
        if let PassLaw::Accelerated { room } = p.law {
            match room {
                Some((approach, overrun)) => {
                    if let Some(a) = thread_room(lead, rpm.abs(), vmax, accel, (approach, overrun)) {
                        self.raise(a);
                        return;
                    }
                }
                None => v = v.min(vmax),
            }
        }
        // Revolutions since the start angle (index + phase), in the sense the spindle turns,
        // signed: within half a turn either side.
        let turned = angle * rpm.signum() / 360.0 - p.phase_rev;
        let past = turned - turned.floor();
        let n0 = if past > 0.5 { past - 1.0 } else { past };
        if n0.abs() > rev_us * 0.5 + 1e-9 {
            // Not at the start angle (to within the µs its instant is rounded to): wait for the
            // next one. The control arms its index latch when the pass begins: an index that
            // has passed is not used. Checked again when the wait ends (the speed may change).
            let dt = ((1.0 - past) / rev_us).round().max(1.0) as Micros;
            self.steps.push_front(Step::Thread(p));
            self.active = Active::Until(now + dt);
            return;
        }
        let start = self.cmd;
        let (a0, _) = p.knots[0];
        let (a_end, _) = p.knots[p.n - 1];
        let dist = (a_end - start[p.along] as f64).abs();
        let dir = if a_end >= start[p.along] as f64 { 1.0 } else { -1.0 };
        let mut knots = [(0.0, 0.0); 4];
        for (k, &(ak, ck)) in p.knots[..p.n].iter().enumerate() {
            knots[k] = ((ak - a0).abs(), ck);
        }
        knots[0].1 = start[p.across] as f64;
        if dist == 0.0 {
            return;
        }
        let law = match p.law {
            PassLaw::Locked => {
                // n where lead·n + dlead·n²/2 = dist (the stable form of the quadratic's root).
                let (l, d) = (lead, p.dlead_nm);
                let revs = if d == 0.0 {
                    dist / l
                } else {
                    2.0 * dist / (l + (l * l + 2.0 * d * dist).max(0.0).sqrt())
                };
                let left = ((revs - n0) / rev_us).ceil().max(1.0) as Micros;
                let total = ceil_to(now + left, period) - now;
                Law::Locked { rev_us, n0, lead: l, dlead: d, total }
            }
            PassLaw::Accelerated { .. } => Law::Ramped(Profile::thread(dist, v, accel, period, now % period)),
        };
        for axis in [p.along, p.across] {
            let d = p.target[axis] - start[axis];
            if d != 0 {
                self.backlash(axis, d.signum() as i8);
            }
        }
        self.start_motion(
            p.target,
            Path::Thread { law, along: p.along, across: p.across, knots, n: p.n, dir, len: dist },
        );
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

/// The checks of a pass with room for its ramps (HDH-C832-05): lead × speed within the
/// maximum cutting feed (NC-1077), the ramps within the approach and overrun paths (NC-1078).
fn thread_room(lead: f64, rpm: f64, vmax: f64, a: f64, (approach, overrun): (i64, i64)) -> Option<Alarm> {
    let v = rpm * lead / 60e6;
    if v > vmax * (1.0 + 1e-12) {
        return Some(Alarm::new(
            AlarmKind::ThreadFeedTooHigh,
            format!(
                "pitch {:.4} mm x {:.0} rpm = {:.0} mm/min, above the maximum cutting feed {:.0} mm/min",
                lead / 1e6,
                rpm,
                v * 60.0,
                vmax * 60.0
            ),
        ));
    }
    let ramp = v * v / (2.0 * a);
    let room = approach.min(overrun) as f64;
    if ramp > room + 0.5 {
        let which = if approach <= overrun { "approach path" } else { "overrun path" };
        return Some(Alarm::new(
            AlarmKind::ThreadPathTooShort,
            format!(
                "the feed axis needs {:.3} mm to reach or leave {:.0} mm/min; the {which} is {:.3} mm",
                ramp / 1e6,
                v * 60.0,
                room / 1e6
            ),
        ));
    }
    None
}
