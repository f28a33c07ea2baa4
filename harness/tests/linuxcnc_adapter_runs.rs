//! LinuxCNC 2.9's own runs of `scenarios/linuxcnc`, kept (`scripts/linuxcnc-conform --keep`) in
//! `testdata/linuxcnc/adapter-runs/` (its README: the command, the LinuxCNC version, the decision
//! each guards). `cargo test` cannot run LinuxCNC; these runs are the oracle in its place: each
//! kept trace is judged as `nc-conform conform` judged it (`conform::kept::judge_kept`: the
//! same reference run, tolerances and `verdict::judge`) and must pass. The reference fixed with
//! LinuxCNC as its oracle must stay that way: a reference without the fix (a plant setting put
//! back, the program the old reference ran in effect) must fail on the same trace, and the
//! judgement must fail on a trace showing the behaviour the decision ruled out.

use std::path::{Path, PathBuf};

use nc_conform::check::Tolerances;
use nc_conform::conform::kept::judge_kept;
use nc_conform::conform::verdict::{ScenarioVerdict, Status};
use nc_conform::scenario::load::{self, Scenario};
use nc_engine::dialect::{Dialect, Interpreter};
use nc_engine::exec::PlantConfig;
use nc_engine::params::{ParamDef, Params};
use nc_engine::parse::{LexRules, ParseError, Program};
use nc_engine::trace::AxisSpec;

/// One kept run: the scenario (under `scenarios/linuxcnc/`), its file (`adapter-runs/`), and the
/// decisions whose behaviour it shows.
struct Kept {
    scenario: &'static str,
    file: &'static str,
    guards: &'static str,
}

/// Every kept run that must pass.
const KEPT: &[Kept] = &[
    Kept { scenario: "g84/single_block", file: "g84_single_block.jsonl.gz", guards: "DEC-158, DEC-160" },
    Kept { scenario: "g331/standard", file: "g331_standard.jsonl.gz", guards: "DEC-149" },
    Kept { scenario: "g331/spindle_override", file: "g331_spindle_override.jsonl.gz", guards: "DEC-149" },
    Kept { scenario: "g331/feed_hold_deferred", file: "g331_feed_hold_deferred.jsonl.gz", guards: "DEC-157" },
    Kept {
        scenario: "g331/feed_hold_in_way_out",
        file: "g331_feed_hold_in_way_out.jsonl.gz",
        guards: "DEC-157",
    },
];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn runs() -> PathBuf {
    root().join("testdata/linuxcnc/adapter-runs")
}

/// The LinuxCNC machine's tolerances (`scripts/linuxcnc-conform`'s default `--tolerances`).
fn machine_tolerances() -> Tolerances {
    let p = root().join("examples/linuxcnc-adapter/tolerances.yaml");
    nc_conform::input::load_tolerances(&p).expect("the adapter's tolerances")
}

/// The text of a gzip file (`gzip -n`: no name, no extra fields).
fn gunzip(path: &Path) -> String {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(bytes.len() > 18 && bytes[..3] == [0x1f, 0x8b, 8], "{}: not gzip (deflate)", path.display());
    assert_eq!(bytes[3], 0, "{}: gzip header with optional fields (write it with gzip -n)", path.display());
    let body = &bytes[10..bytes.len() - 8];
    let out = miniz_oxide::inflate::decompress_to_vec(body).expect("a deflate stream");
    String::from_utf8(out).expect("UTF-8")
}

/// The scenario `name` as `conform` loads it, with its path.
fn scenario(name: &str) -> (Scenario, PathBuf) {
    let path = root().join("scenarios/linuxcnc").join(format!("{name}.yaml"));
    let s = load::load(&path, &format!("linuxcnc/{name}.yaml")).expect("the scenario loads");
    (s, path)
}

/// The verdict on the kept `file` of scenario `name`, its reference changed by `change` first.
fn verdict_with(name: &str, file: &str, change: impl FnOnce(&mut Scenario)) -> ScenarioVerdict {
    let (mut s, path) = scenario(name);
    change(&mut s);
    let text = gunzip(&runs().join(file));
    judge_kept(&s, &path, &machine_tolerances(), file, &text).expect("the kept trace reads")
}

/// The verdict on a kept trace whose text `mutate` changed (the reference unchanged).
fn verdict_of_text(name: &str, file: &str, mutate: impl FnOnce(String) -> String) -> ScenarioVerdict {
    let (s, path) = scenario(name);
    let text = gunzip(&runs().join(file));
    let changed = mutate(text.clone());
    assert_ne!(changed, text, "the mutation changed nothing");
    judge_kept(&s, &path, &machine_tolerances(), file, &changed).expect("the mutated trace reads")
}

#[test]
fn every_kept_linuxcnc_run_passes_as_conform_judged_it() {
    let mut bad = String::new();
    for k in KEPT {
        let v = verdict_with(k.scenario, k.file, |_| {});
        if v.status != Status::Passed {
            bad.push_str(&format!("{} ({}, {}):\n{}", k.scenario, k.file, k.guards, v.failure_text()));
        }
    }
    assert!(bad.is_empty(), "kept LinuxCNC runs that no longer pass:\n{bad}");
}

/// Every file in `adapter-runs/` named `*.jsonl.gz` is listed in [`KEPT`] (or judged by a test
/// of its own below), and every listed file is there.
#[test]
fn every_kept_file_is_judged() {
    let mut on_disk: Vec<String> = std::fs::read_dir(runs())
        .expect("adapter-runs/")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".jsonl.gz"))
        .collect();
    on_disk.sort();
    let mut listed: Vec<String> = KEPT.iter().map(|k| k.file.to_string()).collect();
    listed.extend(OTHERS.iter().map(|s| s.to_string()));
    listed.sort();
    assert_eq!(on_disk, listed);
    let readme = std::fs::read_to_string(runs().join("README.md")).expect("adapter-runs/README.md");
    for f in &listed {
        assert!(readme.contains(f.as_str()), "README.md does not describe {f}");
    }
}

/// Kept files judged by their own tests rather than through [`KEPT`].
const OTHERS: &[&str] = &[];

// ---- The reference without a fix fails on LinuxCNC's run ----

/// A dialect that is another with its plant settings changed: the reference without a fix.
#[derive(Debug)]
struct Changed {
    inner: &'static dyn Dialect,
    change: fn(&mut PlantConfig),
}

impl Dialect for Changed {
    fn name(&self) -> &'static str {
        self.inner.name()
    }
    fn lex_rules(&self) -> &'static LexRules {
        self.inner.lex_rules()
    }
    fn axes(&self) -> &'static [AxisSpec] {
        self.inner.axes()
    }
    fn param_table(&self) -> &'static [ParamDef] {
        self.inner.param_table()
    }
    fn plant_config(&self, params: &Params) -> PlantConfig {
        let mut c = self.inner.plant_config(params);
        (self.change)(&mut c);
        c
    }
    fn interpreter(&self, params: &Params) -> Box<dyn Interpreter> {
        self.inner.interpreter(params)
    }
    fn parse(&self, text: &str) -> Result<Program, ParseError> {
        self.inner.parse(text)
    }
}

/// `s`'s machine with its plant settings changed by `change`.
fn without(s: &mut Scenario, change: fn(&mut PlantConfig)) {
    let inner = s.machine.dialect;
    s.machine.dialect = Box::leak(Box::new(Changed { inner, change }));
}

/// DEC-160: LinuxCNC's step runs `G80 M4` with the G84 line and stops only before the G74 line
/// (three stops in all). The reference as it was before DEC-160 (`step_stops_before_motion`
/// off: a stop after every block) stops after `G80 M4` too and fails on LinuxCNC's run.
#[test]
fn dec160_a_reference_stopping_after_every_block_fails_on_linuxcnc_s_step() {
    let v = verdict_with("g84/single_block", "g84_single_block.jsonl.gz", |s| {
        without(s, |c| c.step_stops_before_motion = false)
    });
    let text = v.failure_text();
    assert_eq!(v.status, Status::Failed, "{text}");
    // The reference's fourth stop, after `G80 M4` (4399 ms), which LinuxCNC never makes.
    assert!(text.contains("[CHK-EVT-02] SPL ↑ missing"), "{text}");
}

// ---- A trace showing the behaviour a decision ruled out fails ----

/// The time of an event line (`{"t_us":N,...`).
fn t_us(line: &str) -> u64 {
    line.strip_prefix("{\"t_us\":")
        .and_then(|r| r.split(',').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("an event line: {line}"))
}

/// The trace with the events other than samples at `from_us` that `pick` selects moved to
/// `to_us` (after every event of that time), the rest in place.
fn moved(text: &str, from_us: u64, to_us: u64, pick: impl Fn(&str) -> bool) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let is_moved = |l: &&str| t_us(l) == from_us && !l.contains("\"kind\":\"sample\"") && pick(l);
    let taken: Vec<String> = lines
        .iter()
        .filter(|l| is_moved(l))
        .map(|l| l.replacen(&from_us.to_string(), &to_us.to_string(), 1))
        .collect();
    assert!(!taken.is_empty(), "no event at {from_us} µs to move");
    let mut out = String::new();
    let mut placed = false;
    for l in lines.iter().filter(|l| !is_moved(l)) {
        if !placed && t_us(l) > to_us {
            taken.iter().for_each(|m| out.push_str(&format!("{m}\n")));
            placed = true;
        }
        out.push_str(&format!("{l}\n"));
    }
    assert!(placed, "{to_us} µs is past the trace's end");
    out
}

/// DEC-149: LinuxCNC gives the spindle its sense back (the restoring M3) as the tap passes the
/// start at 3935 ms; the reference before DEC-149 gave it after the move back, at the line's
/// end (4057 ms in LinuxCNC's run), where the adapter had reported it too. LinuxCNC's run with
/// the M3 moved there fails: the judgement sees where the M3 comes.
#[test]
fn dec149_a_restoring_m3_after_the_move_back_fails() {
    let v = verdict_of_text("g331/standard", "g331_standard.jsonl.gz", |t| {
        moved(&t, 3_935_000, 4_057_000, |l| {
            l.contains("\"code\":3") || l.contains("\"MF\"") || l.contains("\"FIN\"")
        })
    });
    let text = v.failure_text();
    assert_eq!(v.status, Status::Failed, "{text}");
    assert!(text.contains("[CHK-EVT-01] M3 output 122.666 ms late"), "{text}");
}
