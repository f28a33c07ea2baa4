//! Inputs on conditions act at their exact time (COM-INP-01) and parameter changes at run time
//! (COM-INP-10).

mod support;

use nc_engine::input::{Condition, Input, InputSchedule};
use nc_engine::trace::{EndReason, Phase, Signal};
use nc_engine::RunOptions;
use support::run;

const MM: i64 = 1_000_000;
const TAP: &str = "G98;\nG0 X50 Z0;\nM29 S1000;\nG84 Z-20 F1 Q5000 R1;\nG80;\nM30;\n";

fn opts(inputs: InputSchedule) -> RunOptions {
    RunOptions { inputs, auto_cycle_start: false, ..RunOptions::default() }
}

fn input_time(t: &nc_engine::Trace, name: &str) -> u64 {
    t.events
        .iter()
        .find(|e| matches!(&e.event, nc_engine::Event::Input { name: n, .. } if n == name))
        .unwrap_or_else(|| panic!("no {name}"))
        .t_us
}

#[test]
fn com_inp_signal_condition_with_delay() {
    let i = InputSchedule::default().when(
        Condition::Signal { signal: Signal::Rgtap, value: true },
        1,
        10_000,
        Input::Reset,
    );
    let t = run("gsk-lathe", &[], TAP, &opts(i));
    let rgtap = t.edges(Signal::Rgtap).find(|e| e.1).unwrap().0;
    assert_eq!(input_time(&t, "reset"), rgtap + 10_000);
    assert_eq!(t.end().unwrap().reason, EndReason::Reset);
}

#[test]
fn com_inp_axis_crossing_acts_at_the_exact_microsecond() {
    // Z below -5 mm: the first microsecond at which the command position is below -5.
    let i = InputSchedule::default().when(
        Condition::AxisBelow { axis: 2, nm: -5 * MM },
        1,
        0,
        Input::EmergencyStop(true),
    );
    let t = run("gsk-lathe", &[], TAP, &opts(i));
    let at = input_time(&t, "emergency_stop");
    let before = t.samples().filter(|(s, _)| *s < at).last().unwrap().1.axes[2];
    assert!(before >= -5 * MM, "{before}");
    assert_eq!(t.alarms().next().unwrap().1.kind.code(), "NC-1030");
    assert!(t.end().unwrap().state.axes[2] < -5 * MM && t.end().unwrap().state.axes[2] > -5 * MM - 100_000);
}

#[test]
fn com_inp_nth_occurrence_of_a_phase() {
    // The third cutting stroke of the peck (Q5000 = 0.5 mm in 0.0001 mm units... R1 retract).
    let i = InputSchedule::default().when(
        Condition::Phase(Phase::Cutting),
        3,
        0,
        Input::MotorCurrent { source: nc_engine::input::CurrentSource::FeedAxis, percent: 0 },
    );
    let t = run("gsk-lathe", &[], TAP, &opts(i));
    let third = t.phases().filter(|p| p.1 == Phase::Cutting).nth(2).unwrap().0;
    assert_eq!(input_time(&t, "motor_current"), third);
}

#[test]
fn com_inp_block_and_function_conditions() {
    let i = InputSchedule::default().when(Condition::Block { line: 4 }, 1, 0, Input::DryRun(true)).when(
        Condition::Function { letter: 'M', code: 29 },
        1,
        0,
        Input::FeedOverride(50),
    );
    let t = run("gsk-lathe", &[], TAP, &opts(i));
    let m29 = t.functions().find(|f| f.2 == 29).unwrap().0;
    assert_eq!(input_time(&t, "feed_override"), m29);
    let block4 =
        t.events.iter().find(|e| matches!(e.event, nc_engine::Event::Block { line: 4, .. })).unwrap().t_us;
    assert_eq!(input_time(&t, "dry_run"), block4);
}

#[test]
fn com_inp_parameter_change_takes_effect_and_a_bad_value_alarms() {
    // RTCRG 0 → 1 before the G80: the M30 no longer waits for RGTAP to fall.
    let i = InputSchedule::default().at(0, Input::SetParam { id: "186.2".into(), axis: None, value: 1.0 });
    let t = run("gsk-lathe", &[], TAP, &opts(i));
    let rgtap_fall = t.edges(Signal::Rgtap).find(|e| !e.1).unwrap().0;
    let m30 = t.functions().find(|f| f.2 == 30).unwrap().0;
    assert!(m30 < rgtap_fall);
    let i =
        InputSchedule::default().at(100_000, Input::SetParam { id: "271".into(), axis: None, value: 400.0 });
    let t = run("gsk-lathe", &[], TAP, &opts(i));
    let (at, a) = t.alarms().next().unwrap();
    assert_eq!((at, a.kind.code()), (100_000, "NC-1040"));
}

#[test]
fn com_inp_phase_idle_condition_waits_for_the_first_entry() {
    // The power-on idle is no entry: the input acts when the cycle ends and enters idle.
    let i = InputSchedule::default().when(Condition::Phase(Phase::Idle), 1, 0, Input::EmergencyStop(true));
    let t = run("gsk-lathe", &[], TAP, &opts(i));
    let at = input_time(&t, "emergency_stop");
    let idle = t
        .events
        .iter()
        .find(|e| matches!(e.event, nc_engine::Event::Phase(Phase::Idle)))
        .expect("an entry into idle")
        .t_us;
    assert!(at > 0);
    assert_eq!(at, idle);
}
