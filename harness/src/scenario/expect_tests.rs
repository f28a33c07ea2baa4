//! Expectations against real engine traces (GSK lathe rigid tapping) and resolution errors.

use nc_engine::input::{Condition, CurrentSource, Input, InputSchedule};
use nc_engine::trace::{Event, Phase, Sample, Signal, TraceEvent, TraceMeta};
use nc_engine::{Machine, RunOptions, Trace};

use super::*;
use crate::scenario::resolve::Ctx;

const HEAD: &str = "G98;\nG0 X50 Z0;\nM29 S1000;\n";

fn prog(cycle: &str) -> String {
    format!("{HEAD}{cycle}\nG80;\nM30;\n")
}

fn run(text: &str, inputs: InputSchedule) -> Trace {
    let m = Machine::new("gsk-lathe").unwrap();
    let p = m.parse(text).expect("parse");
    m.run_to_trace(&p, &RunOptions { inputs, auto_cycle_start: false, ..RunOptions::default() })
}

fn resolve_yaml(yaml: &str) -> Result<Expectations, InputError> {
    let m = Machine::new("gsk-lathe").unwrap();
    let ctx = Ctx { file: "s.yaml", text: yaml, axes: m.dialect.axes() };
    let e: schema::Expect = serde_saphyr::from_str(yaml).expect("yaml");
    resolve(&ctx, &e, "GSK-RT-01")
}

fn verdicts(yaml: &str, trace: &Trace) -> Vec<Verdict> {
    evaluate(&resolve_yaml(yaml).expect("resolve"), trace)
}

fn one(yaml: &str, trace: &Trace) -> Verdict {
    let v = verdicts(yaml, trace);
    assert_eq!(v.len(), 1, "{v:#?}");
    v.into_iter().next().unwrap()
}

fn lock() -> InputSchedule {
    InputSchedule::default().at(0, Input::MachineLock(true))
}

fn overload() -> Trace {
    let inputs = InputSchedule::default()
        .at(1_000_000, Input::MotorCurrent { source: CurrentSource::FeedAxis, percent: 100 });
    run(&prog("G84 Z-40 F1 D80;"), inputs)
}

const STILL_WHILE_RTAP: &str = "
always:
  - rule: GSK-RT-24
    while: {signals: {F76.3: 1}}
    still: [Z, X]
    spindle_still: true
";

#[test]
fn still_while_rtap_passes_under_machine_lock() {
    let t = run(&prog("G84 Z-10 F1;"), lock());
    let v = verdicts(STILL_WHILE_RTAP, &t);
    assert_eq!(v.len(), 3);
    assert!(v.iter().all(|v| v.pass), "{v:#?}");
    assert_eq!(v[0].what, "always #1 (still Z)");
    assert_eq!(v[0].rule, "GSK-RT-24");
    assert_eq!(v[2].what, "always #1 (spindle_still)");
    assert_eq!(v[0].t_us, Some(288_000), "the window opens at M29");
}

#[test]
fn still_while_rtap_fails_without_machine_lock_at_the_first_move() {
    let t = run(&prog("G84 Z-10 F1;"), InputSchedule::default());
    let v = verdicts(STILL_WHILE_RTAP, &t);
    let z = &v[0];
    assert!(!z.pass);
    let at = z.t_us.unwrap();
    assert!(at > 354_000 && at <= 360_000, "first move seen at {at}");
    assert_eq!(z.expected, "Z = 0 mm (still since 288 ms) while F76.3 = 1");
    assert!(z.actual.starts_with("Z = -0.0"), "{}", z.actual);
    assert!(v[1].pass, "X does not move: {:?}", v[1]);
    assert!(!v[2].pass && v[2].actual.starts_with("rpm "), "{:?}", v[2]);
}

#[test]
fn never_beyond_after_overload_retract() {
    let t = overload();
    let yaml = "
always:
  - rule: GSK-RT-26
    after: {phase: overload_retract}
    never_beyond: {axis: Z, direction: down}
  - rule: GSK-RT-26
    after: {phase: overload_retract}
    never_beyond: {axis: Z, direction: up}
";
    let v = verdicts(yaml, &t);
    assert!(v[0].pass, "{:?}", v[0]);
    assert_eq!(v[0].what, "always #1 (never_beyond Z down)");
    assert!(v[0].expected.ends_with(" after phase overload_retract entered"), "{}", v[0].expected);
    assert!(!v[1].pass, "the retract goes up");
    assert!(v[1].expected.starts_with("Z <= -"), "{}", v[1].expected);
    assert!(v[1].t_us.unwrap() > v[0].t_us.unwrap());
}

#[test]
fn alarm_lists_compare_in_order_with_both_lists_shown() {
    let t = overload();
    let (at, _) = t.alarms().next().unwrap();
    let ok = one("alarms: [{code: NC-1031, line: 4}]", &t);
    assert!(ok.pass, "{ok:?}");
    assert_eq!(ok.rule, "GSK-RT-01");
    assert_eq!(ok.what, "alarms");
    let yaml = format!("alarms: [{{code: NC-1031, at_ms: {}, tolerance_ms: 1}}]", at as f64 / 1000.0 + 0.5);
    assert!(one(&yaml, &t).pass);
    let yaml = format!("alarms: [{{code: NC-1031, at_ms: {}}}]", at as f64 / 1000.0 + 0.5);
    assert!(!one(&yaml, &t).pass, "outside the default tolerance 0");
    let bad = one("alarms: [{code: NC-1030}, {code: NC-1031}]", &t);
    assert!(!bad.pass);
    assert_eq!(bad.expected, "NC-1030; NC-1031");
    assert_eq!(bad.actual, format!("NC-1031 line 4 at {}", ms(at)));
    assert_eq!(bad.t_us, Some(at));
    let none = one("alarms: []", &t);
    assert!(!none.pass);
    assert_eq!(none.expected, "no alarm");
    let clean = run(&prog("G84 Z-10 F1;"), InputSchedule::default());
    let missing = one("alarms: [{code: NC-1031}]", &clean);
    assert_eq!((missing.pass, missing.actual.as_str(), missing.t_us), (false, "no alarm", None));
}

const FEED_HOLD_IN_CUTTING: &str = "
reached:
  - rule: GSK-RT-27
    input: feed_hold
    during: {phase: cutting}
";

#[test]
fn reached_feed_hold_during_cutting() {
    let inputs = InputSchedule::default().at(1_000_000, Input::FeedHold).at(20_000_000, Input::CycleStart);
    let t = run(&prog("G84 Z-20 F1;"), inputs);
    let v = one(FEED_HOLD_IN_CUTTING, &t);
    assert!(v.pass, "{v:?}");
    assert_eq!(v.t_us, Some(1_000_000));
    assert_eq!(v.actual, "feed_hold acted at 1000 ms with phase cutting");

    // Pressed only during the dwell at the bottom.
    let inputs = InputSchedule::default().at(1_500_000, Input::FeedHold).at(20_000_000, Input::CycleStart);
    let t = run(&prog("G84 Z-10 F1 P2000;"), inputs);
    let tl = Timeline::new(&t);
    assert_eq!(tl.phase(tl.at(1_500_000).unwrap()), Phase::Dwell);
    let v = one(FEED_HOLD_IN_CUTTING, &t);
    assert!(!v.pass);
    assert_eq!(v.actual, "never; feed_hold acted at 1500 ms with phase dwell");
    assert_eq!(v.expected, "feed_hold acted while phase cutting");
}

#[test]
fn reached_input_sees_the_state_the_input_met() {
    // Reset while cutting: the state after the reset's events is idle, the one it met is cutting.
    let t = run(&prog("G84 Z-40 F1;"), InputSchedule::default().at(1_500_000, Input::Reset));
    let yaml = "
reached:
  - {rule: GSK-RT-25, input: reset, during: {phase: cutting, signals: {RGTAP: 1}}}
  - {rule: GSK-RT-25, state: {phase: cutting, spindle_rpm: {above: 999}}}
  - {rule: GSK-RT-25, state: {phase: overload_retract}}
end: {reason: reset, state: {signals: {F76.3: 0, RGTAP: 0}}}
";
    let v = verdicts(yaml, &t);
    assert_eq!(v[0].what, "end");
    assert!(v[0].pass, "{:?}", v[0]);
    assert!(v[1].pass, "{:?}", v[1]);
    assert!(v[2].pass, "{:?}", v[2]);
    assert_eq!(v[3].actual, "never");
    assert!(!v[3].pass);
}

#[test]
fn checks_at_a_time_and_on_a_condition() {
    let t = run(&prog("G84 Z-10 F1;"), InputSchedule::default());
    let yaml = "
checks:
  - {rule: COM-PLC-02, when: {signal: RGTAP, value: 1}, state: {signals: {F76.3: 1, SPPOSA: 1}}}
  - {rule: COM-PLC-02, when: {signal: RGTAP, value: 1}, state: {phase: retract}}
  - {rule: GSK-RT-07, at_ms: 1000, state: {axes: {Z: 0}}}
  - {rule: GSK-RT-07, when: {block: 99}, state: {phase: idle}}
  - {rule: GSK-RT-07, at_ms: 100000, state: {phase: idle}}
  - {rule: GSK-RT-07, when: {phase: retract}, delay_ms: 1, state: {axes: {Z: {max: -9.9, min: -10}}, spindle_rpm: {below: 0}}}
";
    let v = verdicts(yaml, &t);
    assert!(v[0].pass, "{:?}", v[0]);
    assert_eq!(v[0].what, "check #1");
    assert_eq!(v[0].t_us, Some(354_000));
    assert_eq!(v[0].expected, "F76.3 = 1, SPPOSA = 1 when RGTAP = 1");
    assert!(!v[1].pass);
    assert_eq!(v[1].actual, "phase cutting");
    assert!(!v[2].pass);
    assert!(v[2].actual.starts_with("Z = -") && v[2].expected == "Z = 0 mm at 1000 ms", "{:?}", v[2]);
    assert_eq!((v[3].pass, v[3].actual.as_str()), (false, "condition never held"));
    assert!(!v[4].pass && v[4].actual.starts_with("the run ended at"), "{:?}", v[4]);
    assert!(v[5].pass, "{:?}", v[5]);
    assert_eq!(v[5].expected, "Z >= -10 mm, Z <= -9.9 mm, rpm < 0 when phase retract entered + 1 ms");
}

#[test]
fn end_reason_time_modal_and_state() {
    let t = run(&prog("G84 Z-10 F1;"), lock());
    let end = t.events.last().unwrap().t_us;
    let yaml = format!(
        "end: {{reason: program_end, at_ms: {}, tolerance_ms: 2, modal: [G0, G98],
  state: {{axes: {{X: 0, Z: 0}}, command: {{X: 50, Z: 0}}, phase: idle, spindle_rpm: 0}}}}",
        end as f64 / 1000.0 - 1.5
    );
    let v = one(&yaml, &t);
    assert!(v.pass, "{v:?}");
    assert_eq!(v.t_us, Some(end));
    let v = one("end: {reason: alarm, modal: [G99], state: {command: {X: 49}}}", &t);
    assert!(!v.pass);
    assert_eq!(v.expected, "reason alarm, modal G99, command X = 49 mm");
    assert_eq!(v.actual, "reason program_end, modal G00 G98 G21, command X = 50 mm");
}

#[test]
fn an_empty_window_fails() {
    let t = run(&prog("G84 Z-10 F1;"), InputSchedule::default());
    let yaml = "
always:
  - rule: GSK-RT-26
    while: {phase: overload_retract}
    holds: {signals: {RGTAP: 1}}
  - rule: GSK-RT-26
    after: {function: M5}
    never_rises: [RGSPP]
  - rule: COM-PLC-02
    holds: {signals: {ESP: 0}}
";
    let v = verdicts(yaml, &t);
    assert_eq!((v[0].pass, v[0].actual.as_str()), (false, "window never opened"));
    assert_eq!(v[0].expected, "window while phase overload_retract");
    assert_eq!((v[1].pass, v[1].actual.as_str()), (false, "window never opened"));
    assert!(v[2].pass, "{:?}", v[2]);
}

#[test]
fn never_rises_and_holds_report_the_first_violation() {
    let yaml = "
always:
  - {rule: COM-INP-02, never_rises: [SPL]}
  - {rule: GSK-RT-07, while: {phase: cutting}, holds: {signals: {RGSPP: 1, RGTAP: 1}, spindle_rpm: {min: 0}}}
  - {rule: GSK-RT-07, while: {phase: cutting}, never_rises: [RGSPP]}
";
    let t = run(&prog("G84 Z-10 F1;"), InputSchedule::default());
    let v = verdicts(yaml, &t);
    assert!(v.iter().all(|v| v.pass), "{v:#?}");
    let inputs = InputSchedule::default().at(1_000_000, Input::FeedHold).at(20_000_000, Input::CycleStart);
    let t = run(&prog("G84 Z-10 F1;"), inputs);
    let spl = t.edges(Signal::Spl).find(|e| e.1).unwrap().0;
    let v = verdicts(yaml, &t);
    assert!(!v[0].pass);
    assert_eq!(v[0].t_us, Some(spl));
    assert_eq!(v[0].actual, "SPL rose to 1");
}

#[test]
fn timeline_merges_same_time_events_and_finds_conditions() {
    let t = run(&prog("G84 Z-10 F1;"), InputSchedule::default());
    let tl = Timeline::new(&t);
    let mut times: Vec<u64> = t.events.iter().map(|e| e.t_us).collect();
    times.dedup();
    assert_eq!(tl.len(), times.len());
    // Positioning and cutting are entered at the same time: the instant shows cutting.
    let i = tl.at(354_000).unwrap();
    assert_eq!((tl.t_us(i), tl.phase(i)), (354_000, Phase::Cutting));
    assert!(tl.signals(i).get(Signal::Rgtap) && !tl.signals(i).get(Signal::Mf));
    assert_eq!(tl.blocks(i).collect::<Vec<_>>(), [4]);
    assert_eq!(tl.at(354_500), Some(i));
    let ft = |c: Condition, n| tl.first_time(&c, n);
    assert_eq!(ft(Condition::Phase(Phase::Positioning), 1), Some(354_000));
    assert_eq!(ft(Condition::Phase(Phase::Positioning), 2), None);
    assert_eq!(ft(Condition::Signal { signal: Signal::Stl, value: true }, 1), Some(0));
    assert_eq!(ft(Condition::Signal { signal: Signal::Mf, value: false }, 1), Some(0), "holds at t = 0");
    assert_eq!(ft(Condition::Signal { signal: Signal::Mf, value: true }, 2), Some(1_704_000));
    assert_eq!(ft(Condition::Function { letter: 'M', code: 30 }, 1), Some(1_704_000));
    assert_eq!(ft(Condition::Block { line: 4 }, 1), Some(354_000));
    let below = ft(Condition::AxisBelow { axis: 2, nm: -5_000_000 }, 1).unwrap();
    let z = |t: u64| tl.machine(tl.at(t).unwrap()).unwrap()[2];
    assert!(z(below) < -5_000_000 && z(below - 1000) >= -5_000_000);
    assert_eq!(ft(Condition::AxisBelow { axis: 2, nm: -5_000_000 }, 2), None);
    let last = tl.len() - 1;
    assert!(tl.is_end(last));
    assert_eq!(tl.command(last).unwrap()[0], 50_000_000);
}

#[test]
fn timeline_is_linear_on_long_traces() {
    // 600 000 samples (10 min at 1 kHz) with a signal toggling every second.
    let n = 600_000u64;
    let mut events = Vec::with_capacity(n as usize + 700);
    for k in 0..n {
        let t = k * 1000;
        let z = -((k % 1000) as i64) * 1000;
        events.push(TraceEvent {
            t_us: t,
            event: Event::Sample(Sample { axes: [0, 0, z, 0, 0, 0], ..Sample::default() }),
        });
        if k % 1000 == 0 {
            events.push(TraceEvent {
                t_us: t,
                event: Event::Signal { signal: Signal::Rgspp, value: k % 2000 == 0 },
            });
        }
    }
    let meta = TraceMeta { dialect: "gsk-lathe", axes: Vec::new(), period_us: 1000, sample_us: 1000 };
    let t = Trace { meta, events };
    let start = std::time::Instant::now();
    let tl = Timeline::new(&t);
    assert_eq!(tl.len(), n as usize);
    let c = Condition::Signal { signal: Signal::Rgspp, value: true };
    assert_eq!(tl.first_time(&c, 300), Some(598_000_000));
    let yaml =
        "always: [{rule: COM-SYNC-01, while: {signals: {RGSPP: 1}}, never_beyond: {axis: Z, direction: up}}]";
    let v = one(yaml, &t);
    assert!(v.pass, "{v:?}");
    assert!(start.elapsed().as_secs() < 20, "{:?}", start.elapsed());
}

fn err(yaml: &str) -> InputError {
    resolve_yaml(yaml).expect_err("should not resolve")
}

#[test]
fn unknown_signal_points_at_its_key() {
    let yaml = "checks:\n  - rule: GSK-RT-01\n    at_ms: 5\n    state:\n      signals: {RGTAP: 1, FOO: 0}\n";
    let e = err(yaml);
    let col = yaml.lines().nth(4).unwrap().find("FOO").unwrap() + 1;
    assert_eq!(e.location(), format!("s.yaml:5:{col}"));
    assert!(e.message.contains("unknown signal `FOO`"), "{}", e.message);
}

#[test]
fn bad_rule_ids_are_located_and_show_the_form() {
    for id in ["GSK-rt-01", "ABC-RT-01", "GSK-RT-1", "GSK-RT-001", "GSK--01", "GSK-RT"] {
        let yaml = format!("always:\n  - rule: {id}\n    spindle_still: true\n");
        let e = err(&yaml);
        assert_eq!(e.location(), "s.yaml:2:11", "{id}");
        assert!(e.message.contains("not a rule id"), "{id}: {}", e.message);
        assert!(e.expected.as_deref().unwrap().contains("COM GSK FAN KND LCN HDH"));
    }
    assert!(resolve_yaml("always:\n  - {rule: HDH-ABC-99, spindle_still: true}\n").is_ok());
}

#[test]
fn a_check_needs_exactly_one_moment() {
    let both =
        "checks:\n  - rule: GSK-RT-01\n    at_ms: 5\n    when: {phase: cutting}\n    state: {phase: idle}\n";
    let e = err(both);
    assert_eq!(e.location(), "s.yaml:2:5");
    assert!(e.message.contains("exactly one of `at_ms` and `when`"), "{}", e.message);
    let neither = "checks:\n  - rule: GSK-RT-01\n    state: {phase: idle}\n";
    assert!(err(neither).message.contains("exactly one"));
    let delay = "checks:\n  - {rule: GSK-RT-01, at_ms: 5, delay_ms: 1, state: {phase: idle}}\n";
    assert!(err(delay).message.contains("delay_ms"));
    let empty = "checks:\n  - {rule: GSK-RT-01, at_ms: 5, state: {}}\n";
    assert!(err(empty).message.contains("`state` is empty"));
}

#[rstest::rstest]
#[case::two_windows(
    "always: [{rule: GSK-RT-01, while: {phase: idle}, after: {phase: cutting}, still: [Z]}]",
    "at most one window"
)]
#[case::no_property("always: [{rule: GSK-RT-01, while: {phase: idle}}]", "without a property")]
#[case::unknown_axis("always: [{rule: GSK-RT-01, still: [Y]}]", "not an axis")]
#[case::direction(
    "always: [{rule: GSK-RT-01, never_beyond: {axis: Z, direction: deeper}}]",
    "unknown direction"
)]
#[case::phase("always: [{rule: GSK-RT-01, holds: {phase: tapping}}]", "unknown phase")]
#[case::no_bound("checks: [{rule: GSK-RT-01, at_ms: 1, state: {axes: {Z: {}}}}]", "at least one bound")]
#[case::empty_bounds(
    "checks: [{rule: GSK-RT-01, at_ms: 1, state: {axes: {Z: {below: 1, above: 2}}}}]",
    "never hold"
)]
#[case::signal_value("checks: [{rule: GSK-RT-01, at_ms: 1, state: {signals: {FIN: 2}}}]", "signal value 2")]
#[case::alarm_code("alarms: [{code: '204'}]", "not an alarm code")]
#[case::end_reason("end: {reason: finished}", "unknown end reason")]
#[case::end_nothing("end: {}", "checks nothing")]
#[case::modal("end: {modal: [M30]}", "not a modal G code")]
#[case::input("reached: [{rule: GSK-RT-01, input: feedhold}]", "unknown input `feedhold`")]
#[case::reached_both("reached: [{rule: GSK-RT-01, input: reset, state: {phase: idle}}]", "exactly one of")]
#[case::tolerance("alarms: [{code: '0204', tolerance_ms: 1}]", "without `at_ms`")]
fn resolution_errors(#[case] yaml: &str, #[case] message: &str) {
    let e = err(yaml);
    assert!(e.message.contains(message), "{yaml}: {}", e.headline());
}

#[test]
fn every_input_name_is_known() {
    use nc_engine::input::PlcAnswer;
    let all = [
        Input::CycleStart,
        Input::Reset,
        Input::FeedHold,
        Input::SingleBlock(true),
        Input::DryRun(true),
        Input::MachineLock(true),
        Input::OptionalStop(true),
        Input::FeedOverride(100),
        Input::SpindleOverride(100),
        Input::EmergencyStop(true),
        Input::MotorCurrent { source: CurrentSource::FeedAxis, percent: 0 },
        Input::PlcAnswer { answer: PlcAnswer::Fin, extra_us: None },
        Input::SpindleStall(true),
        Input::SetParam { id: String::new(), axis: None, value: 0.0 },
    ];
    for i in &all {
        assert!(INPUT_NAMES.split_whitespace().any(|n| n == i.name()), "{}", i.name());
    }
}

#[test]
fn rules_and_numbers_read_well() {
    let x = resolve_yaml(
        "always: [{rule: GSK-RT-24, spindle_still: true}]\nreached: [{rule: GSK-RT-27, input: overload_trip}, {rule: GSK-RT-24, state: {phase: dwell}}]",
    )
    .unwrap();
    assert_eq!(x.rules(), ["GSK-RT-24", "GSK-RT-27"]);
    assert!(!x.is_empty() && resolve_yaml("{}").unwrap().is_empty());
    assert_eq!(fixed(-12_500_000, 6), "-12.5");
    assert_eq!(fixed(-500, 6), "-0.0005");
    assert_eq!(fixed(1_000_000, 6), "1");
    assert_eq!(show(999_500, Unit::Rpm), "999.5");
    assert_eq!(modal_code("g00").as_deref(), Some("G0"));
    assert_eq!(modal_code("G61.0").as_deref(), Some("G61.0"));
    assert_eq!(modal_code("G"), None);
}
