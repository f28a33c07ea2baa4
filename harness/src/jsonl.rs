//! The JSON Lines trace writer: one JSON object per line, streamed as the engine runs.
//!
//! The format (`nc-conform-trace/1`) is documented in `docs/trace-format.md`. Every object has an
//! integer `t_us` and a `kind`, keys in a fixed order, and numbers written exactly: lengths are
//! integer nanometres written as millimetres with no trailing zeros (the same text as
//! [`nc_engine::units::nm_to_mm_string`]), speeds and angles are milli-units written as exact
//! decimals. The output is a pure function of the events: the same run gives the same bytes.
//!
//! Speed matters (long runs sample every millisecond), so lines are formatted by hand into a
//! reused buffer with no allocation per sample, and written out in large chunks.

use std::io::{self, Write};

use nc_engine::alarm::Alarm;
use nc_engine::trace::{
    AxisSpec, EndReason, EndSummary, Event, Sample, Signal, Signals, TraceEvent, TraceMeta, TraceSink, AXES,
};

/// The value of the meta line's `format` key.
pub const FORMAT: &str = "nc-conform-trace/1";

/// Bytes gathered before they are written to the underlying writer.
const CHUNK: usize = 64 * 1024;

/// A [`TraceSink`] that writes the trace as JSON Lines.
///
/// It buffers internally (pass an unbuffered writer such as a `File` or a locked stdout). Write
/// errors cannot be returned through [`TraceSink`]: the first one is kept, later output is
/// dropped, and [`JsonlWriter::finish`] returns it.
pub struct JsonlWriter<W: Write> {
    out: W,
    /// The output gathered before it is written: a fixed area (zeroed once) of which the first
    /// `len` bytes are used; sample lines are built in it in place.
    area: Vec<u8>,
    len: usize,
    /// A line of the general path, appended to the area when complete.
    buf: Vec<u8>,
    /// Per reported axis: its slot and the text before its value (`{"X":`, `,"Z":`).
    axes: Vec<(usize, Box<[u8]>)>,
    error: Option<io::Error>,
    end: Option<EndReason>,
    /// Bytes handed to `out` so far.
    written: u64,
    /// The output budget: past it the writer asks the run to stop (`output_limit`).
    budget: Option<u64>,
    /// Each numeric field of a sample (the axes by slot, then rpm and angle): its last value
    /// and where its text is in the previous sample line. A value that did not change since the
    /// previous sample is copied from there, not formatted again (most axes stand still most of
    /// the time).
    last: [Cached; AXES + 2],
    /// Per reported axis: its slot and its key text in a fixed-size field (None: a key too long
    /// for one; samples are then written by the general path).
    keys: Option<Vec<(usize, Key)>>,
}

/// A numeric field of the previous sample line: its value (None: none yet, or the line was
/// written out) and its text's place in the output area.
#[derive(Clone, Copy, Default)]
struct Cached {
    v: Option<i64>,
    at: usize,
    len: usize,
}

/// An axis key (`,"X":`) in a fixed-size field, copied as a whole 24-byte block.
#[derive(Clone, Copy)]
struct Key {
    b: [u8; 24],
    n: usize,
}

impl Key {
    /// A key text (None: longer than the field).
    fn text(t: &[u8]) -> Option<Key> {
        let mut b = [0; 24];
        b.get_mut(..t.len())?.copy_from_slice(t);
        Some(Key { b, n: t.len() })
    }
}

/// The decimal digits of `x` at `b[at..]`, two at a time; returns the index after them.
#[inline]
fn digits_at(b: &mut [u8], at: usize, mut x: u64) -> usize {
    let end = at + x.checked_ilog10().map_or(1, |l| l as usize + 1);
    let mut i = end;
    while x >= 100 {
        let r = (x % 100) as usize * 2;
        x /= 100;
        i -= 2;
        b[i..i + 2].copy_from_slice(&PAIRS[r..r + 2]);
    }
    if x >= 10 {
        let r = x as usize * 2;
        b[i - 2..i].copy_from_slice(&PAIRS[r..r + 2]);
    } else {
        b[i - 1] = b'0' + x as u8;
    }
    end
}

/// `v / 10^D` (D at most 6) at `b[at..]`, the same text as [`push_fixed`] (at most 21 bytes);
/// returns the index after it.
#[inline]
fn fixed_at<const D: u32>(b: &mut [u8], at: usize, v: i64) -> usize {
    const { assert!(D <= 6) };
    let mut n = at;
    if v < 0 {
        b[n] = b'-';
        n += 1;
    }
    let a = v.unsigned_abs();
    let p = 10u64.pow(D);
    n = digits_at(b, n, a / p);
    let mut frac = a % p;
    if frac != 0 {
        let mut d = D as usize;
        while frac.is_multiple_of(10) {
            frac /= 10;
            d -= 1;
        }
        b[n] = b'.';
        // `d` digits, leading zeros included, two at a time from the right.
        let mut k = n + 1 + d;
        n = k;
        while d >= 2 {
            let r = (frac % 100) as usize * 2;
            frac /= 100;
            k -= 2;
            d -= 2;
            b[k..k + 2].copy_from_slice(&PAIRS[r..r + 2]);
        }
        if d == 1 {
            b[k - 1] = b'0' + frac as u8;
        }
    }
    n
}

/// "00" to "99".
const PAIRS: [u8; 200] = {
    let mut t = [0u8; 200];
    let mut k = 0;
    while k < 100 {
        t[2 * k] = b'0' + (k / 10) as u8;
        t[2 * k + 1] = b'0' + (k % 10) as u8;
        k += 1;
    }
    t
};

/// Room for one sample line: the longest (six axes) is under 400 bytes.
const LINE: usize = 512;

/// The output area: a chunk, a long general line's worth, a sample line.
const AREA: usize = CHUNK + 4096 + LINE;

/// A numeric field of a sample line at `area[*n..]`: copied from the previous line when `v` did
/// not change (a 24-byte block, the bytes after the number ignored), else formatted; `c` then
/// says where it is in this line.
#[inline]
fn field<const D: u32>(area: &mut [u8], n: &mut usize, c: &mut Cached, v: i64) {
    let start = *n;
    if c.v == Some(v) {
        area.copy_within(c.at..c.at + 24, start);
        *n = start + c.len;
    } else {
        *n = fixed_at::<D>(area, start, v);
        c.v = Some(v);
    }
    c.at = start;
    c.len = *n - start;
}

/// A constant piece of a sample line.
#[inline]
fn put(area: &mut [u8], n: &mut usize, t: &[u8]) {
    area[*n..*n + t.len()].copy_from_slice(t);
    *n += t.len();
}

impl<W: Write> JsonlWriter<W> {
    /// A writer into `out`.
    pub fn new(out: W) -> Self {
        JsonlWriter {
            out,
            area: vec![0; AREA],
            len: 0,
            buf: Vec::with_capacity(4096),
            axes: Vec::new(),
            error: None,
            end: None,
            written: 0,
            budget: None,
            last: [Cached::default(); AXES + 2],
            keys: None,
        }
    }

    /// The same writer with an output budget in bytes: once the trace is that long it asks the
    /// run to stop ([`TraceSink::wants_stop`]), which then ends with reason `output_limit` (its
    /// `end` line is still written).
    #[must_use]
    pub fn with_budget(mut self, bytes: u64) -> Self {
        self.budget = Some(bytes);
        self
    }

    /// Bytes of trace written so far (buffered ones included).
    pub fn bytes(&self) -> u64 {
        self.written + self.len as u64
    }

    /// The reason of the `end` event, once it has been written.
    pub fn end_reason(&self) -> Option<&EndReason> {
        self.end.as_ref()
    }

    /// Writes out what is buffered and returns the writer, or the first write error.
    ///
    /// # Errors
    ///
    /// The first error the underlying writer returned.
    pub fn finish(mut self) -> io::Result<W> {
        self.flush_buf();
        if self.error.is_none() {
            if let Err(e) = self.out.flush() {
                self.error = Some(e);
            }
        }
        match self.error.take() {
            Some(e) => Err(e),
            None => Ok(self.out),
        }
    }

    /// Writes the meta line and takes the axis order from it.
    pub fn write_meta(&mut self, meta: &TraceMeta) {
        self.axes = meta
            .axes
            .iter()
            .enumerate()
            .map(|(i, a)| {
                let mut key = Vec::with_capacity(8);
                key.push(if i == 0 { b'{' } else { b',' });
                push_json_char(&mut key, a.letter);
                key.push(b':');
                (a.index.min(AXES - 1), key.into_boxed_slice())
            })
            .collect();
        self.keys = if self.axes.len() <= AXES {
            self.axes.iter().map(|(slot, key)| Key::text(key).map(|k| (*slot, k))).collect()
        } else {
            None
        };
        let b = &mut self.buf;
        b.clear();
        b.extend_from_slice(b"{\"t_us\":0,\"kind\":\"meta\",\"dialect\":");
        push_json_str(b, meta.dialect);
        b.extend_from_slice(b",\"axes\":");
        push_letter_list(b, meta.axes.iter());
        b.extend_from_slice(b",\"diameter\":");
        push_letter_list(b, meta.axes.iter().filter(|a| a.diameter));
        b.extend_from_slice(b",\"period_us\":");
        push_u64(b, meta.period_us);
        b.extend_from_slice(b",\"sample_us\":");
        push_u64(b, meta.sample_us);
        b.extend_from_slice(b",\"format\":");
        push_json_str(b, FORMAT);
        b.extend_from_slice(b"}\n");
        self.append_line();
    }

    /// A sample line, built in place in the output area (the same bytes as the general path of
    /// [`JsonlWriter::write_event`]); false when an axis key does not fit ([`Key`]).
    fn write_sample(&mut self, t: u64, s: &Sample) -> bool {
        match &self.keys {
            Some(keys) if !keys.is_empty() => {}
            _ => return false,
        }
        if self.len + LINE > self.area.len() {
            self.flush_buf();
        }
        let Some(keys) = &self.keys else { return false };
        let area = &mut self.area[..];
        let mut n = self.len;
        put(area, &mut n, b"{\"t_us\":");
        n = digits_at(area, n, t);
        put(area, &mut n, b",\"kind\":\"sample\",\"axes\":");
        for (slot, key) in keys {
            area[n..n + 24].copy_from_slice(&key.b);
            n += key.n;
            field::<6>(area, &mut n, &mut self.last[*slot], s.axes[*slot]);
        }
        put(area, &mut n, b"},\"spindle\":{\"rpm\":");
        field::<3>(area, &mut n, &mut self.last[AXES], s.spindle_mrpm);
        put(area, &mut n, b",\"angle_deg\":");
        field::<3>(area, &mut n, &mut self.last[AXES + 1], s.spindle_mdeg);
        put(area, &mut n, b"}}\n");
        self.len = n;
        true
    }

    /// Writes one event line.
    pub fn write_event(&mut self, ev: &TraceEvent) {
        if let Event::Sample(s) = &ev.event {
            if self.write_sample(ev.t_us, s) {
                self.maybe_flush();
                return;
            }
        }
        let b = &mut self.buf;
        b.clear();
        b.extend_from_slice(b"{\"t_us\":");
        push_u64(b, ev.t_us);
        b.extend_from_slice(b",\"kind\":\"");
        match &ev.event {
            Event::Sample(s) => {
                b.extend_from_slice(b"sample\",\"axes\":");
                if self.axes.is_empty() {
                    b.extend_from_slice(b"{}");
                }
                for (slot, key) in &self.axes {
                    b.extend_from_slice(key);
                    push_fixed(b, s.axes[*slot], 6);
                }
                if !self.axes.is_empty() {
                    b.push(b'}');
                }
                b.extend_from_slice(b",\"spindle\":{\"rpm\":");
                push_fixed(b, s.spindle_mrpm, 3);
                b.extend_from_slice(b",\"angle_deg\":");
                push_fixed(b, s.spindle_mdeg, 3);
                b.push(b'}');
            }
            Event::Signal { signal, value } => {
                b.extend_from_slice(b"signal\",\"name\":");
                push_json_str(b, signal.name());
                b.extend_from_slice(b",\"value\":");
                b.push(if *value { b'1' } else { b'0' });
            }
            Event::Block { line, text } => {
                b.extend_from_slice(b"block\",\"line\":");
                push_u64(b, u64::from(*line));
                b.extend_from_slice(b",\"text\":");
                push_json_str(b, text);
            }
            Event::Function { letter, code } => {
                b.extend_from_slice(b"function\",\"letter\":");
                push_json_char(b, *letter);
                b.extend_from_slice(b",\"code\":");
                push_u64(b, u64::from(*code));
            }
            Event::Alarm(a) => {
                b.extend_from_slice(b"alarm\",");
                push_alarm(b, a);
            }
            Event::Phase(p) => {
                b.extend_from_slice(b"phase\",\"name\":");
                push_json_str(b, p.name());
            }
            Event::Input { name, value } => {
                b.extend_from_slice(b"input\",\"name\":");
                push_json_str(b, name);
                b.extend_from_slice(b",\"value\":");
                push_json_str(b, value);
            }
            Event::End(s) => {
                b.extend_from_slice(b"end\",");
                push_end(b, &self.axes, s);
                self.end = Some(s.reason.clone());
            }
        }
        b.extend_from_slice(b"}\n");
        self.append_line();
    }

    /// Moves the general path's line into the output area (written out directly when longer
    /// than the area).
    fn append_line(&mut self) {
        let n = self.buf.len();
        if self.len + n > self.area.len() {
            self.flush_buf();
        }
        if n > self.area.len() {
            if self.error.is_none() {
                if let Err(e) = self.out.write_all(&self.buf) {
                    self.error = Some(e);
                }
            }
            self.written += n as u64;
        } else {
            self.area[self.len..self.len + n].copy_from_slice(&self.buf);
            self.len += n;
        }
        self.buf.clear();
        self.maybe_flush();
    }

    fn maybe_flush(&mut self) {
        if self.len >= CHUNK {
            self.flush_buf();
        }
    }

    fn flush_buf(&mut self) {
        if self.error.is_none() && self.len > 0 {
            if let Err(e) = self.out.write_all(&self.area[..self.len]) {
                self.error = Some(e);
            }
        }
        self.written += self.len as u64;
        self.len = 0;
        // The previous sample line is gone: its numbers are formatted again.
        for c in &mut self.last {
            c.v = None;
        }
    }
}

impl<W: Write> TraceSink for JsonlWriter<W> {
    fn start(&mut self, meta: &TraceMeta) {
        self.write_meta(meta);
    }

    fn event(&mut self, ev: &TraceEvent) {
        self.write_event(ev);
    }

    /// Past the budget, or once the output failed (a reader that went away), the run stops.
    fn wants_stop(&self) -> bool {
        self.error.is_some() || self.budget.is_some_and(|b| self.bytes() >= b)
    }
}

fn push_letter_list<'a>(b: &mut Vec<u8>, axes: impl Iterator<Item = &'a AxisSpec>) {
    b.push(b'[');
    for (i, a) in axes.enumerate() {
        if i > 0 {
            b.push(b',');
        }
        push_json_char(b, a.letter);
    }
    b.push(b']');
}

/// `{"X":50,"Z":0}` in the meta's axis order (values in mm or degrees).
fn push_axes(b: &mut Vec<u8>, keys: &[(usize, Box<[u8]>)], values: &[i64; AXES]) {
    if keys.is_empty() {
        b.extend_from_slice(b"{}");
        return;
    }
    for (slot, key) in keys {
        b.extend_from_slice(key);
        push_fixed(b, values[*slot], 6);
    }
    b.push(b'}');
}

/// `{"rpm":1000,"angle_deg":12.5}`.
fn push_spindle(b: &mut Vec<u8>, s: &Sample) {
    b.extend_from_slice(b"{\"rpm\":");
    push_fixed(b, s.spindle_mrpm, 3);
    b.extend_from_slice(b",\"angle_deg\":");
    push_fixed(b, s.spindle_mdeg, 3);
    b.push(b'}');
}

/// `"code":"0204","message":"...","line":7,"col":3` (line and col only when known).
fn push_alarm(b: &mut Vec<u8>, a: &Alarm) {
    b.extend_from_slice(b"\"code\":");
    push_json_str(b, a.kind.code());
    b.extend_from_slice(b",\"message\":");
    push_json_str(b, &a.message());
    if let Some(line) = a.line {
        b.extend_from_slice(b",\"line\":");
        push_u64(b, u64::from(line));
    }
    if let Some(col) = a.col {
        b.extend_from_slice(b",\"col\":");
        push_u64(b, u64::from(col));
    }
}

/// The body of the `end` line after its kind.
fn push_end(b: &mut Vec<u8>, keys: &[(usize, Box<[u8]>)], s: &EndSummary) {
    b.extend_from_slice(b"\"reason\":");
    push_json_str(b, s.reason.name());
    b.extend_from_slice(b",\"axes\":");
    push_axes(b, keys, &s.state.axes);
    b.extend_from_slice(b",\"command\":");
    push_axes(b, keys, &s.command);
    b.extend_from_slice(b",\"spindle\":");
    push_spindle(b, &s.state);
    b.extend_from_slice(b",\"signals\":");
    push_signals(b, s.signals);
    b.extend_from_slice(b",\"modal\":[");
    for (i, m) in s.modal.iter().enumerate() {
        if i > 0 {
            b.push(b',');
        }
        push_json_str(b, m);
    }
    b.extend_from_slice(b"],\"alarms\":");
    push_u64(b, u64::from(s.alarms));
    b.extend_from_slice(b",\"blocks\":");
    push_u64(b, u64::from(s.blocks));
}

/// `{"MF":0,"SF":0,...}`, every signal in [`Signal::ALL`] order.
fn push_signals(b: &mut Vec<u8>, signals: Signals) {
    b.push(b'{');
    for (i, sig) in Signal::ALL.iter().enumerate() {
        if i > 0 {
            b.push(b',');
        }
        push_json_str(b, sig.name());
        b.push(b':');
        b.push(if signals.get(*sig) { b'1' } else { b'0' });
    }
    b.push(b'}');
}

/// Writes `v` in decimal.
pub fn push_u64(b: &mut Vec<u8>, v: u64) {
    b.extend_from_slice(itoa::Buffer::new().format(v).as_bytes());
}

/// Writes `v / 10^decimals` exactly, with no trailing zeros in the fraction and no fraction when
/// it is zero (`1500000, 6` → `1.5`; `-50000000, 6` → `-50`). Same text as
/// [`nc_engine::units::fixed_string`], without allocating.
pub fn push_fixed(b: &mut Vec<u8>, v: i64, decimals: u32) {
    let p = 10u64.pow(decimals);
    let a = v.unsigned_abs();
    if v < 0 {
        b.push(b'-');
    }
    push_u64(b, a / p);
    let mut frac = a % p;
    if frac == 0 {
        return;
    }
    let mut digits = decimals as usize;
    while frac.is_multiple_of(10) {
        frac /= 10;
        digits -= 1;
    }
    b.push(b'.');
    // Leading zeros of the fraction, then its significant digits.
    let mut buf = itoa::Buffer::new();
    let text = buf.format(frac).as_bytes();
    b.extend(std::iter::repeat_n(b'0', digits - text.len()));
    b.extend_from_slice(text);
}

/// Writes `s` as a JSON string (quotes, backslashes and control characters escaped; other
/// characters as UTF-8).
pub fn push_json_str(b: &mut Vec<u8>, s: &str) {
    const HEX: &[u8; 16] = b"0123456789abcdef";
    b.push(b'"');
    let bytes = s.as_bytes();
    let mut start = 0;
    for (i, &c) in bytes.iter().enumerate() {
        let esc: &[u8] = match c {
            b'"' => b"\\\"",
            b'\\' => b"\\\\",
            b'\n' => b"\\n",
            b'\r' => b"\\r",
            b'\t' => b"\\t",
            0x08 => b"\\b",
            0x0c => b"\\f",
            0..=0x1f | 0x7f => b"",
            _ => continue,
        };
        b.extend_from_slice(&bytes[start..i]);
        if esc.is_empty() {
            b.extend_from_slice(b"\\u00");
            b.push(HEX[(c >> 4) as usize]);
            b.push(HEX[(c & 0xf) as usize]);
        } else {
            b.extend_from_slice(esc);
        }
        start = i + 1;
    }
    b.extend_from_slice(&bytes[start..]);
    b.push(b'"');
}

fn push_json_char(b: &mut Vec<u8>, c: char) {
    let mut tmp = [0u8; 4];
    push_json_str(b, c.encode_utf8(&mut tmp));
}

#[cfg(test)]
#[path = "jsonl_tests.rs"]
mod tests;
