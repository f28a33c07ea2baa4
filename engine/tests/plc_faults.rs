//! PLC and drive faults: answers that are late or never come, a stalled spindle, backlash and
//! orientation timing (COM-PLC-*, COM-INP-*, GSK-RT-19, GSK-RT-28).

mod support;

use nc_engine::input::{Input, InputSchedule, PlcAnswer};
use nc_engine::trace::{EndReason, Phase, Signal};
use nc_engine::RunOptions;
use support::run;

const MM: i64 = 1_000_000;
const TAP: &str = "G98;\nG0 X50 Z0;\nM29 S1000;\nG84 Z-10 F1;\nG80;\nM30;\n";

fn with(inputs: InputSchedule) -> RunOptions {
    RunOptions { inputs, ..RunOptions::default() }
}

fn alarm_codes(t: &nc_engine::Trace) -> Vec<&'static str> {
    t.alarms().map(|(_, a)| a.kind.code()).collect()
}

#[test]
fn com_plc_position_mode_never_reached_raises_5002_after_the_timer() {
    let inputs = InputSchedule::default()
        .at(0, Input::PlcAnswer { answer: PlcAnswer::PositionModeReached, extra_us: None });
    let t = run("gsk-lathe", &[("plc.m29_timeout_ms", None, 1500.0)], TAP, &with(inputs));
    assert_eq!(alarm_codes(&t), ["5002"]);
    let sppos = t.edges(Signal::Sppos).next().unwrap().0;
    let (at, _) = t.alarms().next().unwrap();
    assert_eq!(at - sppos, 1_500_000);
    assert_eq!(t.edges(Signal::Rgtap).count(), 0);
}

#[test]
fn com_plc_a_late_answer_only_delays_the_cycle() {
    let inputs = InputSchedule::default()
        .at(0, Input::PlcAnswer { answer: PlcAnswer::PositionModeReached, extra_us: Some(400_000) });
    let late = run("gsk-lathe", &[], TAP, &with(inputs));
    let plain = run("gsk-lathe", &[], TAP, &RunOptions::default());
    assert!(alarm_codes(&late).is_empty());
    let first_cut = |t: &nc_engine::Trace| t.edges(Signal::Rgspp).next().unwrap().0;
    assert_eq!(first_cut(&late) - first_cut(&plain), 400_000);
}

#[test]
fn com_plc_fin_never_comes_raises_the_fin_timer_alarm() {
    let inputs = InputSchedule::default().at(0, Input::PlcAnswer { answer: PlcAnswer::Fin, extra_us: None });
    let t = run("gsk-lathe", &[], "S500 M3;\nM30;\n", &with(inputs));
    assert_eq!(alarm_codes(&t), ["NC-1020"]);
    assert_eq!(t.alarms().next().unwrap().0, 10_000_000);
}

#[test]
fn com_plc_rgtap_never_comes_leaves_m29_waiting_until_the_fin_timer() {
    let inputs =
        InputSchedule::default().at(0, Input::PlcAnswer { answer: PlcAnswer::Rgtap, extra_us: None });
    let t = run("gsk-lathe", &[("plc.fin_timeout_ms", None, 3000.0)], TAP, &with(inputs));
    // FIN and RGTAP come from the same rung: without RGTAP the ladder... still gives FIN, so the
    // cycle finds RGTAP off when it starts.
    assert_eq!(alarm_codes(&t), ["NC-1015"]);
}

#[test]
fn com_inp_spindle_stalled_before_the_stroke_trips_the_excess_error() {
    // Stalled from the start at 1000 rpm: the axis runs 1 mm ahead within the 100 ms PLC timer.
    let inputs = InputSchedule::default().at(0, Input::SpindleStall(true));
    let t = run("gsk-lathe", &[], TAP, &with(inputs));
    assert_eq!(alarm_codes(&t), ["0411"]);
    let cut = t.edges(Signal::Rgspp).next().unwrap().0;
    assert!(t.alarms().next().unwrap().0 - cut < 100_000);
}

#[test]
fn com_inp_emergency_stop_stops_at_once_with_its_alarm() {
    let inputs = InputSchedule::default().at(600_000, Input::EmergencyStop(true));
    let t = run("gsk-lathe", &[], TAP, &with(inputs));
    assert_eq!(alarm_codes(&t), ["NC-1030"]);
    assert_eq!(t.end().unwrap().reason, EndReason::Alarm);
    assert_eq!(t.alarms().next().unwrap().0, 600_000);
}

#[test]
fn gsk_rt_backlash_is_taken_up_on_each_reversal() {
    // GSK-RT-28: 0.05 mm backlash on Z: the return stroke turns the spindle 0.05 revolutions more
    // (lead 1 mm) and takes longer; the table positions are unchanged.
    let plain = run("gsk-lathe", &[], TAP, &RunOptions::default());
    let b = run("gsk-lathe", &[("34", Some('Z'), 0.05)], TAP, &RunOptions::default());
    let ret = |t: &nc_engine::Trace| {
        let e: Vec<_> = t.edges(Signal::Rgspm).collect();
        e[1].0 - e[0].0
    };
    assert!(ret(&b) > ret(&plain), "{} vs {}", ret(&b), ret(&plain));
    assert_eq!(b.end().unwrap().state.axes[2], 0);
    assert_eq!(b.samples().map(|(_, s)| s.axes[2]).min().unwrap(), -10 * MM);
    let turned = |t: &nc_engine::Trace| t.end().unwrap().state.spindle_mdeg;
    // The return stroke turns in reverse: 0.05 rev = 18° further back.
    assert_eq!((turned(&plain) - turned(&b)).rem_euclid(360_000), 18_000);
}

#[test]
fn gsk_rt_rtori_orients_the_spindle_before_the_first_hole() {
    // GSK-RT-19: with 186#7 the first cut starts after the orientation time (500 ms).
    let plain = run("gsk-lathe", &[], TAP, &RunOptions::default());
    let o = run("gsk-lathe", &[("186.7", None, 1.0)], TAP, &RunOptions::default());
    let first = |t: &nc_engine::Trace| t.edges(Signal::Rgspp).next().unwrap().0;
    assert_eq!(first(&o) - first(&plain), 500_000);
    let cut = o.phases().find(|p| p.1 == Phase::Cutting).unwrap().0;
    let s = o.samples().find(|(ts, _)| *ts == cut).unwrap().1;
    assert_eq!(s.spindle_mdeg, 0, "at the reference angle");
}

#[test]
fn com_plc_zero_speed_rises_when_the_spindle_has_stopped_unless_withheld() {
    // 1000 rpm, ramp 1000 ms per 6000 rpm: stopping takes 166.7 ms after M05, ZSP 8 ms later.
    let text = "S1000 M3;\nG4 P2000;\nM5;\nG4 P1000;\nM30;\n";
    let t = run("gsk-lathe", &[], text, &RunOptions::default());
    let m5 = t.functions().find(|f| f.2 == 5).unwrap().0;
    let rise = t.edges(Signal::Zsp).filter(|e| e.1).nth(1).unwrap().0;
    assert_eq!(rise - m5, 166_667 + 8_000);
    let inputs =
        InputSchedule::default().at(0, Input::PlcAnswer { answer: PlcAnswer::ZeroSpeed, extra_us: None });
    let t = run("gsk-lathe", &[], text, &with(inputs));
    assert_eq!(t.edges(Signal::Zsp).filter(|e| e.1).count(), 1, "only the power-on state");
}

#[test]
fn com_time_a_sample_shows_the_state_before_the_events_at_its_time() {
    let t = run("gsk-lathe", &[], TAP, &RunOptions::default());
    let mut last_t = None;
    for e in &t.events {
        if last_t != Some(e.t_us) && e.t_us % 1000 == 0 && !matches!(e.event, nc_engine::Event::End(_)) {
            assert!(
                matches!(e.event, nc_engine::Event::Sample(_)),
                "first event at {} is {:?}",
                e.t_us,
                e.event
            );
        }
        last_t = Some(e.t_us);
    }
}

#[test]
fn com_inp_a_stall_during_a_stroke_freezes_the_spindle_and_trips_the_excess_error() {
    // Stall at 0.6 s, mid-cut (1000 rpm × 1 mm = 16.7 mm/s): the axis runs 1 mm ahead in 60 ms.
    let inputs = InputSchedule::default().at(600_000, Input::SpindleStall(true));
    let t = run("gsk-lathe", &[], TAP, &with(inputs));
    assert_eq!(alarm_codes(&t), ["0411"], "{}", support::events(&t));
    let (at, _) = t.alarms().next().unwrap();
    assert!((655_000..=670_000).contains(&at), "{at}");
    let frozen: Vec<i64> = t.samples().filter(|(ts, _)| *ts > 600_000).map(|(_, s)| s.spindle_mdeg).collect();
    assert!(frozen.windows(2).all(|w| w[0] == w[1]), "the stalled spindle's angle does not move");
    assert!(t.samples().filter(|(ts, _)| *ts > 600_000).all(|(_, s)| s.spindle_mrpm == 0));
}

#[test]
fn com_inp_a_slow_stall_is_caught_by_the_ladder_timer_first() {
    // At 100 rpm the axis needs 600 ms to run 1 mm ahead: the 100 ms PLC timer (5074) comes first.
    let slow = "G98;\nG0 X50 Z0;\nM29 S100;\nG84 Z-10 F1;\nG80;\nM30;\n";
    let inputs = InputSchedule::default().at(2_000_000, Input::SpindleStall(true));
    let t = run("gsk-lathe", &[], slow, &with(inputs));
    assert_eq!(alarm_codes(&t), ["5074"]);
    assert_eq!(t.alarms().next().unwrap().0, 2_100_000);
}

#[test]
fn gsk_rt_a_clamp_code_in_a_continuation_block_is_output_once_after_positioning() {
    let text = "G98;\nG0 X50 Z0;\nM29 S1000;\nG84 Z-5 F1;\nC90 M68;\nG80;\nM30;\n";
    let t = run("gsk-lathe", &[("170", None, 68.0)], text, &RunOptions::default());
    let ms: Vec<u32> = t.functions().filter(|f| f.1 == 'M').map(|f| f.2).collect();
    assert_eq!(ms, [29, 68, 69, 30]);
}
