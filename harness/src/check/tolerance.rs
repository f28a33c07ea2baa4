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
        nc_engine::units::round_i64(ms * 1000.0)
    } else {
        0
    }
}

/// Millimetres to nm.
pub fn mm_nm(mm: f64) -> i64 {
    if mm.is_finite() && mm > 0.0 {
        nc_engine::units::round_i64(mm * 1e6)
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
    /// The first motion of the tap axis (beyond `position_mm` from where it stood; without a
    /// tap, of the axis that moves first in the reference): for a recording that carries neither
    /// functions nor the cycle-start and rigid-tapping signals.
    TapMotion,
    /// The first start of the spindle (its speed beyond `speed_rpm` from where it stood).
    SpindleStart,
}

impl Anchor {
    /// Parses `M29`, `S1000`, `STL`, `RGTAP:0`, `motion` (the first motion of the tap axis),
    /// `offset:-1500` (µs).
    pub fn parse(s: &str) -> Option<Anchor> {
        if s.eq_ignore_ascii_case("motion") {
            return Some(Anchor::TapMotion);
        }
        if s.eq_ignore_ascii_case("spindle") {
            return Some(Anchor::SpindleStart);
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
            Anchor::TapMotion => "first motion of the tap axis (else the first axis to move)".into(),
            Anchor::SpindleStart => "first spindle start".into(),
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
    /// The rule of the synchronised move the reference is in then (`sync_rule`).
    pub sync_rule: Option<&'static str>,
    /// The reference is in a synchronised move then (a rigid stroke, a thread pass, ...).
    pub in_sync: bool,
}

/// The M codes that are not spindle clamp codes.
const PLAIN_M: [u32; 9] = [0, 1, 2, 3, 4, 5, 19, 29, 30];

/// The rule ids of one dialect for what a divergence can be about (`docs/checking.md`, "Rule ids
/// of divergences"): each list in order of preference, the first the scenario cites winning.
struct Ids {
    /// SPL/STL edges, and motion under a feed hold.
    feed_hold: &'static [&'static str],
    dry_run: &'static [&'static str],
    machine_lock: &'static [&'static str],
    /// Motion or the final speed after a reset.
    reset: &'static [&'static str],
    /// The final spindle speed otherwise.
    end_speed: &'static [&'static str],
    /// Peck count, depths, retract heights, reversals.
    pecks: &'static [&'static str],
    /// Hole bottom, return level.
    bottom: &'static [&'static str],
    /// The pause at the bottom.
    dwell: &'static [&'static str],
    /// A spindle clamp M code (GSK).
    clamp: &'static [&'static str],
}

fn ids(dialect: &str) -> Ids {
    match dialect {
        "gsk-lathe" => Ids {
            feed_hold: &["GSK-RT-27", "GSK-G923-12"],
            dry_run: &["GSK-RT-23", "GSK-G923-14"],
            machine_lock: &["GSK-RT-24", "GSK-G923-14"],
            reset: &["GSK-RT-25", "GSK-G923-15"],
            end_speed: &["GSK-RT-29"],
            pecks: &["GSK-RT-08", "GSK-RT-09", "GSK-G923-05"],
            bottom: &["GSK-RT-03", "GSK-G923-05"],
            dwell: &["GSK-RT-04"],
            clamp: &["GSK-RT-11"],
        },
        "linuxcnc" => Ids {
            feed_hold: &["LCNC-INP-04", "LCNC-TAP-02", "LCNC-G331-03", "LCNC-G76-04"],
            dry_run: &["LCNC-INP-02"],
            machine_lock: &["LCNC-INP-03"],
            reset: &["LCNC-INP-04", "LCNC-G331-03", "COM-INP-05"],
            end_speed: &["COM-MOT-06"],
            pecks: &["LCNC-CYC-07", "LCNC-G76-01"],
            bottom: &["LCNC-CYC-04", "LCNC-CYC-03", "LCNC-G331-02"],
            dwell: &["LCNC-CYC-07", "LCNC-CYC-06"],
            clamp: &[],
        },
        "heidenhain" => Ids {
            feed_hold: &["HDH-C832-16"],
            dry_run: &["HDH-C832-15"],
            machine_lock: &["HDH-C832-16"],
            reset: &["HDH-C832-16"],
            end_speed: &["HDH-LEX-04"],
            pecks: &["HDH-C832-07", "HDH-C832-10"],
            bottom: &["HDH-C832-06", "HDH-C832-11"],
            dwell: &["HDH-C832-09"],
            clamp: &[],
        },
        "knd-lathe" => Ids {
            feed_hold: &["COM-INP-02"],
            dry_run: &["COM-MOT-05"],
            machine_lock: &["COM-MOT-04"],
            reset: &["COM-INP-05", "KND-CSS-06"],
            end_speed: &["KND-G93-09", "COM-MOT-06"],
            pecks: &["KND-G93-03"],
            bottom: &["KND-G93-04", "KND-G93-05"],
            dwell: &["KND-G93-04", "KND-G93-06"],
            clamp: &[],
        },
        _ => Ids {
            feed_hold: &["FAN-RT-15"],
            dry_run: &["COM-MOT-05"],
            machine_lock: &["COM-MOT-04"],
            reset: &["FAN-RT-14"],
            end_speed: &["FAN-RT-14"],
            pecks: &["FAN-RT-05", "FAN-RT-04"],
            bottom: &["FAN-RT-03"],
            dwell: &["FAN-RT-03"],
            clamp: &[],
        },
    }
}

/// The rule of a synchronised move by the block's G code (`sync::Window::code`).
pub fn sync_rule(dialect: &str, code: Option<&str>) -> Option<&'static str> {
    if dialect == "heidenhain" {
        return Some("HDH-C832-05");
    }
    Some(match (dialect, code?) {
        ("gsk-lathe", "G92.3") => "GSK-G923-11",
        ("knd-lathe", "G32" | "G92") => "KND-LEX-08",
        ("knd-lathe", "G93") => "KND-G93-03",
        ("linuxcnc", "G33.1") => "LCNC-G331-01",
        ("linuxcnc", "G33") => "LCNC-G33-01",
        ("linuxcnc", "G76") => "LCNC-G76-01",
        _ => return None,
    })
}

/// The rule id a divergence breaks: the first candidate the scenario cites, else the first.
pub fn attribute(topic: Topic, ctx: &Context) -> String {
    let d = ids(&ctx.dialect);
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
        cands.extend(d.feed_hold);
    }
    if matches!(topic, Topic::Envelope | Topic::Bottom | Topic::Pecks | Topic::Sync | Topic::Dwell) {
        if ctx.overload {
            cands.push("GSK-RT-26");
        }
        if has("machine_lock") {
            cands.extend(d.machine_lock);
        }
        if has("dry_run") {
            cands.extend(d.dry_run);
        }
        if has("reset") {
            cands.extend(d.reset);
        }
        if has("feed_hold") {
            cands.extend(d.feed_hold);
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
        Topic::Function('M', c) if !d.clamp.is_empty() && !PLAIN_M.contains(&c) => cands.extend(d.clamp),
        Topic::Function('M', 29) => cands.push("COM-PLC-02"),
        Topic::Function(..) => cands.push("COM-PLC-01"),
        Topic::Alarm => {}
        Topic::Pecks | Topic::Reversals => cands.extend(d.pecks),
        Topic::Bottom => cands.extend(d.bottom),
        Topic::Dwell => cands.extend(d.dwell),
        Topic::Sync => {
            cands.extend(ctx.sync_rule);
            cands.push("COM-SYNC-01");
        }
        Topic::Envelope if ctx.in_sync || ctx.phase.is_none() => {
            cands.extend(ctx.sync_rule);
            cands.push("COM-SYNC-01");
        }
        // A position off outside any synchronised move: the motion's own rule.
        Topic::Envelope => match (ctx.dialect.as_str(), ctx.phase) {
            ("linuxcnc", Some(Phase::Cutting | Phase::Dwell | Phase::Retract | Phase::Positioning)) => {
                cands.extend(["LCNC-CYC-03", "LCNC-MOD-02"])
            }
            ("linuxcnc", _) => cands.push("LCNC-MOD-02"),
            (_, Some(Phase::Cutting | Phase::Dwell)) => cands.push("COM-MOT-02"),
            _ => cands.push("COM-MOT-01"),
        },
        Topic::End => {
            if has("reset") {
                cands.extend(d.reset);
            }
            cands.extend(d.end_speed);
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
        assert_eq!(Anchor::parse("spindle"), Some(Anchor::SpindleStart));
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

    /// Issue 14 §5: no dialect falls back to another dialect's ids (LinuxCNC, Heidenhain and KND
    /// were given FAN-RT-14/15).
    #[test]
    fn every_dialect_gets_its_own_ids() {
        for dialect in nc_engine::dialect_names() {
            let ctx = |inputs: &[&str]| Context {
                dialect: dialect.into(),
                inputs: inputs.iter().map(|s| s.to_string()).collect(),
                ..Context::default()
            };
            let family = match dialect {
                "gsk-lathe" => "GSK-",
                "fanuc-mill" => "FAN-",
                "linuxcnc" => "LCNC-",
                "heidenhain" => "HDH-",
                _ => "KND-",
            };
            let got = [
                attribute(Topic::Edge(Signal::Stl, false), &ctx(&[])),
                attribute(Topic::Envelope, &ctx(&["reset"])),
                attribute(Topic::Pecks, &ctx(&[])),
                attribute(Topic::Bottom, &ctx(&[])),
                attribute(Topic::End, &ctx(&["reset"])),
            ];
            for (k, g) in got.iter().enumerate() {
                let other = ["GSK-", "FAN-", "LCNC-", "HDH-", "KND-"]
                    .iter()
                    .any(|f| *f != family && g.starts_with(f));
                assert!(!other, "{dialect}: topic {k} attributed to {g}");
            }
            if dialect != "knd-lathe" {
                assert!(got[2].starts_with(family), "{dialect}: pecks → {}", got[2]);
            }
        }
        let lc = Context {
            dialect: "linuxcnc".into(),
            sync_rule: sync_rule("linuxcnc", Some("G76")),
            ..Context::default()
        };
        assert_eq!(attribute(Topic::Sync, &lc), "LCNC-G76-01");
        // A position off outside any synchronised move is the motion's, not COM-SYNC-01.
        let drill =
            Context { dialect: "linuxcnc".into(), phase: Some(Phase::Positioning), ..Context::default() };
        assert_eq!(attribute(Topic::Envelope, &drill), "LCNC-CYC-03");
        let rapid = Context { dialect: "gsk-lathe".into(), phase: Some(Phase::Idle), ..Context::default() };
        assert_eq!(attribute(Topic::Envelope, &rapid), "COM-MOT-01");
        let stroke = Context { in_sync: true, ..rapid };
        assert_eq!(attribute(Topic::Envelope, &stroke), "COM-SYNC-01");
    }
}
