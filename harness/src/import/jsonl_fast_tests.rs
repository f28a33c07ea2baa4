//! Differential test: the JSON Lines importer with its fast path gives exactly what the general
//! path (serde_json on every line, the importer before the fast path) gives, events and errors
//! alike, strict and lenient, on the fuzz corpus, a generated trace, an engine run, and every
//! one-byte edit of their first sample lines.

use std::io::Cursor;

use crate::import::{from_reader_with, gen, ImportError, Options, Warnings};
use nc_engine::trace::TraceEvent;

type Outcome = (Result<Vec<Result<TraceEvent, ImportError>>, ImportError>, Option<Warnings>);

fn import(text: &[u8], lenient: bool, general_only: bool) -> Outcome {
    let opts = Options { format: None, map: None, lenient };
    match from_reader_with("t.jsonl", Box::new(Cursor::new(text.to_vec())), &opts, general_only) {
        Ok(mut imp) => {
            let evs: Vec<_> = imp.by_ref().collect();
            (Ok(evs), Some(imp.warnings().clone()))
        }
        Err(e) => (Err(e), None),
    }
}

fn same(text: &[u8]) {
    for lenient in [false, true] {
        let fast = import(text, lenient, false);
        let general = import(text, lenient, true);
        assert_eq!(fast, general, "lenient {lenient}, input:\n{}", String::from_utf8_lossy(text));
    }
}

fn inputs() -> Vec<Vec<u8>> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../fuzz/corpus/import_jsonl");
    let mut v: Vec<Vec<u8>> = std::fs::read_dir(dir)
        .expect("the corpus")
        .map(|e| std::fs::read(e.expect("an entry").path()).expect("a corpus file"))
        .collect();
    let mut g = Vec::new();
    std::io::Read::read_to_end(&mut gen::GenJsonl::new(3000), &mut g).expect("in memory");
    v.push(g);
    let m = nc_engine::Machine::new("gsk-lathe").expect("dialect");
    let prog =
        m.parse("G98;\nG0 X50 Z0;\nM29 S1000;\nG88 X-50 P300 Q2000 R0.5 F2;\nG80;\nM30;\n").expect("parses");
    let mut w = crate::jsonl::JsonlWriter::new(Vec::new());
    m.run(&prog, &nc_engine::RunOptions { sample_us: 1000, ..Default::default() }, &mut w);
    v.push(w.finish().expect("in memory"));
    v
}

#[test]
fn whole_inputs_read_the_same() {
    for text in inputs() {
        same(&text);
    }
}

#[test]
fn the_writers_sample_lines_take_the_fast_path() {
    let text = inputs().pop().expect("the engine run");
    let imp = crate::import::from_reader("t.jsonl", Box::new(Cursor::new(text.clone())), &Options::default())
        .expect("opens");
    let keys = super::SampleKeys::new(&imp.meta().axes);
    let samples: Vec<_> =
        text.split(|&c| c == b'\n').filter(|l| l.windows(8).any(|w| w == b"\"sample\"")).collect();
    assert!(samples.len() > 100);
    for l in samples {
        assert!(super::sample(l, &keys).is_some(), "{}", String::from_utf8_lossy(l));
    }
}

#[test]
fn every_one_byte_edit_of_a_sample_line_reads_the_same() {
    const EDITS: [&[u8]; 9] = [b"", b" ", b"e", b"0", b"9", b"-", b".", b"\"", b"\xC3\xA9"];
    for text in inputs().into_iter().take(3) {
        let lines: Vec<&[u8]> = text.split(|&c| c == b'\n').collect();
        let Some(i) = lines
            .iter()
            .position(|l| l.starts_with(b"{\"t_us\"") && l.windows(8).any(|w| w == b"\"sample\""))
        else {
            continue;
        };
        let line = lines[i];
        for at in 0..line.len() {
            for edit in EDITS {
                for replace in [false, true] {
                    let mut l = line[..at].to_vec();
                    l.extend_from_slice(edit);
                    l.extend_from_slice(&line[at + usize::from(replace)..]);
                    let mut t = lines[..i].join(&b'\n');
                    t.push(b'\n');
                    t.extend_from_slice(&l);
                    // The next two lines and the last (a short file, the same shape).
                    let tail =
                        lines.iter().skip(i + 1).take(2).chain(lines.iter().rev().find(|l| !l.is_empty()));
                    for rest in tail {
                        t.push(b'\n');
                        t.extend_from_slice(rest);
                    }
                    same(&t);
                }
            }
        }
    }
}

#[test]
fn numbers_at_the_edges_read_the_same() {
    let head = "{\"t_us\":0,\"kind\":\"meta\",\"dialect\":\"gsk-lathe\",\"axes\":[\"X\",\"Z\"],\"diameter\":[\"X\"],\"period_us\":1000,\"sample_us\":1000,\"format\":\"nc-conform-trace/1\"}\n";
    let nums = [
        "0",
        "-0",
        "-0.0",
        "1.",
        "01",
        "1.5",
        "0.0000005",
        "0.000001",
        "123456789.123456",
        "999999999999999",
        "9999999999999.99",
        "9223372036854.775807",
        "1e3",
        "1E-3",
        "-",
        "00.1",
        "12345678901234567890",
        "0.1234567",
        "-123.4560",
    ];
    for x in nums {
        for t in ["0", "5", "18446744073709551615", "18446744073709551616", "007"] {
            let line = format!(
                "{{\"t_us\":{t},\"kind\":\"sample\",\"axes\":{{\"X\":{x},\"Z\":1}},\"spindle\":{{\"rpm\":{x},\"angle_deg\":{x}}}}}\n"
            );
            same(format!("{head}{line}{line}").as_bytes());
        }
    }
}
