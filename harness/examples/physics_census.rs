//! A census of the physics invariants (INV-11..INV-14, issue 12) over fresh campaign cases:
//! decodes N cases from a seeded byte stream (the `engine_case` fuzz target's `Case`), checks each
//! with the campaign's oracle, and counts the violations by invariant, dialect and kind, with the
//! first case of each kind. Unlike `nc-conform campaign` it does not stop at the first failure.
//!
//! `cargo run --release -p nc-conform --example physics_census -- [CASES] [SEED] [SHOW]`: with
//! SHOW = k, case k is printed as a regression scenario instead.

use std::collections::BTreeMap;

use arbitrary::{Arbitrary, Unstructured};
use nc_conform::campaign::{check_case, Case};

fn main() {
    let mut args = std::env::args().skip(1);
    let cases: u64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(10_000);
    let seed: u64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(1);
    let show: Option<u64> = args.next().and_then(|a| a.parse().ok());
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut bytes = vec![0u8; 2048];
    let mut tally: BTreeMap<String, (u64, String)> = BTreeMap::new();
    let (mut run, mut broken, mut threads) = (0u64, 0u64, 0u64);
    for k in 0..cases {
        for b in bytes.iter_mut() {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            *b = state as u8;
        }
        let Ok(case) = Case::arbitrary(&mut Unstructured::new(&bytes)) else { continue };
        run += 1;
        use nc_conform::campaign::case::Cycle;
        if matches!(case.program.cycle, Cycle::GskG923 | Cycle::Heidenhain832) {
            threads += 1;
        }
        let report = check_case(&case);
        if show == Some(k) {
            let origin = format!("physics census, seed {seed}, case {k}");
            print!("{}", nc_conform::campaign::regression::scenario_yaml(&case, &report.violations, &origin));
            return;
        }
        let dialect = case.machine().dialect.name();
        if !report.violations.is_empty() {
            broken += 1;
        }
        for v in &report.violations {
            let kind: String = v.detail.split_whitespace().take(2).collect::<Vec<_>>().join(" ");
            let key = format!("{} {} [{dialect}] {kind}", v.invariant.id(), v.invariant.name());
            let e = tally.entry(key).or_insert((0, format!("case {k}: {v}")));
            e.0 += 1;
        }
    }
    println!("{run} cases (seed {seed}), {threads} of them thread passes (G92.3, cycle 832), {broken} with a violation");
    for (key, (n, first)) in &tally {
        println!("{n:>6}  {key}\n        first: {first}");
    }
}
