//! `expect.invariants` of a scenario: the engine's invariants (docs/invariants.md) checked on the
//! scenario's run, with the context the trace alone cannot give (the tap's lead, the alarm of an
//! out-of-range word) and an optional comparison run. Regression scenarios written by the property
//! campaigns use it; any scenario may.

use nc_engine::invariants::{physics, Context, Invariant, RangeAlarm, TapSpec};
use nc_engine::{AlarmKind, Machine, Program, RunOptions, Trace};
use serde::Deserialize;
use serde_saphyr::Spanned;

use super::expect::Verdict;
use super::resolve::{mm_to_nm, ms_to_us, Ctx};
use crate::campaign::oracle::{check_run, CompareRun};
use crate::diag::InputError;

/// `expect.invariants` as written.
#[derive(Debug, Deserialize, Clone, Default)]
#[serde(deny_unknown_fields)]
pub struct InvariantsSpec {
    /// The tap: `{axis: Z, lead: 1.25, tolerance: 0.002}` (mm), for INV-04 and INV-09.
    #[serde(default)]
    pub tap: Option<TapYaml>,
    /// The alarm of the program's out-of-range word: `{code: NC-1001, line: 4}` (INV-03).
    #[serde(default)]
    pub range_alarm: Option<RangeAlarmYaml>,
    /// The spindle speed commanded before M29, rpm signed (INV-08).
    #[serde(default)]
    pub pre_m29_rpm: Option<i64>,
    /// Feed hold and single block are suppressed in rigid tapping (INV-05).
    #[serde(default)]
    pub hold_suppressed: bool,
    /// A comparison run: `{dry_run_at_ms: 120}` (INV-06) or `{machine_lock: true}` (INV-07).
    #[serde(default)]
    pub compare: Option<CompareYaml>,
}

/// The tap of `expect.invariants`.
#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct TapYaml {
    /// Tap axis letter.
    pub axis: Spanned<String>,
    /// Lead, mm per revolution.
    pub lead: f64,
    /// Allowed synchronisation error, mm (default 0.002).
    #[serde(default)]
    pub tolerance: Option<f64>,
}

/// The expected range alarm.
#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct RangeAlarmYaml {
    /// Alarm code.
    pub code: Spanned<String>,
    /// Program line.
    pub line: u32,
}

/// The comparison run.
#[derive(Debug, Deserialize, Clone, Default)]
#[serde(deny_unknown_fields)]
pub struct CompareYaml {
    /// Dry run switched on at this time, ms.
    #[serde(default)]
    pub dry_run_at_ms: Option<f64>,
    /// Machine lock from the start.
    #[serde(default)]
    pub machine_lock: bool,
}

/// Resolved `expect.invariants`.
#[derive(Debug, Clone)]
pub struct InvariantCheck {
    /// What the invariants need to know.
    pub ctx: Context,
    /// The comparison run.
    pub compare: Option<CompareRun>,
}

/// Resolves `expect.invariants`.
///
/// # Errors
///
/// An unknown axis or alarm code, a non-positive lead, or both comparisons at once, located.
pub fn resolve(ctx: &Ctx, spec: &Spanned<InvariantsSpec>) -> Result<InvariantCheck, InputError> {
    let s = &spec.value;
    let tap = match &s.tap {
        None => None,
        Some(t) => {
            let axis = ctx.axis(&t.axis)?;
            if t.lead.is_nan() || t.lead <= 0.0 {
                return Err(ctx.err(
                    &t.axis,
                    format!("lead {} is not a lead", t.lead),
                    "lead: a length > 0 in mm",
                ));
            }
            Some(TapSpec {
                axis: axis.index,
                lead_nm: mm_to_nm(t.lead),
                tolerance_nm: mm_to_nm(t.tolerance.unwrap_or(0.002).abs()),
            })
        }
    };
    let range_alarm = match &s.range_alarm {
        None => None,
        Some(r) => {
            let kind =
                AlarmKind::ALL.iter().copied().find(|k| k.code() == r.code.value).ok_or_else(|| {
                    ctx.err(
                        &r.code,
                        format!("unknown alarm code `{}`", r.code.value),
                        "a code of docs/alarms.md (NC-1001, 0200, ...)",
                    )
                })?;
            Some(RangeAlarm { kind, line: r.line })
        }
    };
    let compare = match &s.compare {
        None => None,
        Some(CompareYaml { dry_run_at_ms: Some(ms), machine_lock: false }) => {
            Some(CompareRun::DryRunAt(ms_to_us(*ms)))
        }
        Some(CompareYaml { dry_run_at_ms: None, machine_lock: true }) => Some(CompareRun::MachineLock),
        Some(_) => {
            return Err(ctx.err(
                spec,
                "`compare` has exactly one of `dry_run_at_ms` and `machine_lock: true`",
                "compare: {dry_run_at_ms: 0} or compare: {machine_lock: true}",
            ))
        }
    };
    let ctx = Context {
        tap,
        range_alarm,
        pre_m29_mrpm: s.pre_m29_rpm.map(|r| r.saturating_mul(1000)),
        hold_suppressed: s.hold_suppressed,
    };
    Ok(InvariantCheck { ctx, compare })
}

/// The invariants that `check` asks for, one verdict each, reported under their ids.
pub fn evaluate(check: &InvariantCheck, m: &Machine, program: &Program, opts: &RunOptions) -> Vec<Verdict> {
    let (_, violations) = check_run(m, program, opts, &check.ctx, check.compare);
    let c = &check.ctx;
    let asked = Invariant::ALL.into_iter().filter(|i| match i {
        Invariant::RangeAlarmNoMotion => c.range_alarm.is_some(),
        Invariant::TapSync => c.tap.is_some(),
        Invariant::HoldDeferredInTapping => c.hold_suppressed,
        Invariant::DryRunKeepsTapFeed => matches!(check.compare, Some(CompareRun::DryRunAt(_))),
        // Checked on every scenario by `run::run` (INV-11..INV-14).
        i if Invariant::PHYSICS.contains(i) => false,
        _ => true,
    });
    asked
        .map(|inv| {
            let v = violations.iter().find(|v| v.invariant == inv);
            Verdict {
                rule: inv.id().to_string(),
                what: format!("invariant {}", inv.name()),
                pass: v.is_none(),
                t_us: v.map(|v| v.t_us),
                expected: format!("{} holds", inv.name()),
                actual: v.map_or_else(|| "it holds".to_string(), |v| v.detail.clone()),
            }
        })
        .collect()
}

/// One verdict per physics invariant (INV-11..INV-14) on `trace`, under `m`'s own limits.
pub fn physics_verdicts(trace: &Trace, m: &Machine, tap: Option<TapSpec>) -> Vec<Verdict> {
    let violations = physics::check(trace, &physics::Limits::of(m), tap);
    Invariant::PHYSICS
        .into_iter()
        .filter(|i| *i != Invariant::FollowsSpindle || tap.is_some())
        .map(|inv| {
            let v = violations.iter().find(|v| v.invariant == inv);
            Verdict {
                rule: inv.id().to_string(),
                what: format!("invariant {}", inv.name()),
                pass: v.is_none(),
                t_us: v.map(|v| v.t_us),
                expected: format!("{} holds", inv.name()),
                actual: v.map_or_else(|| "it holds".to_string(), |v| v.detail.clone()),
            }
        })
        .collect()
}
