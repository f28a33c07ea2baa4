//! The logic of the cargo-fuzz targets in `fuzz/`, kept in the library so that plain `cargo test`
//! on stable replays the seed corpora and every stored crash input
//! (`harness/tests/fuzz_corpus.rs`), and so that the targets themselves stay one line each.
//!
//! Each function takes the raw bytes of one fuzz input and panics when it finds a bug; anything
//! else (a program the parser refuses, a scenario with a mistake in it) is a normal outcome:
//!
//! - [`gcode`]: the bytes as a program (UTF-8, lossy) for every dialect: the parser never panics,
//!   its errors carry a line and a column and render as a diagnostic; a program that parses runs
//!   (bounded simulated time, see [`GCODE_TIME_LIMIT_US`]) to a time-ordered trace that ends with
//!   exactly one `end` event (INV-02);
//! - [`scenario_yaml`]: the bytes as a scenario file: loading never panics, its errors render,
//!   and a scenario that loads runs and renders (report, timing diagram, event listing, VCD);
//! - [`engine_case`]: the bytes decoded as a structured campaign [`Case`] (`arbitrary`): the run
//!   keeps every invariant of `nc_engine::invariants` (`docs/invariants.md`);
//! - `cli_files`: the bytes as a file handed to `nc-conform run` / `check` (program, scenario,
//!   parameters, recorded trace, column map, tolerances), at realistic sizes or as a special file,
//!   through the command line itself: its logic is in `src/cli/fuzz_files.rs`, part of the
//!   command line, which library modules never import;
//! - [`nesting`]: deep nesting built from a structured input (LinuxCNC expressions, o-words,
//!   recursion, VCD scopes), as deep as [`nesting::MAX_DEPTH`];
//! - [`adapter_lines`]: the adapter runner of `nc-conform conform` against a fuzzed fake adapter
//!   process (its answer lines and how it misbehaves after them).
//!
//! # Bounded cost
//!
//! A fuzzer wants thousands of executions per second, so no input may make one execution slow:
//! a G-code run stops at [`GCODE_TIME_LIMIT_US`] of simulated time with a sample every
//! [`GCODE_SAMPLE_US`]; a scenario's own `options` are clamped before it runs (time limit at most
//! [`SCENARIO_MAX_TIME_LIMIT_US`], the sample period raised so that the run writes at most
//! [`SCENARIO_MAX_SAMPLES`] samples). The clamp changes how long a scenario runs, never whether
//! the harness may panic, so no bug is hidden by it. A scenario naming a `program_file` is only
//! loaded when the path is relative, stays below the working directory and names a small regular
//! file (a fuzzed `/dev/zero` would otherwise read forever).

use std::path::{Component, Path};

pub mod adapter_lines;
pub mod nesting;

pub use adapter_lines::adapter_lines;
pub use nesting::nesting;

use arbitrary::{Arbitrary, Unstructured};
use nc_engine::invariants::time_ordered_ends;
use nc_engine::{Machine, RunOptions};

use crate::campaign::case::{Compare, GenInput};
use crate::campaign::{check_case, Case};
use crate::render::{events::event_listing, timing::timing_diagram, vcd::write_vcd};
use crate::scenario::{load, run, schema::ScenarioFile};

/// A small scenario (fanuc-mill, two holes with L2), the fixture of the `cli_files` and
/// `adapter_lines` targets.
pub const SCENARIO: &str = "\
title: L2 in G91 taps two holes 10 mm apart
rules: [FAN-LEX-03]
dialect: fanuc-mill
program: |
  G90 G0 X0 Y0 Z10
  M29 S1000
  G91 G99 G84 X10 R-8 Z-6 F1000 L2
  G80
  M30
expect:
  alarms: []
  end:
    reason: program_end
";

/// Simulated time limit of a fuzzed G-code run, µs.
pub const GCODE_TIME_LIMIT_US: u64 = 60_000_000;
/// Sample period of a fuzzed G-code run, µs.
pub const GCODE_SAMPLE_US: u64 = 10_000;
/// The largest time limit a fuzzed scenario runs with, µs.
pub const SCENARIO_MAX_TIME_LIMIT_US: u64 = 20_000_000;
/// The most samples a fuzzed scenario's run writes.
pub const SCENARIO_MAX_SAMPLES: u64 = 20_000;
/// The largest `program_file` a fuzzed scenario may read, bytes.
pub const MAX_PROGRAM_FILE_BYTES: u64 = 1 << 20;

/// Fuzz target `gcode`: parse `data` under every dialect and run what parses.
///
/// # Panics
///
/// On a bug: the parser or the engine panics, a parse error has no line or column, the trace is
/// not time-ordered or does not end with exactly one `end` event.
pub fn gcode(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let opts = RunOptions {
        sample_us: GCODE_SAMPLE_US,
        time_limit_us: GCODE_TIME_LIMIT_US,
        auto_cycle_start: true,
        ..RunOptions::default()
    };
    for name in nc_engine::dialect_names() {
        let machine = Machine::new(name).expect("a listed dialect exists");
        match machine.parse(&text) {
            Ok(program) => {
                let trace = machine.run_to_trace(&program, &opts);
                if let Some(v) = time_ordered_ends(&trace) {
                    panic!("dialect {name}: {v}");
                }
            }
            Err(e) => {
                assert!(e.line >= 1 && e.col >= 1, "dialect {name}: parse error without a location: {e:?}");
                assert!(!e.message.is_empty(), "dialect {name}: parse error without a message: {e:?}");
                let diag = crate::diag::parse_error("fuzz.nc", &text, &e);
                let plain = diag.render_plain();
                assert!(
                    plain.contains("fuzz.nc:"),
                    "dialect {name}: diagnostic without its location:\n{plain}"
                );
                let _ = diag.render_fancy(false);
            }
        }
    }
}

/// Fuzz target `scenario_yaml`: load `data` as a scenario file, render its error or run it
/// (with bounded options, see the module doc) and render the outcome.
///
/// # Panics
///
/// On a bug: loading, running or rendering panics.
pub fn scenario_yaml(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    if !program_file_is_safe(&text) {
        return;
    }
    let mut s = match load::load_text(&text, "fuzz.yaml", Path::new(".")) {
        Ok(s) => s,
        Err(e) => {
            let plain = e.render_plain();
            assert!(plain.starts_with("error: "), "a scenario error renders oddly:\n{plain}");
            let _ = e.render_fancy(false);
            return;
        }
    };
    bound_options(&mut s.opts);
    let outcome = run::run(&s);
    if let Some(v) = time_ordered_ends(&outcome.trace) {
        panic!("scenario run: {v}");
    }
    let _ = outcome.passed();
    let _ = outcome.failures();
    let _ = outcome.report(&s);
    let _ = timing_diagram(&outcome.trace, &s.diagram);
    let _ = event_listing(&outcome.trace);
    let mut vcd = Vec::new();
    write_vcd(&outcome.trace, &mut vcd).expect("writing a VCD file into memory cannot fail");
}

/// Clamps a fuzzed scenario's run options so that one execution stays fast (module doc).
pub fn bound_options(opts: &mut RunOptions) {
    opts.time_limit_us = opts.time_limit_us.min(SCENARIO_MAX_TIME_LIMIT_US);
    if opts.sample_us != 0 {
        opts.sample_us = opts.sample_us.max(opts.time_limit_us / SCENARIO_MAX_SAMPLES).max(1);
    }
}

/// Whether loading `text` may read its `program_file` (module doc): true when it has none, or
/// when the path is relative, has no `..`, and names a regular file of at most
/// [`MAX_PROGRAM_FILE_BYTES`]. Texts that cannot name a program file (no `program_file` and no
/// escape that could spell it) skip the extra YAML pass.
fn program_file_is_safe(text: &str) -> bool {
    if !text.contains("program_file") && !text.contains('\\') {
        return true;
    }
    let options = serde_saphyr::options! { strict_booleans: true, with_snippet: false };
    let Ok(file) = serde_saphyr::from_str_with_options::<ScenarioFile>(text, options) else {
        return true; // load_text refuses it before reading anything
    };
    let Some(f) = &file.program_file else { return true };
    let path = Path::new(&f.value);
    let plain = path.components().all(|c| matches!(c, Component::Normal(_) | Component::CurDir));
    plain && std::fs::metadata(path).map_or(true, |m| m.is_file() && m.len() <= MAX_PROGRAM_FILE_BYTES)
}

/// Fuzz target `engine_case`: decode `data` as a campaign [`Case`] and check every invariant.
///
/// # Panics
///
/// On a bug: the engine panics or breaks an invariant (the message lists the violations and the
/// case).
///
/// The differential invariants (INV-06, INV-07) compare two runs that differ in one input, which
/// only means something when the other inputs act the same in both (`docs/invariants.md`): like
/// the campaign's `strategy::differential_case`, a case is compared only when its inputs are
/// feed overrides (`strategy::comparable`); any other case keeps its inputs and the single-trace invariants
/// (found by fuzzing: a spindle stall and late zero-speed answers made a machine-lock comparison
/// end 100 ms apart).
pub fn engine_case(data: &[u8]) {
    let Ok(mut case) = Case::arbitrary_take_rest(Unstructured::new(data)) else { return };
    if !case.inputs.iter().all(|i: &GenInput| crate::campaign::strategy::comparable(&i.action)) {
        case.compare = Compare::None;
    }
    let report = check_case(&case);
    if !report.violations.is_empty() {
        let list: Vec<String> = report.violations.iter().map(|v| format!("  {v}")).collect();
        panic!("invariants broken:\n{}\ncase: {case:?}", list.join("\n"));
    }
}
