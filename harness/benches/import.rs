//! Import benchmark: a 1-hour, 1 kHz, 8-column CSV trace (3.6 million rows, generated as a
//! stream by `nc_conform::import::gen`, never written to disk), imported event by event. The
//! throughput is reported in rows per second. Peak memory: `examples/import_rss.rs` under
//! `/usr/bin/time -v` (see `docs/checking.md`).
//!
//! Also measures the generator alone, so the reader's own cost is the difference.

use std::hint::black_box;
use std::io::BufRead;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nc_conform::import::{from_reader, gen, ColumnMap, Options};

/// One hour at 1 kHz.
const ROWS: u64 = 3_600_000;

fn import_csv(c: &mut Criterion) {
    let map = ColumnMap::from_yaml("gen.yaml", gen::MAP).expect("the generator's map loads");
    let mut g = c.benchmark_group("import_csv_1h_1khz_8col");
    g.sample_size(10);
    g.throughput(Throughput::Elements(ROWS));
    g.bench_function("generator_only", |b| {
        b.iter(|| {
            let mut r = gen::GenCsv::new(ROWS);
            let mut n = 0usize;
            loop {
                let len = r.fill_buf().expect("in memory").len();
                if len == 0 {
                    break;
                }
                n += len;
                r.consume(len);
            }
            black_box(n)
        });
    });
    g.bench_function("import", |b| {
        b.iter(|| {
            let opts = Options { format: None, map: Some(&map), lenient: false };
            let imp = from_reader("gen.csv", Box::new(gen::GenCsv::new(ROWS)), &opts).expect("opens");
            let mut n = 0u64;
            for ev in imp {
                black_box(ev.expect("a good row"));
                n += 1;
            }
            black_box(n)
        });
    });
    g.finish();
}

/// JSON Lines rows in the JSON Lines benchmark.
const JSONL_ROWS: u64 = 500_000;

/// A JSON Lines trace as `nc-conform run` writes it: a meta line, then samples of 3 axes at 1 kHz.
fn jsonl_text(rows: u64) -> Vec<u8> {
    let mut out = String::from("{\"t_us\":0,\"kind\":\"meta\",\"dialect\":\"fanuc-mill\",\"axes\":[\"X\",\"Y\",\"Z\"],\"diameter\":[],\"period_us\":1000,\"sample_us\":1000,\"format\":\"nc-conform-trace/1\"}\n");
    for r in 0..rows {
        let z = -((r % 20_000) as f64) * 0.000_75;
        out.push_str(&format!(
            "{{\"t_us\":{},\"kind\":\"sample\",\"axes\":{{\"X\":60,\"Y\":28.5,\"Z\":{z:.6}}},\"spindle\":{{\"rpm\":1200,\"angle_deg\":{}}}}}\n",
            r * 1000,
            (r * 7200 % 360_000) as f64 / 1000.0
        ));
    }
    out.push_str(&format!(
        "{{\"t_us\":{},\"kind\":\"end\",\"reason\":\"program_end\",\"axes\":{{\"X\":60,\"Y\":28.5,\"Z\":0}},\"command\":{{\"X\":60,\"Y\":28.5,\"Z\":0}},\"spindle\":{{\"rpm\":0,\"angle_deg\":0}},\"signals\":{{\"STL\":1}},\"modal\":[],\"alarms\":0,\"blocks\":0}}\n",
        rows * 1000
    ));
    out.into_bytes()
}

fn import_jsonl(c: &mut Criterion) {
    let text = jsonl_text(JSONL_ROWS);
    let mut g = c.benchmark_group("import_jsonl_500k_samples");
    g.sample_size(10);
    g.throughput(Throughput::Elements(JSONL_ROWS));
    g.bench_function("import", |b| {
        b.iter(|| {
            let opts = Options { format: None, map: None, lenient: false };
            let imp =
                from_reader("gen.jsonl", Box::new(std::io::Cursor::new(text.clone())), &opts).expect("opens");
            let mut n = 0u64;
            for ev in imp {
                black_box(ev.expect("a good line"));
                n += 1;
            }
            assert_eq!(n, JSONL_ROWS + 1);
            black_box(n)
        });
    });
    g.finish();
}

criterion_group!(benches, import_csv, import_jsonl);
criterion_main!(benches);
