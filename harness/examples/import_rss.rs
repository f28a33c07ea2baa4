//! Imports a generated CSV trace of N rows (default: 1 hour at 1 kHz, 8 columns) and prints the
//! rows, events and rows per second; run under `/usr/bin/time -v` for the peak RSS:
//!
//! ```sh
//! cargo build --release -p nc-conform --example import_rss
//! /usr/bin/time -v target/release/examples/import_rss 3600000
//! /usr/bin/time -v target/release/examples/import_rss 36000000   # ten hours: same peak
//! ```
//!
//! With a file argument after N (`import_rss 0 FILE.csv MAP.yaml`, `import_rss 0 FILE.jsonl`) it
//! imports that file instead; `import_rss N jsonl` imports N generated JSON Lines samples;
//! `import_rss write-csv N FILE` and `import_rss write-jsonl N FILE` write the generated
//! recordings to FILE (the 10 M-row figures of `docs/checking.md`).

use std::time::Instant;

use nc_conform::import::{from_reader, gen, open, ColumnMap, Options};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let (Some(what @ ("write-csv" | "write-jsonl")), Some(n), Some(file)) =
        (args.get(1).map(String::as_str), args.get(2).and_then(|a| a.parse().ok()), args.get(3))
    {
        let mut src: Box<dyn std::io::Read> =
            if what == "write-csv" { Box::new(gen::GenCsv::new(n)) } else { Box::new(gen::GenJsonl::new(n)) };
        let mut out = std::io::BufWriter::new(std::fs::File::create(file).expect("creates FILE"));
        std::io::copy(&mut src, &mut out).expect("writes FILE");
        return;
    }
    let rows: u64 = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(3_600_000);
    let start = Instant::now();
    let imp = if args.get(2).is_some_and(|a| a == "jsonl") {
        from_reader("gen.jsonl", Box::new(gen::GenJsonl::new(rows)), &Options::default())
    } else if let (Some(file), None) = (args.get(2), args.get(3)) {
        open(std::path::Path::new(file), &Options::default())
    } else if let (Some(file), Some(map)) = (args.get(2), args.get(3)) {
        let map = ColumnMap::load(std::path::Path::new(map)).unwrap_or_else(|e| {
            e.report();
            std::process::exit(2)
        });
        let opts = Options { format: None, map: Some(&map), lenient: false };
        open(std::path::Path::new(file), &opts)
    } else {
        let map = ColumnMap::from_yaml("gen.yaml", gen::MAP).expect("the generator's map loads");
        let opts = Options { format: None, map: Some(&map), lenient: false };
        from_reader("gen.csv", Box::new(gen::GenCsv::new(rows)), &opts)
    };
    let imp = imp.unwrap_or_else(|e| {
        nc_conform::diag::InputError::from(e).report();
        std::process::exit(2)
    });
    let (mut samples, mut events) = (0u64, 0u64);
    for ev in imp {
        match ev {
            Ok(e) => {
                events += 1;
                samples += u64::from(matches!(e.event, nc_engine::trace::Event::Sample(_)));
            }
            Err(e) => {
                nc_conform::diag::InputError::from(e).report();
                std::process::exit(2)
            }
        }
    }
    let secs = start.elapsed().as_secs_f64();
    println!("rows {samples}, events {events}, {secs:.3} s, {:.0} rows/s", samples as f64 / secs);
}
