//! Number parsing shared by the importers: exact decimals to fixed point (JSON Lines, SHDR) and a
//! fast decimal-to-`f64` parser for CSV fields (exact on the fast path, `str::parse` otherwise).

/// Powers of ten exactly representable as `f64`.
pub(crate) const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18,
    1e19, 1e20, 1e21, 1e22,
];

/// Parses a decimal number (`-12.5`, `3`, `1e-3`, `+.5`) as `f64`; `None` when it is not one (or
/// not finite). Surrounding spaces are allowed.
pub fn parse_f64(s: &[u8]) -> Option<f64> {
    let s = s.trim_ascii();
    let (neg, digits) = match s.first() {
        Some(b'-') => (true, &s[1..]),
        Some(b'+') => (false, &s[1..]),
        _ => (false, s),
    };
    // Integer digits, then fractional digits; anything else goes to the standard library.
    let n = digits.len();
    let mut mant: u64 = 0;
    let mut i = 0;
    while i < n {
        let d = digits[i].wrapping_sub(b'0');
        if d > 9 {
            break;
        }
        mant = mant.wrapping_mul(10).wrapping_add(u64::from(d));
        i += 1;
    }
    let int_digits = i;
    let mut frac = 0usize;
    if i < n && digits[i] == b'.' {
        i += 1;
        let start = i;
        while i < n {
            let d = digits[i].wrapping_sub(b'0');
            if d > 9 {
                break;
            }
            mant = mant.wrapping_mul(10).wrapping_add(u64::from(d));
            i += 1;
        }
        frac = i - start;
    }
    if i != n {
        return slow(s);
    }
    if digits.is_empty() || digits == b"." {
        return None;
    }
    // At most 19 digits cannot overflow; below 2^53 and 10^22 the division is exactly rounded.
    if int_digits + frac > 19 || mant >= 1 << 53 || frac >= POW10.len() {
        return slow(s);
    }
    let v = mant as f64 / POW10[frac];
    Some(if neg { -v } else { v })
}

/// The general case, through the standard library.
fn slow(s: &[u8]) -> Option<f64> {
    let v: f64 = std::str::from_utf8(s).ok()?.parse().ok()?;
    v.is_finite().then_some(v)
}

/// `v × 10^decimals` rounded to the nearest integer; `None` when out of `i64` or not finite.
pub fn f64_to_fixed(v: f64, decimals: u32) -> Option<i64> {
    let y = v * POW10[decimals as usize];
    if y.abs() < 4.5e15 {
        // Below 2^52 the truncation and the fraction are exact: rounding half away from zero
        // without a call to `round` (not inlined on baseline x86-64).
        let i = y as i64;
        let frac = y - i as f64;
        return Some(i + i64::from(frac >= 0.5) - i64::from(frac <= -0.5));
    }
    let x = y.round();
    // 2^63 is exactly representable; anything at or past it does not fit.
    (x.is_finite() && x.abs() < 9.223_372_036_854_775e18).then_some(x as i64)
}

/// Parses an exact decimal (`-12.5`, `0.000001`, `1e-6`, `50`) as an integer of `decimals`
/// decimal places, rounding any further digits half away from zero; `None` when the text is not a
/// decimal or the value does not fit an `i64`.
pub fn decimal_to_fixed(s: &str, decimals: u32) -> Option<i64> {
    let b = s.trim().as_bytes();
    let (neg, rest) = match b.first() {
        Some(b'-') => (true, &b[1..]),
        Some(b'+') => (false, &b[1..]),
        _ => (false, b),
    };
    let (num, exp) = match rest.iter().position(|&c| c == b'e' || c == b'E') {
        Some(i) => {
            let e: i64 = std::str::from_utf8(&rest[i + 1..]).ok()?.parse().ok()?;
            (&rest[..i], e)
        }
        None => (rest, 0),
    };
    let (int, frac) = match num.iter().position(|&c| c == b'.') {
        Some(i) => (&num[..i], &num[i + 1..]),
        None => (num, &num[num.len()..]),
    };
    if int.is_empty() && frac.is_empty() || !int.iter().chain(frac).all(u8::is_ascii_digit) {
        return None;
    }
    // value = digits × 10^(shift), digits = int ++ frac.
    let shift = exp.checked_add(i64::from(decimals))?.checked_sub(frac.len() as i64)?;
    let mut acc: i128 = 0;
    let limit: i128 = 1 << 100;
    for &c in int.iter().chain(frac) {
        acc = acc * 10 + i128::from(c - b'0');
        if acc > limit {
            return None;
        }
    }
    let value = if shift >= 0 {
        if shift > 38 && acc != 0 {
            return None;
        }
        let mut v = acc;
        for _ in 0..shift.min(38) {
            v = v.checked_mul(10)?;
        }
        v
    } else {
        let drop = (-shift).min(38);
        let p = 10i128.checked_pow(u32::try_from(drop).ok()?)?;
        let (q, r) = (acc / p, acc % p);
        if r * 2 >= p {
            q + 1
        } else {
            q
        }
    };
    let value = if neg { -value } else { value };
    i64::try_from(value).ok()
}

/// Parses an unsigned integer (decimal, or hexadecimal with `0x`); `None` when it is not one.
pub fn parse_u64(s: &[u8]) -> Option<u64> {
    let s = s.trim_ascii();
    if let Some(h) = s.strip_prefix(b"0x").or_else(|| s.strip_prefix(b"0X")) {
        return u64::from_str_radix(std::str::from_utf8(h).ok()?, 16).ok();
    }
    if s.is_empty() {
        return None;
    }
    let mut v: u64 = 0;
    for &c in s {
        if !c.is_ascii_digit() {
            return None;
        }
        v = v.checked_mul(10)?.checked_add(u64::from(c - b'0'))?;
    }
    Some(v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    #[rstest]
    #[case("50", 6, Some(50_000_000))]
    #[case("-12.5", 6, Some(-12_500_000))]
    #[case("0.000001", 6, Some(1))]
    #[case("1e-6", 6, Some(1))]
    #[case("359.999", 3, Some(359_999))]
    #[case("0.0000005", 6, Some(1))]
    #[case("-0.0000005", 6, Some(-1))]
    #[case("1e400", 6, None)]
    #[case("1e-400", 6, Some(0))]
    #[case("abc", 6, None)]
    #[case(".", 6, None)]
    #[case("99999999999999999999", 0, None)]
    fn decimals(#[case] s: &str, #[case] d: u32, #[case] want: Option<i64>) {
        assert_eq!(decimal_to_fixed(s, d), want);
    }

    #[rstest]
    #[case("1.5", Some(1.5))]
    #[case(" -0.25 ", Some(-0.25))]
    #[case("1e3", Some(1000.0))]
    #[case("12345678901234567890.5", Some(12_345_678_901_234_567_890.5))]
    #[case("", None)]
    #[case("-", None)]
    #[case("1.2.3", None)]
    #[case("nan", None)]
    #[case("inf", None)]
    fn floats(#[case] s: &str, #[case] want: Option<f64>) {
        assert_eq!(parse_f64(s.as_bytes()), want);
    }

    #[test]
    fn fixed_rounds_half_away_from_zero() {
        for v in [0.5, -0.5, 1.4999, -2.5, 2.5000001, 123.456_789_5, -0.000_000_4, 4.4e15, 5e15, -7e17] {
            for d in [0, 3, 6] {
                let x = (v * POW10[d as usize]).round();
                let want = (x.abs() < 9.223_372_036_854_775e18).then_some(x as i64);
                assert_eq!(f64_to_fixed(v, d), want, "{v} {d}");
            }
        }
        assert_eq!(f64_to_fixed(f64::NAN, 0), None);
        assert_eq!(f64_to_fixed(1e19, 0), None);
        assert_eq!(parse_u64(b"18446744073709551615"), Some(u64::MAX));
        assert_eq!(parse_u64(b"18446744073709551616"), None);
        assert_eq!(parse_u64(b" 0x1F "), Some(31));
        assert_eq!(parse_u64(b"+1"), None);
    }

    #[test]
    fn fast_path_is_exact() {
        for s in [
            "0.001328",
            "123.456789",
            "-0.000001",
            "3600.999",
            "0000000000000000000001.5",
            "9007199254740993",
            ".5",
            "7.",
        ] {
            assert_eq!(parse_f64(s.as_bytes()), s.parse().ok());
        }
    }
}
