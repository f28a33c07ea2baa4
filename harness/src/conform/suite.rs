//! Every scenario of a directory against one controller: the run of one scenario (with its
//! reference run and tolerances), the summary per rule id, the JUnit XML and JSON reports, and
//! the libtest-mimic entry behind [`crate::conformance_suite!`].

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::drive;
use super::verdict::{judge, ScenarioVerdict, Status};
use super::{Controller, Identity};
use crate::check::report::xml_escape;
use crate::check::Tolerances;
use crate::diag::InputError;
use crate::scenario::load;

/// The scenario files under `dir` (`.yaml`/`.yml`, recursively, sorted by path).
/// Each directory is entered once, however many links lead to it (a symbolic link to `.` made
/// the walk endless).
pub fn scenario_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut seen = std::collections::HashSet::new();
    collect(dir, &mut out, &mut seen);
    out
}

fn collect(dir: &Path, out: &mut Vec<PathBuf>, seen: &mut std::collections::HashSet<PathBuf>) {
    if !std::fs::canonicalize(dir).is_ok_and(|c| seen.insert(c)) {
        return;
    }
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    let mut entries: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            collect(&p, out, seen);
        } else if p.is_file() && p.extension().is_some_and(|e| e == "yaml" || e == "yml") {
            out.push(p);
        }
    }
}

/// Runs one scenario file on `ctl` and judges it. `dialects`: what the controller runs (a
/// scenario of another dialect is skipped without asking it).
///
/// # Errors
///
/// The scenario file (or its tolerance file) is bad: an input error, not a verdict.
pub fn run_one(
    ctl: &mut dyn Controller,
    dialects: &[String],
    path: &Path,
    name: &str,
) -> Result<ScenarioVerdict, InputError> {
    run_one_within(ctl, dialects, path, name, &Tolerances::default())
}

/// [`run_one`] with the machine's own tolerances (`conform --tolerances FILE`) in place of the
/// defaults; a scenario's own `.check.yaml` still wins, being the scenario's statement.
pub fn run_one_within(
    ctl: &mut dyn Controller,
    dialects: &[String],
    path: &Path,
    name: &str,
    machine: &Tolerances,
) -> Result<ScenarioVerdict, InputError> {
    let setup = MachineSetup { tolerances: machine.clone(), params: Vec::new() };
    run_one_on(ctl, dialects, path, name, &setup)
}

/// What a user states of their machine for every scenario (`conform --tolerances`, `--params`).
#[derive(Debug, Clone, Default)]
pub struct MachineSetup {
    /// The comparison's tolerances for a scenario without a `.check.yaml` of its own.
    pub tolerances: Tolerances,
    /// The machine's parameter files, in order (a later file over an earlier), under each
    /// scenario's own: the reference runs on them and the controller is sent them in `load`.
    pub params: Vec<load::MachineParams>,
}

/// [`run_one_within`] on the machine's own parameters too (`conform --params FILE`): the
/// reference runs the scenario on them with the scenario's parameters on top, and the controller
/// is sent the same values in `load`.
///
/// # Errors
///
/// As [`run_one`]; also a machine parameter the scenario's dialect refuses.
pub fn run_one_on(
    ctl: &mut dyn Controller,
    dialects: &[String],
    path: &Path,
    name: &str,
    setup: &MachineSetup,
) -> Result<ScenarioVerdict, InputError> {
    let machine = &setup.tolerances;
    let started = std::time::Instant::now();
    let s = load::load_over(path, name, &setup.params)?;
    let dialect = s.machine.dialect.name();
    if !dialects.iter().any(|d| d == dialect) {
        let why = format!("the controller does not run dialect {dialect}");
        return Ok(ScenarioVerdict {
            name: s.name.clone(),
            title: s.title.clone(),
            rules: s.rules.clone(),
            status: Status::Skipped(why),
            failures: Vec::new(),
            notes: Vec::new(),
            seconds: 0.0,
        });
    }
    let tolerances = tolerances_of(path, machine)?;
    let program = match &s.refusal {
        Some((_, _, text)) => text.clone(),
        None => drive::program_text(path, name)?,
    };
    let job = drive::job_of(&s, program);
    let reference = s.machine.run_to_trace(&s.program, &s.opts);
    let mut v = match drive::drive(ctl, &s, &job, reference.meta.clone()) {
        Ok(driven) => judge(&s, &driven, &reference, &tolerances),
        Err(e) => ScenarioVerdict::controller_error(&s, &e),
    };
    v.seconds = started.elapsed().as_secs_f64();
    Ok(v)
}

/// The tolerances a scenario is judged within: its own `.check.yaml` next to it when it has one
/// (the scenario's statement), else the machine's (`conform --tolerances`).
///
/// # Errors
///
/// The scenario's `.check.yaml` is bad.
pub fn tolerances_of(path: &Path, machine: &Tolerances) -> Result<Tolerances, InputError> {
    let side = path.with_extension("check.yaml");
    if side.is_file() {
        crate::input::load_tolerances(&side)
    } else {
        Ok(machine.clone())
    }
}

/// The outcome of a whole suite.
#[derive(Debug, Clone, Serialize)]
pub struct SuiteReport {
    /// The controller.
    pub controller: String,
    /// Every scenario's verdict, in file order.
    pub scenarios: Vec<ScenarioVerdict>,
}

/// One rule id's line of the summary.
#[derive(Debug, Clone, Default, Serialize)]
pub struct RuleSummary {
    /// Scenarios that cite it and passed (or failed on other rules only).
    pub passed: Vec<String>,
    /// Scenarios with a failure naming it.
    pub failed: Vec<String>,
}

impl SuiteReport {
    /// A report for the controller `id`.
    pub fn new(id: &Identity) -> Self {
        SuiteReport { controller: format!("{} {}", id.name, id.version), scenarios: Vec::new() }
    }

    /// Counts: passed, failed, skipped.
    pub fn counts(&self) -> (usize, usize, usize) {
        let p = self.scenarios.iter().filter(|v| v.status == Status::Passed).count();
        let f = self.scenarios.iter().filter(|v| v.failed()).count();
        (p, f, self.scenarios.len() - p - f)
    }

    /// Every rule id met, with the scenarios that passed and failed it.
    pub fn by_rule(&self) -> BTreeMap<String, RuleSummary> {
        let mut m: BTreeMap<String, RuleSummary> = BTreeMap::new();
        for v in self.scenarios.iter().filter(|v| !matches!(v.status, Status::Skipped(_))) {
            let mut failed: Vec<&str> = v.failures.iter().map(|f| f.rule.as_str()).collect();
            failed.sort_unstable();
            failed.dedup();
            for r in &failed {
                m.entry(r.to_string()).or_default().failed.push(v.name.clone());
            }
            for r in v.rules.iter().filter(|r| !failed.contains(&r.as_str())) {
                m.entry(r.clone()).or_default().passed.push(v.name.clone());
            }
        }
        m
    }

    /// The text printed by `nc-conform conform`: the failures, the table per rule id, totals.
    pub fn summary(&self) -> String {
        let mut out = format!("conformance of {}\n", self.controller);
        for v in self.scenarios.iter().filter(|v| v.failed()) {
            let _ = writeln!(out, "\nFAILED {} — {}", v.name, v.title);
            for f in &v.failures {
                let _ = writeln!(out, "  {} [{}] {}", f.rule, f.by, f.text.replace('\n', "\n    "));
            }
        }
        let _ = writeln!(out, "\n{:<14} {:>6} {:>6}  failing scenarios", "rule", "passed", "failed");
        for (rule, r) in self.by_rule() {
            let _ = writeln!(
                out,
                "{rule:<14} {:>6} {:>6}  {}",
                r.passed.len(),
                r.failed.len(),
                r.failed.join(", ")
            );
        }
        let skipped: Vec<&ScenarioVerdict> =
            self.scenarios.iter().filter(|v| matches!(v.status, Status::Skipped(_))).collect();
        if !skipped.is_empty() {
            let _ = writeln!(out, "\nskipped:");
            for v in skipped {
                if let Status::Skipped(why) = &v.status {
                    let _ = writeln!(out, "  {} ({why})", v.name);
                }
            }
        }
        let (p, f, s) = self.counts();
        let _ = writeln!(out, "\n{} scenarios: {p} passed, {f} failed, {s} skipped", self.scenarios.len());
        out
    }

    /// JUnit XML: one test case per scenario (classname: its directory, `time`: its seconds),
    /// failures with rule ids; a scenario failed by the controller itself (timeout, crash,
    /// protocol) is an `<error>` and counted in `errors`, not in `failures`.
    pub fn junit(&self) -> String {
        let (_, f, s) = self.counts();
        let errors = self.scenarios.iter().filter(|v| v.errored()).count();
        let time: f64 = self.scenarios.iter().map(|v| v.seconds).sum();
        let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
        let _ = writeln!(
            out,
            "<testsuites tests=\"{n}\" failures=\"{fl}\" errors=\"{errors}\" skipped=\"{s}\" time=\"{time:.3}\">\n  <testsuite name=\"{}\" tests=\"{n}\" failures=\"{fl}\" errors=\"{errors}\" skipped=\"{s}\" time=\"{time:.3}\">",
            xml_escape(&format!("nc-conform conform: {}", self.controller)),
            n = self.scenarios.len(),
            fl = f - errors,
        );
        for v in &self.scenarios {
            let class = v.name.rsplit_once('/').map_or("scenarios", |(d, _)| d);
            let _ = write!(
                out,
                "    <testcase classname=\"{}\" name=\"{}\" time=\"{:.3}\"",
                xml_escape(class),
                xml_escape(&v.name),
                v.seconds
            );
            match &v.status {
                Status::Passed => out.push_str("/>\n"),
                Status::Skipped(why) => {
                    let _ =
                        writeln!(out, ">\n      <skipped message=\"{}\"/>\n    </testcase>", xml_escape(why));
                }
                Status::Failed => {
                    let mut rules: Vec<&str> = v.failures.iter().map(|f| f.rule.as_str()).collect();
                    rules.dedup();
                    let tag = if v.errored() { "error" } else { "failure" };
                    let _ = writeln!(
                        out,
                        ">\n      <{tag} message=\"{}\">{}</{tag}>\n    </testcase>",
                        xml_escape(&format!("{}: {}", rules.join(", "), v.title)),
                        xml_escape(&v.failure_text())
                    );
                }
            }
        }
        out.push_str("  </testsuite>\n</testsuites>\n");
        out
    }

    /// The whole report as JSON (verdicts and the summary per rule id).
    pub fn json(&self) -> String {
        #[derive(Serialize)]
        struct Out<'a> {
            controller: &'a str,
            passed: usize,
            failed: usize,
            skipped: usize,
            rules: BTreeMap<String, RuleSummary>,
            scenarios: &'a [ScenarioVerdict],
        }
        let (passed, failed, skipped) = self.counts();
        let o = Out {
            controller: &self.controller,
            passed,
            failed,
            skipped,
            rules: self.by_rule(),
            scenarios: &self.scenarios,
        };
        serde_json::to_string_pretty(&o).unwrap_or_default()
    }
}

/// The entry of a vendor's test file (`harness = false`): one libtest-mimic test per scenario
/// under `dir`, named by its path relative to `dir`'s parent; a scenario of a dialect the
/// controller does not run is listed as ignored. `factory` makes a fresh controller per test.
pub fn libtest_main<C, F>(factory: F, dir: &str)
where
    C: Controller,
    F: Fn() -> C + Send + Sync + Clone + 'static,
{
    use libtest_mimic::{Arguments, Failed, Trial};
    let args = Arguments::from_args();
    let dir = PathBuf::from(dir);
    let dialects = match factory().identity() {
        Ok(id) => id.dialects,
        Err(e) => {
            eprintln!("the controller cannot say who it is: {e}");
            std::process::exit(101);
        }
    };
    let base = dir.parent().unwrap_or(Path::new("")).to_path_buf();
    let trials: Vec<Trial> = scenario_files(&dir)
        .into_iter()
        .map(|p| {
            let name = p.strip_prefix(&base).unwrap_or(&p).to_string_lossy().replace('\\', "/");
            let skip = dialect_of(&p).is_some_and(|d| !dialects.contains(&d));
            let (factory, dialects, n) = (factory.clone(), dialects.clone(), name.clone());
            Trial::test(name, move || {
                let mut ctl = factory();
                let v = run_one(&mut ctl, &dialects, &p, &n).map_err(|e| Failed::from(e.render_plain()))?;
                match v.status {
                    Status::Failed => Err(Failed::from(format!("{}\n{}", v.title, v.failure_text()))),
                    _ => Ok(()),
                }
            })
            .with_ignored_flag(skip)
        })
        .collect();
    let ignored = trials.iter().filter(|t| t.has_ignored_flag()).count();
    if ignored > 0 {
        // Said where `cargo test` prints the ignored ones, so that nobody takes them for a gap.
        eprintln!(
            "note: {ignored} scenario(s) listed as ignored: their dialect is not one the controller declares ({})",
            dialects.join(", ")
        );
    }
    libtest_mimic::run(&args, trials).exit();
}

/// The `dialect:` of a scenario file, read cheaply (None when not found).
fn dialect_of(path: &Path) -> Option<String> {
    let text = String::from_utf8(crate::input::read_capped(path, crate::input::YAML).ok()?).ok()?;
    text.lines()
        .find_map(|l| l.strip_prefix("dialect:"))
        .map(|d| d.trim().trim_matches(['"', '\'']).to_string())
}

/// One libtest-mimic test per scenario file for a vendor's controller, in a test file with
/// `harness = false`:
///
/// ```ignore
/// nc_conform::conformance_suite!(my_controller::MyCtl::new, concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenarios"));
/// ```
///
/// The first argument makes a fresh controller (anything `Fn() -> impl Controller`), the second
/// is the scenario directory. Run with `cargo test`; filter like any test (`cargo test -- gsk/`).
#[macro_export]
macro_rules! conformance_suite {
    ($factory:expr, $dir:expr) => {
        fn main() {
            $crate::conform::suite::libtest_main($factory, $dir);
        }
    };
}
