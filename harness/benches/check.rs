//! `check` end to end (issue 14 §4): a recording of 400 rigid holes (`check::holes`, 210,000
//! rows at 1 ms) read from memory as JSON Lines and as CSV (parsed ahead on a thread of its own,
//! as the command does), compared with the program's reference
//! run replayed alongside (`check::check_source`): import, the reference's passes and the
//! comparison. Throughput in recorded rows per second. The 10 M-row figures and the peak memory:
//! `examples/check_rss.rs` (`docs/checking.md`).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nc_conform::check::{self, holes, Carried, CheckSpec, Source};
use nc_conform::import::{from_reader, ColumnMap, Options};
use nc_conform::jsonl::JsonlWriter;
use nc_engine::trace::TraceSink;
use nc_engine::{Machine, RunOptions};

const HOLES: usize = 400;

fn bench(c: &mut Criterion) {
    let m = Machine::new("fanuc-mill").unwrap();
    let p = m.parse(&holes::program(HOLES)).unwrap();
    let mut w = JsonlWriter::new(Vec::new());
    m.run(&p, &RunOptions::default(), &mut w);
    let jsonl = w.finish().unwrap();
    let mut csv = holes::Csv::new(Vec::new());
    m.run(&p, &RunOptions::default(), &mut csv);
    let csv = csv.out;
    let rows = m.run_to_trace(&p, &RunOptions::default()).samples().count() as u64;
    let map = ColumnMap::from_yaml("map.yaml", holes::MAP).unwrap();
    let run = |sink: &mut dyn TraceSink| m.run(&p, &RunOptions::default(), sink);
    let mut g = c.benchmark_group("check_400_rigid_holes");
    g.throughput(Throughput::Elements(rows));
    g.sample_size(10);
    for (name, data, map) in [("jsonl", &jsonl, None), ("csv", &csv, Some(&map))] {
        g.bench_function(name, |b| {
            b.iter(|| {
                let opts = Options { format: None, map, lenient: false };
                let imp = from_reader(name, Box::new(std::io::Cursor::new(data.clone())), &opts).unwrap();
                let spec = CheckSpec { carried: Carried::of(imp.meta()), ..CheckSpec::default() };
                let rep =
                    check::check_source(Source::Run(&run), imp.read_ahead().map_while(Result::ok), &spec);
                assert!(rep.conformant());
                rep.figures.recorded_samples
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
