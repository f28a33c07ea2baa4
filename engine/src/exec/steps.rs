//! Carrying out one planned step: starting motions, functions, handshakes, dwells and stops.

use super::motion::{Motion, Path};
use super::profile::Profile;
use super::{Active, AfterAwait, Exec};
use crate::alarm::{Alarm, AlarmKind};
use crate::plan::{Feed, PassLaw, Plane, Pos, SpindleEffect, Step, TapMove, ThreadPass};
use crate::trace::{EndReason, Event, Signal, AXES};
use crate::units::{ceil_to, Micros};

impl Exec<'_> {
    /// Takes the next step (reading the next block when the queue is empty) and starts it.
    pub(super) fn start_next(&mut self) {
        if self.hold_requested {
            self.hold_requested = false;
            self.merge_single_block_stop();
            self.hold_force();
            return;
        }
        if let Some((line, text)) = self.held_block.take() {
            // The block single block stopped before (`step_stops_before_motion`) runs now.
            self.emit(Event::Block { line, text });
        }
        let Some(step) = self.steps.pop_front() else {
            if self.in_block && self.cfg.step_stops_before_motion {
                // LinuxCNC: the step goes on into the blocks that move nothing (L-121).
                self.step_done = true;
            } else if self.in_block && self.single_block && !self.hold_suppressed {
                self.in_block = false;
                self.hold_force();
                return;
            }
            self.in_block = false;
            self.read_block();
            return;
        };
        // The step a feed hold puts back to carry the move on after cycle start (an
        // unsynchronised follow too: LinuxCNC's G33.1 move back, DEC-157).
        if matches!(
            step,
            Step::Rapid { .. } | Step::Feed { .. } | Step::Arc { .. } | Step::Tap(_) | Step::Thread(_)
        ) || matches!(&step, Step::Follow(f) if f.kind == crate::plan::FollowKind::Unsynced)
        {
            self.motion_step = Some(step.clone());
        }
        self.start_step(step);
    }

    /// A hold that falls where single block stops anyway (the next step that does anything is a
    /// single-block stop, or the end of the block) is that stop too: one stop, not two. Feed hold
    /// and single block take effect at the same point of a tapping cycle (seed 000 注意事项 6,
    /// GSK-RT-27, COM-INP-03).
    fn merge_single_block_stop(&mut self) {
        match self.steps.iter().position(|s| !matches!(s, Step::Phase(_))) {
            Some(i) if matches!(self.steps[i], Step::SingleBlockStop) => {
                self.steps.remove(i);
            }
            // LinuxCNC's step stops before the next block that moves, not here (L-121).
            None if !self.cfg.step_stops_before_motion => self.in_block = false,
            _ => {}
        }
    }

    fn read_block(&mut self) {
        let Some(block) = self.program.blocks.get(self.pc) else {
            self.finish(EndReason::ProgramEnd);
            return;
        };
        self.pc += 1;
        self.blocks += 1;
        self.in_block = true;
        self.cur_line = Some(block.line);
        let (line, text) = (block.line, block.text.clone());
        let mut out = Vec::new();
        // A block read ahead by the planner (`planner.rs`) was interpreted then.
        let read = match self.ahead.pop_front() {
            Some(Ok(steps)) => {
                out = steps;
                Ok(())
            }
            Some(Err(a)) => Err(a),
            None => self.interp.block(block, &mut out),
        };
        if read.is_ok() && self.stops_before(&out) {
            self.step_done = false;
            self.held_block = Some((line, text));
            self.steps.extend(out);
            self.hold_force();
            return;
        }
        self.emit(Event::Block { line, text });
        match read {
            Ok(()) => self.steps.extend(out),
            Err(a) => self.raise(a),
        }
    }

    /// LinuxCNC's step (`PlantConfig::step_stops_before_motion`, LCNC-INP-01, L-121): under single
    /// block, once a block has ended in the present step, the step ends before the next block
    /// that moves the axes. The task stops a step when it takes up a command of another line
    /// (emctaskmain.cc `STEPPING_CHECK`), and only the moves carry their line to it (emccanon.cc:
    /// `STRAIGHT_TRAVERSE`, `STRAIGHT_FEED`, `ARC_FEED`, `RIGID_TAP`, `STRAIGHT_PROBE` set the
    /// line number; spindle, coolant, `DWELL` and the program end take the line before).
    fn stops_before(&self, out: &[Step]) -> bool {
        self.cfg.step_stops_before_motion
            && self.step_done
            && self.single_block
            && !self.hold_suppressed
            && out.iter().any(|s| {
                matches!(
                    s,
                    Step::Rapid { .. }
                        | Step::Feed { .. }
                        | Step::Arc { .. }
                        | Step::Tap(_)
                        | Step::Thread(_)
                        | Step::Follow(_)
                        | Step::More(_)
                )
            })
    }

    fn start_step(&mut self, step: Step) {
        let now = self.now;
        // A new strobe waits until the ladder has dropped FIN of the previous one (COM-PLC-01).
        if matches!(step, Step::Function { .. } | Step::FunctionWithMotion { .. } | Step::RigidEnter { .. })
            && self.signals.get(Signal::Fin)
        {
            self.steps.push_front(step);
            self.active = Active::Await { signal: Signal::Fin, value: false, then: AfterAwait::Nothing };
            return;
        }
        // A feed at 0 % feed override does not start: the axes stand still until an input may
        // have raised the override (it used to take no time and jump to its end: INV-11).
        if matches!(step, Step::Feed { .. } | Step::Arc { .. })
            && self.feed_override == 0
            && !(self.hold_suppressed || self.override_locked)
        {
            self.steps.push_front(step);
            let next = self.inputs.get(self.next_input).map_or(Micros::MAX, |(t, _)| (*t).max(now));
            self.active = Active::Until(next);
            return;
        }
        // LinuxCNC: the first cutting move after a spindle start waits for the spindle at speed,
        // the same wait as before a synchronised move (`Step::AwaitAtSpeed`).
        if self.atspeed_next_feed && matches!(step, Step::Feed { .. } | Step::Arc { .. }) {
            self.atspeed_next_feed = false;
            self.steps.push_front(step);
            self.steps.push_front(Step::AwaitAtSpeed);
            return;
        }
        // LinuxCNC: a synchronised move straight after another goes on with the run (DEC-170).
        let step = match step {
            Step::Thread(p)
                if self.cfg.sync_run_continues
                    && self.sync_run
                    && self.sync_lock.is_some()
                    && p.law == PassLaw::Accelerated { room: None } =>
            {
                Step::Thread(ThreadPass { law: PassLaw::Tracking, ..p })
            }
            other => other,
        };
        // The run ends at any other step that moves or waits; a synchronised move's own start
        // (`start_motion`) begins or continues it.
        if !super::planner::is_bookkeeping(&step) && !matches!(step, Step::Thread(_)) {
            self.sync_run = false;
        }
        match step {
            Step::Phase(p) => self.set_phase(p),
            Step::Rapid { target } => {
                // Under G96 the speed for the end point, from the start of the rapid (DEC-66).
                self.css_follow(target[0]);
                if self.start_blend_arc(&Step::Rapid { target }, target) {
                    return;
                }
                let scale = self.planner_accel_scale();
                if !self.start_blended_line(target, scale, None) {
                    self.start_rapid(target, scale)
                }
            }
            Step::Feed { target, feed } => {
                // LinuxCNC 2.9's blend arcs between G64 feeds (DEC-164).
                if self.start_blend_arc(&Step::Feed { target, feed }, target) {
                    return;
                }
                let scale = self.planner_accel_scale();
                if self.start_blended_line(target, scale, Some(feed)) {
                    return;
                }
                let len = path_len(&self.cmd, &target);
                if let Some(profile) = self.feed_profile(len, feed, scale) {
                    self.start_motion(target, Path::Line { profile, len });
                }
            }
            Step::Arc { target, center, plane, clockwise, feed } => {
                // LinuxCNC 2.9's blend from a G64 feed into the arc (DEC-164).
                if self.start_blend_arc(&step, target) {
                    return;
                }
                self.start_arc(target, center, plane, clockwise, feed)
            }
            Step::Dwell { us } => self.active = Active::Until(ceil_to(now + us, self.cfg.period_us)),
            Step::Function { letter, code, effect } => {
                let strobe = self.start_function(letter, code, effect);
                self.active =
                    Active::Await { signal: Signal::Fin, value: true, then: AfterAwait::EndStrobe(strobe) };
                self.check_await();
            }
            Step::FunctionWithMotion { letter, code, effect } => {
                // The motion after it starts now; the strobe drops when FIN comes (KND-LEX-04).
                self.function_strobe = Some(self.start_function(letter, code, effect));
            }
            Step::AwaitFunction => {
                if let Some(strobe) = self.function_strobe.take() {
                    self.active = Active::Await {
                        signal: Signal::Fin,
                        value: true,
                        then: AfterAwait::EndStrobe(strobe),
                    };
                    self.check_await();
                }
            }
            Step::RigidEnter { code, rpm } => {
                self.emit(Event::Function { letter: 'M', code });
                // The state before M29 is what the spindle was commanded to do (it may still be ramping).
                let rpm_now = self.spindle.target;
                self.pre_rigid_rpm = Some(self.pre_rigid_rpm.unwrap_or(rpm_now));
                self.s_cmd = rpm;
                self.spindle.command(now, 0.0);
                self.spindle.position_mode = true;
                self.spindle_changed();
                self.set_signal(Signal::Mf, true);
                self.set_signal(Signal::Rtap, true);
                self.plc.rigid_strobe(now);
                self.active = Active::Await {
                    signal: Signal::Fin,
                    value: true,
                    then: AfterAwait::EndStrobe(Signal::Mf),
                };
                self.check_await();
            }
            Step::RigidCheck { alarm } => {
                if !self.signals.get(Signal::Rgtap) {
                    self.raise(Alarm::new(alarm, "RGTAP (G61.0) is 0 when the rigid tapping cycle starts"));
                }
            }
            Step::RigidExit { wait_rgtap } => {
                self.set_signal(Signal::Rtap, false);
                self.plc.rigid_exit(now);
                self.spindle.position_mode = false;
                let (a, _) = self.spindle.at(now);
                self.spindle.hold(now, a);
                self.pre_rigid_rpm = None;
                if wait_rgtap && self.signals.get(Signal::Rgtap) {
                    self.active =
                        Active::Await { signal: Signal::Rgtap, value: false, then: AfterAwait::Nothing };
                }
            }
            Step::Tap(t) => self.start_tap(t),
            Step::Thread(t) => self.start_thread(t),
            Step::Hold => self.hold_force(),
            Step::SingleBlockStop => {
                if self.single_block && !self.hold_suppressed {
                    self.hold_force();
                }
            }
            Step::Follow(f) => self.start_follow(f),
            Step::AwaitSignal { signal, value, timeout_us, alarm } => {
                self.start_await(signal, value, timeout_us, alarm)
            }
            Step::More(m) => {
                // The next chunk of a peck cycle, planned now that the run has got there.
                let mut next = Vec::new();
                m.expand(&mut next);
                for s in next.into_iter().rev() {
                    self.steps.push_front(s);
                }
            }
            Step::HoldSuppress(b) => {
                self.hold_suppressed = b;
                if !b && self.hold_pending {
                    self.hold_pending = false;
                    self.hold_requested = true;
                }
            }
            Step::OverrideLock(b) => {
                self.override_locked = b;
                self.spindle_override_changed();
            }
            Step::AwaitAtSpeed => {
                if !self.spindle_at_speed(now) {
                    self.active = Active::AtSpeed;
                }
            }
            Step::Css(c) => self.css_set(c),
            Step::Overload(w) => {
                self.overload = w;
                self.over_since = None;
                if let Some(w) = w {
                    self.overload_check(w);
                }
            }
            Step::Orient => {
                // Onto the next whole turn at the spindle's own acceleration (issue 12: it used
                // to jump there): complete after the orientation time, or at rest if later.
                let rest = self.spindle.orient(now, self.cfg.orient_us);
                self.active = Active::Until(ceil_to(rest, self.cfg.period_us));
            }
            Step::Stop { optional } => {
                if !optional || self.optional_stop {
                    self.hold();
                }
            }
            Step::End => self.finish(EndReason::ProgramEnd),
            Step::Alarm(a) => self.raise(a),
            Step::Report(a) => self.report(a),
            Step::Halt => self.halt(),
            Step::PathMode { continuous, tolerance_nm } => {
                self.path_continuous = continuous;
                self.path_tolerance = tolerance_nm as f64;
            }
        }
    }

    /// Stops automatic operation until cycle start (or goes on at once in a batch run).
    pub(super) fn hold(&mut self) {
        if self.opts.auto_cycle_start {
            return;
        }
        self.set_signal(Signal::Stl, false);
        self.set_signal(Signal::Spl, true);
        self.active = Active::Held;
    }

    /// The profile of a cutting feed move of `len` nm (COM-MOT-02) at `scale` × the cutting
    /// acceleration (`Exec::planner_accel_scale`); None after raising 0011.
    fn feed_profile(&mut self, len: f64, feed: Feed, scale: f64) -> Option<Profile> {
        let nm_per_min = match feed {
            Feed::PerMin(f) => f,
            Feed::PerRev(f) => f * self.spindle.at(self.now).1.abs(),
        };
        // A spindle starting from rest (M03 with the move, KND-LEX-04) is changing speed: the
        // feed follows it below.
        let starting = matches!(feed, Feed::PerRev(_)) && self.spindle.ramp(self.now).is_some();
        if nm_per_min <= 0.0 && !starting {
            self.raise(Alarm::new(AlarmKind::FeedZero, "feed per revolution with the spindle stopped"));
            return None;
        }
        // In a tapping cycle (hold suppressed) feed override and dry run do not act (COM-MOT-07).
        let tapping = self.hold_suppressed || self.override_locked;
        let ovr = if tapping { 100.0 } else { self.feed_override as f64 };
        let dry = self.dry_run && !tapping;
        let mut v = nm_per_min * ovr / 100.0;
        if dry {
            v = self.cfg.dry_run_nm_min * ovr / 100.0;
        }
        let vmax = self.cfg.feed_max_nm_min / 60e6;
        let a = self.cfg.feed_max_nm_min / 60e6 / self.cfg.feed_ramp_us.max(1) as f64 * scale;
        // Per revolution while the spindle changes speed: F x the actual speed throughout.
        if let (Feed::PerRev(f), false, Some(ramp)) = (feed, dry, self.spindle.ramp(self.now)) {
            let per_rpm = f * ovr / 100.0 / 60e6;
            let p = Profile::following(len, per_rpm, ramp, vmax, a, self.cfg.period_us);
            if p.is_none() {
                self.raise(Alarm::new(
                    AlarmKind::FeedZero,
                    "feed per revolution with the spindle stopping before the end of the move",
                ));
            }
            return p;
        }
        Some(Profile::trapezoid(len, (v / 60e6).min(vmax), a, self.cfg.period_us))
    }

    /// A rapid to `target`, at `scale` × the axes' acceleration (`Exec::planner_accel_scale`).
    fn start_rapid(&mut self, target: Pos, scale: f64) {
        let ramp_us =
            self.cfg
                .rapid_ramp_us
                .map(|r| if scale == 1.0 { r } else { (r as f64 / scale).round() as Micros });
        if self.cfg.coordinated_rapid {
            // One straight line (LinuxCNC); backlash is the joints' business, not the path's.
            for i in 0..AXES {
                let d = target[i] - self.cmd[i];
                if d != 0 {
                    self.backlash(i, d.signum() as i8);
                }
            }
            let delta = std::array::from_fn(|i| (target[i] - self.cmd[i]) as f64);
            let path =
                super::motion::coordinated_rapid(delta, self.cfg.rapid_nm_min, ramp_us, self.cfg.period_us);
            self.start_motion(target, path);
            return;
        }
        let mut profiles = [Profile::still(); AXES];
        let mut backlash = [0.0; AXES];
        for i in 0..AXES {
            let d = target[i] - self.cmd[i];
            if d == 0 {
                continue;
            }
            let b = self.backlash(i, d.signum() as i8);
            let v = self.cfg.rapid_nm_min[i] / 60e6;
            let a = v / ramp_us[i].max(1) as f64;
            profiles[i] = Profile::trapezoid(d.abs() as f64 + b, v, a, self.cfg.period_us);
            backlash[i] = b;
        }
        self.start_motion(target, Path::Rapid { profiles, backlash });
    }

    /// Backlash to take up when axis `i` moves in direction `dir` (and records the direction).
    /// Under machine lock the motor stays still: a locked motion keeps the timing of the
    /// commanded reversal (COM-MOT-04: the same timing with and without the lock) but leaves the
    /// motor's own direction alone, which the first motion after the lock then meets (it used to
    /// take up a backlash the motor never left: campaign seed 778, INV-11).
    pub(super) fn backlash(&mut self, i: usize, dir: i8) -> f64 {
        let last = if self.machine_lock { self.last_dir[i] } else { self.motor_dir[i] };
        self.last_dir[i] = dir;
        if !self.machine_lock {
            self.motor_dir[i] = dir;
        }
        if last != 0 && last != dir {
            self.cfg.backlash_nm[i] as f64
        } else {
            0.0
        }
    }

    fn start_arc(&mut self, target: Pos, center: [i64; 2], plane: Plane, cw: bool, feed: Feed) {
        let (i0, i1, i2) = plane.axes();
        let c = [center[0] as f64, center[1] as f64];
        let s = self.cmd;
        let (sx, sy) = (s[i0] as f64 - c[0], s[i1] as f64 - c[1]);
        let (ex, ey) = (target[i0] as f64 - c[0], target[i1] as f64 - c[1]);
        let radius = libm::hypot(sx, sy);
        let radius_end = libm::hypot(ex, ey);
        let a0 = libm::atan2(sy, sx);
        let a1 = libm::atan2(ey, ex);
        let tau = std::f64::consts::TAU;
        let mut sweep = arc_sweep(a0, a1, cw);
        let full_turn = (target[i0] == s[i0] && target[i1] == s[i1]) as u8;
        if full_turn == 0 && sweep.abs() > tau - 1e-12 {
            sweep = 0.0;
        }
        let h = (target[i2] - s[i2]) as f64;
        let len = libm::hypot(0.5 * (radius + radius_end) * sweep.abs(), h);
        let scale = self.planner_accel_scale();
        // LinuxCNC 2.9 (DEC-164): entered from a blend at its speed, or left through one into the
        // next feed, the circle runs from the blend's end to the next blend's start.
        let entry = if self.cfg.parabolic_half_accel { self.entry.take().map(|e| e.0) } else { None };
        let sf = [s[0] as f64, s[1] as f64, s[2] as f64];
        let exit =
            self.arc_to_line_blend(sf, (target, center, plane, cw, feed), (scale, entry.unwrap_or(0.0)));
        if entry.is_some() || exit.is_some() {
            let mut end = target;
            let (mut sweep, mut v1) = (sweep, 0.0);
            if let Some((arc, trim, next_target, nominal2)) = exit {
                sweep -= sweep.signum() * trim;
                for i in 0..3 {
                    end[i] = crate::units::round_i64(arc.start[i]);
                }
                v1 = arc.v;
                self.pend_blend(arc, next_target, nominal2);
            }
            let len = radius * sweep.abs();
            if let Some(v) = self.acting_feed(feed) {
                let a = self.cfg.feed_max_nm_min / 60e6 / self.cfg.feed_ramp_us.max(1) as f64 * scale;
                let vmax = v.min(self.cfg.feed_max_nm_min / 60e6);
                let profile = Profile::between(len, entry.unwrap_or(0.0), vmax, v1, a, self.cfg.period_us);
                let path =
                    Path::Arc { profile, len, center: c, radius, radius_end: radius, a0, sweep, plane };
                self.start_motion(end, path);
                return;
            }
        }
        if let Some(profile) = self.feed_profile(len, feed, scale) {
            self.start_motion(
                target,
                Path::Arc { profile, len, center: c, radius, radius_end, a0, sweep, plane },
            );
        }
    }

    fn start_tap(&mut self, t: TapMove) {
        let now = self.now;
        let d = t.target - self.cmd[t.axis];
        let b = if d != 0 { self.backlash(t.axis, d.signum() as i8) } else { 0.0 };
        if d == 0 && b == 0.0 {
            // A stroke of no length (the tap already stands at its target, e.g. an overload
            // return after a peck retract that ended at the start point): nothing turns, so
            // RGSPP / RGSPM stay 0 (COM-SYNC-03).
            return;
        }
        let rpm = t.rpm.min(self.cfg.rigid_max_rpm.max(1)) as f64 * t.override_pct.max(1) as f64 / 100.0;
        let lead = t.lead_nm as f64;
        // No faster than the tap axis may cut: a long lead slows the spindle with it (INV-11).
        let v = (rpm * lead / 60e6).min(self.cfg.feed_max_nm_min / 60e6);
        // Spindle and tap axis share one time constant at the rigid tapping maximum speed.
        let a_rpm = self.cfg.rigid_max_rpm.max(1) as f64 / self.cfg.rigid_ramp_us.max(1) as f64;
        let a = a_rpm * lead / 60e6;
        let profile = Profile::trapezoid(d.unsigned_abs() as f64 + b, v, a, self.cfg.period_us);
        let spin = if t.spindle_forward { 1.0 } else { -1.0 };
        let (angle, _) = self.spindle.at(now);
        self.spindle.hold(now, angle);
        self.set_signal(if t.spindle_forward { Signal::Rgspp } else { Signal::Rgspm }, true);
        if !self.spindle.stalled && !self.machine_lock {
            self.set_signal(Signal::Zsp, false);
        }
        let mut target = self.cmd;
        target[t.axis] = t.target;
        self.stall_angle = None;
        self.start_motion(target, Path::Tap { profile, axis: t.axis, backlash: b, lead, spin });
        if self.spindle.stalled {
            self.stall_checks();
        }
    }

    /// The spindle is stalled during a tapping stroke: its angle freezes while the tap axis goes on
    /// (COM-INP-09). The servo's excess error trips when the axis has run the limit ahead (0411);
    /// the ladder's stall timer raises 5074 — whichever comes first.
    pub(super) fn stall_checks(&mut self) {
        let now = self.now;
        let Some(m) = &self.motion else { return };
        let Path::Tap { axis, .. } = m.path else { return };
        self.stall_angle = Some(self.spindle_at(now).0);
        let p0 = m.pos(now)[axis];
        let limit = self.cfg.excess_error_nm;
        let ahead = |t: Micros| (m.pos(t)[axis] - p0).abs() >= limit;
        let end = m.end();
        if ahead(end) {
            let (mut lo, mut hi) = (now, end);
            while hi - lo > 1 {
                let mid = lo + (hi - lo) / 2;
                if ahead(mid) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            self.plc.at(hi, super::plc::PlcAction::ExcessError);
        }
        self.plc.at(now + self.cfg.plc.spindle_stall_us, super::plc::PlcAction::StallTimer);
    }

    pub(super) fn start_motion(&mut self, target: Pos, path: Path) {
        self.sync_run = matches!(path, Path::Thread { .. });
        let m = Motion {
            t0: self.now,
            start: self.cmd,
            target,
            path_end: target,
            path,
            locked: self.machine_lock,
            lock_spindle: self.machine_lock,
        };
        if m.duration() == 0 {
            // A motion of no duration (a G01 at feed override 0 %) still moves the command
            // positions; under machine lock the machine stays where it is (COM-MOT-04), as
            // `end_motion_then` does for a motion that ran (found by the campaign, seed 13).
            if m.locked {
                for i in 0..AXES {
                    self.lock_offset[i] += target[i] - m.start[i];
                }
            }
            self.cmd = target;
            return;
        }
        self.motion = Some(m);
        self.active = Active::Moving;
    }

    /// The present motion reached its end.
    pub(super) fn end_motion(&mut self) {
        self.end_motion_then(true);
    }

    /// The present motion ends: positions and the spindle stay where the motion leaves them, a
    /// tapping stroke drops RGSPP / RGSPM and (with `zsp_answer`) asks the drive for zero speed.
    pub(super) fn end_motion_then(&mut self, zsp_answer: bool) {
        let Some(m) = self.motion.take() else { return };
        self.following = false;
        let end = m.end();
        if let Some((da, _)) = m.spindle(end) {
            let angle = match self.stall_angle.take() {
                Some(a) => a,
                None if m.locked && m.lock_spindle => self.spindle.angle0,
                None => self.spindle.angle0 + da,
            };
            self.spindle.hold(end, angle);
            self.set_signal(Signal::Rgspp, false);
            self.set_signal(Signal::Rgspm, false);
            // A coast cut short at the allowance: the spindle brakes on, its ZSP comes after.
            let coast = self.coast.take().filter(|c| c.0 == end && c.1 != 0.0 && !self.spindle.stalled);
            if let Some((_, rpm, decel)) = coast {
                self.spindle.rpm0 = rpm;
                self.spindle.seg_accel = Some(decel);
                self.spindle_changed();
            } else if zsp_answer {
                let zsp = self.cfg.plc.zsp_us;
                self.plc.answer(
                    self.now,
                    zsp,
                    crate::input::PlcAnswer::ZeroSpeed,
                    super::plc::PlcAction::ZeroSpeed,
                );
            }
        }
        if m.locked {
            for i in 0..AXES {
                self.lock_offset[i] += m.target[i] - m.start[i];
            }
        }
        self.cmd = m.target;
    }

    /// Outputs a function (its strobe, its effect on the spindle, the PLC's FIN to come); returns
    /// its strobe signal.
    fn start_function(&mut self, letter: char, code: u32, effect: SpindleEffect) -> Signal {
        let now = self.now;
        self.emit(Event::Function { letter, code });
        let strobe = match letter {
            'S' => Signal::Sf,
            'T' => Signal::Tf,
            _ => Signal::Mf,
        };
        let max = self.cfg.spindle_max_rpm as f64;
        let spindle_ovr = self.spindle_ovr();
        let speed = match self.css {
            Some(css) => self.css_speed(&css, self.cmd[0]),
            None => (self.s_cmd as f64 * spindle_ovr as f64 / 100.0).min(max),
        };
        let mut orient_fin = 0;
        match effect {
            SpindleEffect::None => {}
            SpindleEffect::Forward => {
                self.spindle.command(now, speed);
                self.atspeed_next_feed = self.cfg.feed_waits_at_speed;
            }
            SpindleEffect::Reverse => {
                self.spindle.command(now, -speed);
                self.atspeed_next_feed = self.cfg.feed_waits_at_speed;
            }
            SpindleEffect::Stop => self.spindle.command(now, 0.0),
            SpindleEffect::Orient => {
                // FIN comes when the orientation is complete (FAN-LEX-06).
                let done = self.spindle.orient(now, self.cfg.orient_us);
                orient_fin = done - now;
            }
            SpindleEffect::Speed(s) => {
                self.s_cmd = s;
                let (_, rpm) = self.spindle.at(now);
                if rpm != 0.0 && !self.spindle.position_mode {
                    let s = (s as f64 * spindle_ovr as f64 / 100.0).min(max);
                    self.spindle.command(now, s * rpm.signum());
                }
            }
        }
        if effect != SpindleEffect::None {
            self.spindle_changed();
        }
        self.set_signal(strobe, true);
        let fin = if letter == 'M' && code == 6 && self.cfg.tool_change_us > 0 {
            self.cfg.tool_change_us
        } else {
            self.cfg.plc.fin_us.max(orient_fin)
        };
        self.plc.strobe(now, fin);
        strobe
    }
}

/// Euclidean length between two positions, nm.
fn path_len(a: &Pos, b: &Pos) -> f64 {
    let mut s = 0.0;
    for i in 0..AXES {
        let d = (b[i] - a[i]) as f64;
        s += d * d;
    }
    s.sqrt()
}

/// The signed angle an arc turns from the angle `a0` to `a1` about its centre: negative clockwise
/// (G2), positive counter-clockwise (G3), never zero (a whole turn when they are equal). Two
/// iterations at most: `a1 - a0` from two `atan2` lies in (−2π, 2π].
pub(crate) fn arc_sweep(a0: f64, a1: f64, cw: bool) -> f64 {
    let tau = std::f64::consts::TAU;
    let mut sweep = a1 - a0;
    if cw {
        while sweep >= 0.0 {
            sweep -= tau;
        }
    } else {
        while sweep <= 0.0 {
            sweep += tau;
        }
    }
    sweep
}
