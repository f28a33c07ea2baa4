//! Running a loaded scenario: the engine's trace and the verdict on every expectation.

use std::fmt::Write as _;

use nc_engine::Trace;

use nc_engine::ParseError;

use super::expect::{self, Verdict};
use super::load::Scenario;
use super::schema::ExpectRefused;

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
    let mut verdicts = match &s.refusal {
        Some(r) => vec![refusal_verdict(s, r)],
        None => expect::evaluate(&s.expect, &trace),
    };
    if let (Some(check), None) = (&s.invariants, &s.refusal) {
        verdicts.extend(super::invariants::evaluate(check, &s.machine, &s.program, &s.opts));
    }
    if s.refusal.is_none() {
        // Physical plausibility holds in every scenario, asked for or not (INV-11..INV-14).
        let tap = s.invariants.as_ref().and_then(|c| c.ctx.tap);
        verdicts.extend(super::invariants::physics_verdicts(&trace, &s.machine, tap));
    }
    Outcome { trace, verdicts }
}

/// The verdict on `expect.refused`: the parser refused the program where and why expected.
fn refusal_verdict(s: &Scenario, (err, want, _): &(Option<ParseError>, ExpectRefused, String)) -> Verdict {
    let rule = s.rules[0].clone();
    let expected = format!(
        "refused at line {}{}{}",
        want.line,
        want.col.map_or(String::new(), |c| format!(", column {c}")),
        want.message.as_ref().map_or(String::new(), |m| format!(", message containing `{m}`"))
    );
    let (pass, actual, t_us) = match err {
        None => (false, "the program parsed".to_string(), None),
        Some(e) => {
            let ok = e.line == want.line
                && want.col.is_none_or(|c| c == e.col)
                && want.message.as_ref().is_none_or(|m| e.message.contains(m.as_str()));
            (
                ok,
                format!(
                    "refused at line {}, column {}: {}; expected {}",
                    e.line, e.col, e.message, e.expected
                ),
                None,
            )
        }
    };
    Verdict { rule, what: "refused".into(), pass, t_us, expected, actual }
}
