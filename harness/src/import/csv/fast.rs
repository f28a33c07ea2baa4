//! The CSV fast path: a plain row read in one pass over its bytes, the fields split and their
//! decimals parsed together, with no allocation and no second look at a field.
//!
//! A row is plain when no field is quoted, it has the expected number of fields, every mapped
//! field is a plain decimal `-?d*(.d*)?` of 1 to 19 digits (no spaces, `+` or exponent), and
//! every value fits (positions, times, signal levels as the general path computes them, time in
//! order). Anything else is declined (`None`) and the row goes through the general parser
//! ([`Rows::row`]), so the events, errors and warnings are exactly the general path's: the fast
//! path computes a value only where the general one would compute the same (`parse_f64`'s own
//! fast path: the digits as a `u64` below 2^53, divided by an exact power of ten).

use nc_engine::trace::Sample;

use super::{Action, Rows};
use crate::import::map::Level;
use crate::import::num::{f64_to_fixed, POW10};

/// A mapped field read on the fast path: `±mant / 10^frac`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Dec {
    pub mant: u64,
    /// Digits after the point.
    pub frac: u8,
    pub neg: bool,
    /// A point was written (`7.` is not an integer for a bit).
    pub dot: bool,
}

impl Dec {
    /// The value as `parse_f64` gives it, when on its fast path (mantissa below 2^53).
    #[inline]
    pub fn f64(self) -> Option<f64> {
        if self.mant >= 1 << 53 {
            return None;
        }
        let v = self.mant as f64 / POW10[usize::from(self.frac)];
        Some(if self.neg { -v } else { v })
    }

    /// The value as `parse_u64` gives it: an unsigned integer without a point.
    #[inline]
    pub fn u64(self) -> Option<u64> {
        (!self.neg && !self.dot).then_some(self.mant)
    }
}

/// The run of ASCII digits at `line[i..]` appended to `mant` (wrapping: the caller bounds the
/// count), and where the run ends.
#[inline]
fn digits_at(line: &[u8], mut i: usize, mut mant: u64) -> (u64, usize) {
    while let Some(d) = line.get(i).map(|b| b.wrapping_sub(b'0')).filter(|d| *d <= 9) {
        mant = mant.wrapping_mul(10).wrapping_add(u64::from(d));
        i += 1;
    }
    (mant, i)
}

/// Reads the plain decimal at `line[i..]` up to `delim` or the line's end: the decimal and where
/// it ends (at the delimiter or the end); `None` when the field is not a plain decimal.
#[inline]
pub(crate) fn scan_dec(line: &[u8], mut i: usize, delim: u8) -> Option<(Dec, usize)> {
    let n = line.len();
    let neg = i < n && line[i] == b'-';
    i += usize::from(neg);
    let (mut mant, mut end) = digits_at(line, i, 0);
    let mut digits = end - i;
    let dot = end < n && line[end] == b'.';
    let mut frac = 0;
    if dot {
        let start = end + 1;
        (mant, end) = digits_at(line, start, mant);
        frac = end - start;
        digits += frac;
    }
    let i = end;
    // At most 19 digits: no wrap above (10^19 − 1 < 2^64).
    if digits == 0 || digits > 19 || (i < n && line[i] != delim) {
        return None;
    }
    Some((Dec { mant, frac: frac as u8, neg, dot }, i))
}

impl Rows {
    /// The row `line` on the fast path (see the module's comment): `Some(t)` with the sample and
    /// new levels set, as [`Rows::row`] would; `None` to leave the row to it (the sample and the
    /// new levels may then be partly written).
    pub(super) fn fast_row(&mut self, line: &[u8], sample: &mut Sample) -> Option<u64> {
        let want = self.n_cols?;
        let delim = self.delim;
        let n = line.len();
        let mut i = 0;
        let mut c = 0;
        loop {
            if c < self.decs.len() && self.used[c] {
                let (d, end) = scan_dec(line, i, delim)?;
                self.decs[c] = d;
                i = end;
            } else {
                while i < n && line[i] != delim {
                    if line[i] == b'"' {
                        return None;
                    }
                    i += 1;
                }
            }
            c += 1;
            if i >= n {
                break;
            }
            i += 1; // the delimiter
        }
        if c != want || c < self.min_cols {
            return None;
        }
        let mut t = None;
        for &(c, act) in &self.flat {
            let d = self.decs[c];
            match act {
                Action::Signal { i } => {
                    let s = &self.sigs[i];
                    let level = match s.level {
                        Level::Bit(bit) => d.u64()? >> bit & 1 == 1,
                        lv => {
                            let v = d.f64()? * s.scale + s.offset;
                            match lv {
                                Level::Above(th) => v > th,
                                Level::Below(th) => v < th,
                                _ => v != 0.0,
                            }
                        }
                    };
                    self.new_levels[i] = level != s.invert;
                }
                Action::Time => {
                    let us = (d.f64()? * self.time_scale + self.time_offset) * self.us_per_unit;
                    t = Some(u64::try_from(f64_to_fixed(us, 0)?).ok()?);
                }
                Action::Axis { slot, scale, offset } => {
                    sample.axes[slot] = f64_to_fixed(d.f64()? * scale + offset, 6)?;
                }
                Action::Rpm { scale, offset } => {
                    sample.spindle_mrpm = f64_to_fixed(d.f64()? * scale + offset, 3)?;
                }
                Action::Angle { scale, offset } => {
                    sample.spindle_mdeg = f64_to_fixed(d.f64()? * scale + offset, 3)?.rem_euclid(360_000);
                }
            }
        }
        let t = t.unwrap_or(0);
        if self.last_t.is_some_and(|last| t < last) {
            return None;
        }
        Some(t)
    }
}

#[cfg(test)]
#[path = "fast_tests.rs"]
mod tests;
