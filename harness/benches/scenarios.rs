//! The whole scenario library: load, run on the reference engine, evaluate every expectation and
//! render both snapshot texts — what `cargo test --test scenarios` does per file, minus insta's
//! file comparison. Target (issue 3): under 5 s for the library on this 2-core machine.

use std::path::{Path, PathBuf};

use criterion::{criterion_group, criterion_main, Criterion};
use nc_conform::render::{events::event_listing, timing::timing_diagram};
use nc_conform::scenario::{load, run};

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).into_iter().flatten() {
        let p = e.unwrap().path();
        if p.is_dir() {
            files(&p, out);
        } else if p.extension().is_some_and(|e| e == "yaml") {
            out.push(p);
        }
    }
}

fn bench(c: &mut Criterion) {
    let mut all = Vec::new();
    files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios"), &mut all);
    eprintln!("{} scenarios", all.len());
    let mut g = c.benchmark_group("scenario_library");
    g.sample_size(10);
    g.bench_function("load_run_evaluate_render_all", |b| {
        b.iter(|| {
            for p in &all {
                let name = p.display().to_string();
                let s = load::load(p, &name).expect("scenario loads");
                let o = run::run(&s);
                std::hint::black_box((
                    timing_diagram(&o.trace, &s.diagram),
                    event_listing(&o.trace),
                    o.passed(),
                ));
            }
        })
    });
    g.finish();
}

criterion_group!(scenarios, bench);
criterion_main!(scenarios);
