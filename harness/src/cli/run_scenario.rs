//! `nc-conform run SCENARIO.yaml`: runs a scenario and prints its verdicts (exit 0 when every
//! expectation holds, 1 when one fails, 2 for input errors, 3 with `--check-determinism` when two
//! runs differ), or with `--format` writes the trace as JSON Lines, VCD or the timing diagram.

use std::fs::File;
use std::io::{self, Write};
use std::path::Path;

use super::{display_name, RunArgs, EXIT_OK, EXIT_RUN_FAILED};
use crate::determinism::{self, Digest};
use crate::diag::InputError;
use crate::jsonl::JsonlWriter;
use crate::render::{timing::timing_diagram, vcd::write_vcd};
use crate::scenario::{load, run};

/// The digest of a trace written as JSON Lines.
fn jsonl_digest(trace: &nc_engine::Trace) -> (u64, u64, u64) {
    let mut w = JsonlWriter::new(Digest::<io::Sink>::new(None));
    w.write_meta(&trace.meta);
    for e in &trace.events {
        w.write_event(e);
    }
    w.finish().map(|d| d.summary()).unwrap_or_default()
}

/// Whether the file is a scenario (by its extension).
pub fn is_scenario(path: &Path) -> bool {
    path.extension().is_some_and(|e| e == "yaml" || e == "yml")
}

/// Runs `nc-conform run SCENARIO.yaml`.
///
/// # Errors
///
/// Input errors: the scenario file, options that do not apply, an unwritable output.
pub fn run(args: &RunArgs) -> Result<u8, InputError> {
    if args.dialect.is_some() || args.params.is_some() {
        return Err(InputError::new(
            "--dialect/--params",
            "a scenario names its own dialect and parameters; leave out --dialect and --params",
        ));
    }
    if args.time_limit != super::run::DEFAULT_TIME_LIMIT_S {
        return Err(InputError::new(
            "--time-limit",
            "a scenario names its own time limit (options.time_limit_ms); leave out --time-limit",
        ));
    }
    let name = display_name(&args.program);
    let mut s = load::load(&args.program, &name)?;
    s.opts.sample_us = if args.sample_us == nc_engine::RunOptions::default().sample_us {
        s.opts.sample_us
    } else {
        args.sample_us
    };
    // The trace is held in memory: --sample-us may not make it hold more than a scenario may.
    if s.opts.sample_us > 0 && s.opts.time_limit_us / s.opts.sample_us > load::MAX_SAMPLES {
        let mut e = InputError::new(
            "--sample-us",
            format!(
                "{} µs samples over the scenario's time limit of {} ms would be more than {} samples",
                s.opts.sample_us,
                s.opts.time_limit_us / 1000,
                load::MAX_SAMPLES
            ),
        );
        e.expected = Some("a larger --sample-us (or none: the scenario's own)".into());
        return Err(e);
    }
    let outcome = run::run(&s);
    let code = if outcome.passed() { EXIT_OK } else { EXIT_RUN_FAILED };
    if args.check_determinism {
        let (a, b) = (jsonl_digest(&outcome.trace), jsonl_digest(&run::run(&s).trace));
        if a != b {
            eprintln!("{name}: {}", determinism::report(a, b));
            return Ok(determinism::EXIT_NONDETERMINISTIC);
        }
    }
    let (mut out, dest): (Box<dyn Write>, String) = match &args.out {
        Some(path) => {
            let f = File::create(path)
                .map_err(|e| InputError::new(display_name(path), format!("cannot create: {e}")))?;
            (Box::new(io::BufWriter::new(f)), display_name(path))
        }
        None => (Box::new(io::BufWriter::new(io::stdout().lock())), "standard output".to_string()),
    };
    let written = match args.format.as_deref() {
        None => out.write_all(outcome.report(&s).as_bytes()),
        Some("jsonl") => {
            let mut w = JsonlWriter::new(&mut out);
            w.write_meta(&outcome.trace.meta);
            for e in &outcome.trace.events {
                w.write_event(e);
            }
            w.finish().map(|_| ())
        }
        Some("vcd") => write_vcd(&outcome.trace, &mut out),
        Some(_) => out.write_all(timing_diagram(&outcome.trace, &s.diagram).as_bytes()),
    };
    if args.format.is_some() && !outcome.passed() {
        eprint!("{}", outcome.failures());
    }
    match written.and_then(|()| out.flush()) {
        Ok(()) => Ok(code),
        Err(e) if e.kind() == io::ErrorKind::BrokenPipe => Ok(code),
        Err(e) => Err(InputError::new(dest, format!("cannot write: {e}"))),
    }
}
