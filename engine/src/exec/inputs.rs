//! Operator inputs, faults and PLC answers acting on a run, and the overload retract.

use super::{Active, Exec};
use crate::alarm::{Alarm, AlarmKind};
use crate::input::{CurrentSource, Input};
use crate::plan::{OverloadWatch, Step, TapMove};
use crate::trace::{EndReason, Event, Phase, Signal};
use crate::units::Micros;

use super::motion::Path;
use super::plc::PlcAction;

impl Exec<'_> {
    /// A PLC or drive action falls due.
    pub(super) fn plc_edge(&mut self, action: PlcAction) {
        match action {
            PlcAction::Set(sig, v) => {
                self.set_signal(sig, v);
                if sig == Signal::Fin && v {
                    // A function output with a motion: the CNC drops its strobe as it sees FIN.
                    if let Some(strobe) = self.function_strobe.take() {
                        self.set_signal(strobe, false);
                        self.plc.strobe_dropped(self.now);
                    }
                }
                let rtap = self.signals.get(Signal::Rtap);
                let rest = self.spindle_rest();
                self.plc.react(self.now, sig, v, rtap, rest);
                self.check_await();
            }
            PlcAction::M29Timer(n) => {
                if n == self.plc.strobe_no
                    && self.signals.get(Signal::Rtap)
                    && !self.signals.get(Signal::Spposa)
                {
                    self.raise(Alarm::new(
                        AlarmKind::M29FeedbackTimeout,
                        "the spindle drive did not report position mode after M29",
                    ));
                }
            }
            PlcAction::FinTimer(n) => {
                let strobing = [Signal::Mf, Signal::Sf, Signal::Tf].iter().any(|&s| self.signals.get(s));
                if n == self.plc.strobe_no && strobing && !self.signals.get(Signal::Fin) {
                    self.raise(Alarm::new(AlarmKind::FinTimeout, "the PLC did not answer FIN"));
                }
            }
            PlcAction::ZeroSpeed => {
                if self.spindle_at(self.now).1 == 0.0 {
                    self.set_signal(Signal::Zsp, true);
                    self.check_await();
                }
            }
            PlcAction::AwaitTimer(n, alarm) => self.await_timer(n, alarm),
            PlcAction::ExcessError => {
                if self.stall_angle.is_some() && self.spindle.stalled {
                    self.raise(Alarm::new(
                        AlarmKind::ExcessErrorMoving,
                        "the tap axis ran ahead of the stalled spindle",
                    ));
                }
            }
            PlcAction::StallTimer => {
                if self.spindle.stalled
                    && self.motion.as_ref().is_some_and(|m| matches!(m.path, Path::Tap { .. }))
                {
                    self.raise(Alarm::new(
                        AlarmKind::SpindleNotRotating,
                        "the spindle does not rotate during rigid tapping",
                    ));
                }
            }
        }
    }

    /// An operator input or fault takes effect now.
    pub(super) fn apply_input(&mut self, input: Input) {
        self.emit(Event::Input { name: input.name().to_string(), value: input.value_text() });
        match input {
            Input::CycleStart => {
                if self.active == Active::Held {
                    self.set_signal(Signal::Spl, false);
                    self.set_signal(Signal::Stl, true);
                    self.active = Active::Idle;
                }
            }
            Input::FeedHold => {
                // FHD (hold_in_rigid_tap) lets feed hold act in rigid tapping only (spindle in
                // position mode), never in conventional tapping (FAN-RT-15, FAN-RT-16).
                let fhd = self.cfg.hold_in_rigid_tap && self.spindle.position_mode;
                if self.hold_suppressed && !fhd {
                    self.hold_pending = true;
                } else if self.thread_retract() {
                    // Thread retract: back to the cycle start, then the hold (GSK-G923-12).
                } else {
                    self.feed_hold_now();
                }
            }
            Input::Reset => self.reset(),
            Input::SingleBlock(b) => self.single_block = b,
            Input::DryRun(b) => self.dry_run = b,
            Input::MachineLock(b) => self.machine_lock = b,
            Input::OptionalStop(b) => self.optional_stop = b,
            Input::FeedOverride(p) => self.feed_override = self.cfg.overrides.feed(p),
            Input::SpindleOverride(p) => {
                self.spindle_override = self.cfg.overrides.spindle(p);
                self.spindle_override_changed();
            }
            Input::EmergencyStop(true) => {
                self.set_signal(Signal::Esp, true);
                self.stop_motion_now();
                self.raise(Alarm::new(AlarmKind::EmergencyStop, "emergency stop pressed"));
            }
            Input::EmergencyStop(false) => self.set_signal(Signal::Esp, false),
            Input::MotorCurrent { source, percent } => {
                self.current_pct[source_slot(source)] = percent;
                if let Some(w) = self.overload {
                    self.overload_check(w);
                }
            }
            Input::PlcAnswer { answer, extra_us } => self.plc.set_fault(answer, extra_us),
            // Releasing a stall that is not in force changes nothing (it used to stop the
            // spindle at once and ramp it up again: found by the physics invariants, INV-12).
            Input::SpindleStall(false) if !self.spindle.stalled => {}
            Input::SpindleStall(b) => {
                let (a, _) = self.spindle.at(self.now);
                let target = self.spindle.target;
                self.spindle.hold(self.now, a);
                self.spindle.stalled = b;
                if !b {
                    self.spindle.command(self.now, target);
                }
                if b && self.stall_angle.is_none() && !self.following {
                    self.stall_checks();
                }
                self.spindle_changed();
                if b {
                    self.follow_stalled();
                }
            }
            Input::SetParam { id, axis, value } => match self.params.set(&id, axis, value) {
                Ok(()) => {
                    self.cfg = self.dialect.plant_config(&self.params);
                    self.plc.cfg = self.cfg.plc;
                    self.interp.set_params(&self.params);
                }
                Err(e) => self.raise(Alarm::new(AlarmKind::ParameterOutOfRange, e.to_string())),
            },
        }
    }

    /// Feed hold outside rigid tapping: a motion decelerates to a stop, then the control waits
    /// for cycle start and carries on with the rest of the move.
    fn feed_hold_now(&mut self) {
        let period = self.cfg.period_us;
        let a = self.stop_rate();
        if let Some(m) = &mut self.motion {
            // Decelerate along the path, then wait; cycle start carries out the rest of the move.
            m.stop_at(self.now, a, period);
            if let Some(s) = self.motion_step.clone() {
                self.steps.push_front(s);
            }
        }
        self.drop_blend();
        self.hold_requested = true;
    }

    /// The deceleration (nm/µs² along the path) with which the present motion stops: a rapid at
    /// the lowest rapid rate / time constant, a tapping stroke on its rigid tapping profile, any
    /// other motion at the cutting feed's.
    fn stop_rate(&self) -> f64 {
        let feed = self.cfg.feed_max_nm_min / 60e6 / self.cfg.feed_ramp_us.max(1) as f64;
        // The lowest rate / time constant of the axes `moves` names that have a rapid rate (an
        // axis without one, standing still, used to make it 0: a stop at once; found by the
        // campaign, INV-11); the cutting acceleration when none has.
        let rapid = |moves: &dyn Fn(usize) -> bool| {
            let a = (0..crate::trace::AXES)
                .filter(|&i| moves(i))
                .map(|i| self.cfg.rapid_nm_min[i] / 60e6 / self.cfg.rapid_ramp_us[i].max(1) as f64)
                .filter(|a| *a > 0.0)
                .fold(f64::INFINITY, f64::min);
            if a.is_finite() {
                a
            } else {
                feed
            }
        };
        match self.motion.as_ref().map(|m| &m.path) {
            Some(Path::Rapid { profiles, .. }) => rapid(&|i| profiles[i].dist > 0.0),
            // A rigid tapping stroke on its profile; a tap following a spindle in speed mode
            // (G93, G33.1 return) at the spindle's ramp, within the axis' own acceleration.
            Some(Path::Tap { lead, .. }) if self.spindle.position_mode => {
                self.cfg.rigid_max_rpm.max(1) as f64 / self.cfg.rigid_ramp_us.max(1) as f64 * lead / 60e6
            }
            Some(Path::Tap { lead, .. }) => {
                let a_rpm = self.cfg.spindle_max_rpm.max(1) as f64 / self.cfg.spindle_ramp_us.max(1) as f64;
                (a_rpm * lead / 60e6).min(feed)
            }
            // A coordinated rapid (LinuxCNC's G0, one straight line, LCNC-MOT-01): the lowest
            // rapid acceleration of the axes that have one.
            Some(Path::Line { .. }) if matches!(self.motion_step, Some(crate::plan::Step::Rapid { .. })) => {
                rapid(&|_| true)
            }
            // LinuxCNC 2.9's blend arc slows along itself at its tangential acceleration, half of
            // what its plane allows (its normal acceleration takes the rest; DEC-164).
            Some(Path::Bend { .. }) => 0.5 * rapid(&|_| true),
            Some(_) => feed,
            None => 0.0,
        }
    }

    pub(super) fn hold_force(&mut self) {
        self.set_signal(Signal::Stl, false);
        self.set_signal(Signal::Spl, true);
        if matches!(self.active, Active::Moving | Active::Idle) {
            self.active = Active::Held;
        }
    }

    /// Stops the present motion where it is (decelerating within the interpolation period).
    pub(super) fn stop_motion_now(&mut self) {
        if let Some(m) = &mut self.motion {
            m.stop_at(self.now, f64::INFINITY, self.cfg.period_us);
        }
        self.end_motion();
        if self.active == Active::Moving {
            self.active = Active::Idle;
        }
    }

    /// CNC reset: motion stops, rigid tapping is cancelled, the spindle returns to its state
    /// before M29, the program ends.
    fn reset(&mut self) {
        // The motion decelerates to a stop at its own limits (issue 12: it used to stop at once,
        // INV-11, INV-12); `finish` lets it come to rest before it restores the spindle.
        let a = self.stop_rate();
        let period = self.cfg.period_us;
        if let Some(m) = &mut self.motion {
            m.stop_at(self.now, a, period);
        }
        if self.active == Active::Moving {
            self.active = Active::Idle;
        }
        self.plc.clear();
        self.steps.clear();
        if self.signals.get(Signal::Rtap) || self.signals.get(Signal::Rgtap) {
            self.set_signal(Signal::Rtap, false);
            self.plc.rigid_exit(self.now);
        }
        // RGSPP / RGSPM fall when a stroke has come to rest (`end_motion`).
        for s in [Signal::Mf, Signal::Sf, Signal::Tf] {
            self.set_signal(s, false);
        }
        self.function_strobe = None;
        if self.motion.is_none() {
            self.set_signal(Signal::Rgspp, false);
            self.set_signal(Signal::Rgspm, false);
        }
        self.hold_suppressed = false;
        self.override_locked = false;
        self.overload = None;
        self.css = None;
        // A stroke's spindle turns with the tap until both are at rest; otherwise the spindle
        // goes back at once.
        if !self.motion.as_ref().is_some_and(|m| matches!(m.path, Path::Tap { .. })) {
            self.restore_after_reset();
        }
        let stop = self.motion.as_ref().map_or(self.cmd, |m| m.target);
        self.interp.reset(stop);
        self.set_phase(Phase::Idle);
        self.finish(EndReason::Reset);
    }

    /// After a reset, once the axes are at rest: the spindle returns to its state before M29
    /// (GSK-RT-25).
    pub(super) fn restore_after_reset(&mut self) {
        if let Some(rpm) = self.pre_rigid_rpm.take() {
            self.spindle.position_mode = false;
            self.spindle.command(self.now, rpm);
            self.spindle_changed();
        }
    }

    /// Starts or stops the overload timer after a change of current or watch.
    pub(super) fn overload_check(&mut self, w: OverloadWatch) {
        let over = self.current_pct[source_slot(w.source)] > w.threshold_pct;
        match (over, self.over_since) {
            (true, None) => self.over_since = Some(self.now),
            (false, Some(_)) => self.over_since = None,
            _ => {}
        }
    }

    /// When the overload retract will trip if nothing changes.
    pub(super) fn overload_expiry(&self) -> Option<Micros> {
        let w = self.overload?;
        Some(self.over_since? + w.delay_us)
    }

    /// The current stayed above the threshold for the delay: stop, retract to the start point.
    pub(super) fn overload_trip(&mut self) {
        let Some(w) = self.overload.take() else { return };
        self.over_since = None;
        let tap = self.motion.as_ref().and_then(|m| match m.path {
            Path::Tap { axis, lead, spin, .. } => {
                // The spindle turns with the tap axis (travel = lead x revolutions): the return
                // keeps the stroke's direction when the stroke already moves towards the start
                // point (a peck retract), and reverses it otherwise (a cut) (COM-SYNC-05).
                let stroke = (m.target[axis] - m.start[axis]).signum();
                let back = (w.return_to - m.pos(self.now)[axis]).signum();
                Some((axis, lead, if stroke != 0 && stroke == back { spin } else { -spin }))
            }
            _ => None,
        });
        self.emit(Event::Input { name: "overload_trip".into(), value: format!("{}%", w.threshold_pct) });
        let Some((axis, lead, spin)) = tap else { return };
        if let Some(m) = &mut self.motion {
            // The same constant acceleration as the stroke's own ramps (COM-SYNC-02).
            let a_rpm = self.cfg.rigid_max_rpm.max(1) as f64 / self.cfg.rigid_ramp_us.max(1) as f64;
            m.stop_at(self.now, a_rpm * lead / 60e6, self.cfg.period_us);
        }
        self.steps.clear();
        self.steps.push_back(Step::Phase(Phase::OverloadRetract));
        self.steps.push_back(Step::Tap(TapMove {
            axis,
            target: w.return_to,
            lead_nm: lead as i64,
            rpm: self.s_cmd.max(1),
            spindle_forward: spin > 0.0,
            override_pct: 100,
            cutting: false,
        }));
        // The alarm comes the moment the return is complete, before a feed hold or single block
        // stop that waited for the end of the cycle could hold the control first (GSK-RT-26,
        // GSK-RT-27).
        self.steps.push_back(Step::Alarm(Alarm::new(
            AlarmKind::OverloadRetract,
            format!("motor current above {}% for {} ms: tap retracted", w.threshold_pct, w.delay_us / 1000),
        )));
    }
}

fn source_slot(s: CurrentSource) -> usize {
    match s {
        CurrentSource::FeedAxis => 0,
        CurrentSource::Spindle => 1,
    }
}
