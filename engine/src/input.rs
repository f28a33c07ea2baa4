//! Inputs: operator actions and faults, the one door through which anything outside the program
//! acts on the machine. A scenario, a property test, a fuzzer and a vendor adapter all build an
//! [`InputSchedule`]; the executor consults it and applies each input at its exact time.

use crate::trace::{Phase, Signal};
use crate::units::{Micros, Nm};

/// Which motor's current the overload watch reads (parameter 186 bit 5 on GSK).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum CurrentSource {
    /// The tapping (feed) axis motor.
    FeedAxis,
    /// The spindle motor.
    Spindle,
}

/// A PLC or drive answer that can be delayed or withheld.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum PlcAnswer {
    /// The drive's position-mode reached answer after M29.
    PositionModeReached,
    /// FIN of M/S/T functions.
    Fin,
    /// The PLC raising RGTAP after the position mode is reached.
    Rgtap,
    /// The drive's zero-speed signal.
    ZeroSpeed,
}

/// One operator action or fault.
#[derive(Debug, Clone, PartialEq)]
pub enum Input {
    /// Cycle start button.
    CycleStart,
    /// Reset key.
    Reset,
    /// Feed hold button.
    FeedHold,
    /// Single block switch.
    SingleBlock(bool),
    /// Dry run switch.
    DryRun(bool),
    /// Machine lock switch.
    MachineLock(bool),
    /// Optional stop (M01) switch.
    OptionalStop(bool),
    /// Feed override, %.
    FeedOverride(u32),
    /// Spindle override, %.
    SpindleOverride(u32),
    /// Emergency stop pressed (true) or released (false).
    EmergencyStop(bool),
    /// Motor current of one motor, % of rated.
    MotorCurrent {
        /// Which motor.
        source: CurrentSource,
        /// % of rated current.
        percent: u32,
    },
    /// A PLC/drive answer is delayed by this much more than its parameter, or never comes (None).
    PlcAnswer {
        /// Which answer.
        answer: PlcAnswer,
        /// Extra delay in µs; `None`: the answer never comes.
        extra_us: Option<Micros>,
    },
    /// The spindle stalls (true: it stops turning whatever it is commanded) or recovers.
    SpindleStall(bool),
    /// A machine parameter changes.
    SetParam {
        /// Parameter id.
        id: String,
        /// Axis for per-axis parameters.
        axis: Option<char>,
        /// New value.
        value: f64,
    },
}

impl Input {
    /// The name used in traces and scenarios.
    pub fn name(&self) -> &'static str {
        match self {
            Input::CycleStart => "cycle_start",
            Input::Reset => "reset",
            Input::FeedHold => "feed_hold",
            Input::SingleBlock(_) => "single_block",
            Input::DryRun(_) => "dry_run",
            Input::MachineLock(_) => "machine_lock",
            Input::OptionalStop(_) => "optional_stop",
            Input::FeedOverride(_) => "feed_override",
            Input::SpindleOverride(_) => "spindle_override",
            Input::EmergencyStop(_) => "emergency_stop",
            Input::MotorCurrent { .. } => "motor_current",
            Input::PlcAnswer { .. } => "plc_answer",
            Input::SpindleStall(_) => "spindle_stall",
            Input::SetParam { .. } => "set_param",
        }
    }

    /// The value as trace text.
    pub fn value_text(&self) -> String {
        let onoff = |b: &bool| if *b { "on".to_string() } else { "off".to_string() };
        match self {
            Input::CycleStart | Input::Reset | Input::FeedHold => String::new(),
            Input::SingleBlock(b)
            | Input::DryRun(b)
            | Input::MachineLock(b)
            | Input::OptionalStop(b)
            | Input::EmergencyStop(b)
            | Input::SpindleStall(b) => onoff(b),
            Input::FeedOverride(p) | Input::SpindleOverride(p) => format!("{p}%"),
            Input::MotorCurrent { source, percent } => {
                let s = match source {
                    CurrentSource::FeedAxis => "feed_axis",
                    CurrentSource::Spindle => "spindle",
                };
                format!("{s} {percent}%")
            }
            Input::PlcAnswer { answer, extra_us } => {
                let a = match answer {
                    PlcAnswer::PositionModeReached => "position_mode_reached",
                    PlcAnswer::Fin => "fin",
                    PlcAnswer::Rgtap => "rgtap",
                    PlcAnswer::ZeroSpeed => "zero_speed",
                };
                match extra_us {
                    Some(us) => format!("{a} late {us}us"),
                    None => format!("{a} never"),
                }
            }
            Input::SetParam { id, axis, value } => match axis {
                Some(a) => format!("{id}.{a}={value}"),
                None => format!("{id}={value}"),
            },
        }
    }
}

/// Something that happens during a run, by which inputs and checks are timed.
#[derive(Debug, Clone, PartialEq)]
pub enum Condition {
    /// A signal has this value.
    Signal {
        /// Which signal.
        signal: Signal,
        /// 1 or 0.
        value: bool,
    },
    /// An axis' machine position (as sampled) is strictly below this (nm, reported units: diameter for a
    /// lathe's X).
    AxisBelow {
        /// Axis slot.
        axis: usize,
        /// Threshold.
        nm: Nm,
    },
    /// An axis' machine position (as sampled) is strictly above this.
    AxisAbove {
        /// Axis slot.
        axis: usize,
        /// Threshold.
        nm: Nm,
    },
    /// The block on this source line starts.
    Block {
        /// 1-based line.
        line: u32,
    },
    /// The phase is entered.
    Phase(Phase),
    /// An M/S/T function is output.
    Function {
        /// `M`, `S`, `T`.
        letter: char,
        /// Its number.
        code: u32,
    },
}

/// When an input acts.
#[derive(Debug, Clone, PartialEq)]
pub enum Trigger {
    /// At this time.
    At(Micros),
    /// `delay` after the `occurrence`-th time (1 = first) `condition` begins to hold.
    When {
        /// The condition.
        condition: Condition,
        /// Which occurrence, from 1.
        occurrence: u32,
        /// Delay after it, µs.
        delay_us: Micros,
    },
}

/// An input with its trigger.
#[derive(Debug, Clone, PartialEq)]
pub struct ScheduledInput {
    /// When.
    pub trigger: Trigger,
    /// What.
    pub input: Input,
}

/// Everything that will act on the run, in the order given.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct InputSchedule {
    /// The inputs.
    pub inputs: Vec<ScheduledInput>,
}

impl InputSchedule {
    /// Adds an input at a time.
    pub fn at(mut self, t_us: Micros, input: Input) -> Self {
        self.inputs.push(ScheduledInput { trigger: Trigger::At(t_us), input });
        self
    }

    /// Adds an input on a condition.
    pub fn when(mut self, condition: Condition, occurrence: u32, delay_us: Micros, input: Input) -> Self {
        self.inputs
            .push(ScheduledInput { trigger: Trigger::When { condition, occurrence, delay_us }, input });
        self
    }

    /// The timed inputs sorted by time (stable: same-time inputs keep their order).
    pub fn timed(&self) -> Vec<(Micros, Input)> {
        let mut v: Vec<(Micros, Input)> = self
            .inputs
            .iter()
            .filter_map(|s| match s.trigger {
                Trigger::At(t) => Some((t, s.input.clone())),
                Trigger::When { .. } => None,
            })
            .collect();
        v.sort_by_key(|(t, _)| *t);
        v
    }

    /// The inputs on conditions, in the order given.
    pub fn conditional(&self) -> Vec<(Condition, u32, Micros, Input)> {
        self.inputs
            .iter()
            .filter_map(|s| match &s.trigger {
                Trigger::When { condition, occurrence, delay_us } => {
                    Some((condition.clone(), *occurrence, *delay_us, s.input.clone()))
                }
                Trigger::At(_) => None,
            })
            .collect()
    }
}
