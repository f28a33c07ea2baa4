//! `linuxcnc`: the LinuxCNC RS274NGC interpreter and motion controller, the open-source peer
//! (behaviour §7; rules LCNC-* in `docs/rules/linuxcnc.md`).
//!
//! Mill and lathe alike: axes X Y Z (X always a radius in the machine; G7 makes the program's X a
//! diameter), planes G17/G18/G19, G84/G74 floating tapping, G33.1 rigid tapping, G33 and the G76
//! threading cycle, the G73/G81..G89 canned cycles with L repeats and G98/G99, and the program
//! language the corpus needs: expressions, numbered and named parameters, o-word subroutines,
//! if/while/repeat. Owns the parameter table and the parser; the interpreter is in
//! [`interp`] (control flow), `machine` (modal state, motions) and `cycles` (canned cycles).

mod cycles;
mod eval;
mod interp;
mod machine;
mod ngc;
mod path_mode;

use super::common::rows::*;
use crate::dialect::{Dialect, Interpreter};
use crate::exec::PlantConfig;
use crate::params::{num, ParamDef, ParamKind::*, Params};
use crate::parse::{Block, LexRules, ParseError, Program};
use crate::trace::AxisSpec;

/// The LinuxCNC dialect.
#[derive(Debug)]
pub struct Linuxcnc;

static LEX: LexRules = LexRules { dialect: "linuxcnc", letters: ngc::LETTERS, semicolon_ends_block: false };

static AXES: [AxisSpec; 3] = [
    AxisSpec { letter: 'X', index: 0, diameter: false, rotary: false },
    AxisSpec { letter: 'Y', index: 1, diameter: false, rotary: false },
    AxisSpec { letter: 'Z', index: 2, diameter: false, rotary: false },
];

/// Parameters of `linuxcnc`: the project's shared `nc.*` / `plc.*` model (LinuxCNC's INI
/// settings have no numbers; DEC-80).
pub static PARAMS: &[ParamDef] = &[
    num("nc.trajectory_planner", "LinuxCNC trajectory planner", Int, 209.0, 210.0, 210.0, "", "Which LinuxCNC's G64 planner the motion follows: 210 (default), LinuxCNC 2.10 as modelled so far (every move ends at rest at its full acceleration: DEC-141); 209, LinuxCNC 2.9: a G64 move that no move follows in the planner's queue runs at half its acceleration (tc.c tcGetOverallMaxAccel, fixed after 2.9 by LinuxCNC #4220; DEC-163), and two G64 rapids or feeds that turn, or a G76 pass and its exit taper, are joined by its blend arc (tp.c tpCreateLineLineBlend; DEC-164)."),
    num("nc.g74_g84_plane_points", "G74/G84 in G18/G19 as LinuxCNC runs it", Int, 0.0, 1.0, 1.0, "", "Where G84 and G74 feed in the XZ and YZ planes: 1 (default), as LinuxCNC's interpreter and motion do, to a point whose axes are permuted (interp_cycles.cc convert_cycle_g74_g84 passes its cycle_feed arguments out of order: in G18 X = the Y bottom, Y = the hole's Z, Z = the hole's X; in G19 X = the hole's Z, Y = the X bottom, Z = the hole's Y; rs274 2.9, 2.10 and real motion alike; DEC-166); 0, along the plane's tool axis at the hole, as LinuxCNC's manual says a canned cycle works (DEC-84), for a controller written to the manual. In G17 both are the same."),
    num("nc.startup_g64_p_mm", "Startup G64 P", Real, -1.0, 100.0, -1.0, "mm", "The G64 P of the machine's RS274NGC_STARTUP_CODE, which sets the blend tolerance of LinuxCNC's canonical layer and of its planner at power-on (0: G64 without P, no limit); -1 (default): no G64 there, LinuxCNC's own power-on: canon keeps 0.001 inch, which a canned cycle restores, the planner none (emccanon.cc INIT_CANON; DEC-169). Acts under nc.trajectory_planner 209 only."),
    num("nc.rigid_overshoot_pitches", "G33.1 overshoot allowance", Real, 0.1, 100.0, 10.0, "pitches", "How far past the end point the G33.1 tap may follow the reversing spindle, in pitches (LinuxCNC: 10); beyond: NC-1097."),
    ParamDef { doc: "Servo period: 1000, 2000, 4000 or 8000 (LinuxCNC SERVO_PERIOD).", ..PERIOD_US },
    ParamDef { doc: "Rapid rate per axis (MAX_VELOCITY).", ..RAPID_MM_MIN },
    ParamDef { doc: "Time to reach the rapid rate (from MAX_ACCELERATION).", ..RAPID_RAMP_MS },
    BACKLASH_MM,
    FEED_MAX_MM_MIN,
    FEED_RAMP_MS,
    ParamDef { default: 120.0, doc: "Top position of the feed override switch; a larger input acts as it (DEC-112). LinuxCNC: [DISPLAY] MAX_FEED_OVERRIDE of the INI (1.2 in the recorded machine's sim_tap.ini).", ..FEED_OVERRIDE_MAX_PCT },
    FEED_OVERRIDE_STEP_PCT,
    ParamDef { doc: "Lowest position of the spindle override switch (DEC-112). LinuxCNC: [DISPLAY] MIN/MAX_SPINDLE_OVERRIDE (sim_tap.ini: MAX 1.0, MIN not set: 0 here).", ..SPINDLE_OVERRIDE_MIN_PCT },
    ParamDef { default: 100.0, doc: "Top position of the spindle override switch (DEC-112). LinuxCNC: [DISPLAY] MIN/MAX_SPINDLE_OVERRIDE (sim_tap.ini: MAX 1.0, MIN not set: 0 here).", ..SPINDLE_OVERRIDE_MAX_PCT },
    DRY_RUN_MM_MIN,
    SPINDLE_MAX_RPM,
    ParamDef { doc: "Time from 0 to the maximum spindle speed; the G33.1 reversal follows it.", ..SPINDLE_RAMP_MS },
    ParamDef { doc: "Spindle orientation (G87) time.", ..ORIENT_MS },
    ParamDef { name: "M function delay", default: 0.0, doc: "M/S/T function to its completion (LinuxCNC does not wait for a FIN: 0).", ..FIN_MS },
    ParamDef { name: "M function fall delay", default: 0.0, doc: "Strobe falling to completion falling.", ..FIN_FALL_MS },
    ParamDef { name: "M function timer", doc: "No completion within this time: NC-1020.", ..FIN_TIMEOUT_MS },
    ParamDef { doc: "The spindle must stay stopped this long before zero speed is reported.", ..ZSP_MS },
];

impl Dialect for Linuxcnc {
    fn name(&self) -> &'static str {
        "linuxcnc"
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
        // LinuxCNC's motion controller: G0 is one coordinated line (LCNC-MOD-02) and a cutting
        // move after M3/M4 waits for the spindle at speed (LCNC-MOT-01); a spindle override acts on
        // the turning spindle at once (LCNC-G331-04, LCNC-G76-04).
        let mut c = super::common::plant_config(p, "nc.rapid_mm_min", "nc.rapid_ramp_ms", "nc.backlash_mm");
        c.coordinated_rapid = true;
        c.feed_waits_at_speed = true;
        c.spindle_override_at_once = true;
        // LinuxCNC's single block is its step: it stops where the task takes up a command of
        // another line, and only the commands of moves carry a line (LCNC-INP-01, L-121).
        c.step_stops_before_motion = true;
        c.index_latency_periods = 1;
        c.sync_run_continues = true;
        c.parabolic_half_accel = p.get("nc.trajectory_planner") < 209.5;
        c.power_on_tolerance_nm = (p.get("nc.startup_g64_p_mm") * 1e6).round().max(0.0);
        c
    }
    fn interpreter(&self, params: &Params) -> Box<dyn Interpreter> {
        Box::new(interp::LcncInterp::new(params))
    }
    fn parse(&self, text: &str) -> Result<Program, ParseError> {
        parse(text)
    }
}

/// Text of the block that stands for the end of a file without `%` framing: the interpreter
/// raises LinuxCNC's "File ended with no percent sign or program end" there unless the program
/// has ended (LCNC-LEX-04).
pub const END_OF_FILE: &str = "";

/// Parses a whole program (LCNC-LEX-01): `%` framing (a first `%` line starts the program, the
/// next one ends it), every line checked by [`ngc::parse_line`]; blocks keep the line's text with
/// its leading blanks so the interpreter's columns are exact.
pub fn parse(text: &str) -> Result<Program, ParseError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut blocks = Vec::new();
    let mut framed = false;
    let mut started = false;
    let mut last = 0u32;
    for (i, raw) in text.split('\n').enumerate() {
        let line_no = u32::try_from(i + 1).unwrap_or(u32::MAX);
        last = line_no;
        let line = raw.strip_suffix('\r').unwrap_or(raw);
        let trimmed = line.trim_start();
        if trimmed.starts_with('%') {
            if !started {
                framed = true;
                started = true;
                continue;
            }
            if framed {
                return Ok(Program { blocks });
            }
        }
        if !trimmed.is_empty() {
            started = true;
        }
        let parsed = ngc::parse_line(line, line_no)?;
        if !parsed.is_empty() {
            blocks.push(Block {
                line: line_no,
                text: line.trim_end().to_string(),
                seq: None,
                block_delete: parsed.block_delete,
                words: Vec::new(),
                klartext: None,
            });
        }
    }
    if framed {
        return Err(ParseError {
            line: last,
            col: 1,
            len: 1,
            message: "File ended with no percent sign".into(),
            expected: "a closing `%` line".into(),
        });
    }
    // The end of file is reported at the file's last line (a final line break opens none).
    let last = u32::try_from(text.lines().count().max(1)).unwrap_or(u32::MAX);
    blocks.push(Block {
        line: last,
        text: END_OF_FILE.into(),
        seq: None,
        block_delete: false,
        words: Vec::new(),
        klartext: None,
    });
    Ok(Program { blocks })
}
