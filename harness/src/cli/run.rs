//! `nc-conform run PROGRAM --dialect NAME [--params FILE.yaml] [--sample-us N] [--out FILE]`:
//! parses the program, runs it on the reference engine and streams the trace as JSON Lines. A
//! scenario file given as PROGRAM is handed to [`super::run_scenario`].

use std::fs::File;
use std::io::{self, Write};
use std::path::PathBuf;

use clap::builder::PossibleValuesParser;
use clap::Args;
use nc_engine::alarm::Alarm;
use nc_engine::trace::{EndReason, Event, TraceEvent, TraceMeta, TraceSink};
use nc_engine::{Machine, RunOptions};

use super::{display_name, parse_error, EXIT_INPUT, EXIT_OK, EXIT_RUN_FAILED};
use crate::determinism::{self, Digest};
use crate::diag::{self, InputError};
use crate::input;
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

    /// Stop the run after this many seconds of simulated machine time (end reason `time_limit`,
    /// exit 1). For a program; a scenario names its own (`options.time_limit_ms`).
    #[arg(long, value_name = "SECONDS", default_value_t = DEFAULT_TIME_LIMIT_S, value_parser = seconds)]
    pub time_limit: f64,

    /// Stop the run once its trace is this many MiB long (end reason `output_limit`, exit 1,
    /// a line on stderr); 0: no limit. A slow feed or a long dwell would otherwise write samples
    /// until the time limit (docs/input-limits.md).
    #[arg(long, value_name = "MIB", default_value_t = DEFAULT_MAX_OUTPUT_MIB)]
    pub max_output_mib: u64,
}

/// `--time-limit` by default: seven days of machine time, the engine's own default.
pub const DEFAULT_TIME_LIMIT_S: f64 = 604_800.0;

/// `--max-output-mib` by default: 1 GiB of trace, about 2.5 hours of machine time at the default
/// 1 ms samples.
pub const DEFAULT_MAX_OUTPUT_MIB: u64 = 1024;

/// A `--time-limit` value: seconds, above 0, at most 100 years, whole microseconds.
fn seconds(s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|_| format!("`{s}` is not a number of seconds"))?;
    if !(v > 0.0 && v <= 3.2e9) {
        return Err(format!("`{s}`: expected seconds above 0 and at most 3.2e9"));
    }
    Ok(v)
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
    let text = input::read_text(&args.program, input::PROGRAM)?;
    if let Some(path) = &args.params {
        let name = display_name(path);
        let yaml = input::read_text(path, input::YAML)?;
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
    let opts = RunOptions {
        sample_us: args.sample_us,
        time_limit_us: (args.time_limit * 1e6).round() as u64,
        ..RunOptions::default()
    };
    let budget = args.max_output_mib.checked_mul(1024 * 1024).filter(|b| *b > 0).unwrap_or(u64::MAX);
    let writer = FirstAlarm::new(
        JsonlWriter::new(Digest::new(Some(sink)).hashing(args.check_determinism)).with_budget(budget),
    );
    let mut writer = super::progress::Watched::new("run", writer);
    machine.run(&program, &opts, &mut writer);
    let writer = writer.done();
    let (writer, alarm) = (writer.inner, writer.alarm);
    let end = writer.end_reason().cloned();
    if let Some(why) = why_not_ended(end.as_ref(), alarm.as_ref(), &program_name, &text, args) {
        eprintln!("{why}");
    }
    let first = match writer.finish() {
        Ok(d) => d.summary(),
        // A reader that stopped early (`| head`) is not an error of the run.
        Err(e) if e.kind() == io::ErrorKind::BrokenPipe => return Ok(exit_of(end)),
        Err(e) => return Err(InputError::new(dest, format!("cannot write the trace: {e}"))),
    };
    if args.check_determinism {
        let mut again = JsonlWriter::new(Digest::<io::Sink>::new(None)).with_budget(budget);
        machine.run(&program, &opts, &mut again);
        let second = again.finish().map(|d| d.summary()).unwrap_or_default();
        if second != first {
            eprintln!("{program_name}: {}", determinism::report(first, second));
            return Ok(determinism::EXIT_NONDETERMINISTIC);
        }
    }
    Ok(exit_of(end))
}

/// A sink that passes every event on and keeps the first alarm.
struct FirstAlarm<S> {
    inner: S,
    alarm: Option<Alarm>,
}

impl<S: TraceSink> FirstAlarm<S> {
    fn new(inner: S) -> Self {
        FirstAlarm { inner, alarm: None }
    }
}

impl<S: TraceSink> TraceSink for FirstAlarm<S> {
    fn start(&mut self, meta: &TraceMeta) {
        self.inner.start(meta);
    }
    fn event(&mut self, ev: &TraceEvent) {
        if let (None, Event::Alarm(a)) = (&self.alarm, &ev.event) {
            self.alarm = Some(a.clone());
        }
        self.inner.event(ev);
    }
    fn wants_stop(&self) -> bool {
        self.inner.wants_stop()
    }
}

/// The one line on stderr that says why a run did not reach its program end (exit 1), or
/// `None` when it did. An alarm names its code, message and the program line that raised it.
fn why_not_ended(
    end: Option<&EndReason>,
    alarm: Option<&Alarm>,
    name: &str,
    text: &str,
    args: &RunArgs,
) -> Option<String> {
    let name = diag::printable(name, 200);
    Some(match end? {
        EndReason::ProgramEnd => return None,
        EndReason::Alarm => match alarm {
            Some(a) => {
                let at = a.line.map(|l| format!(":{l}")).unwrap_or_default();
                let block = a
                    .line
                    .and_then(|l| text.lines().nth((l as usize).saturating_sub(1)))
                    .map(|b| format!(" in `{}`", diag::printable(b.trim(), 120)))
                    .unwrap_or_default();
                let message = match a.detail.as_str() {
                    "" => a.kind.title().to_string(),
                    d => format!("{}: {}", a.kind.title(), diag::printable(d, 300)),
                };
                format!("{name}{at}: alarm {}: {message}{block}", a.kind.code())
            }
            None => format!("{name}: the run stopped on an alarm"),
        },
        EndReason::Reset => format!("{name}: the run ended on a reset"),
        EndReason::Stopped => {
            format!("{name}: the run stopped, held with nothing to restart it (M00/M01, feed hold or single block)")
        }
        EndReason::TimeLimit => format!(
            "{name}: the run reached its time limit of {} s of machine time before the program end (--time-limit)",
            args.time_limit
        ),
        EndReason::OutputLimit => format!(
            "{name}: the run was stopped when its trace reached {} MiB (--max-output-mib)",
            args.max_output_mib
        ),
    })
}

fn exit_of(end: Option<EndReason>) -> u8 {
    match end {
        Some(EndReason::ProgramEnd) => EXIT_OK,
        _ => EXIT_RUN_FAILED,
    }
}
