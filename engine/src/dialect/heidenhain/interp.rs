//! The `heidenhain` interpreter: Klartext blocks → steps for a threading program (BEGIN/END PGM,
//! FUNCTION MODE, FUNCTION TURNDATA SPIN, TOOL CALL, L, M functions, STOP, CYCL DEF, CYCL CALL)
//! and cycle 832 (rules HDH-* in `docs/rules/heidenhain.md`).

use super::cycle832::{thread, CallContext, Def832};
use crate::alarm::{Alarm, AlarmKind};
use crate::dialect::Interpreter;
use crate::params::Params;
use crate::parse::klartext::{KCoord, KFeed, KValue, Klartext};
use crate::parse::Block;
use crate::plan::thread_832::thread_cycle;
use crate::plan::{Feed, Pos, SpindleEffect, Step};
use crate::trace::AXES;
use crate::units::{Nm, NM_PER_MM};

const X: usize = 0;
const Z: usize = 2;
/// Largest coordinate, spindle speed and feed a block may give (TNC input formats).
const MAX_COORD_NM: Nm = 99_999_999_900_000;

/// The cycle most recently defined.
#[derive(Debug, Clone, PartialEq)]
enum Defined {
    None,
    C832(Def832),
    Other(i64),
}

/// The interpreter.
pub struct HeiInterp {
    flank_deg: f64,
    neg_diameter_alarm: bool,
    spindle_max_rpm: u32,
    /// Physical position (X as radius).
    pos: Pos,
    /// `FUNCTION MODE TURN` is active.
    turn: bool,
    /// Feed of L moves, nm/min (modal).
    feed: Option<f64>,
    s_cmd: u32,
    /// 1 (M3/M303), −1 (M4/M304), 0 (stopped).
    spindle_dir: i8,
    cycle: Defined,
}

fn located(kind: AlarmKind, v: &KValue, detail: String) -> Alarm {
    Alarm::new(kind, detail).at(v.line, Some(v.col))
}

impl HeiInterp {
    /// Power-on state: milling mode, spindle stopped, no cycle defined.
    pub fn new(p: &Params) -> Self {
        let mut i = HeiInterp {
            flank_deg: 30.0,
            neg_diameter_alarm: true,
            spindle_max_rpm: 3000,
            pos: [0; AXES],
            turn: false,
            feed: None,
            s_cmd: 0,
            spindle_dir: 0,
            cycle: Defined::None,
        };
        i.set_params(p);
        i
    }

    /// A spindle speed S (0..the maximum) as an S function.
    fn speed(&mut self, s: &KValue, out: &mut Vec<Step>) -> Result<(), Alarm> {
        let rpm = s.value.as_int().filter(|v| (0..=i64::from(self.spindle_max_rpm)).contains(v));
        let Some(rpm) = rpm else {
            return Err(located(
                AlarmKind::WordOutOfRange,
                s,
                format!(
                    "S{}: the speed must be a whole number 0..{} rpm",
                    s.value.display(),
                    self.spindle_max_rpm
                ),
            ));
        };
        self.s_cmd = rpm as u32;
        out.push(Step::Function { letter: 'S', code: rpm as u32, effect: SpindleEffect::Speed(rpm as u32) });
        Ok(())
    }

    /// M functions: spindle starts before the block's motion, stops and ends after it (HDH-LEX-05).
    fn mcodes(&mut self, m: &[KValue], pre: &mut Vec<Step>, post: &mut Vec<Step>) -> Result<(), Alarm> {
        for v in m {
            let Some(code) = v.value.as_int().filter(|c| (0..=999).contains(c)).map(|c| c as u32) else {
                return Err(located(
                    AlarmKind::WordOutOfRange,
                    v,
                    format!("M{}: an M function is a whole number 0..999", v.value.display()),
                ));
            };
            let f = |effect| Step::Function { letter: 'M', code, effect };
            match code {
                3 | 303 => {
                    self.spindle_dir = 1;
                    pre.push(f(SpindleEffect::Forward));
                }
                4 | 304 => {
                    self.spindle_dir = -1;
                    pre.push(f(SpindleEffect::Reverse));
                }
                5 | 305 => {
                    self.spindle_dir = 0;
                    post.push(f(SpindleEffect::Stop));
                }
                0 => {
                    post.push(f(SpindleEffect::None));
                    post.push(Step::Stop { optional: false });
                }
                1 => {
                    post.push(f(SpindleEffect::None));
                    post.push(Step::Stop { optional: true });
                }
                2 | 30 => {
                    self.spindle_dir = 0;
                    post.push(f(SpindleEffect::Stop));
                    post.push(Step::End);
                }
                _ => pre.push(f(SpindleEffect::None)),
            }
        }
        Ok(())
    }

    /// A coordinate of an L block → physical target (X diameter → radius).
    fn coord(&self, c: &KCoord, slot: usize) -> Result<Nm, Alarm> {
        let v = c.v.value.scaled(NM_PER_MM);
        if v.abs() > MAX_COORD_NM {
            return Err(located(
                AlarmKind::WordOutOfRange,
                &c.v,
                format!("{}: a coordinate must be within ±99999.9999 mm", c.v.value.display()),
            ));
        }
        let v = if slot == X { v / 2 } else { v };
        Ok(if c.incremental { self.pos[slot] + v } else { v })
    }

    fn line(
        &mut self,
        k: (&Option<KCoord>, &Option<KCoord>, &Option<KCoord>),
        comp: Option<u32>,
        feed: &Option<KFeed>,
        block: &Block,
        body: &mut Vec<Step>,
    ) -> Result<(), Alarm> {
        let (x, y, z) = k;
        if let Some(col) = comp {
            return Err(Alarm::new(
                AlarmKind::NotModelled,
                "RL/RR: radius compensation is not modelled; position with R0 (seed 004)",
            )
            .at(block.line, Some(col)));
        }
        if let Some(y) = y {
            // Absolute or incremental, only a zero leaves the (absent) Y axis where it is.
            if y.v.value.mantissa != 0 {
                return Err(located(
                    AlarmKind::NotModelled,
                    &y.v,
                    "the lathe has no Y axis: only Y+0".into(),
                ));
            }
        }
        let mut target = self.pos;
        if let Some(c) = x {
            target[X] = self.coord(c, X)?;
        }
        if let Some(c) = z {
            target[Z] = self.coord(c, Z)?;
        }
        let rapid = match feed {
            Some(KFeed::Max) => true,
            Some(KFeed::Rate(f)) => {
                let v = f.value.scaled(NM_PER_MM);
                if !(NM_PER_MM / 1000..=99_999_999 * NM_PER_MM / 1000).contains(&v) {
                    return Err(located(
                        AlarmKind::WordOutOfRange,
                        f,
                        format!(
                            "F{}: the feed must be above 0 and at most 99999.999 mm/min",
                            f.value.display()
                        ),
                    ));
                }
                self.feed = Some(v as f64);
                false
            }
            None => false,
        };
        if target == self.pos {
            return Ok(());
        }
        if rapid {
            body.push(Step::Rapid { target });
        } else {
            let Some(f) = self.feed else {
                return Err(Alarm::new(AlarmKind::FeedZero, "an L move without FMAX or a feed F")
                    .at(block.line, None));
            };
            body.push(Step::Feed { target, feed: Feed::PerMin(f) });
        }
        self.pos = target;
        Ok(())
    }

    /// `CYCL CALL`: cycle 832 from where the tool stands (HDH-C832-*).
    fn cycl_call(&mut self, block: &Block, body: &mut Vec<Step>) -> Result<(), Alarm> {
        let def = match &self.cycle {
            Defined::C832(d) => d.clone(),
            Defined::Other(n) => {
                return Err(Alarm::new(
                    AlarmKind::NotModelled,
                    format!("cycle {n} is not modelled (only 832)"),
                )
                .at(block.line, None))
            }
            Defined::None => {
                return Err(Alarm::new(AlarmKind::CycleNotDefined, "CYCL CALL with no CYCL DEF before it")
                    .at(block.line, None))
            }
        };
        if !self.turn {
            return Err(Alarm::new(
                AlarmKind::TurningModeRequired,
                "cycle 832 runs only in FUNCTION MODE TURN",
            )
            .at(block.line, None));
        }
        if self.spindle_dir == 0 || self.s_cmd == 0 {
            return Err(Alarm::new(
                AlarmKind::SpindleNotTurning,
                "cycle 832: the spindle must turn (M3/M303 or M4/M304 with S > 0) before CYCL CALL",
            )
            .at(block.line, None));
        }
        let ctx = CallContext {
            pos: self.pos,
            flank_deg: self.flank_deg,
            neg_diameter_alarm: self.neg_diameter_alarm,
        };
        let c = thread(&def, &ctx).map_err(|mut a| {
            if a.line.is_none() {
                a.line = Some(block.line);
            }
            a
        })?;
        thread_cycle(&c, body);
        Ok(())
    }
}

impl Interpreter for HeiInterp {
    fn block(&mut self, block: &Block, out: &mut Vec<Step>) -> Result<(), Alarm> {
        let Some(kb) = block.klartext.as_deref() else {
            return Err(Alarm::new(AlarmKind::NotModelled, "not a Klartext block").at(block.line, None));
        };
        let (mut pre, mut body, mut post) = (Vec::new(), Vec::new(), Vec::new());
        match kb {
            Klartext::BeginPgm { inch, col } => {
                if *inch {
                    return Err(Alarm::new(AlarmKind::NotModelled, "INCH programs are not modelled")
                        .at(block.line, Some(*col)));
                }
            }
            Klartext::EndPgm => post.push(Step::End),
            Klartext::Mode(turn) => self.turn = *turn,
            Klartext::Spin { s, vconst_on } => {
                if let Some(col) = vconst_on {
                    return Err(Alarm::new(
                        AlarmKind::NotModelled,
                        "VCONST:ON (constant cutting speed) is not modelled",
                    )
                    .at(block.line, Some(*col)));
                }
                if let Some(s) = s {
                    self.speed(s, &mut pre)?;
                }
            }
            Klartext::ToolCall { tool, s } => {
                if let Some(t) = tool {
                    let Some(n) = t.value.as_int().filter(|n| (0..=32767).contains(n)) else {
                        return Err(located(
                            AlarmKind::WordOutOfRange,
                            t,
                            format!("tool {}: a tool number is 0..32767", t.value.display()),
                        ));
                    };
                    pre.push(Step::Function { letter: 'T', code: n as u32, effect: SpindleEffect::None });
                }
                if let Some(s) = s {
                    self.speed(s, &mut pre)?;
                }
            }
            Klartext::Line { x, y, z, comp, feed, m } => {
                self.mcodes(m, &mut pre, &mut post)?;
                self.line((x, y, z), *comp, feed, block, &mut body)?;
            }
            Klartext::Misc { stop, m } => {
                self.mcodes(m, &mut pre, &mut post)?;
                if *stop && m.is_empty() {
                    post.push(Step::Stop { optional: false });
                }
            }
            Klartext::CyclDef { number, params } => {
                self.cycle = if number.value.as_int() == Some(832) {
                    Defined::C832(Def832::new(params)?)
                } else {
                    Defined::Other(number.value.as_int().unwrap_or(-1))
                };
            }
            Klartext::CyclCall { m } => {
                self.mcodes(m, &mut pre, &mut post)?;
                self.cycl_call(block, &mut body)?;
            }
            Klartext::NotModelled { what, col } => {
                return Err(Alarm::new(AlarmKind::NotModelled, format!("{what} is not modelled"))
                    .at(block.line, Some(*col)));
            }
        }
        out.extend(pre);
        out.extend(body);
        out.extend(post);
        Ok(())
    }

    fn reset(&mut self, pos: Pos) {
        self.pos = pos;
    }

    fn set_position(&mut self, pos: Pos) {
        self.pos = pos;
    }

    fn modal(&self) -> Vec<String> {
        let mut v = vec![if self.turn { "MODE TURN".to_string() } else { "MODE MILL".to_string() }];
        match &self.cycle {
            Defined::C832(_) => v.push("CYCL 832".into()),
            Defined::Other(n) => v.push(format!("CYCL {n}")),
            Defined::None => {}
        }
        v
    }

    fn rigid_mode(&self) -> bool {
        false
    }

    fn set_params(&mut self, p: &Params) {
        self.flank_deg = p.get("hei.flank_angle_deg");
        self.neg_diameter_alarm = p.bit("hei.neg_diameter_alarm");
        self.spindle_max_rpm = p.get("nc.spindle_max_rpm") as u32;
    }
}
