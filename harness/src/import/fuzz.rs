//! The logic of the importer fuzz targets (`fuzz/fuzz_targets/import_*.rs`), kept in the library
//! so that `cargo test` replays their corpora (`harness/tests/fuzz_corpus.rs`).
//!
//! Each function imports the bytes in one format, strict and lenient: the importer never panics,
//! every error has a message and (past the header) a line, renders as an `InputError` with its
//! location, and the events come in time order. The number of events read is bounded
//! ([`MAX_EVENTS`]) so that one input stays fast (a VCD can ask for a sample every µs over years).

use std::io::Cursor;

use super::{from_reader, ColumnMap, Format, Options};
use crate::diag::InputError;

/// The most events a fuzzed import reads.
pub const MAX_EVENTS: usize = 100_000;

/// The column map the CSV target uses: every kind of column.
pub const FUZZ_MAP: &str = "\
skip_rows: 0
time: {column: t, unit: ms}
axes:
  - {axis: X, column: x, diameter: true}
  - {axis: Z, column: z, scale: 0.001}
spindle:
  rpm: {column: s}
  angle_deg: {column: a}
signals:
  - {signal: F76.3, column: flags, bit: 3}
  - {signal: RGTAP, column: flags, bit: 0}
  - {signal: ZSP, column: s, below: 5}
ignore: [note]
";

fn check(format: Format, data: &[u8], map: Option<&ColumnMap>) {
    for lenient in [false, true] {
        let opts = Options { format: Some(format), map, lenient };
        let imp = match from_reader("fuzz.in", Box::new(Cursor::new(data.to_vec())), &opts) {
            Ok(i) => i,
            Err(e) => {
                check_error(&e);
                continue;
            }
        };
        let mut last = 0;
        let mut imp = imp;
        for item in imp.by_ref().take(MAX_EVENTS) {
            match item {
                Ok(ev) => {
                    assert!(ev.t_us >= last, "{format:?}: time goes back: {} after {last}", ev.t_us);
                    last = ev.t_us;
                }
                Err(e) => {
                    assert!(
                        e.line > 0 || e.kind == super::ErrorKind::Truncated,
                        "{format:?}: an error without a line: {e:?}"
                    );
                    check_error(&e);
                    break;
                }
            }
        }
        if !lenient {
            assert_eq!(imp.warnings().total(), 0, "{format:?}: warnings in strict mode");
        }
    }
}

fn check_error(e: &super::ImportError) {
    assert!(!e.message.is_empty(), "an error without a message: {e:?}");
    let d: InputError = e.clone().into();
    let plain = d.render_plain();
    assert!(plain.contains("fuzz.in"), "a diagnostic without its file:\n{plain}");
    if e.line > 0 {
        assert!(plain.contains(&format!(":{}", e.line)), "a diagnostic without its line:\n{plain}");
    }
}

/// Fuzz target `import_csv`: the bytes as a CSV file under [`FUZZ_MAP`].
///
/// # Panics
///
/// On a bug (see the module doc).
pub fn import_csv(data: &[u8]) {
    let map = ColumnMap::from_yaml("fuzz.yaml", FUZZ_MAP).expect("the fuzz map loads");
    check(Format::Csv, data, Some(&map));
}

/// Fuzz target `import_jsonl`: the bytes as a JSON Lines trace.
///
/// # Panics
///
/// On a bug (see the module doc).
pub fn import_jsonl(data: &[u8]) {
    check(Format::Jsonl, data, None);
}

/// Fuzz target `import_vcd`: the bytes as a VCD file.
///
/// # Panics
///
/// On a bug (see the module doc).
pub fn import_vcd(data: &[u8]) {
    check(Format::Vcd, data, None);
}

/// Fuzz target `import_shdr`: the bytes as SHDR lines.
///
/// # Panics
///
/// On a bug (see the module doc).
pub fn import_shdr(data: &[u8]) {
    check(Format::Shdr, data, None);
}
