//! An axis that follows the spindle's encoder while the spindle is in speed mode (KND G93): the
//! cut at the spindle's speed, the braking coast with its overshoot, and the return behind the
//! reversed spindle; and the CNC's own wait for a signal with a timer (`Step::AwaitSignal`).
//!
//! Knows no G code: everything arrives as [`Follow`] and [`FollowKind`] (rules KND-G93-* in
//! `docs/rules/knd-lathe.md` describe the cycle built from them).

use super::motion::Path;
use super::plc::PlcAction;
use super::profile::{Profile, Ramp};
use super::{Active, AfterAwait, Exec};
use crate::alarm::{Alarm, AlarmKind};
use crate::plan::{Follow, FollowKind, Step};
use crate::trace::{Signal, AXES};
use crate::units::{ceil_to, Micros, Nm};

impl Exec<'_> {
    /// Starts a following motion.
    pub(super) fn start_follow(&mut self, f: Follow) {
        let now = self.now;
        self.follow_step = Some((now, f));
        let d = f.target - self.cmd[f.axis];
        let lead = f.lead_nm.max(1) as f64;
        let period = self.cfg.period_us;
        let (angle, rpm) = self.spindle_at(now);
        let mut target = self.cmd;
        match f.kind {
            FollowKind::Cut => {
                if rpm == 0.0 {
                    self.raise(Alarm::new(f.alarm, "the spindle is not turning when the cycle starts"));
                    return;
                }
                if f.index {
                    // Wait for the spindle's next index pulse (angle 0 in its direction of
                    // rotation); the cut starts on the tick after it, later by the control's
                    // index latency (LinuxCNC: one period more, DEC-157).
                    let next =
                        if rpm > 0.0 { (angle / 360.0).ceil() } else { (angle / 360.0).floor() } * 360.0;
                    let dt = ((next - angle).abs() / (rpm.abs() * super::spindle::DEG_PER_US_PER_RPM)).ceil();
                    if dt > 0.0 {
                        let latency = period.max(1) * Micros::from(self.cfg.index_latency_periods);
                        let at = ceil_to(now + dt as Micros, period.max(1)) + latency;
                        self.steps.push_front(Step::Follow(Follow { index: false, ..f }));
                        self.active = Active::Until(at);
                        return;
                    }
                }
                let b = self.follow_backlash(&f, d);
                self.follow_on(&f, d, b, rpm, target);
            }
            FollowKind::Through { rpm: r, forward } => {
                // The spindle is commanded the other way at S × the spindle override (COM-MOT-06)
                // and ramps there; the tap follows it, locked, through the start.
                let r = (r as f64 * self.spindle_override as f64 / 100.0)
                    .min(self.cfg.spindle_max_rpm as f64)
                    .max(1.0);
                self.spindle.command(now, if forward { r } else { -r });
                self.stall_angle = None;
                self.spindle_changed();
                let b = self.follow_backlash(&f, d);
                self.follow_on(&f, d, b, rpm, target);
            }
            FollowKind::Unsynced => {
                if d == 0 {
                    return;
                }
                let b = self.follow_backlash(&f, d);
                let v = self.cfg.rapid_nm_min[f.axis] / 60e6;
                let a = v / self.cfg.rapid_ramp_us[f.axis].max(1) as f64;
                let mut profiles = [Profile::still(); AXES];
                let mut backlash = [0.0; AXES];
                profiles[f.axis] = Profile::trapezoid(d.unsigned_abs() as f64 + b, v, a, period);
                backlash[f.axis] = b;
                target[f.axis] = f.target;
                self.start_motion(target, Path::Rapid { profiles, backlash });
            }
            FollowKind::Brake { .. } | FollowKind::Reversal => {
                if rpm == 0.0 {
                    return;
                }
                // The spindle brakes on its own in speed mode (its brake time from its speed at
                // the end point); the tap brakes behind it within its own acceleration, from the
                // speed the cut reached the end point with (locked: lead × speed). Where the brake
                // would carry it past the allowance it leaves the spindle just in time to stop
                // there, and the spindle brakes on (KND-G93-05).
                // Never faster than the spindle can slow down: its ramp, or its brake (a spindle
                // turning above S under an override takes longer than the brake time for S).
                let max_rpm = self.cfg.spindle_max_rpm.max(1) as f64;
                let mut a_limit = max_rpm / self.cfg.spindle_ramp_us.max(1) as f64;
                if self.cfg.spindle_brake_us > 0 {
                    a_limit = a_limit.max(max_rpm / self.cfg.spindle_brake_us as f64);
                }
                let total = match f.kind {
                    FollowKind::Brake { brake_us } => {
                        brake_us.max(1).max((rpm.abs() / a_limit).floor() as Micros)
                    }
                    // Commanded the other sense already: zero is passed at its own ramp.
                    _ => {
                        let a = self.spindle.ramp(now).map_or(a_limit, |r| r.slope.abs());
                        ((rpm.abs() / a).floor() as Micros).max(1)
                    }
                };
                let (v0, cut_locked) =
                    self.follow_v.take().unwrap_or((rpm.abs() * lead / 60e6, self.machine_lock));
                let a_spindle = rpm.abs() * lead / 60e6 / total as f64;
                let a_axis = self.cfg.feed_max_nm_min / 60e6 / self.cfg.feed_ramp_us.max(1) as f64;
                let room = d.unsigned_abs() as f64;
                let coast = v0 * v0 / (2.0 * a_spindle.min(a_axis));
                let (profile, over) = Profile::brake_behind(v0, a_spindle, a_axis, room);
                // The control sees the stop on the tick after the tap and the spindle are still.
                let rest = profile.total.max(if over { 0 } else { total });
                let profile = profile.still_until(ceil_to(now + rest, period.max(1)) - now);
                let travel = profile.dist.round() as Nm;
                target[f.axis] = self.cmd[f.axis] + d.signum() * travel;
                if matches!(f.kind, FollowKind::Brake { .. }) {
                    self.spindle.command(now, 0.0);
                    self.spindle.seg_accel = Some(rpm.abs() / total as f64);
                    self.stall_angle = None;
                    self.spindle_changed();
                }
                let mut profiles = [Profile::still(); AXES];
                profiles[f.axis] = profile;
                self.start_motion(target, Path::Rapid { profiles, backlash: [0.0; AXES] });
                if let Some(m) = &mut self.motion {
                    // The brake carries on the cut without a stop: a machine lock switched during
                    // the cut acts from the next motion that starts from rest (COM-INP-10).
                    m.locked = cut_locked;
                    m.lock_spindle = cut_locked;
                }
                self.following = f.encoder_bound && self.motion.is_some();
                if over {
                    let a = Alarm::new(
                        f.alarm,
                        format!(
                            "the braking spindle would carry the tap {:.3} mm past the end point; the allowance is {:.3} mm",
                            coast / 1e6,
                            room / 1e6
                        ),
                    );
                    self.steps.push_front(Step::Alarm(a));
                }
            }
            FollowKind::Return { rpm: r, forward } => {
                let b = self.follow_backlash(&f, d);
                if d == 0 && b == 0.0 {
                    return;
                }
                // The reversed spindle turns at S × the spindle override in force (COM-MOT-06).
                let r = (r as f64 * self.spindle_override as f64 / 100.0)
                    .min(self.cfg.spindle_max_rpm as f64)
                    .max(1.0);
                // The tap and the spindle locked together, within both limits: the spindle's ramp
                // (× lead) and the axis' own acceleration and feed limit.
                let vmax = self.cfg.feed_max_nm_min / 60e6;
                let v = (r * lead / 60e6).min(vmax);
                let a_rpm = self.cfg.spindle_max_rpm.max(1) as f64 / self.cfg.spindle_ramp_us.max(1) as f64;
                let a = (a_rpm * lead / 60e6).min(vmax / self.cfg.feed_ramp_us.max(1) as f64);
                let profile = Profile::trapezoid(d.unsigned_abs() as f64 + b, v, a, period);
                self.spindle.hold(now, angle);
                self.stall_angle = None;
                // The spindle is in speed mode: machine lock holds the axis, not the spindle
                // (COM-MOT-04, KND-G93-03), so it turns and the drive reports it.
                self.set_signal(Signal::Zsp, false);
                target[f.axis] = f.target;
                let spin = if forward { 1.0 } else { -1.0 };
                self.start_motion(target, Path::Tap { profile, axis: f.axis, backlash: b, lead, spin });
                self.free_spindle();
                self.following = f.encoder_bound && self.motion.is_some();
            }
        }
    }

    /// The axis catches up with lead × the spindle's speed within the cutting acceleration, then
    /// stays locked to it and reaches the target still at that speed: the brake that follows
    /// carries it on with the spindle (no stop at Z while the spindle turns). A single-axis
    /// profile with its backlash `b` first (the spindle keeps its own state); a spindle still
    /// ramping is followed through its ramp.
    fn follow_on(&mut self, f: &Follow, d: Nm, b: f64, rpm: f64, mut target: crate::plan::Pos) {
        if d == 0 && b == 0.0 {
            return;
        }
        let lead = f.lead_nm.max(1) as f64;
        let period = self.cfg.period_us;
        let vmax = self.cfg.feed_max_nm_min / 60e6;
        let v = (rpm.abs() * lead / 60e6).min(vmax);
        let a = vmax / self.cfg.feed_ramp_us.max(1) as f64;
        let mut profiles = [Profile::still(); AXES];
        let mut backlash = [0.0; AXES];
        let dist = d.unsigned_abs() as f64 + b;
        let ramp = self.spindle.ramp(self.now).unwrap_or(Ramp { rpm0: rpm, slope: 0.0, dur: 0.0 });
        profiles[f.axis] = match Profile::following_through(dist, lead / 60e6, ramp, vmax, a) {
            Some((p, v_end)) => {
                self.follow_v = Some((v_end, self.machine_lock));
                p
            }
            None => Profile::trapezoid(dist, v, a, period),
        };
        backlash[f.axis] = b;
        target[f.axis] = f.target;
        self.start_motion(target, Path::Rapid { profiles, backlash });
        self.following = f.encoder_bound && self.motion.is_some();
    }

    /// The spindle stalled while the axis follows its encoder: the axis stops with it at once and
    /// the cycle ends with NC-1017, the tap where it stopped (KND-G93-11).
    pub(super) fn follow_stalled(&mut self) {
        if !self.following || self.motion.is_none() {
            return;
        }
        self.stop_motion_now();
        self.raise(Alarm::new(
            AlarmKind::SpindleNotTurning,
            "the spindle stalled during the cycle: the tap, following its encoder, stops with it",
        ));
    }

    /// The motion just started keeps its spindle turning under machine lock (speed mode).
    fn free_spindle(&mut self) {
        if let Some(m) = &mut self.motion {
            m.lock_spindle = false;
        }
    }

    /// Backlash to take up before a following motion of `d` nm (0 when the step does not
    /// compensate it; the direction is recorded either way).
    fn follow_backlash(&mut self, f: &Follow, d: Nm) -> f64 {
        if d == 0 {
            return 0.0;
        }
        let b = self.backlash(f.axis, d.signum() as i8);
        if f.backlash {
            b
        } else {
            0.0
        }
    }

    /// Starts waiting for `signal` to have `value`, with the CNC's timer raising `alarm`.
    pub(super) fn start_await(&mut self, signal: Signal, value: bool, timeout_us: Micros, alarm: AlarmKind) {
        if self.signals.get(signal) == value {
            return;
        }
        self.await_no += 1;
        self.active = Active::Await { signal, value, then: AfterAwait::Nothing };
        self.plc.at(self.now + timeout_us, PlcAction::AwaitTimer(self.await_no, alarm));
    }

    /// The timer of wait `n` ran out: the alarm, unless the signal came.
    pub(super) fn await_timer(&mut self, n: u64, alarm: AlarmKind) {
        if n != self.await_no {
            return;
        }
        if let Active::Await { signal, value, then: AfterAwait::Nothing } = self.active {
            if self.signals.get(signal) != value {
                let what = format!("{} did not become {} within the timer", signal.name(), u8::from(value));
                self.raise(Alarm::new(alarm, what));
            }
        }
    }
}
