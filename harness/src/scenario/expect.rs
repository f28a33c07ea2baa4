//! What a scenario expects (`expect:`), resolved against the dialect and checked against a trace.
//!
//! [`resolve`] turns [`schema::Expect`] into [`Expectations`], checking every name (signals, axes,
//! phases, end reasons, input names, rule ids, the form of alarm codes and modal codes) with an
//! error located at the offending text where the schema keeps a location; [`evaluate`] gives one
//! [`Verdict`] per expectation. States are those of the [`Timeline`]: after every event at a time.
//!
//! - Values: positions in mm (degrees on rotary axes, a lathe's X as a diameter), compared in nm;
//!   speeds in rpm, compared in milli-rpm; an exact value matches within 1 nm / 1 milli-rpm.
//! - `alarms`: exactly these, in order (code, and line / time ± tolerance when given).
//! - `checks`: the state at the last instant at or before `at_ms`, or before the time `when` first
//!   holds (+ `delay_ms`), the events at that time included; fails when the condition never holds
//!   or the run ended before that time.
//! - `always`: the window is the instants where `while` holds (stretches of consecutive
//!   instants), or every instant from the one where `after` first holds, or the whole run. An
//!   empty window fails ("window never opened"). `still`, `spindle_still` and `never_beyond`
//!   compare each instant with the first sampled instant of its stretch; `never_rises` counts the
//!   rises (edges, including zero-width pulses) after a stretch's first instant.
//! - `reached`: the first instant where `state` (and `during`) hold; or the first `input` event
//!   whose state just before it (same-time events listed before it included) satisfies `during`.

use std::ops::Range;

use nc_engine::input::Condition;
use nc_engine::trace::{EndReason, Event, Phase, Sample, Signal, Trace};
use nc_engine::units::{Micros, Nm};
use serde::Serialize;
use serde_saphyr::Spanned;

use super::resolve::{mm_to_nm, ms_to_us, Ctx};
use super::schema::{self, Compare, StateSpec};
use super::timeline::{
    describe_condition, fixed, ms, show, Cmp, Departure, Item, Obs, Slack, State, Timeline, Unit,
};
use crate::diag::{InputError, Span};

/// The outcome of one expectation.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Verdict {
    /// The rule id the expectation proves (`alarms` and `end` use the scenario's first rule).
    pub rule: String,
    /// Which expectation: `alarms`, `end`, `check #2`, `always #1 (still Z)`, `reached #1`.
    pub what: String,
    /// Whether it held.
    pub pass: bool,
    /// Time of the first violation, or of the observation.
    pub t_us: Option<u64>,
    /// What was expected, human readable with units.
    pub expected: String,
    /// What the trace shows.
    pub actual: String,
}

/// A scenario's expectations, resolved and validated.
#[derive(Debug, Clone)]
pub struct Expectations {
    default_rule: String,
    alarms: Option<Vec<AlarmExp>>,
    end: Option<EndExp>,
    checks: Vec<CheckExp>,
    always: Vec<AlwaysExp>,
    reached: Vec<ReachedExp>,
}

impl Expectations {
    /// The rule `alarms` and `end` verdicts are reported under.
    pub fn default_rule(&self) -> &str {
        &self.default_rule
    }

    /// Whether nothing at all is expected.
    pub fn is_empty(&self) -> bool {
        self.alarms.is_none()
            && self.end.is_none()
            && self.checks.is_empty()
            && self.always.is_empty()
            && self.reached.is_empty()
    }

    /// The rule ids the checks, temporal rules and `reached` entries cite, in order, without
    /// repeats.
    pub fn rules(&self) -> Vec<&str> {
        let all = self.checks.iter().map(|c| &c.rule);
        let all = all.chain(self.always.iter().map(|a| &a.rule)).chain(self.reached.iter().map(|r| &r.rule));
        let mut out: Vec<&str> = Vec::new();
        for r in all {
            if !out.contains(&r.as_str()) {
                out.push(r);
            }
        }
        out
    }
}

#[derive(Debug, Clone)]
struct AlarmExp {
    code: String,
    line: Option<u32>,
    at: Option<(Micros, Micros)>,
}

#[derive(Debug, Clone)]
struct EndExp {
    reason: Option<EndReason>,
    at: Option<(Micros, Micros)>,
    modal: Vec<String>,
    state: State,
}

/// A condition with its occurrence, delay and description.
#[derive(Debug, Clone)]
struct Cond {
    cond: Condition,
    occurrence: u32,
    delay: Micros,
    desc: String,
}

impl Cond {
    fn time(&self, tl: &Timeline) -> Option<Micros> {
        tl.first_time(&self.cond, self.occurrence).map(|t| t.saturating_add(self.delay))
    }
}

#[derive(Debug, Clone)]
enum Moment {
    At(Micros),
    When(Cond),
}

#[derive(Debug, Clone)]
struct CheckExp {
    rule: String,
    moment: Moment,
    state: State,
}

#[derive(Debug, Clone)]
enum Window {
    Whole,
    While(State),
    After(Cond),
}

#[derive(Debug, Clone, Copy)]
struct AxisRef {
    letter: char,
    slot: usize,
    unit: Unit,
}

#[derive(Debug, Clone)]
enum Property {
    Holds(State),
    Still(AxisRef),
    SpindleStill,
    NeverBeyond { axis: AxisRef, down: bool },
    NeverRises(Signal),
}

#[derive(Debug, Clone)]
struct AlwaysExp {
    rule: String,
    window: Window,
    props: Vec<Property>,
}

#[derive(Debug, Clone)]
enum Target {
    State(State),
    Input(String),
}

#[derive(Debug, Clone)]
struct ReachedExp {
    rule: String,
    target: Target,
    during: Option<State>,
}

// ---------------------------------------------------------------------------------------------
// Resolution

/// An error at `loc`, or about the whole file when the schema keeps no location there.
fn err_at(ctx: &Ctx, loc: Option<Span>, message: impl Into<String>, expected: &str) -> InputError {
    match loc {
        Some(span) => InputError::at(ctx.file, ctx.text, span, message, Some(expected.to_string())),
        None => InputError { expected: Some(expected.to_string()), ..InputError::new(ctx.file, message) },
    }
}

/// A rule id: `^(COM|GSK|FAN|KND|LCN|HDH|LCNC)-[A-Z][A-Z0-9]*-\d{2}$` (the area may hold digits after
/// its first letter: `KND-G93-04`).
fn rule_id(ctx: &Ctx, r: &Spanned<String>) -> Result<String, InputError> {
    let parts: Vec<&str> = r.value.splitn(3, '-').collect();
    let ok = parts.len() == 3
        && ["COM", "GSK", "FAN", "KND", "LCN", "HDH", "LCNC"].contains(&parts[0])
        && !parts[1].is_empty()
        && parts[1].as_bytes()[0].is_ascii_uppercase()
        && parts[1].bytes().all(|b| b.is_ascii_uppercase() || b.is_ascii_digit())
        && parts[2].len() == 2
        && parts[2].bytes().all(|b| b.is_ascii_digit());
    if ok {
        Ok(r.value.clone())
    } else {
        Err(ctx.err(
            r,
            format!("`{}` is not a rule id", r.value),
            "PREFIX-AREA-NN: PREFIX one of COM GSK FAN KND LCN HDH LCNC, AREA capital letters (then digits too), NN two digits (GSK-RT-07, KND-G93-04)",
        ))
    }
}

/// A time in ms, finite and not negative.
fn time(ctx: &Ctx, loc: Option<Span>, v: f64, key: &str) -> Result<Micros, InputError> {
    if v.is_finite() && v >= 0.0 {
        Ok(ms_to_us(v))
    } else {
        Err(err_at(ctx, loc, format!("`{key}: {v}` is not a time"), "a number of ms, 0 or more"))
    }
}

/// `at_ms` ± `tolerance_ms` (default 0), µs.
fn at_tolerance(
    ctx: &Ctx,
    loc: Option<Span>,
    at: Option<f64>,
    tol: Option<f64>,
) -> Result<Option<(Micros, Micros)>, InputError> {
    match (at, tol) {
        (Some(t), tol) => {
            Ok(Some((time(ctx, loc, t, "at_ms")?, time(ctx, loc, tol.unwrap_or(0.0), "tolerance_ms")?)))
        }
        (None, Some(_)) => Err(err_at(ctx, loc, "`tolerance_ms` without `at_ms`", "at_ms")),
        (None, None) => Ok(None),
    }
}

fn resolve_cmp(ctx: &Ctx, c: &Compare, unit: Unit, loc: Option<Span>) -> Result<Cmp, InputError> {
    let conv = |v: f64| if unit == Unit::Rpm { (v * 1e3).round() as i64 } else { mm_to_nm(v) };
    let bad = |m: &str, e: &str| Err(err_at(ctx, loc, m.to_string(), e));
    match c {
        Compare::Exact(v) if v.is_finite() => Ok(Cmp::Exact(conv(*v))),
        Compare::Exact(_) => bad("not a finite number", "a number"),
        Compare::Range(b) => {
            let all = [b.below, b.above, b.min, b.max];
            if all.iter().all(Option::is_none) {
                return bad("bounds need at least one bound", "one or more of below, above, min, max");
            }
            if all.iter().flatten().any(|v| !v.is_finite()) {
                return bad("a bound is not a finite number", "numbers");
            }
            let [below, above, min, max] = all.map(|v| v.map(conv));
            let lo = above.map(|a| a.saturating_add(1)).into_iter().chain(min).max();
            let hi = below.map(|b| b.saturating_sub(1)).into_iter().chain(max).min();
            if let (Some(lo), Some(hi)) = (lo, hi) {
                if lo > hi {
                    return bad("these bounds can never hold", "a lower bound below the upper bound");
                }
            }
            Ok(Cmp::Bounds { below, above, min, max })
        }
    }
}

/// A state; `what` names it in the error when it is empty and `allow_empty` is false.
fn resolve_state(
    ctx: &Ctx,
    s: &StateSpec,
    loc: Option<Span>,
    what: &str,
    allow_empty: bool,
) -> Result<State, InputError> {
    let mut items = Vec::new();
    for (command, map) in [(false, &s.axes), (true, &s.command)] {
        for (key, c) in &map.0 {
            let a = ctx.axis(key)?;
            let unit = Unit::of(&a);
            let name = if command { format!("command {}", a.letter) } else { a.letter.to_string() };
            let cmp = resolve_cmp(ctx, c, unit, Some(ctx.span(key)))?;
            items.push(Item::Axis { name, slot: a.index, unit, command, cmp });
        }
    }
    if let Some(c) = &s.spindle_rpm {
        items.push(Item::Rpm(resolve_cmp(ctx, c, Unit::Rpm, loc)?));
    }
    for (key, v) in &s.signals.0 {
        let sig = ctx.signal(key)?;
        if *v > 1 {
            return Err(ctx.err(key, format!("signal value {v}"), "0 or 1"));
        }
        items.push(Item::Signal(sig, *v == 1));
    }
    if let Some(p) = &s.phase {
        items.push(Item::Phase(ctx.phase(p)?));
    }
    if items.is_empty() && !allow_empty {
        let e = "at least one of axes, command, spindle_rpm, signals, phase";
        return Err(err_at(ctx, loc, format!("`{what}` is empty"), e));
    }
    Ok(State(items))
}

fn resolve_cond(ctx: &Ctx, w: &Spanned<schema::When>, delay_ms: Option<f64>) -> Result<Cond, InputError> {
    if delay_ms.is_some_and(|d| !d.is_finite() || d < 0.0) {
        return Err(ctx.err(w, "`delay_ms` is not a time", "a number of ms, 0 or more"));
    }
    let (cond, occurrence, delay) = ctx.condition(w, delay_ms)?;
    let desc = describe_condition(&cond, occurrence, delay, ctx.axes);
    Ok(Cond { cond, occurrence, delay, desc })
}

/// The names inputs have in traces: [`Input::name`](nc_engine::Input::name) of every input, and `overload_trip`, which
/// the engine writes when the overload watch trips.
const INPUT_NAMES: &str = "cycle_start reset feed_hold single_block dry_run machine_lock optional_stop \
    feed_override spindle_override emergency_stop motor_current plc_answer spindle_stall set_param overload_trip";

const END_REASONS: [EndReason; 5] =
    [EndReason::ProgramEnd, EndReason::Alarm, EndReason::Reset, EndReason::Stopped, EndReason::TimeLimit];

/// A modal G code normalised (`G00` → `G0`), or `None` when it is not one.
fn modal_code(s: &str) -> Option<String> {
    let rest = s.strip_prefix(['G', 'g'])?;
    let (int, frac) = rest.split_once('.').map_or((rest, None), |(i, f)| (i, Some(f)));
    let digits = |x: &str| !x.is_empty() && x.bytes().all(|b| b.is_ascii_digit());
    if !digits(int) || frac.is_some_and(|f| !digits(f)) {
        return None;
    }
    let int = int.trim_start_matches('0');
    let int = if int.is_empty() { "0" } else { int };
    Some(match frac {
        Some(f) => format!("G{int}.{f}"),
        None => format!("G{int}"),
    })
}

/// Resolves and validates a scenario's `expect:` section. `default_rule` (the scenario's first
/// rule id) is the rule the `alarms` and `end` verdicts are reported under.
///
/// # Errors
///
/// The first problem, located at the offending key or entry where the schema keeps a location.
pub fn resolve(ctx: &Ctx, e: &schema::Expect, default_rule: &str) -> Result<Expectations, InputError> {
    let mut alarms = None;
    if let Some(list) = &e.alarms {
        let mut v = Vec::new();
        for a in list {
            let loc = Some(ctx.span(a));
            let code = &a.value.code;
            let ok = |d: &str| d.len() == 4 && d.bytes().all(|b| b.is_ascii_digit());
            if !(ok(&code.value) || code.value.strip_prefix("NC-").is_some_and(ok)) {
                let m = format!("`{}` is not an alarm code", code.value);
                return Err(ctx.err(code, m, "four digits (\"0204\") or NC- and four digits (\"NC-1031\")"));
            }
            let at = at_tolerance(ctx, loc, a.value.at_ms, a.value.tolerance_ms)?;
            v.push(AlarmExp { code: code.value.clone(), line: a.value.line, at });
        }
        alarms = Some(v);
    }

    let end = match &e.end {
        None => None,
        Some(x) => {
            let loc = x.reason.as_ref().map(|r| ctx.span(r));
            let reason = match &x.reason {
                None => None,
                Some(r) => {
                    Some(END_REASONS.iter().find(|k| k.name() == r.value).cloned().ok_or_else(|| {
                        let m = format!("unknown end reason `{}`", r.value);
                        ctx.err(r, m, "one of program_end, alarm, reset, stopped, time_limit")
                    })?)
                }
            };
            let at = at_tolerance(ctx, loc, x.at_ms, x.tolerance_ms)?;
            let mut modal = Vec::new();
            for m in &x.modal {
                modal.push(modal_code(m).ok_or_else(|| {
                    err_at(ctx, loc, format!("end: `{m}` is not a modal G code"), "e.g. G98, G21, G80")
                })?);
            }
            let state = resolve_state(ctx, &x.state, loc, "end.state", true)?;
            if reason.is_none() && at.is_none() && modal.is_empty() && state.0.is_empty() {
                let e = "at least one of reason, at_ms, modal, state";
                return Err(err_at(ctx, loc, "`end` checks nothing", e));
            }
            Some(EndExp { reason, at, modal, state })
        }
    };

    let mut checks = Vec::new();
    for c in &e.checks {
        let loc = Some(ctx.span(c));
        let rule = rule_id(ctx, &c.value.rule)?;
        let moment = match (&c.value.at_ms, &c.value.when) {
            (Some(t), None) => {
                if c.value.delay_ms.is_some() {
                    return Err(ctx.err(c, "`delay_ms` goes with `when`, not `at_ms`", "at_ms alone"));
                }
                Moment::At(time(ctx, loc, *t, "at_ms")?)
            }
            (None, Some(w)) => Moment::When(resolve_cond(ctx, w, c.value.delay_ms)?),
            _ => return Err(ctx.err(c, "a check needs exactly one of `at_ms` and `when`", "at_ms or when")),
        };
        let state = resolve_state(ctx, &c.value.state, loc, "state", false)?;
        checks.push(CheckExp { rule, moment, state });
    }

    let mut always = Vec::new();
    for a in &e.always {
        let loc = Some(ctx.span(a));
        let r = &a.value;
        let rule = rule_id(ctx, &r.rule)?;
        let window = match (&r.while_, &r.after) {
            (None, None) => Window::Whole,
            (Some(s), None) => Window::While(resolve_state(ctx, s, loc, "while", false)?),
            (None, Some(w)) => Window::After(resolve_cond(ctx, w, None)?),
            (Some(_), Some(_)) => {
                let e = "one of `while` or `after` (neither: the whole run)";
                return Err(ctx.err(a, "a temporal rule has at most one window", e));
            }
        };
        let mut props = Vec::new();
        if let Some(s) = &r.holds {
            props.push(Property::Holds(resolve_state(ctx, s, loc, "holds", false)?));
        }
        let axis = |s: &Spanned<String>| {
            ctx.axis(s).map(|a| AxisRef { letter: a.letter, slot: a.index, unit: Unit::of(&a) })
        };
        for s in &r.still {
            props.push(Property::Still(axis(s)?));
        }
        if r.spindle_still {
            props.push(Property::SpindleStill);
        }
        if let Some(nb) = &r.never_beyond {
            let down = match nb.direction.value.as_str() {
                "down" => true,
                "up" => false,
                d => return Err(ctx.err(&nb.direction, format!("unknown direction `{d}`"), "down or up")),
            };
            props.push(Property::NeverBeyond { axis: axis(&nb.axis)?, down });
        }
        for s in &r.never_rises {
            props.push(Property::NeverRises(ctx.signal(s)?));
        }
        if props.is_empty() {
            let e = "at least one of holds, still, spindle_still, never_beyond, never_rises";
            return Err(ctx.err(a, "a temporal rule without a property checks nothing", e));
        }
        always.push(AlwaysExp { rule, window, props });
    }

    let mut reached = Vec::new();
    for x in &e.reached {
        let loc = Some(ctx.span(x));
        let rule = rule_id(ctx, &x.value.rule)?;
        let target = match (&x.value.state, &x.value.input) {
            (Some(s), None) => Target::State(resolve_state(ctx, s, loc, "state", false)?),
            (None, Some(name)) => {
                if !INPUT_NAMES.split_whitespace().any(|n| n == name) {
                    let e =
                        format!("one of {}", INPUT_NAMES.split_whitespace().collect::<Vec<_>>().join(", "));
                    return Err(ctx.err(x, format!("unknown input `{name}`"), e));
                }
                Target::Input(name.clone())
            }
            _ => {
                return Err(ctx.err(
                    x,
                    "`reached` needs exactly one of `state` and `input`",
                    "state or input",
                ))
            }
        };
        let during = match &x.value.during {
            Some(s) => Some(resolve_state(ctx, s, loc, "during", false)?),
            None => None,
        };
        reached.push(ReachedExp { rule, target, during });
    }

    Ok(Expectations { default_rule: default_rule.to_string(), alarms, end, checks, always, reached })
}

// ---------------------------------------------------------------------------------------------
// Evaluation

/// Checks every expectation against `trace`: one verdict for `alarms`, one for `end`, one per
/// check, one per property of each temporal rule (one per axis of `still`, per signal of
/// `never_rises`), one per `reached`.
pub fn evaluate(exp: &Expectations, trace: &Trace) -> Vec<Verdict> {
    evaluate_within(exp, trace, &Slack::EXACT)
}

/// [`evaluate`] with the values expected met within `slack`: what `conform` holds a controller's
/// trace to (DEC-156). Exact values and bounds of `checks`, `end.state`, `holds` and `reached`
/// states within `slack` of what they expect; `still` and `never_beyond` within `slack` of the
/// window's first sampled value; `spindle_still` within the speed and angle slack. Windows
/// (`while`), `during` and conditions (`when`, `after`), which say where to look, stay exact, as
/// do signals, phases, alarms and the end's reason and modal codes; times have their own
/// `tolerance_ms`.
pub fn evaluate_within(exp: &Expectations, trace: &Trace, slack: &Slack) -> Vec<Verdict> {
    let tl = Timeline::new(trace);
    let mut out = Vec::new();
    let v = |rule: &str, what: String, pass: bool, t_us: Option<u64>, expected: String, actual: String| {
        Verdict { rule: rule.to_string(), what, pass, t_us, expected, actual }
    };
    if let Some(a) = &exp.alarms {
        let (pass, t, e, act) = eval_alarms(a, trace);
        out.push(v(&exp.default_rule, "alarms".into(), pass, t, e, act));
    }
    if let Some(end) = &exp.end {
        let (pass, t, e, act) = eval_end(end, &tl, slack);
        out.push(v(&exp.default_rule, "end".into(), pass, t, e, act));
    }
    for (k, c) in exp.checks.iter().enumerate() {
        let (pass, t, e, act) = eval_check(c, &tl, slack);
        out.push(v(&c.rule, format!("check #{}", k + 1), pass, t, e, act));
    }
    for (k, a) in exp.always.iter().enumerate() {
        let stretches = window(&a.window, &tl);
        let wdesc = match &a.window {
            Window::Whole => String::new(),
            Window::While(s) => format!(" while {}", s.describe()),
            Window::After(c) => format!(" after {}", c.desc),
        };
        for p in &a.props {
            let what = format!("always #{} ({})", k + 1, label(p));
            let (pass, t, e, act) = if stretches.is_empty() {
                let e = format!(
                    "window{}",
                    if wdesc.is_empty() { " over the whole run".into() } else { wdesc.clone() }
                );
                (false, None, e, "window never opened".to_string())
            } else {
                let (pass, t, e, act) = eval_property(p, &stretches, &tl, slack);
                (pass, t, format!("{e}{wdesc}"), act)
            };
            out.push(v(&a.rule, what, pass, t, e, act));
        }
    }
    for (k, r) in exp.reached.iter().enumerate() {
        let (pass, t, e, act) = eval_reached(r, &tl, slack);
        out.push(v(&r.rule, format!("reached #{}", k + 1), pass, t, e, act));
    }
    out
}

/// The temporal rules of `exp` that a third-party trace can be held to, evaluated on `trace`
/// (`nc-conform check`): the `always` properties over signals and phases (`holds` with signal
/// and phase items only, `never_rises`) and the `reached` states over signals and phases. Exact
/// positions, `checks`, `end` and `alarms` are left out: the comparison checks them with
/// tolerances, and a recorded trace has no inputs or program lines.
pub fn evaluate_discrete(exp: &Expectations, trace: &Trace) -> Vec<Verdict> {
    let discrete = |s: &State| s.0.iter().all(|i| matches!(i, Item::Signal(..) | Item::Phase(_)));
    let always = exp
        .always
        .iter()
        .filter(|a| match &a.window {
            Window::While(s) => discrete(s),
            _ => true,
        })
        .map(|a| AlwaysExp {
            rule: a.rule.clone(),
            window: a.window.clone(),
            props: a
                .props
                .iter()
                .filter(|p| match p {
                    Property::Holds(s) => discrete(s),
                    Property::NeverRises(_) => true,
                    _ => false,
                })
                .cloned()
                .collect(),
        })
        .filter(|a| !a.props.is_empty())
        .collect();
    let reached = exp
        .reached
        .iter()
        .filter(|r| {
            matches!(&r.target, Target::State(s) if discrete(s)) && r.during.as_ref().is_none_or(discrete)
        })
        .cloned()
        .collect();
    let only = Expectations {
        default_rule: exp.default_rule.clone(),
        alarms: None,
        end: None,
        checks: Vec::new(),
        always,
        reached,
    };
    evaluate(&only, trace)
}

type Outcome = (bool, Option<u64>, String, String);

fn eval_alarms(exp: &[AlarmExp], trace: &Trace) -> Outcome {
    let actual: Vec<_> = trace.alarms().collect();
    let matches = |e: &AlarmExp, t: Micros, a: &nc_engine::Alarm| {
        e.code == a.kind.code()
            && e.line.is_none_or(|l| a.line == Some(l))
            && e.at.is_none_or(|(at, tol)| t.abs_diff(at) <= tol)
    };
    let first_bad = (0..exp.len().max(actual.len())).find(|&k| match (exp.get(k), actual.get(k)) {
        (Some(e), Some((t, a))) => !matches(e, *t, a),
        _ => true,
    });
    let list = |v: Vec<String>| if v.is_empty() { "no alarm".to_string() } else { v.join("; ") };
    let expected = list(
        exp.iter()
            .map(|e| {
                let mut s = e.code.clone();
                if let Some(l) = e.line {
                    s.push_str(&format!(" line {l}"));
                }
                if let Some((at, tol)) = e.at {
                    s.push_str(&format!(" at {}", ms(at)));
                    if tol > 0 {
                        s.push_str(&format!(" ±{}", ms(tol)));
                    }
                }
                s
            })
            .collect(),
    );
    let shown = list(
        actual
            .iter()
            .map(|(t, a)| match a.line {
                Some(l) => format!("{} line {l} at {}", a.kind.code(), ms(*t)),
                None => format!("{} at {}", a.kind.code(), ms(*t)),
            })
            .collect(),
    );
    let t = first_bad.and_then(|k| actual.get(k)).map(|(t, _)| *t);
    (first_bad.is_none(), t, expected, shown)
}

fn eval_end(exp: &EndExp, tl: &Timeline, slack: &Slack) -> Outcome {
    let (Some(end), Some(t_end)) = (tl.end(), tl.end_time()) else {
        return (false, None, "an end summary".into(), "the trace has no end".into());
    };
    let mut pass = true;
    let (mut e, mut a) = (Vec::new(), Vec::new());
    if let Some(r) = &exp.reason {
        pass &= *r == end.reason;
        e.push(format!("reason {}", r.name()));
        a.push(format!("reason {}", end.reason.name()));
    }
    if let Some((at, tol)) = exp.at {
        pass &= t_end.abs_diff(at) <= tol;
        e.push(if tol > 0 { format!("at {} ±{}", ms(at), ms(tol)) } else { format!("at {}", ms(at)) });
        a.push(format!("at {}", ms(t_end)));
    }
    if !exp.modal.is_empty() {
        let have: Vec<Option<String>> = end.modal.iter().map(|m| modal_code(m)).collect();
        pass &= exp.modal.iter().all(|m| have.contains(&Some(m.clone())));
        e.push(format!("modal {}", exp.modal.join(" ")));
        a.push(format!("modal {}", end.modal.join(" ")));
    }
    if !exp.state.0.is_empty() {
        let phase = tl.len().checked_sub(1).map_or(Phase::Idle, |i| tl.phase(i));
        let o = Obs { signals: end.signals, phase, sample: Some(&end.state), command: Some(&end.command) };
        pass &= exp.state.holds_within(&o, slack);
        e.push(exp.state.describe());
        a.push(exp.state.actual(&o));
    }
    (pass, Some(t_end), e.join(", "), a.join(", "))
}

fn eval_check(c: &CheckExp, tl: &Timeline, slack: &Slack) -> Outcome {
    let (t, when) = match &c.moment {
        Moment::At(t) => (Some(*t), format!("at {}", ms(*t))),
        Moment::When(cond) => (cond.time(tl), format!("when {}", cond.desc)),
    };
    let expected = format!("{} {when}", c.state.describe());
    let Some(t) = t else {
        return (false, None, expected, "condition never held".into());
    };
    if let Some(end) = tl.end_time().filter(|&e| e < t) {
        return (false, Some(t), expected, format!("the run ended at {}, before {}", ms(end), ms(t)));
    }
    let Some(i) = tl.at(t) else {
        return (false, Some(t), expected, "nothing recorded yet".into());
    };
    let o = tl.obs(i);
    (c.state.holds_within(&o, slack), Some(t), expected, c.state.actual(&o))
}

/// The window as stretches of consecutive instants.
fn window(w: &Window, tl: &Timeline) -> Vec<Range<usize>> {
    let from = match w {
        Window::Whole => Some(0),
        Window::After(c) => c.time(tl).and_then(|t| tl.at(t)),
        Window::While(s) => return tl.stretches(|o| s.holds(o)),
    };
    from.filter(|&i| i < tl.len()).map(|i| i..tl.len()).into_iter().collect()
}

fn label(p: &Property) -> String {
    match p {
        Property::Holds(_) => "holds".into(),
        Property::Still(a) => format!("still {}", a.letter),
        Property::SpindleStill => "spindle_still".into(),
        Property::NeverBeyond { axis, down } => {
            format!("never_beyond {} {}", axis.letter, if *down { "down" } else { "up" })
        }
        Property::NeverRises(s) => format!("never_rises {}", s.name()),
    }
}

fn eval_property(p: &Property, stretches: &[Range<usize>], tl: &Timeline, slack: &Slack) -> Outcome {
    let start = Some(tl.t_us(stretches[0].start));
    let instants: usize = stretches.iter().map(|r| r.len()).sum();
    let held = format!("held at all {instants} instants of the window");
    let no_sample = |e: String| (false, None, e, "no sample in the window".to_string());
    match p {
        Property::Holds(s) => {
            for i in stretches.iter().flat_map(|r| r.clone()) {
                let o = tl.obs(i);
                if !s.holds_within(&o, slack) {
                    return (false, Some(tl.t_us(i)), s.describe(), s.actual(&o));
                }
            }
            (true, start, s.describe(), held)
        }
        Property::Still(ax) | Property::NeverBeyond { axis: ax, .. } => {
            let (op, how, bad): (_, _, fn(Nm, Nm, Nm) -> bool) = match p {
                Property::NeverBeyond { down: true, .. } => (">=", "not below", |b, v, s| v < b - s),
                Property::NeverBeyond { .. } => ("<=", "not above", |b, v, s| v > b + s),
                _ => ("=", "still", |b, v, s| v.abs_diff(b) > s as u64),
            };
            let name = ax.letter;
            let s = slack.position_nm.max(0);
            match tl.first_departure(stretches, |x| x.axes[ax.slot], |b, v| bad(b, v, s)) {
                Departure::At { t0, base, t, value } => {
                    let e = format!("{name} {op} {} ({how} since {})", show(base, ax.unit), ms(t0));
                    (false, Some(t), e, format!("{name} = {}", show(value, ax.unit)))
                }
                Departure::Never => (true, start, format!("{name} {how} from the window's start"), held),
                Departure::NoSample => no_sample(format!("{name} {how}")),
            }
        }
        Property::SpindleStill => {
            let read = |s: &Sample| (s.spindle_mrpm, s.spindle_mdeg);
            let (rpm, deg) = (slack.speed_mrpm.max(0), slack.angle_mdeg.max(0));
            let turned = |b: i64, v: i64| {
                let d = (v - b).rem_euclid(360_000);
                d.min(360_000 - d)
            };
            match tl.first_departure(stretches, read, |b, v| v.0.abs() > rpm || turned(b.1, v.1) > deg) {
                Departure::At { t0, base, t, value } => {
                    let e = format!("rpm 0, angle {} deg (since {})", fixed(base.1, 3), ms(t0));
                    (false, Some(t), e, format!("rpm {}, angle {} deg", fixed(value.0, 3), fixed(value.1, 3)))
                }
                Departure::Never => (true, start, "spindle still (rpm 0, angle unchanged)".into(), held),
                Departure::NoSample => no_sample("spindle still".into()),
            }
        }
        Property::NeverRises(sig) => {
            for r in stretches {
                if let Some(i) = (r.start + 1..r.end).find(|&i| tl.rose(i, *sig)) {
                    let was = tl.signals(r.start).get(*sig) as u8;
                    let e = format!("{} does not rise (was {was} at {})", sig.name(), ms(tl.t_us(r.start)));
                    return (false, Some(tl.t_us(i)), e, format!("{} rose to 1", sig.name()));
                }
            }
            (true, start, format!("{} does not rise", sig.name()), held)
        }
    }
}

fn eval_reached(r: &ReachedExp, tl: &Timeline, slack: &Slack) -> Outcome {
    let during = |o: &Obs| r.during.as_ref().is_none_or(|d| d.holds(o));
    let dsuffix = r.during.as_ref().map_or(String::new(), |d| format!(" while {}", d.describe()));
    match &r.target {
        Target::State(s) => {
            let expected = format!("{} at some instant{dsuffix}", s.describe());
            for i in 0..tl.len() {
                let o = tl.obs(i);
                if s.holds_within(&o, slack) && during(&o) {
                    return (true, Some(tl.t_us(i)), expected, s.actual(&o));
                }
            }
            (false, None, expected, "never".into())
        }
        Target::Input(name) => {
            let expected = format!("{name} acted{dsuffix}");
            let mut miss = None;
            for (k, e) in tl.trace().events.iter().enumerate() {
                let Event::Input { name: n, .. } = &e.event else { continue };
                if n != name {
                    continue;
                }
                let o = tl.obs_before_event(k);
                let with = r.during.as_ref().map_or(String::new(), |d| format!(" with {}", d.actual(&o)));
                let text = format!("{name} acted at {}{with}", ms(e.t_us));
                if during(&o) {
                    return (true, Some(e.t_us), expected, text);
                }
                miss.get_or_insert(text);
            }
            let actual = match miss {
                Some(m) => format!("never; {m}"),
                None => format!("never; no {name} in the trace"),
            };
            (false, None, expected, actual)
        }
    }
}

#[cfg(test)]
#[path = "expect_tests.rs"]
mod tests;
