//! The verdict on one scenario run by a controller: the scenario's own expectations evaluated
//! on the controller's trace, and the controller's trace compared with the reference's by
//! [`crate::check`] (same tolerances as `nc-conform check`, the scenario's `.check.yaml` when it
//! has one). Every failure names the rule id it breaks.

use nc_engine::trace::{Event, Trace, AXES};
use serde::Serialize;

use super::drive::Driven;
use super::ControllerError;
use crate::check::{self, CheckSpec, Tolerances};
use crate::scenario::expect;
use crate::scenario::load::Scenario;
use crate::scenario::timeline::{ms, Slack};

/// One thing the controller got wrong.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Failure {
    /// The rule id it breaks.
    pub rule: String,
    /// Which test found it: `expect` (the scenario's expectations), `check` (the comparison with
    /// the reference, `CHK-...`), `refusal`, or `controller` (the controller failed).
    pub by: String,
    /// What, when, expected and actual.
    pub text: String,
}

/// How a scenario went.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Every expectation held and the trace conforms to the reference.
    Passed,
    /// At least one failure.
    Failed,
    /// The controller does not run it (the reason).
    Skipped(String),
}

/// The verdict on one scenario.
#[derive(Debug, Clone, Serialize)]
pub struct ScenarioVerdict {
    /// The scenario file as named.
    pub name: String,
    /// Its title.
    pub title: String,
    /// The rule ids it cites.
    pub rules: Vec<String>,
    /// Passed, failed or skipped.
    pub status: Status,
    /// The failures.
    pub failures: Vec<Failure>,
    /// Comparisons left out because the reference fails them against itself.
    pub notes: Vec<String>,
    /// Wall time of the scenario (its reference run, the controller's run, the verdict), s.
    pub seconds: f64,
}

impl ScenarioVerdict {
    /// Whether it failed.
    pub fn failed(&self) -> bool {
        self.status == Status::Failed
    }

    /// Whether it failed because the controller did (timeout, crash, protocol): a JUnit error,
    /// not a failure.
    pub fn errored(&self) -> bool {
        self.failed() && self.failures.iter().all(|f| f.by == "controller")
    }

    /// Whether a failure names a rule of this family (`GSK-RT` matches `GSK-RT-07`).
    pub fn names_family(&self, family: &str) -> bool {
        self.failures.iter().any(|f| f.rule.starts_with(family))
    }

    /// The failures, one per line.
    pub fn failure_text(&self) -> String {
        self.failures.iter().map(|f| format!("FAIL {} [{}] {}\n", f.rule, f.by, f.text)).collect()
    }

    /// The verdict when the controller failed.
    pub fn controller_error(s: &Scenario, e: &ControllerError) -> ScenarioVerdict {
        let failures = s
            .rules
            .iter()
            .take(1)
            .map(|r| Failure { rule: r.clone(), by: "controller".into(), text: e.to_string() })
            .collect();
        ScenarioVerdict {
            name: s.name.clone(),
            title: s.title.clone(),
            rules: s.rules.clone(),
            status: Status::Failed,
            failures,
            notes: Vec::new(),
            seconds: 0.0,
        }
    }
}

/// Judges what the controller did with `s` against the reference's trace.
pub fn judge(s: &Scenario, driven: &Driven, reference: &Trace, tolerances: &Tolerances) -> ScenarioVerdict {
    let mut failures = Vec::new();
    let mut notes: Vec<String> = s
        .over_machine
        .iter()
        .map(|o| format!("the scenario's own parameter over the machine's: {o}"))
        .collect();
    let first_rule = s.rules.first().cloned().unwrap_or_default();
    match (driven, &s.refusal) {
        (Driven::Unsupported(why), _) => {
            return ScenarioVerdict {
                name: s.name.clone(),
                title: s.title.clone(),
                rules: s.rules.clone(),
                status: Status::Skipped(why.clone()),
                failures,
                notes: Vec::new(),
                seconds: 0.0,
            }
        }
        (Driven::Refused { line, col, message }, Some((_, want, _))) => {
            let ok = *line == want.line && want.col.is_none_or(|c| Some(c) == *col);
            if !ok {
                let at = col.map_or(String::new(), |c| format!(", column {c}"));
                let want_at = want.col.map_or(String::new(), |c| format!(", column {c}"));
                failures.push(Failure {
                    rule: first_rule,
                    by: "refusal".into(),
                    text: format!(
                        "refused at line {line}{at} ({message}); expected a refusal at line {}{want_at}",
                        want.line
                    ),
                });
            }
        }
        (Driven::Ran(_), Some((_, want, _))) => failures.push(Failure {
            rule: first_rule,
            by: "refusal".into(),
            text: format!("the controller ran the program; expected a refusal at line {}", want.line),
        }),
        (Driven::Refused { line, col, message }, None) => failures.push(Failure {
            rule: first_rule,
            by: "refusal".into(),
            text: format!(
                "the controller refused a valid program at line {line}{}: {message}",
                col.map_or(String::new(), |c| format!(", column {c}"))
            ),
        }),
        (Driven::Ran(trace), None) => {
            // The expectations are exact on the reference, within the comparison's tolerances on
            // a controller (it quantises, and its events fall a servo period from the
            // reference's): its values within them of the reference's at the same time are read
            // as the reference's (DEC-122), and the expected values are met within them (DEC-156).
            let (quantised, slack) = if trace.events == reference.events {
                (None, Slack::EXACT)
            } else {
                (Some(snap(trace, reference, tolerances)), slack(tolerances))
            };
            let within = if slack == Slack::EXACT { String::new() } else { describe(&slack) };
            // An expectation the reference itself does not meet (on a machine's own parameters,
            // `conform --params`, a scenario's times and levels may not hold) says nothing about
            // the controller: it is left out, noted; the comparison with the reference still
            // judges that stretch.
            let missed: Vec<String> = expect::evaluate_within(&s.expect, reference, &Slack::EXACT)
                .into_iter()
                .filter(|v| !v.pass)
                .map(|v| v.what)
                .collect();
            for w in &missed {
                notes.push(format!(
                    "expectation {w} left out: the reference itself does not meet it on these parameters"
                ));
            }
            for v in expect::evaluate_within(&s.expect, quantised.as_ref().unwrap_or(trace), &slack)
                .into_iter()
                .filter(|v| !v.pass && !missed.contains(&v.what))
            {
                let at = v.t_us.map_or(String::new(), |t| format!(" at {}", ms(t)));
                failures.push(Failure {
                    rule: v.rule.clone(),
                    by: "expect".into(),
                    text: format!("{}{at}: expected {}{within}; actual {}", v.what, v.expected, v.actual),
                });
            }
            let spec = CheckSpec {
                tolerances: tolerances.clone(),
                anchor: None,
                expect: None,
                rules: s.rules.clone(),
                // A controller's outputs are full trace events: everything is comparable.
                carried: Default::default(),
            };
            // A comparison the reference fails against itself (the absolute sync error of a
            // stalled spindle, ...) says nothing about the controller: it is left out, noted.
            let own = check::check(reference, reference.events.iter().cloned(), &spec);
            let mut left_out: Vec<(String, String)> =
                own.divergences.iter().map(|d| (d.rule.clone(), d.check.clone())).collect();
            left_out.sort();
            left_out.dedup();
            for (rule, chk) in &left_out {
                notes.push(format!("{chk} ({rule}) left out: the reference itself diverges from it"));
            }
            // The same events compare as the reference with itself: nothing is left to find.
            let rep = if trace.events == reference.events {
                own
            } else {
                check::check(reference, trace.events.iter().cloned(), &spec)
            };
            let kept =
                rep.sorted().into_iter().filter(|d| !left_out.contains(&(d.rule.clone(), d.check.clone())));
            for d in kept {
                let at = d.t_us.map_or(String::new(), |t| format!(" at {}", ms(t.max(0) as u64)));
                failures.push(Failure {
                    rule: d.rule.clone(),
                    by: d.check.clone(),
                    text: format!(
                        "{}{at}: expected {}; actual {} (beyond by {})",
                        d.what, d.expected, d.actual, d.margin
                    ),
                });
            }
            if rep.omitted > 0 {
                failures.push(Failure {
                    rule: first_rule,
                    by: "check".into(),
                    text: format!("{} more divergences not listed", rep.omitted),
                });
            }
        }
    }
    let status = if failures.is_empty() { Status::Passed } else { Status::Failed };
    ScenarioVerdict {
        name: s.name.clone(),
        title: s.title.clone(),
        rules: s.rules.clone(),
        status,
        failures,
        notes,
        seconds: 0.0,
    }
}

/// The controller's trace with every sampled value that lies within the comparison's tolerance
/// of the reference's value at the same time replaced by the reference's: positions within
/// `keypoint_mm`, the spindle speed within `speed_rpm`, its angle within [`ANGLE_MDEG`]; the end
/// summary's positions, command positions and spindle against the reference's end summary.
/// Values beyond the tolerance are kept as the controller reported them. A position or speed the
/// controller holds unchanged from one sample to the next keeps the value its first sample was
/// read as: where the reference moves within the tolerance of a standing controller (it resumed
/// a feed hold 20–35 ms earlier), the controller is not read as moving with it (DEC-155).
pub fn snap(trace: &Trace, reference: &Trace, tol: &Tolerances) -> Trace {
    let r = crate::check::reference::Reference::new(reference);
    let pos = crate::check::tolerance::mm_nm(tol.keypoint_mm);
    let rpm = (tol.speed_rpm.max(0.0) * 1000.0).round() as i64;
    let near = |v: &mut i64, want: f64, within: i64| {
        let w = want.round() as i64;
        if (*v - w).abs() <= within {
            *v = w;
        }
    };
    let near_angle = |v: &mut i64, want: f64| {
        let w = want.round() as i64;
        let d = (*v - w).rem_euclid(360_000);
        if d.min(360_000 - d) <= ANGLE_MDEG {
            *v = w.rem_euclid(360_000);
        }
    };
    let mut out = trace.clone();
    let ref_end = reference.end();
    // per axis, then the spindle speed: (the value reported, the value it was read as)
    let mut held: [Option<(i64, i64)>; AXES + 1] = [None; AXES + 1];
    let mut keep = |slot: usize, v: &mut i64, read: &dyn Fn(&mut i64)| match held[slot] {
        Some((raw, as_read)) if raw == *v => *v = as_read,
        _ => {
            let raw = *v;
            read(v);
            held[slot] = Some((raw, *v));
        }
    };
    for e in &mut out.events {
        let t = e.t_us as i64;
        match &mut e.event {
            Event::Sample(s) => {
                for a in r.axes() {
                    keep(a.index, &mut s.axes[a.index], &|v| {
                        if let Some(want) = r.pos_at(t, a.index) {
                            near(v, want, pos);
                        }
                    });
                }
                keep(AXES, &mut s.spindle_mrpm, &|v| {
                    if let Some(want) = r.value_at(t, |x| x.spindle_mrpm) {
                        near(v, want, rpm);
                    }
                });
                if let Some(want) = r.angle_at(t) {
                    near_angle(&mut s.spindle_mdeg, want);
                }
            }
            Event::End(end) => {
                let Some(want) = ref_end else { continue };
                for a in r.axes() {
                    near(&mut end.state.axes[a.index], want.state.axes[a.index] as f64, pos);
                    near(&mut end.command[a.index], want.command[a.index] as f64, pos);
                }
                near(&mut end.state.spindle_mrpm, want.state.spindle_mrpm as f64, rpm);
                near_angle(&mut end.state.spindle_mdeg, want.state.spindle_mdeg as f64);
            }
            _ => {}
        }
    }
    out
}

/// How far from the expected values a controller's values may lie (DEC-156): positions
/// `keypoint_mm`, the spindle speed `speed_rpm`, its angle [`ANGLE_MDEG`], the tolerances under
/// which [`snap`] reads a value as the reference's.
pub fn slack(tol: &Tolerances) -> Slack {
    Slack {
        position_nm: crate::check::tolerance::mm_nm(tol.keypoint_mm).max(0),
        speed_mrpm: (tol.speed_rpm.max(0.0) * 1000.0).round() as i64,
        angle_mdeg: ANGLE_MDEG,
    }
}

/// ` (within 0.02 mm, 5 rpm, 0.5°)`: the slack as the failure text gives it.
fn describe(s: &Slack) -> String {
    let f = crate::scenario::timeline::fixed;
    format!(" (within {} mm, {} rpm, {}°)", f(s.position_nm, 6), f(s.speed_mrpm, 3), f(s.angle_mdeg, 3))
}

/// The spindle angle tolerance of expectations on a controller, milli-degrees (0.5°).
pub const ANGLE_MDEG: i64 = 500;
