//! Engine throughput (issue 2): simulated time per wall-clock time on the GSK seed peck program
//! with 1 ms samples, and a generated 20,000-hole Fanuc G84 program with samples off.
//!
//! Criterion's throughput is set to the simulated microseconds of one run, so "elem/s" divided by
//! 10^6 is the real-time factor (simulated seconds per wall-clock second).

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use nc_engine::trace::{Event, TraceEvent, TraceSink};
use nc_engine::{Machine, RunOptions};
use std::hint::black_box;

/// Counts events and keeps the last time: what a streaming writer would see, minus formatting.
#[derive(Default)]
struct CountSink {
    events: u64,
    samples: u64,
    last_t: u64,
}

impl TraceSink for CountSink {
    fn event(&mut self, ev: &TraceEvent) {
        self.events += 1;
        if let Event::Sample(s) = &ev.event {
            self.samples += 1;
            black_box(s);
        }
        self.last_t = ev.t_us;
    }
}

const PECK: &str = "G98;\nG0 X50 Z0;\nM29 S1000;\nG88 X-50 P3000 Q20000 R0.5 F2;\nG80;\nM30;\n";

/// A Fanuc program tapping `holes` holes on a grid, rigid, 20 holes per row.
pub fn fanuc_holes(holes: usize) -> String {
    let mut s =
        String::from("G90 G17 G21 G94 G54\nG0 X0 Y0 Z50\nS1000 M3\nM29 S1000\nG98 G84 X0 Y0 Z-12 R2 F1000\n");
    for i in 1..holes {
        s.push_str(&format!("X{} Y{}\n", (i % 20) * 10, (i / 20) * 10));
    }
    s.push_str("G80\nM30\n");
    s
}

/// A KND G93 program (examples/knd_g93.nc): two holes, M10×1.5 at 300 rpm.
const KND_G93: &str =
    "G98;\nG00 X100 Z100;\nM03 S300;\nG00 X0 Z5;\nM08;\nG93 Z-20 F1.5;\nW-25;\nG00 Z100;\nM09;\nM05;\nM30;\n";

fn run_once(m: &Machine, prog: &nc_engine::Program, opts: &RunOptions) -> CountSink {
    let mut sink = CountSink::default();
    m.run(prog, opts, &mut sink);
    sink
}

fn benches(c: &mut Criterion) {
    let m = Machine::new("gsk-lathe").unwrap();
    let prog = m.parse(PECK).unwrap();
    let opts = RunOptions { sample_us: 1000, ..RunOptions::default() };
    let probe = run_once(&m, &prog, &opts);
    eprintln!("gsk peck: {} µs simulated, {} events, {} samples", probe.last_t, probe.events, probe.samples);
    let mut g = c.benchmark_group("realtime_factor");
    g.throughput(Throughput::Elements(probe.last_t));
    g.bench_function("gsk_g88_peck_1ms_samples", |b| b.iter(|| run_once(&m, &prog, &opts)));
    g.finish();

    // knd-lathe: the seed-001 G93 program (cut, brake overshoot, ZSP wait, return, M03 again).
    let km = Machine::new("knd-lathe").unwrap();
    let kprog = km.parse(KND_G93).unwrap();
    let probe = run_once(&km, &kprog, &opts);
    eprintln!("knd g93: {} µs simulated, {} events, {} samples", probe.last_t, probe.events, probe.samples);
    let mut g = c.benchmark_group("realtime_factor");
    g.throughput(Throughput::Elements(probe.last_t));
    g.bench_function("knd_g93_1ms_samples", |b| b.iter(|| run_once(&km, &kprog, &opts)));
    g.finish();

    let fm = Machine::new("fanuc-mill").unwrap();
    let text = fanuc_holes(20_000);
    let fprog = fm.parse(&text).unwrap();
    let fopts = RunOptions { sample_us: 0, ..RunOptions::default() };
    let probe = run_once(&fm, &fprog, &fopts);
    eprintln!("fanuc 20000 holes: {} µs simulated, {} events", probe.last_t, probe.events);
    let mut g = c.benchmark_group("events_only");
    g.sample_size(10);
    g.throughput(Throughput::Elements(probe.last_t));
    g.bench_function("fanuc_g84_20000_holes_no_samples", |b| {
        b.iter_batched(|| (), |_| run_once(&fm, &fprog, &fopts), BatchSize::SmallInput)
    });
    g.finish();

    // heidenhain: the seed-004 cycle 832 example (Klartext, taper thread, 2 starts x 8 passes).
    let hm = Machine::new("heidenhain").unwrap();
    let hprog = hm.parse(include_str!("../../examples/heidenhain_832_seed.h")).unwrap();
    let probe = run_once(&hm, &hprog, &opts);
    eprintln!(
        "heidenhain 832: {} µs simulated, {} events, {} samples",
        probe.last_t, probe.events, probe.samples
    );
    let mut g = c.benchmark_group("realtime_factor");
    g.throughput(Throughput::Elements(probe.last_t));
    g.bench_function("heidenhain_832_seed_1ms_samples", |b| b.iter(|| run_once(&hm, &hprog, &opts)));
    g.finish();
}

criterion_group!(engine, benches);
criterion_main!(engine);
