//! Scenarios: a program, parameters, operator actions and faults, and what must happen
//! (`docs/scenarios.md`).
//!
//! - [`schema`]: the file format as serde types;
//! - [`resolve`]: names in the file → engine values, with located errors;
//! - [`load`]: a file → a runnable [`load::Scenario`];
//! - [`run`]: trace and verdicts;
//! - [`invariants`]: `expect.invariants`, the engine's invariants on the scenario's run.
pub mod expect;
pub mod invariants;
pub mod load;
pub mod resolve;
pub mod run;
pub mod schema;
pub mod timeline;
