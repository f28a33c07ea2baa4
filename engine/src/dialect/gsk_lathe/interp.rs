//! The `gsk-lathe` interpreter: modal state and block → steps, including G84/G88 rigid tapping
//! (seed 000; rules GSK-* in `docs/rules/gsk-lathe.md`).

mod g923;

use crate::alarm::{Alarm, AlarmKind};
use crate::dialect::common::{dwell_p, g_name, lathe_dwell, speed_s, tool_t, Units, Words};
use crate::dialect::Interpreter;
use crate::input::CurrentSource;
use crate::params::Params;
use crate::parse::{Block, Word};
use crate::plan::rigid_tap::{rigid_tap, Peck, RigidTap};
use crate::plan::{Feed, OverloadWatch, Plane, Pos, SpindleEffect, Step};
use crate::trace::{Phase, AXES};
use crate::units::{Micros, Nm, NM_PER_INCH, NM_PER_MM};

const X: usize = 0;
const Z: usize = 2;
const C: usize = 5;

/// Data of the modal tapping cycle, kept for the next hole (GSK-RT-02).
#[derive(Debug, Clone, Copy, PartialEq)]
struct TapData {
    /// 84 (face, tap axis Z) or 88 (radial, tap axis X).
    g: u32,
    bottom: Nm,
    dwell_us: Micros,
    q: Nm,
    r: Nm,
    j: Option<i64>,
    lead_nm: i64,
    right_hand: bool,
    d: Option<u32>,
}

/// Parameters the interpreter reads.
#[derive(Debug, Clone, Copy)]
struct Cfg {
    clamp_code: u32,
    q_in_mm: bool,
    rtcrg: bool,
    overload_spindle: bool,
    rtori: bool,
    overload_delay_us: Micros,
    overload_pct: u32,
    d_clamp: bool,
    thread_retract: bool,
    rt_max_rpm: u32,
    spindle_max_rpm: u32,
    increment_nm: i64,
}

/// The interpreter.
pub struct GskInterp {
    cfg: Cfg,
    units: Units,
    /// Program position (physical, X as radius).
    pos: Pos,
    absolute_only: bool,
    /// Group 01 as G×10 (0, 10, 20, 30, 840, 880).
    motion: u32,
    /// Group 01 before the tapping cycle, restored when it ends (GSK-RT-20).
    saved_motion: u32,
    per_rev: bool,
    feed: Option<f64>,
    s_cmd: u32,
    rigid: bool,
    /// M29 given and no tapping block yet: an axis move now is an alarm (GSK-RT-12).
    m29_pending: bool,
    oriented: bool,
    tap: Option<TapData>,
    inch: bool,
    /// Modal data of G92.3 (GSK-G923-02).
    thread: g923::ThreadData,
}

impl GskInterp {
    /// Power-on state.
    pub fn new(p: &Params) -> Self {
        let cfg = Cfg::from(p);
        GskInterp {
            units: Units { inch: false, dpi: p.bit("nc.dpi"), increment_nm: cfg.increment_nm },
            cfg,
            pos: [0; AXES],
            absolute_only: false,
            motion: 0,
            saved_motion: 0,
            per_rev: false,
            feed: None,
            s_cmd: 0,
            rigid: false,
            m29_pending: false,
            oriented: false,
            tap: None,
            inch: false,
            thread: g923::ThreadData::default(),
        }
    }
}

impl Cfg {
    fn from(p: &Params) -> Cfg {
        Cfg {
            clamp_code: p.get("170") as u32,
            q_in_mm: p.bit("182.7"),
            rtcrg: p.bit("186.2"),
            overload_spindle: p.bit("186.5"),
            rtori: p.bit("186.7"),
            overload_delay_us: (p.get("270") * 1000.0) as Micros,
            overload_pct: p.get("271") as u32,
            d_clamp: p.get("nc.d_above_150") != 0.0,
            thread_retract: p.bit("nc.thread_retract"),
            rt_max_rpm: p.get("nc.rt_max_rpm") as u32,
            spindle_max_rpm: p.get("nc.spindle_max_rpm") as u32,
            increment_nm: p.get("nc.increment_nm") as i64,
        }
    }
}

impl GskInterp {
    /// X word (diameter) or U (incremental diameter) → physical radius target.
    fn axis_target(
        &self,
        w: &Words,
        abs: char,
        inc: char,
        slot: usize,
        diameter: bool,
    ) -> Result<Option<Nm>, Alarm> {
        let div = if diameter { 2 } else { 1 };
        if let Some(v) = self.units.coord(w, abs)? {
            if w.has(inc) {
                let word = w.get(inc).unwrap();
                return Err(w.alarm(AlarmKind::IllegalWord, &word, format!("{abs} and {inc} in one block")));
            }
            return Ok(Some(v / div));
        }
        if self.absolute_only {
            return Ok(None);
        }
        Ok(self.units.coord(w, inc)?.map(|v| self.pos[slot] + v / div))
    }

    /// The X, Z, C targets of a block (None where not given).
    fn targets(&self, w: &Words) -> Result<[Option<Nm>; 3], Alarm> {
        Ok([
            self.axis_target(w, 'X', 'U', X, true)?,
            self.axis_target(w, 'Z', 'W', Z, false)?,
            self.axis_target(w, 'C', 'H', C, false)?,
        ])
    }

    fn moved_pos(&self, t: &[Option<Nm>; 3]) -> Pos {
        let mut p = self.pos;
        for (slot, v) in [X, Z, C].into_iter().zip(t) {
            if let Some(v) = v {
                p[slot] = *v;
            }
        }
        p
    }

    fn feed_word(&mut self, w: &Words) -> Result<(), Alarm> {
        if let Some(f) = w.get('F') {
            let v = f.value.scaled(self.units.unit_nm()) as f64;
            // Above 0 and not finer than the least input increment (a feed of 1 nm/min would
            // run for years, issue 15).
            if v < self.units.increment_nm.max(1) as f64 {
                return Err(w.alarm(
                    AlarmKind::WordOutOfRange,
                    &f,
                    if v <= 0.0 {
                        format!("F{}: feed must be > 0", f.value.display())
                    } else {
                        format!(
                            "F{}: feed finer than the least input increment ({} mm)",
                            f.value.display(),
                            self.units.increment_nm as f64 / NM_PER_MM as f64
                        )
                    },
                ));
            }
            self.feed = Some(v);
        }
        Ok(())
    }

    fn current_feed(&self, w: &Words) -> Result<Feed, Alarm> {
        match self.feed {
            Some(f) if self.per_rev => Ok(Feed::PerRev(f)),
            Some(f) => Ok(Feed::PerMin(f)),
            None => Err(w.block_alarm(AlarmKind::FeedZero, "no F for a feed move".into())),
        }
    }

    /// Leaving rigid tapping mode (GSK-RT-20..23): F76.3 falls; RTCRG decides the wait.
    fn cancel_rigid(&mut self, out: &mut Vec<Step>) {
        if self.rigid {
            out.push(Step::RigidExit { wait_rgtap: !self.cfg.rtcrg });
            out.push(Step::Phase(Phase::Idle));
        }
        self.rigid = false;
        self.m29_pending = false;
        self.oriented = false;
        if self.motion == 840 || self.motion == 880 {
            self.motion = self.saved_motion;
        }
        self.tap = None;
    }

    fn mcode_steps(
        &mut self,
        w: &Words,
        code: u32,
        word: &Word,
        pre: &mut Vec<Step>,
        post: &mut Vec<Step>,
    ) -> Result<(), Alarm> {
        let f = |code, effect| Step::Function { letter: 'M', code, effect };
        match code {
            3 => pre.push(f(3, SpindleEffect::Forward)),
            4 => pre.push(f(4, SpindleEffect::Reverse)),
            5 => post.push(f(5, SpindleEffect::Stop)),
            29 => {
                if self.rigid {
                    return Err(w.alarm(
                        AlarmKind::M29Repeated,
                        word,
                        "M29 while rigid tapping mode is on".into(),
                    ));
                }
                let rpm = match speed_s(w, self.cfg.spindle_max_rpm)? {
                    Some(s) => s,
                    None if self.s_cmd > 0 => self.s_cmd,
                    None => {
                        return Err(w.alarm(
                            AlarmKind::WordMissing,
                            word,
                            "M29 needs S (the tapping speed)".into(),
                        ))
                    }
                };
                if rpm == 0 || rpm > self.cfg.rt_max_rpm {
                    let sw = w.get('S').unwrap_or(*word);
                    return Err(w.alarm(
                        AlarmKind::WordOutOfRange,
                        &sw,
                        format!("S{rpm}: rigid tapping speed must be 1..{} rpm", self.cfg.rt_max_rpm),
                    ));
                }
                self.s_cmd = rpm;
                self.rigid = true;
                self.m29_pending = true;
                pre.push(Step::RigidEnter { code: 29, rpm });
            }
            0 | 1 => {
                post.push(f(code, SpindleEffect::None));
                post.push(Step::Stop { optional: code == 1 });
            }
            2 | 30 => {
                let mut c = Vec::new();
                self.cancel_rigid(&mut c);
                post.extend(c);
                post.push(f(code, SpindleEffect::Stop));
                post.push(Step::End);
            }
            98 | 99 => {
                return Err(w.alarm(
                    AlarmKind::NotModelled,
                    word,
                    format!("M{code}: subprogram calls are not modelled"),
                ))
            }
            9 => post.push(f(9, SpindleEffect::None)),
            _ => pre.push(f(code, SpindleEffect::None)),
        }
        Ok(())
    }

    fn tap_cycle(&mut self, g: u32, w: &Words, steps: &mut Vec<Step>) -> Result<(), Alarm> {
        let (tap_axis, tap_abs, tap_inc, diameter) =
            if g == 84 { (Z, 'Z', 'W', false) } else { (X, 'X', 'U', true) };
        if !self.rigid {
            return Err(w.block_alarm(
                AlarmKind::RigidSignalOff,
                format!("G{g}: rigid tapping mode is not set (M29 S_ must come first)"),
            ));
        }
        let prev = self.tap;
        let bottom = self.axis_target(w, tap_abs, tap_inc, tap_axis, diameter)?;
        let bottom = match (bottom, prev) {
            (Some(b), _) => b,
            (None, Some(t)) if t.g == g => t.bottom,
            (None, Some(_)) => {
                return Err(w.block_alarm(
                    AlarmKind::TapAxisChangedWithoutBottom,
                    format!(
                        "G{g} after the other tapping direction needs a new hole bottom {tap_abs}({tap_inc})"
                    ),
                ))
            }
            (None, None) => {
                return Err(w.block_alarm(
                    AlarmKind::WordMissing,
                    format!("G{g} needs the hole bottom {tap_abs}({tap_inc})"),
                ))
            }
        };
        let dwell_us = match dwell_p(w, false)? {
            Some(p) => p,
            None => prev.map_or(0, |t| t.dwell_us),
        };
        let q = match w.get('Q') {
            Some(qw) => self.q_word(w, &qw)?,
            None => prev.map_or(0, |t| t.q),
        };
        let r = match w.get('R') {
            Some(rw) => {
                let v = rw.value.scaled(self.units.unit_nm());
                if v > 999_999_900 {
                    return Err(w.alarm(
                        AlarmKind::WordOutOfRange,
                        &rw,
                        format!("R{}: retract must be 0..999.9999 mm", rw.value.display()),
                    ));
                }
                v
            }
            None => prev.map_or(0, |t| t.r),
        };
        let j = match w.int_in('J', 0, 1, "J (1: back to the start point after each peck)")? {
            Some(j) => Some(j),
            None => prev.and_then(|t| t.j),
        };
        let k = w.int_in('K', 1, 9999, "repeat count K")?.unwrap_or(1);
        let d = match w.get('D') {
            Some(dw) => match dw.value.as_int() {
                Some(v) if !dw.value.point && (0..=150).contains(&v) => Some(v as u32),
                Some(v) if !dw.value.point && v > 150 && self.cfg.d_clamp => Some(150),
                _ => {
                    return Err(w.alarm(
                        AlarmKind::WordOutOfRange,
                        &dw,
                        format!(
                            "D{}: overload threshold must be a whole number 0..150 %",
                            dw.value.display()
                        ),
                    ))
                }
            },
            None => prev.and_then(|t| t.d),
        };
        let (lead_nm, right_hand) = match (w.get('F'), w.get('I')) {
            (Some(f), None) => {
                let v = f.value.scaled(self.units.unit_nm());
                if v.unsigned_abs() < NM_PER_MM as u64 / 10_000 || v.unsigned_abs() > 500 * NM_PER_MM as u64 {
                    return Err(w.alarm(
                        AlarmKind::WordOutOfRange,
                        &f,
                        format!("F{}: lead must be 0.0001..500 mm (negative: left-hand)", f.value.display()),
                    ));
                }
                (v.abs(), v > 0)
            }
            (None, Some(i)) => {
                let tpi = i.value.to_f64();
                if tpi == 0.0 || !(0.06..=25400.0).contains(&tpi.abs()) {
                    return Err(w.alarm(
                        AlarmKind::WordOutOfRange,
                        &i,
                        format!(
                            "I{}: threads per inch must be 0.06..25400 (negative: left-hand)",
                            i.value.display()
                        ),
                    ));
                }
                ((NM_PER_INCH as f64 / tpi.abs()).round() as i64, tpi > 0.0)
            }
            (Some(_), Some(i)) => {
                return Err(w.alarm(AlarmKind::IllegalWord, &i, "F and I in one block".into()))
            }
            (None, None) => match prev {
                Some(t) => (t.lead_nm, t.right_hand),
                None => {
                    return Err(w.block_alarm(AlarmKind::WordMissing, format!("G{g} needs the lead F (or I)")))
                }
            },
        };
        let clamp = match w.m.iter().find(|(c, _)| *c != 29) {
            Some((code, word)) => {
                if self.cfg.clamp_code == 0 || *code != self.cfg.clamp_code {
                    return Err(w.alarm(
                        AlarmKind::ClampCodeMismatch,
                        word,
                        format!("M{code} is not the clamp code of parameter 170 ({})", self.cfg.clamp_code),
                    ));
                }
                Some(*code)
            }
            None => None,
        };
        let data = TapData { g, bottom, dwell_us, q, r, j, lead_nm, right_hand, d };
        self.tap = Some(data);
        if self.motion != 840 && self.motion != 880 {
            self.saved_motion = self.motion;
        }
        self.motion = g * 10;
        self.m29_pending = false;

        // Hole position: (X, C) for G84, (Z, C) for G88; the other axis stays (start point).
        let (pos_abs, pos_inc, pos_slot, pos_dia) =
            if g == 84 { ('X', 'U', X, true) } else { ('Z', 'W', Z, false) };
        let incremental = w.has(pos_inc) || w.has('H');
        let peck = if q > 0 && j == Some(1) {
            Peck::Deep { q }
        } else if q > 0 && r > 0 {
            Peck::HighSpeed { q, d: r }
        } else {
            Peck::None
        };
        let threshold = d.unwrap_or(self.cfg.overload_pct);
        for n in 0..k {
            let mut target = self.pos;
            if n == 0 || incremental {
                if let Some(v) = self.axis_target(w, pos_abs, pos_inc, pos_slot, pos_dia)? {
                    target[pos_slot] = v;
                }
                if let Some(v) = self.axis_target(w, 'C', 'H', C, false)? {
                    target[C] = v;
                }
            }
            steps.push(Step::Phase(Phase::Positioning));
            steps.push(Step::Rapid { target });
            self.pos = target;
            if self.cfg.rtori && !self.oriented {
                steps.push(Step::Orient);
                self.oriented = true;
            }
            if let Some(a) = clamp {
                steps.push(Step::Function { letter: 'M', code: a, effect: SpindleEffect::None });
            }
            steps.push(Step::RigidCheck { alarm: AlarmKind::RigidSignalOff });
            let start = self.pos[tap_axis];
            let overload = (threshold > 0).then_some(OverloadWatch {
                threshold_pct: threshold,
                source: if self.cfg.overload_spindle {
                    CurrentSource::Spindle
                } else {
                    CurrentSource::FeedAxis
                },
                delay_us: self.cfg.overload_delay_us,
                return_to: start,
            });
            rigid_tap(
                &RigidTap {
                    axis: tap_axis,
                    start,
                    bottom,
                    lead_nm,
                    rpm: self.s_cmd,
                    right_hand,
                    dwell_us,
                    peck,
                    extraction_pct: 100,
                    overload,
                },
                steps,
            );
            if let Some(a) = clamp {
                steps.push(Step::Function { letter: 'M', code: a + 1, effect: SpindleEffect::None });
            }
            steps.push(Step::Phase(Phase::Idle));
        }
        Ok(())
    }

    /// Q in least input increments or mm (parameter 182.7), radius, ≤ 0: no peck (GSK-RT-05).
    fn q_word(&self, w: &Words, qw: &Word) -> Result<Nm, Alarm> {
        let (v, limit_ok) = if self.cfg.q_in_mm || qw.value.point {
            let v = qw.value.scaled(self.units.unit_nm());
            (v, v.unsigned_abs() <= 9_999_999_900)
        } else {
            let Some(n) = qw.value.as_int() else { unreachable!("a number without point is integral") };
            (n.saturating_mul(self.cfg.increment_nm), n.abs() <= 99_999_999)
        };
        if !limit_ok {
            return Err(w.alarm(
                AlarmKind::WordOutOfRange,
                qw,
                format!(
                    "Q{}: depth per peck must be within ±99999999 increments (±9999.9999 mm)",
                    qw.value.display()
                ),
            ));
        }
        Ok(v.max(0))
    }
}

impl Interpreter for GskInterp {
    fn block(&mut self, block: &Block, out: &mut Vec<Step>) -> Result<(), Alarm> {
        let w = Words::new(block)?;
        let mut pre = Vec::new();
        let mut body = Vec::new();
        let mut post = Vec::new();
        // The clamp code is a cycle word in a tapping block and in a block that continues the cycle.
        let in_cycle = self.motion == 840 || self.motion == 880;
        let cancels = w.g.iter().any(|(g, _)| matches!(g, 0 | 10 | 20 | 30 | 800));
        let cycle_m_ok = w.g.iter().any(|(g, _)| *g == 840 || *g == 880) || (in_cycle && !cancels);
        // One M code per block; in a tapping block M29 and the clamp code can't share it (GSK-RT-13).
        if w.m.len() > 1 {
            let has29 = w.m.iter().any(|(c, _)| *c == 29);
            let kind = if has29 { AlarmKind::M29SharesBlock } else { AlarmKind::TooManyMCodes };
            return Err(w.alarm(kind, &w.m[1].1, "only one M code per block".into()));
        }
        if let Some(s) = speed_s(&w, self.cfg.spindle_max_rpm)? {
            if !w.m.iter().any(|(c, _)| *c == 29) {
                self.s_cmd = s;
                pre.push(Step::Function { letter: 'S', code: s, effect: SpindleEffect::Speed(s) });
            }
        }
        if let Some(t) = tool_t(&w)? {
            pre.push(Step::Function { letter: 'T', code: t, effect: SpindleEffect::None });
        }
        let mut cycle_g = None;
        let mut motion_set = None;
        let mut nonmodal = None;
        for &(g, word) in &w.g {
            match g {
                0 | 10 | 20 | 30 | 923 => motion_set = Some(g),
                840 | 880 => cycle_g = Some(g / 10),
                800 => motion_set = Some(800),
                40 | 280 | 500 => nonmodal = Some((g, word)),
                980 => self.per_rev = false,
                990 => self.per_rev = true,
                200 => self.inch = true,
                210 => self.inch = false,
                960 | 970 | 400 => {}
                _ => {
                    return Err(w.alarm(
                        AlarmKind::UnsupportedGCode,
                        &word,
                        format!("{} is not a gsk-lathe G code", g_name(g)),
                    ))
                }
            }
        }
        self.units.inch = self.inch;
        let tapping = cycle_g.is_some() || (self.motion == 840 || self.motion == 880) && motion_set.is_none();
        // In G92.3 F is the lead, not a feed (GSK-G923-03).
        let threading = motion_set == Some(923) || (self.motion == 923 && motion_set.is_none());
        if !tapping && !threading {
            self.feed_word(&w)?;
        }
        let mut m_codes = Vec::new();
        for &(code, word) in &w.m {
            if code == self.cfg.clamp_code && cycle_m_ok && code != 29 {
                continue; // the clamp code of a tapping block is a cycle word
            }
            m_codes.push((code, word));
        }
        for (code, word) in m_codes {
            self.mcode_steps(&w, code, &word, &mut pre, &mut post)?;
        }
        let targets = self.targets(&w)?;
        let moves = targets.iter().any(Option::is_some);
        // An axis move between M29 and the tapping block, the M29 block included (GSK-RT-12).
        if self.m29_pending && moves && cycle_g.is_none() {
            let word = ['X', 'U', 'Z', 'W', 'C', 'H'].iter().find_map(|&l| w.get(l)).unwrap();
            return Err(w.alarm(
                AlarmKind::AxisMoveAfterM29,
                &word,
                "axis move between M29 and G84/G88".into(),
            ));
        }
        if let Some(g) = motion_set {
            if g == 800 {
                self.cancel_rigid(&mut body);
            } else {
                if self.motion == 840 || self.motion == 880 || self.rigid {
                    self.cancel_rigid(&mut body);
                }
                self.motion = g;
            }
        }
        if let Some((g, word)) = nonmodal {
            match g {
                40 => {
                    body.push(Step::Dwell { us: lathe_dwell(&w)? });
                }
                280 => {
                    let mid = self.moved_pos(&targets);
                    let mut refp = mid;
                    for (slot, v) in [X, Z, C].into_iter().zip(targets) {
                        if v.is_some() {
                            refp[slot] = 0;
                        }
                    }
                    body.push(Step::Rapid { target: mid });
                    body.push(Step::Rapid { target: refp });
                    self.pos = refp;
                }
                _ => {
                    let _ = word;
                    return Err(w.alarm(
                        AlarmKind::NotModelled,
                        &word,
                        "G50: coordinate system setting is not modelled".into(),
                    ));
                }
            }
            out.extend(pre);
            out.extend(body);
            out.extend(post);
            return Ok(());
        }
        let cycle_active = self.motion == 840 || self.motion == 880;
        if let Some(g) = cycle_g.or(if cycle_active && moves && motion_set.is_none() {
            Some(self.motion / 10)
        } else {
            None
        }) {
            self.tap_cycle(g, &w, &mut body)?;
        } else if self.motion == 923 && (moves || motion_set == Some(923)) {
            self.g923(&w, &targets, &mut body)?;
        } else if moves {
            let target = self.moved_pos(&targets);
            match self.motion {
                0 => body.push(Step::Rapid { target }),
                10 => body.push(Step::Feed { target, feed: self.current_feed(&w)? }),
                20 | 30 => {
                    let (r, iw, kw) = (w.get('R'), w.get('I'), w.get('K'));
                    let center = arc_center(self.pos, target, self.motion == 20, r, iw, kw, &self.units, &w)?;
                    body.push(Step::Arc {
                        target,
                        center,
                        plane: Plane::Zx,
                        clockwise: self.motion == 20,
                        feed: self.current_feed(&w)?,
                    });
                }
                _ => {}
            }
            self.pos = target;
        }
        out.extend(pre);
        out.extend(body);
        out.extend(post);
        Ok(())
    }

    fn reset(&mut self, pos: Pos) {
        self.rigid = false;
        self.m29_pending = false;
        self.oriented = false;
        if self.motion == 840 || self.motion == 880 {
            self.motion = self.saved_motion;
        }
        self.tap = None;
        self.thread = g923::ThreadData::default();
        self.pos = pos;
    }

    fn set_position(&mut self, pos: Pos) {
        self.pos = pos;
    }

    fn modal(&self) -> Vec<String> {
        vec![
            g_name(self.motion),
            if self.per_rev { "G99".into() } else { "G98".into() },
            if self.inch { "G20".into() } else { "G21".into() },
        ]
    }

    fn rigid_mode(&self) -> bool {
        self.rigid
    }

    fn set_params(&mut self, p: &Params) {
        self.cfg = Cfg::from(p);
        self.units.dpi = p.bit("nc.dpi");
        self.units.increment_nm = self.cfg.increment_nm;
    }
}

/// Centre of a lathe arc (plane ZX: first axis Z, second X) from R or I/K.
#[allow(clippy::too_many_arguments)]
fn arc_center(
    start: Pos,
    end: Pos,
    cw: bool,
    r: Option<Word>,
    i: Option<Word>,
    k: Option<Word>,
    u: &Units,
    w: &Words,
) -> Result<[Nm; 2], Alarm> {
    let (sz, sx, ez, ex) = (start[Z] as f64, start[X] as f64, end[Z] as f64, end[X] as f64);
    if let Some(rw) = r {
        let rad = u.len(rw.value) as f64;
        let (dz, dx) = (ez - sz, ex - sx);
        let chord = (dz * dz + dx * dx).sqrt();
        if chord == 0.0 || chord > 2.0 * rad.abs() + 1.0 {
            return Err(w.alarm(
                AlarmKind::WordOutOfRange,
                &rw,
                format!("R{}: arc radius too small for the end point", rw.value.display()),
            ));
        }
        let h = ((rad * rad - chord * chord / 4.0).max(0.0)).sqrt();
        let (mz, mx) = ((sz + ez) / 2.0, (sx + ex) / 2.0);
        let (nz, nx) = (-dx / chord, dz / chord);
        let sign = if cw == (rad > 0.0) { -1.0 } else { 1.0 };
        return Ok([(mz + sign * h * nz).round() as Nm, (mx + sign * h * nx).round() as Nm]);
    }
    let kz = k.map_or(0, |k| u.len(k.value));
    let ix = i.map_or(0, |i| u.len(i.value));
    Ok([start[Z] + kz, start[X] + ix])
}
