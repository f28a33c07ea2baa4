//! The `knd-lathe` interpreter: modal state and block → steps for the program basics of seed 001
//! (G00, G01, G02/G03, G04, G28, G50, G32, G92, G93, G96/G97, G98/G99, M00/M02/M03/M04/M05/M08/M09/
//! M30) and the G93 tapping cycle (rules KND-* in `docs/rules/knd-lathe.md`).

use crate::alarm::{Alarm, AlarmKind};
use crate::dialect::common::{g_name, lathe_dwell, speed_s, tool_t, Units, Words};
use crate::dialect::Interpreter;
use crate::params::Params;
use crate::parse::{Block, Word};
use crate::plan::follow_tap::{follow_tap, FollowTap};
use crate::plan::{Css, Feed, Plane, Pos, SpindleEffect, Step};
use crate::trace::{Phase, AXES};
use crate::units::{Micros, Nm, NM_PER_INCH, NM_PER_MM};

const X: usize = 0;
const Z: usize = 2;

/// Parameters the interpreter reads.
#[derive(Debug, Clone, Copy)]
struct Cfg {
    rvdl: bool,
    brake_us: Micros,
    allowance_nm: Nm,
    zsp_timeout_us: Micros,
    spindle_max_rpm: u32,
    increment_nm: i64,
}

impl Cfg {
    fn from(p: &Params) -> Cfg {
        Cfg {
            rvdl: p.bit("003.RVDL"),
            brake_us: (p.get("nc.spindle_brake_ms") * 1000.0) as Micros,
            allowance_nm: (p.get("nc.g93_allowance_mm") * 1e6).round() as Nm,
            zsp_timeout_us: (p.get("nc.g93_zsp_timeout_ms") * 1000.0) as Micros,
            spindle_max_rpm: p.get("nc.spindle_max_rpm") as u32,
            increment_nm: p.get("nc.increment_nm") as i64,
        }
    }
}

/// The interpreter.
pub struct KndInterp {
    cfg: Cfg,
    units: Units,
    /// Physical position (X as radius).
    pos: Pos,
    /// Physical position of the program zero (G50), X as radius.
    zero: [Nm; 2],
    /// Group 01 as G×10 (0, 10, 20, 30, 320, 920, 930).
    motion: u32,
    per_rev: bool,
    feed: Option<f64>,
    /// Lead of G32 / G92 / G93 (nm per revolution), modal.
    lead: Option<i64>,
    s_cmd: u32,
    /// End point Z of the last G92, for a repeat with X only.
    g92_z: Option<Nm>,
    /// Spindle direction commanded: 1 (M03), −1 (M04), 0 (M05, power-on).
    spindle_dir: i8,
    /// G96 in force (power-on: G97).
    css_on: bool,
    /// The G96 surface speed, m/min, kept through G97 (KND-CSS-03).
    css_s: u32,
    /// The G50 S limit, rpm (0: none given).
    css_limit: u32,
    /// The constant surface speed last sent to the executor.
    css_sent: Option<Css>,
}

impl KndInterp {
    /// Power-on state.
    pub fn new(p: &Params) -> Self {
        let cfg = Cfg::from(p);
        KndInterp {
            units: Units { inch: false, dpi: p.bit("nc.dpi"), increment_nm: cfg.increment_nm },
            cfg,
            pos: [0; AXES],
            zero: [0; 2],
            motion: 0,
            per_rev: false,
            feed: None,
            lead: None,
            s_cmd: 0,
            spindle_dir: 0,
            g92_z: None,
            css_on: false,
            css_s: 0,
            css_limit: 0,
            css_sent: None,
        }
    }

    /// X/Z word (absolute, from the G50 zero) or U/W (incremental) → physical target.
    fn axis_target(&self, w: &Words, abs: char, inc: char) -> Result<Option<Nm>, Alarm> {
        let (slot, div, zi) = if abs == 'X' { (X, 2, 0) } else { (Z, 1, 1) };
        if let Some(v) = self.units.coord(w, abs)? {
            if let Some(word) = w.get(inc) {
                return Err(w.alarm(AlarmKind::IllegalWord, &word, format!("{abs} and {inc} in one block")));
            }
            return Ok(Some(self.zero[zi] + v / div));
        }
        Ok(self.units.coord(w, inc)?.map(|v| self.pos[slot] + v / div))
    }

    fn targets(&self, w: &Words) -> Result<[Option<Nm>; 2], Alarm> {
        Ok([self.axis_target(w, 'X', 'U')?, self.axis_target(w, 'Z', 'W')?])
    }

    fn moved(&self, t: &[Option<Nm>; 2]) -> Pos {
        let mut p = self.pos;
        if let Some(x) = t[0] {
            p[X] = x;
        }
        if let Some(z) = t[1] {
            p[Z] = z;
        }
        p
    }

    fn current_feed(&self, w: &Words) -> Result<Feed, Alarm> {
        match self.feed {
            Some(f) if self.per_rev => Ok(Feed::PerRev(f)),
            Some(f) => Ok(Feed::PerMin(f)),
            None => Err(w.block_alarm(AlarmKind::FeedZero, "no F for a feed move".into())),
        }
    }

    /// The lead of a threading or G93 block: F (mm, 0.0001..500) or I (threads per inch,
    /// 0.06..25400), else the modal lead (KND-LEX-05).
    fn lead_word(&mut self, w: &Words, g: u32) -> Result<i64, Alarm> {
        let lead = match (w.get('F'), w.get('I')) {
            (Some(f), None) => {
                let v = f.value.scaled(self.units.unit_nm());
                if !(NM_PER_MM / 10_000..=500 * NM_PER_MM).contains(&v) {
                    return Err(w.alarm(
                        AlarmKind::WordOutOfRange,
                        &f,
                        format!("F{}: lead must be 0.0001..500 mm", f.value.display()),
                    ));
                }
                v
            }
            (None, Some(i)) => {
                let tpi = i.value.to_f64();
                if !(0.06..=25400.0).contains(&tpi) {
                    return Err(w.alarm(
                        AlarmKind::WordOutOfRange,
                        &i,
                        format!("I{}: threads per inch must be 0.06..25400", i.value.display()),
                    ));
                }
                (NM_PER_INCH as f64 / tpi).round() as i64
            }
            (Some(_), Some(i)) => {
                return Err(w.alarm(AlarmKind::IllegalWord, &i, "F and I in one block".into()))
            }
            (None, None) => match self.lead {
                Some(l) => l,
                None => {
                    return Err(w.block_alarm(
                        AlarmKind::WordMissing,
                        format!("{} needs the lead F (or I)", g_name(g)),
                    ))
                }
            },
        };
        self.lead = Some(lead);
        Ok(lead)
    }

    fn mcode(
        &mut self,
        code: u32,
        word: &Word,
        w: &Words,
        pre: &mut Vec<Step>,
        post: &mut Vec<Step>,
    ) -> Result<(), Alarm> {
        let f = |code, effect| Step::Function { letter: 'M', code, effect };
        match code {
            3 => {
                self.spindle_dir = 1;
                pre.push(f(3, SpindleEffect::Forward));
            }
            4 => {
                self.spindle_dir = -1;
                pre.push(f(4, SpindleEffect::Reverse));
            }
            5 => {
                self.spindle_dir = 0;
                post.push(f(5, SpindleEffect::Stop));
            }
            0 => {
                post.push(f(0, SpindleEffect::None));
                post.push(Step::Stop { optional: false });
            }
            2 | 30 => {
                self.spindle_dir = 0;
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

    /// G93 (KND-G93-01..12): the tap axis Z follows the spindle to the end point, the spindle
    /// brakes, reverses, the tap returns, the spindle resumes its direction.
    fn g93(&mut self, w: &Words, body: &mut Vec<Step>) -> Result<(), Alarm> {
        if let Some(word) = w.get('X').or(w.get('U')) {
            return Err(w.alarm(AlarmKind::IllegalWord, &word, "G93 taps along Z only: no X/U".into()));
        }
        let Some(end) = self.axis_target(w, 'Z', 'W')? else {
            return Err(w.block_alarm(AlarmKind::WordMissing, "G93 needs the end point Z(W)".into()));
        };
        let lead_nm = self.lead_word(w, 930)?;
        let rpm = match self.css() {
            Some(c) => c.rpm(self.pos[X], self.cfg.spindle_max_rpm).round() as u32,
            None => self.s_cmd,
        };
        if self.spindle_dir == 0 || rpm == 0 {
            return Err(w.block_alarm(
                AlarmKind::SpindleNotTurning,
                "G93: the spindle must be started (M03/M04 and S > 0) before the cycle".into(),
            ));
        }
        follow_tap(
            &FollowTap {
                axis: Z,
                start: self.pos[Z],
                end,
                lead_nm,
                rpm,
                forward: self.spindle_dir > 0,
                brake_us: self.cfg.brake_us,
                allowance_nm: self.cfg.allowance_nm,
                zsp_timeout_us: Some(self.cfg.zsp_timeout_us),
                backlash: self.cfg.rvdl,
                encoder_bound: true,
                not_turning: AlarmKind::SpindleNotTurning,
                overshoot: AlarmKind::TapOvershoot,
            },
            body,
        );
        body.push(Step::Phase(Phase::Idle));
        Ok(())
    }

    /// The constant surface speed in force (G96), or None under G97.
    fn css(&self) -> Option<Css> {
        self.css_on.then_some(Css { m_min: self.css_s, limit_rpm: self.css_limit, x_zero: self.zero[0] })
    }

    /// The block's output, led by a `Step::Css` when the constant surface speed changed.
    fn emit(&mut self, out: &mut Vec<Step>, steps: [Vec<Step>; 3]) {
        let css = self.css();
        if css != self.css_sent {
            self.css_sent = css;
            out.push(Step::Css(css));
        }
        for s in steps {
            out.extend(s);
        }
    }

    /// G92 (KND-LEX-08): X to the thread's start, thread to the end point, X back, Z back.
    fn g92(&mut self, w: &Words, t: [Option<Nm>; 2], body: &mut Vec<Step>) -> Result<(), Alarm> {
        if let Some(word) = ['L', 'J', 'K', 'P'].iter().find_map(|&l| w.get(l)) {
            return Err(w.alarm(
                AlarmKind::NotModelled,
                &word,
                format!("{}: multi-start threads and thread run-out in G92 are not modelled", word.letter),
            ));
        }
        let lead = self.lead_word(w, 920)?;
        // Modal: a repeat block may give X(U) only, the end point Z staying.
        let (Some(x), Some(z)) = (t[0], t[1].or(self.g92_z)) else {
            return Err(w.block_alarm(AlarmKind::WordMissing, "G92 needs X(U) and Z(W)".into()));
        };
        self.g92_z = Some(z);
        let r = match w.get('R') {
            Some(rw) => self.units.len(rw.value),
            None => 0,
        };
        let start = self.pos;
        let mut a = start;
        a[X] = x + r;
        let mut b = a;
        b[X] = x;
        b[Z] = z;
        let mut c = b;
        c[X] = start[X];
        body.push(Step::Rapid { target: a });
        body.push(Step::HoldSuppress(true));
        body.push(Step::Feed { target: b, feed: Feed::PerRev(lead as f64) });
        body.push(Step::HoldSuppress(false));
        body.push(Step::Rapid { target: c });
        body.push(Step::Rapid { target: start });
        Ok(())
    }
}

impl Interpreter for KndInterp {
    fn block(&mut self, block: &Block, out: &mut Vec<Step>) -> Result<(), Alarm> {
        let w = Words::new(block)?;
        let (mut pre, mut body, mut post) = (Vec::new(), Vec::new(), Vec::new());
        if w.m.len() > 1 {
            return Err(w.alarm(AlarmKind::TooManyMCodes, &w.m[1].1, "only one M code per block".into()));
        }
        let mut motion_set = None;
        let mut nonmodal = None;
        let css_before = self.css();
        for &(g, word) in &w.g {
            match g {
                0 | 10 | 20 | 30 | 320 | 920 | 930 => motion_set = Some(g),
                40 | 280 | 500 => nonmodal = Some(g),
                980 => self.per_rev = false,
                990 => self.per_rev = true,
                960 => self.css_on = true,
                970 => self.css_on = false,
                900 | 940 | 700 | 710 | 720 | 730 | 740 | 750 | 760 => {
                    return Err(w.alarm(
                        AlarmKind::NotModelled,
                        &word,
                        format!("{} is a knd-lathe G code the engine does not model", g_name(g)),
                    ))
                }
                _ => {
                    return Err(w.alarm(
                        AlarmKind::UnsupportedGCode,
                        &word,
                        format!("{} is not a knd-lathe G code", g_name(g)),
                    ))
                }
            }
        }
        if self.css_on && nonmodal != Some(500) {
            // Under G96, S is the surface speed in m/min (KND-CSS-01).
            if let Some(v) = w.int_in('S', 0, 99_999, "surface speed (m/min)")? {
                self.css_s = v as u32;
            }
        } else if let Some(s) = speed_s(&w, self.cfg.spindle_max_rpm)? {
            if nonmodal != Some(500) {
                self.s_cmd = s;
                pre.push(Step::Function { letter: 'S', code: s, effect: SpindleEffect::Speed(s) });
            }
        }
        // G96 → G97 without S: the last speed of G96 becomes S (KND-CSS-04).
        if let (Some(c), false, None) = (css_before, self.css_on, w.get('S')) {
            self.s_cmd = c.rpm(self.pos[X], self.cfg.spindle_max_rpm).round() as u32;
        }
        if let Some(t) = tool_t(&w)? {
            pre.push(Step::Function { letter: 'T', code: t, effect: SpindleEffect::None });
        }
        if let Some(g) = motion_set {
            self.motion = g;
        }
        let threading = matches!(self.motion, 320 | 920 | 930);
        if !threading && nonmodal.is_none() {
            if let Some(f) = w.get('F') {
                let v = f.value.scaled(self.units.unit_nm());
                // Above 0 and not finer than the least input increment (issue 15).
                if v < self.units.increment_nm.max(1) {
                    return Err(w.alarm(
                        AlarmKind::WordOutOfRange,
                        &f,
                        if v <= 0 {
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
                self.feed = Some(v as f64);
            }
        }
        if let Some(&(code, word)) = w.m.first() {
            self.mcode(code, &word, &w, &mut pre, &mut post)?;
        }
        if let Some(g) = nonmodal {
            match g {
                40 => {
                    body.push(Step::Dwell { us: lathe_dwell(&w)? });
                }
                280 => {
                    let t = self.targets(&w)?;
                    let mid = self.moved(&t);
                    let mut refp = mid;
                    if t[0].is_some() {
                        refp[X] = 0;
                    }
                    if t[1].is_some() {
                        refp[Z] = 0;
                    }
                    body.push(Step::Rapid { target: mid });
                    body.push(Step::Rapid { target: refp });
                    self.pos = refp;
                }
                _ => {
                    // G50: the present position gets the given program coordinates (KND-LEX-07).
                    if let Some(x) = self.units.coord(&w, 'X')? {
                        self.zero[0] = self.pos[X] - x / 2;
                    }
                    if let Some(z) = self.units.coord(&w, 'Z')? {
                        self.zero[1] = self.pos[Z] - z;
                    }
                    if let Some(word) = w.get('U').or(w.get('W')) {
                        return Err(w.alarm(
                            AlarmKind::IllegalWord,
                            &word,
                            "G50 takes X, Z and S only".into(),
                        ));
                    }
                    if let Some(s) = w.get('S') {
                        if s.value
                            .as_int()
                            .is_none_or(|v| !(0..=self.cfg.spindle_max_rpm as i64).contains(&v))
                        {
                            return Err(w.alarm(
                                AlarmKind::WordOutOfRange,
                                &s,
                                format!(
                                    "S{}: G50 S must be 0..{} rpm",
                                    s.value.display(),
                                    self.cfg.spindle_max_rpm
                                ),
                            ));
                        }
                        self.css_limit = s.value.as_int().unwrap_or(0) as u32;
                    }
                }
            }
            self.emit(out, [pre, body, post]);
            return Ok(());
        }
        let t = self.targets(&w)?;
        let moves = t.iter().any(Option::is_some);
        if moves || motion_set == Some(930) {
            match self.motion {
                930 => self.g93(&w, &mut body)?,
                920 => self.g92(&w, t, &mut body)?,
                320 => {
                    let lead = self.lead_word(&w, 320)?;
                    let target = self.moved(&t);
                    body.push(Step::HoldSuppress(true));
                    body.push(Step::Feed { target, feed: Feed::PerRev(lead as f64) });
                    body.push(Step::HoldSuppress(false));
                    self.pos = target;
                }
                0 => {
                    let target = self.moved(&t);
                    body.push(Step::Rapid { target });
                    self.pos = target;
                }
                10 => {
                    let target = self.moved(&t);
                    body.push(Step::Feed { target, feed: self.current_feed(&w)? });
                    self.pos = target;
                }
                _ => {
                    let target = self.moved(&t);
                    let cw = self.motion == 20;
                    let center = arc_center(self.pos, target, cw, &w, &self.units)?;
                    body.push(Step::Arc {
                        target,
                        center,
                        plane: Plane::Zx,
                        clockwise: cw,
                        feed: self.current_feed(&w)?,
                    });
                    self.pos = target;
                }
            }
        }
        self.emit(out, [pre, body, post]);
        Ok(())
    }

    fn reset(&mut self, pos: Pos) {
        self.pos = pos;
        // Reset cancels G96: the executor has dropped it too (DEC-66).
        self.css_on = false;
        self.css_sent = None;
    }

    fn set_position(&mut self, pos: Pos) {
        self.pos = pos;
    }

    fn modal(&self) -> Vec<String> {
        vec![g_name(self.motion), if self.per_rev { "G99".into() } else { "G98".into() }]
    }

    fn rigid_mode(&self) -> bool {
        false
    }

    fn set_params(&mut self, p: &Params) {
        self.cfg = Cfg::from(p);
        self.units.dpi = p.bit("nc.dpi");
        self.units.increment_nm = self.cfg.increment_nm;
    }
}

/// Centre of a lathe arc (plane ZX: first axis Z, second X) from R (radius) or I/K (from the
/// start, I as radius).
fn arc_center(start: Pos, end: Pos, cw: bool, w: &Words, u: &Units) -> Result<[Nm; 2], Alarm> {
    let (sz, sx, ez, ex) = (start[Z] as f64, start[X] as f64, end[Z] as f64, end[X] as f64);
    if let Some(rw) = w.get('R') {
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
    let kz = w.get('K').map_or(0, |k| u.len(k.value));
    let ix = w.get('I').map_or(0, |i| u.len(i.value));
    Ok([start[Z] + kz, start[X] + ix])
}
