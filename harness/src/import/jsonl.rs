//! JSON Lines importer: `nc-conform-trace/1` exactly as `docs/trace-format.md` defines it, every
//! kind (`meta`, `sample`, `signal`, `block`, `function`, `alarm`, `phase`, `input`, `end`).
//!
//! Each line is checked: its keys (no unknown key, none missing), their types, the names of
//! signals, phases and end reasons, the alarm codes (`AlarmKind::code`), time order, one `meta`
//! first and one `end` last. Numbers are read exactly (the decimal text, not a float) into nm,
//! milli-rpm and milli-degrees. Key order is not enforced.

use std::collections::VecDeque;
use std::io::BufRead;

use nc_engine::alarm::{Alarm, AlarmKind};
use nc_engine::trace::{
    axis_index, AxisSpec, EndReason, EndSummary, Event, Phase, Sample, Signal, Signals, TraceEvent,
    TraceMeta, AXES,
};
use serde_json::{Map, Value};

use super::jsonl_fast::{self, SampleKeys};
use super::num::decimal_to_fixed;
use super::{char_col, read_line, Ctx, ErrorKind, Format, ImportError, RecordedMeta, Source};

/// The format name of the meta line.
pub const FORMAT: &str = "nc-conform-trace/1";
/// The longest line read, bytes.
const MAX_LINE: usize = 16 << 20;

/// One parsed line being checked.
struct Line<'a> {
    ctx: &'a Ctx,
    no: u64,
    text: &'a [u8],
    obj: Map<String, Value>,
}

impl Line<'_> {
    fn col_of(&self, key: &str) -> u64 {
        let pat = format!("\"{key}\"");
        let text = String::from_utf8_lossy(self.text);
        text.find(&pat).map_or(1, |i| char_col(self.text, i))
    }

    fn err(&self, key: &str, msg: impl Into<String>, exp: impl Into<String>) -> ImportError {
        self.ctx.err(ErrorKind::BadRow, self.no, self.col_of(key), msg).expected(exp).with_line(self.text)
    }

    /// Refuses keys other than `t_us`, `kind` and `allowed`; requires those of `required`.
    fn keys(&self, allowed: &[&str], required: &[&str]) -> Result<(), ImportError> {
        for k in self.obj.keys() {
            if k != "t_us" && k != "kind" && !allowed.contains(&k.as_str()) {
                let kind = self.obj.get("kind").and_then(Value::as_str).unwrap_or("");
                let mut e = self.err(
                    k,
                    format!("unknown key `{k}` in a `{kind}` line"),
                    format!("one of {}", allowed.join(", ")),
                );
                e.kind = ErrorKind::Unknown;
                return Err(e);
            }
        }
        for k in required {
            if !self.obj.contains_key(*k) {
                let kind = self.obj.get("kind").and_then(Value::as_str).unwrap_or("");
                return Err(self.err(
                    "kind",
                    format!("a `{kind}` line without `{k}`"),
                    format!("the keys {}", required.join(", ")),
                ));
            }
        }
        Ok(())
    }

    fn get<'v>(&'v self, key: &str) -> &'v Value {
        self.obj.get(key).unwrap_or(&Value::Null)
    }

    fn uint(&self, key: &str, v: &Value) -> Result<u64, ImportError> {
        v.as_u64().ok_or_else(|| self.err(key, format!("`{key}` is {v}"), "an unsigned integer"))
    }

    fn u32(&self, key: &str, v: &Value) -> Result<u32, ImportError> {
        u32::try_from(self.uint(key, v)?)
            .map_err(|_| self.err(key, format!("`{key}` is {v}"), "an integer up to 4294967295"))
    }

    fn string<'v>(&self, key: &str, v: &'v Value) -> Result<&'v str, ImportError> {
        v.as_str().ok_or_else(|| self.err(key, format!("`{key}` is {v}"), "a string"))
    }

    fn fixed(&self, key: &str, v: &Value, decimals: u32) -> Result<i64, ImportError> {
        let n = v.as_number().ok_or_else(|| self.err(key, format!("`{key}` is {v}"), "a number"))?;
        decimal_to_fixed(&n.to_string(), decimals)
            .ok_or_else(|| self.err(key, format!("`{key}` is out of range: {n}"), "a number that fits"))
    }

    /// An `axes`-like object: every axis of the meta, nothing else.
    fn axes(&self, key: &str, axes: &[AxisSpec]) -> Result<[i64; AXES], ImportError> {
        let v = self.get(key);
        let o = v
            .as_object()
            .ok_or_else(|| self.err(key, format!("`{key}` is {v}"), "an object of axis positions"))?;
        let mut out = [0; AXES];
        for (k, val) in o {
            let Some(a) = axes.iter().find(|a| k.len() == 1 && k.starts_with(a.letter)) else {
                let letters: String = axes.iter().map(|a| a.letter).collect();
                let mut e = self.err(
                    key,
                    format!("axis `{k}` is not in the meta line"),
                    format!("the axes {letters}"),
                );
                e.kind = ErrorKind::Unknown;
                return Err(e);
            };
            out[a.index] = self.fixed(key, val, 6)?;
        }
        if o.len() != axes.len() {
            return Err(self.err(
                key,
                format!("`{key}` has {} axes, the meta line {}", o.len(), axes.len()),
                "every axis of the meta line",
            ));
        }
        Ok(out)
    }

    fn spindle(&self, sample: &mut Sample) -> Result<(), ImportError> {
        let v = self.get("spindle");
        let o = v
            .as_object()
            .ok_or_else(|| self.err("spindle", format!("`spindle` is {v}"), "{\"rpm\":…,\"angle_deg\":…}"))?;
        for k in o.keys() {
            if k != "rpm" && k != "angle_deg" {
                return Err(self.err("spindle", format!("unknown key `{k}` in `spindle`"), "rpm, angle_deg"));
            }
        }
        let rpm = o
            .get("rpm")
            .ok_or_else(|| self.err("spindle", "`spindle` without `rpm`", "rpm and angle_deg"))?;
        let ang = o
            .get("angle_deg")
            .ok_or_else(|| self.err("spindle", "`spindle` without `angle_deg`", "rpm and angle_deg"))?;
        sample.spindle_mrpm = self.fixed("rpm", rpm, 3)?;
        sample.spindle_mdeg = self.fixed("angle_deg", ang, 3)?;
        Ok(())
    }

    fn signal(&self, key: &str, name: &str) -> Result<Signal, ImportError> {
        Signal::from_name(name).ok_or_else(|| {
            let mut e = self.err(key, format!("unknown signal `{name}`"), "a signal of docs/trace-format.md");
            e.kind = ErrorKind::Unknown;
            e
        })
    }
}

/// Parses one line into a JSON object (errors with serde_json's column).
fn parse<'a>(ctx: &'a Ctx, no: u64, text: &'a [u8]) -> Result<Line<'a>, ImportError> {
    match crate::json_keys::from_slice(text) {
        Ok(Value::Object(obj)) => Ok(Line { ctx, no, text, obj }),
        Ok(v) => Err(ctx
            .err(ErrorKind::BadRow, no, 1, format!("a line that is not an object: {v}"))
            .expected("a JSON object")
            .with_line(text)),
        Err(e) => {
            let kind = if e.is_eof() { ErrorKind::Truncated } else { ErrorKind::BadRow };
            let col = e.column().max(1) as u64;
            let col = char_col(text, (col - 1) as usize);
            let message = if crate::json_keys::is_duplicate(&e) {
                format!("a key given twice: {}", crate::json_keys::message(&e))
            } else {
                format!("not JSON: {e}")
            };
            Err(ctx.err(kind, no, col, message).expected("one JSON object per line").with_line(text))
        }
    }
}

struct JsonlSource {
    r: Box<dyn BufRead + Send>,
    buf: Vec<u8>,
    line_no: u64,
    axes: Vec<AxisSpec>,
    last_t: u64,
    ended: bool,
    /// The fast path's axis keys; `None` reads every line through serde_json (the differential
    /// test's reference).
    fast: Option<SampleKeys>,
}

/// Reads the `meta` line.
pub(crate) fn open(
    ctx: &mut Ctx,
    mut r: Box<dyn BufRead + Send>,
) -> Result<(RecordedMeta, Box<dyn Source>), ImportError> {
    let mut buf = Vec::new();
    let mut line_no = 0;
    loop {
        line_no += 1;
        if !read_line(ctx, r.as_mut(), &mut buf, line_no, MAX_LINE)? {
            return Err(ctx
                .err(ErrorKind::Truncated, line_no, 0, "the file has no meta line")
                .expected("a first line of kind `meta`"));
        }
        if !buf.iter().all(u8::is_ascii_whitespace) {
            break;
        }
    }
    let text = buf.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&buf);
    let header = |mut e: ImportError| {
        e.kind = ErrorKind::Header;
        e
    };
    let l = parse(ctx, line_no, text).map_err(header)?;
    if l.get("kind").as_str() != Some("meta") {
        return Err(header(l.err("kind", "the first line is not the meta line", "`\"kind\":\"meta\"`")));
    }
    l.keys(
        &["dialect", "axes", "diameter", "period_us", "sample_us", "format"],
        &["dialect", "axes", "diameter", "period_us", "sample_us", "format"],
    )
    .map_err(header)?;
    let fmt = l.string("format", l.get("format")).map_err(header)?;
    if fmt != FORMAT {
        return Err(header(l.err("format", format!("format `{fmt}`"), FORMAT)));
    }
    let t = l.uint("t_us", l.get("t_us")).map_err(header)?;
    if t != 0 {
        return Err(header(l.err("t_us", format!("a meta line at {t} µs"), "`\"t_us\":0`")));
    }
    let dname = l.string("dialect", l.get("dialect")).map_err(header)?;
    let dialect = nc_engine::dialect_names().into_iter().find(|d| *d == dname).ok_or_else(|| {
        header(l.err(
            "dialect",
            format!("unknown dialect `{dname}`"),
            nc_engine::dialect_names().join(" or "),
        ))
    })?;
    let letters = |key: &str| -> Result<Vec<char>, ImportError> {
        let v = l.get(key);
        let arr = v
            .as_array()
            .ok_or_else(|| header(l.err(key, format!("`{key}` is {v}"), "an array of axis letters")))?;
        arr.iter()
            .map(|x| {
                x.as_str()
                    .filter(|s| s.len() == 1)
                    .and_then(|s| s.chars().next())
                    .filter(|c| axis_index(*c).is_some())
                    .ok_or_else(|| {
                        header(l.err(key, format!("`{x}` in `{key}`"), "axis letters X, Y, Z, A, B, C"))
                    })
            })
            .collect()
    };
    let axis_letters = letters("axes")?;
    let diameter = letters("diameter")?;
    let mut axes: Vec<AxisSpec> = Vec::new();
    for c in axis_letters {
        if axes.iter().any(|a| a.letter == c) {
            return Err(header(l.err("axes", format!("axis {c} twice"), "each axis once")));
        }
        let index = axis_index(c).unwrap_or(0);
        axes.push(AxisSpec {
            letter: c,
            index,
            diameter: diameter.contains(&c),
            rotary: matches!(c, 'A' | 'B' | 'C'),
        });
    }
    let period_us = l.uint("period_us", l.get("period_us")).map_err(header)?;
    let sample_us = l.uint("sample_us", l.get("sample_us")).map_err(header)?;
    let tm = TraceMeta { dialect, axes: axes.clone(), period_us, sample_us };
    let meta = RecordedMeta {
        file: ctx.file.clone(),
        format: Format::Jsonl,
        trace: Some(tm),
        axes: axes.clone(),
        spindle: (sample_us > 0, sample_us > 0),
        signals: Signal::ALL.to_vec(),
        sample_us: Some(sample_us),
        first_t_us: None,
    };
    let fast = (!ctx.general_only).then(|| SampleKeys::new(&axes));
    Ok((meta, Box::new(JsonlSource { r, buf, line_no, axes, last_t: 0, ended: false, fast })))
}

/// An alarm from its code and message: the title and the location are taken off the message.
fn alarm(l: &Line<'_>) -> Result<Alarm, ImportError> {
    let code = l.string("code", l.get("code"))?;
    let message = l.string("message", l.get("message"))?;
    let Some(kind) = AlarmKind::ALL.iter().copied().find(|k| k.code() == code) else {
        // A vendor's code the engine does not know: kept, with its code (NC-1120).
        if code.is_empty() {
            return Err(l.err("code", "an alarm without a code".to_string(), "an alarm code"));
        }
        return Ok(super::vendor_alarm(code, message));
    };
    let line = match l.obj.get("line") {
        Some(v) => Some(l.u32("line", v)?),
        None => None,
    };
    let col = match l.obj.get("col") {
        Some(v) => Some(l.u32("col", v)?),
        None => None,
    };
    let mut a = Alarm { kind, detail: String::new(), line, col };
    // Strip the location suffix and the title prefix; keep the message whole when it does not
    // have the engine's shape.
    let loc = Alarm { kind, detail: String::new(), line, col }.message();
    let suffix = loc.strip_prefix(kind.title()).unwrap_or("");
    let body = message.strip_suffix(suffix).unwrap_or(message);
    a.detail = match body.strip_prefix(kind.title()) {
        Some("") => String::new(),
        Some(rest) => rest.strip_prefix(": ").unwrap_or(rest).to_string(),
        None => body.to_string(),
    };
    Ok(a)
}

impl JsonlSource {
    fn event(&mut self, l: &Line<'_>) -> Result<TraceEvent, ImportError> {
        let t_us = l.uint("t_us", l.get("t_us"))?;
        let kind = l.string("kind", l.get("kind"))?;
        let event = match kind {
            "sample" => {
                l.keys(&["axes", "spindle"], &["axes", "spindle"])?;
                let mut s = Sample { axes: l.axes("axes", &self.axes)?, ..Sample::default() };
                l.spindle(&mut s)?;
                Event::Sample(s)
            }
            "signal" => {
                l.keys(&["name", "value"], &["name", "value"])?;
                let signal = l.signal("name", l.string("name", l.get("name"))?)?;
                let value = match l.get("value").as_u64() {
                    Some(0) => false,
                    Some(1) => true,
                    _ => return Err(l.err("value", format!("`value` is {}", l.get("value")), "0 or 1")),
                };
                Event::Signal { signal, value }
            }
            "block" => {
                l.keys(&["line", "text"], &["line", "text"])?;
                Event::Block {
                    line: l.u32("line", l.get("line"))?,
                    text: l.string("text", l.get("text"))?.to_string(),
                }
            }
            "function" => {
                l.keys(&["letter", "code"], &["letter", "code"])?;
                let letter = match l.string("letter", l.get("letter"))? {
                    "M" => 'M',
                    "S" => 'S',
                    "T" => 'T',
                    other => return Err(l.err("letter", format!("letter `{other}`"), "M, S or T")),
                };
                Event::Function { letter, code: l.u32("code", l.get("code"))? }
            }
            "alarm" => {
                l.keys(&["code", "message", "line", "col"], &["code", "message"])?;
                Event::Alarm(alarm(l)?)
            }
            "phase" => {
                l.keys(&["name"], &["name"])?;
                let name = l.string("name", l.get("name"))?;
                Event::Phase(Phase::from_name(name).ok_or_else(|| {
                    l.err(
                        "name",
                        format!("unknown phase `{name}`"),
                        "idle, positioning, cutting, dwell, retract or overload_retract",
                    )
                })?)
            }
            "input" => {
                l.keys(&["name", "value"], &["name", "value"])?;
                Event::Input {
                    name: l.string("name", l.get("name"))?.to_string(),
                    value: l.string("value", l.get("value"))?.to_string(),
                }
            }
            "end" => {
                let keys = ["reason", "axes", "command", "spindle", "signals", "modal", "alarms", "blocks"];
                l.keys(&keys, &keys)?;
                let reason = match l.string("reason", l.get("reason"))? {
                    "program_end" => EndReason::ProgramEnd,
                    "alarm" => EndReason::Alarm,
                    "reset" => EndReason::Reset,
                    "stopped" => EndReason::Stopped,
                    "time_limit" => EndReason::TimeLimit,
                    "output_limit" => EndReason::OutputLimit,
                    r => {
                        return Err(l.err(
                            "reason",
                            format!("unknown end reason `{r}`"),
                            "program_end, alarm, reset, stopped, time_limit or output_limit",
                        ))
                    }
                };
                let mut state = Sample { axes: l.axes("axes", &self.axes)?, ..Sample::default() };
                l.spindle(&mut state)?;
                let command = l.axes("command", &self.axes)?;
                let sv = l.get("signals");
                let so = sv.as_object().ok_or_else(|| {
                    l.err("signals", format!("`signals` is {sv}"), "an object of signal levels")
                })?;
                let mut signals = Signals::default();
                for (k, v) in so {
                    let s = l.signal("signals", k)?;
                    match v.as_u64() {
                        Some(0) => signals.set(s, false),
                        Some(1) => signals.set(s, true),
                        _ => return Err(l.err("signals", format!("signal {k} is {v}"), "0 or 1")),
                    }
                }
                let mv = l.get("modal");
                let modal = mv
                    .as_array()
                    .and_then(|a| {
                        a.iter().map(|x| x.as_str().map(str::to_string)).collect::<Option<Vec<_>>>()
                    })
                    .ok_or_else(|| l.err("modal", format!("`modal` is {mv}"), "an array of strings"))?;
                Event::End(Box::new(EndSummary {
                    reason,
                    state,
                    command,
                    signals,
                    modal,
                    alarms: l.u32("alarms", l.get("alarms"))?,
                    blocks: l.u32("blocks", l.get("blocks"))?,
                }))
            }
            "meta" => return Err(l.err("kind", "a second meta line", "one meta line, the first")),
            other => {
                let mut e = l.err(
                    "kind",
                    format!("unknown kind `{other}`"),
                    "sample, signal, block, function, alarm, phase, input or end",
                );
                e.kind = ErrorKind::Unknown;
                return Err(e);
            }
        };
        if t_us < self.last_t {
            let mut e = l.err(
                "t_us",
                format!("time goes back: {t_us} µs after {} µs", self.last_t),
                format!("a time ≥ {} µs", self.last_t),
            );
            e.kind = ErrorKind::NonMonotonicTime;
            return Err(e);
        }
        Ok(TraceEvent { t_us, event })
    }
}

impl Source for JsonlSource {
    fn fill(&mut self, ctx: &mut Ctx, out: &mut VecDeque<TraceEvent>) -> Result<bool, ImportError> {
        loop {
            self.line_no += 1;
            let no = self.line_no;
            let more = read_line(ctx, self.r.as_mut(), &mut self.buf, no, MAX_LINE);
            match more {
                Ok(true) => {}
                Ok(false) => {
                    if !self.ended {
                        self.ended = true;
                        ctx.fault(
                            ctx.err(ErrorKind::Truncated, no, 0, "the trace ends without its `end` line")
                                .expected("a last line of kind `end`"),
                        )?;
                    }
                    return Ok(false);
                }
                Err(e) => {
                    ctx.fault(e)?;
                    continue;
                }
            }
            if let Some((t_us, s)) = self.fast.as_ref().and_then(|k| jsonl_fast::sample(&self.buf, k)) {
                if !self.ended && t_us >= self.last_t {
                    self.last_t = t_us;
                    out.push_back(TraceEvent { t_us, event: Event::Sample(s) });
                    return Ok(true);
                }
            }
            if self.buf.iter().all(u8::is_ascii_whitespace) {
                continue;
            }
            // The sample line as `nc-conform run` writes it, read without building a JSON value;
            // any other form (or any fault) goes through the full check below.
            if !self.ended {
                if let Some((t_us, s)) = fast_sample(&self.buf, &self.axes) {
                    if t_us >= self.last_t {
                        self.last_t = t_us;
                        out.push_back(TraceEvent { t_us, event: Event::Sample(s) });
                        return Ok(true);
                    }
                }
            }
            let buf = std::mem::take(&mut self.buf);
            let res = parse(ctx, no, &buf).and_then(|l| {
                if self.ended {
                    return Err(l.err("kind", "a line after the `end` line", "the `end` line last"));
                }
                self.event(&l)
            });
            self.buf = buf;
            match res {
                Ok(ev) => {
                    self.last_t = ev.t_us;
                    if matches!(ev.event, Event::End(_)) {
                        self.ended = true;
                    }
                    out.push_back(ev);
                    return Ok(true);
                }
                Err(e) => ctx.fault(e)?,
            }
        }
    }
}

/// Reads `lit` at `*i`.
fn lit(b: &[u8], i: &mut usize, lit: &[u8]) -> Option<()> {
    if b.get(*i..*i + lit.len())? == lit {
        *i += lit.len();
        Some(())
    } else {
        None
    }
}

/// A JSON number at `*i` in plain decimal form (`-12.345`, no exponent) as fixed point.
fn number(b: &[u8], i: &mut usize, decimals: u32) -> Option<i64> {
    let start = *i;
    if b.get(*i) == Some(&b'-') {
        *i += 1;
    }
    let digits = *i;
    while b.get(*i).is_some_and(u8::is_ascii_digit) {
        *i += 1;
    }
    if *i == digits || (b[digits] == b'0' && *i > digits + 1) {
        return None; // no digits, or a leading zero JSON does not allow
    }
    if b.get(*i) == Some(&b'.') {
        *i += 1;
        let f = *i;
        while b.get(*i).is_some_and(u8::is_ascii_digit) {
            *i += 1;
        }
        if *i == f {
            return None;
        }
    }
    if matches!(b.get(*i), Some(b'e' | b'E')) {
        return None;
    }
    decimal_to_fixed(std::str::from_utf8(&b[start..*i]).ok()?, decimals)
}

/// A sample line exactly as `nc-conform run` writes it: `{"t_us":T,"kind":"sample","axes":{…
/// every axis of the meta in its order…},"spindle":{"rpm":R,"angle_deg":A}}` (a trailing `\r`
/// allowed). None for any other form: the full parser then reads (and judges) it.
pub(crate) fn fast_sample(b: &[u8], axes: &[AxisSpec]) -> Option<(u64, Sample)> {
    let b = b.strip_suffix(b"\r").unwrap_or(b);
    let mut i = 0;
    lit(b, &mut i, b"{\"t_us\":")?;
    let t0 = i;
    while b.get(i).is_some_and(u8::is_ascii_digit) {
        i += 1;
    }
    if i == t0 || (b[t0] == b'0' && i > t0 + 1) || i - t0 > 19 {
        return None;
    }
    let t_us: u64 = std::str::from_utf8(&b[t0..i]).ok()?.parse().ok()?;
    lit(b, &mut i, b",\"kind\":\"sample\",\"axes\":{")?;
    let mut s = Sample::default();
    for (k, a) in axes.iter().enumerate() {
        if k > 0 {
            lit(b, &mut i, b",")?;
        }
        lit(b, &mut i, b"\"")?;
        let mut l = [0u8; 4];
        lit(b, &mut i, a.letter.encode_utf8(&mut l).as_bytes())?;
        lit(b, &mut i, b"\":")?;
        s.axes[a.index] = number(b, &mut i, 6)?;
    }
    lit(b, &mut i, b"},\"spindle\":{\"rpm\":")?;
    s.spindle_mrpm = number(b, &mut i, 3)?;
    lit(b, &mut i, b",\"angle_deg\":")?;
    s.spindle_mdeg = number(b, &mut i, 3)?;
    lit(b, &mut i, b"}}")?;
    (i == b.len()).then_some((t_us, s))
}
