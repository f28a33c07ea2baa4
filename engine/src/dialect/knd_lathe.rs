//! `knd-lathe`: KND lathe control (seed 001: the G93 tapping cycle and the program basics a
//! tapping program uses).
//!
//! X is a diameter, U/W are the incremental forms of X/Z, G98/G99 are feed per minute / per
//! revolution (feed per minute at power-on). Owns the parameter table and the interpreter of this
//! dialect (rules KND-* in `docs/rules/knd-lathe.md`).

mod interp;

use crate::dialect::{Dialect, Interpreter};
use crate::exec::PlantConfig;
use crate::params::{axis, bit, num, ParamDef, ParamKind::*, Params};
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
    axis("nc.backlash_mm", "backlash", 0.0, 2.0, 0.0, "mm", "Backlash of each axis, compensated on every reversal (G93: see 003.RVDL)."),
    num("nc.spindle_brake_ms", "spindle brake time", Int, 1.0, 60000.0, 300.0, "ms", "Time the braked spindle takes from its speed to rest; the G93 tap follows it meanwhile (seed 001 notes 6, 10)."),
    num("nc.g93_allowance_mm", "G93 overshoot allowance", Real, 0.001, 1000.0, 50.0, "mm", "How far past the end point the braking G93 tap may go (seed 001 note 10: 50 mm); beyond: NC-1050."),
    num("nc.g93_zsp_timeout_ms", "G93 zero-speed timer", Int, 1.0, 600000.0, 5000.0, "ms", "No zero speed (ZSP) this long after a G93 stop: NC-1051 (the tap would never retract)."),
    num("nc.period_us", "interpolation period", Int, 1000.0, 8000.0, 1000.0, "us", "Interpolation period: 1000, 2000, 4000 or 8000."),
    num("nc.increment_nm", "least input increment", Int, 100.0, 1000.0, 1000.0, "nm", "1000 (0.001 mm) or 100 (0.0001 mm)."),
    bit("nc.dpi", "calculator decimal point", 1.0, "1: a word without decimal point is in mm (Z50 = 50 mm); 0: in least input increments."),
    axis("nc.rapid_mm_min", "rapid rate", 1.0, 240000.0, 6000.0, "mm/min", "Rapid traverse rate per axis (X as radius)."),
    axis("nc.rapid_ramp_ms", "rapid time constant", 0.0, 4000.0, 100.0, "ms", "Time to reach the rapid rate."),
    num("nc.feed_max_mm_min", "max cutting feed", Real, 1.0, 240000.0, 6000.0, "mm/min", "Upper limit of the cutting feed (seed 001 names parameter P25 for it)."),
    num("nc.feed_ramp_ms", "cutting time constant", Int, 0.0, 4000.0, 100.0, "ms", "Time to reach the maximum cutting feed."),
    num("nc.feed_override_max_pct", "feed override maximum", Int, 0.0, 254.0, 150.0, "%", "Top position of the feed override switch; a larger input acts as it (DEC-112). Seed 001: 0..150 % (\"调整范围是(0%~150%)\")."),
    num("nc.feed_override_step_pct", "feed override step", Int, 1.0, 100.0, 10.0, "%", "Seed 001: 10 % (\"0~150%档(每档10%)\"). Step between the feed override switch's positions; an input between two acts as the lower one (DEC-112)."),
    num("nc.spindle_override_min_pct", "spindle override minimum", Int, 0.0, 254.0, 0.0, "%", "Lowest position of the spindle override switch (DEC-112). No document of this dialect gives it: the project default."),
    num("nc.spindle_override_max_pct", "spindle override maximum", Int, 0.0, 254.0, 200.0, "%", "Top position of the spindle override switch (DEC-112). No document of this dialect gives it: the project default."),
    num("nc.dry_run_mm_min", "dry run feed", Real, 1.0, 240000.0, 2000.0, "mm/min", "Feed of cutting moves under dry run."),
    num("nc.spindle_max_rpm", "max spindle speed", Int, 1.0, 60000.0, 3000.0, "rpm", "Spindle speed limit."),
    num("nc.spindle_ramp_ms", "spindle time constant", Int, 0.0, 20000.0, 1000.0, "ms", "Time from 0 to the maximum spindle speed (speed mode; the G93 return follows it)."),
    num("plc.fin_ms", "FIN delay", Int, 0.0, 10000.0, 16.0, "ms", "Strobe to FIN."),
    num("plc.fin_fall_ms", "FIN fall delay", Int, 0.0, 10000.0, 8.0, "ms", "Strobe falling to FIN falling."),
    num("plc.fin_timeout_ms", "FIN timer", Int, 1.0, 600000.0, 10000.0, "ms", "No FIN within this time: alarm NC-1020."),
    num("plc.zsp_ms", "zero-speed detection time", Int, 0.0, 10000.0, 8.0, "ms", "The spindle must stay stopped this long before the drive reports zero speed (ZSP)."),
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
        super::common::plant_config(p, "nc.rapid_mm_min", "nc.rapid_ramp_ms", "nc.backlash_mm")
    }
    fn interpreter(&self, params: &Params) -> Box<dyn Interpreter> {
        Box::new(interp::KndInterp::new(params))
    }
}
