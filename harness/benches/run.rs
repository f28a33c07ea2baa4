//! `nc-conform run` throughput: the engine streaming its trace through the JSON Lines writer
//! (what the command does, minus the file system), on the GSK seed peck program with 1 ms samples.
//! Throughput is in simulated µs, so elem/s ÷ 10^6 is the real-time factor.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nc_conform::jsonl::JsonlWriter;
use nc_engine::{Machine, RunOptions};

const PECK: &str = "G98;\nG0 X50 Z0;\nM29 S1000;\nG88 X-50 P3000 Q20000 R0.5 F2;\nG80;\nM30;\n";

fn bench(c: &mut Criterion) {
    let m = Machine::new("gsk-lathe").unwrap();
    let prog = m.parse(PECK).unwrap();
    let opts = RunOptions { sample_us: 1000, ..RunOptions::default() };
    let simulated = m.run_to_trace(&prog, &opts).events.last().unwrap().t_us;
    let mut g = c.benchmark_group("run_jsonl");
    g.throughput(Throughput::Elements(simulated));
    g.bench_function("gsk_g88_peck_1ms_samples_jsonl", |b| {
        b.iter(|| {
            let mut w = JsonlWriter::new(std::io::sink());
            m.run(&prog, &opts, &mut w);
            w.finish().unwrap()
        })
    });
    // The engine alone (events dropped): the writer's own cost is the difference.
    g.bench_function("gsk_g88_peck_1ms_samples_engine_only", |b| {
        b.iter(|| {
            let mut n = 0u64;
            let mut sink = |_: &nc_engine::trace::TraceEvent| n += 1;
            m.run(&prog, &opts, &mut Count(&mut sink));
            n
        })
    });
    g.finish();
}

/// A sink that hands every event to a closure.
struct Count<'a>(&'a mut dyn FnMut(&nc_engine::trace::TraceEvent));

impl nc_engine::trace::TraceSink for Count<'_> {
    fn start(&mut self, _: &nc_engine::trace::TraceMeta) {}
    fn event(&mut self, ev: &nc_engine::trace::TraceEvent) {
        (self.0)(ev);
    }
}

criterion_group!(run, bench);
criterion_main!(run);
