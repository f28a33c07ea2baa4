//! `nc-conform campaign`: the properties of [`crate::campaign::properties`] run for long, from
//! fresh seeds, with a progress bar and a summary of what the runs covered (`scripts/campaign`).
//! A failure is shrunk and written as a regression scenario; its replay commands are printed.

use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::PathBuf;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use super::{EXIT_INPUT, EXIT_OK, EXIT_RUN_FAILED};
use crate::campaign::properties::{self, Property};
use crate::campaign::Stats;

/// Arguments of `nc-conform campaign`.
#[derive(Debug, Args)]
pub struct CampaignArgs {
    /// Cases per property and round.
    #[arg(long, value_name = "N", default_value_t = 2000)]
    pub cases: u32,

    /// Rounds: each round runs every chosen property from a new seed.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub rounds: u32,

    /// The first seed (then seed+1, seed+2, ... per round); default: from the clock. Printed, so a
    /// campaign can be replayed.
    #[arg(long, value_name = "SEED")]
    pub seed: Option<u64>,

    /// Only this property (repeatable); default: all of them.
    #[arg(long, value_name = "NAME", value_parser = clap::builder::PossibleValuesParser::new(properties::ALL.map(|p| p.name)))]
    pub property: Vec<String>,

    /// Where failing cases are written as scenarios.
    #[arg(long, value_name = "DIR", default_value = "scenarios/regressions")]
    pub regressions: PathBuf,

    /// No progress bar (logs, CI).
    #[arg(long)]
    pub quiet: bool,
}

/// The situations a campaign should reach: every operator action and fault at every phase of a
/// rigid tapping cycle (the `reached` keys of [`crate::campaign::Report`]).
fn targets() -> Vec<String> {
    let inputs = [
        "feed_hold",
        "single_block",
        "reset",
        "emergency_stop",
        "dry_run",
        "machine_lock",
        "spindle_stall",
        "motor_current",
        "plc_answer",
        "overload_trip",
    ];
    let phases = ["positioning", "cutting", "dwell", "retract"];
    // The overload watch runs only while the tap cuts (GSK-RT-26): it trips in cutting or in a
    // peck retract, never while positioning or dwelling.
    let mut t: Vec<String> = inputs
        .iter()
        .flat_map(|i| phases.iter().map(move |p| (i, p)))
        .filter(|(i, p)| **i != "overload_trip" || matches!(**p, "cutting" | "retract"))
        .map(|(i, p)| format!("{i} during {p} in rigid mode"))
        .collect();
    t.push("phase overload_retract".into());
    t
}

/// Runs `nc-conform campaign`; returns the exit status.
pub fn run(args: &CampaignArgs) -> u8 {
    let chosen: Vec<Property> = if args.property.is_empty() {
        properties::ALL.to_vec()
    } else {
        args.property.iter().filter_map(|n| properties::by_name(n)).collect()
    };
    if args.cases == 0 || args.rounds == 0 {
        eprintln!("nc-conform campaign: --cases and --rounds must be at least 1");
        return EXIT_INPUT;
    }
    let seed0 = args.seed.unwrap_or_else(|| {
        std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(1, |d| d.as_nanos() as u64)
    });
    let total = chosen.len() as u64 * args.cases as u64 * args.rounds as u64;
    println!(
        "campaign: {} properties x {} cases x {} rounds from seed {seed0}",
        chosen.len(),
        args.cases,
        args.rounds
    );
    let bar = if args.quiet { ProgressBar::hidden() } else { ProgressBar::new(total) };
    bar.set_style(
        ProgressStyle::with_template(
            "{elapsed_precise} [{bar:40}] {pos}/{len} cases ({per_sec}, eta {eta}) {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    let started = std::time::Instant::now();
    let mut per_property: BTreeMap<&str, Stats> = BTreeMap::new();
    let mut all = Stats::default();
    let mut failures = Vec::new();
    for round in 0..args.rounds {
        let seed = seed0.wrapping_add(round as u64);
        for p in &chosen {
            bar.set_message(format!("{} (seed {seed})", p.name));
            let mut tick = |_: &crate::campaign::Report| bar.inc(1);
            match (p.run)(args.cases, seed, &args.regressions, &mut tick) {
                Ok(stats) => {
                    all.merge(&stats);
                    per_property.entry(p.name).or_default().merge(&stats);
                }
                Err(f) => {
                    bar.println(format!("{f}"));
                    all.merge(&f.stats);
                    per_property.entry(p.name).or_default().merge(&f.stats);
                    failures.push(f);
                }
            }
        }
    }
    bar.finish_and_clear();
    let secs = started.elapsed().as_secs_f64();
    let mut out = String::new();
    summary(&mut out, &per_property, &all, failures.len(), secs);
    print!("{out}");
    let _ = std::io::stdout().flush();
    if failures.is_empty() {
        EXIT_OK
    } else {
        for f in &failures {
            if let Some(p) = &f.path {
                println!("failure written to {}", p.display());
            }
        }
        EXIT_RUN_FAILED
    }
}

/// The summary: cases per property, alarms hit, ends, and the target situations reached.
fn summary(out: &mut String, per: &BTreeMap<&str, Stats>, all: &Stats, failures: usize, secs: f64) {
    use std::fmt::Write as _;
    let _ = writeln!(
        out,
        "\n{} cases in {secs:.1} s ({:.0} cases/s), {failures} failures",
        all.cases,
        all.cases as f64 / secs.max(1e-9)
    );
    for (name, s) in per {
        let _ = writeln!(out, "  {name}: {} cases", s.cases);
    }
    let _ = writeln!(out, "alarms hit:");
    for (code, n) in &all.alarms {
        let _ = writeln!(out, "  {code:<8} {n}");
    }
    let _ = writeln!(out, "runs ended by:");
    for (end, n) in &all.ends {
        let _ = writeln!(out, "  {end:<12} {n}");
    }
    let targets = targets();
    let covered = targets.iter().filter(|t| all.reached.contains_key(*t)).count();
    let _ = writeln!(out, "reached: {covered} of {} target situations", targets.len());
    for t in &targets {
        let n = all.reached.get(t).copied().unwrap_or(0);
        let _ = writeln!(out, "  {} {t:<50} {n}", if n > 0 { "+" } else { "-" });
    }
}
