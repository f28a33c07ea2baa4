//! The `nc-conform` command line.
//!
//! `nc-conform run PROGRAM --dialect NAME [--params FILE.yaml] [--sample-us N] [--out FILE]`
//! parses the program, runs it on the reference engine and streams the trace as JSON Lines.
//! `nc-conform run SCENARIO.yaml [--format jsonl|vcd|timing] [--out FILE]` runs a scenario and
//! prints its verdicts, or writes its trace in the chosen format (see [`run_scenario`]).
//!
//! Exit status: 0 when the program ran to its end (end reason `program_end`), 1 when the run
//! ended any other way (an alarm, a reset, a stop, the time limit), 2 for errors in what was
//! given (command line, unreadable or unparsable program, bad parameter file, unwritable output),
//! 3 with `--check-determinism` when two runs wrote different traces.

//!
//! One file per subcommand: [`run`] (a program) and [`run_scenario`] (a scenario) for `run`,
//! [`campaign`], [`check`], [`conform`] (with the hidden `serve`). Only this module and its
//! children know the command line; the library modules they call never import it.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

pub mod campaign;
pub mod check;
pub mod conform;
pub mod fuzz_files;
pub mod params;
pub mod progress;
pub mod run;
pub mod run_scenario;

pub use crate::diag::parse_error;
pub(crate) use crate::input::display_name;
pub use run::RunArgs;

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
    Campaign(campaign::CampaignArgs),
    /// Compare a trace recorded on a real control with the reference run of the same scenario
    /// or program (docs/checking.md): discrete events, key points, synchronisation error,
    /// position envelope and the scenario's temporal rules, within tolerances.
    ///
    /// Exits 0 when the trace conforms, 1 when it diverges (every divergence listed with rule
    /// id, time, expected, actual and margin), 2 for errors in the input.
    Check(check::CheckArgs),
    /// Run every scenario against a controller behind an adapter program (docs/adapter-protocol.md)
    /// and print a conformance summary per rule id.
    ///
    /// Exits 0 when every scenario run passed (skipped ones aside), 1 when one failed, 2 for errors
    /// in the input (command line, scenario files, an adapter that cannot be started).
    Conform(conform::ConformArgs),
    /// Estimate a machine's timing (axis rates and time constants, spindle ramp, PLC answer
    /// delays) from a recording of a known-good run; write a parameter file (docs/checking.md).
    Calibrate(check::CalibrateArgs),
    /// Write the linuxcnc dialect's parameters from a LinuxCNC machine's INI file
    /// (`--from-ini MACHINE.ini`), naming what could not be mapped.
    ///
    /// Exits 0 when the file was written, 2 for errors in the input.
    Params(params::ParamsArgs),
    /// Serve the reference engine over the adapter protocol on stdin/stdout (for adapters that
    /// delegate to it, and for tests).
    #[command(hide = true)]
    Serve,
}

/// Writes a report or generated file the user named; a failure is an input error naming it.
pub(crate) fn write_file(path: &std::path::Path, body: &str) -> Result<(), crate::diag::InputError> {
    std::fs::write(path, body)
        .map_err(|e| crate::diag::InputError::new(display_name(path), format!("cannot write: {e}")))
}

/// Writes `body` to `out` when given, else to standard output.
pub(crate) fn write_or_print(
    out: Option<&std::path::Path>,
    body: &str,
) -> Result<(), crate::diag::InputError> {
    match out {
        Some(p) => write_file(p, body),
        None => {
            print!("{body}");
            Ok(())
        }
    }
}

/// Entry point of the binary: parses the command line, runs, and returns the exit status.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Run(args) => ExitCode::from(run::run(&args)),
        Command::Campaign(args) => ExitCode::from(campaign::run(&args)),
        Command::Check(args) => ExitCode::from(check::run(&args)),
        Command::Conform(args) => ExitCode::from(conform::run(&args)),
        Command::Calibrate(args) => ExitCode::from(check::calibrate(&args)),
        Command::Params(args) => ExitCode::from(params::run(&args)),
        Command::Serve => ExitCode::from(conform::serve()),
    }
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
}
