//! Human- and tool-readable views of a [`Trace`](nc_engine::Trace): an event listing for
//! snapshots, an ASCII timing diagram in the style of the controller manuals' timing charts, and
//! a VCD file for waveform viewers (GTKWave, Surfer).
//!
//! - [`events`]: [`event_listing`](events::event_listing), one line per non-sample event;
//! - [`timing`]: [`timing_diagram`](timing::timing_diagram), signals, phase, axes and spindle on
//!   one time axis;
//! - [`vcd`]: [`write_vcd`](vcd::write_vcd), every signal, axis, the spindle and the phase.
//!
//! Every view is a pure function of the trace: the same trace gives the same text or bytes.
//! Numbers are written exactly (no floating point on the way): lengths in mm, speeds in rpm and
//! times in ms with the trailing zeros of the fraction trimmed, except where a fixed width is
//! documented.

pub mod events;
pub mod timing;
pub mod vcd;

use nc_engine::units::Micros;

/// `t_us` as milliseconds with exactly three decimals (`354000` → `354.000`).
pub fn ms3(t_us: Micros) -> String {
    format!("{}.{:03}", t_us / 1000, t_us % 1000)
}

/// `t_us` as milliseconds with no trailing zeros (`354000` → `354`, `1500` → `1.5`).
pub fn ms_trim(t_us: Micros) -> String {
    let mut b = Vec::new();
    crate::jsonl::push_fixed(&mut b, i64::try_from(t_us).unwrap_or(i64::MAX), 3);
    String::from_utf8(b).unwrap_or_default()
}

/// Exact decimal `v / 10^decimals` with no trailing zeros (`-50000000, 6` → `-50`).
pub fn fixed(v: i64, decimals: u32) -> String {
    nc_engine::units::fixed_string(v, decimals)
}

/// `s` on one line: control characters escaped as in JSON (`\n`, `\t`, `\u001b`), so every
/// event stays on its own line of a listing.
pub fn one_line(s: &str) -> String {
    if !s.chars().any(char::is_control) {
        return s.to_string();
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        match c {
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => out.push_str(&format!("\\u{:04x}", u32::from(c))),
            c => out.push(c),
        }
    }
    out
}

/// The time of the trace's last event (the `End` event's time in a finished trace), 0 when empty.
pub fn end_time(trace: &nc_engine::Trace) -> Micros {
    trace.events.last().map_or(0, |e| e.t_us)
}

/// `parts` joined by spaces into lines of at most `w` characters, a part cut at its spaces (or
/// anywhere) only when it does not fit on a line of its own.
pub fn wrap(parts: &[String], w: usize) -> Vec<String> {
    let w = w.max(1);
    let mut lines: Vec<String> = Vec::new();
    let mut cur = String::new();
    let mut put = |piece: &str, cur: &mut String| {
        let (n, m) = (cur.chars().count(), piece.chars().count());
        if n > 0 && n + 1 + m <= w {
            cur.push(' ');
            cur.push_str(piece);
            return true;
        }
        if m <= w {
            if n > 0 {
                lines.push(std::mem::take(cur));
            }
            cur.push_str(piece);
            return true;
        }
        false
    };
    for part in parts {
        if put(part, &mut cur) {
            continue;
        }
        for word in part.split(' ') {
            if put(word, &mut cur) {
                continue;
            }
            let mut chars: Vec<char> = word.chars().collect();
            while !chars.is_empty() {
                let rest = chars.split_off(chars.len().min(w));
                put(&chars.iter().collect::<String>(), &mut cur);
                chars = rest;
            }
        }
    }
    lines.push(cur);
    lines
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    #[rstest]
    #[case(0, "0.000", "0")]
    #[case(354_000, "354.000", "354")]
    #[case(1_500, "1.500", "1.5")]
    #[case(7, "0.007", "0.007")]
    fn milliseconds(#[case] us: u64, #[case] three: &str, #[case] trimmed: &str) {
        assert_eq!(ms3(us), three);
        assert_eq!(ms_trim(us), trimmed);
    }

    #[rstest]
    #[case(30, &["gsk-lathe 0 .. 10058 ms,", "100.58 ms/column"])]
    #[case(15, &["gsk-lathe", "0 .. 10058 ms,", "100.58", "ms/column"])]
    #[case(5, &["gsk-l", "athe", "0 ..", "10058", "ms,", "100.5", "8", "ms/co", "lumn"])]
    fn wrapping(#[case] w: usize, #[case] want: &[&str]) {
        let parts = ["gsk-lathe".to_string(), "0 .. 10058 ms,".into(), "100.58 ms/column".into()];
        assert_eq!(wrap(&parts, w), want);
    }

    #[test]
    fn one_line_escapes_controls() {
        assert_eq!(one_line("G0 X1"), "G0 X1");
        assert_eq!(one_line("a\nb\tc\u{1b}"), "a\\nb\\tc\\u001b");
    }
}
