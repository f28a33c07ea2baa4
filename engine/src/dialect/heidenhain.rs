//! `heidenhain`: a Heidenhain TNC in turning mode (seed 004: cycle 832 THREAD EXTENDED, and the
//! Klartext program blocks a threading program uses).
//!
//! Programs are Klartext, not letter-address G-code: [`crate::parse::klartext`] reads them. X is
//! a diameter, Z the turning axis. Owns the parameter table and the interpreter of this dialect
//! (rules HDH-* in `docs/rules/heidenhain.md`).

mod cycle832;
mod interp;

use super::common::rows::*;
use crate::dialect::{Dialect, Interpreter};
use crate::exec::PlantConfig;
use crate::params::{bit, num, ParamDef, ParamKind::*, Params};
use crate::parse::{LexRules, ParseError, Program};
use crate::trace::AxisSpec;

/// The Heidenhain turning dialect.
#[derive(Debug)]
pub struct Heidenhain;

/// Klartext has no word letters; these rules only name the dialect (the Klartext parser is used).
static LEX: LexRules = LexRules { dialect: "heidenhain", letters: "", semicolon_ends_block: false };

static AXES: [AxisSpec; 2] = [
    AxisSpec { letter: 'X', index: 0, diameter: true, rotary: false },
    AxisSpec { letter: 'Z', index: 2, diameter: false, rotary: false },
];

/// Parameters of `heidenhain`. Seed 004 gives no machine parameter numbers: the cautions' checks
/// and the plant are the project's `hei.*` / `nc.*` / `plc.*` model (DEC-70).
pub static PARAMS: &[ParamDef] = &[
    num("hei.flank_angle_deg", "thread flank angle", Real, 0.0, 90.0, 30.0, "deg", "Flank angle of the thread profile (half the thread angle: 30 for a 60° ISO metric thread). An infeed angle Q467 above it raises NC-1074 (seed 004 caution)."),
    bit("hei.neg_diameter_alarm", "negative diameter check", 1.0, "1: cycle 832 called with the tool at a negative diameter raises NC-1075; 0: the cycle runs, Q471 acting reversed (seed 004 caution)."),
    ParamDef { doc: "Backlash of each axis, compensated on reversals of rapid moves.", ..BACKLASH_MM },
    PERIOD_US,
    RAPID_MM_MIN,
    RAPID_RAMP_MS,
    ParamDef { doc: "Upper limit of the cutting feed; a thread pass faster than it raises NC-1077.", ..FEED_MAX_MM_MIN },
    ParamDef { doc: "Time to reach the maximum cutting feed (thread passes accelerate within Q465, stop within Q466).", ..FEED_RAMP_MS },
    FEED_OVERRIDE_MAX_PCT,
    FEED_OVERRIDE_STEP_PCT,
    SPINDLE_OVERRIDE_MIN_PCT,
    SPINDLE_OVERRIDE_MAX_PCT,
    ParamDef { doc: "Feed of L moves with F under dry run (not of thread passes).", ..DRY_RUN_MM_MIN },
    ParamDef { default: 3000.0, ..SPINDLE_MAX_RPM },
    SPINDLE_RAMP_MS,
    FIN_MS,
    FIN_FALL_MS,
    FIN_TIMEOUT_MS,
    ZSP_MS,
];

impl Dialect for Heidenhain {
    fn name(&self) -> &'static str {
        "heidenhain"
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
        super::common::plant_config(p, "nc.rapid_mm_min", "nc.rapid_ramp_ms", "nc.backlash_mm")
    }
    fn interpreter(&self, params: &Params) -> Box<dyn Interpreter> {
        Box::new(interp::HeiInterp::new(params))
    }
    fn parse(&self, text: &str) -> Result<Program, ParseError> {
        crate::parse::klartext::parse(text, "heidenhain")
    }
}
