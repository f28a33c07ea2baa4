//! KND G93 tapping (seed 001): the tap follows the spindle's encoder, overshoots while the spindle
//! brakes, returns behind the reversed spindle; the forum's "never retracts" as alarms
//! (KND-G93-01..10) and the program basics (KND-LEX-*).

mod support;

use nc_engine::input::{Input, InputSchedule, PlcAnswer};
use nc_engine::trace::{EndReason, Phase, Signal};
use nc_engine::RunOptions;
use support::run;

const MM: i64 = 1_000_000;
const G93: &str = "G00 X0 Z5;\nM03 S300;\nG93 Z-20 F1.5;\nG00 Z50;\nM30;\n";

fn sampled(inputs: InputSchedule) -> RunOptions {
    RunOptions { inputs, sample_us: 1000, ..RunOptions::default() }
}

fn codes(t: &nc_engine::Trace) -> Vec<&'static str> {
    t.alarms().map(|(_, a)| a.kind.code()).collect()
}

/// The deepest Z the samples show, nm.
fn deepest(t: &nc_engine::Trace) -> i64 {
    t.samples().map(|(_, s)| s.axes[2]).min().unwrap()
}

#[test]
fn knd_g93_04_the_tap_overshoots_by_lead_times_braking_revolutions() {
    // 300 rpm, lead 1.5 mm, brake 300 ms: 5 rev/s × 0.15 s = 0.75 rev → 1.125 mm past Z-20.
    let t = run("knd-lathe", &[], G93, &sampled(InputSchedule::default()));
    assert!(codes(&t).is_empty(), "{:?}", codes(&t));
    assert_eq!(t.end().unwrap().reason, EndReason::ProgramEnd);
    assert!((deepest(&t) + 21_125_000).abs() <= 1_000, "{}", deepest(&t));
    // KND-G93-03: speed mode, no rigid tapping signals.
    assert_eq!(t.edges(Signal::Rgspp).count() + t.edges(Signal::Rtap).count(), 0);
    // KND-G93-09: the spindle resumes M03 after the return.
    let m: Vec<u32> = t.functions().filter(|f| f.1 == 'M').map(|f| f.2).collect();
    assert_eq!(m, [3, 3, 30]);
    let phases: Vec<Phase> = t.phases().map(|p| p.1).collect();
    assert_eq!(phases, [Phase::Cutting, Phase::Dwell, Phase::Retract, Phase::Idle]);
}

#[test]
fn knd_g93_05_a_long_brake_stops_the_tap_at_the_allowance_with_nc_1050() {
    // 20 s brake: 5 rev/s × 10 s × 1.5 mm = 75 mm > 50 mm.
    let t =
        run("knd-lathe", &[("nc.spindle_brake_ms", None, 20_000.0)], G93, &sampled(InputSchedule::default()));
    assert_eq!(codes(&t), ["NC-1050"]);
    assert_eq!(t.end().unwrap().state.axes[2], -70 * MM);
    let a = t.alarms().next().unwrap().1;
    assert!(a.detail.contains("75.000 mm") && a.detail.contains("50.000 mm"), "{}", a.detail);
    assert_eq!(a.line, Some(3));
}

#[test]
fn knd_g93_06_zero_speed_never_reported_raises_nc_1051_instead_of_waiting_for_ever() {
    let inputs =
        InputSchedule::default().at(0, Input::PlcAnswer { answer: PlcAnswer::ZeroSpeed, extra_us: None });
    let t = run("knd-lathe", &[("nc.g93_zsp_timeout_ms", None, 2000.0)], G93, &sampled(inputs));
    assert_eq!(codes(&t), ["NC-1051"]);
    let dwell = t.phases().find(|p| p.1 == Phase::Dwell).unwrap().0;
    assert_eq!(t.alarms().next().unwrap().0 - dwell, 2_000_000);
    assert!(!t.end().unwrap().signals.get(Signal::Zsp));
    assert!((t.end().unwrap().state.axes[2] + 21_125_000).abs() <= 1_000);
}

#[test]
fn knd_g93_02_no_spindle_raises_nc_1017_at_the_block() {
    let t = run("knd-lathe", &[], "G00 X0 Z5;\nS300;\nG93 Z-20 F1.5;\nM30;\n", &RunOptions::default());
    assert_eq!(codes(&t), ["NC-1017"]);
    assert_eq!(t.alarms().next().unwrap().1.line, Some(3));
}

#[test]
fn knd_g93_08_backlash_on_the_return_the_tap_stands_while_the_spindle_turns() {
    // 0.3 mm backlash at lead 1.5: the spindle turns 0.2 rev (72°) before Z moves out.
    let t = run("knd-lathe", &[("nc.backlash_mm", Some('Z'), 0.3)], G93, &sampled(InputSchedule::default()));
    assert!(codes(&t).is_empty());
    let ret = t.phases().find(|p| p.1 == Phase::Retract).unwrap().0;
    let s: Vec<_> = t.samples().filter(|(at, _)| *at >= ret).collect();
    let z0 = s[0].1.axes[2];
    let a0 = s[0].1.spindle_mdeg;
    let first_move = s.iter().find(|(_, x)| x.axes[2] != z0).unwrap();
    let turned = (a0 - first_move.1.spindle_mdeg).rem_euclid(360_000);
    assert!((60_000..=80_000).contains(&turned), "{turned}");
    // RVDL = 0: no compensation, Z moves at once.
    let t0 = run(
        "knd-lathe",
        &[("nc.backlash_mm", Some('Z'), 0.3), ("003.RVDL", None, 0.0)],
        G93,
        &sampled(InputSchedule::default()),
    );
    let ret0 = t0.phases().find(|p| p.1 == Phase::Retract).unwrap().0;
    let s0: Vec<_> = t0.samples().filter(|(at, _)| *at >= ret0).collect();
    let first0 = s0.iter().position(|(_, x)| x.axes[2] != s0[0].1.axes[2]).unwrap();
    let first = s.iter().position(|(_, x)| x.axes[2] != z0).unwrap();
    assert!(first0 < first, "{first0} {first}");
}

#[test]
fn knd_lex_basics_run_and_refusals_are_located() {
    let prog = "G50 X100 Z100;\nG98 G01 X80 Z90 F200;\nG04 P100;\nG04 X0.2;\nG99 G01 Z80 F0.1 M03 S500;\nG32 Z60 F2;\nG00 X90;\nG92 X78 Z40 F2;\nG28 U0 W0;\nM05;\nM30;\n";
    let t = run("knd-lathe", &[], prog, &RunOptions::default());
    // M03 and the feed move in one block: one M only, so it is fine.
    assert!(codes(&t).is_empty(), "{:?}", codes(&t));
    assert_eq!(t.end().unwrap().reason, EndReason::ProgramEnd);
    for (p, code, line) in [
        ("G96 S100.5;\n", "NC-1001", 1),
        ("G96;\nM03;\nG00 X10 S100000;\n", "NC-1001", 3),
        ("G90 X10 Z-5 F1;\n", "NC-1004", 1),
        ("G00 X0;\nG71 U1 R1;\n", "NC-1004", 2),
        ("M03 M08;\n", "NC-1016", 1),
        ("G31 X0;\n", "NC-1003", 1),
        ("G93 Z-5;\n", "NC-1002", 1),
        ("M03 S100;\nG93 X0 Z-5 F1;\n", "NC-1005", 2),
        ("G92 X10 Z-5 F1 L2;\n", "NC-1004", 1),
    ] {
        let t = run("knd-lathe", &[], p, &RunOptions::default());
        assert_eq!(codes(&t), [code], "{p}");
        assert_eq!(t.alarms().next().unwrap().1.line, Some(line), "{p}");
    }
}

#[test]
fn knd_g93_inputs_at_any_phase_end_the_run_and_keep_the_invariants() {
    // Operator inputs and faults dropped into every part of the cycle (cut, brake, ZSP wait,
    // return, resume): the run always ends, time-ordered, with no invariant violated.
    use nc_engine::invariants::{check, Context};
    let inputs = [
        Input::Reset,
        Input::FeedHold,
        Input::EmergencyStop(true),
        Input::SpindleStall(true),
        Input::MachineLock(true),
        Input::DryRun(true),
        Input::SingleBlock(true),
        Input::FeedOverride(0),
        Input::SpindleOverride(50),
    ];
    for input in inputs {
        for at_ms in [100u64, 1_000, 3_700, 3_858, 3_900, 5_000, 7_455, 7_460] {
            let sched = InputSchedule::default().at(at_ms * 1000, input.clone());
            let opts = RunOptions {
                inputs: sched,
                sample_us: 1000,
                time_limit_us: 120_000_000,
                auto_cycle_start: true,
                ..RunOptions::default()
            };
            let t = run("knd-lathe", &[("nc.backlash_mm", Some('Z'), 0.02)], G93, &opts);
            assert!(t.end().is_some(), "{input:?} at {at_ms} ms: no end");
            let ctx = Context { tap: None, range_alarm: None, pre_m29_mrpm: None, hold_suppressed: true };
            let v = check(&t, &ctx);
            assert!(v.is_empty(), "{input:?} at {at_ms} ms: {v:?}");
        }
    }
}

#[test]
fn knd_g93_07_the_return_turns_at_s_times_the_spindle_override() {
    // 300 rpm × 150 %: the return runs at -450 rpm, the cut before it at 300 (M03 came first).
    let inputs = InputSchedule::default().when(
        nc_engine::input::Condition::Phase(Phase::Cutting),
        1,
        0,
        Input::SpindleOverride(150),
    );
    let t = run("knd-lathe", &[], G93, &sampled(inputs));
    assert!(codes(&t).is_empty(), "{:?}", codes(&t));
    let cut_max = t.samples().map(|(_, s)| s.spindle_mrpm).max().unwrap();
    let ret_min = t.samples().map(|(_, s)| s.spindle_mrpm).min().unwrap();
    assert_eq!(cut_max, 450_000, "the resumed M03 turns at 450 rpm too");
    // The return's trapezoid is stretched to whole periods: its top speed is a hair below.
    assert!((ret_min + 450_000).abs() < 500, "{ret_min}");
    let plain = run("knd-lathe", &[], G93, &sampled(InputSchedule::default()));
    let plain_min = plain.samples().map(|(_, s)| s.spindle_mrpm).min().unwrap();
    assert!((plain_min + 300_000).abs() < 500, "{plain_min}");
}

#[test]
fn knd_g93_after_g96_then_g97_taps_at_the_last_surface_speed() {
    // G96 S150 at X100: 477.465 rpm; G97 without S keeps it as S (KND-CSS-04), so G93 runs at it
    // (rounded to 477 rpm for the return) instead of refusing a spindle without S.
    let prog = "G00 X100 Z5;\nG96 S150 M03;\nG04 P500;\nG97;\nG93 Z-5 F1;\nM30;\n";
    let t = run("knd-lathe", &[], prog, &RunOptions::default());
    assert!(codes(&t).is_empty(), "{:?}", codes(&t));
    assert_eq!(t.end().unwrap().reason, EndReason::ProgramEnd);
    let top = t.samples().map(|(_, s)| s.spindle_mrpm).max().unwrap();
    let low = t.samples().map(|(_, s)| s.spindle_mrpm).min().unwrap();
    assert!((477_400..=477_500).contains(&top), "{top}");
    assert!((-477_000..=-470_000).contains(&low), "{low}");
}
