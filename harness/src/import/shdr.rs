//! MTConnect SHDR importer: adapter lines `timestamp|key|value|key|value...` (one line per
//! instant, changes only) read into samples, signal edges, blocks and alarms.
//!
//! Keys, when no column map names them (a map's `column`s name SHDR keys instead, with the same
//! scale, offset and level rules as CSV):
//! - positions: `X` .. `C`, alone or followed by `act`, `pos`, `abs` (`Xact`, `Zpos`), mm (deg);
//! - spindle: `S`, `Sspeed`, `S1speed`, `Srpm`, `Sact` (rpm); `Sangle`, `S1angle`, `Spos`,
//!   `S1pos` (degrees);
//! - signals by their trace names (`F76.3`, `RGTAP`, ...), values `0`/`1`, `ON`/`OFF`,
//!   `TRUE`/`FALSE`;
//! - `execution`: `ACTIVE` sets STL, `FEED_HOLD` / `INTERRUPTED` set SPL, `READY`, `STOPPED`,
//!   `PROGRAM_STOPPED`, `PROGRAM_COMPLETED`, `OPTIONAL_STOP`, `WAIT` clear both;
//! - `estop` / `emergency_stop`: `TRIGGERED` sets ESP, `ARMED` clears it;
//! - `line` gives a block (its text from a `block` key on the same line, else empty);
//! - `alarm`: `code|native_code|severity|state|text`, and the conditions `system`, `logic`,
//!   `motion`, `comms`, `cond`: `level|native_code|native_severity|qualifier|text`; an active
//!   alarm (`FAULT`) gives an `alarm` event: the engine's alarm of its native code (else code),
//!   or, for a code the engine does not know, a vendor alarm (`NC-1120`) carrying the code.
//!
//! A line with a position or spindle change gives one sample (the last value of everything else
//! held), before the line's other events. `UNAVAILABLE` changes nothing. Lines starting with `*`
//! (adapter commands) are skipped. Times are µs since the Unix epoch (`YYYY-MM-DDTHH:MM:SS[.f][Z]`).

use std::collections::VecDeque;
use std::io::BufRead;

use nc_engine::alarm::AlarmKind;
use nc_engine::trace::{axis_index, AxisSpec, Event, Sample, Signal, TraceEvent, AXIS_LETTERS};

use super::map::{ColRef, ColumnMap, Level};
use super::num::{f64_to_fixed, parse_f64, parse_u64};
use super::{char_col, read_line, recorded_alarm, Ctx, ErrorKind, Format, ImportError, RecordedMeta, Source};

/// The longest line read, bytes.
const MAX_LINE: usize = 1 << 20;

/// Keys read and left out when no map says otherwise.
const IGNORED: [&str; 22] = [
    "avail",
    "mode",
    "program",
    "program_comment",
    "Fovr",
    "Sovr",
    "Frapidovr",
    "path_feedrate",
    "Fact",
    "tool_id",
    "part_count",
    "controller_mode",
    "functional_mode",
    "message",
    "Sload",
    "Xload",
    "Yload",
    "Zload",
    "Stemp",
    "Fcmd",
    "block",
    "operator",
];

/// Condition keys.
const CONDITIONS: [&str; 5] = ["system", "logic", "motion", "comms", "cond"];

/// What a key feeds.
#[derive(Debug, Clone, Copy)]
enum Key {
    Axis { slot: usize, scale: f64, offset: f64 },
    Rpm { scale: f64, offset: f64 },
    Angle { scale: f64, offset: f64 },
    Signal { signal: Signal, level: Level, invert: bool, scale: f64, offset: f64 },
    Execution,
    Estop,
    Line,
    Alarm,
    Condition,
    Ignored,
}

/// Whether a first line looks like SHDR: an ISO date, then `|`.
pub(crate) fn looks_like_shdr(line: &[u8]) -> bool {
    let ts = line.split(|&c| c == b'|').next().unwrap_or(b"");
    ts.len() < line.len() && (parse_time(ts).is_some() || timestamp_shaped(ts))
}

/// Whether `s` has the shape `dddd-dd-ddTdd:dd:dd…` whatever its values (a timestamp of 1900
/// still makes the file SHDR, with a bad timestamp, not a CSV file without a map).
fn timestamp_shaped(s: &[u8]) -> bool {
    let s = s.trim_ascii();
    s.len() >= 19
        && s.iter().take(19).enumerate().all(|(i, c)| match i {
            4 | 7 => *c == b'-',
            10 => matches!(c, b'T' | b' '),
            13 | 16 => *c == b':',
            _ => c.is_ascii_digit(),
        })
}

/// `YYYY-MM-DDTHH:MM:SS[.fraction][Z]` as µs since the Unix epoch.
pub(crate) fn parse_time(s: &[u8]) -> Option<u64> {
    let s = s.trim_ascii();
    let s = s.strip_suffix(b"Z").unwrap_or(s);
    if s.len() < 19
        || s[4] != b'-'
        || s[7] != b'-'
        || !matches!(s[10], b'T' | b' ')
        || s[13] != b':'
        || s[16] != b':'
    {
        return None;
    }
    let num = |a: usize, b: usize| -> Option<i64> {
        let d = &s[a..b];
        d.iter().all(u8::is_ascii_digit).then(|| d.iter().fold(0i64, |n, c| n * 10 + i64::from(c - b'0')))
    };
    let (y, mo, d, h, mi, sec) =
        (num(0, 4)?, num(5, 7)?, num(8, 10)?, num(11, 13)?, num(14, 16)?, num(17, 19)?);
    if !(1..=12).contains(&mo) || !(1..=31).contains(&d) || h > 23 || mi > 59 || sec > 60 {
        return None;
    }
    let mut frac_us = 0i64;
    if s.len() > 19 {
        if s[19] != b'.' || s.len() == 20 || !s[20..].iter().all(u8::is_ascii_digit) {
            return None;
        }
        for (i, c) in s[20..].iter().enumerate().take(6) {
            frac_us += i64::from(c - b'0') * 10i64.pow(5 - i as u32);
        }
    }
    // Days from the civil date (H. Hinnant's algorithm).
    let y = if mo <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (mo + 9) % 12;
    let doy = (153 * mp + 2) / 5 + d - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    let days = era * 146_097 + doe - 719_468;
    let secs = days * 86_400 + h * 3600 + mi * 60 + sec;
    u64::try_from(secs.checked_mul(1_000_000)?.checked_add(frac_us)?).ok()
}

struct ShdrSource {
    r: Box<dyn BufRead + Send>,
    buf: Vec<u8>,
    line_no: u64,
    map: Option<ColumnMap>,
    sample: Sample,
    sig: [bool; Signal::ALL.len()],
    last_t: Option<u64>,
    named: Vec<Signal>,
}

/// Sets up an SHDR reader (SHDR has no header).
pub(crate) fn open(
    ctx: &mut Ctx,
    r: Box<dyn BufRead + Send>,
    map: Option<&ColumnMap>,
) -> Result<(RecordedMeta, Box<dyn Source>), ImportError> {
    let (axes, spindle, signals) = match map {
        Some(m) => (
            m.axes.iter().map(|a| a.axis).collect(),
            (m.rpm.is_some(), m.angle.is_some()),
            m.signals.iter().map(|s| s.signal).collect(),
        ),
        None => (
            AXIS_LETTERS
                .iter()
                .enumerate()
                .map(|(index, &letter)| AxisSpec { letter, index, diameter: false, rotary: index >= 3 })
                .collect(),
            (true, true),
            // `execution` gives these; a key named after another signal may add it.
            vec![Signal::Stl, Signal::Spl],
        ),
    };
    let meta = RecordedMeta {
        file: ctx.file.clone(),
        format: Format::Shdr,
        trace: None,
        axes,
        spindle,
        signals,
        sample_us: None,
        first_t_us: None,
    };
    let src = ShdrSource {
        r,
        buf: Vec::new(),
        line_no: 0,
        map: map.cloned(),
        sample: Sample::default(),
        sig: [false; Signal::ALL.len()],
        last_t: None,
        named: Vec::new(),
    };
    Ok((meta, Box::new(src)))
}

impl ShdrSource {
    fn key(&self, k: &str) -> Option<Key> {
        if let Some(m) = &self.map {
            let is = |c: &ColRef| matches!(c, ColRef::Name(n) if n == k);
            if let Some(a) = m.axes.iter().find(|a| is(&a.value.column)) {
                return Some(Key::Axis { slot: a.axis.index, scale: a.value.scale, offset: a.value.offset });
            }
            if let Some(v) = m.rpm.as_ref().filter(|v| is(&v.column)) {
                return Some(Key::Rpm { scale: v.scale, offset: v.offset });
            }
            if let Some(v) = m.angle.as_ref().filter(|v| is(&v.column)) {
                return Some(Key::Angle { scale: v.scale, offset: v.offset });
            }
            if let Some(s) = m.signals.iter().find(|s| is(&s.value.column)) {
                return Some(Key::Signal {
                    signal: s.signal,
                    level: s.level,
                    invert: s.invert,
                    scale: s.value.scale,
                    offset: s.value.offset,
                });
            }
            if m.ignore.iter().any(|x| x == k) {
                return Some(Key::Ignored);
            }
        }
        let mut chars = k.chars();
        if let (Some(c), rest) = (chars.next(), chars.as_str()) {
            if let Some(slot) = axis_index(c) {
                if ["", "act", "pos", "abs"].iter().any(|s| rest.eq_ignore_ascii_case(s)) {
                    return Some(Key::Axis { slot, scale: 1.0, offset: 0.0 });
                }
            }
        }
        Some(match k {
            "S" | "Sspeed" | "S1speed" | "Srpm" | "Sact" => Key::Rpm { scale: 1.0, offset: 0.0 },
            "Sangle" | "S1angle" | "Spos" | "S1pos" => Key::Angle { scale: 1.0, offset: 0.0 },
            "execution" => Key::Execution,
            "estop" | "emergency_stop" | "emergencyStop" => Key::Estop,
            "line" => Key::Line,
            "alarm" => Key::Alarm,
            _ if CONDITIONS.contains(&k) => Key::Condition,
            _ if IGNORED.contains(&k) => Key::Ignored,
            _ => {
                let signal = Signal::from_name(k)?;
                Key::Signal { signal, level: Level::NonZero, invert: false, scale: 1.0, offset: 0.0 }
            }
        })
    }

    fn set_sig(&mut self, t: u64, s: Signal, v: bool, evs: &mut Vec<TraceEvent>) {
        let i = Signal::ALL.iter().position(|x| *x == s).unwrap_or(0);
        if self.sig[i] != v {
            self.sig[i] = v;
            evs.push(TraceEvent { t_us: t, event: Event::Signal { signal: s, value: v } });
        }
    }

    /// Parses the line in `self.buf` into `out` (nothing is queued when it has an error).
    fn line(&mut self, ctx: &Ctx, out: &mut VecDeque<TraceEvent>) -> Result<(), ImportError> {
        let line = std::mem::take(&mut self.buf);
        let res = self.parse(ctx, &line, out);
        self.buf = line;
        res
    }

    fn parse(&mut self, ctx: &Ctx, line: &[u8], out: &mut VecDeque<TraceEvent>) -> Result<(), ImportError> {
        let no = self.line_no;
        let fields: Vec<(usize, &[u8])> = {
            let mut v = Vec::new();
            let mut start = 0;
            for i in memchr::memchr_iter(b'|', line) {
                v.push((start, &line[start..i]));
                start = i + 1;
            }
            v.push((start, &line[start..]));
            v
        };
        let err = |kind: ErrorKind, at: usize, msg: String, exp: &str| {
            ctx.err(kind, no, char_col(line, at), msg).expected(exp.to_string()).with_line(line)
        };
        let t = parse_time(fields[0].1).ok_or_else(|| {
            err(
                ErrorKind::BadRow,
                0,
                format!(
                    "bad timestamp `{}`",
                    crate::diag::printable(&String::from_utf8_lossy(fields[0].1), 60)
                ),
                "YYYY-MM-DDTHH:MM:SS[.ffffff]Z, from 1970 on",
            )
        })?;
        if let Some(last) = self.last_t.filter(|l| t < *l) {
            return Err(err(
                ErrorKind::NonMonotonicTime,
                0,
                format!("time goes back: {t} µs after {last} µs"),
                "a timestamp not before the one of the line before",
            ));
        }
        let (saved_sample, saved_sig) = (self.sample, self.sig);
        let mut evs: Vec<TraceEvent> = Vec::new();
        let mut moved = false;
        let mut block_text = String::new();
        if let Some(i) = fields.iter().skip(1).step_by(2).position(|(_, k)| *k == b"block") {
            if let Some((_, v)) = fields.get(2 + 2 * i) {
                block_text = String::from_utf8_lossy(v).trim().to_string();
            }
        }
        let mut i = 1;
        let res = (|| {
            while i < fields.len() {
                let (kat, kb) = fields[i];
                let k = String::from_utf8_lossy(kb).trim().to_string();
                let Some(key) = self.key(&k) else {
                    return Err(err(ErrorKind::Unknown, kat, format!("unknown key `{k}`"), "a key of docs/checking.md, or a column map naming it (or listing it under `ignore:`)"));
                };
                let n_vals = if matches!(key, Key::Alarm | Key::Condition) { 5 } else { 1 };
                if i + n_vals >= fields.len() {
                    return Err(err(
                        ErrorKind::Truncated,
                        line.len(),
                        format!("key `{k}` without its {n_vals} value(s)"),
                        "`|value` after each key",
                    ));
                }
                let (vat, vb) = fields[i + 1];
                let v = String::from_utf8_lossy(vb).trim().to_string();
                let bad = |exp: &str| err(ErrorKind::BadRow, vat, format!("bad value `{v}` of `{k}`"), exp);
                if v != "UNAVAILABLE" {
                    match key {
                        Key::Axis { slot, scale, offset } => {
                            let x = parse_f64(vb).ok_or_else(|| bad("a number"))?;
                            self.sample.axes[slot] = f64_to_fixed(x * scale + offset, 6)
                                .ok_or_else(|| bad("a position in range"))?;
                            moved = true;
                        }
                        Key::Rpm { scale, offset } => {
                            let x = parse_f64(vb).ok_or_else(|| bad("a number"))?;
                            self.sample.spindle_mrpm =
                                f64_to_fixed(x * scale + offset, 3).ok_or_else(|| bad("a speed in range"))?;
                            moved = true;
                        }
                        Key::Angle { scale, offset } => {
                            let x = parse_f64(vb).ok_or_else(|| bad("a number"))?;
                            let m = f64_to_fixed(x * scale + offset, 3)
                                .ok_or_else(|| bad("an angle in range"))?;
                            self.sample.spindle_mdeg = m.rem_euclid(360_000);
                            moved = true;
                        }
                        Key::Signal { signal, level, invert, scale, offset } => {
                            if !self.named.contains(&signal) {
                                self.named.push(signal);
                            }
                            let word = match v.to_ascii_uppercase().as_str() {
                                "ON" | "TRUE" | "HIGH" => Some(true),
                                "OFF" | "FALSE" | "LOW" => Some(false),
                                _ => None,
                            };
                            let lv = match (word, level) {
                                (Some(b), _) => b,
                                (None, Level::Bit(b)) => {
                                    parse_u64(vb).ok_or_else(|| bad("an unsigned integer"))? >> b & 1 == 1
                                }
                                (None, lv) => {
                                    let x = parse_f64(vb).ok_or_else(|| bad("0, 1, ON, OFF or a number"))?
                                        * scale
                                        + offset;
                                    match lv {
                                        Level::Above(th) => x > th,
                                        Level::Below(th) => x < th,
                                        _ => x != 0.0,
                                    }
                                }
                            };
                            self.set_sig(t, signal, lv != invert, &mut evs);
                        }
                        Key::Execution => {
                            let (stl, spl) = match v.as_str() {
                                "ACTIVE" => (true, false),
                                "FEED_HOLD" | "INTERRUPTED" => (false, true),
                                "READY" | "STOPPED" | "PROGRAM_STOPPED" | "PROGRAM_COMPLETED" | "OPTIONAL_STOP" | "WAIT" => (false, false),
                                _ => return Err(bad("ACTIVE, FEED_HOLD, INTERRUPTED, READY, STOPPED, PROGRAM_STOPPED, PROGRAM_COMPLETED, OPTIONAL_STOP or WAIT")),
                            };
                            self.set_sig(t, Signal::Stl, stl, &mut evs);
                            self.set_sig(t, Signal::Spl, spl, &mut evs);
                        }
                        Key::Estop => {
                            let on = match v.as_str() {
                                "TRIGGERED" => true,
                                "ARMED" => false,
                                _ => return Err(bad("TRIGGERED or ARMED")),
                            };
                            self.set_sig(t, Signal::Esp, on, &mut evs);
                        }
                        Key::Line => {
                            let l = parse_u64(vb)
                                .and_then(|l| u32::try_from(l).ok())
                                .ok_or_else(|| bad("a line number"))?;
                            evs.push(TraceEvent {
                                t_us: t,
                                event: Event::Block { line: l, text: block_text.clone() },
                            });
                        }
                        Key::Alarm | Key::Condition => {
                            let f = |j: usize| String::from_utf8_lossy(fields[i + j].1).trim().to_string();
                            let (active, codes, text) = if matches!(key, Key::Alarm) {
                                let state = f(4);
                                (state != "CLEARED", [f(2), f(1)], f(5))
                            } else {
                                (v == "FAULT", [f(2), String::new()], f(5))
                            };
                            if active {
                                // The engine's alarm of the native code (else the code); a code
                                // it does not know is a vendor alarm (NC-1120).
                                let known = codes
                                    .iter()
                                    .filter(|c| !c.is_empty())
                                    .find(|c| AlarmKind::ALL.iter().any(|k| k.code() == c.as_str()));
                                let Some(code) = known.or(codes.iter().find(|c| !c.is_empty())) else {
                                    return Err(err(
                                        ErrorKind::BadRow,
                                        fields[i + 2].0,
                                        "an active alarm without a code".into(),
                                        "a native code (or code) for the alarm",
                                    ));
                                };
                                evs.push(TraceEvent {
                                    t_us: t,
                                    event: Event::Alarm(recorded_alarm(code, &text)),
                                });
                            }
                        }
                        Key::Ignored => {}
                    }
                }
                i += 1 + n_vals;
            }
            Ok(())
        })();
        if let Err(e) = res {
            self.sample = saved_sample;
            self.sig = saved_sig;
            return Err(e);
        }
        self.last_t = Some(t);
        if moved {
            out.push_back(TraceEvent { t_us: t, event: Event::Sample(self.sample) });
        }
        out.extend(evs);
        Ok(())
    }
}

impl Source for ShdrSource {
    fn named_signals(&self) -> Vec<Signal> {
        self.named.clone()
    }

    fn fill(&mut self, ctx: &mut Ctx, out: &mut VecDeque<TraceEvent>) -> Result<bool, ImportError> {
        loop {
            self.line_no += 1;
            match read_line(ctx, self.r.as_mut(), &mut self.buf, self.line_no, MAX_LINE) {
                Ok(true) => {}
                Ok(false) => return Ok(false),
                Err(e) => {
                    ctx.fault(e)?;
                    continue;
                }
            }
            let b = self.buf.trim_ascii();
            if b.is_empty() || b.starts_with(b"*") {
                continue;
            }
            match self.line(ctx, out) {
                Ok(()) if out.is_empty() => continue,
                Ok(()) => return Ok(true),
                Err(e) => ctx.fault(e)?,
            }
        }
    }
}
