//! Import benchmark: a 1-hour, 1 kHz, 8-column CSV trace (3.6 million rows, generated as a
//! stream by `nc_conform::import::gen`, never written to disk), imported event by event. The
//! throughput is reported in rows per second. Peak memory: `examples/import_rss.rs` under
//! `/usr/bin/time -v` (see `docs/checking.md`).
//!
//! The same hour as JSON Lines (`gen::GenJsonl`) through the JSON Lines reader.
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

/// One hour at 1 kHz as JSON Lines (`gen::GenJsonl`: X and Z, a signal line every 50 samples),
/// imported by the JSON Lines reader; throughput in sample rows per second.
fn import_jsonl(c: &mut Criterion) {
    let mut g = c.benchmark_group("import_jsonl_1h_1khz");
    g.sample_size(10);
    g.throughput(Throughput::Elements(ROWS));
    g.bench_function("generator_only", |b| {
        b.iter(|| {
            let mut r = gen::GenJsonl::new(ROWS);
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
            let imp = from_reader("gen.jsonl", Box::new(gen::GenJsonl::new(ROWS)), &Options::default())
                .expect("opens");
            let mut n = 0u64;
            for ev in imp {
                black_box(ev.expect("a good line"));
                n += 1;
            }
            black_box(n)
        });
    });
    g.finish();
}

criterion_group!(benches, import_csv, import_jsonl);
criterion_main!(benches);
