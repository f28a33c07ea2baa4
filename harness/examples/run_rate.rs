//! `nc-conform run`'s JSON Lines writer as a real-time factor measured in CPU time, for a machine
//! shared with other work, where `cargo bench`'s wall times swing with the load: the program of
//! `benches/run.rs` (the GSK seed peck, 1 ms samples) run N times into `io::sink()`, then the
//! engine alone, the thread's own CPU time read from `/proc/thread-self/schedstat`:
//!
//! ```sh
//! cargo build --release -p nc-conform --example run_rate
//! target/release/examples/run_rate 2000
//! ```

use std::time::Instant;

use nc_conform::jsonl::JsonlWriter;
use nc_engine::trace::{TraceEvent, TraceMeta, TraceSink};
use nc_engine::{Machine, RunOptions};

const PECK: &str = "G98;\nG0 X50 Z0;\nM29 S1000;\nG88 X-50 P3000 Q20000 R0.5 F2;\nG80;\nM30;\n";

/// This thread's CPU time so far, ns.
fn cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|v| v.parse().ok()))
        .unwrap_or(0)
}

struct Drop0(u64);

impl TraceSink for Drop0 {
    fn start(&mut self, _: &TraceMeta) {}
    fn event(&mut self, _: &TraceEvent) {
        self.0 += 1;
    }
}

fn main() {
    let n: u32 = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(1000);
    let m = Machine::new("gsk-lathe").expect("gsk-lathe");
    let prog = m.parse(PECK).expect("parses");
    let opts = RunOptions { sample_us: 1000, ..RunOptions::default() };
    let simulated = m.run_to_trace(&prog, &opts).events.last().map_or(0, |e| e.t_us) as f64;
    let measure = |what: &str, f: &dyn Fn() -> u64| {
        let (w0, c0) = (Instant::now(), cpu_ns());
        let mut bytes = 0;
        for _ in 0..n {
            bytes += f();
        }
        let (wall, cpu) = (w0.elapsed().as_secs_f64(), (cpu_ns() - c0) as f64 / 1e9);
        println!(
            "{what}: {n} runs of {:.3} s machine time, {:.1} µs CPU per run ({:.0}x real time), {:.1} µs wall ({:.0}x), {} bytes per run",
            simulated / 1e6,
            cpu * 1e6 / n as f64,
            simulated * n as f64 / 1e6 / cpu,
            wall * 1e6 / n as f64,
            simulated * n as f64 / 1e6 / wall,
            bytes / u64::from(n.max(1))
        );
    };
    measure("jsonl", &|| {
        let mut w = JsonlWriter::new(std::io::sink());
        m.run(&prog, &opts, &mut w);
        let b = w.bytes();
        w.finish().expect("writes");
        b
    });
    measure("engine only", &|| {
        let mut s = Drop0(0);
        m.run(&prog, &opts, &mut s);
        s.0
    });
}
