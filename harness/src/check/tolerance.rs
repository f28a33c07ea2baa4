//! Tolerances of a comparison, the alignment anchor, and the attribution of a divergence to the
//! rule id it breaks (`docs/checking.md`).

use std::collections::BTreeMap;

use nc_engine::trace::{Phase, Signal};
use serde::{Deserialize, Serialize};

/// How far a recorded trace may stray from the reference before it diverges.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Tolerances {
    /// Time window of a discrete event (signal edge, function, alarm), ms either side.
    pub event_ms: f64,
    /// Per-event windows overriding `event_ms`: keys are signal names (`FIN`), functions (`M29`),
    /// or `alarm`.
    pub event_windows_ms: BTreeMap<String, f64>,
    /// Position envelope: mm either side of the reference's band.
    pub position_mm: f64,
    /// Position envelope: time slack in ms either side (the band is the reference's range over
    /// the window).
    pub envelope_ms: f64,
    /// Key points (hole bottom, peck depths, retract heights, return level), mm.
    pub keypoint_mm: f64,
    /// Dwell at the bottom of each peck, ms.
    pub dwell_ms: f64,
    /// Synchronisation error: tap travel − lead × revolutions, mm.
    pub sync_mm: f64,
    /// Final spindle speed, rpm.
    pub speed_rpm: f64,
}

impl Default for Tolerances {
    fn default() -> Self {
        Tolerances {
            event_ms: 20.0,
            event_windows_ms: BTreeMap::new(),
            position_mm: 0.05,
            envelope_ms: 20.0,
            keypoint_mm: 0.02,
            dwell_ms: 20.0,
            sync_mm: 0.02,
            speed_rpm: 5.0,
        }
    }
}

/// Milliseconds to µs (negative and non-finite values count as 0).
pub fn ms_us(ms: f64) -> i64 {
    if ms.is_finite() && ms > 0.0 {
        (ms * 1000.0).round() as i64
    } else {
        0
    }
}

/// Millimetres to nm.
pub fn mm_nm(mm: f64) -> i64 {
    if mm.is_finite() && mm > 0.0 {
        (mm * 1e6).round() as i64
    } else {
        0
    }
}

impl Tolerances {
    /// The window of one discrete event in µs.
    pub fn window_us(&self, key: &str) -> i64 {
        ms_us(*self.event_windows_ms.get(key).unwrap_or(&self.event_ms))
    }
}

/// Where the recorded time base is tied to the reference's.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Anchor {
    /// The first output of this function (`M29`).
    Function(char, u32),
    /// The first edge of a signal to this value (`STL`: the first cycle start).
    Edge(Signal, bool),
    /// An explicit offset: reference time = recorded time + offset.
    Offset(i64),
    /// The first motion of the tap axis (beyond `position_mm` from where it stood): for a
    /// recording that carries neither functions nor the cycle-start and rigid-tapping signals.
    TapMotion,
}

impl Anchor {
    /// Parses `M29`, `S1000`, `STL`, `RGTAP:0`, `motion` (the first motion of the tap axis),
    /// `offset:-1500` (µs).
    pub fn parse(s: &str) -> Option<Anchor> {
        if s.eq_ignore_ascii_case("motion") {
            return Some(Anchor::TapMotion);
        }
        if let Some(v) = s.strip_prefix("offset:") {
            return v.trim().parse().ok().map(Anchor::Offset);
        }
        let (name, value) = match s.split_once(':') {
            Some((n, v)) => (n, v == "1"),
            None => (s, true),
        };
        if let Some(sig) = Signal::from_name(name) {
            return Some(Anchor::Edge(sig, value));
        }
        let mut ch = name.chars();
        let letter = ch.next()?.to_ascii_uppercase();
        let code: u32 = ch.as_str().parse().ok()?;
        matches!(letter, 'M' | 'S' | 'T').then_some(Anchor::Function(letter, code))
    }

    /// The anchor as text.
    pub fn describe(&self) -> String {
        match self {
            Anchor::Function(l, c) => format!("first {l}{c}"),
            Anchor::Edge(s, v) => format!("first {} = {}", s.name(), *v as u8),
            Anchor::Offset(o) => format!("offset {o} µs"),
            Anchor::TapMotion => "first motion of the tap axis".into(),
        }
    }
}

/// What a divergence is about, for attribution to a rule id.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Topic {
    /// A signal edge.
    Edge(Signal, bool),
    /// An M/S/T function.
    Function(char, u32),
    /// An alarm.
    Alarm,
    /// Peck count or depth, retract heights.
    Pecks,
    /// Hole bottom, return level.
    Bottom,
    /// Dwell at the bottom.
    Dwell,
    /// Spindle reversals.
    Reversals,
    /// Synchronisation error.
    Sync,
    /// Position envelope.
    Envelope,
    /// The final state (spindle speed, signals).
    End,
}

/// What was going on in the reference at the divergence's time.
#[derive(Debug, Clone, Default)]
pub struct Context {
    /// Dialect name.
    pub dialect: String,
    /// Inputs that had acted by then and were still on (`dry_run`, `machine_lock`, `reset`, ...).
    pub inputs: Vec<String>,
    /// The reference was in `overload_retract` at or before that time (same cycle).
    pub overload: bool,
    /// The scenario's rule ids (preferred when several candidates fit).
    pub scenario_rules: Vec<String>,
    /// The reference's phase at that time.
    pub phase: Option<Phase>,
}

/// The M codes that are not spindle clamp codes.
const PLAIN_M: [u32; 9] = [0, 1, 2, 3, 4, 5, 19, 29, 30];

/// The rule id a divergence breaks: the first candidate the scenario cites, else the first.
pub fn attribute(topic: Topic, ctx: &Context) -> String {
    let gsk = ctx.dialect.starts_with("gsk");
    let pick = |g: &'static str, f: &'static str| if gsk { g } else { f };
    let has = |name: &str| ctx.inputs.iter().any(|i| i == name);
    let mut cands: Vec<&str> = Vec::new();
    if ctx.dialect.starts_with("knd") {
        // KND G93: the tap follows the spindle in speed mode (no RGSPP/RGSPM strokes).
        match (topic, ctx.phase) {
            (Topic::Edge(Signal::Zsp, _), _) => cands.push("KND-G93-06"),
            (Topic::Envelope | Topic::Bottom | Topic::Sync, Some(Phase::Retract)) => cands.push("KND-G93-07"),
            (Topic::Envelope | Topic::Bottom | Topic::Sync, Some(Phase::Dwell)) => {
                cands.extend(["KND-G93-04", "KND-G93-05"])
            }
            (Topic::Envelope | Topic::Bottom | Topic::Sync, Some(Phase::Cutting)) => cands.push("KND-G93-03"),
            (Topic::Function('M', 3 | 4), _) => cands.push("KND-G93-09"),
            _ => {}
        }
    }
    if let Topic::Edge(Signal::Spl | Signal::Stl, _) = topic {
        cands.push(pick("GSK-RT-27", "FAN-RT-15"));
    }
    if matches!(topic, Topic::Envelope | Topic::Bottom | Topic::Pecks | Topic::Sync | Topic::Dwell) {
        if ctx.overload {
            cands.push("GSK-RT-26");
        }
        if has("machine_lock") {
            cands.push(pick("GSK-RT-24", "COM-MOT-04"));
        }
        if has("dry_run") {
            cands.push(pick("GSK-RT-23", "COM-MOT-05"));
        }
        if has("reset") {
            cands.push(pick("GSK-RT-25", "FAN-RT-14"));
        }
        if has("feed_hold") {
            cands.push(pick("GSK-RT-27", "FAN-RT-15"));
        }
    }
    match topic {
        Topic::Edge(Signal::Rtap | Signal::Rgtap | Signal::Sppos | Signal::Spposa, false) => {
            cands.push("COM-PLC-05")
        }
        Topic::Edge(Signal::Rtap | Signal::Rgtap | Signal::Sppos | Signal::Spposa, true) => {
            cands.push("COM-PLC-02")
        }
        Topic::Edge(Signal::Rgspp | Signal::Rgspm, _) => cands.extend(["COM-SYNC-03", "COM-SYNC-04"]),
        Topic::Edge(Signal::Zsp, _) => cands.push("COM-PLC-07"),
        Topic::Edge(_, _) => cands.push("COM-PLC-01"),
        Topic::Function('M', c) if gsk && !PLAIN_M.contains(&c) => cands.push("GSK-RT-11"),
        Topic::Function('M', 29) => cands.push("COM-PLC-02"),
        Topic::Function(..) => cands.push("COM-PLC-01"),
        Topic::Alarm => {}
        Topic::Pecks | Topic::Reversals => {
            cands.extend(if gsk { ["GSK-RT-08", "GSK-RT-09"] } else { ["FAN-RT-05", "FAN-RT-04"] })
        }
        Topic::Bottom => cands.push(pick("GSK-RT-03", "FAN-RT-03")),
        Topic::Dwell => cands.push(pick("GSK-RT-04", "FAN-RT-03")),
        Topic::Sync => cands.push("COM-SYNC-01"),
        Topic::Envelope => cands.push("COM-SYNC-01"),
        Topic::End => {
            if has("reset") {
                cands.push(pick("GSK-RT-25", "FAN-RT-14"));
            }
            cands.push(pick("GSK-RT-29", "FAN-RT-14"));
        }
    }
    if let Some(c) = cands.iter().find(|c| ctx.scenario_rules.iter().any(|r| r == *c)) {
        return (*c).to_string();
    }
    cands
        .first()
        .map(|c| c.to_string())
        .or_else(|| ctx.scenario_rules.first().cloned())
        .unwrap_or_else(|| "COM-TIME-01".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn anchors_parse() {
        assert_eq!(Anchor::parse("M29"), Some(Anchor::Function('M', 29)));
        assert_eq!(Anchor::parse("STL"), Some(Anchor::Edge(Signal::Stl, true)));
        assert_eq!(Anchor::parse("RGTAP:0"), Some(Anchor::Edge(Signal::Rgtap, false)));
        assert_eq!(Anchor::parse("offset:-15"), Some(Anchor::Offset(-15)));
        assert_eq!(Anchor::parse("motion"), Some(Anchor::TapMotion));
        assert_eq!(Anchor::parse("bogus"), None);
        assert_eq!(Anchor::parse(""), None);
    }

    #[test]
    fn attribution_prefers_context_and_scenario_rules() {
        let knd = Context { dialect: "knd-lathe".into(), phase: Some(Phase::Retract), ..Context::default() };
        assert_eq!(attribute(Topic::Envelope, &knd), "KND-G93-07");
        let mut ctx = Context { dialect: "gsk-lathe".into(), ..Context::default() };
        assert_eq!(attribute(Topic::Function('M', 68), &ctx), "GSK-RT-11");
        assert_eq!(attribute(Topic::Edge(Signal::Rgtap, false), &ctx), "COM-PLC-05");
        ctx.inputs.push("dry_run".into());
        assert_eq!(attribute(Topic::Envelope, &ctx), "GSK-RT-23");
        ctx.scenario_rules.push("GSK-RT-09".into());
        assert_eq!(attribute(Topic::Pecks, &Context { inputs: vec![], ..ctx }), "GSK-RT-09");
    }
}
