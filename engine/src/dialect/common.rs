//! Shared interpretation pieces: reading a block's words, turning them into lengths, feeds and
//! times with range checks, and the plant settings every dialect shares.

use crate::alarm::{Alarm, AlarmKind};
use crate::exec::{PlantConfig, PlcConfig};
use crate::params::Params;
use crate::parse::{Block, Word};
use crate::trace::{AXES, AXIS_LETTERS};
use crate::units::{Decimal, Micros, Nm, NM_PER_INCH, NM_PER_MM};

/// Plant settings from the parameters that every dialect names alike (`nc.*`, `plc.*`), plus the
/// dialect's ids for the per-axis rapid rate, rapid time constant and backlash.
pub fn plant_config(p: &Params, rapid: &str, rapid_ramp: &str, backlash: &str) -> PlantConfig {
    let ms = |id: &str| (p.get(id) * 1000.0) as Micros;
    let mut rapid_nm_min = [0.0; AXES];
    let mut rapid_ramp_us = [0; AXES];
    let mut backlash_nm = [0; AXES];
    for (i, &l) in AXIS_LETTERS.iter().enumerate() {
        rapid_nm_min[i] = p.get_axis(rapid, Some(l)) * 1e6;
        rapid_ramp_us[i] = (p.get_axis(rapid_ramp, Some(l)) * 1000.0) as Micros;
        backlash_nm[i] = (p.get_axis(backlash, Some(l)) * 1e6).round() as Nm;
    }
    let period = p.get("nc.period_us") as Micros;
    PlantConfig {
        period_us: [1000, 2000, 4000, 8000].into_iter().find(|&v| v >= period).unwrap_or(8000),
        rapid_nm_min,
        rapid_ramp_us,
        feed_max_nm_min: p.get("nc.feed_max_mm_min") * 1e6,
        feed_ramp_us: ms("nc.feed_ramp_ms"),
        dry_run_nm_min: p.get("nc.dry_run_mm_min") * 1e6,
        backlash_nm,
        spindle_max_rpm: p.get("nc.spindle_max_rpm") as u32,
        spindle_ramp_us: ms("nc.spindle_ramp_ms"),
        rigid_max_rpm: p.get("nc.rt_max_rpm") as u32,
        rigid_ramp_us: ms("nc.rt_ramp_ms"),
        hold_in_rigid_tap: false,
        orient_us: ms("nc.orient_ms"),
        excess_error_nm: 1_000_000,
        tool_change_us: 0,
        coordinated_rapid: false,
        feed_waits_at_speed: false,
        plc: PlcConfig {
            fin_us: ms("plc.fin_ms"),
            fin_fall_us: ms("plc.fin_fall_ms"),
            sppos_request_us: ms("plc.sppos_request_ms"),
            sppos_reach_us: ms("plc.sppos_reach_ms"),
            rgtap_us: ms("plc.rgtap_ms"),
            rgtap_fall_us: ms("plc.rgtap_fall_ms"),
            m29_timeout_us: ms("plc.m29_timeout_ms"),
            fin_timeout_us: ms("plc.fin_timeout_ms"),
            spindle_stall_us: ms("plc.spindle_stall_ms"),
            zsp_us: ms("plc.zsp_ms"),
        },
    }
}

/// The words of one block by letter, G and M codes listed apart; a letter written twice (other
/// than G and M) is an alarm.
#[derive(Debug)]
pub struct Words<'a> {
    /// The block.
    pub block: &'a Block,
    by_letter: [Option<Word>; 26],
    /// G codes in order, as value × 10 (`G84.2` → 842).
    pub g: Vec<(u32, Word)>,
    /// M codes in order.
    pub m: Vec<(u32, Word)>,
}

impl<'a> Words<'a> {
    /// Collects the words, refusing duplicates and malformed G/M numbers.
    pub fn new(block: &'a Block) -> Result<Self, Alarm> {
        let mut w = Words { block, by_letter: [None; 26], g: Vec::new(), m: Vec::new() };
        for word in &block.words {
            match word.letter {
                'G' => {
                    let v = word.value;
                    let tenths = v.scaled(10);
                    if v.mantissa < 0 || tenths > 9999 || v.scaled(1000) != tenths * 100 {
                        return Err(w.alarm(AlarmKind::ImproperGCode, word, format!("G{}", v.display())));
                    }
                    w.g.push((tenths as u32, *word));
                }
                'M' => {
                    let code = word.value.as_int().filter(|c| (0..=99_999_999).contains(c));
                    match code {
                        Some(c) => w.m.push((c as u32, *word)),
                        None => {
                            return Err(w.alarm(
                                AlarmKind::WordOutOfRange,
                                word,
                                format!("M{}: an M code is a whole number 0..99999999", word.value.display()),
                            ))
                        }
                    }
                }
                l => {
                    let i = (l as u8 - b'A') as usize;
                    if w.by_letter[i].is_some() {
                        return Err(w.alarm(
                            AlarmKind::IllegalWord,
                            word,
                            format!("{l} written twice in one block"),
                        ));
                    }
                    w.by_letter[i] = Some(*word);
                }
            }
        }
        Ok(w)
    }

    /// The word with this letter.
    pub fn get(&self, letter: char) -> Option<Word> {
        self.by_letter[(letter as u8 - b'A') as usize]
    }

    /// Whether the letter is present.
    pub fn has(&self, letter: char) -> bool {
        self.get(letter).is_some()
    }

    /// Whether any of the letters is present.
    pub fn any(&self, letters: &str) -> bool {
        letters.chars().any(|l| self.has(l))
    }

    /// Whether G code `tenths` (G×10) is in the block.
    pub fn has_g(&self, tenths: u32) -> bool {
        self.g.iter().any(|(g, _)| *g == tenths)
    }

    /// An alarm located at a word of this block.
    pub fn alarm(&self, kind: AlarmKind, word: &Word, detail: String) -> Alarm {
        Alarm::new(kind, detail).at(self.block.line, Some(word.col))
    }

    /// An alarm located at this block.
    pub fn block_alarm(&self, kind: AlarmKind, detail: String) -> Alarm {
        Alarm::new(kind, detail).at(self.block.line, None)
    }

    /// An integer word in `lo..=hi` (no decimal point allowed).
    pub fn int_in(&self, letter: char, lo: i64, hi: i64, what: &str) -> Result<Option<i64>, Alarm> {
        let Some(w) = self.get(letter) else { return Ok(None) };
        match w.value.as_int() {
            Some(v) if !w.value.point && (lo..=hi).contains(&v) => Ok(Some(v)),
            _ => Err(self.alarm(
                AlarmKind::WordOutOfRange,
                &w,
                format!("{letter}{}: {what} must be a whole number {lo}..{hi}", w.value.display()),
            )),
        }
    }
}

/// Formats a G code given as value × 10.
pub fn g_name(tenths: u32) -> String {
    if tenths.is_multiple_of(10) {
        format!("G{:02}", tenths / 10)
    } else {
        format!("G{:02}.{}", tenths / 10, tenths % 10)
    }
}

/// How lengths are read: metric or inch, and what a number without decimal point means.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Units {
    /// G20: inch.
    pub inch: bool,
    /// A number without decimal point is in mm/inch (calculator type).
    pub dpi: bool,
    /// Least input increment in nm (metric); inch uses a tenth of it in 0.1 µinch terms.
    pub increment_nm: i64,
}

/// The largest coordinate a word may give, nm (99999.999 mm).
pub const MAX_COORD_NM: Nm = 99_999_999_000;

impl Units {
    /// nm in one program unit (mm or inch).
    pub fn unit_nm(self) -> i64 {
        if self.inch {
            NM_PER_INCH
        } else {
            NM_PER_MM
        }
    }

    /// A length word in nm (program units; no diameter handling).
    pub fn len(self, d: Decimal) -> Nm {
        if d.point || self.dpi {
            d.scaled(self.unit_nm())
        } else if self.inch {
            // IS-B inch: 0.0001 in = 2540 nm; IS-C: 254 nm.
            d.mantissa.saturating_mul(self.increment_nm * 254 / 100)
        } else {
            d.mantissa.saturating_mul(self.increment_nm)
        }
    }

    /// A length word in nm, checked against ±99999.999 mm.
    pub fn coord(self, w: &Words, letter: char) -> Result<Option<Nm>, Alarm> {
        let Some(word) = w.get(letter) else { return Ok(None) };
        let v = self.len(word.value);
        // unsigned_abs: a saturated i64::MIN (a huge negative word) has no i64 magnitude.
        if v.unsigned_abs() > MAX_COORD_NM as u64 {
            return Err(w.alarm(
                AlarmKind::WordOutOfRange,
                &word,
                format!("{letter}{}: a coordinate must be within ±99999.999 mm", word.value.display()),
            ));
        }
        Ok(Some(v))
    }
}

/// A dwell word P in ms as an integer (`P3000` = 3 s); with a decimal point, seconds when
/// `point_is_seconds` (Haas `P.5`), else refused.
pub fn dwell_p(w: &Words, point_is_seconds: bool) -> Result<Option<Micros>, Alarm> {
    let Some(word) = w.get('P') else { return Ok(None) };
    let v = word.value;
    let us = if v.point {
        if !point_is_seconds {
            return Err(w.alarm(
                AlarmKind::WordOutOfRange,
                &word,
                format!("P{}: dwell P is a whole number of ms (0..99999999)", v.display()),
            ));
        }
        v.scaled(1_000_000)
    } else {
        v.mantissa.saturating_mul(1000)
    };
    if !(0..=99_999_999_000).contains(&us) {
        return Err(w.alarm(
            AlarmKind::WordOutOfRange,
            &word,
            format!("P{}: dwell must be 0..99999999 ms", v.display()),
        ));
    }
    Ok(Some(us as Micros))
}

/// The dwell of a lathe G04: P in ms (as [`dwell_p`]), else X or U in seconds (0..99999 s), else
/// none.
pub fn lathe_dwell(w: &Words) -> Result<Micros, Alarm> {
    if let Some(p) = dwell_p(w, false)? {
        return Ok(p);
    }
    let Some(xw) = w.get('X').or(w.get('U')) else { return Ok(0) };
    let us = xw.value.scaled(1_000_000);
    if !(0..=99_999_000_000).contains(&us) {
        return Err(w.alarm(AlarmKind::WordOutOfRange, &xw, "dwell X/U must be 0..99999 s".into()));
    }
    Ok(us as Micros)
}

/// A spindle speed word S: a whole number 0..=max rpm.
pub fn speed_s(w: &Words, max: u32) -> Result<Option<u32>, Alarm> {
    let Some(word) = w.get('S') else { return Ok(None) };
    match word.value.as_int() {
        Some(v) if (0..=max as i64).contains(&v) => Ok(Some(v as u32)),
        _ => Err(w.alarm(
            AlarmKind::WordOutOfRange,
            &word,
            format!("S{}: spindle speed must be a whole number 0..{max} rpm", word.value.display()),
        )),
    }
}

/// A tool word T: a whole number 0..99999999.
pub fn tool_t(w: &Words) -> Result<Option<u32>, Alarm> {
    Ok(w.int_in('T', 0, 99_999_999, "tool number")?.map(|v| v as u32))
}
