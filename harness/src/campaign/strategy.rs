//! proptest strategies for generated cases, and the operator panel as a proptest-state-machine
//! reference model: switches that toggle, an emergency stop that stays pressed, holds that wait
//! for cycle start, at random times and at random phases of the cycle.

use proptest::prelude::*;
use proptest::sample::SizeRange;
use proptest_state_machine::ReferenceStateMachine;

use super::case::{
    Action, AnswerKind, Cancel, Case, Compare, Cycle, Edge, GenInput, ParamSpec, Peck, PhaseKind,
    ProgramSpec, Trigger,
};

fn cycle() -> impl Strategy<Value = Cycle> {
    prop_oneof![
        Just(Cycle::GskG84),
        Just(Cycle::GskG88),
        Just(Cycle::FanucG84),
        Just(Cycle::KndG93),
        Just(Cycle::GskG923),
        Just(Cycle::LinuxcncG33_1),
        Just(Cycle::Heidenhain832)
    ]
}

fn peck() -> impl Strategy<Value = Peck> {
    prop_oneof![Just(Peck::Standard), Just(Peck::HighSpeed), Just(Peck::Deep)]
}

fn cancel() -> impl Strategy<Value = Cancel> {
    prop_oneof![Just(Cancel::G80), Just(Cancel::Rapid), Just(Cancel::Feed), Just(Cancel::ProgramEnd)]
}

/// Every edge word, valid and invalid.
pub fn edge() -> impl Strategy<Value = Edge> {
    proptest::sample::select(Edge::ALL.to_vec())
}

prop_compose! {
    /// A tapping program of any dialect; one case in four carries an edge word.
    pub fn program()(
        (cycle, peck, depth, lead, left_hand, speed, dwell) in
            (cycle(), peck(), 0u16..200, 0u8..12, any::<bool>(), 0u8..30, 0u8..5),
        (peck_depth, peck_retract, repeats, clamp, overload, m29_in_block) in
            (0u8..40, 0u8..20, 0u8..3, any::<bool>(), proptest::option::of(0u8..151), any::<bool>()),
        (spindle_before, second_hole, return_initial, per_revolution, feed_move_before, cancel) in
            (proptest::option::of((any::<bool>(), 0u8..20)), any::<bool>(), any::<bool>(), any::<bool>(),
             any::<bool>(), cancel()),
        edge in proptest::option::weighted(0.25, edge()),
    ) -> ProgramSpec {
        ProgramSpec {
            cycle, peck, depth, lead, left_hand, speed, dwell, peck_depth, peck_retract, repeats, clamp,
            overload, m29_in_block, spindle_before, second_hole, return_initial, per_revolution,
            feed_move_before, cancel, edge,
        }
    }
}

prop_compose! {
    /// Machine parameters over their useful ranges.
    pub fn params()(
        (period, rt_ramp, spindle_ramp, rtcrg, overload_spindle, rtori, overload_delay, overload_threshold) in
            (0u8..4, 0u8..41, 0u8..21, any::<bool>(), any::<bool>(), any::<bool>(), 0u8..201, 0u16..301),
        (backlash, fin, sppos_reach, rgtap, q_in_mm, fhd, extraction) in
            (prop_oneof![3 => Just(0u8), 1 => 0u8..51], 0u8..51, 0u8..31, 0u8..51, any::<bool>(), any::<bool>(),
             0u8..201),
    ) -> ParamSpec {
        ParamSpec {
            period, rt_ramp, spindle_ramp, rtcrg, overload_spindle, rtori, overload_delay, overload_threshold,
            backlash, fin, sppos_reach, rgtap, q_in_mm, fhd, extraction,
        }
    }
}

fn phase_kind() -> impl Strategy<Value = PhaseKind> {
    prop_oneof![
        Just(PhaseKind::Positioning),
        Just(PhaseKind::Cutting),
        Just(PhaseKind::Dwell),
        Just(PhaseKind::Retract)
    ]
}

fn answer() -> impl Strategy<Value = AnswerKind> {
    prop_oneof![
        Just(AnswerKind::PositionModeReached),
        Just(AnswerKind::Fin),
        Just(AnswerKind::Rgtap),
        Just(AnswerKind::ZeroSpeed)
    ]
}

/// When an input acts: at a time in the first 8 s, or at a phase of the cycle.
pub fn trigger() -> impl Strategy<Value = Trigger> {
    prop_oneof![
        (0u16..800).prop_map(Trigger::AtMs),
        (phase_kind(), 0u8..4, 0u16..1000).prop_map(|(k, o, d)| Trigger::Phase(k, o, d)),
        (0u8..3, 0u16..1000).prop_map(|(o, d)| Trigger::HoldLamp(o, d)),
    ]
}

/// Any operator action or fault.
pub fn action() -> impl Strategy<Value = Action> {
    prop_oneof![
        3 => Just(Action::CycleStart),
        2 => Just(Action::Reset),
        3 => Just(Action::FeedHold),
        2 => any::<bool>().prop_map(Action::SingleBlock),
        1 => any::<bool>().prop_map(Action::DryRun),
        1 => any::<bool>().prop_map(Action::MachineLock),
        1 => (0u8..201).prop_map(Action::FeedOverride),
        1 => (0u8..101).prop_map(Action::SpindleOverride),
        1 => Just(Action::EmergencyStop),
        2 => (any::<bool>(), 0u8..201).prop_map(|(s, p)| Action::MotorCurrent(s, p)),
        1 => (answer(), 0u16..3001).prop_map(|(a, ms)| Action::Late(a, ms)),
        1 => answer().prop_map(Action::Never),
        1 => any::<bool>().prop_map(Action::SpindleStall),
    ]
}

/// One input with its trigger.
pub fn input() -> impl Strategy<Value = GenInput> {
    (trigger(), action()).prop_map(|(trigger, action)| GenInput { trigger, action })
}

/// Whether an input leaves the two runs of a differential comparison comparable (the actions
/// [`benign_action`] draws).
pub fn comparable(a: &Action) -> bool {
    matches!(a, Action::FeedOverride(_))
}

/// The actions that leave the two runs of a differential comparison comparable: nothing whose
/// effect depends on when it lands. A feed hold or a cycle start at a fixed time is not: dry run
/// shortens the G01 moves, so the same instant falls in another phase and a cycle start may come
/// before the hold it was meant to end (found by the campaign, seed 2000).
pub fn benign_action() -> impl Strategy<Value = Action> {
    // Not the spindle override either: a KND G93 tap follows the speed-mode spindle, so the
    // override changes its cut wherever it lands (found by the campaign, seed 4000).
    (0u8..201).prop_map(Action::FeedOverride)
}

/// A whole case with up to `inputs` inputs of any kind and no comparison run.
pub fn case(inputs: impl Into<SizeRange>) -> impl Strategy<Value = Case> {
    (program(), params(), proptest::collection::vec(input(), inputs))
        .prop_map(|(program, params, inputs)| Case { program, params, inputs, compare: Compare::None })
}

/// A case for a differential comparison (`compare` decides which), with benign inputs only and
/// no edge word (an alarm before the cycle leaves nothing to compare).
pub fn differential_case(compare: impl Strategy<Value = Compare>) -> impl Strategy<Value = Case> {
    let benign = (trigger(), benign_action()).prop_map(|(trigger, action)| GenInput { trigger, action });
    (program(), params(), proptest::collection::vec(benign, 0..4), compare).prop_map(
        |(mut program, params, inputs, compare)| {
            program.edge = None;
            Case { program, params, inputs, compare }
        },
    )
}

/// The operator panel seen by the reference model.
#[derive(Debug, Clone)]
pub struct Panel {
    /// The case being built (program and parameters drawn once; inputs appended).
    pub case: Case,
    /// Time of the last timed action, ms.
    pub t_ms: u32,
    /// Single block switch.
    pub single_block: bool,
    /// Dry run switch.
    pub dry_run: bool,
    /// Machine lock switch.
    pub machine_lock: bool,
    /// Emergency stop pressed (nothing else acts after it).
    pub estop: bool,
}

/// An operator step: wait, then act (or act at a phase of the cycle).
#[derive(Debug, Clone)]
pub struct Step {
    /// Wait this long after the previous timed step, ms (ignored for phase triggers).
    pub wait_ms: u16,
    /// Act at a phase instead of after the wait.
    pub at_phase: Option<(PhaseKind, u8, u16)>,
    /// The action.
    pub action: Action,
}

/// The reference model of the operator panel for proptest-state-machine.
pub struct OperatorModel;

impl ReferenceStateMachine for OperatorModel {
    type State = Panel;
    type Transition = Step;

    fn init_state() -> BoxedStrategy<Panel> {
        (program(), params())
            .prop_map(|(program, params)| Panel {
                case: Case { program, params, inputs: Vec::new(), compare: Compare::None },
                t_ms: 0,
                single_block: false,
                dry_run: false,
                machine_lock: false,
                estop: false,
            })
            .boxed()
    }

    fn transitions(s: &Panel) -> BoxedStrategy<Step> {
        let toggles = prop_oneof![
            Just(Action::SingleBlock(!s.single_block)),
            Just(Action::DryRun(!s.dry_run)),
            Just(Action::MachineLock(!s.machine_lock)),
        ];
        let action = prop_oneof![
            4 => Just(Action::CycleStart),
            3 => Just(Action::FeedHold),
            1 => Just(Action::Reset),
            3 => toggles,
            1 => (0u8..201).prop_map(Action::FeedOverride),
            1 => Just(Action::EmergencyStop),
            2 => (any::<bool>(), 0u8..201).prop_map(|(sp, p)| Action::MotorCurrent(sp, p)),
            1 => (answer(), 0u16..3001).prop_map(|(a, ms)| Action::Late(a, ms)),
            1 => answer().prop_map(Action::Never),
            1 => any::<bool>().prop_map(Action::SpindleStall),
        ];
        let at_phase = proptest::option::weighted(0.5, (phase_kind(), 0u8..4, 0u16..1000));
        (0u16..1500, at_phase, action)
            .prop_map(|(wait_ms, at_phase, action)| Step { wait_ms, at_phase, action })
            .boxed()
    }

    fn preconditions(s: &Panel, step: &Step) -> bool {
        // After the emergency stop nothing acts any more (the run has ended): any step is
        // allowed, so that shrinking never runs out of valid sequences.
        s.estop
            || match step.action {
                Action::SingleBlock(b) => b != s.single_block,
                Action::DryRun(b) => b != s.dry_run,
                Action::MachineLock(b) => b != s.machine_lock,
                _ => true,
            }
    }

    fn apply(mut s: Panel, step: &Step) -> Panel {
        let trigger = match step.at_phase {
            Some((k, o, d)) => Trigger::Phase(k, o, d),
            None => {
                s.t_ms += step.wait_ms as u32;
                Trigger::AtMs((s.t_ms / 10).min(u16::MAX as u32) as u16)
            }
        };
        match step.action {
            Action::SingleBlock(b) => s.single_block = b,
            Action::DryRun(b) => s.dry_run = b,
            Action::MachineLock(b) => s.machine_lock = b,
            Action::EmergencyStop => s.estop = true,
            _ => {}
        }
        s.case.inputs.push(GenInput { trigger, action: step.action });
        s
    }
}
