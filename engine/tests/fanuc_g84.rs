//! Fanuc/Haas milling G84 end to end through the executor (seed 003; rules FAN-CYC-*, FAN-RT-*).

mod support;

use nc_engine::trace::{EndReason, Phase, Signal};
use nc_engine::{Event, RunOptions, Trace};
use rstest::rstest;
use support::{run, run_default};

const MM: i64 = 1_000_000;
const SEED_1: &str = "N150 M6 T2\nN160 G90 G00 X60 Y28 Z12 S100 M03\nN170 G99 G84 X60 Y28 Z-17 P300 R2 F120\nN180 G98 Y12\nN190 G91 G80 G28 X0 Y0 Z0 M05\nN200 M30\n";

fn z_at(t: &Trace, ts: u64) -> i64 {
    t.samples().find(|(s, _)| *s >= ts).unwrap().1.axes[2]
}

/// Times at which each block starts, by line.
fn block_time(t: &Trace, line: u32) -> u64 {
    t.events.iter().find(|e| matches!(e.event, Event::Block { line: l, .. } if l == line)).unwrap().t_us
}

#[test]
fn fan_cyc_seed_program_taps_two_holes_g99_then_g98() {
    let t = run_default("fanuc-mill", SEED_1);
    let end = t.end().unwrap();
    assert_eq!(end.reason, EndReason::ProgramEnd, "{}", support::events(&t));
    // Spindle reversal at each bottom, forward again at R: M05 M04 M05 M03 per hole.
    let ms: Vec<u32> = t.functions().filter(|f| f.1 == 'M').map(|f| f.2).collect();
    assert_eq!(ms, [6, 3, 5, 4, 5, 3, 5, 4, 5, 3, 5, 30]);
    // Both holes reach Z-17; hole 1 (G99) ends at R2, hole 2 (G98) at the initial level Z12.
    let deepest: Vec<i64> = t.samples().map(|(_, s)| s.axes[2]).filter(|&z| z == -17 * MM).take(1).collect();
    assert_eq!(deepest, [-17 * MM]);
    assert_eq!(z_at(&t, block_time(&t, 4)), 2 * MM, "G99: back at R");
    assert_eq!(z_at(&t, block_time(&t, 5)), 12 * MM, "G98: back at the initial level");
    let at_y12 = t.samples().filter(|(_, s)| s.axes[1] == 12 * MM).map(|(_, s)| s.axes[2]).min().unwrap();
    assert_eq!(at_y12, -17 * MM, "second hole at Y12 tapped to Z-17");
    assert_eq!(end.state.axes[..3], [0, 0, 0], "G28 back to the reference point");
}

#[test]
fn fan_cyc_dwell_p_at_the_bottom_before_the_reversal() {
    let t = run_default("fanuc-mill", SEED_1);
    let dwell = t.phases().find(|p| p.1 == Phase::Dwell).unwrap().0;
    let m05 = t.functions().find(|f| f.2 == 5).unwrap().0;
    assert_eq!(m05 - dwell, 300_000);
    assert_eq!(z_at(&t, dwell), -17 * MM);
}

#[test]
fn fan_cyc_conventional_tap_feeds_at_f() {
    // 19 mm from R2 to Z-17 at F120 mm/min ≈ 9.5 s (plus the ramps).
    let t = run_default("fanuc-mill", SEED_1);
    let cut: Vec<_> = t.phases().filter(|p| p.1 == Phase::Cutting).map(|p| p.0).collect();
    let dwell = t.phases().find(|p| p.1 == Phase::Dwell).unwrap().0;
    let d = dwell - cut[0];
    assert!((9_500_000..9_600_000).contains(&d), "{d}");
}

#[rstest]
#[case::pcp_1_back_to_r(1.0, 9, 5 * MM)]
#[case::pcp_0_high_speed(0.0, 9, i64::MIN)]
fn fan_rt_seed_peck_example(#[case] pcp: f64, #[case] cuts: usize, #[case] retract_to: i64) {
    // G84 Z-40 R5 Q5 F100 after M29 S100: 5 mm per cut; PCP=1 returns to R between cuts.
    let text = "G90 G00 X30 Y50\nG43 Z50 H01\nM29 S100\nG84 Z-40 R5 Q5 F100\nG80\nM30\n";
    let t = run("fanuc-mill", &[("5200.5", None, pcp)], text, &RunOptions::default());
    assert_eq!(t.end().unwrap().reason, EndReason::ProgramEnd, "{}", support::events(&t));
    assert_eq!(t.phases().filter(|p| p.1 == Phase::Cutting).count(), cuts);
    let ends_of_returns: Vec<i64> =
        t.edges(Signal::Rgspm).filter(|e| !e.1).map(|(ts, _)| z_at(&t, ts)).collect();
    assert_eq!(*ends_of_returns.last().unwrap(), 5 * MM, "final return to R");
    if retract_to != i64::MIN {
        assert!(ends_of_returns.iter().all(|&z| z == retract_to), "{ends_of_returns:?}");
    } else {
        // High-speed: each retract is 1 mm (5213) above the depth reached.
        // R5 - Q5 = 0 reached, then 1 mm back up.
        assert_eq!(ends_of_returns[0], MM);
    }
    assert_eq!(t.samples().map(|(_, s)| s.axes[2]).min().unwrap(), -40 * MM);
    assert_eq!(t.end().unwrap().state.axes[2], 50 * MM, "G98 default: initial level");
}

#[test]
fn fan_rt_lead_is_f_over_s_and_stays_synchronised() {
    // F100 mm/min at S100 → 1 mm per revolution; 45 mm from R5 to Z-40 = 45 revolutions.
    let text = "G90 G00 X0 Y0 Z50\nM29 S100\nG84 Z-40 R5 F100\nG80\nM30\n";
    let t = run_default("fanuc-mill", text);
    let e: Vec<_> = t.edges(Signal::Rgspp).collect();
    let (a, b) = (e[0].0, e[1].0);
    let mut turned = 0i64;
    let mut last = t.samples().find(|(s, _)| *s == a).unwrap().1.spindle_mdeg;
    for (_, s) in t.samples().filter(|(s, _)| *s > a && *s <= b) {
        turned += (s.spindle_mdeg - last).rem_euclid(360_000);
        last = s.spindle_mdeg;
    }
    assert_eq!(turned, 45 * 360_000);
}

#[rstest]
#[case::s_missing("G90 G0 Z50\nM29\n", "0200")]
#[case::s_too_high("G90 G0 Z50\nM29 S5000\nG84 Z-5 R2 F100\n", "0200")]
#[case::f_missing("G90 G0 Z50\nM29 S100\nG84 Z-5 R2\n", "0201")]
#[case::m29_twice("G90 G0 Z50\nM29 S100\nM29 S100\n", "0203")]
#[case::axis_after_m29("G90 G0 Z50\nM29 S100\nX10\nG84 Z-5 R2 F100\n", "0204")]
#[case::plane_change("G90 G0 Z50\nM29 S100\nG84 Z-5 R2 F100\nG18\n", "0206")]
#[case::feed_zero("G90 G0 Z50\nG1 X10 F0\n", "0011")]
#[case::improper_g("G90 G0 Z50\nG7 X1\n", "0010")]
#[case::g_number_beyond_i64_tenths("G90 G0 Z50\nG998888888888888888\n", "0010")] // found by fuzzing
fn fan_rt_documented_alarms(#[case] text: &str, #[case] code: &str) {
    let t = run_default("fanuc-mill", text);
    let codes: Vec<_> = t.alarms().map(|(_, a)| a.kind.code()).collect();
    assert_eq!(codes, [code], "{}", support::events(&t));
    assert!(t.alarms().next().unwrap().1.line.is_some());
}

#[test]
fn fan_rt_rgtap_off_raises_0205() {
    let inputs = nc_engine::InputSchedule::default()
        .at(0, nc_engine::Input::PlcAnswer { answer: nc_engine::input::PlcAnswer::Rgtap, extra_us: None });
    let opts = RunOptions { inputs, ..RunOptions::default() };
    let t = run("fanuc-mill", &[], "G90 G0 Z50\nM29 S100\nG84 Z-5 R2 F100\n", &opts);
    let codes: Vec<_> = t.alarms().map(|(_, a)| a.kind.code()).collect();
    assert_eq!(codes, ["0205"]);
}

#[test]
fn fan_cyc_k_repeats_in_g91_make_a_row_of_holes() {
    let text = "G90 G0 X0 Y0 Z10 S500 M3\nG91 G99 G84 X10 Z-15 R-8 F500 K3\nG80\nM30\n";
    let t = run_default("fanuc-mill", text);
    assert_eq!(t.end().unwrap().reason, EndReason::ProgramEnd, "{}", support::events(&t));
    assert_eq!(t.phases().filter(|p| p.1 == Phase::Cutting).count(), 3);
    assert_eq!(t.end().unwrap().state.axes[0], 30 * MM);
    assert_eq!(t.samples().map(|(_, s)| s.axes[2]).min().unwrap(), -13 * MM, "R at 2, bottom 15 below R");
}

#[test]
fn fan_rt_feed_hold_waits_until_the_return_is_complete() {
    // Seed 003: "Feed hold does not stop the machine until the return is complete."
    let inputs = nc_engine::InputSchedule::default()
        .at(1_500_000, nc_engine::Input::FeedHold)
        .at(60_000_000, nc_engine::Input::CycleStart);
    let opts = RunOptions { inputs, auto_cycle_start: false, ..RunOptions::default() };
    let t = run("fanuc-mill", &[], "G90 G0 X0 Y0 Z50\nM29 S100\nG84 Z-40 R5 F100\nG80\nM30\n", &opts);
    let spl = t.edges(Signal::Spl).find(|e| e.1).unwrap().0;
    let back = t.edges(Signal::Rgspm).filter(|e| !e.1).last().unwrap().0;
    assert!(spl >= back, "held at {spl}, return ended at {back}");
    assert_eq!(t.end().unwrap().reason, EndReason::ProgramEnd);
}

#[test]
fn fan_rt_conventional_tapping_ignores_feed_override_and_dry_run() {
    let text = "G90 G0 X0 Y0 Z10 S500 M3\nG84 Z-10 R2 F500\nG80\nM30\n";
    let plain = run_default("fanuc-mill", text);
    let inputs = nc_engine::InputSchedule::default()
        .at(0, nc_engine::Input::FeedOverride(50))
        .at(0, nc_engine::Input::DryRun(true));
    let t = run("fanuc-mill", &[], text, &RunOptions { inputs, ..RunOptions::default() });
    let cut = |t: &Trace| {
        let c = t.phases().find(|p| p.1 == Phase::Cutting).unwrap().0;
        let r = t.phases().find(|p| p.1 == Phase::Retract).unwrap().0;
        r - c
    };
    assert_eq!(cut(&t), cut(&plain));
}

#[test]
fn fan_lex_tool_change_takes_the_tool_change_time() {
    let t = run("fanuc-mill", &[("nc.tool_change_ms", None, 3000.0)], "T2 M6\nM30\n", &RunOptions::default());
    let m6 = t.functions().find(|f| f.2 == 6).unwrap().0;
    let fin = t.edges(Signal::Fin).filter(|e| e.1).map(|e| e.0).find(|&ts| ts > m6).unwrap();
    assert_eq!(fin - m6, 3_000_000);
}
