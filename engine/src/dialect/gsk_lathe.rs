//! `gsk-lathe`: GSK 980TDi-style lathe control (seed 000: rigid tapping G84 face / G88 radial).
//!
//! X is a diameter, U/W/H are the incremental forms of X/Z/C, G98/G99 are feed per minute / per
//! revolution. Owns the parameter table and the interpreter of this dialect.

mod interp;

use super::common::rows::*;
use crate::dialect::{Dialect, Interpreter};
use crate::exec::PlantConfig;
use crate::params::{axis, bit, num, ParamDef, ParamKind::*, Params};
use crate::parse::LexRules;
use crate::trace::AxisSpec;

/// The GSK lathe dialect.
#[derive(Debug)]
pub struct GskLathe;

static LEX: LexRules =
    LexRules { dialect: "gsk-lathe", letters: "ACDEFGHIJKLMNOPQRSTUWXZ", semicolon_ends_block: true };

static AXES: [AxisSpec; 3] = [
    AxisSpec { letter: 'X', index: 0, diameter: true, rotary: false },
    AxisSpec { letter: 'Z', index: 2, diameter: false, rotary: false },
    AxisSpec { letter: 'C', index: 5, diameter: false, rotary: true },
];

/// Parameters of `gsk-lathe`. Vendor numbers from seed 000 and the GSK 980TDi manual; `nc.*` and
/// `plc.*` are the project's model where no document gives a number.
pub static PARAMS: &[ParamDef] = &[
    axis("34", "backlash", 0.0, 2.0, 0.0, "mm", "Backlash of each axis, compensated on every reversal (seed 000 note 7)."),
    num("170", "clamp M code", Int, 0.0, 9998.0, 0.0, "", "Spindle clamp M code α; unclamp is α+1. 0: no clamp code configured (an M word in G84/G88 raises NC-1012)."),
    bit("182.7", "Q unit", 0.0, "Unit of Q in G84/G88: 0 = least input increment, 1 = mm."),
    bit("186.2", "RTCRG", 0.0, "1: after rigid tapping is cancelled go on without waiting for RGTAP to fall; 0: wait."),
    bit("186.5", "overload source", 0.0, "Overload retract watches 0 = the feed-axis motor, 1 = the spindle motor."),
    bit("186.7", "RTORI", 0.0, "1: spindle reference return before rigid tapping starts."),
    num("270", "overload delay", Int, 0.0, 65535.0, 100.0, "ms", "The motor current must stay above the threshold this long before the tap retracts."),
    num("271", "overload threshold", Int, 0.0, 300.0, 0.0, "%", "Overload threshold, % of rated current; 0 = off. Word D overrides it."),
    PERIOD_US,
    ParamDef { default: 100.0, doc: "100 (IS-C, 0.0001 mm) or 1000 (IS-B, 0.001 mm).", ..INCREMENT_NM },
    DPI,
    num("nc.d_above_150", "D above 150", Int, 0.0, 1.0, 0.0, "", "0: D > 150 raises NC-1001 (seed range); 1: D is clamped to 150 (980TDi)."),
    ParamDef { default: 8000.0, ..RAPID_MM_MIN },
    RAPID_RAMP_MS,
    FEED_MAX_MM_MIN,
    FEED_RAMP_MS,
    FEED_OVERRIDE_MAX_PCT,
    FEED_OVERRIDE_STEP_PCT,
    SPINDLE_OVERRIDE_MIN_PCT,
    SPINDLE_OVERRIDE_MAX_PCT,
    DRY_RUN_MM_MIN,
    SPINDLE_MAX_RPM,
    SPINDLE_RAMP_MS,
    num("nc.rt_max_rpm", "rigid tap max speed", Int, 1.0, 60000.0, 3000.0, "rpm", "Maximum S in rigid tapping (above: NC-1001)."),
    num("nc.rt_ramp_ms", "rigid tap time constant", Int, 0.0, 4000.0, 200.0, "ms", "Shared time constant of spindle and tap axis at nc.rt_max_rpm (scaled by S/max)."),
    ParamDef { doc: "Spindle reference return time (RTORI).", ..ORIENT_MS },
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
    bit("nc.thread_retract", "thread retract on feed hold", 0.0, "G92.3 feed hold during a pass: 0 = finish the pass (thread and X out), then hold; 1 = retract at once to the cycle start, hold, and cut the pass again on cycle start (DEC-60)."),
];

impl Dialect for GskLathe {
    fn name(&self) -> &'static str {
        "gsk-lathe"
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
        let mut c = super::common::plant_config(p, "nc.rapid_mm_min", "nc.rapid_ramp_ms", "34");
        c.hold_in_rigid_tap = false;
        c
    }
    fn interpreter(&self, params: &Params) -> Box<dyn Interpreter> {
        Box::new(interp::GskInterp::new(params))
    }
}
