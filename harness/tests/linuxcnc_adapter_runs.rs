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
use nc_engine::parse::{Block, LexRules, ParseError, Program};
use nc_engine::plan::{FollowKind, PassLaw, Pos, Step};
use nc_engine::trace::AxisSpec;
use nc_engine::Alarm;

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
    Kept {
        scenario: "g331/feed_hold_then_reset_mid_stroke",
        file: "g331_feed_hold_then_reset_mid_stroke.jsonl.gz",
        guards: "DEC-154",
    },
    Kept { scenario: "g76/feed_hold", file: "g76_feed_hold.jsonl.gz", guards: "DEC-154" },
    Kept {
        scenario: "cycles/g81_feed_hold",
        file: "cycles_g81_feed_hold.jsonl.gz",
        guards: "DEC-154, DEC-155, DEC-156, DEC-159",
    },
    Kept {
        scenario: "g84/overrides_and_feed_hold",
        file: "g84_overrides_and_feed_hold.jsonl.gz",
        guards: "DEC-159",
    },
    Kept {
        scenario: "cycles/g91_l2_initial_below_r_g99",
        file: "cycles_g91_l2_initial_below_r_g99.jsonl.gz",
        guards: "DEC-153",
    },
    Kept {
        scenario: "g84/spindle_override_held_at_100",
        file: "g84_spindle_override_held_at_100.jsonl.gz",
        guards: "DEC-153",
    },
    Kept {
        scenario: "g84/spindle_never_at_speed",
        file: "g84_spindle_never_at_speed.jsonl.gz",
        guards: "LCNC-MOT-01 (at speed)",
    },
    Kept {
        scenario: "g331/emergency_stop",
        file: "g331_emergency_stop.jsonl.gz",
        guards: "T5 (sync cut), I5",
    },
    Kept { scenario: "g331/reset", file: "g331_reset.jsonl.gz", guards: "T5 (sync cut), DEC-153" },
    Kept { scenario: "g331/g33_index", file: "g331_g33_index.jsonl.gz", guards: "DEC-157" },
    Kept {
        scenario: "g76/spring_passes",
        file: "g76_spring_passes.jsonl.gz",
        guards: "DEC-147, DEC-155, DEC-156",
    },
    Kept { scenario: "g331/single_block", file: "g331_single_block.jsonl.gz", guards: "DEC-158, DEC-160" },
    Kept { scenario: "g331/no_k", file: "g331_no_k.jsonl.gz", guards: "DEC-150" },
    Kept { scenario: "g76/reset", file: "g76_reset_pass2.jsonl", guards: "T5 (the sync cut before a reset)" },
    Kept {
        scenario: "g76/spindle_override",
        file: "g76_spindle_override.jsonl.gz",
        guards: "LCNC-G76-01 (override at once)",
    },
    Kept { scenario: "g76/single_block", file: "g76_single_block.jsonl.gz", guards: "DEC-158, DEC-160" },
    Kept { scenario: "cycles/g88", file: "cycles_g88.jsonl.gz", guards: "DEC-151" },
    Kept { scenario: "g76/passes", file: "g76_passes.jsonl.gz", guards: "DEC-147" },
    Kept { scenario: "cycles/g99_planes", file: "cycles_g99_planes.jsonl.gz", guards: "DEC-166" },
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

/// The text of a kept file: JSON Lines, or JSON Lines in a gzip file (`.gz`, written by
/// `gzip -n`: no name, no extra fields).
fn gunzip(path: &Path) -> String {
    if path.extension().is_none_or(|e| e != "gz") {
        return std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    }
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
fn verdict_with(name: &str, file: &str, change: impl FnOnce(&mut Scenario, &Path)) -> ScenarioVerdict {
    let (mut s, path) = scenario(name);
    change(&mut s, &path);
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
        let v = verdict_with(k.scenario, k.file, |_, _| {});
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
        .filter(|n| n.ends_with(".jsonl.gz") || n.ends_with(".jsonl"))
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

/// Kept files judged by their own tests rather than through [`KEPT`]: runs `conform` failed,
/// with its verdict in `conform-verdicts.json`.
const OTHERS: &[&str] = &["g331_overshoot.jsonl.gz", "g76_single_block_lost_start.jsonl.gz"];

/// `judge_kept` is `conform`'s verdict: on runs `conform` failed (`g331/overshoot`, LinuxCNC
/// departing from its manual, U2: expectations, synchronisation and events; a `g76/single_block`
/// run whose last cycle start was lost), it gives the failures `conform` reported in its
/// `report.json` (kept in `conform-verdicts.json`), the same rule, test and text, in the same
/// order.
#[test]
fn the_kept_verdict_is_conform_s_verdict() {
    let text = std::fs::read_to_string(runs().join("conform-verdicts.json")).expect("conform-verdicts.json");
    let want: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    let want = want.as_array().expect("a list");
    assert_eq!(want.len(), OTHERS.len());
    for w in want {
        let file = w["file"].as_str().expect("file");
        let name = w["scenario"].as_str().expect("scenario");
        let scenario = name.trim_start_matches("linuxcnc/").trim_end_matches(".yaml");
        let v = verdict_with(scenario, file, |_, _| {});
        assert_eq!(v.name, name);
        assert_eq!(serde_json::to_value(&v.status).expect("status"), w["status"], "{file}");
        let got = serde_json::to_value(&v.failures).expect("failures");
        assert_eq!(got, w["failures"], "{file}: {}", v.failure_text());
    }
}

// ---- The reference without a fix fails on LinuxCNC's run ----

/// A dialect that is another with its plant settings changed, or its interpreter's steps: the
/// reference without a fix.
#[derive(Debug)]
struct Changed {
    inner: &'static dyn Dialect,
    change: fn(&mut PlantConfig),
    /// The interpreter's steps of each block, changed.
    edit: fn(Vec<Step>) -> Vec<Step>,
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
        Box::new(Edited { inner: self.inner.interpreter(params), edit: self.edit })
    }
    fn parse(&self, text: &str) -> Result<Program, ParseError> {
        self.inner.parse(text)
    }
}

/// An interpreter whose blocks' steps [`Changed::edit`] changes.
struct Edited {
    inner: Box<dyn Interpreter>,
    edit: fn(Vec<Step>) -> Vec<Step>,
}

impl Interpreter for Edited {
    fn block(&mut self, block: &Block, out: &mut Vec<Step>) -> Result<(), Alarm> {
        let start = out.len();
        let r = self.inner.block(block, out);
        let steps: Vec<Step> = out.drain(start..).collect();
        out.extend((self.edit)(steps));
        r
    }
    fn reset(&mut self, pos: Pos) {
        self.inner.reset(pos)
    }
    fn set_position(&mut self, pos: Pos) {
        self.inner.set_position(pos)
    }
    fn modal(&self) -> Vec<String> {
        self.inner.modal()
    }
    fn rigid_mode(&self) -> bool {
        self.inner.rigid_mode()
    }
    fn set_params(&mut self, params: &Params) {
        self.inner.set_params(params)
    }
    fn program(&mut self, program: &Program) {
        self.inner.program(program)
    }
}

/// The steps as they are.
fn unchanged(steps: Vec<Step>) -> Vec<Step> {
    steps
}

/// `s` running its program text changed by `change` (the scenario file at `path`).
fn with_program(s: &mut Scenario, path: &Path, change: impl FnOnce(&str) -> String) {
    let text = nc_conform::conform::drive::program_text(path, &s.name).expect("the program");
    let changed = change(&text);
    assert_ne!(changed, text, "the program is unchanged");
    s.program = s.machine.parse(&changed).expect("the changed program parses");
}

/// `s`'s machine with its plant settings changed by `change`.
fn without(s: &mut Scenario, change: fn(&mut PlantConfig)) {
    let inner = s.machine.dialect;
    s.machine.dialect = Box::leak(Box::new(Changed { inner, change, edit: unchanged }));
}

/// `s`'s interpreter with each block's steps changed by `edit`.
fn with_steps(s: &mut Scenario, edit: fn(Vec<Step>) -> Vec<Step>) {
    let inner = s.machine.dialect;
    s.machine.dialect = Box::leak(Box::new(Changed { inner, change: |_| {}, edit }));
}

/// DEC-160: LinuxCNC's step runs `G80 M4` with the G84 line and stops only before the G74 line,
/// and runs the M2 with the `G0 Z20` step after G33.1 and with the `G0 X20` step after G76 (three
/// stops in each). The reference as
/// it was before DEC-160 (`step_stops_before_motion` off: a stop after every block) stops once
/// more, where LinuxCNC never stops, and fails on both runs.
#[test]
fn dec160_a_reference_stopping_after_every_block_fails_on_linuxcnc_s_step() {
    for (name, file, extra_stop) in [
        // after `G80 M4`, before the G74 line
        ("g84/single_block", "g84_single_block.jsonl.gz", "SPL ↑ missing at 4399 ms"),
        // after `G0 Z20`, before the M2
        ("g331/single_block", "g331_single_block.jsonl.gz", "SPL ↑ missing at"),
        // after `G0 X20`, before the M2
        ("g76/single_block", "g76_single_block.jsonl.gz", "SPL ↑ missing at"),
    ] {
        let v = verdict_with(name, file, |s, _| without(s, |c| c.step_stops_before_motion = false));
        fails_with(&v, &format!("[CHK-EVT-02] {extra_stop}"));
        // The same run passes the reference with DEC-160 (`every_kept_...`).
    }
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

/// The failures of `v`, which must have failed with a failure containing `want`.
fn fails_with(v: &ScenarioVerdict, want: &str) {
    let text = v.failure_text();
    assert_eq!(v.status, Status::Failed, "{text}");
    assert!(text.contains(want), "no `{want}` in:\n{text}");
}

/// DEC-154: LinuxCNC's task pauses at the feed hold (798 ms) but motion runs the G76 pass to its
/// end and holds there (1903 ms): SPL where motion holds. SPL at the task's pause fails.
#[test]
fn dec154_spl_at_the_task_s_pause_in_a_g76_pass_fails() {
    let v = verdict_of_text("g76/feed_hold", "g76_feed_hold.jsonl.gz", |t| {
        moved(&t, 1_903_000, 798_000, |l| l.contains("\"SPL\"") || l.contains("\"STL\""))
    });
    fails_with(&v, "[CHK-EVT-01] SPL rises 1102 ms early");
}

/// DEC-154: a feed hold given during G33.1's cut never holds its motion (the reset comes
/// first): no SPL at all. SPL at the task's pause (445 ms) fails.
#[test]
fn dec154_spl_at_the_task_s_pause_in_a_rigid_tap_fails() {
    let v = verdict_of_text(
        "g331/feed_hold_then_reset_mid_stroke",
        "g331_feed_hold_then_reset_mid_stroke.jsonl.gz",
        |t| {
            let hold = "{\"t_us\":445000,\"kind\":\"input\",\"name\":\"feed_hold\",\"value\":\"\"}\n";
            assert!(t.contains(hold), "the feed hold at 445 ms");
            let spl = "{\"t_us\":445000,\"kind\":\"signal\",\"name\":\"SPL\",\"value\":1}\n";
            let stl = "{\"t_us\":445000,\"kind\":\"signal\",\"name\":\"STL\",\"value\":0}\n";
            t.replacen(hold, &format!("{hold}{spl}{stl}"), 1)
        },
    );
    fails_with(&v, "SPL ↑");
}

/// DEC-159: inputs counted from a time 0 seen 17 ms late held G84's tap 0.17 mm lower. The
/// reference given the feed hold 17 ms later than the scenario's (as the adapter gave it before
/// DEC-159) fails on LinuxCNC's run, which was given it on time.
#[test]
fn dec159_a_feed_hold_17_ms_late_fails_on_linuxcnc_s_g84() {
    let v = verdict_with("g84/overrides_and_feed_hold", "g84_overrides_and_feed_hold.jsonl.gz", |s, _| {
        let hold = s
            .opts
            .inputs
            .inputs
            .iter_mut()
            .find(|i| matches!(i.input, nc_engine::input::Input::FeedHold))
            .expect("the feed hold");
        match &mut hold.trigger {
            nc_engine::input::Trigger::When { delay_us, .. } => *delay_us += 17_000,
            other => panic!("{other:?}"),
        }
    });
    // The reference holds at Z -1.17 (the 0.17 mm of DEC-159), LinuxCNC at Z -1.
    fails_with(&v, "[CHK-ENV-01] Z position envelope");
}

/// DEC-153: LinuxCNC's interpreter keeps a canned cycle's P across programs; the adapter sets
/// it back to 0 before each run. A reference whose G84 dwells 0.3 s at the bottom (the P that
/// `cycles/g88` leaves) fails on LinuxCNC's run from the power-on state.
#[test]
fn dec153_a_sticky_cycle_p_fails_on_linuxcnc_s_g84_l2() {
    let v = verdict_with(
        "cycles/g91_l2_initial_below_r_g99",
        "cycles_g91_l2_initial_below_r_g99.jsonl.gz",
        |s, p| with_program(s, p, |t| t.replace("G84 X10 Z-8 R2 L2", "G84 X10 Z-8 R2 L2 P0.3")),
    );
    // The reference dwells at the first hole's bottom while LinuxCNC's tap is on its way out.
    fails_with(&v, "LCNC-CYC-03 [CHK-ENV-01] Z position envelope");
}

/// DEC-153: the adapter's power-on gives M48: the spindle override acts before the G84 (300 rpm
/// at 50 %). LinuxCNC's run as it would be left in M49 by an earlier abort (600 rpm until the
/// cycle) fails on the scenario's expectation. (A reference ignoring the override would not
/// fail here: `check` compares the spindle speed only at the end and through the
/// synchronisation, L-125; the scenario's expectations hold the reference to it.)
#[test]
fn dec153_overrides_left_off_fail_on_the_spindle_speed_before_the_g84() {
    let v = verdict_of_text(
        "g84/spindle_override_held_at_100",
        "g84_spindle_override_held_at_100.jsonl.gz",
        |t| {
            let mut out = String::new();
            let mut before = true;
            for l in t.lines() {
                if l.contains("\"kind\":\"phase\"") {
                    before = false;
                }
                let l = if before { l.replace("\"rpm\":300,", "\"rpm\":600,") } else { l.to_string() };
                out.push_str(&l);
                out.push('\n');
            }
            out
        },
    );
    fails_with(&v, "LCNC-TAP-02 [expect] check #1");
}

/// A G84 waits for the spindle at speed (LCNC-MOT-01, HAL `spindle.0.at-speed`): with the
/// spindle stalled LinuxCNC never feeds. A reference feeding without waiting fails.
#[test]
fn a_g84_feeding_before_the_spindle_is_at_speed_fails() {
    let v = verdict_with("g84/spindle_never_at_speed", "g84_spindle_never_at_speed.jsonl.gz", |s, _| {
        without(s, |c| c.feed_waits_at_speed = false)
    });
    // The reference taps to Z-10; LinuxCNC stays at R (Z2) until the time limit.
    fails_with(&v, "LCNC-CYC-03 [CHK-ENV-01] Z position envelope");
}

/// Moves the `kind` input of `s` (a `when:` input) by `us` µs (earlier when negative).
fn shift_input(s: &mut Scenario, kind: fn(&nc_engine::input::Input) -> bool, us: i64) {
    let i = s.opts.inputs.inputs.iter_mut().find(|i| kind(&i.input)).expect("the input");
    match &mut i.trigger {
        nc_engine::input::Trigger::When { delay_us, .. } => {
            *delay_us = delay_us.checked_add_signed(us).expect("a delay after the condition")
        }
        other => panic!("{other:?}"),
    }
}

/// An E-stop in G33.1's reversal, where the spindle brakes at 5000 rpm/s: LinuxCNC's run, given
/// it through HAL in its servo cycle (the adapter's `estop_at`), passes within 10 rpm (its final
/// speed -118 rpm, the reference's bound -120). LinuxCNC given it 16 ms late (the adapter's
/// E-stop through the task before its latency was measured, I5) is the reference given it 16 ms
/// early: 63 rpm beyond the tolerance, it fails (4 ms already fails by 12 rpm).
#[test]
fn an_e_stop_16_ms_late_in_the_reversal_fails() {
    let v = verdict_with("g331/emergency_stop", "g331_emergency_stop.jsonl.gz", |s, _| {
        shift_input(s, |i| matches!(i, nc_engine::input::Input::EmergencyStop(_)), -16_000)
    });
    fails_with(&v, "[CHK-END-01] final spindle speed");
}

/// A reset in G33.1's cut: LinuxCNC given it 35 ms late (the session's first reset before its
/// latency was measured, I2), i.e. the reference 35 ms early, fails on where the tap stops.
#[test]
fn a_reset_35_ms_late_in_the_cut_fails() {
    let v = verdict_with("g331/reset", "g331_reset.jsonl.gz", |s, _| {
        shift_input(s, |i| matches!(i, nc_engine::input::Input::Reset), -35_000)
    });
    fails_with(&v, "LCNC-G331-03 [CHK-ENV-01] Z position envelope");
}

/// DEC-150: LinuxCNC reports a G33.1 without K when its read-ahead reaches the line (time 0 of
/// the run), the G0 before it still runs. The alarm where the reference raised it before
/// DEC-150, when the program reached line 3 (146 ms, at the G0's end), fails.
#[test]
fn dec150_a_read_phase_alarm_when_the_line_is_reached_fails() {
    let v = verdict_of_text("g331/no_k", "g331_no_k.jsonl.gz", |t| {
        moved(&t, 0, 145_999, |l| l.contains("\"kind\":\"alarm\""))
    });
    fails_with(&v, "[CHK-EVT-01] alarm NC-1096 raised 145.999 ms late");
}

/// The spindle override acts at once on LinuxCNC, in a G76 pass as in G33.1 (its spindle
/// command follows the override in the servo cycle; the passes after it run at 300 rpm). A
/// reference whose override waits (`spindle_override_at_once` off) fails on both runs.
#[test]
fn a_spindle_override_that_waits_fails_on_linuxcnc_s_threads() {
    for (name, file, want) in [
        (
            "g76/spindle_override",
            "g76_spindle_override.jsonl.gz",
            "LCNC-G76-01 [CHK-ENV-01] Z position envelope",
        ),
        (
            "g331/spindle_override",
            "g331_spindle_override.jsonl.gz",
            "LCNC-G331-01 [CHK-ENV-01] Z position envelope",
        ),
    ] {
        let v = verdict_with(name, file, |s, _| without(s, |c| c.spindle_override_at_once = false));
        fails_with(&v, want);
    }
}

/// DEC-151: after G88's program stop and the cycle start, LinuxCNC leaves the tool at the bottom
/// (Z-5) and ends there. The reference as it was before DEC-151 (DEC-85: a rapid to the
/// clearance level, Z10 under G98, once cycle start is pressed), run here as the program with
/// that rapid written out on the line after the cycle, fails on LinuxCNC's run.
#[test]
fn dec151_a_retract_after_g88_s_cycle_start_fails() {
    let v = verdict_with("cycles/g88", "cycles_g88.jsonl.gz", |s, p| {
        with_program(s, p, |t| t.replace("G80 M2", "G0 Z10 M2"))
    });
    // The reference's rapid delays its M2 by 243 ms. (LinuxCNC's recording ends before the
    // reference's rapid does: the positions after its last sample, and the end positions, are
    // judged by the scenario's expectations only, L-125.)
    fails_with(&v, "[CHK-EVT-01] M2 output 243 ms early");
}

/// DEC-157: G33.1's move back is not synchronised on LinuxCNC (tp.c FINAL_REVERSAL), so a feed
/// hold given during the tap, or on the way out, holds the tap where it turned round past the
/// start (Z 5.346), before it moves back to Z5. The reference as it was before DEC-157 (the hold
/// suppressed to the end of the whole tap: the `HoldSuppress(false)` before the unsynchronised
/// move back left out) holds at Z5 and fails on both LinuxCNC runs.
#[test]
fn dec157_a_hold_deferred_to_the_end_of_the_tap_fails() {
    fn not_lifted_before_the_move_back(steps: Vec<Step>) -> Vec<Step> {
        let lifts = |k: usize| {
            matches!(steps[k], Step::HoldSuppress(false))
                && matches!(steps.get(k + 1), Some(Step::Follow(f)) if f.kind == FollowKind::Unsynced)
        };
        (0..steps.len()).filter(|&k| !lifts(k)).map(|k| steps[k].clone()).collect()
    }
    for (name, file) in [
        ("g331/feed_hold_deferred", "g331_feed_hold_deferred.jsonl.gz"),
        ("g331/feed_hold_in_way_out", "g331_feed_hold_in_way_out.jsonl.gz"),
    ] {
        // The wrapper itself changes nothing: every step kept, the run passes.
        let v = verdict_with(name, file, |s, _| with_steps(s, unchanged));
        assert_eq!(v.status, Status::Passed, "{}", v.failure_text());
        let v = verdict_with(name, file, |s, _| with_steps(s, not_lifted_before_the_move_back));
        fails_with(&v, "LCNC-G331-03 [CHK-ENV-01] Z position envelope");
    }
}

/// What `conform` refuses from a controller, `judge_kept` refuses: events out of time order, an
/// event after `end`, no `end`, an event that is not one; never a panic.
#[test]
fn a_kept_file_conform_would_refuse_is_an_input_error() {
    let (s, path) = scenario("g331/reset");
    let text = gunzip(&runs().join("g331_reset.jsonl.gz"));
    let lines: Vec<&str> = text.lines().collect();
    let n = lines.len();
    // the last sample before the end moved to the front
    let swapped = [&lines[n - 2..n - 1], &lines[..n - 2], &lines[n - 1..]].concat().join("\n");
    let after_end = format!("{text}{}\n", lines[n - 2]);
    let no_end = lines[..n - 1].join("\n");
    let garbage = text.replacen("\"kind\":\"sample\"", "\"kind\":\"sampel\"", 1);
    for (what, bad) in [("order", swapped), ("after end", after_end), ("no end", no_end), ("kind", garbage)] {
        let r = judge_kept(&s, &path, &machine_tolerances(), "bad.jsonl", &bad);
        assert!(r.is_err(), "{what}: judged");
    }
}

/// DEC-147: LinuxCNC ends each synchronised segment of a G76 pass with tapers (E2 L2) at rest,
/// and the next starts from rest behind the spindle and catches it up. The reference before
/// DEC-147 (the pass one accelerated synchronised move through its joints,
/// `PassLaw::Accelerated`) fails on LinuxCNC's `g76/passes` on the synchronisation.
#[test]
fn dec147_a_g76_pass_blended_through_its_taper_joints_fails() {
    fn blended(steps: Vec<Step>) -> Vec<Step> {
        steps
            .into_iter()
            .map(|s| match s {
                Step::Thread(p) if p.law == PassLaw::Segments => Step::Thread(nc_engine::plan::ThreadPass {
                    law: PassLaw::Accelerated { room: None },
                    ..p
                }),
                other => other,
            })
            .collect()
    }
    let file = "g76_passes.jsonl.gz";
    let v = verdict_with("g76/passes", file, |s, _| with_steps(s, blended));
    // 0.247 mm out of sync 17 ms into the taper of every pass (DEC-147: 0.251 mm).
    fails_with(&v, "LCNC-G76-01 [CHK-SYNC-01] Z synchronisation with the spindle, thread pass 1 (lead)");
}

/// DEC-166: LinuxCNC's G84 in G19 (`cycles/g99_planes`, hole Y10 Z15 down to X-5) feeds to its
/// permuted point X15 Y-5 Z10 and back to X15 Y5 Z10. The reference asked for the manual's tool
/// axis (`nc.g74_g84_plane_points` 0, DEC-84: X-5 Y10 Z15) fails on LinuxCNC's run.
#[test]
fn dec166_a_reference_tapping_along_the_manual_s_tool_axis_fails() {
    let v = verdict_with("cycles/g99_planes", "cycles_g99_planes.jsonl.gz", |s, _| {
        s.machine.params.set("nc.g74_g84_plane_points", None, 0.0).expect("a linuxcnc parameter");
    });
    fails_with(&v, "[CHK-ENV-01] X position envelope");
}
