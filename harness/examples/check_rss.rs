//! `check` of a long recording, end to end, for the memory and throughput figures of
//! `docs/checking.md` (issue 14 §4): N rigid holes on a fanuc mill (about 530 samples each at
//! 1 ms), recorded as JSON Lines (what `nc-conform run` writes) and as CSV (a servo trace tool's
//! export: time, X, Y, Z, spindle speed and angle, a status word of F76.3, RGTAP, RGSPP, RGSPM),
//! then checked against the program, the reference replayed alongside (`check::check_source`).
//! It prints the rows, the time, rows/s and the process' peak RSS (`VmHWM`):
//!
//! ```sh
//! cargo build --release -p nc-conform --example check_rss
//! E=target/release/examples/check_rss
//! $E write 20000 /tmp/holes            # /tmp/holes.{nc,jsonl,csv,map.yaml}: 10.6 M rows
//! $E check /tmp/holes jsonl
//! $E check /tmp/holes csv
//! $E write-repeated 100000 /tmp/rep    # the same holes from a short program (G84 K1000 per row):
//!                                      # CSV only (/tmp/rep.{nc,csv,map.yaml}), about 20 MB a 1,000 holes
//! ```

use std::io::Write;
use std::time::Instant;

use nc_conform::check::holes::{program as holes, Csv, MAP};
use nc_conform::check::{self, Carried, CheckSpec, Source};
use nc_conform::import::{self, ColumnMap, Options};
use nc_conform::jsonl::JsonlWriter;
use nc_engine::trace::TraceSink;
use nc_engine::{Machine, RunOptions};

fn vm_hwm() -> String {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("VmHWM")).map(|l| l.split_whitespace().skip(1).collect())
        })
        .unwrap_or_else(|| "?".into())
}

/// `n` rigid holes (a multiple of 1,000 rounded up) from a program that does not grow with them:
/// rows of 1,000 holes 5 mm apart, each one `G84 ... K1000` block in incremental coordinates.
fn repeated(n: usize) -> String {
    let mut p = String::new();
    for row in 0..n.div_ceil(1000) {
        p.push_str(&format!(
            "G90 G00 X0 Y{} Z10\nM29 S2000\nG91 G99 G84 X5 Y0 Z-6 R-9 F3000 K1000\nG90 G80\n",
            row * 5
        ));
    }
    p.push_str("M30\n");
    p
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let m = Machine::new("fanuc-mill").expect("fanuc-mill");
    match (args.get(1).map(String::as_str), args.get(2), args.get(3)) {
        (Some("write"), Some(n), Some(base)) => {
            let n: usize = n.parse().expect("N holes");
            let text = holes(n);
            std::fs::write(format!("{base}.nc"), &text).expect("writes the program");
            std::fs::write(format!("{base}.map.yaml"), MAP).expect("writes the map");
            let p = m.parse(&text).expect("parses");
            let f = std::io::BufWriter::new(std::fs::File::create(format!("{base}.jsonl")).expect("creates"));
            let mut w = JsonlWriter::new(f);
            m.run(&p, &RunOptions::default(), &mut w);
            w.finish().expect("writes the JSON Lines");
            let f = std::io::BufWriter::with_capacity(
                1 << 20,
                std::fs::File::create(format!("{base}.csv")).expect("creates"),
            );
            let mut c = Csv::new(f);
            m.run(&p, &RunOptions::default(), &mut c);
            c.out.flush().expect("writes the CSV");
        }
        (Some("write-repeated"), Some(n), Some(base)) => {
            let n: usize = n.parse().expect("N holes");
            let text = repeated(n);
            std::fs::write(format!("{base}.nc"), &text).expect("writes the program");
            std::fs::write(format!("{base}.map.yaml"), MAP).expect("writes the map");
            let p = m.parse(&text).expect("parses");
            let f = std::io::BufWriter::with_capacity(
                1 << 20,
                std::fs::File::create(format!("{base}.csv")).expect("creates"),
            );
            let mut c = Csv::new(f);
            m.run(&p, &RunOptions::default(), &mut c);
            c.out.flush().expect("writes the CSV");
        }
        (Some("check"), Some(base), Some(fmt)) => {
            let text = std::fs::read_to_string(format!("{base}.nc")).expect("reads the program");
            let p = m.parse(&text).expect("parses");
            let map = ColumnMap::from_yaml("map.yaml", MAP).expect("the map loads");
            let opts = Options { format: None, map: (fmt == "csv").then_some(&map), lenient: false };
            let start = Instant::now();
            let imp =
                import::open(std::path::Path::new(&format!("{base}.{fmt}")), &opts).unwrap_or_else(|e| {
                    nc_conform::diag::InputError::from(e).report();
                    std::process::exit(2)
                });
            let spec = CheckSpec { carried: Carried::of(imp.meta()), ..CheckSpec::default() };
            let run = |sink: &mut dyn TraceSink| m.run(&p, &RunOptions::default(), sink);
            let rep = check::check_source(Source::Run(&run), imp.read_ahead().map_while(Result::ok), &spec);
            let secs = start.elapsed().as_secs_f64();
            let rows = rep.figures.recorded_samples;
            println!(
                "{fmt}: rows {rows}, {secs:.3} s, {:.2} M rows/s, conformant {}, divergences {}, reference samples held at most {}, other records {}, VmHWM {}",
                rows as f64 / secs / 1e6,
                rep.conformant(),
                rep.divergences.len() + rep.omitted,
                rep.reference_samples_held,
                rep.reference_records_held,
                vm_hwm()
            );
        }
        _ => {
            eprintln!("usage: check_rss write|write-repeated N BASE | check_rss check BASE jsonl|csv");
            std::process::exit(2)
        }
    }
}
