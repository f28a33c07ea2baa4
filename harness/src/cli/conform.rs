//! `nc-conform conform --adapter "CMD ARGS" [--scenarios DIR] [--filter TEXT] [--junit FILE]
//! [--report FILE.json] [--timeout-ms N] [--tolerances FILE.yaml] [--params FILE.yaml]`: every scenario against a controller behind an adapter
//! program (`docs/adapter-protocol.md`), a summary per rule id (passed, failed, which scenarios).
//! `nc-conform serve` (hidden) is the reference engine behind the same protocol.
//!
//! Exit status: 0 every scenario run passed, 1 any failed, 2 input error (command line, a bad
//! scenario file, no scenario found, an adapter that cannot be started or greeted, an unwritable
//! report).

use std::path::{Path, PathBuf};
use std::time::Duration;

use clap::Args;

use super::{display_name, EXIT_INPUT, EXIT_OK, EXIT_RUN_FAILED};
use crate::conform::process::{split_command, ProcessController};
use crate::conform::suite::{run_one_on, scenario_files, MachineSetup, SuiteReport};
use crate::conform::verdict::Status;
use crate::conform::Controller;
use crate::diag::InputError;
use crate::scenario::load::MachineParams;

/// Arguments of `nc-conform conform`.
#[derive(Debug, Args)]
pub struct ConformArgs {
    /// The adapter program and its arguments, as one string (`"python3 adapter.py --port 3"`).
    #[arg(long, value_name = "CMD ARGS")]
    pub adapter: String,

    /// The scenario directory (searched recursively for .yaml/.yml files).
    #[arg(long, value_name = "DIR", default_value = "scenarios")]
    pub scenarios: PathBuf,

    /// Run only the scenarios whose path contains this text (repeatable: any of them).
    #[arg(long, value_name = "TEXT")]
    pub filter: Vec<String>,

    /// Most time the adapter may take to answer one message, ms.
    #[arg(long, value_name = "N", default_value_t = 10_000)]
    pub timeout_ms: u64,

    /// Most time one scenario may take against the adapter, ms (from its `load`): past it the
    /// scenario fails and the adapter is restarted for the next one.
    #[arg(long, value_name = "N", default_value_t = 600_000)]
    pub scenario_timeout_ms: u64,

    /// The machine's tolerances (the `check --tolerances` file format, docs/checking.md) for
    /// every scenario without a `.check.yaml` of its own, instead of the defaults: a real
    /// controller's task and PLC cycles are not the reference's.
    #[arg(long, value_name = "FILE.yaml")]
    pub tolerances: Option<PathBuf>,

    /// The machine's parameters (a parameter file, docs/parameters-format.md; for LinuxCNC the
    /// output of `nc-conform params --from-ini MACHINE.ini`) under every scenario's own: the
    /// reference runs each scenario on them and the controller is sent them in `load`. A file
    /// naming a `dialect:` applies to that dialect's scenarios only. Repeatable: a later file
    /// over an earlier (a machine's file, then a site's or a controller version's).
    #[arg(long, value_name = "FILE.yaml")]
    pub params: Vec<PathBuf>,

    /// Write the verdicts as JUnit XML (one test case per scenario).
    #[arg(long, value_name = "FILE.xml")]
    pub junit: Option<PathBuf>,

    /// Write the verdicts and the summary per rule id as JSON.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
}

/// Carries out `nc-conform conform`; returns the exit status.
pub fn run(args: &ConformArgs) -> u8 {
    match run_inner(args) {
        Ok(code) => code,
        Err(e) => {
            e.report();
            EXIT_INPUT
        }
    }
}

fn run_inner(args: &ConformArgs) -> Result<u8, InputError> {
    let argv = split_command(&args.adapter).map_err(|e| InputError::new("--adapter", e))?;
    if !args.scenarios.is_dir() {
        return Err(InputError::new(display_name(&args.scenarios), "not a directory of scenarios"));
    }
    let base = args.scenarios.parent().unwrap_or(Path::new("")).to_path_buf();
    let files: Vec<(PathBuf, String)> = scenario_files(&args.scenarios)
        .into_iter()
        .map(|p| {
            let name = p.strip_prefix(&base).unwrap_or(&p).to_string_lossy().replace('\\', "/");
            (p, name)
        })
        .filter(|(_, n)| args.filter.is_empty() || args.filter.iter().any(|f| n.contains(f.as_str())))
        .collect();
    if files.is_empty() {
        let mut e = InputError::new(display_name(&args.scenarios), "no scenario file matches");
        e.expected = Some(".yaml files under the directory (and a --filter that matches some)".into());
        return Err(e);
    }
    let machine = MachineSetup {
        tolerances: match &args.tolerances {
            Some(p) => crate::input::load_tolerances(p)?,
            None => crate::check::Tolerances::default(),
        },
        params: args.params.iter().map(|p| MachineParams::read(p)).collect::<Result<_, _>>()?,
    };
    let mut ctl = ProcessController::new(argv, Duration::from_millis(args.timeout_ms.max(1)))
        .with_scenario_limit(Duration::from_millis(args.scenario_timeout_ms.max(1)));
    let id = ctl
        .identity()
        .map_err(|e| InputError::new("--adapter", format!("the adapter cannot be greeted: {e}")))?;
    println!("{} {} (dialects: {})", id.name, id.version, id.dialects.join(", "));
    for p in &machine.params {
        let of = p.file.dialect.as_ref().map_or("every dialect".to_string(), |(d, _)| format!("dialect {d}"));
        println!(
            "machine parameters: {} ({} values, for {of}), under each scenario's own",
            p.name,
            p.file.settings.len()
        );
    }
    let mut report = SuiteReport::new(&id);
    for (path, name) in &files {
        let v = run_one_on(&mut ctl, &id.dialects, path, name, &machine)?;
        let tag = match v.status {
            Status::Passed => "ok  ",
            Status::Failed => "FAIL",
            Status::Skipped(_) => "skip",
        };
        println!("{tag} {name}");
        report.scenarios.push(v);
    }
    print!("\n{}", crate::diag::printable_lines(&report.summary()));
    let write = |p: &PathBuf, body: String| super::write_file(p, &body);
    if let Some(p) = &args.junit {
        write(p, report.junit())?;
    }
    if let Some(p) = &args.report {
        write(p, report.json())?;
    }
    Ok(if report.counts().1 == 0 { EXIT_OK } else { EXIT_RUN_FAILED })
}

/// Carries out `nc-conform serve`: the reference engine behind the adapter protocol on
/// stdin/stdout.
pub fn serve() -> u8 {
    let mut ctl = crate::conform::reference::Reference::new();
    let stdin = std::io::stdin();
    match crate::conform::serve::serve(&mut ctl, stdin.lock(), std::io::stdout().lock()) {
        Ok(()) => EXIT_OK,
        Err(e) => {
            eprintln!("nc-conform serve: {e}");
            EXIT_INPUT
        }
    }
}
