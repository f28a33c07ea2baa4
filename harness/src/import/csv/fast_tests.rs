//! The CSV fast path against the general parser: on random decimal strings the fast path's
//! value is exactly `parse_f64`'s / `parse_u64`'s (or it declines), and on random files (plain,
//! quoted, spaced, signed, exponents, empty fields, short and long rows, time going back) the
//! importer with its fast path gives exactly the events, errors and warnings of the general path
//! (and on the CSV fuzz corpus, the generated recording).

use std::io::Cursor;

use proptest::prelude::*;

use super::scan_dec;
use crate::import::map::ColumnMap;
use crate::import::num::{parse_f64, parse_u64};
use crate::import::{from_reader_with, gen, ImportError, Options, Warnings};
use nc_engine::trace::TraceEvent;

/// The fast path's reading of `s` as a whole field: its `f64` and its `u64`, or `None` each.
fn fast(s: &[u8]) -> (Option<f64>, Option<u64>) {
    match scan_dec(s, 0, b',') {
        Some((d, end)) if end == s.len() => (d.f64(), d.u64()),
        Some(_) => (None, None),
        None => (None, None),
    }
}

/// The fast path agrees with the general parsers wherever it gives a value.
fn agrees(s: &[u8]) -> Result<(), TestCaseError> {
    let (f, u) = fast(s);
    if let Some(v) = f {
        let want = parse_f64(s);
        prop_assert_eq!(want.map(f64::to_bits), Some(v.to_bits()), "{:?}", String::from_utf8_lossy(s));
    }
    if let Some(v) = u {
        prop_assert_eq!(parse_u64(s), Some(v), "{:?}", String::from_utf8_lossy(s));
    }
    Ok(())
}

/// Decimal-looking text: spaces, signs, leading zeros, many digits, points, exponents.
const DECIMAL: &str = " ?[+-]?0{0,3}[0-9]{0,22}(\\.[0-9]{0,22})?([eE][+-]?[0-9]{1,3})? ?";

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4000))]

    #[test]
    fn decimals_read_as_the_general_parser_reads_them(s in DECIMAL) {
        agrees(s.as_bytes())?;
    }

    #[test]
    fn any_short_text_reads_as_the_general_parser_reads_it(s in "[0-9.eE+\\- \"x,]{0,24}") {
        agrees(s.as_bytes())?;
    }

    #[test]
    /// Up to 15 digits: always below 2^53.
    fn plain_decimals_take_the_fast_path(neg in any::<bool>(), int in "[0-9]{0,8}", frac in proptest::option::of("[0-9]{0,7}")) {
        let s = format!("{}{int}{}", if neg { "-" } else { "" }, frac.as_ref().map_or(String::new(), |f| format!(".{f}")));
        let digits = int.len() + frac.as_ref().map_or(0, String::len);
        let (f, u) = fast(s.as_bytes());
        prop_assert_eq!(f.is_some(), digits > 0, "{}", s);
        prop_assert_eq!(u.is_some(), digits > 0 && !neg && frac.is_none(), "{}", s);
        agrees(s.as_bytes())?;
    }
}

#[test]
fn edges_of_the_fast_path() {
    for s in [
        "0",
        "-0",
        "00",
        "-.5",
        ".5",
        "7.",
        ".",
        "-",
        "",
        "+1",
        " 1",
        "1 ",
        "1e3",
        "9007199254740991",
        "9007199254740992",
        "9007199254740993",
        "9999999999999999999",
        "18446744073709551615",
        "0000000000000000001",
        "00000000000000000001",
        "0.000000000000000001",
        "1.5.",
    ] {
        agrees(s.as_bytes()).expect(s);
    }
    assert_eq!(fast(b"-0").0.map(f64::to_bits), Some((-0.0f64).to_bits()));
    assert_eq!(fast(b"9007199254740991"), (Some(9_007_199_254_740_991.0), Some(9_007_199_254_740_991)));
    // Above 2^53 the general parser rounds: left to it.
    assert_eq!(fast(b"9007199254740993").0, None);
    assert_eq!(fast(b"9999999999999999999").1, Some(9_999_999_999_999_999_999));
    assert_eq!(fast(b"00000000000000000001"), (None, None));
    // A field ends at the delimiter only.
    assert_eq!(scan_dec(b"1.5;2", 0, b';').map(|(d, e)| (d.f64(), e)), Some((Some(1.5), 3)));
    assert_eq!(scan_dec(b"1.5x;2", 0, b';'), None);
}

const MAP: &str = "\
time: {column: time, unit: ms}
axes:
  - {axis: X, column: X_act, diameter: true}
  - {axis: Z, column: Z_act, scale: 0.001, offset: -2.5}
spindle:
  rpm: {column: S_act}
  angle_deg: {column: A}
signals:
  - {signal: F76.3, column: flags, bit: 3}
  - {signal: RGTAP, column: flags, bit: 0}
  - {signal: ZSP, column: S_act, below: 5}
  - {signal: SPPOSA, column: A, above: 0.5, invert: true}
ignore: [note]
";

type Outcome = (Result<Vec<Result<TraceEvent, ImportError>>, ImportError>, Option<Warnings>);

fn import(text: &[u8], map: &ColumnMap, lenient: bool, general_only: bool) -> Outcome {
    let opts = Options { format: Some(crate::import::Format::Csv), map: Some(map), lenient };
    match from_reader_with("t.csv", Box::new(Cursor::new(text.to_vec())), &opts, general_only) {
        Ok(mut imp) => {
            let evs: Vec<_> = imp.by_ref().collect();
            (Ok(evs), Some(imp.warnings().clone()))
        }
        Err(e) => (Err(e), None),
    }
}

fn same(text: &[u8], map: &ColumnMap) -> Result<(), TestCaseError> {
    for lenient in [false, true] {
        let fast = import(text, map, lenient, false);
        let general = import(text, map, lenient, true);
        prop_assert_eq!(fast, general, "lenient {}, input:\n{}", lenient, String::from_utf8_lossy(text));
    }
    Ok(())
}

/// A field: mostly plain decimals, sometimes anything a recording could hold.
fn field() -> impl Strategy<Value = String> {
    prop_oneof![
        6 => "-?[0-9]{1,6}(\\.[0-9]{0,6})?",
        1 => DECIMAL,
        1 => "[0-9]{15,21}",
        1 => Just(String::new()),
        1 => "\"[0-9.,\" -]{0,6}\"",
        1 => " *-?[0-9]{1,3} *",
        1 => "[a-z0-9.;\t]{0,4}",
        1 => "0x[0-9A-F]{1,3}",
    ]
}

/// A row of 6 fields (sometimes 5 or 7) with a time that mostly goes forward.
fn row() -> impl Strategy<Value = (u32, Vec<String>, bool)> {
    (0u32..5, proptest::collection::vec(field(), 5..=7), proptest::bool::weighted(0.05))
}

fn text(rows: &[(u32, Vec<String>, bool)], header: &str, delim: char) -> String {
    let mut t = format!("{header}\n");
    let mut ms = 0u32;
    for (step, fields, blank) in rows {
        if *blank {
            t.push_str("  \r\n");
            continue;
        }
        ms = ms.saturating_add(*step).saturating_sub(u32::from(*step == 4) * 6);
        let mut f = fields.clone();
        // The time: a counter, mostly.
        if f[0].len() % 3 != 2 {
            f[0] = format!("{ms}.{}", step * 25);
        }
        t.push_str(&f.join(&delim.to_string()));
        t.push_str(if ms.is_multiple_of(7) { "\r\n" } else { "\n" });
    }
    t
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(600))]

    #[test]
    fn random_files_read_the_same_both_ways(rows in proptest::collection::vec(row(), 0..40)) {
        let map = ColumnMap::from_yaml("map.yaml", MAP).expect("map loads");
        same(text(&rows, "time,X_act,Z_act,S_act,flags,A,note", ',').as_bytes(), &map)?;
        same(text(&rows, "time,X_act,Z_act,S_act,flags,A", ',').as_bytes(), &map)?;
        let semi = format!("delimiter: \";\"\n{MAP}");
        let map = ColumnMap::from_yaml("map.yaml", &semi).expect("map loads");
        same(text(&rows, "time;X_act;Z_act;S_act;flags;A;note", ';').as_bytes(), &map)?;
    }

    #[test]
    fn files_without_a_header_read_the_same_both_ways(rows in proptest::collection::vec(row(), 0..30)) {
        let map = ColumnMap::from_yaml(
            "map.yaml",
            "header: false\ntime: {column: 1}\naxes:\n  - {axis: X, column: 2}\nsignals:\n  - {signal: STL, column: 5, bit: 1}\n",
        )
        .expect("map loads");
        same(text(&rows, "", ',').trim_start().as_bytes(), &map)?;
    }
}

#[test]
fn the_generated_recording_reads_the_same_both_ways() {
    let map = ColumnMap::from_yaml("gen.yaml", gen::MAP).expect("the generator's map loads");
    let mut g = Vec::new();
    std::io::Read::read_to_end(&mut gen::GenCsv::new(5000), &mut g).expect("in memory");
    same(&g, &map).expect("the same");
    // Its rows are plain: every field the map reads takes the fast path.
    let text = String::from_utf8(g).expect("text");
    for line in text.lines().skip(1) {
        for f in line.split(',') {
            if !f.is_empty() && f.bytes().all(|c| c.is_ascii_digit() || c == b'.' || c == b'-') {
                assert!(fast(f.as_bytes()).0.is_some(), "{f}");
            }
        }
    }
}

#[test]
fn the_fuzz_corpus_reads_the_same_both_ways() {
    let map = ColumnMap::from_yaml("fuzz.yaml", crate::import::fuzz::FUZZ_MAP).expect("the fuzz map loads");
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../fuzz/corpus/import_csv");
    let mut n = 0;
    for e in std::fs::read_dir(dir).expect("the corpus") {
        let text = std::fs::read(e.expect("an entry").path()).expect("a corpus file");
        same(&text, &map).expect("the same");
        n += 1;
    }
    assert!(n >= 3);
}
