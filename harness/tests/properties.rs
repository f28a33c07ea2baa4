//! Property-based fault campaigns under `cargo test` (issue 4; invariants in docs/invariants.md).
//!
//! Each property draws cases from one seed (`NC_SEED`, else fixed per property) and runs a modest
//! number of them (`PROPTEST_CASES`, else the default below). A failure is shrunk to a minimal
//! case, written as `scenarios/regressions/<property>-<seed>.yaml`, and reported with the seed and
//! the commands that replay it. `scripts/campaign` runs the same properties for longer.

use std::path::PathBuf;

use nc_conform::campaign::case::Compare;
use nc_conform::campaign::strategy::{self, OperatorModel, Panel, Step};
use nc_conform::campaign::{cases_from_env, run_property, seed_from_env, Case};
use proptest::prelude::*;
use proptest::strategy::ValueTree;
use proptest_state_machine::ReferenceStateMachine;

fn regressions() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenarios/regressions")
}

fn property<S: Strategy>(name: &str, s: S, to_case: impl Fn(S::Value) -> Case, default_cases: u32) {
    let seed = seed_from_env(name);
    let cases = cases_from_env(default_cases);
    if let Err(f) = run_property(name, s, to_case, cases, seed, &regressions(), &mut |_| {}) {
        panic!("{f}");
    }
}

/// INV-01..05, 07..10 over random programs of every dialect and peck mode, edge words, random
/// parameters and random inputs and faults.
#[test]
fn random_cases_keep_every_invariant() {
    property("random_cases_keep_every_invariant", strategy::case(0..6), |c| c, 96);
}

/// INV-03: every word at or beyond an edge of its range: the last valid value runs, the first
/// invalid one raises its alarm at its block and nothing moves.
#[test]
fn range_edges_alarm_without_motion() {
    let s = (strategy::program(), strategy::params(), strategy::edge()).prop_map(
        |(mut program, params, edge)| {
            program.edge = Some(edge);
            Case { program, params, inputs: Vec::new(), compare: Compare::None }
        },
    );
    property("range_edges_alarm_without_motion", s, |c| c, 64);
}

/// INV-06: dry run switched on at any time never changes a rigid tapping stroke.
#[test]
fn dry_run_never_changes_the_tap_feed() {
    let s = strategy::differential_case((0u16..600).prop_map(Compare::DryRun));
    property("dry_run_never_changes_the_tap_feed", s, |c| c, 48);
}

/// INV-07: under machine lock the axes and the tapping spindle stay still while the command
/// positions and the timing are those of the run without the lock.
#[test]
fn machine_lock_keeps_the_machine_still() {
    let s = strategy::differential_case(Just(Compare::MachineLock));
    property("machine_lock_keeps_the_machine_still", s, |c| c, 48);
}

/// The operator panel as a state machine (proptest-state-machine): toggled switches, holds,
/// resets, an emergency stop that stays pressed, motor current and PLC faults, at times and at
/// phases; shrinking removes steps until the failing sequence is minimal.
#[test]
fn operator_sequences_keep_every_invariant() {
    let s = OperatorModel::sequential_strategy(1..8);
    let to_case =
        |(init, steps, seen): (Panel, Vec<Step>, Option<std::sync::Arc<std::sync::atomic::AtomicUsize>>)| {
            if let Some(seen) = seen {
                seen.store(steps.len(), std::sync::atomic::Ordering::SeqCst);
            }
            steps.iter().fold(init, OperatorModel::apply).case
        };
    property("operator_sequences_keep_every_invariant", s, to_case, 64);
}

/// A failing case becomes a scenario that loads and, run by the scenario suite, reports the
/// same invariant: proof that the regression files replay what the property found.
#[test]
fn a_regression_scenario_replays_its_violation() {
    use nc_conform::campaign::regression::scenario_yaml;
    use nc_conform::scenario::{load, run};
    use nc_engine::invariants::{Invariant, Violation};
    // A case whose stated lead is deliberately wrong, so INV-04 must fail on replay.
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let mut case = strategy::case(0..1).new_tree(&mut runner).unwrap().current();
    case.program.edge = None;
    case.program.cycle = nc_conform::campaign::case::Cycle::GskG84;
    let v = Violation { invariant: Invariant::TapSync, t_us: 0, detail: "test".into() };
    let good = scenario_yaml(&case, std::slice::from_ref(&v), "test");
    let s = load::load_text(&good, "regression.yaml", std::path::Path::new("."))
        .unwrap_or_else(|e| panic!("{}\n{good}", e.render_plain()));
    let outcome = run::run(&s);
    assert!(
        outcome.passed(),
        "the correct engine passes its own regression file:\n{}\n{good}",
        outcome.failures()
    );
    assert!(outcome.verdicts.iter().any(|v| v.rule == "INV-04"), "INV-04 is checked");
    let bad = good
        .replace(&format!("lead: {}", nc_conform::campaign::case::mm(case.program.lead_nm())), "lead: 99");
    assert_ne!(bad, good);
    let s = load::load_text(&bad, "regression.yaml", std::path::Path::new(".")).unwrap();
    let outcome = run::run(&s);
    assert!(
        outcome.verdicts.iter().any(|v| v.rule == "INV-04" && !v.pass),
        "a wrong lead breaks INV-04:\n{}",
        outcome.report(&s)
    );
}
