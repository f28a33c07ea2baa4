//! Helpers shared by the engine's integration tests.
#![allow(dead_code)]

use nc_engine::trace::{Event, Trace};
use nc_engine::{Machine, RunOptions};

/// Runs `text` on a default machine of `dialect` with `params` overrides.
pub fn run(dialect: &str, params: &[(&str, Option<char>, f64)], text: &str, opts: &RunOptions) -> Trace {
    let mut m = Machine::new(dialect).expect("dialect");
    for (id, ax, v) in params {
        m.params.set(id, *ax, *v).expect("param");
    }
    let prog = m.parse(text).expect("parse");
    m.run_to_trace(&prog, opts)
}

/// Runs with default options.
pub fn run_default(dialect: &str, text: &str) -> Trace {
    run(dialect, &[], text, &RunOptions::default())
}

/// A compact listing of the non-sample events (for debugging and snapshots).
pub fn events(trace: &Trace) -> String {
    let mut s = String::new();
    for e in &trace.events {
        let line = match &e.event {
            Event::Sample(_) => continue,
            Event::Signal { signal, value } => format!("signal {} {}", signal.name(), *value as u8),
            Event::Block { line, text } => format!("block {line} {text}"),
            Event::Function { letter, code } => format!("function {letter}{code}"),
            Event::Alarm(a) => format!("alarm {} {}", a.kind.code(), a.message()),
            Event::Phase(p) => format!("phase {}", p.name()),
            Event::Input { name, value } => format!("input {name} {value}"),
            Event::End(end) => {
                format!("end {} blocks={} alarms={}", end.reason.name(), end.blocks, end.alarms)
            }
        };
        s.push_str(&format!("{:>10} {line}\n", e.t_us));
    }
    s
}
