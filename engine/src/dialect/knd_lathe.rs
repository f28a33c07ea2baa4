//! `knd-lathe`: KND lathe control (seed 001: the G93 tapping cycle and the program basics a
//! tapping program uses).
//!
//! X is a diameter, U/W are the incremental forms of X/Z, G98/G99 are feed per minute / per
//! revolution (feed per minute at power-on). Owns the parameter table and the interpreter of this
//! dialect (rules KND-* in `docs/rules/knd-lathe.md`).

mod interp;

use super::common::rows::*;
use crate::dialect::{Dialect, Interpreter};
use crate::exec::PlantConfig;
use crate::params::{bit, num, ParamDef, ParamKind::*, Params};
use crate::parse::LexRules;
use crate::trace::AxisSpec;

/// The KND lathe dialect.
#[derive(Debug)]
pub struct KndLathe;

static LEX: LexRules =
    LexRules { dialect: "knd-lathe", letters: "DFGIJKLMNOPQRSTUWXZ", semicolon_ends_block: true };

static AXES: [AxisSpec; 2] = [
    AxisSpec { letter: 'X', index: 0, diameter: true, rotary: false },
    AxisSpec { letter: 'Z', index: 2, diameter: false, rotary: false },
];

/// Parameters of `knd-lathe`. Seed 001 names P003 RVDL; it gives no number for the brake time,
/// the backlash or the timers, which are the project's `nc.*` / `plc.*` model (DEC-50).
pub static PARAMS: &[ParamDef] = &[
    bit("003.RVDL", "RVDL", 1.0, "1: a reversal of the tap axis in G93 takes up its backlash first (the tap stands while the spindle turns); 0: G93 does not compensate backlash (seed 001 note 5)."),
    ParamDef { doc: "Backlash of each axis, compensated on every reversal (G93: see 003.RVDL).", ..BACKLASH_MM },
    num("nc.spindle_brake_ms", "spindle brake time", Int, 1.0, 60000.0, 300.0, "ms", "Time the braked spindle takes from its speed to rest; the G93 tap follows it meanwhile (seed 001 notes 6, 10)."),
    num("nc.g93_allowance_mm", "G93 overshoot allowance", Real, 0.001, 1000.0, 50.0, "mm", "How far past the end point the braking G93 tap may go (seed 001 note 10: 50 mm); beyond: NC-1050."),
    num("nc.g93_zsp_timeout_ms", "G93 zero-speed timer", Int, 1.0, 600000.0, 5000.0, "ms", "No zero speed (ZSP) this long after a G93 stop: NC-1051 (the tap would never retract)."),
    PERIOD_US,
    INCREMENT_NM,
    ParamDef { doc: "1: a word without decimal point is in mm (Z50 = 50 mm); 0: in least input increments.", ..DPI },
    RAPID_MM_MIN,
    RAPID_RAMP_MS,
    ParamDef { doc: "Upper limit of the cutting feed (seed 001 names parameter P25 for it).", ..FEED_MAX_MM_MIN },
    FEED_RAMP_MS,
    ParamDef { default: 150.0, doc: "Top position of the feed override switch; a larger input acts as it (DEC-112). Seed 001: 0..150 % (\"调整范围是(0%~150%)\").", ..FEED_OVERRIDE_MAX_PCT },
    ParamDef { default: 10.0, doc: "Seed 001: 10 % (\"0~150%档(每档10%)\"). Step between the feed override switch's positions; an input between two acts as the lower one (DEC-112).", ..FEED_OVERRIDE_STEP_PCT },
    SPINDLE_OVERRIDE_MIN_PCT,
    SPINDLE_OVERRIDE_MAX_PCT,
    DRY_RUN_MM_MIN,
    ParamDef { default: 3000.0, ..SPINDLE_MAX_RPM },
    ParamDef { doc: "Time from 0 to the maximum spindle speed (speed mode; the G93 return follows it).", ..SPINDLE_RAMP_MS },
    FIN_MS,
    FIN_FALL_MS,
    FIN_TIMEOUT_MS,
    ZSP_MS,
];

impl Dialect for KndLathe {
    fn name(&self) -> &'static str {
        "knd-lathe"
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
        let mut c = super::common::plant_config(p, "nc.rapid_mm_min", "nc.rapid_ramp_ms", "nc.backlash_mm");
        // The G93 brake: the physics invariants judge a braking spindle by it (INV-12).
        c.spindle_brake_us = (p.get("nc.spindle_brake_ms") * 1000.0) as crate::units::Micros;
        c
    }
    fn interpreter(&self, params: &Params) -> Box<dyn Interpreter> {
        Box::new(interp::KndInterp::new(params))
    }
}
