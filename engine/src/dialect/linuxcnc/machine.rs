//! The modal state of a LinuxCNC interpreter and the execution of one evaluated line in
//! RS274NGC order (LCNC-MOD-*): feed mode, F, S, T, M6, spindle, coolant, dwell, plane, units,
//! cutter compensation, tool length, coordinate system, distance mode, retract mode, lathe mode,
//! G92 offsets, motion (G0/G1/G2/G3, G33, G33.1, G76, canned cycles), stops.
//!
//! Positions are kept in machine nm (X a radius); words are converted once, in program units,
//! with G7 halving X, and G92 offsets subtracted to give the program's coordinates.

use super::cycles;
use super::eval::System;
use crate::alarm::{Alarm, AlarmKind};
use crate::dialect::common::g_name;
use crate::params::Params;
use crate::plan::follow_tap::{follow_tap, FollowTap};
use crate::plan::thread_g76::{thread_g76, ThreadG76, MAX_PASSES};
use crate::plan::{Feed, Plane, Pos, SpindleEffect, Step, ThreadPass};
use crate::trace::Phase;
use crate::units::{Micros, Nm};

/// One line with its words evaluated: value and column of each letter, G and M codes apart.
#[derive(Debug, Clone)]
pub struct Eb {
    /// Source line.
    pub line: u32,
    vals: [Option<(f64, u32)>; 26],
    /// G codes as value × 10, with their columns.
    pub g: Vec<(u32, u32)>,
    /// M codes with their columns.
    pub m: Vec<(u32, u32)>,
}

impl Eb {
    /// An empty line.
    pub fn new(line: u32) -> Self {
        Eb { line, vals: [None; 26], g: Vec::new(), m: Vec::new() }
    }

    /// Adds a word; `Err` with LinuxCNC's text for a letter given twice or a bad G/M number.
    pub fn push(&mut self, letter: char, v: f64, col: u32) -> Result<(), String> {
        match letter {
            'G' => {
                let t = (v * 10.0).round();
                if v < 0.0 {
                    return Err("Negative g code used".into());
                }
                if (v * 10.0 - t).abs() > 1e-3 || t > 9999.0 {
                    return Err("G code out of range".into());
                }
                self.g.push((t as u32, col));
            }
            'M' => {
                if v < 0.0 {
                    return Err("Negative m code used".into());
                }
                if v.fract() != 0.0 || v > 199.0 {
                    return Err("M code out of range".into());
                }
                self.m.push((v as u32, col));
            }
            l => {
                let i = (l as u8 - b'A') as usize;
                if self.vals[i].is_some() {
                    return Err(format!("Multiple {} words on one line", l.to_ascii_lowercase()));
                }
                self.vals[i] = Some((v, col));
            }
        }
        Ok(())
    }

    /// The value of a letter.
    pub fn get(&self, l: char) -> Option<f64> {
        self.vals[(l as u8 - b'A') as usize].map(|(v, _)| v)
    }

    /// The column of a letter.
    pub fn col(&self, l: char) -> Option<u32> {
        self.vals[(l as u8 - b'A') as usize].map(|(_, c)| c)
    }

    /// Whether a G code (× 10) is in the line.
    pub fn has_g(&self, t: u32) -> bool {
        self.g.iter().any(|(g, _)| *g == t)
    }

    /// Whether any of X, Y, Z is given.
    pub fn has_axis(&self) -> bool {
        "XYZ".chars().any(|l| self.get(l).is_some())
    }
}

/// Feed mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FeedMode {
    /// G93.
    InverseTime,
    /// G94.
    PerMin,
    /// G95.
    PerRev,
}

/// What the canned cycles remember between lines (LinuxCNC's `cycle_*` settings).
#[derive(Debug, Clone, Copy, Default)]
pub struct CycleMemo {
    /// Last R word.
    pub r: f64,
    /// Last bottom word (Z in G17).
    pub cc: f64,
    /// Last P (dwell, s).
    pub p: f64,
    /// Last Q (peck).
    pub q: f64,
    /// Last I, J, K (G87).
    pub ijk: [f64; 3],
    /// Initial level of the cycle series, work nm on the tool axis.
    pub il: Option<Nm>,
}

/// Settings from the parameters.
#[derive(Debug, Clone, Copy)]
pub struct Cfg {
    max_rpm: f64,
    overshoot_pitches: f64,
    /// LinuxCNC 2.9's planner (`nc.trajectory_planner` 209): the path control mode is passed on
    /// to the executor (`Step::PathMode`, DEC-163).
    pub(super) tp_2_9: bool,
    /// G84/G74 in G18 and G19 feed to LinuxCNC's permuted point (`nc.g74_g84_plane_points` 1,
    /// DEC-166); 0: along the plane's tool axis at the hole, as its manual says.
    pub(super) tap_permuted: bool,
    /// The startup code's G64 P (nm; `nc.startup_g64_p_mm`, DEC-169): the blend tolerance of
    /// canon and of the planner at power-on; None: no G64 there (canon 0.001 inch, the planner
    /// none).
    startup_p: Option<Nm>,
}

impl Cfg {
    /// From the parameter values.
    pub fn from(p: &Params) -> Self {
        Cfg {
            max_rpm: p.get("nc.spindle_max_rpm").max(1.0),
            overshoot_pitches: p.get("nc.rigid_overshoot_pitches"),
            tp_2_9: p.get("nc.trajectory_planner") < 209.5,
            tap_permuted: p.get("nc.g74_g84_plane_points") > 0.5,
            startup_p: Some(p.get("nc.startup_g64_p_mm"))
                .filter(|v| *v >= 0.0)
                .map(|v| (v * 1e6).round() as Nm),
        }
    }
}

/// The modal state.
#[derive(Debug, Clone)]
pub struct Machine {
    /// Settings.
    pub cfg: Cfg,
    /// Where the machine stands (machine nm).
    pub pos: Pos,
    /// The tool stands elsewhere than [`Machine::pos`], where the interpreter takes it to be
    /// (G88's bottom, DEC-151; LinuxCNC's permuted tap point, DEC-166): the next move is queued
    /// even to `pos` itself.
    pub astray: bool,
    /// G92 offsets (machine − program), nm.
    pub off: [Nm; 3],
    /// G20.
    pub inch: bool,
    /// G90.
    pub absolute: bool,
    /// G64 (LinuxCNC powers on in it, emccanon.cc INIT_CANON); false under G61 and G61.1.
    pub continuous: bool,
    /// The blend tolerance LinuxCNC's planner gives G64 moves, nm: 0 at start-up (none: the
    /// planner's own limit), G64's P.
    pub tolerance: Nm,
    /// The tolerance LinuxCNC's canonical layer keeps, nm, which rs274 restores after a canned
    /// cycle: 0.001 inch at start-up (emccanon.cc INIT_CANON, never sent to the planner), the
    /// last G64's P, 0 after G61 or G61.1.
    pub canon_tolerance: Nm,
    /// G90.1: arc centres absolute.
    pub arc_absolute: bool,
    /// G7.
    pub diameter: bool,
    /// Plane.
    pub plane: Plane,
    /// Feed mode.
    pub feed_mode: FeedMode,
    /// F, program units.
    pub feed: f64,
    /// S, rpm.
    pub s: f64,
    /// Spindle: 1 clockwise (M3), -1 counter-clockwise (M4), 0 stopped.
    pub spindle: i8,
    /// G98.
    pub old_z: bool,
    /// Modal motion (G × 10).
    pub motion: Option<u32>,
    /// Canned cycle memory.
    pub cyc: CycleMemo,
    /// G41/G42 in force (zero tool radius: paths unchanged).
    pub comp: bool,
    /// M2/M30 seen.
    /// The last error came from converting a canned cycle (LinuxCNC's execute phase: its task
    /// aborts the whole read-ahead, LCNC-LEX-05).
    pub cycle_error: bool,
    pub ended: bool,
}

/// An alarm of this dialect at a line (and column).
pub fn alarm(kind: AlarmKind, text: impl Into<String>, line: u32, col: Option<u32>) -> Alarm {
    Alarm::new(kind, text).at(line, col)
}

impl Machine {
    /// Power-on state: G17 G21 G90 G94 G99 G8, spindle stopped.
    pub fn new(p: &Params) -> Self {
        let cfg = Cfg::from(p);
        Machine {
            cfg,
            pos: [0; 6],
            astray: false,
            off: [0; 3],
            inch: false,
            absolute: true,
            continuous: true,
            // LinuxCNC's power-on (emccanon.cc INIT_CANON: 0.001 inch in canon, none sent to
            // the planner) unless the startup code gives G64 P (both then).
            tolerance: cfg.startup_p.unwrap_or(0),
            canon_tolerance: cfg.startup_p.unwrap_or(25_400),
            arc_absolute: false,
            diameter: false,
            plane: Plane::Xy,
            feed_mode: FeedMode::PerMin,
            feed: 0.0,
            s: 0.0,
            spindle: 0,
            old_z: false,
            motion: None,
            cyc: CycleMemo::default(),
            comp: false,
            ended: false,
            cycle_error: false,
        }
    }

    /// nm in one program unit.
    pub fn unit(&self) -> f64 {
        if self.inch {
            25_400_000.0
        } else {
            1_000_000.0
        }
    }

    /// A length in program units to nm (`axis` 0 is X: halved under G7).
    pub fn len(&self, v: f64, axis: usize, b: &Eb, letter: char) -> Result<Nm, Alarm> {
        let nm = v * self.unit() / if axis == 0 && self.diameter { 2.0 } else { 1.0 };
        if !nm.is_finite() || nm.abs() > 1e14 {
            return Err(alarm(
                AlarmKind::WordOutOfRange,
                format!("{letter}{v}: beyond ±100 m"),
                b.line,
                b.col(letter),
            ));
        }
        Ok(nm.round() as Nm)
    }

    /// Program coordinate (work nm) of an axis.
    pub fn work(&self, axis: usize) -> Nm {
        self.pos[axis].saturating_sub(self.off[axis])
    }

    /// Machine position from program coordinates (work nm) of X, Y, Z.
    pub fn machine(&self, work: [Nm; 3]) -> Pos {
        let mut p = self.pos;
        for a in 0..3 {
            p[a] = work[a].saturating_add(self.off[a]);
        }
        p
    }

    /// What the expressions read (`#<_x>`...).
    pub fn system(&self) -> System {
        let mut xyz = [0.0; 3];
        for (a, v) in xyz.iter_mut().enumerate() {
            let k = if a == 0 && self.diameter { 2.0 } else { 1.0 };
            *v = self.work(a) as f64 * k / self.unit();
        }
        System { xyz, metric: !self.inch, absolute: self.absolute, diameter: self.diameter }
    }

    /// The cutting feed.
    pub fn feed_rate(&self) -> Feed {
        match self.feed_mode {
            FeedMode::PerRev => Feed::PerRev(self.feed * self.unit()),
            _ => Feed::PerMin(self.feed * self.unit()),
        }
    }

    /// Appends a rapid and moves there.
    ///
    /// A move of no length is not queued: LinuxCNC's planner drops it (tp.c `tpAddLine`,
    /// TP_ERR_ZERO_LENGTH), so it neither ends a blend nor counts as the move that follows.
    pub fn rapid(&mut self, target: Pos, out: &mut Vec<Step>) {
        if target != self.pos || self.astray {
            out.push(Step::Rapid { target });
        }
        self.pos = target;
        self.astray = false;
    }

    /// Appends a feed move at the cutting feed and moves there.
    /// (None of no length, as [`Machine::rapid`].)
    pub fn feed_to(&mut self, target: Pos, out: &mut Vec<Step>) {
        if target != self.pos || self.astray {
            out.push(Step::Feed { target, feed: self.feed_rate() });
        }
        self.pos = target;
        self.astray = false;
    }

    /// The target of a motion: each of X, Y, Z given (absolute or incremental) or kept.
    pub fn target(&self, b: &Eb) -> Result<[Nm; 3], Alarm> {
        let mut t = [self.work(0), self.work(1), self.work(2)];
        for (a, l) in ['X', 'Y', 'Z'].into_iter().enumerate() {
            if let Some(v) = b.get(l) {
                let nm = self.len(v, a, b, l)?;
                t[a] = if self.absolute { nm } else { t[a].saturating_add(nm) };
            }
        }
        Ok(t)
    }

    /// Active modal codes for the end summary.
    pub fn modal(&self) -> Vec<String> {
        let plane = match self.plane {
            Plane::Xy => "G17",
            Plane::Zx => "G18",
            Plane::Yz => "G19",
        };
        let mut v = vec![
            plane.to_string(),
            if self.inch { "G20" } else { "G21" }.to_string(),
            if self.absolute { "G90" } else { "G91" }.to_string(),
            match self.feed_mode {
                FeedMode::InverseTime => "G93",
                FeedMode::PerMin => "G94",
                FeedMode::PerRev => "G95",
            }
            .to_string(),
            if self.old_z { "G98" } else { "G99" }.to_string(),
            if self.diameter { "G07" } else { "G08" }.to_string(),
        ];
        v.push(self.motion.map_or("G80".to_string(), g_name));
        v
    }

    /// Executes one evaluated line.
    pub fn run(&mut self, b: &Eb, out: &mut Vec<Step>) -> Result<(), Alarm> {
        let err = |text: String, col: Option<u32>| alarm(AlarmKind::LcncInterpreter, text, b.line, col);
        for &(g, col) in &b.g {
            if !KNOWN_G.contains(&g) {
                return Err(err("Unknown g code used".into(), Some(col)));
            }
            if NOT_MODELLED_G.contains(&g) {
                return Err(alarm(
                    AlarmKind::NotModelled,
                    format!("{} is not modelled by the linuxcnc dialect", g_name(g)),
                    b.line,
                    Some(col),
                ));
            }
        }
        for &(m, col) in &b.m {
            if NOT_MODELLED_M.contains(&m) || m >= 100 {
                // rs274 without the machine's user M code files: "Unknown m code used: M123".
                let user = if m >= 100 { format!("Unknown m code used: M{m}; ") } else { String::new() };
                return Err(alarm(
                    AlarmKind::NotModelled,
                    format!("{user}M{m} is not modelled by the linuxcnc dialect"),
                    b.line,
                    Some(col),
                ));
            }
            if !KNOWN_M.contains(&m) {
                return Err(err("Unknown m code used".into(), Some(col)));
            }
        }
        // 1. Feed mode, F, S, T, M6, spindle, coolant.
        if b.has_g(930) {
            self.feed_mode = FeedMode::InverseTime;
        } else if b.has_g(940) {
            self.feed_mode = FeedMode::PerMin;
        } else if b.has_g(950) {
            self.feed_mode = FeedMode::PerRev;
        }
        if let Some(f) = b.get('F') {
            if f < 0.0 {
                return Err(err("Negative f word used".into(), b.col('F')));
            }
            self.feed = f;
        }
        if let Some(s) = b.get('S') {
            if s < 0.0 {
                return Err(err("Negative spindle speed used".into(), b.col('S')));
            }
            self.s = s;
            let code = s.round().min(u32::MAX as f64) as u32;
            out.push(Step::Function { letter: 'S', code, effect: SpindleEffect::Speed(code) });
        }
        if let Some(t) = b.get('T') {
            if t < 0.0 || t.fract() != 0.0 {
                return Err(err("Negative tool id used".into(), b.col('T')));
            }
            out.push(Step::Function { letter: 'T', code: t as u32, effect: SpindleEffect::None });
        }
        for &(m, _) in &b.m {
            let effect = match m {
                3 => {
                    self.spindle = 1;
                    SpindleEffect::Forward
                }
                4 => {
                    self.spindle = -1;
                    SpindleEffect::Reverse
                }
                5 => {
                    self.spindle = 0;
                    SpindleEffect::Stop
                }
                19 => SpindleEffect::Orient,
                6 | 7 | 8 | 9 | 48..=53 => SpindleEffect::None,
                _ => continue,
            };
            out.push(Step::Function { letter: 'M', code: m, effect });
        }
        // 2. Dwell.
        if b.has_g(40) {
            let Some(p) = b.get('P').filter(|p| *p >= 0.0) else {
                return Err(err("Dwell time missing with g4".into(), None));
            };
            out.push(Step::Dwell { us: secs(p) });
        }
        // 3. Plane, units, compensation, distance, retract, lathe modes, spindle mode.
        for &(g, col) in &b.g {
            match g {
                170 => self.plane = Plane::Xy,
                180 => self.plane = Plane::Zx,
                190 => self.plane = Plane::Yz,
                200 => self.inch = true,
                210 => self.inch = false,
                400 => self.comp = false,
                410 | 420 => self.comp = true,
                900 => self.absolute = true,
                910 => self.absolute = false,
                610 | 611 | 640 => self.control_mode(g, b, out)?,
                901 => self.arc_absolute = true,
                911 => self.arc_absolute = false,
                980 => self.old_z = true,
                990 => self.old_z = false,
                70 => self.diameter = true,
                80 => self.diameter = false,
                960 => {
                    return Err(alarm(
                        AlarmKind::NotModelled,
                        "G96 constant surface speed is not modelled by the linuxcnc dialect".to_string(),
                        b.line,
                        Some(col),
                    ))
                }
                _ => {}
            }
        }
        // 4. G92 offsets and G53.
        if b.has_g(920) {
            if !b.has_axis() {
                return Err(err("All axes missing with g92".into(), None));
            }
            for (a, l) in ['X', 'Y', 'Z'].into_iter().enumerate() {
                if let Some(v) = b.get(l) {
                    self.off[a] = self.pos[a].saturating_sub(self.len(v, a, b, l)?);
                }
            }
        } else if b.has_g(921) || b.has_g(922) {
            self.off = [0; 3];
        }
        // 5. Motion.
        self.motion_of(b, out)?;
        // 6. Stops.
        for &(m, _) in &b.m {
            match m {
                0 | 60 => out.push(Step::Stop { optional: false }),
                1 => out.push(Step::Stop { optional: true }),
                2 | 30 => {
                    out.push(Step::Function { letter: 'M', code: m, effect: SpindleEffect::Stop });
                    out.push(Step::End);
                    self.ended = true;
                    self.spindle = 0;
                }
                _ => {}
            }
        }
        Ok(())
    }

    fn motion_of(&mut self, b: &Eb, out: &mut Vec<Step>) -> Result<(), Alarm> {
        // G80 beside another motion code gives way to it (rs274 runs `G80 G0 Z10`).
        let motions = || b.g.iter().filter(|(g, _)| MOTION_G.contains(g)).map(|(g, _)| *g);
        let explicit = motions().find(|g| *g != 800).or_else(|| motions().next());
        let uses_axes = b.has_g(920) || b.has_g(40);
        // A motion code that needs axis words (interp_internal.cc enhance_block).
        let axis_words = b.has_axis() || ['A', 'B', 'C'].into_iter().any(|l| b.get(l).is_some());
        if explicit.is_some_and(|g| !matches!(g, 0 | 10 | 20 | 30 | 800)) && !axis_words {
            return Err(alarm(AlarmKind::LcncInterpreter, "All axes missing with motion code", b.line, None));
        }
        // A rotary word with a canned cycle to be (interp_check.cc check_other_codes).
        let rotary = ['A', 'B', 'C'].into_iter().find(|l| b.get(*l).is_some());
        if let (Some(l), Some(g)) = (rotary, explicit.or(self.motion)) {
            if cycles::is_cycle(g) {
                let article = if l == 'A' { "an" } else { "a" };
                let text = format!("Cannot put {article} {} in canned cycle", l.to_ascii_lowercase());
                return Err(alarm(AlarmKind::LcncInterpreter, text, b.line, b.col(l)));
            }
        }
        if explicit == Some(800) {
            if b.has_axis() {
                return Err(alarm(
                    AlarmKind::LcncInterpreter,
                    "Cannot use axis values with g80",
                    b.line,
                    None,
                ));
            }
            self.motion = None;
            self.cyc.il = None;
            return Ok(());
        }
        let motion = match explicit {
            Some(g) => g,
            None if b.has_axis() && !uses_axes => match self.motion {
                Some(g) => g,
                None => {
                    return Err(alarm(
                        AlarmKind::LcncInterpreter,
                        "Cannot use axis values without a g code that uses them",
                        b.line,
                        None,
                    ))
                }
            },
            None => return Ok(()),
        };
        if !cycles::is_cycle(motion) {
            self.cyc.il = None;
        }
        let machine_coords = b.has_g(530);
        match motion {
            0 | 10 if machine_coords => {
                let mut t = self.pos;
                for (a, l) in ['X', 'Y', 'Z'].into_iter().enumerate() {
                    if let Some(v) = b.get(l) {
                        t[a] = self.len(v, a, b, l)?;
                    }
                }
                self.check_feed(motion, b)?;
                if motion == 0 {
                    self.rapid(t, out);
                } else {
                    self.feed_to(t, out);
                }
            }
            _ if machine_coords => {
                return Err(alarm(AlarmKind::LcncInterpreter, "Must use g0 or g1 with g53", b.line, None))
            }
            0 => {
                let t = self.machine(self.target(b)?);
                self.rapid(t, out);
            }
            10 => {
                self.check_feed(motion, b)?;
                let t = self.machine(self.target(b)?);
                self.feed_to(t, out);
            }
            20 | 30 => {
                self.check_feed(motion, b)?;
                super::interp::arc(self, b, motion == 20, out)?;
            }
            330 => self.g33(b, out)?,
            331 => self.g33_1(b, out)?,
            760 => self.g76(b, out)?,
            _ => {
                let r = cycles::canned(self, motion, b, out);
                self.cycle_error = r.is_err();
                r?
            }
        }
        self.motion = Some(motion);
        Ok(())
    }

    fn check_feed(&self, motion: u32, b: &Eb) -> Result<(), Alarm> {
        if motion == 0 {
            return Ok(());
        }
        if self.feed_mode == FeedMode::InverseTime {
            return Err(alarm(AlarmKind::NotModelled, "G93 inverse time feed is not modelled", b.line, None));
        }
        if self.feed == 0.0 {
            let text = if motion == 10 {
                "Cannot do G1 with zero feed rate"
            } else {
                "Cannot make arc with zero feed rate"
            };
            return Err(alarm(AlarmKind::LcncFeedZero, text, b.line, None));
        }
        if self.feed_mode == FeedMode::PerRev && self.s == 0.0 {
            let text = "Cannot feed with zero spindle speed in feed per rev mode";
            return Err(alarm(AlarmKind::LcncFeedZero, text, b.line, None));
        }
        Ok(())
    }

    /// The K word of G33 / G33.1 in nm per revolution.
    fn lead(&self, b: &Eb) -> Result<Nm, Alarm> {
        let k = b.get('K').filter(|k| *k > 0.0);
        let Some(k) = k else {
            return Err(alarm(
                AlarmKind::LcncWordMissing,
                "K word missing with g33/g33.1",
                b.line,
                b.col('K'),
            ));
        };
        self.len(k, 2, b, 'K')
    }

    fn spindle_turning(&self, what: &str, b: &Eb) -> Result<(), Alarm> {
        if self.spindle == 0 || self.s <= 0.0 {
            return Err(alarm(
                AlarmKind::LcncSpindle,
                format!("Spindle not turning in {what}"),
                b.line,
                None,
            ));
        }
        Ok(())
    }

    /// G33 (LCNC-G33-01): a spindle-synchronised straight move, K per revolution along the path.
    fn g33(&mut self, b: &Eb, out: &mut Vec<Step>) -> Result<(), Alarm> {
        let lead = self.lead(b)?;
        self.spindle_turning("G33", b)?;
        let t = self.machine(self.target(b)?);
        out.push(Step::AwaitAtSpeed);
        out.push(Step::HoldSuppress(true));
        out.push(Step::Phase(Phase::Cutting));
        // Synchronised from the next index pulse on (LCNC-G33-02), K along the path.
        let longest = |p: [usize; 3]| {
            let mut v = p;
            v.sort_by_key(|&i| std::cmp::Reverse((t[i] - self.pos[i]).unsigned_abs()));
            [v[0], v[1]]
        };
        if let Some(pass) = ThreadPass::line(self.pos, t, longest([0, 1, 2]), lead as f64, true) {
            out.push(Step::Thread(ThreadPass { alarm: AlarmKind::LcncSpindle, ..pass }));
        }
        out.push(Step::HoldSuppress(false));
        out.push(Step::Phase(Phase::Idle));
        self.pos = t;
        Ok(())
    }

    /// G33.1 (LCNC-G331-01..03): rigid tapping along Z from here to Z and back.
    fn g33_1(&mut self, b: &Eb, out: &mut Vec<Step>) -> Result<(), Alarm> {
        let lead = self.lead(b)?;
        let t = self.target(b)?;
        for (a, l) in [(0, 'X'), (1, 'Y')] {
            if t[a] != self.work(a) {
                return Err(alarm(
                    AlarmKind::NotModelled,
                    format!("G33.1 moving {l} (a tap along a slanted line) is not modelled"),
                    b.line,
                    b.col(l),
                ));
            }
        }
        self.spindle_turning("G33.1", b)?;
        let start = self.pos[2];
        let end = t[2].saturating_add(self.off[2]);
        if end == start {
            return Ok(());
        }
        let rpm = self.s.round().min(self.cfg.max_rpm) as u32;
        // LinuxCNC's motion controller starts a synchronised move with the spindle at speed.
        out.push(Step::AwaitAtSpeed);
        follow_tap(
            &FollowTap {
                axis: 2,
                start,
                end,
                lead_nm: lead,
                rpm: rpm.max(1),
                forward: self.spindle > 0,
                // LinuxCNC reverses the spindle at Z from the speed it turns at (S × the
                // override in force) at its ramp: no brake time of its own (DEC-149).
                brake_us: 0,
                allowance_nm: (lead as f64 * self.cfg.overshoot_pitches).round() as Nm,
                zsp_timeout_us: None,
                backlash: false,
                encoder_bound: false,
                not_turning: AlarmKind::LcncSpindle,
                overshoot: AlarmKind::LcncTapOvershoot,
                linuxcnc: true,
            },
            out,
        );
        out.push(Step::Phase(Phase::Idle));
        Ok(())
    }

    /// G76 (LCNC-G76-01..04): the threading cycle from the present point (the drive line).
    fn g76(&mut self, b: &Eb, out: &mut Vec<Step>) -> Result<(), Alarm> {
        let bad = |text: &str, col: Option<u32>| alarm(AlarmKind::LcncInterpreter, text, b.line, col);
        let missing = |text: &str| alarm(AlarmKind::LcncWordMissing, text, b.line, None);
        if self.plane != Plane::Zx {
            return Err(bad("G76 only in the XZ plane (G18)", None));
        }
        let Some(p) = b.get('P') else { return Err(missing("P word missing with G76")) };
        let (Some(i), Some(j), Some(k)) = (b.get('I'), b.get('J'), b.get('K')) else {
            return Err(missing("I J or K words missing with G76"));
        };
        let Some(z) = b.get('Z') else { return Err(missing("Z word missing with G76")) };
        if self.spindle == 0 || self.s <= 0.0 {
            let text = "Chosen spindle (0) not turning in G76";
            return Err(alarm(AlarmKind::LcncSpindle, text, b.line, None));
        }
        let r = b.get('R').unwrap_or(1.0);
        let q = b.get('Q').unwrap_or(0.0);
        let h = b.get('H').unwrap_or(0.0);
        let e = b.get('E').unwrap_or(0.0);
        let l = b.get('L').unwrap_or(0.0);
        if p <= 0.0 {
            return Err(bad("G76: P (pitch) must be greater than zero", b.col('P')));
        }
        if j <= 0.0 || k <= 0.0 {
            return Err(bad("G76: J and K (depths) must be greater than zero", b.col('J')));
        }
        if r < 1.0 {
            return Err(bad("G76: R (depth degression) must be 1.0 or more", b.col('R')));
        }
        if !(0.0..90.0).contains(&q) {
            return Err(bad("G76: Q (compound angle) must be 0 or more and below 90", b.col('Q')));
        }
        if h < 0.0 || h.fract() != 0.0 || h > 1000.0 {
            return Err(bad("G76: H (spring passes) must be a whole number 0..1000", b.col('H')));
        }
        if !(l == 0.0 || l == 1.0 || l == 2.0 || l == 3.0) {
            return Err(bad("G76: L (taper ends) must be 0, 1, 2 or 3", b.col('L')));
        }
        if e < 0.0 {
            return Err(bad("G76: E (taper length) must not be negative", b.col('E')));
        }
        // Under G7 the cross words I, J, K are diameters (LCNC-G76-03).
        let cross = |v: f64, letter| self.len(v, 0, b, letter);
        let c = ThreadG76 {
            x_axis: 0,
            z_axis: 2,
            start: self.pos,
            z_end: self.len(z, 2, b, 'Z')?.saturating_add(if self.absolute {
                self.off[2]
            } else {
                self.pos[2]
            }),
            pitch: self.len(p, 2, b, 'P')?,
            i: cross(i, 'I')?,
            j: cross(j, 'J')?,
            k: cross(k, 'K')?,
            degression: r,
            compound_deg: q,
            spring: h as u32,
            taper: self.len(e, 2, b, 'E')?,
            taper_ends: l as u8,
        };
        if c.depths().count() as u64 >= MAX_PASSES {
            return Err(alarm(
                AlarmKind::LcncLoopLimit,
                format!("G76 would cut more than {MAX_PASSES} passes (J too small for K and R)"),
                b.line,
                b.col('J'),
            ));
        }
        thread_g76(&c, out);
        self.pos[2] = c.z_end;
        Ok(())
    }

    /// CNC reset: the position is kept, cycles and the end flag cleared.
    pub fn reset(&mut self, pos: Pos) {
        self.pos = pos;
        self.astray = false;
        self.motion = None;
        self.cyc.il = None;
        self.ended = false;
    }
}

/// Seconds to µs (negative: 0).
pub fn secs(s: f64) -> Micros {
    (s.max(0.0) * 1e6).round().min(1e15) as Micros
}

/// G codes (× 10) LinuxCNC has.
const KNOWN_G: &[u32] = &[
    0, 10, 20, 30, 40, 50, 51, 52, 53, 70, 80, 100, 170, 171, 180, 181, 190, 191, 200, 210, 280, 281, 300,
    301, 330, 331, 382, 383, 384, 385, 400, 410, 411, 420, 421, 430, 431, 432, 490, 520, 530, 540, 550, 560,
    570, 580, 590, 591, 592, 593, 610, 611, 640, 730, 740, 760, 800, 810, 820, 830, 840, 850, 860, 870, 880,
    890, 900, 901, 910, 911, 920, 921, 922, 923, 930, 940, 950, 960, 970, 980, 990,
];

/// G codes recognised but not modelled (NC-1004).
const NOT_MODELLED_G: &[u32] =
    &[50, 51, 52, 100, 171, 181, 191, 280, 281, 300, 301, 382, 383, 384, 385, 411, 421, 520, 923];

/// Motion G codes (group 1, and G80).
const MOTION_G: &[u32] =
    &[0, 10, 20, 30, 330, 331, 730, 740, 760, 800, 810, 820, 830, 840, 850, 860, 870, 880, 890];

/// M codes LinuxCNC has.
const KNOWN_M: &[u32] = &[
    0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 19, 30, 48, 49, 50, 51, 52, 53, 60, 61, 62, 63, 64, 65, 66, 67, 68, 70, 71,
    72, 73,
];

/// M codes recognised but not modelled (NC-1004).
const NOT_MODELLED_M: &[u32] = &[61, 62, 63, 64, 65, 66, 67, 68, 70, 71, 72];
