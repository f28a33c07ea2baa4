//! `nc-conform check (SCENARIO.yaml | PROGRAM --dialect D) --trace FILE`: runs the reference and
//! compares a recorded controller trace with it (`docs/checking.md`). The recorded file is
//! read by [`crate::import`] as a stream; the verdict goes to standard output (a summary with a
//! timing diagram around the first divergence), the reports to `--report` (JSON), `--junit`
//! (JUnit XML) and `--html` (a self-contained page).
//!
//! Exit status: 0 conformant, 1 divergent, 2 input error (command line, scenario, program,
//! parameters, the recorded file, a map or tolerance file, an unwritable report).

use std::path::PathBuf;

use clap::builder::PossibleValuesParser;
use clap::Args;
use nc_engine::trace::{EndReason, Event, TraceEvent, TraceMeta, TraceSink, VecSink};
use nc_engine::{Machine, RunOptions};

use super::{display_name, parse_error, run_scenario, EXIT_INPUT, EXIT_OK, EXIT_RUN_FAILED};
use crate::check::{self, report, Anchor, CheckSpec, Tolerances};
use crate::diag::InputError;
use crate::import::{self, ColumnMap, Format, ImportError};
use crate::input::{self, load_tolerances};
use crate::{params_yaml, scenario::load};

/// Arguments of `nc-conform check`.
#[derive(Debug, Args)]
pub struct CheckArgs {
    /// The scenario file (`.yaml`/`.yml`) or G-code program the trace was recorded running.
    #[arg(value_name = "SCENARIO.yaml|PROGRAM")]
    pub input: PathBuf,

    /// The recorded trace: JSON Lines, CSV (with --map), VCD or MTConnect SHDR.
    #[arg(long, value_name = "FILE")]
    pub trace: PathBuf,

    /// The dialect of a bare program (a scenario names its own).
    #[arg(long, value_name = "DIALECT", value_parser = PossibleValuesParser::new(nc_engine::dialect_names()))]
    pub dialect: Option<String>,

    /// Machine parameters of a bare program (docs/parameters-format.md).
    #[arg(long, value_name = "FILE.yaml")]
    pub params: Option<PathBuf>,

    /// The column map of a CSV (or SHDR) trace (docs/checking.md).
    #[arg(long, value_name = "MAP.yaml")]
    pub map: Option<PathBuf>,

    /// The recorded trace's format, when detection from its first bytes is not enough.
    #[arg(long, value_name = "FORMAT", value_parser = ["jsonl", "csv", "vcd", "shdr"])]
    pub format: Option<String>,

    /// Leave out faulty rows of the recorded file (counted and reported) instead of stopping.
    #[arg(long)]
    pub lenient: bool,

    /// The event both time bases are tied at: `M29` (default), `STL` (the first cycle start),
    /// any signal `NAME[:0|1]` or function `M.../S.../T...`.
    #[arg(long, value_name = "EVENT", conflicts_with = "offset_us")]
    pub anchor: Option<String>,

    /// An explicit alignment instead of an anchor: reference time = recorded time + N µs.
    #[arg(long, value_name = "N", allow_hyphen_values = true,
          value_parser = clap::value_parser!(i64).range(-MAX_OFFSET_US..=MAX_OFFSET_US))]
    pub offset_us: Option<i64>,

    /// Tolerances (YAML, docs/checking.md); default: `SCENARIO.check.yaml` next to the scenario
    /// when it exists, else the defaults.
    #[arg(long, value_name = "TOL.yaml")]
    pub tolerances: Option<PathBuf>,

    /// Write the report as JSON.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,

    /// Write the report as JUnit XML.
    #[arg(long, value_name = "FILE.xml")]
    pub junit: Option<PathBuf>,

    /// Write the report as a self-contained HTML page with plots.
    #[arg(long, value_name = "FILE.html")]
    pub html: Option<PathBuf>,
}

/// Carries out `nc-conform check`; returns the exit status (errors are reported on stderr).
pub fn run(args: &CheckArgs) -> u8 {
    match run_inner(args) {
        Ok(code) => code,
        Err(e) => {
            e.report();
            EXIT_INPUT
        }
    }
}

fn import_error(e: &ImportError) -> InputError {
    let mut ie = InputError::new(e.location(), e.message.clone());
    ie.expected = e.expected.clone();
    ie
}

/// The largest alignment offset, µs (about 31 years): beyond it times overflow.
const MAX_OFFSET_US: i64 = 1_000_000_000_000_000;

/// The most recorded events other than samples a comparison keeps.
const MAX_RECORDED_EVENTS: usize = 1_000_000;

/// The most events of a program's reference run held in memory.
const MAX_REFERENCE_EVENTS: usize = 1_000_000;

/// A sink keeping the whole trace, that stops the run at `cap` events.
struct Capped {
    inner: VecSink,
    cap: usize,
}

impl TraceSink for Capped {
    fn start(&mut self, meta: &TraceMeta) {
        self.inner.start(meta);
    }
    fn event(&mut self, ev: &TraceEvent) {
        self.inner.event(ev);
    }
    fn wants_stop(&self) -> bool {
        self.inner.events.len() >= self.cap
    }
}

fn run_inner(args: &CheckArgs) -> Result<u8, InputError> {
    let input_name = display_name(&args.input);
    // The reference run.
    let (title, reference, expect, rules, tol_default) = if run_scenario::is_scenario(&args.input) {
        if args.dialect.is_some() || args.params.is_some() {
            return Err(InputError::new(
                "--dialect/--params",
                "a scenario names its own dialect and parameters",
            ));
        }
        let s = load::load(&args.input, &input_name)?;
        let side = args.input.with_extension("check.yaml");
        let tol = if side.is_file() { Some(side) } else { None };
        let trace = s.machine.run_to_trace(&s.program, &s.opts);
        (format!("{} — {}", s.name, s.title), trace, Some(s.expect), s.rules, tol)
    } else {
        let Some(dialect) = &args.dialect else {
            let mut e = InputError::new("--dialect", "a program needs --dialect");
            e.expected = Some(format!("one of: {}", nc_engine::dialect_names().join(", ")));
            return Err(e);
        };
        let mut machine = Machine::new(dialect)
            .ok_or_else(|| InputError::new("--dialect", format!("unknown dialect `{dialect}`")))?;
        if let Some(p) = &args.params {
            let yaml = input::read_utf8(p, input::YAML)?;
            params_yaml::apply(&yaml, &mut machine)
                .map_err(|e| InputError::at(display_name(p), &yaml, e.span, e.message, e.expected))?;
        }
        let text = input::read_text(&args.input, input::PROGRAM)?;
        let program = machine.parse(&text).map_err(|e| parse_error(&input_name, &text, &e))?;
        // Held in memory: at most MAX_REFERENCE_EVENTS events (a slow feed would otherwise fill
        // the memory with seven days of samples).
        let mut sink = Capped { inner: VecSink::default(), cap: MAX_REFERENCE_EVENTS };
        machine.run(&program, &RunOptions::default(), &mut sink);
        let trace = sink.inner.into_trace();
        if trace.end().is_some_and(|e| e.reason == EndReason::OutputLimit) {
            let secs = trace.events.last().map_or(0, |e| e.t_us) as f64 / 1e6;
            let mut e = InputError::new(
                &input_name,
                format!(
                    "the reference run of the program did not end within {MAX_REFERENCE_EVENTS} trace events ({secs} s of machine time)"
                ),
            );
            e.expected = Some("a program that ends (check compares whole runs)".into());
            return Err(e);
        }
        (format!("{input_name} ({dialect}, default inputs)"), trace, None, Vec::new(), None)
    };
    let tolerances = match args.tolerances.as_ref().or(tol_default.as_ref()) {
        Some(p) => load_tolerances(p)?,
        None => Tolerances::default(),
    };
    let anchor = match (&args.anchor, args.offset_us) {
        (_, Some(o)) => Some(Anchor::Offset(o)),
        (Some(a), None) => Some(Anchor::parse(a).ok_or_else(|| {
            let mut e = InputError::new("--anchor", format!("unknown anchor `{a}`"));
            e.expected = Some("M29, STL, a signal NAME[:0|1], a function M../S../T.., offset:N".into());
            e
        })?),
        (None, None) => None,
    };
    if let Some(Anchor::Offset(o)) = anchor {
        if o.unsigned_abs() > MAX_OFFSET_US.unsigned_abs() {
            let mut e = InputError::new("--anchor", format!("offset {o} µs is out of range"));
            e.expected = Some(format!("an offset of at most ±{MAX_OFFSET_US} µs"));
            return Err(e);
        }
    }
    // The recorded stream.
    let map = match &args.map {
        Some(p) => Some(ColumnMap::load(p)?),
        None => None,
    };
    let opts = import::Options {
        format: args.format.as_deref().and_then(Format::from_name),
        map: map.as_ref(),
        lenient: args.lenient,
    };
    let mut importer = import::open(&args.trace, &opts).map_err(|e| import_error(&e))?;
    // A JSON Lines trace names its dialect: one other than the reference's is a mistake in the
    // command line, not 25 divergences.
    if let Some(recorded) = importer.meta().trace.as_ref().map(|m| m.dialect) {
        if recorded != reference.meta.dialect {
            let mut e = InputError::new(
                display_name(&args.trace),
                format!(
                    "the trace was recorded with dialect {} (its meta line), the reference runs {}",
                    crate::diag::printable(recorded, 40),
                    reference.meta.dialect
                ),
            );
            e.expected =
                Some(format!("a trace of dialect {} (or --dialect {recorded})", reference.meta.dialect));
            return Err(e);
        }
    }
    let carried = check::Carried::of(importer.meta());
    let mut failure: Option<ImportError> = None;
    // The comparison keeps the recorded events other than samples: at most
    // MAX_RECORDED_EVENTS of them (docs/input-limits.md).
    let mut discrete = 0usize;
    let trace_name = display_name(&args.trace);
    let stream = std::iter::from_fn(|| match importer.next()? {
        Ok(ev) => {
            if !matches!(ev.event, Event::Sample(_)) {
                discrete += 1;
                if discrete > MAX_RECORDED_EVENTS {
                    failure = Some(ImportError::new(
                        import::ErrorKind::Io,
                        &trace_name,
                        0,
                        0,
                        format!(
                            "more than {MAX_RECORDED_EVENTS} recorded events other than samples (at {} s), more than check holds",
                            ev.t_us as f64 / 1e6
                        ),
                    ));
                    return None;
                }
            }
            Some(ev)
        }
        Err(e) => {
            failure = Some(e);
            None
        }
    });
    let spec = CheckSpec { tolerances, anchor, expect: expect.as_ref(), rules, carried };
    let rep = check::check(&reference, stream.map(|e: TraceEvent| e), &spec);
    if let Some(e) = failure {
        return Err(import_error(&e));
    }
    let warnings = importer.warnings().total();
    let trace_name = display_name(&args.trace);
    let head = format!("{title}\nrecorded: {trace_name}");
    let mut text = report::summary(&rep, &reference, &head);
    if warnings > 0 {
        text.push_str(&format!("warning: {warnings} faulty row(s) of {trace_name} left out (--lenient)\n"));
    }
    print!("{}", crate::diag::printable_lines(&text));
    let write = |p: &PathBuf, body: String| {
        std::fs::write(p, body).map_err(|e| InputError::new(display_name(p), format!("cannot write: {e}")))
    };
    if let Some(p) = &args.report {
        write(p, report::json(&rep, &input_name, &trace_name))?;
    }
    if let Some(p) = &args.junit {
        write(p, report::junit(&rep, &input_name))?;
    }
    if let Some(p) = &args.html {
        write(p, check::html::page(&rep, &reference, &head))?;
    }
    Ok(if rep.conformant() { EXIT_OK } else { EXIT_RUN_FAILED })
}
