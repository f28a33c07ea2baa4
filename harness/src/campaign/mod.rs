//! Property-based fault campaigns: generated programs, parameters and input schedules run on the
//! reference engine, every run checked against the invariants of `nc_engine::invariants`
//! (`docs/invariants.md`), every failure shrunk to a minimal case and written as a scenario.
//!
//! - [`case`]: a generated case and how it becomes parameters and inputs;
//! - [`program`]: how a case becomes program text, per dialect and cycle;
//! - [`strategy`]: proptest strategies, and the operator panel as a proptest-state-machine model;
//! - [`oracle`]: running a case and checking the invariants;
//! - [`regression`]: a failing case as a scenario file;
//! - [`properties`]: the named properties that `cargo test` and `nc-conform campaign` run.
//!
//! One seed decides a whole property run: the failure message prints it with the command that
//! replays it, and the scenario file replays the minimal case without any seed.

pub mod case;
pub mod oracle;
pub mod program;
pub mod properties;
pub mod regression;
pub mod strategy;

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nc_engine::invariants::Violation;
use proptest::strategy::Strategy;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestError, TestRng, TestRunner};

pub use case::Case;
pub use oracle::{check_case, Report};

/// What a property run covered.
#[derive(Debug, Default, Clone)]
pub struct Stats {
    /// Cases run (shrinking not counted).
    pub cases: u64,
    /// How often each alarm code was raised.
    pub alarms: BTreeMap<String, u64>,
    /// How often each situation was reached (`feed_hold during cutting in rigid mode`, ...).
    pub reached: BTreeMap<String, u64>,
    /// How the runs ended.
    pub ends: BTreeMap<String, u64>,
}

impl Stats {
    /// Adds one case's report.
    pub fn add(&mut self, r: &Report) {
        self.cases += 1;
        for a in &r.alarms {
            *self.alarms.entry(a.clone()).or_default() += 1;
        }
        for s in &r.reached {
            *self.reached.entry(s.clone()).or_default() += 1;
        }
        *self.ends.entry(r.end.clone()).or_default() += 1;
    }

    /// Adds another run's figures.
    pub fn merge(&mut self, o: &Stats) {
        self.cases += o.cases;
        for (m, src) in
            [(&mut self.alarms, &o.alarms), (&mut self.reached, &o.reached), (&mut self.ends, &o.ends)]
        {
            for (k, v) in src {
                *m.entry(k.clone()).or_default() += v;
            }
        }
    }
}

/// A property that failed: the minimal case, what it broke, and how to replay it.
#[derive(Debug)]
pub struct Failure {
    /// The property's name.
    pub property: String,
    /// The seed of the run.
    pub seed: u64,
    /// The minimal failing case (none when the run was aborted before one was found).
    pub case: Option<Case>,
    /// What it broke.
    pub violations: Vec<Violation>,
    /// The scenario that replays it.
    pub yaml: String,
    /// Where the scenario was written, if it could be.
    pub path: Option<PathBuf>,
    /// What the cases before the failure covered.
    pub stats: Stats,
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "property `{}` failed (seed {}):", self.property, self.seed)?;
        for v in &self.violations {
            writeln!(f, "  {v}")?;
        }
        if let Some(c) = &self.case {
            writeln!(f, "minimal case: {c:?}")?;
        }
        writeln!(
            f,
            "replay the property:  NC_SEED={} cargo test -p nc-conform --test properties -- {}",
            self.seed, self.property
        )?;
        match &self.path {
            Some(p) => {
                let name = p.file_name().map_or(String::new(), |n| n.to_string_lossy().into_owned());
                writeln!(f, "replay the case:      cargo test -p nc-conform --test scenarios -- scenarios/regressions/{name}")?;
                writeln!(f, "written to:           {}", p.display())?;
            }
            None => writeln!(f, "the scenario could not be written; here it is:")?,
        }
        write!(f, "--- scenario ---\n{}", self.yaml)
    }
}

/// The number of cases: `PROPTEST_CASES` if set, else `default`.
pub fn cases_from_env(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

/// The seed: `NC_SEED` if set, else a fixed seed derived from the property's name (so that plain
/// `cargo test` is reproducible; campaigns pass their own).
pub fn seed_from_env(property: &str) -> u64 {
    std::env::var("NC_SEED").ok().and_then(|v| v.parse().ok()).unwrap_or_else(|| {
        property.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3))
    })
}

/// Runs `cases` cases of `strategy` (mapped to a [`Case`] by `to_case`) from `seed`, calling
/// `progress` after each. On failure the minimal case is written under `regressions` as
/// `<property>-<seed>-<hash>.yaml`.
///
/// # Errors
///
/// The minimal failing case, with its violations and replay commands.
pub fn run_property<S: Strategy>(
    property: &str,
    strategy: S,
    to_case: impl Fn(S::Value) -> Case,
    cases: u32,
    seed: u64,
    regressions: &Path,
    progress: &mut dyn FnMut(&Report),
) -> Result<Stats, Box<Failure>> {
    let config = Config { cases, failure_persistence: None, ..Config::default() };
    let mut bytes = [0u8; 32];
    bytes[..8].copy_from_slice(&seed.to_le_bytes());
    let mut runner = TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &bytes));
    let stats = RefCell::new(Stats::default());
    let failed = RefCell::new(false);
    let progress = RefCell::new(progress);
    let result = runner.run(&strategy, |value| {
        let case = to_case(value);
        let report = check_case(&case);
        if !*failed.borrow() {
            stats.borrow_mut().add(&report);
            (progress.borrow_mut())(&report);
        }
        if report.violations.is_empty() {
            Ok(())
        } else {
            *failed.borrow_mut() = true;
            Err(TestCaseError::fail(report.violations[0].to_string()))
        }
    });
    match result {
        Ok(()) => Ok(stats.into_inner()),
        Err(TestError::Fail(_, value)) => {
            let case = to_case(value);
            let violations = check_case(&case).violations;
            let origin = format!("property {property}, seed {seed}");
            let yaml = regression::scenario_yaml(&case, &violations, &origin);
            // Named by property, seed and content, so that one seed's successive failures (after a
            // fix) never overwrite each other.
            let hash = yaml
                .bytes()
                .fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3));
            let name = format!("{property}-{seed}-{:08x}", hash as u32);
            let path = regression::write(regressions, &name, &yaml).ok();
            Err(Box::new(Failure {
                property: property.to_string(),
                seed,
                case: Some(case),
                violations,
                yaml,
                path,
                stats: stats.into_inner(),
            }))
        }
        Err(TestError::Abort(why)) => {
            let violations = vec![Violation {
                invariant: nc_engine::invariants::Invariant::NoPanic,
                t_us: 0,
                detail: format!("the property run was aborted: {why}"),
            }];
            Err(Box::new(Failure {
                property: property.to_string(),
                seed,
                case: None,
                violations,
                yaml: String::new(),
                path: None,
                stats: stats.into_inner(),
            }))
        }
    }
}
