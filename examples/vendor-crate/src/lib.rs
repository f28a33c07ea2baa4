//! An example vendor crate: "Acme 980" is a lathe control that runs the `gsk-lathe` dialect.
//! It implements [`nc_conform::conform::Controller`] so that `cargo test` runs every scenario
//! against it (see `tests/conformance.rs`).
//!
//! The example's machine is the reference engine (a real vendor puts its own controller, a
//! simulator or a bridge to the machine here); what it shows is the shape of the glue: the
//! identity and dialects it declares, a load that refuses dialects it does not run, and the
//! four calls the harness steps it with.

use nc_conform::conform::reference::Reference;
use nc_conform::conform::{Advanced, Controller, ControllerError, Identity, Job, Loaded};
use nc_engine::input::{Condition, Input};
use nc_engine::trace::TraceEvent;
use nc_engine::units::Micros;

/// The Acme 980 lathe control.
#[derive(Debug, Default)]
pub struct Acme980 {
    machine: Reference,
}

impl Acme980 {
    /// A control at power-on.
    pub fn new() -> Self {
        Acme980::default()
    }
}

/// The only dialect the Acme 980 runs.
pub const DIALECT: &str = "gsk-lathe";

impl Controller for Acme980 {
    fn identity(&mut self) -> Result<Identity, ControllerError> {
        Ok(Identity { name: "acme-980".into(), version: "2.4.1".into(), dialects: vec![DIALECT.into()] })
    }

    fn load(&mut self, job: &Job) -> Result<Loaded, ControllerError> {
        if job.dialect != DIALECT {
            return Ok(Loaded::Unsupported(format!("the Acme 980 runs {DIALECT} only")));
        }
        self.machine.load(job)
    }

    fn input(&mut self, t_us: Micros, input: &Input) -> Result<(), ControllerError> {
        self.machine.input(t_us, input)
    }

    fn advance(&mut self, until_us: Micros, stop_on: &[Condition]) -> Result<Advanced, ControllerError> {
        self.machine.advance(until_us, stop_on)
    }

    fn read(&mut self) -> Result<Vec<TraceEvent>, ControllerError> {
        self.machine.read()
    }
}
