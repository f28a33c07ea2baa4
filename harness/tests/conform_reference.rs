//! The reference engine through the conformance harness: driven step by step as a `Controller`
//! (inputs on conditions given when the controller stops on them), it must give exactly the
//! trace of the scenario run, and pass every scenario. One test per scenario directory keeps
//! the output short; every scenario file is covered, whatever the library holds.

use std::path::PathBuf;

use nc_conform::conform::drive::{self, Driven};
use nc_conform::conform::reference::Reference;
use nc_conform::conform::suite::{run_one, scenario_files};
use nc_conform::conform::verdict::Status;
use nc_conform::conform::Controller;
use nc_conform::scenario::load;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

#[test]
fn stepping_the_reference_repeats_every_scenario_run_exactly() {
    repeats_every_scenario_run(Reference::new());
}

/// The protocol's time semantics (docs/adapter-protocol.md, `advance`): after a stop on a
/// condition `now_us` is the time of the event that made it hold, and an input at `now_us + d`
/// acts at that literal time. A controller that applies inputs at their literal `t_us` must give
/// the scenario run's trace too (it did not when `now_us` was the time of the next event).
#[test]
fn a_controller_applying_inputs_at_their_literal_time_repeats_every_scenario_run() {
    repeats_every_scenario_run(Reference::literal());
}

fn repeats_every_scenario_run(mut ctl: Reference) {
    let mut mismatched = Vec::new();
    let files = scenario_files(&root().join("scenarios"));
    assert!(files.len() > 100, "the scenario library is found");
    for p in files {
        let name = p.strip_prefix(root()).unwrap().display().to_string();
        let s = load::load(&p, &name).unwrap();
        let program = match &s.refusal {
            Some((_, _, text)) => text.clone(),
            None => drive::program_text(&p, &name).unwrap(),
        };
        let job = drive::job_of(&s, program);
        let want = s.machine.run_to_trace(&s.program, &s.opts);
        match drive::drive(&mut ctl, &s, &job, want.meta.clone()) {
            Ok(Driven::Ran(got)) => {
                if got != want {
                    let i = got.events.iter().zip(&want.events).position(|(a, b)| a != b);
                    mismatched.push(format!("{name}: first difference at event {i:?}"));
                }
            }
            Ok(Driven::Refused { .. }) if s.refusal.is_some() => {}
            Ok(other) => mismatched.push(format!("{name}: {other:?}")),
            Err(e) => mismatched.push(format!("{name}: {e}")),
        }
    }
    assert!(mismatched.is_empty(), "{}", mismatched.join("\n"));
}

#[test]
fn the_reference_passes_every_scenario() {
    let mut ctl = Reference::new();
    let dialects = ctl.identity().unwrap().dialects;
    let mut failed = Vec::new();
    for p in scenario_files(&root().join("scenarios")) {
        let name = p.strip_prefix(root()).unwrap().display().to_string();
        let v = run_one(&mut ctl, &dialects, &p, &name).unwrap();
        if v.status != Status::Passed {
            failed.push(format!("{name}: {:?}\n{}", v.status, v.failure_text()));
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}
