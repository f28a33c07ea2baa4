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
use nc_engine::trace::{EndReason, Event, TraceEvent, TraceMeta, TraceSink};
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
    /// any signal `NAME[:0|1]` or function `M.../S.../T...`, `motion` (the first motion of the
    /// tap axis, else of the first axis to move), `spindle` (the first spindle start).
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

    /// Where the reference's spindle stands when its run starts, degrees after its index, or
    /// `recorded` (the default): the angle of the recording's first sample, when it records
    /// one, so that the waits for the index (G33, G76, G33.1, thread passes) agree.
    #[arg(long, value_name = "DEG|recorded", default_value = "recorded", value_parser = parse_spindle_angle)]
    pub spindle_angle: SpindleAngle,
}

/// `--spindle-angle`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SpindleAngle {
    /// The recording's first angle (0 when it records none).
    Recorded,
    /// This angle, degrees.
    Deg(f64),
}

fn parse_spindle_angle(s: &str) -> Result<SpindleAngle, String> {
    if s == "recorded" {
        return Ok(SpindleAngle::Recorded);
    }
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v.abs() <= 360.0 => Ok(SpindleAngle::Deg(v)),
        _ => Err(format!("`{s}` is not `recorded` or an angle in degrees within ±360")),
    }
}

/// The spindle angle of the first sample of `trace`, degrees, when it records one (read no
/// further than its first `MAX_PEEK` events).
fn first_recorded_angle(trace: &std::path::Path, opts: &import::Options) -> Option<f64> {
    const MAX_PEEK: usize = 10_000;
    let importer = import::open(trace, opts).ok()?;
    if !check::Carried::of(importer.meta()).angle {
        return None;
    }
    importer.take(MAX_PEEK).map_while(Result::ok).find_map(|e| match e.event {
        Event::Sample(s) => Some(s.spindle_mdeg as f64 / 1000.0),
        _ => None,
    })
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

/// The most discrete events (every event but the samples) of a reference run.
const MAX_REFERENCE_EVENTS: usize = 1_000_000;

/// The most samples of a reference run (10 hours at 1 ms): a program that never ends
/// (a slow feed) is refused, not replayed for days.
const MAX_REFERENCE_SAMPLES: usize = 36_000_000;

/// A sink passing a run on that stops it at [`MAX_REFERENCE_EVENTS`] discrete events or
/// [`MAX_REFERENCE_SAMPLES`] samples (the same place in every replay).
struct Capped<'s> {
    inner: &'s mut dyn TraceSink,
    discrete: usize,
    samples: usize,
}

impl TraceSink for Capped<'_> {
    fn start(&mut self, meta: &TraceMeta) {
        self.inner.start(meta);
    }
    fn event(&mut self, ev: &TraceEvent) {
        if matches!(ev.event, Event::Sample(_)) {
            self.samples += 1;
        } else {
            self.discrete += 1;
        }
        self.inner.event(ev);
    }
    fn wants_stop(&self) -> bool {
        self.discrete >= MAX_REFERENCE_EVENTS
            || self.samples >= MAX_REFERENCE_SAMPLES
            || self.inner.wants_stop()
    }
}

fn run_inner(args: &CheckArgs) -> Result<u8, InputError> {
    let input_name = display_name(&args.input);
    // The reference run.
    let (title, machine, program, run_opts, expect, rules, tol_default) =
        if run_scenario::is_scenario(&args.input) {
            if args.dialect.is_some() || args.params.is_some() {
                return Err(InputError::new(
                    "--dialect/--params",
                    "a scenario names its own dialect and parameters",
                ));
            }
            let s = load::load(&args.input, &input_name)?;
            let side = args.input.with_extension("check.yaml");
            let tol = if side.is_file() { Some(side) } else { None };
            (format!("{} — {}", s.name, s.title), s.machine, s.program, s.opts, Some(s.expect), s.rules, tol)
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
            (
                format!("{input_name} ({dialect}, default inputs)"),
                machine,
                program,
                RunOptions::default(),
                None,
                Vec::new(),
                None,
            )
        };
    // The recorded stream's format and map.
    let map = match &args.map {
        Some(p) => Some(ColumnMap::load(p)?),
        None => None,
    };
    let opts = import::Options {
        format: args.format.as_deref().and_then(Format::from_name),
        map: map.as_ref(),
        lenient: args.lenient,
    };
    // The reference's spindle starts where the recorded one stood.
    let mut run_opts = run_opts;
    let spindle_start = match args.spindle_angle {
        SpindleAngle::Deg(d) => Some(d),
        SpindleAngle::Recorded => first_recorded_angle(&args.trace, &opts),
    };
    run_opts.spindle_angle_deg = spindle_start.unwrap_or(0.0);
    // The reference run, replayed as the comparison needs it (never held whole).
    let run = |sink: &mut dyn TraceSink| {
        machine.run(&program, &run_opts, &mut Capped { inner: sink, discrete: 0, samples: 0 });
    };
    let source = check::Source::Run(&run);
    // Without temporal rules the phases, blocks and inputs are not kept (memory).
    let skeleton = check::survey::Skeleton::of_lean(source, expect.is_none());
    if skeleton.end().is_some_and(|e| e.reason == EndReason::OutputLimit) {
        let secs = skeleton.end_us as f64 / 1e6;
        let mut e = InputError::new(
            &input_name,
            format!(
                "the reference run of the program did not end within {MAX_REFERENCE_EVENTS} trace events and {MAX_REFERENCE_SAMPLES} samples ({secs} s of machine time)"
            ),
        );
        e.expected = Some("a program that ends (check compares whole runs)".into());
        return Err(e);
    }
    let tolerances = match args.tolerances.as_ref().or(tol_default.as_ref()) {
        Some(p) => load_tolerances(p)?,
        None => Tolerances::default(),
    };
    let anchor = match (&args.anchor, args.offset_us) {
        (_, Some(o)) => Some(Anchor::Offset(o)),
        (Some(a), None) => Some(Anchor::parse(a).ok_or_else(|| {
            let mut e = InputError::new("--anchor", format!("unknown anchor `{a}`"));
            e.expected = Some(
                "M29, STL, a signal NAME[:0|1], a function M../S../T.., motion, spindle, offset:N".into(),
            );
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
    let importer = import::open(&args.trace, &opts).map_err(|e| import_error(&e))?;
    // A JSON Lines trace names its dialect: one other than the reference's is a mistake in the
    // command line, not 25 divergences.
    if let Some(recorded) = importer.meta().trace.as_ref().map(|m| m.dialect) {
        if recorded != machine.dialect.name() {
            let mut e = InputError::new(
                display_name(&args.trace),
                format!(
                    "the trace was recorded with dialect {} (its meta line), the reference runs {}",
                    crate::diag::printable(recorded, 40),
                    machine.dialect.name()
                ),
            );
            e.expected =
                Some(format!("a trace of dialect {} (or --dialect {recorded})", machine.dialect.name()));
            return Err(e);
        }
    }
    let carried = check::Carried::of(importer.meta());
    // Parsed on a thread of its own, a few batches ahead: the comparison runs on this one.
    let mut importer = importer.read_ahead();
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
    // A bar up to the reference's end (the recording's times are close to the reference's).
    let mut progress = super::progress::Progress::new("check").with_total(skeleton.end_us.max(0) as u64);
    let mut rep = check::check_surveyed(
        source,
        skeleton,
        stream.inspect(|e: &TraceEvent| progress.tick(e.t_us)),
        &spec,
    );
    progress.done();
    if let Some(e) = failure {
        return Err(import_error(&e));
    }
    // The reports show the samples around the divergences (and the HTML page one per bucket of
    // the whole run): the reference is replayed and, when the compact copy could not keep every
    // sample, the recording read again for them.
    let windows = check::excerpt::windows(&rep);
    let bucket = (rep.reference.events.last().map_or(0, |e| e.t_us as i64) / 1500).max(1000);
    let reference = if windows.is_empty() && args.html.is_none() {
        let meta = rep.reference.meta.clone();
        std::mem::replace(&mut rep.reference, nc_engine::trace::Trace { meta, events: Vec::new() })
    } else {
        check::excerpt::reference(source, &windows, if args.html.is_some() { bucket } else { i64::MAX })
    };
    let samples = rep.recorded.events.iter().filter(|e| matches!(e.event, Event::Sample(_))).count();
    let full = samples >= check::compare::MAX_COMPACT_SAMPLES
        || rep.recorded.events.len() - samples >= check::compare::MAX_COMPACT_EVENTS;
    if !windows.is_empty() && full {
        if let Ok(again) = import::open(&args.trace, &opts) {
            check::excerpt::fill_recorded(&mut rep, &windows, again.map_while(Result::ok));
        }
    }
    let warnings = importer.finish().warnings().total();
    let trace_name = display_name(&args.trace);
    let mut head = format!("{title}\nrecorded: {trace_name}");
    match (args.spindle_angle, spindle_start) {
        (SpindleAngle::Recorded, Some(a)) => {
            head.push_str(&format!("\nreference spindle: starts at {a:.3}° (the recording's first sample)"))
        }
        (SpindleAngle::Deg(a), _) => {
            head.push_str(&format!("\nreference spindle: starts at {a:.3}° (--spindle-angle)"))
        }
        (SpindleAngle::Recorded, None) => {}
    }
    let mut text = report::summary(&rep, &reference, &head);
    if warnings > 0 {
        text.push_str(&format!("warning: {warnings} faulty row(s) of {trace_name} left out (--lenient)\n"));
    }
    print!("{}", crate::diag::printable_lines(&text));
    let write = |p: &PathBuf, body: String| super::write_file(p, &body);
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

/// `nc-conform calibrate`: estimate a machine's timing from a recording of a known-good run.
#[derive(Debug, clap::Args)]
pub struct CalibrateArgs {
    /// The G-code program the recording ran.
    #[arg(value_name = "PROGRAM")]
    pub input: PathBuf,

    /// The recorded trace of a known-good run: JSON Lines, CSV (with --map), VCD or SHDR.
    #[arg(long, value_name = "FILE")]
    pub trace: PathBuf,

    /// The dialect of the program.
    #[arg(long, value_name = "DIALECT", value_parser = PossibleValuesParser::new(nc_engine::dialect_names()))]
    pub dialect: String,

    /// Base parameters (kept where nothing is estimated).
    #[arg(long, value_name = "FILE.yaml")]
    pub params: Option<PathBuf>,

    /// Column map of a CSV recording (or of SHDR keys).
    #[arg(long, value_name = "MAP.yaml")]
    pub map: Option<PathBuf>,

    /// The recording's format when the first bytes do not tell it.
    #[arg(long, value_name = "FORMAT")]
    pub format: Option<String>,

    /// Leave out faulty rows instead of stopping.
    #[arg(long)]
    pub lenient: bool,

    /// Write the parameter file here instead of standard output.
    #[arg(long, value_name = "FILE.yaml")]
    pub out: Option<PathBuf>,
}

/// Carries out `nc-conform calibrate`; returns the exit status (0, or 2 for an input error).
pub fn calibrate(args: &CalibrateArgs) -> u8 {
    let inner = || -> Result<(), InputError> {
        let input_name = display_name(&args.input);
        let mut machine = Machine::new(&args.dialect)
            .ok_or_else(|| InputError::new("--dialect", format!("unknown dialect `{}`", args.dialect)))?;
        if let Some(p) = &args.params {
            let yaml = input::read_utf8(p, input::YAML)?;
            params_yaml::apply(&yaml, &mut machine)
                .map_err(|e| InputError::at(display_name(p), &yaml, e.span, e.message, e.expected))?;
        }
        let text = input::read_text(&args.input, input::PROGRAM)?;
        machine.parse(&text).map_err(|e| parse_error(&input_name, &text, &e))?;
        let map = match &args.map {
            Some(p) => Some(ColumnMap::load(p)?),
            None => None,
        };
        let opts = import::Options {
            format: args.format.as_deref().and_then(Format::from_name),
            map: map.as_ref(),
            lenient: args.lenient,
        };
        // One pass over the recording, as it streams (memory does not follow its length).
        let importer = import::open(&args.trace, &opts).map_err(|e| import_error(&e))?;
        let axes = importer.meta().axes.clone();
        let mut cal = check::calibrate::Calibrator::new(&machine, &axes);
        for e in importer {
            cal.event(&e.map_err(|e| import_error(&e))?);
        }
        let est = cal.finish();
        let file = check::calibrate::params_file(&machine, &est, &display_name(&args.trace));
        super::write_or_print(args.out.as_deref(), &file)
    };
    match inner() {
        Ok(()) => EXIT_OK,
        Err(e) => {
            e.report();
            EXIT_INPUT
        }
    }
}
