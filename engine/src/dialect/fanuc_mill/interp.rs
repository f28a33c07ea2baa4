//! The `fanuc-mill` interpreter: the modal state of a Fanuc / Haas milling control and the steps
//! each block becomes (seed 003: G84 / G74 tapping, R plane, G98 / G99, Q peck, K repeats, rigid
//! tapping after M29). The canned cycles are in [`cycles`], the other motions (G00..G03, G04, G28,
//! G30, G53) in [`motion`].
//!
//! Order of the steps of one block: leaving rigid tapping mode (when the block cancels it), S, T,
//! the M codes other than M00/M01/M02/M30/M05/M09 (M29 is the rigid tapping handshake), the motion
//! or cycle, M05 / M09, then M00 / M01 / M02 / M30.
//!
//! Modelled as accepted codes without effect (the tool-length and work-offset tables are all zero,
//! the tool radius is zero): G40/G41/G42 with D, G43/G44/G49 and G43.4/G43.5 with H, G54..G59 and
//! G54.1 Pn, G05.1 (AI contour), G61/G64, G09, G15. They are recorded for [`Interpreter::modal`].
//!
//! Decisions where the Fanuc documents are silent (listed in `docs/`):
//! - two G codes of one group in a block: the last one written wins; a group-01 code and a canned
//!   cycle code in one block: the last one written wins and the other is ignored;
//! - F is the feed in mm/min (G94) or mm/rev (G95), whole numbers meaning whole mm; switching
//!   between G94 and G95 forgets F (the next feed move or cycle needs a new F, else alarm 0011);
//! - F0 is accepted as a word; the move or cycle that would use it raises 0011;
//! - G04 X without a decimal point is in ms (least increment 0.001 s), with one in seconds; P
//!   likewise (Haas); X and P together are refused;
//! - G30 returns to the same reference point as G28 (all reference points are machine zero);
//! - R arcs: an end point equal to the start point moves nothing; I/J/K arcs whose end is more
//!   than 0.01 mm off the circle, and R arcs whose chord exceeds the diameter by more than
//!   0.01 mm, raise NC-1001; I/J/K off the plane are ignored;
//! - words that mean nothing in the block (I J K R outside arcs and cycles, P outside G04 / G30 /
//!   G54.1 / cycles, Q outside cycles and G05.1, L outside cycles, E U V W) raise NC-1005;
//! - an S word in rigid tapping mode that differs from the M29 speed raises 0203; the same speed
//!   is accepted and not output again (the spindle is under position control);
//! - any axis word between M29 and the tapping cycle raises 0204, even with G00/G01/G80 in the
//!   block (the alarm comes before the group-01 code cancels rigid mode).

#[path = "cycles.rs"]
mod cycles;
#[path = "motion.rs"]
mod motion;
#[cfg(test)]
#[path = "interp_tests.rs"]
mod tests;

use crate::alarm::{Alarm, AlarmKind};
use crate::dialect::common::{g_name, speed_s, tool_t, Units, Words};
use crate::dialect::Interpreter;
use crate::params::Params;
use crate::parse::{Block, Word};
use crate::plan::drill::spindle_m;
use crate::plan::{Feed, Plane, Pos, SpindleEffect, Step};
use crate::trace::{AXES, AXIS_LETTERS};
use crate::units::{Micros, Nm, NM_PER_MM};

/// Largest feed per minute, nm/min (240000 mm/min).
const MAX_FEED_MIN_NM: i64 = 240_000 * NM_PER_MM;
/// Largest feed per revolution, nm/rev (500 mm/rev).
const MAX_FEED_REV_NM: i64 = 500 * NM_PER_MM;

/// The parameters the interpreter reads, once, when it is made.
#[derive(Debug, Clone, Copy)]
struct Settings {
    /// 3401.0: a number without decimal point is in mm / inch.
    dpi: bool,
    /// Least input increment, nm.
    increment_nm: i64,
    /// 3716: largest S.
    max_rpm: u32,
    /// 5210: the M code of rigid tapping mode.
    rigid_code: u32,
    /// 5200.0: G84 / G74 are rigid without M29.
    g84_rigid: bool,
    /// 5200.5: Q in rigid tapping returns to R (true) or retracts by 5213 (false).
    pcp: bool,
    /// 5211: extraction override, % (0 read as 100).
    extraction_pct: u32,
    /// 5213: high-speed peck retract, nm.
    peck_return_nm: Nm,
    /// 5241: largest S in rigid tapping.
    rigid_max_rpm: u32,
    /// nc.tap_spindle_check: conventional G84/G74 refuse a spindle not turning the right way.
    tap_spindle_check: bool,
    /// 3410: arc radius tolerance, nm (0: not checked; the arc becomes a spiral).
    arc_tolerance_nm: f64,
}

/// The spindle direction as last commanded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Spindle {
    Stopped,
    Forward,
    Reverse,
}

/// Canned-cycle data kept from block to block (cleared by G80). R and the hole bottom keep the
/// mode they were written in: incremental R is the distance from the initial level, incremental Z
/// the distance from R.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct CycleData {
    /// R and whether it was written in G91.
    r: Option<(Nm, bool)>,
    /// The hole bottom (tool-axis word) and whether it was written in G91.
    z: Option<(Nm, bool)>,
    /// Dwell at the bottom.
    p: Micros,
    /// Depth of cut (peck), or shift of G76 / G87 (not modelled).
    q: Option<Nm>,
}

/// The G codes of one block, by group, after the "last one wins" rules.
#[derive(Debug, Default)]
struct Gs {
    /// The group-01 code that takes effect (0..=3).
    motion: Option<u8>,
    /// The canned cycle ends in this block (G80 or a group-01 code).
    cancel: bool,
    /// G80: the retained cycle data is cleared too.
    clear: bool,
    /// A canned cycle code (G×10) and its word.
    cycle: Option<(u32, Word)>,
    /// G04, G28, G30 or G53 and its word.
    nonmodal: Option<(u32, Word)>,
    plane: Option<(Plane, Word)>,
    inch: Option<bool>,
    abs: Option<bool>,
    per_rev: Option<bool>,
    ret_initial: Option<bool>,
    cutter: Option<u32>,
    length: Option<u32>,
    work: Option<u32>,
    exact_stop: Option<bool>,
    ai_contour: bool,
}

/// Fanuc G codes the engine recognises but does not model.
const NOT_MODELLED_G: &[u32] = &[100, 110, 160, 270, 310, 500, 501, 510, 511, 520, 680, 690, 920];

/// The interpreter of `fanuc-mill`.
#[derive(Debug, Clone)]
pub struct FanucInterp {
    set: Settings,
    /// Program position, physical nm (nano-degrees on A B C).
    pos: Pos,
    /// G90 (true) / G91.
    abs: bool,
    /// G20 (true) / G21.
    inch: bool,
    /// G17 / G18 / G19.
    plane: Plane,
    /// G95 (true) / G94.
    per_rev: bool,
    /// F in nm/min (G94) or nm/rev (G95); None: not given since power-on or the last G94/G95 change.
    feed_nm: Option<i64>,
    /// Commanded S, rpm.
    s: Option<u32>,
    /// Commanded spindle direction.
    spindle: Spindle,
    /// Group 01: 0..=3.
    motion: u8,
    /// Group 09: the active canned cycle (G×10), None = G80.
    cycle: Option<u32>,
    /// G98 (true) / G99.
    ret_initial: bool,
    /// Tool-axis position when the cycle mode was entered from G80.
    initial: Nm,
    /// Retained cycle data.
    data: CycleData,
    /// Rigid tapping mode: its spindle speed, rpm.
    rigid: Option<u32>,
    /// M29 given and no tapping hole made since: an axis move now raises 0204.
    m29_pending: bool,
    /// Group 07: 400 / 410 / 420.
    cutter: u32,
    /// Group 08: 490 / 430 / 440 / 434 / 435.
    length: u32,
    /// Group 14: 540..590, or 541 with `work_p` (G54.1 Pn).
    work: u32,
    work_p: u32,
    /// G61 (true) / G64.
    exact_stop: bool,
    /// G05.1 Q1.
    ai_contour: bool,
}

impl Settings {
    fn from(p: &Params) -> Settings {
        Settings {
            dpi: p.bit("3401.0"),
            increment_nm: p.get("nc.increment_nm") as i64,
            max_rpm: p.get("3716") as u32,
            rigid_code: p.get("5210") as u32,
            g84_rigid: p.bit("5200.0"),
            pcp: p.bit("5200.5"),
            extraction_pct: match p.get("5211") as u32 {
                0 => 100,
                v => v,
            },
            peck_return_nm: (p.get("5213") * NM_PER_MM as f64).round() as Nm,
            rigid_max_rpm: p.get("5241") as u32,
            arc_tolerance_nm: p.get("3410") * NM_PER_MM as f64,
            tap_spindle_check: p.bit("nc.tap_spindle_check"),
        }
    }
}

impl FanucInterp {
    /// The power-on state: G00 G17 G90 G94 G98 G21 G80 G40 G49 G54 G64, at machine zero.
    pub fn new(p: &Params) -> Self {
        let set = Settings::from(p);
        FanucInterp {
            set,
            pos: [0; AXES],
            abs: true,
            inch: false,
            plane: Plane::Xy,
            per_rev: false,
            feed_nm: None,
            s: None,
            spindle: Spindle::Stopped,
            motion: 0,
            cycle: None,
            ret_initial: true,
            initial: 0,
            data: CycleData::default(),
            rigid: None,
            m29_pending: false,
            cutter: 400,
            length: 490,
            work: 540,
            work_p: 1,
            exact_stop: false,
            ai_contour: false,
        }
    }

    /// How the words of axis slot `slot` (and I J K R Q) are read: rotary axes stay in degrees in G20.
    fn units(&self, slot: usize) -> Units {
        Units { inch: self.inch && slot < 3, dpi: self.set.dpi, increment_nm: self.set.increment_nm }
    }

    /// Linear lengths.
    fn lu(&self) -> Units {
        self.units(0)
    }

    /// The axis words of the block, in nm as written (absolute or incremental).
    fn axis_words(&self, w: &Words) -> Result<[Option<Nm>; AXES], Alarm> {
        let mut v = [None; AXES];
        for (i, &l) in AXIS_LETTERS.iter().enumerate() {
            v[i] = self.units(i).coord(w, l)?;
        }
        Ok(v)
    }

    /// Where the axis words lead from the current position under G90 / G91.
    fn target(&self, words: &[Option<Nm>; AXES]) -> Pos {
        let mut t = self.pos;
        for (i, v) in words.iter().enumerate() {
            if let Some(v) = v {
                t[i] = if self.abs { *v } else { t[i].saturating_add(*v) };
            }
        }
        t
    }

    /// The active feed, or alarm 0011 located at the F word (if any) or `at`.
    fn feed(&self, w: &Words, at: Option<Word>, what: &str) -> Result<Feed, Alarm> {
        match self.feed_nm {
            Some(f) if f > 0 => {
                Ok(if self.per_rev { Feed::PerRev(f as f64) } else { Feed::PerMin(f as f64) })
            }
            _ => Err(locate(w, w.get('F').or(at), AlarmKind::FeedZero, format!("{what} needs a feed F > 0"))),
        }
    }

    /// Interprets one block into `out`, changing the state; the caller undoes both on error.
    fn run(&mut self, block: &Block, out: &mut Vec<Step>) -> Result<(), Alarm> {
        let w = Words::new(block)?;
        let g = decode_g(&w)?;
        check_m(&w)?;
        self.apply_modal(&w, &g)?;
        let cycle_after = if g.cancel { None } else { g.cycle.map(|c| c.0).or(self.cycle) };
        let cycle_block = cycle_after.is_some() && g.nonmodal.is_none();
        self.check_letters(&w, &g, cycle_block)?;
        self.read_feed(&w)?;
        let s = speed_s(&w, self.set.max_rpm)?;
        let t = tool_t(&w)?;
        w.int_in('D', 0, 999, "offset number D")?;
        w.int_in('H', 0, 999, "offset number H")?;

        // Axis moves between M29 and the tapping cycle (Fanuc 0204).
        let m29_here = w.m.iter().any(|(c, _)| *c == self.set.rigid_code);
        let tap_block = cycle_block && cycle_after.is_some_and(cycles::is_tap);
        if (self.m29_pending || m29_here) && !tap_block {
            if let Some(aw) = first_axis_word(&w, g.nonmodal.map(|n| n.0)) {
                return Err(w.alarm(
                    AlarmKind::IllegalAxisOperation,
                    &aw,
                    format!("{}: no axis may move between M29 and the tapping cycle", word_text(&aw)),
                ));
            }
        }
        // Leaving rigid tapping mode: G80, a group-01 code, another canned cycle.
        let exits = g.cancel || g.cycle.is_some_and(|(c, _)| !cycles::is_tap(c));
        if self.rigid.is_some() && exits {
            out.push(Step::RigidExit { wait_rgtap: true });
            self.rigid = None;
            self.m29_pending = false;
        }

        if let Some(s) = s {
            if let (Some(rpm), Some(sw)) = (self.rigid, w.get('S')) {
                if s != rpm {
                    return Err(w.alarm(
                        AlarmKind::ProgramMissRigid,
                        &sw,
                        format!("S{s}: the speed cannot change in rigid tapping mode (M29 S{rpm})"),
                    ));
                }
            }
            if self.rigid.is_none() {
                self.s = Some(s);
                // The S of a block that starts rigid tapping (M29 S, or G84 S under 5200.0 = 1)
                // is the tapping speed: it does not change the speed-mode rotation that reset
                // returns to (FAN-RT-14, DEC-08).
                let rigid_s =
                    m29_here || (self.set.g84_rigid && g.cycle.is_some_and(|(c, _)| cycles::is_tap(c)));
                let effect = if rigid_s { SpindleEffect::None } else { SpindleEffect::Speed(s) };
                out.push(Step::Function { letter: 'S', code: s, effect });
            }
        }
        if let Some(t) = t {
            out.push(Step::Function { letter: 'T', code: t, effect: SpindleEffect::None });
        }
        for &(code, word) in &w.m {
            if code == self.set.rigid_code {
                self.m29(&w, &word, out)?;
                continue;
            }
            match code {
                0 | 1 | 2 | 30 | 5 | 9 => continue,
                3 => self.spindle = Spindle::Forward,
                4 => self.spindle = Spindle::Reverse,
                19 => self.spindle = Spindle::Stopped,
                _ => {}
            }
            out.push(spindle_m(code));
        }

        if g.cancel {
            self.cycle = None;
            if g.clear {
                self.data = CycleData::default();
            }
        }
        if let Some(m) = g.motion {
            self.motion = m;
        }
        match (g.nonmodal, cycle_after) {
            (Some((40, _)), _) => self.dwell(&w, out)?,
            (Some((c @ (280 | 300), _)), _) => self.reference_return(&w, c, out)?,
            (Some((530, _)), _) => self.machine_rapid(&w, out)?,
            (_, Some(code)) => self.cycle_block(&w, code, g.cycle.map(|c| c.1), out)?,
            _ => self.motion_block(&w, out)?,
        }

        for &(code, _) in &w.m {
            if code != self.set.rigid_code && matches!(code, 5 | 9) {
                if code == 5 {
                    self.spindle = Spindle::Stopped;
                }
                out.push(spindle_m(code));
            }
        }
        for &(code, _) in &w.m {
            if code == self.set.rigid_code {
                continue;
            }
            match code {
                0 | 1 => {
                    out.push(Step::Function { letter: 'M', code, effect: SpindleEffect::None });
                    out.push(Step::Stop { optional: code == 1 });
                }
                2 | 30 => {
                    if self.rigid.take().is_some() {
                        out.push(Step::RigidExit { wait_rgtap: true });
                    }
                    self.m29_pending = false;
                    self.cycle = None;
                    self.data = CycleData::default();
                    out.push(Step::Function { letter: 'M', code, effect: SpindleEffect::Stop });
                    out.push(Step::End);
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// The modal G codes of the block take effect (before its words are read).
    fn apply_modal(&mut self, w: &Words, g: &Gs) -> Result<(), Alarm> {
        if let Some((plane, word)) = g.plane {
            if plane != self.plane && self.rigid.is_some() && !g.cancel {
                return Err(w.alarm(
                    AlarmKind::CannotChangePlane,
                    &word,
                    format!("{}: the plane cannot change in rigid tapping mode", word_text(&word)),
                ));
            }
            if plane != self.plane && self.cycle.is_some() && !g.cancel {
                // A new tool axis: its initial level is where it stands now.
                self.initial = self.pos[plane.axes().2];
            }
            self.plane = plane;
        }
        if let Some(v) = g.inch {
            self.inch = v;
        }
        if let Some(v) = g.abs {
            self.abs = v;
        }
        if let Some(v) = g.per_rev {
            if v != self.per_rev {
                self.feed_nm = None;
            }
            self.per_rev = v;
        }
        if let Some(v) = g.ret_initial {
            self.ret_initial = v;
        }
        if let Some(v) = g.cutter {
            self.cutter = v;
        }
        if let Some(v) = g.length {
            self.length = v;
        }
        if let Some(v) = g.work {
            self.work = v;
            if v == 541 {
                self.work_p = w.int_in('P', 1, 300, "extended work offset number")?.unwrap_or(1) as u32;
            }
        }
        if let Some(v) = g.exact_stop {
            self.exact_stop = v;
        }
        if g.ai_contour {
            self.ai_contour = w.int_in('Q', 0, 1, "G05.1 Q (0 off, 1 on)")?.unwrap_or(1) == 1;
        }
        Ok(())
    }

    /// Refuses words that mean nothing in this block.
    fn check_letters(&self, w: &Words, g: &Gs, cycle_block: bool) -> Result<(), Alarm> {
        let nonmodal = g.nonmodal.map(|n| n.0);
        let arc = !cycle_block && nonmodal.is_none() && matches!(g.motion.unwrap_or(self.motion), 2 | 3);
        for word in &w.block.words {
            let ok = match word.letter {
                'E' | 'U' | 'V' | 'W' => false,
                'P' => {
                    cycle_block || matches!(nonmodal, Some(40 | 300)) || g.work == Some(541) || w.has_g(50)
                }
                'Q' => cycle_block || g.ai_contour,
                'R' | 'I' | 'J' | 'K' => cycle_block || arc,
                'L' => cycle_block,
                'X' | 'Y' | 'Z' | 'A' | 'B' | 'C' if nonmodal == Some(40) => word.letter == 'X',
                _ => true,
            };
            if !ok {
                let why = match nonmodal {
                    Some(40) => "G04 takes only P or X (dwell)".to_string(),
                    _ => format!("{} has no meaning in this block", word.letter),
                };
                return Err(w.alarm(AlarmKind::IllegalWord, word, format!("{}: {why}", word_text(word))));
            }
        }
        if let (Some(x), Some(_)) = (w.get('X').filter(|_| nonmodal == Some(40)), w.get('P')) {
            return Err(w.alarm(
                AlarmKind::IllegalWord,
                &x,
                "G04: give the dwell as P or X, not both".into(),
            ));
        }
        if let (Some(_), Some(l)) = (w.get('K'), w.get('L')) {
            return Err(w.alarm(AlarmKind::IllegalWord, &l, "L is K (repeats): give one of them".into()));
        }
        Ok(())
    }

    /// Reads F: 0 ≤ F ≤ 240000 mm/min (G94) or ≤ 500 mm/rev (G95).
    fn read_feed(&mut self, w: &Words) -> Result<(), Alarm> {
        let Some(fw) = w.get('F') else { return Ok(()) };
        let nm = fw.value.scaled(self.lu().unit_nm());
        let (max, range) = if self.per_rev {
            (MAX_FEED_REV_NM, "0 < F ≤ 500 mm/rev (G95)")
        } else {
            (MAX_FEED_MIN_NM, "0 < F ≤ 240000 mm/min (G94)")
        };
        // F0 is 0011 when a move needs it; a feed finer than the least input increment is out of
        // range (a feed of 1 nm/min would run for years, issue 15).
        if !(0..=max).contains(&nm) || (nm != 0 && nm < self.set.increment_nm.max(1)) {
            return Err(w.alarm(
                AlarmKind::WordOutOfRange,
                &fw,
                format!("F{}: the feed must be {range}", fw.value.display()),
            ));
        }
        self.feed_nm = Some(nm);
        Ok(())
    }

    /// M29: the rigid tapping handshake at the speed of this block or the commanded one.
    fn m29(&mut self, w: &Words, word: &Word, out: &mut Vec<Step>) -> Result<(), Alarm> {
        let code = self.set.rigid_code;
        if self.rigid.is_some() {
            return Err(w.alarm(
                AlarmKind::ProgramMissRigid,
                word,
                format!("M{code}: rigid tapping mode is already on"),
            ));
        }
        let Some(rpm) = self.s.filter(|&s| s > 0) else {
            return Err(w.alarm(
                AlarmKind::IllegalSCode,
                word,
                format!("M{code}: rigid tapping needs a spindle speed S > 0 (in this block or before)"),
            ));
        };
        out.push(Step::RigidEnter { code, rpm });
        self.rigid = Some(rpm);
        self.m29_pending = true;
        Ok(())
    }
}

impl Interpreter for FanucInterp {
    fn block(&mut self, block: &Block, out: &mut Vec<Step>) -> Result<(), Alarm> {
        let mut next = self.clone();
        let mut steps = Vec::new();
        next.run(block, &mut steps)?;
        *self = next;
        out.extend(steps);
        Ok(())
    }

    fn reset(&mut self, pos: Pos) {
        self.cycle = None;
        self.data = CycleData::default();
        self.rigid = None;
        self.m29_pending = false;
        self.pos = pos;
    }

    fn set_position(&mut self, pos: Pos) {
        self.pos = pos;
    }

    fn modal(&self) -> Vec<String> {
        let mut v = vec![
            format!("G0{}", self.motion),
            match self.plane {
                Plane::Xy => "G17",
                Plane::Zx => "G18",
                Plane::Yz => "G19",
            }
            .to_string(),
            if self.abs { "G90" } else { "G91" }.to_string(),
            if self.per_rev { "G95" } else { "G94" }.to_string(),
            if self.ret_initial { "G98" } else { "G99" }.to_string(),
            if self.inch { "G20" } else { "G21" }.to_string(),
            g_name(self.cycle.unwrap_or(800)),
            g_name(self.cutter),
            g_name(self.length),
            if self.work == 541 { format!("G54.1 P{}", self.work_p) } else { g_name(self.work) },
        ];
        if self.exact_stop {
            v.push("G61".into());
        }
        if self.ai_contour {
            v.push("G05.1 Q1".into());
        }
        v
    }

    fn rigid_mode(&self) -> bool {
        self.rigid.is_some()
    }

    fn set_params(&mut self, p: &Params) {
        self.set = Settings::from(p);
    }
}

/// Sorts the block's G codes into groups; unknown codes raise 0010.
fn decode_g(w: &Words) -> Result<Gs, Alarm> {
    let mut g = Gs::default();
    let mut g01: Option<(usize, u8)> = None;
    let mut g09: Option<(usize, u32, Word)> = None;
    for (i, &(code, word)) in w.g.iter().enumerate() {
        match code {
            0 | 10 | 20 | 30 => g01 = Some((i, (code / 10) as u8)),
            800 => g09 = Some((i, code, word)),
            c if cycles::is_cycle(c) => g09 = Some((i, code, word)),
            40 | 280 | 300 | 530 => {
                if g.nonmodal.is_some() {
                    return Err(w.alarm(
                        AlarmKind::IllegalWord,
                        &word,
                        format!("{}: one of G04 / G28 / G30 / G53 per block", g_name(code)),
                    ));
                }
                g.nonmodal = Some((code, word));
            }
            // G05 P10000 / P0: high-precision contour control, accepted with no effect on motion.
            50 | 90 | 150 => {}
            51 => g.ai_contour = true,
            170 => g.plane = Some((Plane::Xy, word)),
            180 => g.plane = Some((Plane::Zx, word)),
            190 => g.plane = Some((Plane::Yz, word)),
            200 | 210 => g.inch = Some(code == 200),
            400 | 410 | 420 => g.cutter = Some(code),
            430 | 440 | 490 | 434 | 435 => g.length = Some(code),
            540 | 550 | 560 | 570 | 580 | 590 | 541 => g.work = Some(code),
            610 | 640 => g.exact_stop = Some(code == 610),
            900 | 910 => g.abs = Some(code == 900),
            940 | 950 => g.per_rev = Some(code == 950),
            980 | 990 => g.ret_initial = Some(code == 980),
            650 | 660 | 670 => {
                return Err(w.alarm(
                    AlarmKind::NotModelled,
                    &word,
                    format!("{}: subprogram and macro calls are not modelled", g_name(code)),
                ))
            }
            c if NOT_MODELLED_G.contains(&c) => {
                return Err(w.alarm(
                    AlarmKind::NotModelled,
                    &word,
                    format!("{}: this Fanuc G code is not modelled", g_name(code)),
                ))
            }
            _ => {
                return Err(w.alarm(
                    AlarmKind::ImproperGCode,
                    &word,
                    format!("{}: not a G code of fanuc-mill", g_name(code)),
                ))
            }
        }
    }
    if g.nonmodal.is_some() {
        if let Some((_, c, word)) = g09.filter(|c| c.1 != 800) {
            return Err(w.alarm(
                AlarmKind::IllegalWord,
                &word,
                format!("{}: a canned cycle cannot share a block with G04 / G28 / G30 / G53", g_name(c)),
            ));
        }
    }
    match (g01, g09) {
        (m, Some((_, 800, _))) => {
            g.motion = m.map(|m| m.1);
            g.cancel = true;
            g.clear = true;
        }
        (Some((i1, m)), Some((i9, c, word))) => {
            if i1 > i9 {
                g.motion = Some(m);
                g.cancel = true;
            } else {
                g.cycle = Some((c, word));
            }
        }
        (Some((_, m)), None) => {
            g.motion = Some(m);
            g.cancel = true;
        }
        (None, Some((_, c, word))) => g.cycle = Some((c, word)),
        (None, None) => {}
    }
    Ok(g)
}

/// Refuses subprogram calls and more than three M codes.
fn check_m(w: &Words) -> Result<(), Alarm> {
    for &(code, word) in &w.m {
        if matches!(code, 97..=99) {
            return Err(w.alarm(
                AlarmKind::NotModelled,
                &word,
                format!("M{code}: subprogram calls are not modelled"),
            ));
        }
    }
    if let Some(&(_, word)) = w.m.get(3) {
        return Err(w.alarm(AlarmKind::TooManyMCodes, &word, "at most 3 M codes per block".into()));
    }
    Ok(())
}

/// The first axis word that moves an axis (G04's X is a time).
fn first_axis_word(w: &Words, nonmodal: Option<u32>) -> Option<Word> {
    w.block.words.iter().copied().find(|wd| {
        matches!(wd.letter, 'X' | 'Y' | 'Z' | 'A' | 'B' | 'C') && !(nonmodal == Some(40) && wd.letter == 'X')
    })
}

/// An alarm at `at` when given, else at the block.
fn locate(w: &Words, at: Option<Word>, kind: AlarmKind, detail: String) -> Alarm {
    match at {
        Some(word) => w.alarm(kind, &word, detail),
        None => w.block_alarm(kind, detail),
    }
}

/// A word as written (`X-12.5`).
fn word_text(w: &Word) -> String {
    if w.letter == 'G' {
        let t = w.value.scaled(10);
        return g_name(t.max(0) as u32);
    }
    format!("{}{}", w.letter, w.value.display())
}
