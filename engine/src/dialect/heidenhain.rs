//! `heidenhain`: a Heidenhain TNC in turning mode (seed 004: cycle 832 THREAD EXTENDED, and the
//! Klartext program blocks a threading program uses).
//!
//! Programs are Klartext, not letter-address G-code: [`crate::parse::klartext`] reads them. X is
//! a diameter, Z the turning axis. Owns the parameter table and the interpreter of this dialect
//! (rules HDH-* in `docs/rules/heidenhain.md`).

mod cycle832;
mod interp;

use crate::dialect::{Dialect, Interpreter};
use crate::exec::PlantConfig;
use crate::params::{axis, bit, num, ParamDef, ParamKind::*, Params};
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
    axis("nc.backlash_mm", "backlash", 0.0, 2.0, 0.0, "mm", "Backlash of each axis, compensated on reversals of rapid moves."),
    num("nc.period_us", "interpolation period", Int, 1000.0, 8000.0, 1000.0, "us", "Interpolation period: 1000, 2000, 4000 or 8000."),
    axis("nc.rapid_mm_min", "rapid rate", 1.0, 240000.0, 6000.0, "mm/min", "Rapid traverse rate per axis (X as radius)."),
    axis("nc.rapid_ramp_ms", "rapid time constant", 0.0, 4000.0, 100.0, "ms", "Time to reach the rapid rate."),
    num("nc.feed_max_mm_min", "max cutting feed", Real, 1.0, 240000.0, 6000.0, "mm/min", "Upper limit of the cutting feed; a thread pass faster than it raises NC-1077."),
    num("nc.feed_ramp_ms", "cutting time constant", Int, 0.0, 4000.0, 100.0, "ms", "Time to reach the maximum cutting feed (thread passes accelerate within Q465, stop within Q466)."),
    num("nc.feed_override_max_pct", "feed override maximum", Int, 0.0, 254.0, 200.0, "%", "Top position of the feed override switch; a larger input acts as it (DEC-112). The documents of this dialect give no range: the project default."),
    num("nc.feed_override_step_pct", "feed override step", Int, 1.0, 100.0, 1.0, "%", "Step between the feed override switch's positions; an input between two acts as the lower one (DEC-112)."),
    num("nc.spindle_override_min_pct", "spindle override minimum", Int, 0.0, 254.0, 0.0, "%", "Lowest position of the spindle override switch (DEC-112). No document of this dialect gives it: the project default."),
    num("nc.spindle_override_max_pct", "spindle override maximum", Int, 0.0, 254.0, 200.0, "%", "Top position of the spindle override switch (DEC-112). No document of this dialect gives it: the project default."),
    num("nc.dry_run_mm_min", "dry run feed", Real, 1.0, 240000.0, 2000.0, "mm/min", "Feed of L moves with F under dry run (not of thread passes)."),
    num("nc.spindle_max_rpm", "max spindle speed", Int, 1.0, 60000.0, 3000.0, "rpm", "Spindle speed limit."),
    num("nc.spindle_ramp_ms", "spindle time constant", Int, 0.0, 20000.0, 1000.0, "ms", "Time from 0 to the maximum spindle speed."),
    num("plc.fin_ms", "FIN delay", Int, 0.0, 10000.0, 16.0, "ms", "Strobe to FIN."),
    num("plc.fin_fall_ms", "FIN fall delay", Int, 0.0, 10000.0, 8.0, "ms", "Strobe falling to FIN falling."),
    num("plc.fin_timeout_ms", "FIN timer", Int, 1.0, 600000.0, 10000.0, "ms", "No FIN within this time: alarm NC-1020."),
    num("plc.zsp_ms", "zero-speed detection time", Int, 0.0, 10000.0, 8.0, "ms", "The spindle must stay stopped this long before the drive reports zero speed (ZSP)."),
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
