//! Vendor conformance: the scenario suite run against a third-party controller
//! (`docs/adapter-protocol.md`).
//!
//! A controller is anything that implements [`Controller`]: load a program and parameters,
//! take operator inputs and faults at given times, advance its clock, and hand over the trace
//! events it produced (`docs/trace-format.md`). The harness drives it scenario by scenario:
//!
//! - [`reference`]: the reference engine as a [`Controller`] (it re-runs deterministically);
//! - [`wire`]: inputs, conditions and parameters as the adapter protocol's JSON values;
//! - [`process`]: a controller in another process, over the line protocol on stdin/stdout;
//! - [`serve`]: the protocol's other end, for any [`Controller`] (`nc-conform serve`);
//! - [`drive`]: one scenario through a controller, stepping from trigger to trigger so that
//!   `when:` inputs act on the controller's own outputs at their exact time;
//! - [`verdict`]: the scenario's expectations on the controller's trace, and the controller's
//!   trace compared with the reference's by [`crate::check`];
//! - [`kept`]: a controller's trace kept in a file, judged again as [`verdict`] judged it;
//! - [`suite`]: every scenario of a directory, the summary per rule id, JUnit and JSON reports,
//!   and the libtest-mimic entry behind [`crate::conformance_suite!`].

pub mod drive;
pub mod kept;
pub mod process;
pub mod reference;
pub mod serve;
pub mod suite;
pub mod verdict;
pub mod wire;

use nc_engine::input::{Condition, Input};
use nc_engine::trace::TraceEvent;
use nc_engine::units::Micros;

/// The version of the adapter protocol this harness speaks.
pub const PROTOCOL: &str = "nc-conform-adapter/1";

/// Who a controller is and what it can run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Identity {
    /// Its name (`acme-cnc`).
    pub name: String,
    /// Its version.
    pub version: String,
    /// The dialects it runs (scenarios of the others are skipped).
    pub dialects: Vec<String>,
}

/// One parameter value given to the controller: the vendor's parameter id, the axis for a
/// per-axis parameter, the value (units of `docs/parameters.md`).
#[derive(Debug, Clone, PartialEq)]
pub struct ParamValue {
    /// Parameter id (`5200.6`, `271`, `plc.fin_ms`).
    pub id: String,
    /// Axis letter of a per-axis parameter.
    pub axis: Option<char>,
    /// The value.
    pub value: f64,
}

/// What a controller is asked to run.
#[derive(Debug, Clone, PartialEq)]
pub struct Job {
    /// Dialect name (`gsk-lathe`).
    pub dialect: String,
    /// The program text, as written.
    pub program: String,
    /// Parameter values over the dialect's defaults.
    pub params: Vec<ParamValue>,
    /// Sample period, µs (0: no samples).
    pub sample_us: Micros,
    /// The run ends (reason `time_limit`) when the clock reaches this.
    pub time_limit_us: Micros,
    /// Press cycle start whenever the program stops (M00/M01, single block, feed hold).
    pub auto_cycle_start: bool,
}

/// How a load went.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Loaded {
    /// Ready to run.
    Ready,
    /// The controller refuses the program: where and why.
    Refused {
        /// 1-based line.
        line: u32,
        /// 1-based column, when known.
        col: Option<u32>,
        /// The controller's message.
        message: String,
    },
    /// The controller does not run this (dialect, feature): the scenario is skipped.
    Unsupported(String),
}

/// Where an advance stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Advanced {
    /// The controller's clock, µs.
    pub now_us: Micros,
    /// Index (in the `stop_on` list) of the condition that began to hold, when it stopped on one.
    pub stopped_on: Option<usize>,
    /// The run has ended (its `end` event is produced).
    pub ended: bool,
}

/// What went wrong with a controller (not with the scenario): the scenario fails with it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ControllerError {
    /// What kind of failure.
    pub kind: ErrorKind,
    /// What happened.
    pub message: String,
    /// The last lines the controller wrote on its standard error (process adapters).
    pub stderr_tail: String,
}

/// The kinds of [`ControllerError`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// No answer within the timeout.
    Timeout,
    /// The controller exited or was killed by a signal.
    Crash,
    /// An answer that is not JSON, or not an object.
    Garbage,
    /// A well-formed answer that breaks the protocol (wrong version, missing key, bad event).
    Protocol,
    /// The controller answered `ok: false` with an error.
    Failed,
    /// The controller cannot honour an input or condition of this scenario (`ok: false` with
    /// `unsupported` to `input` or `advance`): the scenario is not applicable, reported as skipped.
    NotApplicable,
}

impl ErrorKind {
    /// The name used in reports.
    pub fn name(self) -> &'static str {
        match self {
            ErrorKind::Timeout => "timeout",
            ErrorKind::Crash => "crash",
            ErrorKind::Garbage => "garbage output",
            ErrorKind::Protocol => "protocol error",
            ErrorKind::Failed => "controller error",
            ErrorKind::NotApplicable => "not applicable",
        }
    }
}

impl ControllerError {
    /// An error without stderr.
    pub fn new(kind: ErrorKind, message: impl Into<String>) -> Self {
        ControllerError { kind, message: message.into(), stderr_tail: String::new() }
    }
}

impl std::fmt::Display for ControllerError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.kind.name(), self.message)?;
        if !self.stderr_tail.trim().is_empty() {
            write!(f, "\n--- controller stderr (tail) ---\n{}", self.stderr_tail.trim_end())?;
        }
        Ok(())
    }
}

impl std::error::Error for ControllerError {}

/// A CNC controller under test. The harness calls, for each scenario: [`Controller::load`],
/// [`Controller::input`] for the inputs at fixed times, then [`Controller::advance`] and
/// [`Controller::read`] in turn until the run ends, giving the inputs on conditions as their
/// conditions begin to hold. Time is simulated: µs since the program started.
pub trait Controller {
    /// Who it is and the dialects it runs.
    ///
    /// # Errors
    ///
    /// The controller cannot answer.
    fn identity(&mut self) -> Result<Identity, ControllerError>;

    /// Loads a program with its parameters and options; the machine is at power-on state, the
    /// clock at 0, nothing read yet.
    ///
    /// # Errors
    ///
    /// The controller failed (a refusal of the program is [`Loaded::Refused`], not an error).
    fn load(&mut self, job: &Job) -> Result<Loaded, ControllerError>;

    /// An operator input or fault that acts at `t_us` (at or after the clock). Inputs given while
    /// the controller stands stopped on a condition at `t_us` = its clock act right after the
    /// event that made the condition hold.
    ///
    /// # Errors
    ///
    /// The controller failed or refuses the input (e.g. in the past).
    fn input(&mut self, t_us: Micros, input: &Input) -> Result<(), ControllerError>;

    /// Runs until the clock reaches `until_us` (every event before it produced), or until one of
    /// `stop_on` begins to hold (right after the event that made it hold), or until the run
    /// ends, whichever comes first.
    ///
    /// # Errors
    ///
    /// The controller failed.
    fn advance(&mut self, until_us: Micros, stop_on: &[Condition]) -> Result<Advanced, ControllerError>;

    /// The trace events produced since the last read, in time order.
    ///
    /// # Errors
    ///
    /// The controller failed or produced a bad event.
    fn read(&mut self) -> Result<Vec<TraceEvent>, ControllerError>;
}

impl<C: Controller + ?Sized> Controller for Box<C> {
    fn identity(&mut self) -> Result<Identity, ControllerError> {
        (**self).identity()
    }
    fn load(&mut self, job: &Job) -> Result<Loaded, ControllerError> {
        (**self).load(job)
    }
    fn input(&mut self, t_us: Micros, input: &Input) -> Result<(), ControllerError> {
        (**self).input(t_us, input)
    }
    fn advance(&mut self, until_us: Micros, stop_on: &[Condition]) -> Result<Advanced, ControllerError> {
        (**self).advance(until_us, stop_on)
    }
    fn read(&mut self) -> Result<Vec<TraceEvent>, ControllerError> {
        (**self).read()
    }
}
