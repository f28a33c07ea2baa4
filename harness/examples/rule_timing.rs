//! Our side of the RTAMT comparison (`scripts/rtamt_compare.py`, `docs/checking.md`,
//! "Performance"): imports a CSV trace (timed apart), then times `evaluate_discrete` of ONE
//! temporal rule on it, the rule `nc-conform check` evaluates on recorded traces:
//!
//! ```yaml
//! - rule: FAN-RT-03
//!   while: {signals: {F76.3: 1}}
//!   never_rises: [RGSPP]
//! ```
//!
//! (STL: `always ((F76.3 == 1) implies not rise(RGSPP))`.) The import is excluded from the rule's
//! time, as the CSV parsing is on the RTAMT side.
//!
//! ```sh
//! cargo build --release -p nc-conform --example rule_timing
//! target/release/examples/rule_timing /tmp/gen_1h.csv /tmp/gen.yaml
//! ```

use std::path::Path;
use std::time::Instant;

use nc_conform::import::{open, ColumnMap, Options};
use nc_conform::scenario::expect::evaluate_discrete;
use nc_conform::scenario::load::load_text;
use nc_engine::trace::{EndReason, EndSummary, Event, Trace, TraceEvent, TraceMeta};

const SCENARIO: &str = "\
title: F76.3 on, RGSPP never rises
rules: [FAN-RT-03]
dialect: fanuc-mill
program: |
  M30
expect:
  always:
    - rule: FAN-RT-03
      while: {signals: {F76.3: 1}}
      never_rises: [RGSPP]
";

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (Some(file), Some(map)) = (args.get(1), args.get(2)) else {
        eprintln!("usage: rule_timing FILE.csv MAP.yaml");
        std::process::exit(2)
    };
    let exit = |e: nc_conform::diag::InputError| -> ! {
        e.report();
        std::process::exit(2)
    };
    let map = ColumnMap::load(Path::new(map)).unwrap_or_else(|e| exit(e));
    let sc = load_text(SCENARIO, "rule.yaml", Path::new(".")).unwrap_or_else(|e| exit(e));
    let t0 = Instant::now();
    let opts = Options { format: None, map: Some(&map), lenient: false };
    let imp = open(Path::new(file), &opts).unwrap_or_else(|e| exit(e.into()));
    let meta = TraceMeta {
        dialect: "fanuc-mill",
        axes: imp.meta().axes.clone(),
        period_us: 1000,
        sample_us: imp.meta().sample_us.unwrap_or(1000),
    };
    let mut events: Vec<TraceEvent> = Vec::new();
    for ev in imp {
        events.push(ev.unwrap_or_else(|e| exit(e.into())));
    }
    let samples = events.iter().filter(|e| matches!(e.event, Event::Sample(_))).count();
    let t_end = events.last().map_or(0, |e| e.t_us);
    events.push(TraceEvent {
        t_us: t_end,
        event: Event::End(Box::new(EndSummary {
            reason: EndReason::Stopped,
            state: Default::default(),
            command: Default::default(),
            signals: Default::default(),
            modal: Vec::new(),
            alarms: 0,
            blocks: 0,
        })),
    });
    let trace = Trace { meta, events };
    let import_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let verdicts = evaluate_discrete(&sc.expect, &trace);
    let rule_s = t1.elapsed().as_secs_f64();
    for v in &verdicts {
        println!("{} {}: {}", v.rule, v.what, if v.pass { "pass" } else { "FAIL" });
    }
    println!("rows {samples}, import {import_s:.3} s, rule evaluation {rule_s:.4} s");
}
