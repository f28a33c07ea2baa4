//! GSK lathe rigid tapping G84/G88 end to end (rules GSK-RT-*, COM-PLC-*, COM-SYNC-* in docs/).

mod support;

use nc_engine::input::{CurrentSource, Input, InputSchedule};
use nc_engine::trace::{EndReason, Phase, Signal};
use nc_engine::RunOptions;
use rstest::rstest;
use support::{run, run_default};

const HEAD: &str = "G98;\nG0 X50 Z0;\nM29 S1000;\n";
const MM: i64 = 1_000_000;

fn prog(cycle: &str) -> String {
    format!("{HEAD}{cycle}\nG80;\nM30;\n")
}

/// X (diameter, nm) of every sample.
fn xs(t: &nc_engine::Trace) -> Vec<(u64, i64)> {
    t.samples().map(|(t, s)| (t, s.axes[0])).collect()
}

fn count_phase(t: &nc_engine::Trace, p: Phase) -> usize {
    t.phases().filter(|(_, q)| *q == p).count()
}

#[test]
fn gsk_rt_standard_seed_example_taps_to_the_bottom_dwells_and_returns() {
    // GSK-RT-07, GSK-RT-04: `G88 X-50 P3000 F2` after `G0 X50 Z0; M29 S1000;`.
    let t = run_default("gsk-lathe", &prog("G88 X-50 P3000 F2;"));
    let end = t.end().unwrap();
    assert_eq!(end.reason, EndReason::ProgramEnd, "{}", support::events(&t));
    assert_eq!(end.state.axes[0], 50 * MM, "back at the start point X50");
    let min_x = xs(&t).iter().map(|s| s.1).min().unwrap();
    assert_eq!(min_x, -50 * MM, "bottom X-50 on the diameter");
    assert_eq!(count_phase(&t, Phase::Cutting), 1);
    // Dwell: RGSPP falls at the bottom, RGSPM rises 3 s later.
    let spp: Vec<_> = t.edges(Signal::Rgspp).collect();
    let spm: Vec<_> = t.edges(Signal::Rgspm).collect();
    assert_eq!(spm[0].0 - spp[1].0, 3_000_000);
}

#[test]
fn gsk_rt_tap_travel_equals_lead_times_revolutions() {
    // COM-SYNC-01: 50 mm radius travel at lead 2 → 25 revolutions; the sampled positions agree
    // with the sampled spindle angle within one sample of travel.
    let t = run_default("gsk-lathe", &prog("G88 X-50 P3000 F2;"));
    let (t_in, _) = t.edges(Signal::Rgspp).next().unwrap();
    let (t_out, _) = t.edges(Signal::Rgspp).nth(1).unwrap();
    let samples: Vec<_> = t.samples().filter(|(ts, _)| *ts >= t_in && *ts <= t_out).collect();
    let x0 = samples[0].1.axes[0] / 2;
    let mut turned = 0.0f64;
    let mut last = samples[0].1.spindle_mdeg;
    for (_, s) in &samples[1..] {
        let mut d = s.spindle_mdeg - last;
        if d < -180_000 {
            d += 360_000;
        }
        turned += d as f64 / 360_000.0;
        last = s.spindle_mdeg;
        let travel = (x0 - s.axes[0] / 2) as f64;
        let expect = turned * 2.0 * MM as f64;
        // one sample at 1000 rpm × 2 mm/rev = 33.3 µm
        assert!((travel - expect).abs() <= 34_000.0, "travel {travel} vs lead×rev {expect}");
    }
    assert!((turned - 25.0).abs() < 1e-3, "turned {turned} revolutions");
}

#[test]
fn gsk_rt_high_speed_peck_seed_example_pecks_2mm_and_retracts_half_mm() {
    // GSK-RT-08: Q20000 (0.0001 mm units) = 2 mm radius per peck, R0.5 = 0.5 mm radius retract.
    let t = run_default("gsk-lathe", &prog("G88 X-50 P3000 Q20000 R0.5 F2;"));
    assert_eq!(t.end().unwrap().reason, EndReason::ProgramEnd);
    assert_eq!(count_phase(&t, Phase::Cutting), 25, "50 mm radius / 2 mm");
    // The X at each RGSPM rise (end of a cut) steps by 4 mm on the diameter.
    let cuts: Vec<i64> = t
        .edges(Signal::Rgspp)
        .filter(|e| !e.1)
        .map(|(ts, _)| t.samples().find(|(s, _)| *s == ts).unwrap().1.axes[0])
        .collect();
    assert_eq!(cuts[0], 46 * MM);
    assert_eq!(cuts[1], 42 * MM);
    assert_eq!(*cuts.last().unwrap(), -50 * MM);
    // Each retract stroke ends 1 mm (diameter) above the depth reached.
    let rets: Vec<i64> = t
        .edges(Signal::Rgspm)
        .filter(|e| !e.1)
        .map(|(ts, _)| t.samples().find(|(s, _)| *s == ts).unwrap().1.axes[0])
        .collect();
    assert_eq!(rets[0], 47 * MM);
    assert_eq!(*rets.last().unwrap(), 50 * MM);
}

#[test]
fn gsk_rt_deep_peck_returns_to_the_start_point_after_each_cut() {
    // GSK-RT-09: `G88 X-50 P3000 Q20000 J1 F2`.
    let t = run_default("gsk-lathe", &prog("G88 X-50 P3000 Q20000 J1 F2;"));
    assert_eq!(count_phase(&t, Phase::Cutting), 25);
    let rets: Vec<i64> = t
        .edges(Signal::Rgspm)
        .filter(|e| !e.1)
        .map(|(ts, _)| t.samples().find(|(s, _)| *s == ts).unwrap().1.axes[0])
        .collect();
    assert_eq!(rets.len(), 25);
    assert!(rets.iter().all(|&x| x == 50 * MM), "{rets:?}");
}

#[test]
fn com_plc_m29_handshake_signal_order() {
    // COM-PLC-02: M29 → MF, F76.3 → SPPOS → SPPOSA → RGTAP, FIN → MF falls.
    let t = run_default("gsk-lathe", &prog("G88 X-50 F2;"));
    let handshake = ["MF", "F76.3", "SPPOS", "SPPOSA", "RGTAP", "FIN", "RGSPP"];
    let order: Vec<(u64, &str, bool)> = t
        .events
        .iter()
        .filter_map(|e| match e.event {
            nc_engine::Event::Signal { signal, value } => Some((e.t_us, signal.name(), value)),
            _ => None,
        })
        .filter(|(_, n, _)| handshake.contains(n))
        .take(8)
        .collect();
    let names: Vec<_> = order.iter().map(|(_, n, v)| format!("{n}={}", *v as u8)).collect();
    assert_eq!(names, ["MF=1", "F76.3=1", "SPPOS=1", "SPPOSA=1", "RGTAP=1", "FIN=1", "MF=0", "RGSPP=1"]);
    // Default delays: request 8 ms, drive 50 ms, RGTAP 8 ms.
    assert_eq!(order[2].0 - order[0].0, 8_000);
    assert_eq!(order[3].0 - order[2].0, 50_000);
    assert_eq!(order[4].0 - order[3].0, 8_000);
}

#[rstest]
#[case::rtcrg_0_waits_for_rgtap(0.0, true)]
#[case::rtcrg_1_goes_on(1.0, false)]
fn gsk_rt_cancel_waits_for_rgtap_per_rtcrg(#[case] rtcrg: f64, #[case] waits: bool) {
    // GSK-RT-22: after G80 the next block starts after RGTAP falls only when RTCRG = 0.
    let t = run("gsk-lathe", &[("186.2", None, rtcrg)], &prog("G88 X-50 F2;"), &RunOptions::default());
    let rtap_fall = t.edges(Signal::Rtap).find(|e| !e.1).unwrap().0;
    let rgtap_fall = t.edges(Signal::Rgtap).find(|e| !e.1).unwrap().0;
    assert_eq!(rgtap_fall - rtap_fall, 16_000);
    let m30 = t.functions().find(|f| f.2 == 30).unwrap().0;
    assert_eq!(m30 >= rgtap_fall, waits, "M30 at {m30}, RGTAP fell at {rgtap_fall}");
}

#[test]
fn gsk_rt_left_hand_tap_cuts_with_the_spindle_reversed() {
    // GSK-RT-06: F<0 → left-hand, RGSPM while cutting.
    let t = run_default("gsk-lathe", &prog("G84 Z-20 F-1.5;"));
    let first = t.events.iter().find_map(|e| match e.event {
        nc_engine::Event::Signal { signal: s @ (Signal::Rgspp | Signal::Rgspm), value: true } => Some(s),
        _ => None,
    });
    assert_eq!(first, Some(Signal::Rgspm));
    let min_z = t.samples().map(|(_, s)| s.axes[2]).min().unwrap();
    assert_eq!(min_z, -20 * MM);
}

#[test]
fn gsk_rt_clamp_codes_frame_the_tapping() {
    // GSK-RT-11: with parameter 170 = 68, M68 after positioning, M69 at the end.
    let t =
        run("gsk-lathe", &[("170", None, 68.0)], &prog("G84 X20 C90 Z-10 F1 M68;"), &RunOptions::default());
    assert_eq!(t.end().unwrap().reason, EndReason::ProgramEnd, "{}", support::events(&t));
    let ms: Vec<u32> = t.functions().filter(|f| f.1 == 'M').map(|f| f.2).collect();
    assert_eq!(ms, [29, 68, 69, 30]);
    let m68 = t.functions().find(|f| f.2 == 68).unwrap().0;
    let first_cut = t.edges(Signal::Rgspp).next().unwrap().0;
    assert!(m68 < first_cut);
}

#[rstest]
#[case::m29_repeated("M29 S500;", "NC-1010")]
#[case::axis_move_after_m29("G0 X40;", "NC-1011")]
fn gsk_rt_m29_misuse_alarms(#[case] middle: &str, #[case] code: &str) {
    // GSK-RT-12, GSK-RT-13.
    let text = format!("{HEAD}{middle}\nG84 Z-10 F1;\nM30;\n");
    let t = run_default("gsk-lathe", &text);
    let alarms: Vec<_> = t.alarms().map(|(_, a)| a.kind.code()).collect();
    assert_eq!(alarms, [code]);
    assert_eq!(t.end().unwrap().reason, EndReason::Alarm);
    assert_eq!(t.alarms().next().unwrap().1.line, Some(4));
}

#[rstest]
#[case::no_m29("G98;\nG0 X50 Z0;\nG84 Z-10 F1;\n", "NC-1015")]
#[case::m29_with_clamp_code("G98;\nG0 X50 Z0;\nG84 Z-10 F1 M68 M29 S500;\n", "NC-1014")]
#[case::clamp_code_not_configured("G98;\nG0 X50 Z0;\nM29 S500;\nG84 Z-10 F1 M68;\n", "NC-1012")]
#[case::no_bottom("G98;\nG0 X50 Z0;\nM29 S500;\nG84 F1;\n", "NC-1002")]
#[case::no_lead("G98;\nG0 X50 Z0;\nM29 S500;\nG84 Z-10;\n", "NC-1002")]
#[case::switch_without_bottom("G98;\nG0 X50 Z0;\nM29 S500;\nG84 Z-10 F1;\nG88 Z-5;\n", "NC-1013")]
#[case::m29_without_s("G98;\nG0 X50 Z0;\nM29;\n", "NC-1002")]
#[case::axis_word_in_the_m29_block("G98;\nG0 X50 Z0;\nZ5 M29 S500;\nG84 Z-10 F1;\n", "NC-1011")]
fn gsk_rt_bad_programs_alarm(#[case] text: &str, #[case] code: &str) {
    let t = run_default("gsk-lathe", text);
    let alarms: Vec<_> = t.alarms().map(|(_, a)| a.kind.code()).collect();
    assert_eq!(alarms, [code], "{}", support::events(&t));
}

#[rstest]
#[case::p_max("P99999999", true)]
#[case::p_negative("P-1", false)]
#[case::p_too_big("P100000000", false)]
#[case::r_max("Q10000 R999.9999", true)]
#[case::r_too_big("Q10000 R1000", false)]
#[case::q_max("Q99999999", true)]
#[case::q_too_big("Q100000000", false)]
#[case::d_max("D150", true)]
#[case::d_too_big("D151", false)]
#[case::d_negative("D-1", false)]
#[case::k_min("K1", true)]
#[case::k_zero("K0", false)]
#[case::k_max("K9999", true)]
#[case::k_too_big("K10000", false)]
#[case::j_one("Q10000 J1", true)]
#[case::j_two("J2", false)]
fn gsk_rt_word_ranges_at_both_edges(#[case] words: &str, #[case] ok: bool) {
    // GSK-RT-03..10: the last valid value runs, the first invalid one raises NC-1001 with no motion.
    let text = format!("{HEAD}G84 Z-1 F1 {words};\n");
    let opts = RunOptions { sample_us: 0, ..RunOptions::default() };
    let t = run("gsk-lathe", &[], &text, &opts);
    let alarms: Vec<_> = t.alarms().map(|(_, a)| a.kind.code()).collect();
    if ok {
        assert!(alarms.is_empty(), "{words}: {alarms:?}");
    } else {
        assert_eq!(alarms, ["NC-1001"], "{words}");
        assert_eq!(t.edges(Signal::Rgspp).count(), 0, "no tapping motion after a range alarm");
    }
}

#[rstest]
#[case::f_max("F500", true)]
#[case::f_too_big("F500.0001", false)]
#[case::f_zero("F0", false)]
#[case::f_min("F0.0001", true)]
#[case::i_min("I0.06", true)]
#[case::i_too_small("I0.05", false)]
fn gsk_rt_lead_ranges(#[case] words: &str, #[case] ok: bool) {
    let text = format!("{HEAD}G84 Z-0.001 {words};\n");
    let opts = RunOptions { sample_us: 0, ..RunOptions::default() };
    let t = run("gsk-lathe", &[], &text, &opts);
    let alarms: Vec<_> = t.alarms().map(|(_, a)| a.kind.code()).collect();
    assert_eq!(alarms.is_empty(), ok, "{words}: {alarms:?}");
}

#[rstest]
fn com_time_every_interpolation_period_works(#[values(1000, 2000, 4000, 8000)] period: u64) {
    // COM-TIME-02: motions last whole periods; the seed peck program completes at each period.
    let t = run(
        "gsk-lathe",
        &[("nc.period_us", None, period as f64)],
        &prog("G88 X-50 P3000 Q20000 R0.5 F2;"),
        &RunOptions::default(),
    );
    let end = t.end().unwrap();
    assert_eq!(end.reason, EndReason::ProgramEnd);
    assert_eq!(end.state.axes[0], 50 * MM);
    for (ts, _) in t.phases() {
        assert_eq!(ts % period, 0, "phase change at {ts} not on a {period} µs tick");
    }
    assert_eq!(count_phase(&t, Phase::Cutting), 25);
}

#[test]
fn gsk_rt_group01_modal_is_restored_after_the_cycle() {
    // GSK-RT-20: G01 before the cycle is modal again after G80.
    let text = "G98 G1 F100;\nG0 X50 Z0;\nG1 Z0;\nM29 S1000;\nG84 Z-5 F1;\nG80;\nX40;\nM30;\n";
    let t = run_default("gsk-lathe", text);
    let end = t.end().unwrap();
    assert_eq!(end.reason, EndReason::ProgramEnd, "{}", support::events(&t));
    assert_eq!(end.modal[0], "G01");
}

#[test]
fn gsk_rt_k_repeats_with_incremental_position_tap_new_holes() {
    // GSK-RT-10: K3 with H30 taps at C30, C60, C90.
    let t = run_default("gsk-lathe", &prog("G84 H30 Z-5 F1 K3;"));
    assert_eq!(count_phase(&t, Phase::Cutting), 3);
    assert_eq!(t.end().unwrap().state.axes[5], 90_000_000);
}

#[test]
fn gsk_rt_overload_retracts_to_the_start_and_never_goes_deeper() {
    // GSK-RT-26: D80, current 100% from 1.0 s; parameter 270 = 100 ms.
    let inputs = InputSchedule::default()
        .at(1_000_000, Input::MotorCurrent { source: CurrentSource::FeedAxis, percent: 100 });
    let opts = RunOptions { inputs, ..RunOptions::default() };
    let t = run("gsk-lathe", &[], &prog("G84 Z-40 F1 D80;"), &opts);
    let alarms: Vec<_> = t.alarms().map(|(_, a)| a.kind.code()).collect();
    assert_eq!(alarms, ["NC-1031"], "{}", support::events(&t));
    let retract = t.phases().find(|p| p.1 == Phase::OverloadRetract).unwrap().0;
    let z_at = |ts: u64| t.samples().find(|(s, _)| *s >= ts).unwrap().1.axes[2];
    // Tripped 100 ms after the current rose; the stop takes at most the stroke's own ramp.
    let z_trip = z_at(1_100_000);
    let z_retract = z_at(retract);
    assert!(z_retract < z_trip && z_trip - z_retract < MM, "stopped within 1 mm: {z_trip} → {z_retract}");
    let deepest_after = t.samples().filter(|(ts, _)| *ts >= retract).map(|(_, s)| s.axes[2]).min().unwrap();
    assert_eq!(deepest_after, z_retract, "never deeper once the retract began");
    assert_eq!(t.end().unwrap().state.axes[2], 0, "back at the start point Z0");
}

#[test]
fn gsk_rt_overload_shorter_than_the_delay_does_not_retract() {
    let inputs = InputSchedule::default()
        .at(1_000_000, Input::MotorCurrent { source: CurrentSource::FeedAxis, percent: 100 })
        .at(1_050_000, Input::MotorCurrent { source: CurrentSource::FeedAxis, percent: 50 });
    let opts = RunOptions { inputs, ..RunOptions::default() };
    let t = run("gsk-lathe", &[], &prog("G84 Z-40 F1 D80;"), &opts);
    assert_eq!(t.alarms().count(), 0);
    assert_eq!(t.samples().map(|(_, s)| s.axes[2]).min().unwrap(), -40 * MM);
}

#[test]
fn gsk_rt_machine_lock_moves_neither_axis_nor_spindle() {
    // GSK-RT-24: command coordinates advance, machine positions and spindle angle don't.
    let inputs = InputSchedule::default().at(0, Input::MachineLock(true));
    let opts = RunOptions { inputs, ..RunOptions::default() };
    let t = run("gsk-lathe", &[], &prog("G84 Z-10 F1;"), &opts);
    assert!(t.samples().all(|(_, s)| s.axes[2] == 0 && s.spindle_mrpm == 0 && s.axes[0] == 0));
    assert!(t.edges(Signal::Rgspp).count() >= 2, "RGSPP still reported under machine lock");
    assert_eq!(t.end().unwrap().command[0], 50 * MM);
}

#[test]
fn gsk_rt_dry_run_does_not_change_the_tap_feed() {
    // GSK-RT-23.
    let plain = run_default("gsk-lathe", &prog("G84 Z-10 F1;"));
    let opts =
        RunOptions { inputs: InputSchedule::default().at(0, Input::DryRun(true)), ..RunOptions::default() };
    let dry = run("gsk-lathe", &[], &prog("G84 Z-10 F1;"), &opts);
    let cut = |t: &nc_engine::Trace| {
        let e: Vec<_> = t.edges(Signal::Rgspp).collect();
        e[1].0 - e[0].0
    };
    assert_eq!(cut(&plain), cut(&dry));
}

#[test]
fn gsk_rt_reset_while_cutting_restores_the_spindle_and_drops_the_signals() {
    // GSK-RT-25: spindle turning at 300 rpm before M29; reset at 1.5 s while cutting.
    let text = "G98;\nG0 X50 Z0;\nS300 M3;\nM29 S1000;\nG84 Z-40 F1;\nG80;\nM30;\n";
    let opts =
        RunOptions { inputs: InputSchedule::default().at(1_500_000, Input::Reset), ..RunOptions::default() };
    let t = run("gsk-lathe", &[], text, &opts);
    let end = t.end().unwrap();
    assert_eq!(end.reason, EndReason::Reset, "{}", support::events(&t));
    assert!(!end.signals.get(Signal::Rtap) && !end.signals.get(Signal::Rgtap));
    assert_eq!(end.state.spindle_mrpm, 300_000, "spindle back at its pre-M29 300 rpm forward");
}

#[test]
fn com_time_same_input_same_trace() {
    let a = run_default("gsk-lathe", &prog("G88 X-50 P3000 Q20000 R0.5 F2;"));
    let b = run_default("gsk-lathe", &prog("G88 X-50 P3000 Q20000 R0.5 F2;"));
    assert_eq!(a, b);
}

fn manual(inputs: InputSchedule) -> RunOptions {
    RunOptions { inputs, auto_cycle_start: false, ..RunOptions::default() }
}

#[test]
fn gsk_rt_feed_hold_while_tapping_waits_for_the_end_of_the_retract() {
    // GSK-RT-27: feed hold at 1.0 s (cutting) takes effect only when the return is complete.
    let inputs = InputSchedule::default().at(1_000_000, Input::FeedHold).at(20_000_000, Input::CycleStart);
    let t = run("gsk-lathe", &[], &prog("G84 Z-20 F1;"), &manual(inputs));
    assert_eq!(t.end().unwrap().reason, EndReason::ProgramEnd, "{}", support::events(&t));
    let spl = t.edges(Signal::Spl).find(|e| e.1).unwrap().0;
    let last_retract_end = t.edges(Signal::Rgspm).filter(|e| !e.1).last().unwrap().0;
    assert!(spl >= last_retract_end, "hold at {spl}, retract ended at {last_retract_end}");
    let min_z = t.samples().map(|(_, s)| s.axes[2]).min().unwrap();
    assert_eq!(min_z, -20 * MM, "the tap went to the bottom in one stroke");
}

#[test]
fn com_inp_feed_hold_on_a_feed_move_decelerates_and_resumes_to_the_same_end() {
    // COM-INP-02: G01 hold mid-move, cycle start, the move finishes at its programmed end.
    let text = "G98 G0 X0 Z0;\nG1 Z-100 F600;\nM30;\n";
    let inputs = InputSchedule::default().at(3_000_000, Input::FeedHold).at(5_000_000, Input::CycleStart);
    let t = run("gsk-lathe", &[], text, &manual(inputs));
    assert_eq!(t.end().unwrap().reason, EndReason::ProgramEnd, "{}", support::events(&t));
    assert_eq!(t.end().unwrap().state.axes[2], -100 * MM);
    let z = |ts: u64| t.samples().find(|(s, _)| *s == ts).unwrap().1.axes[2];
    assert_eq!(z(3_500_000), z(4_900_000), "standing still while held");
    assert!(z(3_500_000) < -29 * MM && z(3_500_000) > -32 * MM, "{}", z(3_500_000));
}

#[test]
fn com_inp_single_block_stops_after_each_block() {
    // COM-INP-03: three blocks, single block on: three stops, each released by cycle start.
    let text = "G98 G0 X10 Z0;\nG0 Z-5;\nG0 X20;\n";
    let mut inputs = InputSchedule::default().at(0, Input::SingleBlock(true));
    for k in 1..=3 {
        inputs = inputs.at(k * 2_000_000, Input::CycleStart);
    }
    let t = run("gsk-lathe", &[], text, &manual(inputs));
    assert_eq!(t.end().unwrap().reason, EndReason::ProgramEnd);
    assert_eq!(t.edges(Signal::Spl).filter(|e| e.1).count(), 3);
    let blocks: Vec<u64> = t
        .events
        .iter()
        .filter(|e| matches!(e.event, nc_engine::Event::Block { .. }))
        .map(|e| e.t_us)
        .collect();
    assert_eq!(&blocks[1..], &[2_000_000, 4_000_000]);
}
