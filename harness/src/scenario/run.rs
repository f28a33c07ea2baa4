//! Running a loaded scenario: the engine's trace and the verdict on every expectation.

use std::fmt::Write as _;

use nc_engine::Trace;

use super::expect::{self, Verdict};
use super::load::Scenario;

/// What a run gave.
#[derive(Debug)]
pub struct Outcome {
    /// The whole trace.
    pub trace: Trace,
    /// One verdict per expectation.
    pub verdicts: Vec<Verdict>,
}

impl Outcome {
    /// Every expectation held.
    pub fn passed(&self) -> bool {
        self.verdicts.iter().all(|v| v.pass)
    }

    /// The failures, one per line: rule id, what, time, expected, actual.
    pub fn failures(&self) -> String {
        let mut s = String::new();
        for v in self.verdicts.iter().filter(|v| !v.pass) {
            let at = v.t_us.map_or(String::from("-"), |t| format!("{:.3} ms", t as f64 / 1000.0));
            let _ = writeln!(
                s,
                "FAIL {} {} at {at}: expected {}; actual {}",
                v.rule, v.what, v.expected, v.actual
            );
        }
        s
    }

    /// Every verdict, one per line (for the command line).
    pub fn report(&self, s: &Scenario) -> String {
        let mut out = format!("{} — {}\n", s.name, s.title);
        for v in &self.verdicts {
            let at = v.t_us.map_or(String::new(), |t| format!(" at {:.3} ms", t as f64 / 1000.0));
            if v.pass {
                let _ = writeln!(out, "  ok   {} {}{at}", v.rule, v.what);
            } else {
                let _ = writeln!(
                    out,
                    "  FAIL {} {}{at}: expected {}; actual {}",
                    v.rule, v.what, v.expected, v.actual
                );
            }
        }
        let failed = self.verdicts.iter().filter(|v| !v.pass).count();
        let _ = writeln!(out, "{} passed, {} failed", self.verdicts.len() - failed, failed);
        out
    }
}

/// Runs the scenario and evaluates its expectations.
pub fn run(s: &Scenario) -> Outcome {
    let trace = s.machine.run_to_trace(&s.program, &s.opts);
    let verdicts = expect::evaluate(&s.expect, &trace);
    Outcome { trace, verdicts }
}
