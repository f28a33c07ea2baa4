//! Execute: advances time from event to event over the plant model, carrying out the planned
//! steps and applying inputs and faults at their exact times.
//!
//! The executor's cost grows with the number of events, not with simulated time: motions are
//! closed-form profiles evaluated only where something is observed (a sample, an input, the end
//! of a step). The CNC acts on interpolation-period ticks; the PLC and drive ([`plc`]) answer
//! after their own delays.

mod arc_blend;
mod arc_join;
mod blend;
pub mod config;
mod css;
mod follow;
mod inputs;
pub mod motion;
mod pass_blend;
mod planner;
mod plc;
pub mod profile;
mod resync;
pub mod spindle;
mod steps;
mod thread;
mod triggers;

pub use config::{OverrideLimits, PlantConfig, PlcConfig};

use std::collections::VecDeque;

use crate::alarm::Alarm;
use crate::dialect::Interpreter;
use crate::input::Input;
use crate::parse::Program;
use crate::plan::{Css, OverloadWatch, Pos, Step};
use crate::trace::{
    EndReason, EndSummary, Event, Phase, Sample, Signal, Signals, TraceEvent, TraceMeta, TraceSink, AXES,
};
use crate::units::{ceil_to, Micros};
use crate::{Machine, RunOptions};
use motion::Motion;
use plc::Plc;
use spindle::Spindle;

/// What the CNC is busy with.
#[derive(Debug, Clone, PartialEq)]
enum Active {
    /// Ready for the next step.
    Idle,
    /// A motion (the `Motion` is in `Exec::motion`).
    Moving,
    /// Until a time (dwell, or the tick at which an awaited signal was seen).
    Until(Micros),
    /// Until a signal has a value; then the step's follow-up.
    Await { signal: Signal, value: bool, then: AfterAwait },
    /// Stopped until cycle start (feed hold, single block, M00).
    Held,
    /// Until the spindle is at speed (`Step::AwaitAtSpeed`): its speed change has ended and it
    /// is not stalled; a stalled spindle is never at speed, and the wait lasts.
    AtSpeed,
}

/// What to do once an awaited signal arrives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum AfterAwait {
    /// Drop the strobe, the function is complete.
    EndStrobe(Signal),
    /// Nothing more.
    Nothing,
}

/// The whole state of one run.
pub(crate) struct Exec<'a> {
    cfg: PlantConfig,
    opts: &'a RunOptions,
    sink: &'a mut dyn TraceSink,
    interp: Box<dyn Interpreter>,
    program: &'a Program,
    diameter_x: bool,
    now: Micros,
    next_sample: Micros,
    pc: usize,
    steps: VecDeque<Step>,
    active: Active,
    motion: Option<Motion>,
    /// Command positions when no motion is running.
    cmd: Pos,
    /// Command minus machine position (grows under machine lock).
    lock_offset: Pos,
    /// Last commanded direction of motion per axis (the timing of backlash), −1, 0, +1.
    last_dir: [i8; AXES],
    /// Last direction the motor of each axis really moved (machine lock holds it), −1, 0, +1.
    motor_dir: [i8; AXES],
    spindle: Spindle,
    /// Spindle state before M29 (speed, signed rpm) to restore at reset.
    pre_rigid_rpm: Option<f64>,
    /// Commanded speed, rpm.
    s_cmd: u32,
    signals: Signals,
    plc: Plc,
    inputs: Vec<(Micros, Input)>,
    next_input: usize,
    phase: Phase,
    hold_suppressed: bool,
    /// Overrides held at 100 % by the program (`Step::OverrideLock`).
    override_locked: bool,
    hold_pending: bool,
    single_block: bool,
    dry_run: bool,
    machine_lock: bool,
    optional_stop: bool,
    feed_override: u32,
    spindle_override: u32,
    overload: Option<OverloadWatch>,
    current_pct: [u32; 2],
    over_since: Option<Micros>,
    alarms: u32,
    blocks: u32,
    finished: Option<EndReason>,
    /// A block has been read and its steps not yet all taken (single block stops after it).
    in_block: bool,
    /// `PlantConfig::step_stops_before_motion`: a block has ended in this step, so single block
    /// stops before the next block that moves.
    step_done: bool,
    /// The block read at a stop before it (`step_stops_before_motion`): its line and text, shown
    /// when the cycle start runs it.
    held_block: Option<(u32, String)>,
    /// Inputs waiting for their condition.
    pending: Vec<triggers::Pending>,
    /// The dialect (to re-derive the plant when a parameter changes).
    dialect: &'static dyn crate::dialect::Dialect,
    /// The parameters in force.
    params: crate::params::Params,
    /// The spindle stalled during the present tapping stroke: its angle then.
    stall_angle: Option<f64>,
    /// Source line of the block being executed (located alarms raised while executing it).
    cur_line: Option<u32>,
    /// Feed hold asked for: stop before the next step.
    hold_requested: bool,
    /// The strobe of a function output together with a motion, until its FIN comes.
    function_strobe: Option<Signal>,
    /// The step that started the present motion (re-queued when a hold interrupts it).
    motion_step: Option<Step>,
    /// Serial number of the present `Step::AwaitSignal` wait (its timer checks it).
    await_no: u64,
    /// Constant surface speed in force (KND G96).
    css: Option<Css>,
    /// The present motion follows the spindle's encoder in speed mode (`Step::Follow`).
    following: bool,
    /// The `Step::Follow` that started a motion, with that motion's start time (`resync`).
    follow_step: Option<(Micros, crate::plan::Follow)>,
    /// The law the last accelerated thread pass settled on (DEC-147's tracking segments).
    sync_lock: Option<thread::SyncLock>,
    /// The last step that moved was a synchronised move, with nothing but bookkeeping since
    /// (`PlantConfig::sync_run_continues`).
    sync_run: bool,
    /// A braking coast cut short at the allowance (NC-1050): when it ends (µs), the spindle's
    /// speed then (signed rpm) and its braking deceleration (rpm/µs).
    coast: Option<(Micros, f64, f64)>,
    /// The speed (nm/µs) a following cut reached its end point with, and whether it ran under
    /// machine lock, for the brake after it.
    follow_v: Option<(f64, bool)>,
    /// A spindle start has been commanded since the last cutting move: the next one waits for the
    /// spindle at speed (`PlantConfig::feed_waits_at_speed`), through `Step::AwaitAtSpeed`.
    atspeed_next_feed: bool,
    /// LinuxCNC's path control mode is G64 (`Step::PathMode`; LinuxCNC powers on in it).
    path_continuous: bool,
    /// The blend tolerance the planner gives the moves from here on, nm (0: none; `Step::PathMode`).
    path_tolerance: f64,
    /// Blocks the planner has read ahead of their turn (`planner.rs`), read from here first.
    ahead: planner::Ahead,
    /// LinuxCNC 2.9's blend arc planned to run before the next rapid (`planner.rs`, DEC-164).
    blend: Option<planner::PendingBlend>,
    /// The speed (nm/µs) and nominal length (nm) the next rapid enters with, after a blend arc.
    entry: Option<(f64, f64)>,
    /// LinuxCNC 2.9's blend arc between a G64 thread pass and its exit taper (`pass_blend.rs`).
    pass_blend: Option<pass_blend::PassBlend>,
}

/// Runs `program` on `machine`, streaming the trace into `sink`.
pub fn run(machine: &Machine, program: &Program, opts: &RunOptions, sink: &mut dyn TraceSink) {
    let cfg = machine.dialect.plant_config(&machine.params);
    let power_on_tolerance = cfg.power_on_tolerance_nm;
    let meta = TraceMeta {
        dialect: machine.dialect.name(),
        axes: machine.dialect.axes().to_vec(),
        period_us: cfg.period_us,
        sample_us: opts.sample_us,
    };
    sink.start(&meta);
    let accel = cfg.spindle_max_rpm as f64 / (cfg.spindle_ramp_us.max(1)) as f64;
    let diameter_x = meta.axes.iter().any(|a| a.diameter);
    let mut interp = machine.dialect.interpreter(&machine.params);
    interp.program(program);
    let mut ex = Exec {
        interp,
        plc: Plc::new(cfg.plc),
        cfg,
        opts,
        sink,
        program,
        diameter_x,
        now: 0,
        next_sample: 0,
        pc: 0,
        steps: VecDeque::new(),
        active: Active::Idle,
        motion: None,
        cmd: [0; AXES],
        lock_offset: [0; AXES],
        last_dir: [0; AXES],
        motor_dir: [0; AXES],
        spindle: Spindle {
            angle0: if opts.spindle_angle_deg.is_finite() { opts.spindle_angle_deg } else { 0.0 },
            ..Spindle::new(if accel > 0.0 { accel } else { f64::INFINITY })
        },
        pre_rigid_rpm: None,
        s_cmd: 0,
        signals: Signals::default(),
        inputs: opts.inputs.timed(),
        next_input: 0,
        phase: Phase::Idle,
        hold_suppressed: false,
        override_locked: false,
        hold_pending: false,
        single_block: false,
        dry_run: false,
        machine_lock: false,
        optional_stop: false,
        feed_override: 100,
        spindle_override: 100,
        overload: None,
        current_pct: [0; 2],
        over_since: None,
        alarms: 0,
        blocks: 0,
        finished: None,
        in_block: false,
        step_done: false,
        held_block: None,
        cur_line: None,
        stall_angle: None,
        pending: opts
            .inputs
            .conditional()
            .into_iter()
            .map(|(cond, occurrence, delay_us, input)| triggers::Pending {
                // The power-on idle is no entry into idle: a phase condition counts entries.
                was: cond == crate::input::Condition::Phase(Phase::Idle),
                cond,
                remaining: occurrence.max(1),
                delay_us,
                input,
            })
            .collect(),
        dialect: machine.dialect,
        params: machine.params.clone(),
        hold_requested: false,
        function_strobe: None,
        motion_step: None,
        await_no: 0,
        css: None,
        following: false,
        follow_step: None,
        sync_lock: None,
        sync_run: false,
        coast: None,
        follow_v: None,
        atspeed_next_feed: false,
        path_continuous: true,
        path_tolerance: power_on_tolerance,
        ahead: planner::Ahead::new(),
        blend: None,
        entry: None,
        pass_blend: None,
    };
    ex.main_loop();
}

impl Exec<'_> {
    fn main_loop(&mut self) {
        self.set_signal(Signal::Stl, true);
        self.set_signal(Signal::Zsp, true);
        self.check_triggers(None);
        while self.finished.is_none() {
            // Inputs due now act before the next step starts (COM-INP-01).
            if self.inputs.get(self.next_input).is_some_and(|(t, _)| *t <= self.now) {
                self.handle_events_at(self.now);
                continue;
            }
            if self.active == Active::Idle {
                self.start_next();
                continue;
            }
            let t = self.next_event_time();
            if t == Micros::MAX || t > self.opts.time_limit_us {
                // A control waiting for a stalled spindle to be at speed still waits (LinuxCNC:
                // the feed never starts): the run ends at its time limit, not as stopped.
                let waiting = self.active == Active::AtSpeed;
                let reason = if self.active == Active::Held || (t == Micros::MAX && !waiting) {
                    EndReason::Stopped
                } else {
                    EndReason::TimeLimit
                };
                if reason == EndReason::TimeLimit {
                    self.advance_to(self.opts.time_limit_us);
                }
                self.finish(reason);
                break;
            }
            self.advance_to(t);
            if self.sink.wants_stop() {
                self.finish(EndReason::OutputLimit);
                break;
            }
            self.handle_events_at(t);
        }
    }

    /// The earliest time at which anything happens.
    fn next_event_time(&self) -> Micros {
        let mut t = Micros::MAX;
        match &self.active {
            Active::Moving => {
                if let Some(m) = &self.motion {
                    t = t.min(m.end());
                }
            }
            Active::Until(u) => t = t.min(*u),
            Active::AtSpeed if !self.spindle.stalled => {
                t = t.min(ceil_to(self.spindle.ramp_end().max(self.now), self.cfg.period_us.max(1)));
            }
            _ => {}
        }
        if let Some(p) = self.plc.next_time() {
            t = t.min(p);
        }
        if let Some((ti, _)) = self.inputs.get(self.next_input) {
            t = t.min((*ti).max(self.now));
        }
        if let Some(e) = self.overload_expiry() {
            t = t.min(e.max(self.now));
        }
        if let Some(c) = self.next_axis_crossing() {
            t = t.min(c);
        }
        if let Some(c) = self.css_next() {
            t = t.min(c);
        }
        t
    }

    /// Moves the clock to `t`, writing the samples on the way.
    fn advance_to(&mut self, t: Micros) {
        if self.opts.sample_us > 0 {
            while self.next_sample <= t {
                let s = self.sample_at(self.next_sample);
                self.sink.event(&TraceEvent { t_us: self.next_sample, event: Event::Sample(s) });
                self.next_sample += self.opts.sample_us;
                if self.sink.wants_stop() {
                    // The run ends here, at the last sample written (`main_loop`).
                    self.now = (self.next_sample - self.opts.sample_us).max(self.now);
                    return;
                }
            }
        }
        self.now = t;
    }

    /// Everything due at `now`: PLC answers, inputs, overload, the end of the present activity.
    fn handle_events_at(&mut self, t: Micros) {
        self.check_triggers(None);
        while let Some(a) = self.plc.pop_due(t) {
            self.plc_edge(a);
            if self.finished.is_some() {
                return;
            }
        }
        while let Some((ti, input)) = self.inputs.get(self.next_input).cloned() {
            if ti > t {
                break;
            }
            self.next_input += 1;
            self.apply_input(input);
            if self.finished.is_some() {
                return;
            }
        }
        if let Some(e) = self.overload_expiry() {
            if e <= t {
                self.overload_trip();
                if self.finished.is_some() {
                    return;
                }
            }
        }
        self.css_tick(t);
        match self.active.clone() {
            Active::Moving if self.motion.as_ref().is_some_and(|m| m.end() <= t) => {
                self.end_motion();
                self.active = Active::Idle;
            }
            Active::Until(u) if u <= t => self.active = Active::Idle,
            Active::AtSpeed if self.spindle_at_speed(t) => {
                // The control sees at-speed on its next tick.
                let tick = ceil_to(t, self.cfg.period_us.max(1));
                self.active = if tick > t { Active::Until(tick) } else { Active::Idle };
            }
            _ => {}
        }
    }

    /// The spindle is at speed (LinuxCNC's `spindle.0.at-speed`): not stalled and no speed change
    /// under way.
    fn spindle_at_speed(&self, t: Micros) -> bool {
        !self.spindle.stalled && self.spindle.ramp(t).is_none()
    }

    /// Checks an awaited signal after a PLC edge; the CNC notices it at its next tick.
    fn check_await(&mut self) {
        if let Active::Await { signal, value, then } = self.active {
            if self.signals.get(signal) == value {
                if let AfterAwait::EndStrobe(strobe) = then {
                    self.set_signal(strobe, false);
                    self.plc.strobe_dropped(self.now);
                }
                let tick = ceil_to(self.now, self.cfg.period_us);
                self.active = if tick > self.now { Active::Until(tick) } else { Active::Idle };
            }
        }
    }

    /// Emits an event at the present time.
    fn emit(&mut self, event: Event) {
        // A sample at t shows the state before the events at t (COM-TIME-04).
        if self.opts.sample_us > 0 && self.next_sample <= self.now {
            self.advance_to(self.now);
        }
        let ev = TraceEvent { t_us: self.now, event };
        self.sink.event(&ev);
        if !self.pending.is_empty() {
            self.check_triggers(Some(&ev.event));
        }
    }

    /// Sets a signal, emitting an edge when it changes.
    fn set_signal(&mut self, s: Signal, v: bool) {
        if self.signals.get(s) != v {
            self.signals.set(s, v);
            self.emit(Event::Signal { signal: s, value: v });
        }
    }

    /// The drive's zero-speed signal after a change of the spindle's command: it falls as the
    /// spindle starts and rises when a ramp to a stop has ended (unless withheld by a fault).
    fn spindle_changed(&mut self) {
        let (_, rpm) = self.spindle_at(self.now);
        let moving = rpm != 0.0 || (self.spindle.target != 0.0 && !self.spindle.stalled);
        if moving {
            self.set_signal(Signal::Zsp, false);
        }
        if self.spindle.target == 0.0 {
            let t = self.spindle.ramp_end().max(self.now) + self.cfg.plc.zsp_us;
            self.plc.answer(
                self.now,
                t - self.now,
                crate::input::PlcAnswer::ZeroSpeed,
                plc::PlcAction::ZeroSpeed,
            );
        }
    }

    fn set_phase(&mut self, p: Phase) {
        if self.phase != p {
            self.phase = p;
            self.emit(Event::Phase(p));
        }
    }

    /// Raises an alarm: the machine stops where it is and the run ends.
    fn raise(&mut self, alarm: Alarm) {
        self.report(alarm);
        self.halt();
    }

    /// Reports an alarm without stopping (`Step::Report`).
    fn report(&mut self, mut alarm: Alarm) {
        if alarm.line.is_none() {
            alarm.line = self.cur_line;
        }
        self.alarms += 1;
        self.emit(Event::Alarm(alarm));
    }

    /// The run ends on an alarm already reported: the machine stops where it is.
    fn halt(&mut self) {
        // The motion stops where it is: a tapping stroke ends with the spindle at rest at its
        // present (or frozen) angle and RGSPP / RGSPM off (COM-SYNC-03, COM-INP-09); the drive
        // reports zero speed unless it already does.
        if let Some(m) = &mut self.motion {
            m.stop_at(self.now, f64::INFINITY, self.cfg.period_us);
        }
        let zsp = self.signals.get(Signal::Zsp);
        self.end_motion_then(!zsp);
        self.finish(EndReason::Alarm);
    }

    /// After the end: the ladder and the drive finish what they were answering (FIN falls, RGTAP
    /// and the position mode drop, zero speed comes); their timers no longer matter.
    fn settle(&mut self) {
        while let Some(t) = self.plc.next_time() {
            match self.plc.pop_due(t) {
                Some(plc::PlcAction::Set(sig, v)) => {
                    self.advance_to(t);
                    self.set_signal(sig, v);
                    let rtap = self.signals.get(Signal::Rtap);
                    let rest = self.spindle_rest();
                    self.plc.react(self.now, sig, v, rtap, rest);
                }
                Some(plc::PlcAction::ZeroSpeed) => {
                    self.advance_to(t);
                    if self.spindle_at(t).1 == 0.0 {
                        self.set_signal(Signal::Zsp, true);
                    }
                }
                Some(_) => {}
                None => break,
            }
        }
    }

    /// When the spindle comes to rest: the end of its ramp to a stop in speed mode, else now.
    fn spindle_rest(&self) -> Micros {
        if self.motion.as_ref().is_some_and(|m| m.spindle(self.now).is_some()) || self.spindle.target != 0.0 {
            return self.now;
        }
        self.spindle.ramp_end().max(self.now)
    }

    /// Machine positions (physical) at `t`.
    fn machine_pos(&self, t: Micros) -> Pos {
        self.machine_from(self.command_pos(t))
    }

    /// Machine positions (physical) from the command positions `cmd`.
    fn machine_from(&self, cmd: Pos) -> Pos {
        let mut p = [0; AXES];
        for i in 0..AXES {
            p[i] = cmd[i] - self.lock_offset[i];
        }
        if let Some(m) = self.motion.as_ref().filter(|m| m.locked) {
            for i in 0..AXES {
                p[i] = m.start[i] - self.lock_offset[i];
            }
        }
        p
    }

    /// Command positions (physical) at `t`.
    fn command_pos(&self, t: Micros) -> Pos {
        match &self.motion {
            Some(m) => m.pos(t),
            None => self.cmd,
        }
    }

    /// Spindle angle (deg, unwrapped) and speed (rpm) at `t`.
    fn spindle_at(&self, t: Micros) -> (f64, f64) {
        self.spindle_from(t, self.motion.as_ref().and_then(|m| m.spindle(t)))
    }

    /// [`Exec::spindle_at`], the tapping stroke's spindle at `t` (`Motion::spindle`) given.
    fn spindle_from(&self, t: Micros, tap: Option<(f64, f64)>) -> (f64, f64) {
        if let Some(m) = &self.motion {
            if let Some((da, rpm)) = tap {
                if m.locked && m.lock_spindle {
                    return (self.spindle.angle0, 0.0);
                }
                if let Some(a) = self.stall_angle {
                    return (a, 0.0);
                }
                // The instant a braking coast is cut short, the spindle still turns.
                let rpm = match self.coast {
                    Some((te, r, _)) if te == t => r,
                    _ => rpm,
                };
                return (self.spindle.angle0 + da, rpm);
            }
        }
        self.spindle.at(t)
    }

    #[inline(always)]
    fn sample_at(&self, t: Micros) -> Sample {
        // The motion's positions and a tapping stroke's spindle from one look at its profile.
        let (cmd, tap) = match &self.motion {
            Some(m) => m.pos_and_spindle(t),
            None => (self.cmd, None),
        };
        let p = self.machine_from(cmd);
        let mut axes = p;
        if self.diameter_x {
            axes[0] = p[0] * 2;
        }
        let (angle, rpm) = self.spindle_from(t, tap);
        let mdeg = crate::units::round_i64(angle * 1000.0);
        Sample {
            axes,
            spindle_mrpm: crate::units::round_i64(rpm * 1000.0),
            spindle_mdeg: mdeg.rem_euclid(360_000),
        }
    }

    fn finish(&mut self, reason: EndReason) {
        if self.finished.is_some() {
            return;
        }
        self.finished = Some(reason.clone());
        if matches!(reason, EndReason::ProgramEnd | EndReason::Reset | EndReason::Alarm) {
            self.settle();
        }
        if reason == EndReason::Reset {
            // The motion a reset stopped decelerates to rest; then the spindle returns to its
            // state before M29 (GSK-RT-25), and the run ends once its ramp has ended.
            if let Some(end) = self.motion.as_ref().map(|m| m.end()) {
                self.advance_to(end.max(self.now));
                self.end_motion();
                self.settle();
            }
            if self.pre_rigid_rpm.is_some() {
                self.restore_after_reset();
                self.settle();
            }
            let t = self.spindle.ramp_end().max(self.now);
            self.advance_to(t);
            self.settle();
        }
        let state = self.sample_at(self.now);
        let mut command = self.command_pos(self.now);
        if self.diameter_x {
            command[0] *= 2;
        }
        let summary = EndSummary {
            reason,
            state,
            command,
            signals: self.signals,
            modal: self.interp.modal(),
            alarms: self.alarms,
            blocks: self.blocks,
        };
        self.emit(Event::End(Box::new(summary)));
    }
}
