//! Property-based fault campaigns under `cargo test` (issue 4; invariants in docs/invariants.md).
//!
//! Each property draws cases from one seed (`NC_SEED`, else fixed per property) and runs a modest
//! number of them (`PROPTEST_CASES`, else the property's default). A failure is shrunk to a
//! minimal case, written as `scenarios/regressions/<property>-<seed>-<hash>.yaml`, and reported
//! with the seed and the commands that replay it. `scripts/campaign` runs the same properties for
//! longer.

use std::path::PathBuf;

use nc_conform::campaign::properties;
use nc_conform::campaign::{cases_from_env, seed_from_env};
use proptest::strategy::{Strategy, ValueTree};

fn property(name: &str) {
    let p = properties::by_name(name).expect("a property of that name");
    let seed = seed_from_env(name);
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenarios/regressions");
    if let Err(f) = (p.run)(cases_from_env(p.default_cases), seed, &dir, &mut |_| {}) {
        panic!("{f}");
    }
}

/// INV-01..05, 07..10 over random programs of every dialect and peck mode, edge words, random
/// parameters and random inputs and faults.
#[test]
fn random_cases_keep_every_invariant() {
    property("random_cases_keep_every_invariant");
}

/// INV-03: every word at or beyond an edge of its range: the last valid value runs, the first
/// invalid one raises its alarm at its block and nothing moves.
#[test]
fn range_edges_alarm_without_motion() {
    property("range_edges_alarm_without_motion");
}

/// INV-06: dry run switched on at any time never changes a rigid tapping stroke.
#[test]
fn dry_run_never_changes_the_tap_feed() {
    property("dry_run_never_changes_the_tap_feed");
}

/// INV-07: under machine lock the axes and the tapping spindle stay still while the command
/// positions and the timing are those of the run without the lock.
#[test]
fn machine_lock_keeps_the_machine_still() {
    property("machine_lock_keeps_the_machine_still");
}

/// The operator panel as a state machine (proptest-state-machine): toggled switches, holds,
/// resets, an emergency stop, motor current and PLC faults, at times and at phases; shrinking
/// removes steps until the failing sequence is minimal.
#[test]
fn operator_sequences_keep_every_invariant() {
    property("operator_sequences_keep_every_invariant");
}

/// Every property has its test above (a new property needs a test of the same name).
#[test]
fn every_property_has_a_test() {
    let this = include_str!("properties.rs");
    for p in properties::ALL {
        assert!(this.contains(&format!("fn {}()", p.name)), "no test for property {}", p.name);
    }
}

/// A failing case becomes a scenario that loads and, run by the scenario suite, reports the
/// same invariant: proof that the regression files replay what the properties find.
#[test]
fn a_regression_scenario_replays_its_violation() {
    use nc_conform::campaign::case::{mm, Cycle};
    use nc_conform::campaign::regression::scenario_yaml;
    use nc_conform::campaign::strategy;
    use nc_conform::scenario::{load, run};
    use nc_engine::invariants::{Invariant, Violation};
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let mut case = strategy::case(0..1).new_tree(&mut runner).unwrap().current();
    case.program.edge = None;
    case.program.cycle = Cycle::GskG84;
    let v = Violation { invariant: Invariant::TapSync, t_us: 0, detail: "test".into() };
    let good = scenario_yaml(&case, std::slice::from_ref(&v), "test");
    let dir = std::path::Path::new(".");
    let s = load::load_text(&good, "regression.yaml", dir)
        .unwrap_or_else(|e| panic!("{}\n{good}", e.render_plain()));
    let outcome = run::run(&s);
    assert!(outcome.passed(), "the engine passes its own regression file:\n{}\n{good}", outcome.failures());
    assert!(outcome.verdicts.iter().any(|v| v.rule == "INV-04"), "INV-04 is checked");
    // The same file with a wrong lead: INV-04 must fail on replay.
    let bad = good.replace(&format!("lead: {}", mm(case.program.lead_nm())), "lead: 99");
    assert_ne!(bad, good);
    let s = load::load_text(&bad, "regression.yaml", dir).unwrap();
    let outcome = run::run(&s);
    assert!(
        outcome.verdicts.iter().any(|v| v.rule == "INV-04" && !v.pass),
        "a wrong lead breaks INV-04:\n{}",
        outcome.report(&s)
    );
}
