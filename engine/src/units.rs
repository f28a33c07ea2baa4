//! Units of the engine: integer time, fixed-point lengths, exact decimals from the program.
//!
//! Owns the conversions between what a program writes (decimal words, mm or inch) and what the
//! engine computes with (`Micros` for time, `Nm` for lengths, nano-degrees for rotary axes).
//! Nothing here knows about dialects.

/// Time in integer microseconds since the program started.
pub type Micros = u64;
/// A length in nanometres (or, on a rotary axis, nano-degrees). Fixed point, signed.
pub type Nm = i64;

/// Nanometres in one millimetre.
pub const NM_PER_MM: i64 = 1_000_000;
/// Nanometres in one inch.
pub const NM_PER_INCH: i64 = 25_400_000;

/// A number exactly as written in the program: `-12.5` is `{ mantissa: -125, scale: 1, point: true }`,
/// `X50` is `{ mantissa: 50, scale: 0, point: false }`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Decimal {
    /// The digits as a signed integer.
    pub mantissa: i64,
    /// How many of the digits stand after the decimal point.
    pub scale: u8,
    /// Whether the program wrote a decimal point (`X50.` or `X50.0`): decides the integer rule.
    pub point: bool,
}

impl Decimal {
    /// An integer written without a decimal point.
    pub const fn int(v: i64) -> Self {
        Decimal { mantissa: v, scale: 0, point: false }
    }

    /// The value as a float (for messages and non-length quantities).
    pub fn to_f64(self) -> f64 {
        self.mantissa as f64 / 10f64.powi(self.scale as i32)
    }

    /// True when the value has no fractional part.
    pub fn is_integral(self) -> bool {
        self.mantissa % pow10(self.scale) == 0
    }

    /// The integer part when the value is integral, else `None`.
    pub fn as_int(self) -> Option<i64> {
        if self.is_integral() {
            Some(self.mantissa / pow10(self.scale))
        } else {
            None
        }
    }

    /// Scales the value exactly by `10^-scale * unit` where `unit` is in the target unit, rounding
    /// half away from zero. Used to turn a word into nm (unit = NM_PER_MM) or into units of a
    /// least input increment.
    pub fn scaled(self, unit: i64) -> i64 {
        let num = self.mantissa as i128 * unit as i128;
        let den = pow10(self.scale) as i128;
        let q = num / den;
        let r = num % den;
        let q = if 2 * r.abs() >= den { q + r.signum() } else { q };
        q.clamp(i64::MIN as i128, i64::MAX as i128) as i64
    }

    /// Writes the value back the way a person would read it (`-12.5`, `50`).
    pub fn display(self) -> String {
        if self.scale == 0 {
            return if self.point { format!("{}.", self.mantissa) } else { self.mantissa.to_string() };
        }
        let p = pow10(self.scale);
        let sign = if self.mantissa < 0 { "-" } else { "" };
        let a = self.mantissa.unsigned_abs();
        format!("{sign}{}.{:0width$}", a / p as u64, a % p as u64, width = self.scale as usize)
    }
}

fn pow10(s: u8) -> i64 {
    10i64.pow(s as u32)
}

/// Formats a nanometre value as millimetres with no trailing zeros (`1500000` → `1.5`).
pub fn nm_to_mm_string(nm: Nm) -> String {
    fixed_string(nm, 6)
}

/// Formats `v / 10^decimals` exactly, trimming trailing zeros.
pub fn fixed_string(v: i64, decimals: u32) -> String {
    let p = 10u64.pow(decimals);
    let sign = if v < 0 { "-" } else { "" };
    let a = v.unsigned_abs();
    let int = a / p;
    let frac = a % p;
    if frac == 0 {
        return format!("{sign}{int}");
    }
    let mut f = format!("{:0width$}", frac, width = decimals as usize);
    while f.ends_with('0') {
        f.pop();
    }
    format!("{sign}{int}.{f}")
}

/// Milliseconds to microseconds, saturating.
pub const fn ms(v: u64) -> Micros {
    v.saturating_mul(1000)
}

/// Rounds `t` up to the next multiple of `period` (a period of 0 leaves `t` alone).
pub fn ceil_to(t: Micros, period: Micros) -> Micros {
    if period == 0 {
        t
    } else {
        t.div_ceil(period).saturating_mul(period)
    }
}

/// `x.round() as i64` (half away from zero, NaN 0, saturating), without the call to the C
/// library's `round` that `f64::round` makes on x86-64 without SSE 4.1: the engine rounds every
/// axis of every sample. Exact: below 2^52 the fraction `x - trunc(x)` is representable.
#[inline]
pub fn round_i64(x: f64) -> i64 {
    const BIG: f64 = 4_503_599_627_370_496.0; // 2^52: every double beyond is an integer
    if x.is_nan() || x.abs() >= BIG {
        return x as i64; // NaN: 0; an integer already, or saturated
    }
    let t = x as i64;
    let frac = x - t as f64;
    // Without branches: the fraction of a position is anywhere.
    t + i64::from(frac >= 0.5) - i64::from(frac <= -0.5)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    /// [`round_i64`] is `f64::round` then `as i64`, at the halves, around 2^52 and 2^63, at the
    /// infinities and NaN, and over random doubles of every magnitude.
    #[test]
    fn round_i64_is_round_then_cast() {
        let mut vals = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -1.5,
            2.5,
            -2.5,
            0.49999999999999994,
            -0.49999999999999994,
            4_503_599_627_370_495.5,
            -4_503_599_627_370_495.5,
            4_503_599_627_370_496.0,
            9_007_199_254_740_993.0,
            9.3e18,
            -9.3e18,
            f64::MAX,
            f64::MIN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MIN_POSITIVE,
            1e-300,
        ];
        let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
        for _ in 0..200_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            vals.push(f64::from_bits(x));
            vals.push((x as i64 >> (x % 60)) as f64 / 1024.0);
            vals.push((x % 2_000_001) as f64 / 2.0 - 500_000.0);
        }
        for v in vals {
            assert_eq!(round_i64(v), v.round() as i64, "{v:e}");
        }
    }

    #[rstest]
    #[case(Decimal { mantissa: 125, scale: 1, point: true }, NM_PER_MM, 12_500_000)]
    #[case(Decimal { mantissa: -3937, scale: 4, point: true }, NM_PER_INCH, -9_999_980)]
    #[case(Decimal::int(50), NM_PER_MM, 50_000_000)]
    #[case(Decimal { mantissa: 5, scale: 7, point: true }, NM_PER_MM, 1)]
    #[case(Decimal { mantissa: -5, scale: 7, point: true }, NM_PER_MM, -1)]
    fn scaled_is_exact_and_rounds_half_away(#[case] d: Decimal, #[case] unit: i64, #[case] want: i64) {
        assert_eq!(d.scaled(unit), want);
    }

    #[rstest]
    #[case(0, "0")]
    #[case(1_500_000, "1.5")]
    #[case(-50_000_000, "-50")]
    #[case(-1, "-0.000001")]
    fn mm_strings(#[case] nm: i64, #[case] s: &str) {
        assert_eq!(nm_to_mm_string(nm), s);
    }

    #[test]
    fn decimal_display_round_trips_the_written_form() {
        assert_eq!(Decimal { mantissa: -125, scale: 1, point: true }.display(), "-12.5");
        assert_eq!(Decimal { mantissa: 50, scale: 0, point: true }.display(), "50.");
        assert_eq!(Decimal { mantissa: 5, scale: 3, point: true }.display(), "0.005");
    }

    #[test]
    fn ceil_to_period() {
        assert_eq!(ceil_to(0, 1000), 0);
        assert_eq!(ceil_to(1, 1000), 1000);
        assert_eq!(ceil_to(8000, 8000), 8000);
        assert_eq!(ceil_to(7, 0), 7);
    }
}
