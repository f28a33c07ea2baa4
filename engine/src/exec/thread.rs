//! Spindle-synchronised thread passes (`Step::Thread`), the one executor of every threading cycle:
//! the pass waits for the spindle to turn at a steady speed, then for its start angle (the
//! one-revolution signal plus the pass' phase, in the sense the spindle turns); from that instant
//! the drive axis travels as the spindle's angle gives ([`PassLaw`]: locked after a catch-up ramp
//! that starts a constant lag before that angle, or reaching lead × speed with the cutting feed's
//! acceleration), the infeed axis through the pass' knots, blended within its acceleration
//! (DEC-146); and the thread retract on feed hold. Feed override and dry run do not act.
//!
//! Knows no G code or cycle: everything arrives as a [`ThreadPass`].

use super::motion::Path;
use super::profile::{catch_up_lag, Profile};
use super::{Active, Exec};
use crate::alarm::{Alarm, AlarmKind};
use crate::plan::{PassLaw, Step, ThreadPass};
use crate::trace::Phase;
use crate::units::{ceil_to, Micros, Nm};

/// The law an accelerated pass settles on once at speed, for the segments that follow it without
/// a new index (DEC-147): the drive axis `lead × revolutions since angle0 − lag` from `along0`,
/// in the sense `dir`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct SyncLock {
    /// The spindle's angle when the pass started, deg (unwrapped).
    pub(super) angle0: f64,
    /// The sense the spindle turns (±1).
    pub(super) sign: f64,
    /// The drive axis of the segment the law is counted along (the pass's, or the last tracking
    /// segment's: each rebases it).
    pub(super) axis: usize,
    /// The drive axis' position when the pass started, nm.
    pub(super) along0: Nm,
    /// The sense the drive axis travels (±1).
    pub(super) dir: f64,
    /// Lead, nm per revolution.
    pub(super) lead: f64,
    /// How far the ramp left the axis behind the spindle, nm (v²/2a).
    pub(super) lag: f64,
}

impl Exec<'_> {
    /// Starts a thread pass, or waits first (for the spindle's speed change to end, for the start
    /// angle).
    pub(super) fn start_thread(&mut self, p: ThreadPass) {
        // LinuxCNC 2.9 under G64: the taper of a blended pass runs its arc first (DEC-164).
        if self.start_pass_blend(&p) {
            return;
        }
        if matches!(p.law, PassLaw::Segments | PassLaw::SegmentsTracking) && p.n > 2 {
            self.thread_segments(p);
            return;
        }
        let tracking = p.law == PassLaw::Tracking;
        let now = self.now;
        let period = self.cfg.period_us.max(1);
        let (angle, rpm) = self.spindle_at(now);
        if rpm == 0.0 || self.spindle.stalled {
            self.raise(Alarm::new(p.alarm, "thread cutting with the spindle at rest"));
            return;
        }
        // A thread is cut at a steady speed: wait for the end of a speed change.
        if self.spindle.ramp(now).is_some() && !tracking {
            self.steps.push_front(Step::Thread(p));
            self.active = Active::Until(ceil_to(self.spindle.ramp_end().max(now + 1), period));
            return;
        }
        let rev_us = rpm.abs() / 60e6;
        let lead = p.lead_nm.max(1.0);
        let vmax = self.cfg.feed_max_nm_min / 60e6;
        let a_cut = vmax / self.cfg.feed_ramp_us.max(1) as f64;
        let mut v = rpm.abs() * lead / 60e6;
        let start = self.cmd;
        let (a0, _) = p.knots[0];
        let (a_end, _) = p.knots[p.n - 1];
        let dist = (a_end - start[p.along] as f64).abs();
        let mut knots = [(0.0, 0.0); 4];
        for (k, &(ak, ck)) in p.knots[..p.n].iter().enumerate() {
            knots[k] = ((ak - a0).abs(), ck);
        }
        knots[0].1 = start[p.across] as f64;
        // The drive axis ramps at the cutting acceleration, less where a steep infeed would take
        // the infeed axis (slope × as fast) past its own limit (its rapid rate / time constant or
        // the cutting acceleration), or past half of it when knots need blends: what it leaves
        // is for the blends (DEC-146).
        let steep = super::motion::steepest(&knots[..p.n]);
        let a_across =
            (self.cfg.rapid_nm_min[p.across] / 60e6 / self.cfg.rapid_ramp_us[p.across].max(1) as f64)
                .max(a_cut);
        let share = if p.n > 2 { 0.5 } else { 1.0 };
        let accel = if steep > 0.0 { a_cut.min(share * a_across / steep) } else { a_cut };
        let blend_a = a_across - steep * accel;
        // The locked law's acceleration (a lead changing by dlead per turn) and the lag of its
        // catch-up ramp: the pass starts that long before its start angle (DEC-146).
        let acc = p.dlead_nm * rev_us * rev_us;
        let mut lag_rev = 0.0;
        let mut v_top = v;
        match p.law {
            PassLaw::Accelerated { room: Some((approach, overrun)) } => {
                if let Some(a) = thread_room(lead, rpm.abs(), vmax, accel, (approach, overrun)) {
                    self.raise(a);
                    return;
                }
            }
            PassLaw::Accelerated { room: None }
            | PassLaw::Segments
            | PassLaw::SegmentsTracking
            | PassLaw::Tracking => {
                v = v.min(vmax);
                v_top = v;
            }
            PassLaw::Locked => {
                // The fastest the law runs: at the start, or at the end of a growing lead.
                let lead_end = (lead * lead + 2.0 * p.dlead_nm * dist).max(0.0).sqrt();
                if let Some(a) = thread_locked(lead.max(lead_end), p.dlead_nm, rpm.abs(), vmax, accel) {
                    self.raise(a);
                    return;
                }
                lag_rev = catch_up_lag(v, acc, accel) * rev_us;
                v_top = rpm.abs() * lead.max(lead_end) / 60e6;
            }
        }
        // Revolutions since the start angle (index + phase − the catch-up's lag), in the sense
        // the spindle turns, signed: within half a turn either side.
        // The control's index latency (LinuxCNC: one period more, DEC-157) puts the start that
        // long after the start angle.
        let latency_rev = (self.cfg.index_latency_periods as f64) * period as f64 * rev_us;
        let turned = angle * rpm.signum() / 360.0 - p.phase_rev + lag_rev - latency_rev;
        let past = turned - turned.floor();
        let n0 = if past > 0.5 { past - 1.0 } else { past };
        if n0.abs() > rev_us * 0.5 + 1e-9 && !tracking {
            // Not at the start angle (to within the µs its instant is rounded to): wait for the
            // next one. The control arms its index latch when the pass begins: an index that
            // has passed is not used. Checked again when the wait ends (the speed may change).
            let dt = ((1.0 - past) / rev_us).round().max(1.0) as Micros;
            self.steps.push_front(Step::Thread(p));
            self.active = Active::Until(now + dt);
            return;
        }
        let dir = if a_end >= start[p.along] as f64 { 1.0 } else { -1.0 };
        if dist == 0.0 {
            return;
        }
        let profile = match p.law {
            // The law's origin (the start angle itself) comes lag − n0 revolutions from now.
            PassLaw::Locked => {
                Profile::catch_up(dist, v, acc, (lag_rev - n0) / rev_us, accel, period, now % period)
            }
            PassLaw::Tracking => {
                // The revolutions the run has used so far (its ramp's lag and the segments before
                // this one, each at its own lead), and how far this segment is behind the spindle
                // at its own lead (LinuxCNC's spindle offset, tp.c: each synchronised segment's
                // length over its lead added as the next starts). The law is rebased onto this
                // segment for the next.
                let behind = self.sync_lock.map(|l| {
                    let revs = (angle - l.angle0) * l.sign / 360.0;
                    let used = (l.lag + (start[l.axis] - l.along0) as f64 * l.dir) / l.lead;
                    (lead * (revs - used), lead * used)
                });
                if let (Some(l), Some((_, lag))) = (self.sync_lock.as_mut(), behind) {
                    *l = SyncLock { axis: p.along, along0: start[p.along], dir, lead, lag, ..*l };
                }
                Profile::tracking(dist, v, behind.map_or(0.0, |b| b.0), accel, period, now % period)
            }
            PassLaw::Accelerated { .. } | PassLaw::Segments | PassLaw::SegmentsTracking => {
                self.sync_lock = Some(SyncLock {
                    angle0: angle,
                    sign: rpm.signum(),
                    axis: p.along,
                    along0: start[p.along],
                    dir,
                    lead,
                    lag: v * v / (2.0 * accel),
                });
                if let Some(v_arc) = self.pass_blend_entry() {
                    // The thread of a blended pass runs on into its arc at speed (DEC-164).
                    Profile::between(dist, 0.0, v, v.min(v_arc), accel, period)
                } else {
                    Profile::thread(dist, v, accel, period, now % period)
                }
            }
        };
        let (knots, blend) = super::motion::blended(&knots[..p.n], p.thread, v_top, blend_a);
        // A run-out cut short by its blend ends the pass short of its infeed target.
        let mut target = p.target;
        if knots[p.n - 1].1 != p.knots[p.n - 1].1 {
            target[p.across] = knots[p.n - 1].1.round() as crate::units::Nm;
        }
        for axis in [p.along, p.across] {
            let d = target[axis] - start[axis];
            if d != 0 {
                self.backlash(axis, d.signum() as i8);
            }
        }
        self.start_motion(
            target,
            Path::Thread { profile, along: p.along, across: p.across, knots, n: p.n, blend, dir, len: dist },
        );
        // The spindle turns in speed mode: machine lock holds the axes, not the spindle.
        if let Some(m) = &mut self.motion {
            m.lock_spindle = false;
        }
    }

    /// A pass through tapers as LinuxCNC runs it (DEC-147): one synchronised segment per pair of
    /// knots, each ending at rest; the first waits for the index and ramps, the others track.
    fn thread_segments(&mut self, p: ThreadPass) {
        if let Some(trim) = self.plan_pass_blend(&p) {
            for s in super::pass_blend::blended_steps(&p, trim).into_iter().rev() {
                self.steps.push_front(s);
            }
            return;
        }
        for k in (0..p.n - 1).rev() {
            let mut target = p.target;
            if k + 2 < p.n {
                target[p.along] = p.knots[k + 1].0.round() as Nm;
                target[p.across] = p.knots[k + 1].1.round() as Nm;
            }
            let mut knots = [(0.0, 0.0); 4];
            knots[0] = p.knots[k];
            knots[1] = p.knots[k + 1];
            let law = if k == 0 && !p.tracks_first() {
                PassLaw::Accelerated { room: None }
            } else {
                PassLaw::Tracking
            };
            self.steps.push_front(Step::Thread(ThreadPass { target, knots, n: 2, thread: 0, law, ..p }));
        }
    }

    /// Feed hold during a thread pass with thread retract: the thread decelerates to a stop
    /// along its path, the short axis and then the long axis rapid back to the cycle start, the control holds, and
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
        // The drive axis decelerates along the thread at the cutting acceleration (it used to
        // stop where it was, at speed: INV-11); the retract starts where it comes to rest.
        let a = self.cfg.feed_max_nm_min / 60e6 / self.cfg.feed_ramp_us.max(1) as f64;
        let period = self.cfg.period_us;
        let Some(m) = &mut self.motion else { return false };
        m.stop_at(self.now, a, period);
        let mut out = m.target;
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
    if let Some(alarm) = feed_too_high(lead, rpm, vmax) {
        return Some(alarm);
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

/// The checks of a locked pass (DEC-146): its fastest lead × speed within the maximum cutting
/// feed, and the acceleration of its lead change (dlead × speed²) below the cutting
/// acceleration `a` that has to catch up with it (NC-1077 both: the thread is too fast for the
/// axis). Seed 002: "因 D 的增加/减小使螺距超过允许值 … 时产生报警".
fn thread_locked(lead_max: f64, dlead: f64, rpm: f64, vmax: f64, a: f64) -> Option<Alarm> {
    if let Some(alarm) = feed_too_high(lead_max, rpm, vmax) {
        return Some(alarm);
    }
    let acc = dlead.abs() * (rpm / 60e6).powi(2);
    if acc >= a {
        return Some(Alarm::new(
            AlarmKind::ThreadFeedTooHigh,
            format!(
                "lead change {:.4} mm per turn at {:.0} rpm asks {:.0} mm/s² of the feed axis, not below its cutting acceleration {:.0} mm/s²",
                dlead / 1e6,
                rpm,
                acc * 1e6,
                a * 1e6
            ),
        ));
    }
    None
}

/// NC-1077 when `lead` × `rpm` is above the maximum cutting feed `vmax` (nm/µs).
fn feed_too_high(lead: f64, rpm: f64, vmax: f64) -> Option<Alarm> {
    let v = rpm * lead / 60e6;
    (v > vmax * (1.0 + 1e-12)).then(|| {
        Alarm::new(
            AlarmKind::ThreadFeedTooHigh,
            format!(
                "pitch {:.4} mm x {:.0} rpm = {:.0} mm/min, above the maximum cutting feed {:.0} mm/min",
                lead / 1e6,
                rpm,
                v * 60.0,
                vmax * 60.0
            ),
        )
    })
}
