//! GSK G92.3 variable-lead, equal tip-width threading (seed 002; rules GSK-G923-*): the passes,
//! the thread locked to the spindle's angle, the run-out, every alarm of the document, and the
//! operator inputs during a pass.

mod support;

use nc_engine::input::{Condition, Input, InputSchedule};
use nc_engine::trace::{EndReason, Phase, Trace};
use nc_engine::RunOptions;
use support::run;

const MM: i64 = 1_000_000;
/// Seed 002's own words: lead 4 mm growing by 0.1 mm per revolution, run-out J1 K2, tip width 1,
/// step 0.5, tool width 1: (4 − 1 − 1)/0.5 + 1 = 5 passes.
const PROG: &str = "G0 X40 Z5;\nM03 S500;\nG92.3 X36 Z-20 F4 J1 K2 D0.1 E1 Q0.5 A1;\nG0 X60;\nM30;\n";

fn sampled(inputs: InputSchedule) -> RunOptions {
    RunOptions { inputs, sample_us: 1000, ..RunOptions::default() }
}

fn codes(t: &Trace) -> Vec<&'static str> {
    t.alarms().map(|(_, a)| a.kind.code()).collect()
}

fn cut_count(t: &Trace) -> usize {
    t.phases().filter(|p| p.1 == Phase::Cutting).count()
}

/// Samples inside cutting phases whose Z moved, grouped by pass: (spindle turns unwrapped from
/// the pass's first sample, Z travel from the cycle start Z, X diameter).
fn passes(t: &Trace, start_z: i64) -> Vec<Vec<(f64, f64, i64)>> {
    let phases: Vec<(u64, Phase)> = t.phases().collect();
    let phase_at = |tu: u64| phases.iter().rev().find(|p| p.0 < tu).map_or(Phase::Idle, |p| p.1);
    let mut out: Vec<Vec<(f64, f64, i64)>> = Vec::new();
    let mut open = false;
    let mut turns = 0.0;
    let mut last_deg = 0.0;
    for (tu, s) in t.samples() {
        let z = s.axes[2];
        if phase_at(tu) == Phase::Cutting && z != start_z {
            let deg = s.spindle_mdeg as f64 / 1000.0;
            if !open {
                out.push(Vec::new());
                open = true;
                turns = 0.0;
            } else {
                turns += (deg - last_deg).rem_euclid(360.0) / 360.0;
            }
            last_deg = deg;
            out.last_mut().unwrap().push((turns, (start_z - z) as f64, s.axes[0]));
        } else {
            open = false;
        }
    }
    out
}

#[test]
fn gsk_g923_05_five_passes_each_back_at_the_start_point() {
    let t = run("gsk-lathe", &[], PROG, &sampled(InputSchedule::default()));
    assert!(codes(&t).is_empty(), "{:?}", codes(&t));
    assert_eq!(cut_count(&t), 5);
    let end = t.end().unwrap();
    assert_eq!(end.reason, EndReason::ProgramEnd);
    assert_eq!(end.state.axes[0], 60 * MM);
}

#[test]
fn gsk_g923_11_the_lead_grows_by_d_every_revolution_exactly() {
    // Between two samples the travel per turn is the lead there: L = sqrt(F² + 2·D·s).
    let t = run("gsk-lathe", &[], PROG, &sampled(InputSchedule::default()));
    let ps = passes(&t, 5 * MM);
    assert_eq!(ps.len(), 5);
    let (f, d) = (4e6, 0.1e6);
    let mut checked = 0;
    for p in &ps {
        for w in p.windows(2) {
            let (dn, ds) = (w[1].0 - w[0].0, w[1].1 - w[0].1);
            let s_mid = 0.5 * (w[0].1 + w[1].1);
            // Locked to the spindle between the catch-up ramp (v²/2a: 0.56 mm at 33 mm/s and
            // 1000 mm/s²) and the deceleration at the end (0.72 mm at the end's 38 mm/s).
            if dn <= 0.0 || w[0].1 < 1e6 || w[1].1 >= 24e6 {
                continue;
            }
            let expect = (f * f + 2.0 * d * s_mid).sqrt();
            assert!((ds / dn - expect).abs() < expect * 2e-3, "{} vs {expect}", ds / dn);
            checked += 1;
        }
    }
    assert!(checked > 2000, "{checked}");
    // The lead at the cut end: sqrt(16 + 2·0.1·25) = 4.583 mm.
    let last = ps[0].iter().rev().nth(2).unwrap();
    assert!(last.1 > 24e6, "{}", last.1);
}

#[test]
fn gsk_g923_05_pass_k_starts_k_steps_later_in_the_turn() {
    // Each pass starts min(k·Q, F−E−A)/F of a turn after the index: 0, 45°, 90°, 135°, 180°.
    let t = run("gsk-lathe", &[], PROG, &sampled(InputSchedule::default()));
    let (f, d) = (4e6, 0.1e6);
    let mut starts = Vec::new();
    let phases: Vec<(u64, Phase)> = t.phases().collect();
    let mut samples = t.samples().peekable();
    for (tc, p) in &phases {
        if *p != Phase::Cutting {
            continue;
        }
        // The first sample after the cut began where Z is 2 mm from the start: locked to the
        // spindle there (past the catch-up ramp), so the law F·n + D·n²/2 read back from it gives
        // the angle the pass' thread starts at (DEC-146: the axis itself started earlier).
        let s = loop {
            let (tu, s) = samples.next().unwrap();
            if tu > *tc && s.axes[2] < 3 * MM {
                break *s;
            }
        };
        let travel = (5 * MM - s.axes[2]) as f64;
        let n = (((f * f + 2.0 * d * travel).sqrt()) - f) / d;
        let start_deg = (s.spindle_mdeg as f64 / 1000.0 - n * 360.0).rem_euclid(360.0);
        starts.push(start_deg);
    }
    let expect = [0.0, 45.0, 90.0, 135.0, 180.0];
    for (got, want) in starts.iter().zip(expect) {
        let diff = (got - want + 180.0).rem_euclid(360.0) - 180.0;
        assert!(diff.abs() < 1.0, "{starts:?}");
    }
}

#[test]
fn gsk_g923_04_the_run_out_moves_x_by_j_over_the_last_k_of_z() {
    let t = run("gsk-lathe", &[], PROG, &sampled(InputSchedule::default()));
    let ps = passes(&t, 5 * MM);
    for p in &ps {
        for &(_, s, x) in p {
            if s <= 23e6 - 1e3 {
                assert_eq!(x, 36 * MM, "straight before the run-out at {s}");
            }
        }
        // Over the last 2 mm of Z, X goes out to 36 + 2·1 (diameter): from the run-out's start
        // X accelerates out within its acceleration (DEC-146), never ahead of the linear run-out
        // and never back; it reaches 38 at the cut end.
        let last = p.last().unwrap();
        assert_eq!((last.1, last.2), (25e6, 38 * MM), "the run-out reaches J at the cut end");
        let mut prev = 36 * MM;
        for &(_, s, x) in p.iter().filter(|q| q.1 > 23e6) {
            let linear = 36e6 + 2e6 * (s - 23e6) / 2e6;
            assert!(x as f64 <= linear + 2e3 && x as f64 >= linear - 0.5e6, "{x} vs {linear} at {s}");
            assert!(x >= prev, "{x} after {prev}");
            prev = x;
        }
    }
}

#[test]
fn gsk_g923_09_taper_r_and_inch_lead() {
    // I8: 3.175 mm; R-1 (radius): the cut starts at X34 (diameter) and ends at X36.
    let p = "G0 X40 Z5;\nM03 S400;\nG92.3 X36 Z-10 R-1 I8 E0.5 Q1. A1;\nM30;\n";
    let t = run("gsk-lathe", &[], p, &sampled(InputSchedule::default()));
    assert!(codes(&t).is_empty(), "{:?}", codes(&t));
    // (3.175 − 0.5 − 1)/1 + 1 rounded up: 3 passes.
    assert_eq!(cut_count(&t), 3);
    let ps = passes(&t, 5 * MM);
    let first = ps[0][0];
    assert!(first.2 >= 34 * MM && first.2 < 34 * MM + 100_000, "{}", first.2);
    // X follows Z on the taper line: +2 mm diameter over 15 mm of Z.
    for &(_, s, x) in &ps[0] {
        let want = 34e6 + 2e6 * s / 15e6;
        assert!((x as f64 - want).abs() < 2.0, "{x} vs {want}");
    }
    // Constant lead (no D): once caught up (past v²/2a: 0.2 mm at 21 mm/s), travel = lead × turns.
    let locked: Vec<_> = ps[0].iter().filter(|q| q.1 > 1e6 && q.1 < 14e6).collect();
    assert!(locked.len() > 500, "{}", locked.len());
    let (n0, s0) = (locked[0].0, locked[0].1);
    for &&(n, s, _) in &locked {
        assert!((s - s0 - (n - n0) * 3_175_000.0).abs() < 50.0, "{s} {n}");
    }
}

#[test]
fn gsk_g923_10_every_alarm_of_the_document() {
    let cases: &[(&str, &str)] = &[
        // Lead out of range, and negative through D.
        ("G92.3 X36 Z-20 F600 E1 Q0.5 A1;", "NC-1060"),
        ("G92.3 X36 Z-20 F0 E1 Q0.5 A1;", "NC-1060"),
        ("G92.3 X36 Z-20 F2 D-0.5 E0.5 Q0.5 A0.5;", "NC-1060"),
        ("G92.3 X36 Z-20 F499 D100 E1 Q0.5 A1;", "NC-1060"),
        // Tool width, tip width above the smallest lead (with D < 0 the lead at the end).
        ("G92.3 X36 Z-20 F4 E1 Q0.5 A5;", "NC-1061"),
        ("G92.3 X36 Z-20 F4 D-0.1 E1 Q0.5 A3.5;", "NC-1061"),
        ("G92.3 X36 Z-20 F4 E5 Q0.5 A1;", "NC-1062"),
        ("G92.3 X36 Z-20 F4 E2 Q0.5 A2.5;", "NC-1062"),
        // Q = 0 or never given.
        ("G92.3 X36 Z-20 F4 E1 Q0 A1;", "NC-1063"),
        ("G92.3 X36 Z-20 F4 E1 A1;", "NC-1063"),
        // D out of range.
        ("G92.3 X36 Z-20 F4 D0.0001 E1 Q0.5 A1;", "NC-1064"),
        ("G92.3 X36 Z-20 F4 D-501 E1 Q0.5 A1;", "NC-1064"),
        // No face threads.
        ("G92.3 X20 W0 F4 E1 Q0.5 A1;", "NC-1065"),
        // Range of the other words.
        ("G92.3 X36 Z-20 F4 J-1 E1 Q0.5 A1;", "NC-1001"),
        ("G92.3 X36 Z-20 F4 K-1 E1 Q0.5 A1;", "NC-1001"),
        ("G92.3 X36 Z-20 F4 E-1 Q0.5 A1;", "NC-1001"),
        ("G92.3 X36 Z-20 F4 E1 Q-5 A1;", "NC-1001"),
        ("G92.3 X36 Z-20 F4 E1 Q0.5 A-1;", "NC-1001"),
        ("G92.3 X36 Z-20 R3 F4 E1 Q0.5 A1;", "NC-1001"),
        ("G92.3 X36 Z-20 I0.01 E1 Q0.5 A1;", "NC-1060"),
        ("G92.3 X36 Z-20 F4 I8 E1 Q0.5 A1;", "NC-1005"),
        ("G92.3 X36 Z-20 E1 Q0.5 A1;", "NC-1002"),
        ("G92.3 F4 E1 Q0.5 A1;", "NC-1002"),
        ("G92.3 X36 Z-20 C10 F4 E1 Q0.5 A1;", "NC-1005"),
    ];
    for (block, code) in cases {
        let p = format!("G0 X40 Z5;\nM03 S500;\n{block}\nM30;\n");
        let t = run("gsk-lathe", &[], &p, &RunOptions::default());
        assert_eq!(codes(&t), [*code], "{block}");
        let a = t.alarms().next().unwrap().1;
        assert_eq!(a.line, Some(3), "{block}");
        // The block does nothing: no cutting started.
        assert_eq!(cut_count(&t), 0, "{block}");
    }
}

#[test]
fn gsk_g923_03_no_spindle_raises_0011_when_the_pass_starts() {
    let p = "G0 X40 Z5;\nG92.3 X36 Z-20 F4 E1 Q0.5 A1;\nM30;\n";
    let t = run("gsk-lathe", &[], p, &RunOptions::default());
    assert_eq!(codes(&t), ["0011"]);
}

#[test]
fn gsk_g923_02_modal_repeat_with_a_new_x_keeps_the_other_words() {
    let p = "G0 X40 Z5;\nM03 S500;\nG92.3 X37 Z-10 F2 E0.5 Q0.5 A0.5;\nX36.5;\nX36;\nG0 X50;\nM30;\n";
    let t = run("gsk-lathe", &[], p, &RunOptions::default());
    assert!(codes(&t).is_empty(), "{:?}", codes(&t));
    // (2 − 0.5 − 0.5)/0.5 + 1 = 3 passes per block, three blocks.
    assert_eq!(cut_count(&t), 9);
    let t = run(
        "gsk-lathe",
        &[],
        "G0 X40 Z5;\nM03 S500;\nG92.3 X37 Z-10 F2 E0.5 Q0.5 A0.5;\n",
        &RunOptions::default(),
    );
    assert_eq!(t.end().unwrap().modal[0], "G92.3");
}

fn hold_during_first_pass(retract: f64) -> Trace {
    let inputs = InputSchedule::default()
        .when(Condition::Phase(Phase::Cutting), 1, 300_000, Input::FeedHold)
        .when(Condition::Phase(Phase::Cutting), 1, 3_000_000, Input::CycleStart);
    let opts = RunOptions { auto_cycle_start: false, ..sampled(inputs) };
    run("gsk-lathe", &[("nc.thread_retract", None, retract)], PROG, &opts)
}

#[test]
fn gsk_g923_12_feed_hold_finishes_the_pass_when_the_retract_bit_is_0() {
    let t = hold_during_first_pass(0.0);
    assert!(codes(&t).is_empty(), "{:?}", codes(&t));
    assert_eq!(t.end().unwrap().reason, EndReason::ProgramEnd);
    assert_eq!(cut_count(&t), 5);
    // The hold comes when the pass is back at the cycle start (its X retract and Z return
    // done), where single block stops too (seed 000 注意事项 6, DEC-111).
    let spl = t.edges(nc_engine::trace::Signal::Spl).find(|e| e.1).unwrap().0;
    let at = t.samples().find(|s| s.0 >= spl).unwrap().1;
    assert_eq!((at.axes[0], at.axes[2]), (40 * MM, 5 * MM), "held at the cycle start");
}

#[test]
fn gsk_g923_12_feed_hold_retracts_at_once_and_recuts_the_pass_when_the_bit_is_1() {
    let t = hold_during_first_pass(1.0);
    assert!(codes(&t).is_empty(), "{:?}", codes(&t));
    assert_eq!(t.end().unwrap().reason, EndReason::ProgramEnd);
    // The interrupted pass is cut again: six cutting phases.
    assert_eq!(cut_count(&t), 6);
    let spl = t.edges(nc_engine::trace::Signal::Spl).find(|e| e.1).unwrap().0;
    let at = t.samples().find(|s| s.0 >= spl).unwrap().1;
    assert_eq!((at.axes[0], at.axes[2]), (40 * MM, 5 * MM), "held at the cycle start");
    // The thread stopped where it was: Z never went past the hold's point before the retract.
    let hold_t = t.phases().find(|p| p.1 == Phase::Cutting).unwrap().0 + 300_000;
    let z_at_hold = t.samples().find(|s| s.0 >= hold_t).unwrap().1.axes[2];
    assert!(z_at_hold > -20 * MM, "{z_at_hold}");
}

#[test]
fn gsk_g923_13_single_block_stops_after_every_pass() {
    let inputs = InputSchedule::default().at(0, Input::SingleBlock(true)).when(
        Condition::Phase(Phase::Idle),
        1,
        0,
        Input::SingleBlock(false),
    );
    let mut sched = inputs;
    for k in 0..12 {
        sched = sched.at(1_000_000 + k * 2_000_000, Input::CycleStart);
    }
    let opts = RunOptions { auto_cycle_start: false, ..sampled(sched) };
    let t = run("gsk-lathe", &[], PROG, &opts);
    assert!(codes(&t).is_empty(), "{:?}", codes(&t));
    // Stops: after G0, after M03, after each of the five passes.
    let stops: Vec<u64> = t.edges(nc_engine::trace::Signal::Spl).filter(|e| e.1).map(|e| e.0).collect();
    // Single block goes off when the cycle ends: no stop after the last pass.
    assert_eq!(stops.len(), 6, "{stops:?}");
    for &s in &stops[2..6] {
        let at = t.samples().find(|x| x.0 >= s).unwrap().1;
        assert_eq!((at.axes[0], at.axes[2]), (40 * MM, 5 * MM), "a pass ends at the start point");
    }
}

#[test]
fn gsk_g923_14_machine_lock_keeps_the_axes_and_the_timing_dry_run_changes_nothing() {
    let plain = run("gsk-lathe", &[], PROG, &sampled(InputSchedule::default()));
    let locked =
        run("gsk-lathe", &[], PROG, &sampled(InputSchedule::default().at(0, Input::MachineLock(true))));
    let dry = run("gsk-lathe", &[], PROG, &sampled(InputSchedule::default().at(0, Input::DryRun(true))));
    let ovr = run("gsk-lathe", &[], PROG, &sampled(InputSchedule::default().at(0, Input::FeedOverride(50))));
    let end = |t: &Trace| t.end().unwrap().clone();
    assert_eq!(end(&locked).state.axes, [0; 6]);
    assert!(locked.samples().all(|s| s.1.axes == [0; 6]));
    // The spindle turns under machine lock (speed mode).
    assert!(locked.samples().any(|s| s.1.spindle_mrpm == 500_000));
    for other in [&locked, &dry, &ovr] {
        let a: Vec<(u64, Phase)> = plain.phases().collect();
        let b: Vec<(u64, Phase)> = other.phases().collect();
        assert_eq!(a, b, "same timing");
    }
    assert_eq!(end(&dry).state, end(&plain).state);
}

#[test]
fn gsk_g923_15_reset_and_emergency_stop_stop_the_thread_where_it_is() {
    let inputs = InputSchedule::default().when(Condition::Phase(Phase::Cutting), 2, 500_000, Input::Reset);
    let t = run("gsk-lathe", &[], PROG, &sampled(inputs));
    let end = t.end().unwrap();
    assert_eq!(end.reason, EndReason::Reset);
    assert!(end.state.axes[2] < 5 * MM && end.state.axes[2] > -20 * MM, "{}", end.state.axes[2]);
    let inputs = InputSchedule::default().when(
        Condition::Phase(Phase::Cutting),
        1,
        400_000,
        Input::EmergencyStop(true),
    );
    let t = run("gsk-lathe", &[], PROG, &sampled(inputs));
    assert_eq!(codes(&t), ["NC-1030"]);
    let z = t.end().unwrap().state.axes[2];
    assert!(z < 5 * MM && z > -20 * MM, "{z}");
}

#[test]
fn gsk_g923_16_many_passes_are_planned_as_the_run_reaches_them() {
    // Q0.0001 over 2 mm: 20001 passes; the run is cut short by the time limit, cheaply.
    let p = "G0 X40 Z5;\nM03 S500;\nG92.3 X36 Z-20 F4 E1 Q0.0001 A1;\nM30;\n";
    let opts = RunOptions { time_limit_us: 5_000_000, ..RunOptions::default() };
    let t = run("gsk-lathe", &[], p, &opts);
    assert_eq!(t.end().unwrap().reason, EndReason::TimeLimit);
    assert!(cut_count(&t) >= 3);
}
