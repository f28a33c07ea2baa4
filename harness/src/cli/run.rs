//! `nc-conform run PROGRAM --dialect NAME [--params FILE.yaml] [--sample-us N] [--out FILE]`:
//! parses the program, runs it on the reference engine and streams the trace as JSON Lines. A
//! scenario file given as PROGRAM is handed to [`super::run_scenario`].

use std::fs::File;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use clap::builder::PossibleValuesParser;
use clap::Args;
use nc_engine::trace::EndReason;
use nc_engine::{Machine, RunOptions};

use super::{display_name, parse_error, EXIT_INPUT, EXIT_OK, EXIT_RUN_FAILED};
use crate::determinism::{self, Digest};
use crate::diag::InputError;
use crate::jsonl::JsonlWriter;
use crate::params_yaml;

/// Arguments of `nc-conform run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// The G-code program file to run, or a scenario file (`.yaml`/`.yml`, docs/scenarios.md).
    #[arg(value_name = "PROGRAM")]
    pub program: PathBuf,

    /// The control dialect the program is written for, which decides what each word means
    /// (required for a program; a scenario names its own).
    #[arg(long, value_name = "DIALECT", value_parser = PossibleValuesParser::new(nc_engine::dialect_names()))]
    pub dialect: Option<String>,

    /// For a scenario: write its trace in this format instead of printing the verdicts —
    /// `jsonl` (docs/trace-format.md), `vcd` (GTKWave, Surfer) or `timing` (the ASCII timing
    /// diagram of the scenario's snapshot). The exit status still follows the verdicts.
    #[arg(long, value_name = "FORMAT", value_parser = ["jsonl", "vcd", "timing"])]
    pub format: Option<String>,

    /// A YAML file of machine parameter values that override the dialect's defaults (format:
    /// docs/parameters-format.md).
    #[arg(long, value_name = "FILE.yaml")]
    pub params: Option<PathBuf>,

    /// Sample period in microseconds of simulated time: a sample line every N µs, none when 0.
    #[arg(long, value_name = "N", default_value_t = RunOptions::default().sample_us)]
    pub sample_us: u64,

    /// Write the trace to this file instead of standard output.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,

    /// Run twice and compare the two written traces byte for byte: exit 3 when they differ,
    /// otherwise the usual exit status (the first run's output is written as usual).
    #[arg(long)]
    pub check_determinism: bool,
}

/// Carries out `nc-conform run`; returns the exit status (errors are reported on stderr).
pub fn run(args: &RunArgs) -> u8 {
    match run_inner(args) {
        Ok(code) => code,
        Err(e) => {
            e.report();
            EXIT_INPUT
        }
    }
}

fn run_inner(args: &RunArgs) -> Result<u8, InputError> {
    if super::run_scenario::is_scenario(&args.program) {
        return super::run_scenario::run(args);
    }
    if args.format.as_deref().is_some_and(|f| f != "jsonl") {
        return Err(InputError::new(
            "--format",
            "a program's trace is written as jsonl; vcd and timing are for scenarios",
        ));
    }
    let Some(dialect) = &args.dialect else {
        let mut e = InputError::new("--dialect", "a program needs --dialect");
        e.expected = Some(format!("one of: {}", nc_engine::dialect_names().join(", ")));
        return Err(e);
    };
    let mut machine = Machine::new(dialect).ok_or_else(|| {
        let mut e = InputError::new("--dialect", format!("unknown dialect `{dialect}`"));
        e.expected = Some(format!("one of: {}", nc_engine::dialect_names().join(", ")));
        e
    })?;
    let program_name = display_name(&args.program);
    let text = read_text(&args.program)?;
    if let Some(path) = &args.params {
        let name = display_name(path);
        let yaml = read_text(path)?;
        params_yaml::apply(&yaml, &mut machine)
            .map_err(|e| InputError::at(name, &yaml, e.span, e.message, e.expected))?;
    }
    let program = machine.parse(&text).map_err(|e| parse_error(&program_name, &text, &e))?;

    let (sink, dest): (Box<dyn Write>, String) = match &args.out {
        Some(path) => {
            let f = File::create(path)
                .map_err(|e| InputError::new(display_name(path), format!("cannot create: {e}")))?;
            (Box::new(f), display_name(path))
        }
        None => (Box::new(io::stdout().lock()), "standard output".to_string()),
    };
    let opts = RunOptions { sample_us: args.sample_us, ..RunOptions::default() };
    let mut writer = JsonlWriter::new(Digest::new(Some(sink)));
    machine.run(&program, &opts, &mut writer);
    let end = writer.end_reason().cloned();
    let first = match writer.finish() {
        Ok(d) => d.summary(),
        // A reader that stopped early (`| head`) is not an error of the run.
        Err(e) if e.kind() == io::ErrorKind::BrokenPipe => return Ok(exit_of(end)),
        Err(e) => return Err(InputError::new(dest, format!("cannot write the trace: {e}"))),
    };
    if args.check_determinism {
        let mut again = JsonlWriter::new(Digest::<io::Sink>::new(None));
        machine.run(&program, &opts, &mut again);
        let second = again.finish().map(|d| d.summary()).unwrap_or_default();
        if second != first {
            eprintln!("{program_name}: {}", determinism::report(first, second));
            return Ok(determinism::EXIT_NONDETERMINISTIC);
        }
    }
    Ok(exit_of(end))
}

fn exit_of(end: Option<EndReason>) -> u8 {
    match end {
        Some(EndReason::ProgramEnd) => EXIT_OK,
        _ => EXIT_RUN_FAILED,
    }
}

/// Reads a text file (invalid UTF-8 is replaced, a leading byte-order mark dropped).
fn read_text(path: &Path) -> Result<String, InputError> {
    let bytes =
        std::fs::read(path).map_err(|e| InputError::new(display_name(path), format!("cannot read: {e}")))?;
    let text = String::from_utf8_lossy(&bytes);
    Ok(text.strip_prefix('\u{feff}').unwrap_or(&text).to_string())
}
