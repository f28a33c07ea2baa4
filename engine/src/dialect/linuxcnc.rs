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

use crate::dialect::{Dialect, Interpreter};
use crate::exec::PlantConfig;
use crate::params::{axis, num, ParamDef, ParamKind::*, Params};
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
    num("nc.rigid_overshoot_pitches", "G33.1 overshoot allowance", Real, 0.1, 100.0, 10.0, "pitches", "How far past the end point the G33.1 tap may follow the reversing spindle, in pitches (LinuxCNC: 10); beyond: NC-1097."),
    num("nc.period_us", "interpolation period", Int, 1000.0, 8000.0, 1000.0, "us", "Servo period: 1000, 2000, 4000 or 8000 (LinuxCNC SERVO_PERIOD)."),
    axis("nc.rapid_mm_min", "rapid rate", 1.0, 240000.0, 6000.0, "mm/min", "Rapid rate per axis (MAX_VELOCITY)."),
    axis("nc.rapid_ramp_ms", "rapid time constant", 0.0, 4000.0, 100.0, "ms", "Time to reach the rapid rate (from MAX_ACCELERATION)."),
    axis("nc.backlash_mm", "backlash", 0.0, 2.0, 0.0, "mm", "Backlash of each axis, compensated on every reversal."),
    num("nc.feed_max_mm_min", "max cutting feed", Real, 1.0, 240000.0, 6000.0, "mm/min", "Upper limit of the cutting feed."),
    num("nc.feed_ramp_ms", "cutting time constant", Int, 0.0, 4000.0, 100.0, "ms", "Time to reach the maximum cutting feed."),
    num("nc.dry_run_mm_min", "dry run feed", Real, 1.0, 240000.0, 2000.0, "mm/min", "Feed of cutting moves under dry run."),
    num("nc.spindle_max_rpm", "max spindle speed", Int, 1.0, 60000.0, 6000.0, "rpm", "Spindle speed limit."),
    num("nc.spindle_ramp_ms", "spindle time constant", Int, 0.0, 20000.0, 1000.0, "ms", "Time from 0 to the maximum spindle speed; the G33.1 reversal follows it."),
    num("nc.orient_ms", "orientation time", Int, 0.0, 20000.0, 500.0, "ms", "Spindle orientation (G87) time."),
    num("plc.fin_ms", "M function delay", Int, 0.0, 10000.0, 0.0, "ms", "M/S/T function to its completion (LinuxCNC does not wait for a FIN: 0)."),
    num("plc.fin_fall_ms", "M function fall delay", Int, 0.0, 10000.0, 0.0, "ms", "Strobe falling to completion falling."),
    num("plc.fin_timeout_ms", "M function timer", Int, 1.0, 600000.0, 10000.0, "ms", "No completion within this time: NC-1020."),
    num("plc.zsp_ms", "zero-speed detection time", Int, 0.0, 10000.0, 8.0, "ms", "The spindle must stay stopped this long before zero speed is reported."),
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
        // move after M3/M4 waits for the spindle at speed (LCNC-MOT-01).
        let mut c = super::common::plant_config(p, "nc.rapid_mm_min", "nc.rapid_ramp_ms", "nc.backlash_mm");
        c.coordinated_rapid = true;
        c.feed_waits_at_speed = true;
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
