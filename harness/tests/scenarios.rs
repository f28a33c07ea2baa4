//! The scenario library as a conformance suite: one test per file under `scenarios/`, named by
//! its path, picked up without editing any Rust code. Each test runs the scenario on the reference
//! engine, checks every expectation, and compares the timing diagram and the event trace with
//! their reviewed snapshots in `snapshots/` (a changed snapshot fails under `CI=true`).

use std::path::{Path, PathBuf};

use libtest_mimic::{Arguments, Failed, Trial};
use nc_conform::render::{events::event_listing, timing::timing_diagram};
use nc_conform::scenario::{load, run};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn scenario_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    let mut entries: Vec<PathBuf> = rd.map(|e| e.unwrap().path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            scenario_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "yaml" || e == "yml") {
            out.push(p);
        }
    }
}

/// `scenarios/gsk/feed_hold/x.yaml` → `gsk__feed_hold__x`.
fn snapshot_name(rel: &str) -> String {
    rel.trim_start_matches("scenarios/").trim_end_matches(".yaml").trim_end_matches(".yml").replace('/', "__")
}

fn check(path: &Path, rel: &str) -> Result<(), Failed> {
    let s = load::load(path, rel).map_err(|e| Failed::from(e.render_plain()))?;
    let outcome = run::run(&s);
    let name = snapshot_name(rel);
    let mut settings = insta::Settings::clone_current();
    settings.set_snapshot_path(root().join("snapshots"));
    settings.set_prepend_module_to_snapshot(false);
    settings.set_omit_expression(true);
    settings.set_description(rel);
    let diagram = timing_diagram(&outcome.trace, &s.diagram);
    // A scenario that expects a refusal snapshots the diagnostic the user would see instead.
    let events = match &s.refusal {
        Some((Some(e), _, text)) => {
            nc_conform::diag::parse_error(&format!("{rel} (program)"), text, e).render_plain()
        }
        Some((None, _, _)) => "the program parsed\n".to_string(),
        None => event_listing(&outcome.trace),
    };
    let refused = s.refusal.is_some();
    // Both snapshots are compared (and written for review) even when the first differs.
    let timing = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        if !refused {
            settings.bind(|| insta::assert_snapshot!(format!("{name}.timing"), diagram))
        }
    }));
    let listing = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        settings.bind(|| insta::assert_snapshot!(format!("{name}.events"), events))
    }));
    let snap = timing.and(listing);
    // Physical plausibility (INV-11..INV-14) runs in every scenario. A scenario listed in
    // `physics_open.txt` has a known violation not fixed yet (owner and reason there): its physics
    // verdicts may fail, and once they all hold the listing must go (a ratchet).
    let physics = |v: &&nc_conform::scenario::expect::Verdict| {
        !v.pass && ["INV-11", "INV-12", "INV-13", "INV-14"].contains(&v.rule.as_str())
    };
    let open = physics_open().contains(&rel.to_string());
    let broken = outcome.verdicts.iter().filter(physics).count();
    if open && broken == 0 {
        return Err(
            format!("{rel}: listed in harness/tests/physics_open.txt but physics holds: remove it").into()
        );
    }
    // `reference_open.txt`: expectations of the listed rules that LinuxCNC meets and the reference
    // does not yet; they may fail, and once none does the listing must go (a ratchet).
    let departs = reference_open(rel);
    let known = |v: &&nc_conform::scenario::expect::Verdict| !v.pass && departs.contains(&v.rule);
    if !departs.is_empty() && !outcome.verdicts.iter().any(|v| known(&v)) {
        return Err(format!(
            "{rel}: listed in harness/tests/reference_open.txt but the reference meets {}: remove it",
            departs.join(", ")
        )
        .into());
    }
    let tolerated = |v: &&nc_conform::scenario::expect::Verdict| v.pass || (open && physics(v)) || known(v);
    if !outcome.verdicts.iter().all(|v| tolerated(&v)) {
        return Err(format!("{}\n{}", s.title, outcome.failures()).into());
    }
    snap.map_err(|_| Failed::from(format!("{rel}: a snapshot differs from the reviewed one (see above)")))
}

/// The scenarios with a known, reported physics violation (`physics_open.txt`: path, then why).
fn physics_open() -> Vec<String> {
    include_str!("physics_open.txt")
        .lines()
        .map(|l| l.split('#').next().unwrap_or("").trim().to_string())
        .filter(|l| !l.is_empty())
        .collect()
}

/// The rule ids `reference_open.txt` lists for a scenario (path, then rule ids).
fn reference_open(rel: &str) -> Vec<String> {
    include_str!("reference_open.txt")
        .lines()
        .map(|l| l.split('#').next().unwrap_or("").split_whitespace().map(str::to_string).collect::<Vec<_>>())
        .find(|w| w.first().is_some_and(|p| p == rel))
        .map(|w| w[1..].to_vec())
        .unwrap_or_default()
}

fn main() {
    let args = Arguments::from_args();
    let mut files = Vec::new();
    scenario_files(&root().join("scenarios"), &mut files);
    let trials: Vec<Trial> = files
        .into_iter()
        .map(|p| {
            let rel = p.strip_prefix(root()).unwrap_or(&p).to_string_lossy().replace('\\', "/");
            let rel = rel.trim_start_matches("./").to_string();
            let name = rel.clone();
            Trial::test(name, move || check(&p, &rel))
        })
        .collect();
    libtest_mimic::run(&args, trials).exit();
}
