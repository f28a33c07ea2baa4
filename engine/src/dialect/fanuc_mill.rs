//! `fanuc-mill`: Fanuc / Haas milling control (seed 003: G84 / G74 tapping, R plane, G98/G99
//! return level, Q peck, K repeats; rigid with M29).
//!
//! Owns the parameter table (Fanuc numbers) and the interpreter of this dialect.

mod interp;

use super::common::rows::*;
use crate::dialect::{Dialect, Interpreter};
use crate::exec::PlantConfig;
use crate::params::{axis, bit, num, ParamDef, ParamKind::*, Params};
use crate::parse::LexRules;
use crate::trace::AxisSpec;

/// The Fanuc/Haas milling dialect.
#[derive(Debug)]
pub struct FanucMill;

static LEX: LexRules =
    LexRules { dialect: "fanuc-mill", letters: "ABCDEFGHIJKLMNOPQRSTUVWXYZ", semicolon_ends_block: true };

static AXES: [AxisSpec; 6] = [
    AxisSpec { letter: 'X', index: 0, diameter: false, rotary: false },
    AxisSpec { letter: 'Y', index: 1, diameter: false, rotary: false },
    AxisSpec { letter: 'Z', index: 2, diameter: false, rotary: false },
    AxisSpec { letter: 'A', index: 3, diameter: false, rotary: true },
    AxisSpec { letter: 'B', index: 4, diameter: false, rotary: true },
    AxisSpec { letter: 'C', index: 5, diameter: false, rotary: true },
];

/// Parameters of `fanuc-mill`, Fanuc numbers where Fanuc has one.
pub static PARAMS: &[ParamDef] = &[
    axis("1420", "rapid rate", 1.0, 240000.0, 24000.0, "mm/min", "Rapid traverse rate per axis (deg/min for rotary axes)."),
    axis("1620", "rapid time constant", 0.0, 4000.0, 100.0, "ms", "Time to reach the rapid rate."),
    num("1430", "max cutting feed", Real, 1.0, 240000.0, 10000.0, "mm/min", "Upper limit of the cutting feed."),
    num("1622", "cutting time constant", Int, 0.0, 4000.0, 64.0, "ms", "Time to reach the maximum cutting feed."),
    FEED_OVERRIDE_MAX_PCT,
    FEED_OVERRIDE_STEP_PCT,
    SPINDLE_OVERRIDE_MIN_PCT,
    SPINDLE_OVERRIDE_MAX_PCT,
    num("1410", "dry run feed", Real, 1.0, 240000.0, 5000.0, "mm/min", "Feed of cutting moves under dry run."),
    axis("1851", "backlash", 0.0, 2.0, 0.0, "mm", "Backlash per axis, compensated on every reversal."),
    num("3410", "arc radius tolerance", Real, 0.0, 999.999, 0.0, "mm", "Largest difference of start and end radius of an IJK arc (above: NC-1001); 0 = not checked, the radius changes evenly along the arc."),
    bit("3401.0", "DPI", 1.0, "1: a word without decimal point is in mm/inch (calculator type, as the seed programs are written); 0: in least input increments."),
    num("3716", "max spindle speed", Int, 1.0, 60000.0, 8000.0, "rpm", "Spindle speed limit."),
    bit("5200.0", "G84", 0.0, "1: G84/G74 are rigid tapping without M29; 0: rigid only after M29."),
    bit("5200.5", "PCP", 1.0, "Q in rigid tapping: 1 = peck, back to R after each cut (seed 003); 0 = high-speed peck, retract by 5213."),
    bit("5200.6", "FHD", 0.0, "1: feed hold and single block act during rigid tapping; 0: they wait until the return is complete."),
    num("5210", "rigid M code", Int, 0.0, 255.0, 29.0, "", "The M code that sets rigid tapping mode."),
    num("5211", "extraction override", Int, 0.0, 200.0, 100.0, "%", "Override of the rigid tap return strokes (0 = 100)."),
    num("5213", "peck return", Real, 0.0, 999.999, 1.0, "mm", "High-speed peck: retract amount d after each cut."),
    num("5241", "rigid max speed", Int, 1.0, 60000.0, 4000.0, "rpm", "Maximum S in rigid tapping (above: alarm 0200)."),
    num("5261", "rigid time constant", Int, 0.0, 4000.0, 200.0, "ms", "Shared time constant of spindle and tap axis at 5241 (scaled by S/max)."),
    bit("nc.tap_spindle_check", "tap spindle check", 1.0, "1: conventional G84/G74 with the spindle not turning in the cutting direction (or S0) raise NC-1017 (seed 003 step 0); 0: no check, they run feeding at F."),
    PERIOD_US,
    ParamDef { doc: "1000 (IS-B, 0.001 mm) or 100 (IS-C).", ..INCREMENT_NM },
    SPINDLE_RAMP_MS,
    ParamDef { doc: "Spindle orientation (M19) time: its FIN comes then, or when the spindle is at rest if later (0: instant).", ..ORIENT_MS },
    num("nc.tool_change_ms", "tool change time", Int, 0.0, 60000.0, 2000.0, "ms", "M06: strobe to FIN."),
    FIN_MS,
    FIN_FALL_MS,
    SPPOS_REQUEST_MS,
    SPPOS_REACH_MS,
    RGTAP_MS,
    RGTAP_FALL_MS,
    M29_TIMEOUT_MS,
    FIN_TIMEOUT_MS,
    ZSP_MS,
    SPINDLE_STALL_MS,
];

impl Dialect for FanucMill {
    fn name(&self) -> &'static str {
        "fanuc-mill"
    }
    fn lex_rules(&self) -> &'static LexRules {
        &LEX
    }
    fn axes(&self) -> &'static [AxisSpec] {
        &AXES
    }
    fn param_table(&self) -> &'static [ParamDef] {
        PARAMS
    }
    fn plant_config(&self, p: &Params) -> PlantConfig {
        let mut c = super::common::plant_config(p, "1420", "1620", "1851");
        c.feed_max_nm_min = p.get("1430") * 1e6;
        c.feed_ramp_us = (p.get("1622") * 1000.0) as u64;
        c.dry_run_nm_min = p.get("1410") * 1e6;
        c.spindle_max_rpm = p.get("3716") as u32;
        c.rigid_max_rpm = p.get("5241") as u32;
        c.rigid_ramp_us = (p.get("5261") * 1000.0) as u64;
        c.hold_in_rigid_tap = p.bit("5200.6");
        c.tool_change_us = (p.get("nc.tool_change_ms") * 1000.0) as u64;
        c
    }
    fn interpreter(&self, params: &Params) -> Box<dyn Interpreter> {
        Box::new(interp::FanucInterp::new(params))
    }
}
