//! The named properties: what `cargo test --test properties` runs a few of and `scripts/campaign`
//! (`nc-conform campaign`) runs many of. Each draws its cases from one seed.

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

use proptest::prelude::*;
use proptest_state_machine::ReferenceStateMachine;

use super::case::{Case, Compare};
use super::strategy::{self, OperatorModel, Panel, Step};
use super::{run_property, Failure, Report, Stats};

/// Runs a property: (cases, seed, regressions directory, progress) → figures or the failure.
pub type Runner = fn(u32, u64, &Path, &mut dyn FnMut(&Report)) -> Result<Stats, Box<Failure>>;

/// A named property.
#[derive(Clone, Copy)]
pub struct Property {
    /// Its name (the test's name too).
    pub name: &'static str,
    /// What it checks.
    pub about: &'static str,
    /// Cases under plain `cargo test` (unless `PROPTEST_CASES` says otherwise).
    pub default_cases: u32,
    /// How to run it.
    pub run: Runner,
}

fn random_cases(n: u32, seed: u64, dir: &Path, p: &mut dyn FnMut(&Report)) -> Result<Stats, Box<Failure>> {
    run_property("random_cases_keep_every_invariant", strategy::case(0..6), |c| c, n, seed, dir, p)
}

fn range_edges(n: u32, seed: u64, dir: &Path, p: &mut dyn FnMut(&Report)) -> Result<Stats, Box<Failure>> {
    let s = (strategy::program(), strategy::params(), strategy::edge()).prop_map(
        |(mut program, params, edge)| {
            program.edge = Some(edge);
            Case { program, params, inputs: Vec::new(), compare: Compare::None }
        },
    );
    run_property("range_edges_alarm_without_motion", s, |c| c, n, seed, dir, p)
}

fn dry_run(n: u32, seed: u64, dir: &Path, p: &mut dyn FnMut(&Report)) -> Result<Stats, Box<Failure>> {
    let s = strategy::differential_case((0u16..600).prop_map(Compare::DryRun));
    run_property("dry_run_never_changes_the_tap_feed", s, |c| c, n, seed, dir, p)
}

fn machine_lock(n: u32, seed: u64, dir: &Path, p: &mut dyn FnMut(&Report)) -> Result<Stats, Box<Failure>> {
    let s = strategy::differential_case(Just(Compare::MachineLock));
    run_property("machine_lock_keeps_the_machine_still", s, |c| c, n, seed, dir, p)
}

type Sequence = (Panel, Vec<Step>, Option<Arc<AtomicUsize>>);

fn operator(n: u32, seed: u64, dir: &Path, p: &mut dyn FnMut(&Report)) -> Result<Stats, Box<Failure>> {
    let to_case = |(init, steps, seen): Sequence| {
        // Every step is part of the schedule the engine runs, so every step is "seen" (the
        // state machine's shrinker deletes unseen steps first).
        if let Some(seen) = seen {
            seen.store(steps.len(), Ordering::SeqCst);
        }
        steps.iter().fold(init, OperatorModel::apply).case
    };
    let s = OperatorModel::sequential_strategy(1..8);
    run_property("operator_sequences_keep_every_invariant", s, to_case, n, seed, dir, p)
}

/// Every property, in the order the campaign runs them.
pub const ALL: [Property; 5] = [
    Property {
        name: "random_cases_keep_every_invariant",
        about: "random programs of every dialect and peck mode, edge words, parameters, inputs and faults",
        default_cases: 96,
        run: random_cases,
    },
    Property {
        name: "range_edges_alarm_without_motion",
        about: "every word at the last valid and the first invalid value of its range (INV-03)",
        default_cases: 64,
        run: range_edges,
    },
    Property {
        name: "dry_run_never_changes_the_tap_feed",
        about: "dry run switched on at any time leaves every tapping stroke as it was (INV-06)",
        default_cases: 48,
        run: dry_run,
    },
    Property {
        name: "machine_lock_keeps_the_machine_still",
        about: "machine lock: nothing moves, commands and timing as without it (INV-07)",
        default_cases: 48,
        run: machine_lock,
    },
    Property {
        name: "operator_sequences_keep_every_invariant",
        about: "the operator panel as a state machine: switches, holds, resets, e-stop, faults",
        default_cases: 64,
        run: operator,
    },
];

/// The property of this name.
pub fn by_name(name: &str) -> Option<Property> {
    ALL.iter().copied().find(|p| p.name == name)
}
