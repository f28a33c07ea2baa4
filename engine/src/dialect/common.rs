//! Shared interpretation pieces: reading a block's words, turning them into lengths, feeds and
//! times with range checks, and the plant settings every dialect shares.

use crate::alarm::{Alarm, AlarmKind};
use crate::exec::{OverrideLimits, PlantConfig, PlcConfig};
use crate::params::{axis, bit, num, ParamDef, ParamKind::*, Params};
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
    // An override id a table does not define keeps the project's default switch (DEC-112).
    let pct = |id: &str, default: u32| if p.def(id).is_some() { p.get(id) as u32 } else { default };
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
        spindle_brake_us: 0,
        rigid_max_rpm: p.get("nc.rt_max_rpm") as u32,
        rigid_ramp_us: ms("nc.rt_ramp_ms"),
        hold_in_rigid_tap: false,
        orient_us: ms("nc.orient_ms"),
        excess_error_nm: 1_000_000,
        tool_change_us: 0,
        coordinated_rapid: false,
        feed_waits_at_speed: false,
        spindle_override_at_once: false,
        step_stops_before_motion: false,
        index_latency_periods: 0,
        sync_run_continues: false,
        parabolic_half_accel: false,
        power_on_tolerance_nm: 0.0,
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
        overrides: OverrideLimits {
            feed_max_pct: pct("nc.feed_override_max_pct", 200),
            feed_step_pct: pct("nc.feed_override_step_pct", 1),
            spindle_min_pct: pct("nc.spindle_override_min_pct", 0),
            spindle_max_pct: pct("nc.spindle_override_max_pct", 200),
        },
    }
}

/// The `nc.*` / `plc.*` parameter rows that several dialects share, each defined once here (id,
/// name, type, range, unit, default, text). A dialect's table lists the rows it has, in its own
/// order; where its machine differs it changes the default, name or text
/// (`ParamDef { default: 3000.0, ..SPINDLE_MAX_RPM }`), never the id, type, range or unit.
#[rustfmt::skip]
pub mod rows {
    use super::*;

    /// `nc.period_us`.
    pub const PERIOD_US: ParamDef = num("nc.period_us", "interpolation period", Int, 1000.0, 8000.0, 1000.0, "us", "Interpolation period: 1000, 2000, 4000 or 8000.");
    /// `nc.increment_nm` (each dialect says which value is its default).
    pub const INCREMENT_NM: ParamDef = num("nc.increment_nm", "least input increment", Int, 100.0, 1000.0, 1000.0, "nm", "1000 (0.001 mm) or 100 (0.0001 mm).");
    /// `nc.dpi`.
    pub const DPI: ParamDef = bit("nc.dpi", "calculator decimal point", 1.0, "1: a word without decimal point is in mm (X50 = 50 mm); 0: in least input increments.");
    /// `nc.backlash_mm`.
    pub const BACKLASH_MM: ParamDef = axis("nc.backlash_mm", "backlash", 0.0, 2.0, 0.0, "mm", "Backlash of each axis, compensated on every reversal.");
    /// `nc.rapid_mm_min`.
    pub const RAPID_MM_MIN: ParamDef = axis("nc.rapid_mm_min", "rapid rate", 1.0, 240000.0, 6000.0, "mm/min", "Rapid traverse rate per axis (X as radius).");
    /// `nc.rapid_ramp_ms`.
    pub const RAPID_RAMP_MS: ParamDef = axis("nc.rapid_ramp_ms", "rapid time constant", 0.0, 4000.0, 100.0, "ms", "Time to reach the rapid rate.");
    /// `nc.feed_max_mm_min`.
    pub const FEED_MAX_MM_MIN: ParamDef = num("nc.feed_max_mm_min", "max cutting feed", Real, 1.0, 240000.0, 6000.0, "mm/min", "Upper limit of the cutting feed.");
    /// `nc.feed_ramp_ms`.
    pub const FEED_RAMP_MS: ParamDef = num("nc.feed_ramp_ms", "cutting time constant", Int, 0.0, 4000.0, 100.0, "ms", "Time to reach the maximum cutting feed.");
    /// `nc.feed_override_max_pct` (DEC-112; a dialect with a documented range changes the default and text).
    pub const FEED_OVERRIDE_MAX_PCT: ParamDef = num("nc.feed_override_max_pct", "feed override maximum", Int, 0.0, 254.0, 200.0, "%", "Top position of the feed override switch; a larger input acts as it (DEC-112). The documents of this dialect give no range: the project default.");
    /// `nc.feed_override_step_pct` (DEC-112).
    pub const FEED_OVERRIDE_STEP_PCT: ParamDef = num("nc.feed_override_step_pct", "feed override step", Int, 1.0, 100.0, 1.0, "%", "Step between the feed override switch's positions; an input between two acts as the lower one (DEC-112).");
    /// `nc.spindle_override_min_pct` (DEC-112).
    pub const SPINDLE_OVERRIDE_MIN_PCT: ParamDef = num("nc.spindle_override_min_pct", "spindle override minimum", Int, 0.0, 254.0, 0.0, "%", "Lowest position of the spindle override switch (DEC-112). No document of this dialect gives it: the project default.");
    /// `nc.spindle_override_max_pct` (DEC-112).
    pub const SPINDLE_OVERRIDE_MAX_PCT: ParamDef = num("nc.spindle_override_max_pct", "spindle override maximum", Int, 0.0, 254.0, 200.0, "%", "Top position of the spindle override switch (DEC-112). No document of this dialect gives it: the project default.");
    /// `nc.dry_run_mm_min`.
    pub const DRY_RUN_MM_MIN: ParamDef = num("nc.dry_run_mm_min", "dry run feed", Real, 1.0, 240000.0, 2000.0, "mm/min", "Feed of cutting moves under dry run.");
    /// `nc.spindle_max_rpm`.
    pub const SPINDLE_MAX_RPM: ParamDef = num("nc.spindle_max_rpm", "max spindle speed", Int, 1.0, 60000.0, 6000.0, "rpm", "Spindle speed limit.");
    /// `nc.spindle_ramp_ms`.
    pub const SPINDLE_RAMP_MS: ParamDef = num("nc.spindle_ramp_ms", "spindle time constant", Int, 0.0, 20000.0, 1000.0, "ms", "Time from 0 to the maximum spindle speed.");
    /// `nc.orient_ms` (each dialect says what the time covers).
    pub const ORIENT_MS: ParamDef = num("nc.orient_ms", "orientation time", Int, 0.0, 20000.0, 500.0, "ms", "Spindle orientation time.");
    /// `plc.fin_ms`.
    pub const FIN_MS: ParamDef = num("plc.fin_ms", "FIN delay", Int, 0.0, 10000.0, 16.0, "ms", "Strobe to FIN.");
    /// `plc.fin_fall_ms`.
    pub const FIN_FALL_MS: ParamDef = num("plc.fin_fall_ms", "FIN fall delay", Int, 0.0, 10000.0, 8.0, "ms", "Strobe falling to FIN falling.");
    /// `plc.fin_timeout_ms`.
    pub const FIN_TIMEOUT_MS: ParamDef = num("plc.fin_timeout_ms", "FIN timer", Int, 1.0, 600000.0, 10000.0, "ms", "No FIN within this time: alarm NC-1020.");
    /// `plc.zsp_ms`.
    pub const ZSP_MS: ParamDef = num("plc.zsp_ms", "zero-speed detection time", Int, 0.0, 10000.0, 8.0, "ms", "The spindle must stay stopped this long before the drive reports zero speed (ZSP).");
    /// `plc.sppos_request_ms` (rigid tapping with M29).
    pub const SPPOS_REQUEST_MS: ParamDef = num("plc.sppos_request_ms", "position-mode request delay", Int, 0.0, 10000.0, 8.0, "ms", "M29 strobe to the position-mode request to the drive.");
    /// `plc.sppos_reach_ms` (rigid tapping with M29).
    pub const SPPOS_REACH_MS: ParamDef = num("plc.sppos_reach_ms", "drive answer delay", Int, 0.0, 10000.0, 50.0, "ms", "Position-mode request to the drive's reached answer.");
    /// `plc.rgtap_ms` (rigid tapping with M29).
    pub const RGTAP_MS: ParamDef = num("plc.rgtap_ms", "RGTAP delay", Int, 0.0, 10000.0, 8.0, "ms", "Reached answer to RGTAP and FIN.");
    /// `plc.rgtap_fall_ms` (rigid tapping with M29).
    pub const RGTAP_FALL_MS: ParamDef = num("plc.rgtap_fall_ms", "RGTAP fall delay", Int, 0.0, 10000.0, 16.0, "ms", "F76.3 falling to RGTAP falling.");
    /// `plc.m29_timeout_ms` (rigid tapping with M29).
    pub const M29_TIMEOUT_MS: ParamDef = num("plc.m29_timeout_ms", "M29 answer timer", Int, 1.0, 600000.0, 2000.0, "ms", "No reached answer within this time after the request: alarm 5002.");
    /// `plc.spindle_stall_ms` (rigid tapping with M29).
    pub const SPINDLE_STALL_MS: ParamDef = num("plc.spindle_stall_ms", "stall timer", Int, 100.0, 600000.0, 100.0, "ms", "Spindle not rotating while rigid tapping commands it for this long: alarm 5074.");
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

#[cfg(test)]
mod tests {
    use crate::dialect::ALL;

    /// A parameter id that several dialects have means one thing: same type, range, unit and
    /// shape in every table (only the default, name and text may differ).
    #[test]
    fn shared_parameter_ids_agree_across_dialects() {
        let mut seen = std::collections::BTreeMap::new();
        for d in ALL {
            for p in d.param_table() {
                let shape = (p.kind, p.min.to_bits(), p.max.to_bits(), p.unit, p.per_axis);
                let first = seen.entry(p.id).or_insert((d.name(), shape));
                assert_eq!(first.1, shape, "{} differs between {} and {}", p.id, first.0, d.name());
            }
        }
        assert!(seen.len() > 20);
    }
}
