//! # nc-conform: the harness around the reference engine
//!
//! Runs G-code programs on [`nc_engine`] and writes what happened, for conformance tests,
//! fault-injection runs and comparisons with recorded controller traces.
//!
//! - [`cli`]: the `nc-conform` command line;
//! - [`determinism`]: `run --check-determinism`;
//! - [`json_keys`]: JSON that refuses a key given twice;
//! - [`jsonl`]: the JSON Lines trace writer (`docs/trace-format.md`);
//! - [`params_yaml`]: parameter files (`docs/parameters-format.md`);
//! - [`diag`]: input errors with their location, rendered with miette or as plain text;
//! - [`render`]: event listings, ASCII timing diagrams and VCD files of a trace;
//! - [`scenario`]: scenario files, their expectations and verdicts;
//! - [`check`]: `nc-conform check`, a recorded trace compared with the reference;
//! - [`campaign`]: generated cases (programs, parameters, inputs and faults), the invariants
//!   every run must keep, and failures written back as scenario files;
//! - [`input`]: the files the tool reads, read in one place;
//! - [`import`]: recorded traces (JSON Lines, CSV, VCD, SHDR) read as engine events;
//! - [`fuzz`]: the logic of the cargo-fuzz targets, replayed by `cargo test`.

pub mod campaign;
pub mod check;
pub mod cli;
pub mod conform;
pub mod determinism;
pub mod diag;
pub mod fuzz;
pub mod import;
pub mod ini;
pub mod input;
pub mod json_keys;
pub mod jsonl;
pub mod params_yaml;
pub mod render;
pub mod scenario;
