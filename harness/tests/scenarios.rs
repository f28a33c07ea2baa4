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
    if !outcome.passed() {
        return Err(format!("{}\n{}", s.title, outcome.failures()).into());
    }
    snap.map_err(|_| Failed::from(format!("{rel}: a snapshot differs from the reviewed one (see above)")))
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
