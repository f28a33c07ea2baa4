//! The `nc-conform` command line.
//!
//! `nc-conform run PROGRAM --dialect NAME [--params FILE.yaml] [--sample-us N] [--out FILE]`
//! parses the program, runs it on the reference engine and streams the trace as JSON Lines.
//! `nc-conform run SCENARIO.yaml [--format jsonl|vcd|timing] [--out FILE]` runs a scenario and
//! prints its verdicts, or writes its trace in the chosen format (see [`crate::cli_scenario`]).
//!
//! Exit status: 0 when the program ran to its end (end reason `program_end`), 1 when the run
//! ended any other way (an alarm, a reset, a stop, the time limit), 2 for errors in what was
//! given (command line, unreadable or unparsable program, bad parameter file, unwritable output),
//! 3 with `--check-determinism` when two runs wrote different traces.

use std::fs::File;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::builder::PossibleValuesParser;
use clap::{Args, Parser, Subcommand};
use nc_engine::trace::EndReason;
use nc_engine::{Machine, ParseError, RunOptions};

use crate::determinism::{self, Digest};
use crate::diag::{InputError, Span};
use crate::jsonl::JsonlWriter;
use crate::params_yaml;

/// Exit status: the program ran to its end.
pub const EXIT_OK: u8 = 0;
/// Exit status: the run stopped on an alarm or ended any other way than at the program end.
pub const EXIT_RUN_FAILED: u8 = 1;
/// Exit status: an error in the input (command line, program, parameter file) or the output.
pub const EXIT_INPUT: u8 = 2;

/// Conformance test and fault-injection harness for CNC tapping and threading cycles.
#[derive(Debug, Parser)]
#[command(name = "nc-conform", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run a G-code program on the reference engine and write its trace as JSON Lines.
    ///
    /// Exits 0 when the program runs to its end, 1 when the run stops on an alarm (or ends any
    /// other way), 2 for errors in the input: an unreadable file, a parse error in the program, a
    /// bad parameter file.
    Run(RunArgs),
    /// Run the property-based fault campaign (docs/invariants.md) for long, from fresh seeds,
    /// with a progress bar and a coverage summary; failures become regression scenarios.
    ///
    /// Exits 0 when every case kept every invariant, 1 when one did not, 2 for bad arguments.
    Campaign(crate::cli_campaign::CampaignArgs),
    /// Compare a trace recorded on a real control with the reference run of the same scenario
    /// or program (docs/checking.md): discrete events, key points, synchronisation error,
    /// position envelope and the scenario's temporal rules, within tolerances.
    ///
    /// Exits 0 when the trace conforms, 1 when it diverges (every divergence listed with rule
    /// id, time, expected, actual and margin), 2 for errors in the input.
    Check(crate::cli_check::CheckArgs),
    /// Run every scenario against a controller behind an adapter program (docs/adapter-protocol.md)
    /// and print a conformance summary per rule id.
    ///
    /// Exits 0 when every scenario run passed (skipped ones aside), 1 when one failed, 2 for errors
    /// in the input (command line, scenario files, an adapter that cannot be started).
    Conform(crate::cli_conform::ConformArgs),
    /// Estimate a machine's timing (axis rates and time constants, spindle ramp, PLC answer
    /// delays) from a recording of a known-good run; write a parameter file (docs/checking.md).
    Calibrate(crate::cli_check::CalibrateArgs),
    /// Serve the reference engine over the adapter protocol on stdin/stdout (for adapters that
    /// delegate to it, and for tests).
    #[command(hide = true)]
    Serve,
}

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

/// Entry point of the binary: parses the command line, runs, and returns the exit status.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Run(args) => ExitCode::from(run(&args)),
        Command::Campaign(args) => ExitCode::from(crate::cli_campaign::run(&args)),
        Command::Check(args) => ExitCode::from(crate::cli_check::run(&args)),
        Command::Conform(args) => ExitCode::from(crate::cli_conform::run(&args)),
        Command::Calibrate(args) => ExitCode::from(crate::cli_check::calibrate(&args)),
        Command::Serve => ExitCode::from(crate::cli_conform::serve()),
    }
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
    if crate::cli_scenario::is_scenario(&args.program) {
        return crate::cli_scenario::run(args);
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

/// A path as the user wrote it.
pub(crate) fn display_name(path: &Path) -> String {
    path.display().to_string()
}

/// Reads a text file (invalid UTF-8 is replaced, a leading byte-order mark dropped).
fn read_text(path: &Path) -> Result<String, InputError> {
    let bytes =
        std::fs::read(path).map_err(|e| InputError::new(display_name(path), format!("cannot read: {e}")))?;
    let text = String::from_utf8_lossy(&bytes);
    Ok(text.strip_prefix('\u{feff}').unwrap_or(&text).to_string())
}

/// A parse error of `text` (the file `name`) as an input error at its span.
pub fn parse_error(name: &str, text: &str, e: &ParseError) -> InputError {
    let span = Span::from_line_col(text, e.line, e.col, e.len.max(1));
    let expected = (!e.expected.is_empty()).then(|| e.expected.clone());
    InputError::at(name, text, span, e.message.clone(), expected)
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn command_line_is_well_formed() {
        Cli::command().debug_assert();
    }

    #[test]
    fn run_help_lists_every_flag_and_dialect() {
        let mut cmd = Cli::command();
        let run = cmd.find_subcommand_mut("run").expect("run subcommand");
        let help = run.render_long_help().to_string();
        for flag in
            ["--dialect", "--params", "--sample-us", "--out", "--format", "PROGRAM", "jsonl", "vcd", "timing"]
        {
            assert!(help.contains(flag), "{flag} missing from:\n{help}");
        }
        for d in nc_engine::dialect_names() {
            assert!(help.contains(d), "{d} missing from:\n{help}");
        }
    }

    #[test]
    fn parse_errors_keep_line_col_and_expected() {
        let text = "G98\n#1=5\n";
        let e = ParseError { line: 2, col: 1, len: 1, message: "macro".into(), expected: "a word".into() };
        let ie = parse_error("p.nc", text, &e);
        assert_eq!(ie.headline(), "p.nc:2:1: macro; expected a word");
        let (span, _) = ie.at.unwrap();
        assert_eq!(&text[span.offset..span.offset + span.len], "#");
    }
}
