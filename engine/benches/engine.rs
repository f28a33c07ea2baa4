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

    // gsk-lathe G92.3 (seed 002): five variable-lead passes locked to the spindle, then a taper.
    let gm = Machine::new("gsk-lathe").unwrap();
    let gprog = gm.parse(GSK_G923).unwrap();
    let probe = run_once(&gm, &gprog, &opts);
    eprintln!("gsk g92.3: {} µs simulated, {} events, {} samples", probe.last_t, probe.events, probe.samples);
    let mut g = c.benchmark_group("realtime_factor");
    g.throughput(Throughput::Elements(probe.last_t));
    g.bench_function("gsk_g92_3_1ms_samples", |b| b.iter(|| run_once(&gm, &gprog, &opts)));
    g.finish();

    // linuxcnc: LinuxCNC's own g76only.ngc (35 synchronised passes) and a G33.1 hole.
    let lm = Machine::new("linuxcnc").unwrap();
    let lprog = lm.parse(LINUXCNC_G76_G331).unwrap();
    let probe = run_once(&lm, &lprog, &opts);
    eprintln!(
        "linuxcnc g76+g33.1: {} µs simulated, {} events, {} samples",
        probe.last_t, probe.events, probe.samples
    );
    let mut g = c.benchmark_group("realtime_factor");
    g.throughput(Throughput::Elements(probe.last_t));
    g.bench_function("linuxcnc_g76_g33_1_1ms_samples", |b| b.iter(|| run_once(&lm, &lprog, &opts)));
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

/// A GSK G92.3 program (examples/gsk_g92_3.nc): seed 002's words, then a taper pass set.
const GSK_G923: &str = "G98;\nG0 X40 Z5;\nM03 S500;\nG92.3 X36 Z-20 F4 J1 K2 D0.1 E1 Q0.5 A1;\n\
G92.3 X36 Z-10 R-1 F3 D-0.05 E0.5 Q0.5 A1;\nG0 X60;\nM05;\nM30;\n";

/// A LinuxCNC program: the G76 of LinuxCNC's tests/interp/g76/g76only.ngc, then a G33.1 hole.
const LINUXCNC_G76_G331: &str = "G20 G18 S800 M3\nG0 Z.2 X.2\nG76 P.05 Z-.5 I-.075 J.008 K.045 H3 R2.0 Q29.5 E.05 L2\nG0 X0 Z.1\nG33.1 Z-.5 K.05\nM5 M2\n";

criterion_group!(engine, benches);
criterion_main!(engine);
