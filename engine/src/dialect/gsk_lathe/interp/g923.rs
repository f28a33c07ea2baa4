//! G92.3, the variable-lead, equal tip-width threading cycle of the GSK lathe (seed 002, GSK
//! manual 3.24.14; rules GSK-G923-* in `docs/rules/gsk-lathe.md`): its words, their ranges and
//! alarms, the modal data, and the cycle handed to `plan::thread`.

use super::{GskInterp, X, Z};
use crate::alarm::{Alarm, AlarmKind};
use crate::dialect::common::Words;
use crate::parse::Word;
use crate::plan::thread::{thread_cycle, ThreadCycle};
use crate::plan::Step;
use crate::units::{Nm, NM_PER_INCH, NM_PER_MM};

/// Modal data of G92.3, kept from block to block (GSK-G923-02).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct ThreadData {
    /// Lead from F or I, nm/rev.
    lead_nm: Option<i64>,
    /// Lead change per revolution D, nm/rev² (0: constant lead).
    d_nm: i64,
    /// Run-out along the short axis J and the long axis K, nm.
    j: Nm,
    k: Nm,
    /// Tip width E, axial step Q, tool width A, nm.
    e: Nm,
    q: Nm,
    a: Nm,
    /// End point of the last G92.3 (X radius, Z), for a repeat block that gives one axis.
    end: Option<(Nm, Nm)>,
}

/// Largest run-out J / K: 99999999 least input increments.
const MAX_RUNOUT_INCREMENTS: i64 = 99_999_999;

impl GskInterp {
    /// A G92.3 block (GSK-G923-01..11): checks every word, then plans the passes.
    pub(super) fn g923(&mut self, w: &Words, t: &[Option<Nm>; 3], out: &mut Vec<Step>) -> Result<(), Alarm> {
        if let Some(word) = w.get('C').or(w.get('H')).or(w.get('P')) {
            return Err(w.alarm(
                AlarmKind::IllegalWord,
                &word,
                "G92.3 takes X(U) Z(W) R F/I J K D E Q A".into(),
            ));
        }
        let mut d = self.thread;
        let lead = self.g923_lead(w, &mut d)?;
        d.j = self.runout_word(w, 'J')?.unwrap_or(d.j);
        d.k = self.runout_word(w, 'K')?.unwrap_or(d.k);
        d.e = self.width_word(w, 'E', "tip width")?.unwrap_or(d.e);
        d.a = self.width_word(w, 'A', "tool width")?.unwrap_or(d.a);
        if let Some(dw) = w.get('D') {
            d.d_nm = self.lead_change(w, &dw)?;
        }
        if let Some(qw) = w.get('Q') {
            d.q = self.step_q(w, &qw)?;
        }
        let start = self.pos;
        let (Some(x), Some(z)) = (t[0].or(d.end.map(|e| e.0)), t[1].or(d.end.map(|e| e.1))) else {
            return Err(w.block_alarm(AlarmKind::WordMissing, "G92.3 needs the cut end X(U) and Z(W)".into()));
        };
        if z == start[Z] {
            let word = w.get('Z').or(w.get('W'));
            let detail = "G92.3 cannot cut a face thread: the cut end must differ from the start in Z".into();
            return Err(match word {
                Some(word) => w.alarm(AlarmKind::FaceThread, &word, detail),
                None => w.block_alarm(AlarmKind::FaceThread, detail),
            });
        }
        let r = self.taper_r(w, start[X], x)?;
        if d.q <= 0 {
            let detail = "G92.3 needs the axial step Q > 0".to_string();
            return Err(match w.get('Q') {
                Some(qw) => w.alarm(AlarmKind::ThreadStepZero, &qw, detail),
                None => w.block_alarm(AlarmKind::ThreadStepZero, detail),
            });
        }
        // The long axis is the longer travel of the thread (its lead is measured along it).
        let cut_start_x = x + r;
        let (dz, dx) = ((z - start[Z]).unsigned_abs(), (x - cut_start_x).unsigned_abs());
        let (long, short) = if dz >= dx { (Z, X) } else { (X, Z) };
        let len = if long == Z { dz } else { dx } as f64;
        let min_lead = self.lead_limits(w, lead, d.d_nm, len)?;
        if d.a as f64 > min_lead {
            return Err(self.width_alarm(w, 'A', AlarmKind::ToolWidthAboveLead, d.a, min_lead));
        }
        if d.e as f64 > min_lead {
            return Err(self.width_alarm(w, 'E', AlarmKind::TipWidthAboveLead, d.e, min_lead));
        }
        if d.e + d.a > lead {
            return Err(w.block_alarm(
                AlarmKind::TipWidthAboveLead,
                format!(
                    "tip width E {} mm + tool width A {} mm is above the lead {} mm: no groove is left to cut",
                    mm(d.e),
                    mm(d.a),
                    mm(lead)
                ),
            ));
        }
        d.end = Some((x, z));
        self.thread = d;
        // The run-out goes back towards the start on the short axis (the seed: "根据程序起点位置
        // 自动确定退尾方向").
        let (cut_end_short, start_short) = if short == X { (x, start[X]) } else { (z, start[Z]) };
        let away = if start_short >= cut_end_short { 1 } else { -1 };
        let runout_len = d.k.min(len as Nm);
        let mut cut_end = start;
        cut_end[X] = x;
        cut_end[Z] = z;
        let widen = lead - d.e - d.a;
        let cycle = ThreadCycle {
            start,
            infeed_axis: X,
            short_axis: short,
            long_axis: long,
            cut_start_infeed: cut_start_x,
            cut_end,
            lead_nm: lead,
            dlead_nm: d.d_nm,
            runout: if runout_len > 0 { away * d.j } else { 0 },
            runout_len,
            q: d.q,
            widen,
            passes: ThreadCycle::pass_count(widen, d.q),
            retract_on_hold: self.cfg.thread_retract,
        };
        thread_cycle(&cycle, out);
        Ok(())
    }

    /// F (lead in program units, 0.0001..500 mm) or I (threads per inch, 0.06..25400), else the
    /// modal lead (GSK-G923-03).
    fn g923_lead(&self, w: &Words, d: &mut ThreadData) -> Result<i64, Alarm> {
        let lead = match (w.get('F'), w.get('I')) {
            (Some(f), None) => {
                let v = f.value.scaled(self.units.unit_nm());
                if !(100..=500 * NM_PER_MM).contains(&v) {
                    return Err(w.alarm(
                        AlarmKind::ThreadLeadOutOfRange,
                        &f,
                        format!("F{}: the lead must be 0.0001..500 mm", f.value.display()),
                    ));
                }
                v
            }
            (None, Some(i)) => {
                let tpi = i.value.to_f64();
                if !(0.06..=25400.0).contains(&tpi) {
                    return Err(w.alarm(
                        AlarmKind::ThreadLeadOutOfRange,
                        &i,
                        format!("I{}: threads per inch must be 0.06..25400", i.value.display()),
                    ));
                }
                (NM_PER_INCH as f64 / tpi).round() as i64
            }
            (Some(_), Some(i)) => {
                return Err(w.alarm(AlarmKind::IllegalWord, &i, "F and I in one block".into()))
            }
            (None, None) => match d.lead_nm {
                Some(l) => l,
                None => {
                    return Err(w.block_alarm(AlarmKind::WordMissing, "G92.3 needs the lead F (or I)".into()))
                }
            },
        };
        d.lead_nm = Some(lead);
        Ok(lead)
    }

    /// J / K: unsigned run-out lengths, 0..99999999 least input increments (GSK-G923-04).
    fn runout_word(&self, w: &Words, letter: char) -> Result<Option<Nm>, Alarm> {
        let Some(word) = w.get(letter) else { return Ok(None) };
        let v = self.units.len(word.value);
        let max = MAX_RUNOUT_INCREMENTS.saturating_mul(self.cfg.increment_nm);
        if v < 0 || v > max {
            return Err(w.alarm(
                AlarmKind::WordOutOfRange,
                &word,
                format!(
                    "{letter}{}: the run-out must be 0..{} mm, without sign",
                    word.value.display(),
                    mm(max)
                ),
            ));
        }
        Ok(Some(v))
    }

    /// E / A: unsigned widths up to the largest lead, 500 mm (GSK-G923-06).
    fn width_word(&self, w: &Words, letter: char, what: &str) -> Result<Option<Nm>, Alarm> {
        let Some(word) = w.get(letter) else { return Ok(None) };
        let v = self.units.len(word.value);
        if !(0..=500 * NM_PER_MM).contains(&v) {
            return Err(w.alarm(
                AlarmKind::WordOutOfRange,
                &word,
                format!("{letter}{}: the {what} must be 0..500 mm, without sign", word.value.display()),
            ));
        }
        Ok(Some(v))
    }

    /// D: the lead change per revolution, ±0.001..±500 mm, 0 for a constant lead (GSK-G923-07).
    fn lead_change(&self, w: &Words, dw: &Word) -> Result<i64, Alarm> {
        let v = self.units.len(dw.value);
        if v != 0 && !(NM_PER_MM / 1000..=500 * NM_PER_MM).contains(&v.saturating_abs()) {
            return Err(w.alarm(
                AlarmKind::LeadChangeOutOfRange,
                dw,
                format!(
                    "D{}: the lead change must be ±0.001..±500 mm per revolution (or 0)",
                    dw.value.display()
                ),
            ));
        }
        Ok(v)
    }

    /// Q: the axial step, > 0, in least input increments or mm by parameter 182.7 (GSK-G923-08).
    fn step_q(&self, w: &Words, qw: &Word) -> Result<Nm, Alarm> {
        let (v, ok) = if self.cfg.q_in_mm || qw.value.point {
            let v = qw.value.scaled(self.units.unit_nm());
            (v, v <= 9_999_999_900)
        } else {
            let n = qw.value.mantissa;
            // 999999999 increments at IS-C (0.1 µm), 9999999 at IS-B (1 µm): 99.9999 mm / 9.999999 mm.
            let max = if self.cfg.increment_nm <= 100 { 999_999_999 } else { 9_999_999 };
            (n.saturating_mul(self.cfg.increment_nm), n <= max)
        };
        if v < 0 || !ok {
            return Err(w.alarm(
                AlarmKind::WordOutOfRange,
                qw,
                format!(
                    "Q{}: the axial step must be above 0, without sign, within its range",
                    qw.value.display()
                ),
            ));
        }
        Ok(v)
    }

    /// R (radius, cut start − cut end): when its sign differs from U's it may not exceed |U/2|
    /// (GSK-G923-09).
    fn taper_r(&self, w: &Words, start_x: Nm, end_x: Nm) -> Result<Nm, Alarm> {
        let Some(rw) = w.get('R') else { return Ok(0) };
        let r = self.units.coord(w, 'R')?.unwrap_or(0);
        let u = end_x - start_x;
        if r != 0 && u != 0 && r.signum() != u.signum() && r.abs() > u.abs() {
            return Err(w.alarm(
                AlarmKind::WordOutOfRange,
                &rw,
                format!(
                    "R{}: with a sign opposite to U, |R| must not exceed |U/2| = {} mm",
                    rw.value.display(),
                    mm(u.abs())
                ),
            ));
        }
        Ok(r)
    }

    /// The smallest lead of the thread; alarms when the lead through D leaves 0.0001..500 mm or
    /// would reach zero before the end (GSK-G923-10). Uses lead² = F² + 2·D·travel.
    fn lead_limits(&self, w: &Words, lead: i64, d: i64, len: f64) -> Result<f64, Alarm> {
        let f = lead as f64;
        let sq = f * f + 2.0 * d as f64 * len;
        let end = sq.max(0.0).sqrt();
        if d == 0 {
            return Ok(f);
        }
        let bad = if sq <= 0.0 || end < 100.0 {
            Some("would reach zero (negative lead) before the cut end".to_string())
        } else if end > 500e6 {
            Some(format!("would reach {} mm at the cut end, above 500 mm", mm(end.round() as Nm)))
        } else {
            None
        };
        if let Some(why) = bad {
            let detail = format!("the lead {} mm changing by D {} mm per revolution {why}", mm(lead), mm(d));
            return Err(match w.get('D') {
                Some(dw) => w.alarm(AlarmKind::ThreadLeadOutOfRange, &dw, detail),
                None => w.block_alarm(AlarmKind::ThreadLeadOutOfRange, detail),
            });
        }
        Ok(f.min(end))
    }

    fn width_alarm(&self, w: &Words, letter: char, kind: AlarmKind, v: Nm, min_lead: f64) -> Alarm {
        let what = if letter == 'A' { "tool width A" } else { "tip width E" };
        let detail =
            format!("{what} {} mm is above the smallest lead {} mm", mm(v), mm(min_lead.round() as Nm));
        match w.get(letter) {
            Some(word) => w.alarm(kind, &word, detail),
            None => w.block_alarm(kind, detail),
        }
    }
}

fn mm(nm: Nm) -> String {
    crate::units::nm_to_mm_string(nm)
}
