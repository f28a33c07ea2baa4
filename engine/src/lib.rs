//! # nc-engine: the reference engine of nc-conform
//!
//! Executes G-code of several CNC dialects on a deterministic model of a machine (axes, spindle,
//! PLC interface signals) and reports what happened as a [`trace`].
//!
//! The layers, each in its own module:
//! - [`parse`]: program text → blocks of words (line and column kept);
//! - [`dialect`]: per-dialect word meaning, modal state and parameter tables: blocks → steps;
//! - [`plan`]: the steps a block or cycle becomes (motions, dwells, PLC actions, waits);
//! - [`exec`]: advances time from event to event over the plant model, applying the
//!   [`input`] schedule at exact times;
//! - [`trace`]: the events the run emits, through a streaming [`trace::TraceSink`].
//!
//! Pure and deterministic: no I/O, no clock, no global mutable state; integer microseconds and
//! nanometres; the same input gives the same trace.

// Axis slots are addressed by index across several parallel arrays (start, target, profiles).
#![allow(clippy::needless_range_loop)]

pub mod alarm;
pub mod dialect;
pub mod exec;
pub mod input;
pub mod invariants;
pub mod params;
pub mod parse;
pub mod plan;
pub mod trace;
pub mod units;

pub use alarm::{Alarm, AlarmKind};
pub use dialect::Dialect;
pub use input::{Input, InputSchedule};
pub use params::Params;
pub use parse::{ParseError, Program};
pub use trace::{Event, Trace, TraceEvent, TraceSink, VecSink};
pub use units::Micros;

/// How a run is carried out.
#[derive(Debug, Clone, PartialEq)]
pub struct RunOptions {
    /// Sample period in µs; 0 writes no samples.
    pub sample_us: Micros,
    /// The run stops (end reason `time_limit`) when simulated time reaches this.
    pub time_limit_us: Micros,
    /// Press cycle start at once whenever the program stops at M00/M01 or a single-block or
    /// feed-hold stop (what a batch run of a program wants). Scenarios turn it off.
    pub auto_cycle_start: bool,
    /// Operator actions and faults.
    pub inputs: InputSchedule,
    /// The spindle's angle when the run starts, degrees (0: at its index). A check starts the
    /// reference's spindle where the recorded one stood, so that waits for the index agree.
    pub spindle_angle_deg: f64,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            sample_us: 1000,
            time_limit_us: 7 * 24 * 3600 * 1_000_000,
            auto_cycle_start: true,
            inputs: InputSchedule::default(),
            spindle_angle_deg: 0.0,
        }
    }
}

/// A machine: a dialect and its parameter values.
#[derive(Debug, Clone)]
pub struct Machine {
    /// The dialect.
    pub dialect: &'static dyn Dialect,
    /// Parameter values (defaults from the dialect's table).
    pub params: Params,
}

impl Machine {
    /// A machine of the named dialect with default parameters.
    pub fn new(dialect_name: &str) -> Option<Machine> {
        let d = dialect::by_name(dialect_name)?;
        Some(Machine { dialect: d, params: Params::new(d.param_table()) })
    }

    /// Parses a program under this machine's dialect.
    pub fn parse(&self, text: &str) -> Result<Program, ParseError> {
        self.dialect.parse(text)
    }

    /// Runs a parsed program, streaming the trace into `sink`.
    pub fn run(&self, program: &Program, opts: &RunOptions, sink: &mut dyn TraceSink) {
        exec::run(self, program, opts, sink)
    }

    /// Runs a parsed program and keeps the whole trace.
    pub fn run_to_trace(&self, program: &Program, opts: &RunOptions) -> Trace {
        let mut sink = VecSink::default();
        self.run(program, opts, &mut sink);
        sink.into_trace()
    }
}

/// The names of every dialect, for `--dialect` and error messages.
pub fn dialect_names() -> Vec<&'static str> {
    dialect::ALL.iter().map(|d| d.name()).collect()
}
