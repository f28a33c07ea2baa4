//! `gsk-lathe`: GSK 980TDi-style lathe control (seed 000: rigid tapping G84 face / G88 radial).
//!
//! X is a diameter, U/W/H are the incremental forms of X/Z/C, G98/G99 are feed per minute / per
//! revolution. Owns the parameter table and the interpreter of this dialect.

mod interp;

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
    num("nc.period_us", "interpolation period", Int, 1000.0, 8000.0, 1000.0, "us", "Interpolation period: 1000, 2000, 4000 or 8000."),
    num("nc.increment_nm", "least input increment", Int, 100.0, 1000.0, 100.0, "nm", "100 (IS-C, 0.0001 mm) or 1000 (IS-B, 0.001 mm)."),
    bit("nc.dpi", "calculator decimal point", 1.0, "1: a word without decimal point is in mm (X50 = 50 mm); 0: in least input increments."),
    num("nc.d_above_150", "D above 150", Int, 0.0, 1.0, 0.0, "", "0: D > 150 raises NC-1001 (seed range); 1: D is clamped to 150 (980TDi)."),
    axis("nc.rapid_mm_min", "rapid rate", 1.0, 240000.0, 8000.0, "mm/min", "Rapid traverse rate per axis (X as radius)."),
    axis("nc.rapid_ramp_ms", "rapid time constant", 0.0, 4000.0, 100.0, "ms", "Time to reach the rapid rate."),
    num("nc.feed_max_mm_min", "max cutting feed", Real, 1.0, 240000.0, 6000.0, "mm/min", "Upper limit of the cutting feed."),
    num("nc.feed_ramp_ms", "cutting time constant", Int, 0.0, 4000.0, 100.0, "ms", "Time to reach the maximum cutting feed."),
    num("nc.feed_override_max_pct", "feed override maximum", Int, 0.0, 254.0, 200.0, "%", "Top position of the feed override switch; a larger input acts as it (DEC-112). The documents of this dialect give no range: the project default."),
    num("nc.feed_override_step_pct", "feed override step", Int, 1.0, 100.0, 1.0, "%", "Step between the feed override switch's positions; an input between two acts as the lower one (DEC-112)."),
    num("nc.spindle_override_min_pct", "spindle override minimum", Int, 0.0, 254.0, 0.0, "%", "Lowest position of the spindle override switch (DEC-112). No document of this dialect gives it: the project default."),
    num("nc.spindle_override_max_pct", "spindle override maximum", Int, 0.0, 254.0, 200.0, "%", "Top position of the spindle override switch (DEC-112). No document of this dialect gives it: the project default."),
    num("nc.dry_run_mm_min", "dry run feed", Real, 1.0, 240000.0, 2000.0, "mm/min", "Feed of cutting moves under dry run."),
    num("nc.spindle_max_rpm", "max spindle speed", Int, 1.0, 60000.0, 6000.0, "rpm", "Spindle speed limit."),
    num("nc.spindle_ramp_ms", "spindle time constant", Int, 0.0, 20000.0, 1000.0, "ms", "Time from 0 to the maximum spindle speed."),
    num("nc.rt_max_rpm", "rigid tap max speed", Int, 1.0, 60000.0, 3000.0, "rpm", "Maximum S in rigid tapping (above: NC-1001)."),
    num("nc.rt_ramp_ms", "rigid tap time constant", Int, 0.0, 4000.0, 200.0, "ms", "Shared time constant of spindle and tap axis at nc.rt_max_rpm (scaled by S/max)."),
    num("nc.orient_ms", "orientation time", Int, 0.0, 20000.0, 500.0, "ms", "Spindle reference return time (RTORI)."),
    num("plc.fin_ms", "FIN delay", Int, 0.0, 10000.0, 16.0, "ms", "Strobe to FIN."),
    num("plc.fin_fall_ms", "FIN fall delay", Int, 0.0, 10000.0, 8.0, "ms", "Strobe falling to FIN falling."),
    num("plc.sppos_request_ms", "position-mode request delay", Int, 0.0, 10000.0, 8.0, "ms", "M29 strobe to the position-mode request to the drive."),
    num("plc.sppos_reach_ms", "drive answer delay", Int, 0.0, 10000.0, 50.0, "ms", "Position-mode request to the drive's reached answer."),
    num("plc.rgtap_ms", "RGTAP delay", Int, 0.0, 10000.0, 8.0, "ms", "Reached answer to RGTAP and FIN."),
    num("plc.rgtap_fall_ms", "RGTAP fall delay", Int, 0.0, 10000.0, 16.0, "ms", "F76.3 falling to RGTAP falling."),
    num("plc.m29_timeout_ms", "M29 answer timer", Int, 1.0, 600000.0, 2000.0, "ms", "No reached answer within this time after the request: alarm 5002."),
    num("plc.fin_timeout_ms", "FIN timer", Int, 1.0, 600000.0, 10000.0, "ms", "No FIN within this time: alarm NC-1020."),
    num("plc.zsp_ms", "zero-speed detection time", Int, 0.0, 10000.0, 8.0, "ms", "The spindle must stay stopped this long before the drive reports zero speed (ZSP)."),
    num("plc.spindle_stall_ms", "stall timer", Int, 100.0, 600000.0, 100.0, "ms", "Spindle not rotating while rigid tapping commands it for this long: alarm 5074."),
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
