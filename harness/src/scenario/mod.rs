//! Scenarios: a program, parameters, operator actions and faults, and what must happen
//! (`docs/scenarios.md`).
//!
//! - [`schema`]: the file format as serde types;
//! - [`resolve`]: names in the file → engine values, with located errors.
pub mod resolve;
pub mod schema;
