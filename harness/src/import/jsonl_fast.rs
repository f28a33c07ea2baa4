//! The fast path of the JSON Lines importer: a `sample` line exactly as the writer formats it
//! (`{"t_us":N,"kind":"sample","axes":{"X":…,"Z":…},"spindle":{"rpm":…,"angle_deg":…}}`, keys in
//! the writer's order, axes in the meta line's order, no spaces), read in place from the line's
//! bytes with no allocation.
//!
//! It only accepts lines whose meaning is certain: plain decimals (`-?(0|[1-9][0-9]*)(\.[0-9]+)?`,
//! at most 15 digits, no more decimals than the unit has), so that it gives exactly what the
//! general path (serde_json, then [`super::num::decimal_to_fixed`]) would. Anything else (another
//! kind, another key order, spaces, exponents, an error) returns `None` and the line goes to the
//! general path, which reports errors with their `file:line:col`.

use nc_engine::trace::{AxisSpec, Sample, AXES};

/// The axis keys of a sample line, from the meta line: per axis its slot and the text before its
/// value (`{"X":`, then `,"Z":`).
pub(super) struct SampleKeys(Vec<(usize, Vec<u8>)>);

impl SampleKeys {
    pub(super) fn new(axes: &[AxisSpec]) -> Self {
        SampleKeys(
            axes.iter()
                .enumerate()
                .map(|(i, a)| {
                    let mut key = Vec::with_capacity(6);
                    key.push(if i == 0 { b'{' } else { b',' });
                    key.push(b'"');
                    let mut tmp = [0u8; 4];
                    key.extend_from_slice(a.letter.encode_utf8(&mut tmp).as_bytes());
                    key.extend_from_slice(b"\":");
                    (a.index.min(AXES - 1), key)
                })
                .collect(),
        )
    }
}

struct Cur<'a> {
    b: &'a [u8],
    i: usize,
}

impl<'a> Cur<'a> {
    fn lit(&mut self, s: &[u8]) -> Option<()> {
        if self.b[self.i..].starts_with(s) {
            self.i += s.len();
            Some(())
        } else {
            None
        }
    }

    /// `(0|[1-9][0-9]*)`, at most `max` digits.
    fn digits(&mut self, max: usize) -> Option<&'a [u8]> {
        let start = self.i;
        while self.i < self.b.len() && self.b[self.i].is_ascii_digit() {
            self.i += 1;
        }
        let d = &self.b[start..self.i];
        (!d.is_empty() && d.len() <= max && (d[0] != b'0' || d.len() == 1)).then_some(d)
    }

    fn uint(&mut self) -> Option<u64> {
        let d = self.digits(19)?;
        Some(d.iter().fold(0u64, |v, &c| v * 10 + u64::from(c - b'0')))
    }

    /// A plain decimal as an integer of `decimals` places.
    fn fixed(&mut self, decimals: u32) -> Option<i64> {
        let neg = self.lit(b"-").is_some();
        let int = self.digits(15)?;
        let frac: &[u8] = if self.lit(b".").is_some() {
            let start = self.i;
            while self.i < self.b.len() && self.b[self.i].is_ascii_digit() {
                self.i += 1;
            }
            &self.b[start..self.i]
        } else {
            &[]
        };
        if (self.b.get(self.i - 1) == Some(&b'.'))
            || int.len() + frac.len() > 15
            || frac.len() > decimals as usize
        {
            return None;
        }
        let mut v: i64 = 0;
        for &c in int.iter().chain(frac) {
            v = v * 10 + i64::from(c - b'0');
        }
        v = v.checked_mul(10i64.pow(decimals - frac.len() as u32))?;
        Some(if neg { -v } else { v })
    }
}

/// The time and the sample of a writer-shaped `sample` line, or `None` (then the general path
/// reads the line).
pub(super) fn sample(line: &[u8], keys: &SampleKeys) -> Option<(u64, Sample)> {
    let mut c = Cur { b: line, i: 0 };
    c.lit(b"{\"t_us\":")?;
    let t_us = c.uint()?;
    c.lit(b",\"kind\":\"sample\",\"axes\":")?;
    let mut s = Sample::default();
    if keys.0.is_empty() {
        c.lit(b"{}")?;
    }
    for (slot, key) in &keys.0 {
        c.lit(key)?;
        s.axes[*slot] = c.fixed(6)?;
    }
    if !keys.0.is_empty() {
        c.lit(b"}")?;
    }
    c.lit(b",\"spindle\":{\"rpm\":")?;
    s.spindle_mrpm = c.fixed(3)?;
    c.lit(b",\"angle_deg\":")?;
    s.spindle_mdeg = c.fixed(3)?;
    c.lit(b"}}")?;
    (c.i == line.len()).then_some((t_us, s))
}

#[cfg(test)]
#[path = "jsonl_fast_tests.rs"]
mod tests;
