//! Motions of `fanuc-mill` outside the canned cycles: G00 / G01 / G02 / G03, the dwell G04, the
//! reference returns G28 / G30 and the machine-coordinate rapid G53.

use super::{locate, FanucInterp};

/// How far an R arc's radius may fall short of half the chord, nm.
const R_ARC_SLACK_NM: f64 = 10_000.0;
use crate::alarm::{Alarm, AlarmKind};
use crate::dialect::common::{dwell_p, Words};
use crate::parse::Word;
use crate::plan::{Pos, Step};
use crate::units::{Micros, Nm};

impl FanucInterp {
    /// G04: P or X in ms without decimal point, in seconds with one.
    pub(super) fn dwell(&self, w: &Words, out: &mut Vec<Step>) -> Result<(), Alarm> {
        let us = match (dwell_p(w, true)?, w.get('X')) {
            (Some(us), _) => us,
            (None, Some(x)) => {
                let v = x.value;
                let us = if v.point { v.scaled(1_000_000) } else { v.mantissa.saturating_mul(1000) };
                if !(0..=99_999_999_000).contains(&us) {
                    return Err(w.alarm(
                        AlarmKind::WordOutOfRange,
                        &x,
                        format!("X{}: dwell must be 0..99999999 ms", v.display()),
                    ));
                }
                us as Micros
            }
            (None, None) => 0,
        };
        if us > 0 {
            out.push(Step::Dwell { us });
        }
        Ok(())
    }

    /// G28 / G30: rapid to the intermediate point, then to the reference point (machine zero) on
    /// the axes written.
    pub(super) fn reference_return(
        &mut self,
        w: &Words,
        code: u32,
        out: &mut Vec<Step>,
    ) -> Result<(), Alarm> {
        if code == 300 {
            w.int_in('P', 2, 4, "G30 reference point number")?;
        }
        let words = self.axis_words(w)?;
        if words.iter().all(Option::is_none) {
            return Ok(());
        }
        let mid = self.target(&words);
        out.push(Step::Rapid { target: mid });
        let mut home = mid;
        for (i, v) in words.iter().enumerate() {
            if v.is_some() {
                home[i] = 0;
            }
        }
        out.push(Step::Rapid { target: home });
        self.pos = home;
        Ok(())
    }

    /// A block outside the canned cycles: G00 / G01 / G02 / G03 with its axis words.
    pub(super) fn motion_block(&mut self, w: &Words, out: &mut Vec<Step>) -> Result<(), Alarm> {
        let words = self.axis_words(w)?;
        let gword = w.g.iter().rev().find(|(c, _)| matches!(c, 0 | 10 | 20 | 30)).map(|g| g.1);
        let arc = matches!(self.motion, 2 | 3);
        if words.iter().all(Option::is_none) && !(arc && w.any("IJKR")) {
            return Ok(());
        }
        let target = self.target(&words);
        let step = match self.motion {
            0 => Some(Step::Rapid { target }),
            1 => Some(Step::Feed { target, feed: self.feed(w, gword, "G01")? }),
            m => self.arc(w, m == 2, target, gword)?,
        };
        out.extend(step);
        self.pos = target;
        Ok(())
    }

    /// G02 / G03 in the active plane, centre by I J K (incremental from the start) or R.
    fn arc(&self, w: &Words, cw: bool, target: Pos, gword: Option<Word>) -> Result<Option<Step>, Alarm> {
        let name = if cw { "G02" } else { "G03" };
        let (a, b, _) = self.plane.axes();
        let (sx, sy) = (self.pos[a] as f64, self.pos[b] as f64);
        let (ex, ey) = (target[a] as f64, target[b] as f64);
        let center = if let Some(rw) = w.get('R') {
            let r = self.lu().coord(w, 'R')?.unwrap_or(0);
            let (dx, dy) = (ex - sx, ey - sy);
            let chord = dx.hypot(dy);
            if chord == 0.0 {
                if target == self.pos {
                    return Ok(None);
                }
                return Err(w.alarm(
                    AlarmKind::WordOutOfRange,
                    &rw,
                    format!("{name} R: the end point in the plane equals the start point"),
                ));
            }
            let (half, rad) = (chord / 2.0, (r as f64).abs());
            if r == 0 || half > rad + R_ARC_SLACK_NM {
                return Err(w.alarm(
                    AlarmKind::WordOutOfRange,
                    &rw,
                    format!("R{}: the radius is smaller than half the chord", rw.value.display()),
                ));
            }
            let dist = (rad * rad - half * half).max(0.0).sqrt();
            // Left of the chord for a short counter-clockwise arc; R < 0 (> 180°) the other side.
            let side = if cw == (r < 0) { 1.0 } else { -1.0 };
            let (nx, ny) = (-dy / chord, dx / chord);
            [
                (sx + dx / 2.0 + side * nx * dist).round() as Nm,
                (sy + dy / 2.0 + side * ny * dist).round() as Nm,
            ]
        } else {
            let letter = |slot: usize| ['I', 'J', 'K'][slot];
            if !w.has(letter(a)) && !w.has(letter(b)) {
                return Err(locate(
                    w,
                    gword,
                    AlarmKind::WordMissing,
                    format!("{name} needs {} / {} (centre) or R", letter(a), letter(b)),
                ));
            }
            let i = self.lu().coord(w, letter(a))?.unwrap_or(0);
            let j = self.lu().coord(w, letter(b))?.unwrap_or(0);
            let c = [self.pos[a].saturating_add(i), self.pos[b].saturating_add(j)];
            let rs = (sx - c[0] as f64).hypot(sy - c[1] as f64);
            let re = (ex - c[0] as f64).hypot(ey - c[1] as f64);
            let tol = self.set.arc_tolerance_nm;
            if rs == 0.0 && target == self.pos {
                // A full circle of radius 0 (centre words off the plane, a post's missing G18):
                // nothing to move (FAN-MOT decision).
                return Ok(None);
            }
            if rs == 0.0 || (tol > 0.0 && (rs - re).abs() > tol) {
                return Err(locate(
                    w,
                    gword,
                    AlarmKind::WordOutOfRange,
                    format!("{name}: the end point is not on the circle (radius {rs:.0} nm at the start, {re:.0} nm at the end)"),
                ));
            }
            c
        };
        let feed = self.feed(w, gword, name)?;
        Ok(Some(Step::Arc { target, center, plane: self.plane, clockwise: cw, feed }))
    }

    /// G53: a rapid to machine coordinates (absolute whatever G90 / G91; the offsets are zero).
    pub(super) fn machine_rapid(&mut self, w: &Words, out: &mut Vec<Step>) -> Result<(), Alarm> {
        let words = self.axis_words(w)?;
        if words.iter().all(Option::is_none) {
            return Ok(());
        }
        let mut target = self.pos;
        for (t, v) in target.iter_mut().zip(words) {
            if let Some(v) = v {
                *t = v;
            }
        }
        out.push(Step::Rapid { target });
        self.pos = target;
        Ok(())
    }
}
