//! A generated case: a tapping program (described by its choices, rendered per dialect), machine
//! parameters and a schedule of operator inputs and faults.
//!
//! The same types serve the property tests (proptest strategies in [`super::strategy`]) and the
//! fuzzer (`Arbitrary`): every field is a small raw number that [`Case`]'s methods map into the
//! range it stands for, so any value of any field gives a runnable case.

use arbitrary::Arbitrary;
use nc_engine::input::{Condition, CurrentSource, Input, InputSchedule, PlcAnswer};
use nc_engine::invariants::{Context, TapSpec};
use nc_engine::trace::{axis_index, Phase, Signal};
use nc_engine::{Machine, RunOptions};

use super::oracle::CompareRun;
pub use super::program::mm;

/// The dialect and cycle of the program.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Arbitrary)]
pub enum Cycle {
    /// `gsk-lathe` G84: face tapping along Z.
    GskG84,
    /// `gsk-lathe` G88: radial tapping along X (diameter).
    GskG88,
    /// `fanuc-mill` G84 after M29: rigid tapping along Z from the R plane.
    FanucG84,
    /// `knd-lathe` G93: the tap follows the spindle encoder, brakes past the end point, returns.
    KndG93,
    /// `gsk-lathe` G92.3: variable-lead threading passes locked to the spindle.
    GskG923,
    /// `linuxcnc` G33.1: the tap follows the spindle in, through its reversal and back out.
    LinuxcncG33_1,
    /// `heidenhain` cycle 832 THREAD EXTENDED (Klartext): thread passes following the spindle.
    Heidenhain832,
}

impl Cycle {
    /// The dialect name.
    pub fn dialect(self) -> &'static str {
        match self {
            Cycle::GskG84 | Cycle::GskG88 => "gsk-lathe",
            Cycle::FanucG84 => "fanuc-mill",
            Cycle::KndG93 => "knd-lathe",
            Cycle::GskG923 => "gsk-lathe",
            Cycle::LinuxcncG33_1 => "linuxcnc",
            Cycle::Heidenhain832 => "heidenhain",
        }
    }

    /// A `gsk-lathe` cycle.
    pub fn gsk(self) -> bool {
        matches!(self, Cycle::GskG84 | Cycle::GskG88)
    }
}

/// The peck mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Arbitrary)]
pub enum Peck {
    /// Straight to the bottom.
    Standard,
    /// GSK: Q with R (retract by R); Fanuc: Q with 5200.5 = 0 (retract by 5213).
    HighSpeed,
    /// GSK: Q with J1; Fanuc: Q with 5200.5 = 1 (back to R after each cut).
    Deep,
}

/// How the tapping mode ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Arbitrary)]
pub enum Cancel {
    /// G80.
    G80,
    /// A G00 block.
    Rapid,
    /// A G01 block.
    Feed,
    /// M30 alone.
    ProgramEnd,
}

/// A word at the last valid value of its range, or at the first invalid one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Arbitrary)]
pub enum Edge {
    /// P at its maximum (valid).
    DwellMax,
    /// P one above its maximum.
    DwellBeyond,
    /// P negative.
    DwellNegative,
    /// K at its minimum, 1 (valid).
    RepeatMin,
    /// K0.
    RepeatZero,
    /// K one above its maximum.
    RepeatBeyond,
    /// R at its maximum (GSK, valid).
    RetractMax,
    /// R one increment above its maximum (GSK).
    RetractBeyond,
    /// Q at its maximum (valid).
    PeckMax,
    /// Q beyond its range (GSK) or negative (Fanuc).
    PeckBeyond,
    /// D at 150 (GSK, valid).
    OverloadMax,
    /// D151 (GSK).
    OverloadBeyond,
    /// J2 (GSK).
    JBeyond,
    /// The lead at its maximum (GSK F500, valid).
    LeadMax,
    /// The lead one increment beyond (GSK F500.0001).
    LeadBeyond,
    /// F0.
    LeadZero,
    /// S at the rigid tapping maximum (valid).
    SpeedMax,
    /// S one above the rigid tapping maximum.
    SpeedBeyond,
}

impl Edge {
    /// Every edge word, valid and invalid.
    pub const ALL: [Edge; 18] = [
        Edge::DwellMax,
        Edge::DwellBeyond,
        Edge::DwellNegative,
        Edge::RepeatMin,
        Edge::RepeatZero,
        Edge::RepeatBeyond,
        Edge::RetractMax,
        Edge::RetractBeyond,
        Edge::PeckMax,
        Edge::PeckBeyond,
        Edge::OverloadMax,
        Edge::OverloadBeyond,
        Edge::JBeyond,
        Edge::LeadMax,
        Edge::LeadBeyond,
        Edge::LeadZero,
        Edge::SpeedMax,
        Edge::SpeedBeyond,
    ];
}

/// The program's choices (raw numbers; see the accessors for what each one means).
#[derive(Debug, Clone, PartialEq, Eq, Arbitrary)]
pub struct ProgramSpec {
    /// Dialect and cycle.
    pub cycle: Cycle,
    /// Peck mode.
    pub peck: Peck,
    /// Depth of the hole: 0.5 + raw % 200 × 0.1 mm.
    pub depth: u16,
    /// Lead: 0.25 + raw % 12 × 0.25 mm.
    pub lead: u8,
    /// Left-hand tap (negative F on GSK, G74 is not generated).
    pub left_hand: bool,
    /// Rigid tapping speed: 100 + raw % 30 × 100 rpm (capped by the edge words).
    pub speed: u8,
    /// Dwell at the bottom: raw % 5 × 250 ms.
    pub dwell: u8,
    /// Peck depth: 0.5 + raw % 40 × 0.25 mm.
    pub peck_depth: u8,
    /// Peck retract (GSK R): 0.1 + raw % 20 × 0.1 mm.
    pub peck_retract: u8,
    /// Repeats K: 1 + raw % 3 (K written when above 1).
    pub repeats: u8,
    /// GSK: the clamp code M68 in the tapping block (parameter 170 = 68).
    pub clamp: bool,
    /// GSK: an overload threshold D = raw % 151 %, when given.
    pub overload: Option<u8>,
    /// `M29 S` in the tapping block itself rather than the block before.
    pub m29_in_block: bool,
    /// The spindle before M29: none, or M03 / M04 at 200 + raw % 20 × 100 rpm.
    pub spindle_before: Option<(bool, u8)>,
    /// A second hole after the first (a block with a new position only).
    pub second_hole: bool,
    /// Fanuc: G98 (initial level) rather than G99 (R plane).
    pub return_initial: bool,
    /// Fanuc: G95 (F is the lead) rather than G94 (F = lead × S).
    pub per_revolution: bool,
    /// A G01 move before the cycle (so dry run has something to change).
    pub feed_move_before: bool,
    /// How rigid tapping ends.
    pub cancel: Cancel,
    /// A word at or beyond an edge of its range.
    pub edge: Option<Edge>,
}

/// Machine parameter choices (raw).
#[derive(Debug, Clone, PartialEq, Eq, Arbitrary, Default)]
pub struct ParamSpec {
    /// Interpolation period: 1, 2, 4 or 8 ms.
    pub period: u8,
    /// Rigid tapping time constant: raw % 41 × 10 ms.
    pub rt_ramp: u8,
    /// Spindle time constant (0 .. max speed): raw % 21 × 100 ms.
    pub spindle_ramp: u8,
    /// GSK 186.2 RTCRG.
    pub rtcrg: bool,
    /// GSK 186.5: overload watches the spindle motor.
    pub overload_spindle: bool,
    /// GSK 186.7 RTORI.
    pub rtori: bool,
    /// GSK 270: overload delay raw % 201 ms.
    pub overload_delay: u8,
    /// GSK 271: overload threshold raw % 301 % (0 = off).
    pub overload_threshold: u16,
    /// Backlash of the tap axis: raw % 51 µm.
    pub backlash: u8,
    /// PLC FIN delay raw % 51 ms.
    pub fin: u8,
    /// Drive position-mode answer delay raw % 31 × 10 ms.
    pub sppos_reach: u8,
    /// RGTAP delays raw % 51 ms.
    pub rgtap: u8,
    /// GSK 182.7: Q in mm.
    pub q_in_mm: bool,
    /// Fanuc 5200.6 FHD: feed hold acts in rigid tapping.
    pub fhd: bool,
    /// Fanuc 5211: extraction override raw % 201 % (0 = 100 %).
    pub extraction: u8,
}

/// What triggers an input.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Arbitrary)]
pub enum Trigger {
    /// At raw × 10 ms (0 .. 655 s; the run's time limit cuts it).
    AtMs(u16),
    /// When a phase is entered (its occurrence 1 + raw % 4), delay raw % 1000 ms.
    Phase(PhaseKind, u8, u16),
    /// When the hold lamp SPL rises (occurrence 1 + raw % 3), delay raw % 1000 ms.
    HoldLamp(u8, u16),
}

/// The phases an input can wait for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Arbitrary)]
pub enum PhaseKind {
    /// positioning
    Positioning,
    /// cutting
    Cutting,
    /// dwell
    Dwell,
    /// retract
    Retract,
}

/// A PLC or drive answer a fault acts on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Arbitrary)]
pub enum AnswerKind {
    /// Position mode reached.
    PositionModeReached,
    /// FIN.
    Fin,
    /// RGTAP.
    Rgtap,
    /// Zero speed.
    ZeroSpeed,
}

/// An operator action or fault.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Arbitrary)]
pub enum Action {
    /// Cycle start.
    CycleStart,
    /// Reset.
    Reset,
    /// Feed hold.
    FeedHold,
    /// Single block on/off.
    SingleBlock(bool),
    /// Dry run on/off.
    DryRun(bool),
    /// Machine lock on/off.
    MachineLock(bool),
    /// Feed override raw % 201 %.
    FeedOverride(u8),
    /// Spindle override 50 + raw % 101 %.
    SpindleOverride(u8),
    /// Emergency stop pressed.
    EmergencyStop,
    /// Motor current: spindle (true) or feed axis, raw % 201 %.
    MotorCurrent(bool, u8),
    /// An answer late by raw % 3001 ms.
    Late(AnswerKind, u16),
    /// An answer that never comes.
    Never(AnswerKind),
    /// The spindle stalls (true) or recovers.
    SpindleStall(bool),
}

/// One input with its trigger.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Arbitrary)]
pub struct GenInput {
    /// When.
    pub trigger: Trigger,
    /// What.
    pub action: Action,
}

/// A second run to compare with (the differential invariants).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Arbitrary)]
pub enum Compare {
    /// Nothing beyond the determinism re-run.
    None,
    /// The same case with dry run switched on at raw × 10 ms (INV-06).
    DryRun(u16),
    /// The same case under machine lock from the start (INV-07).
    MachineLock,
}

/// A whole generated case.
#[derive(Debug, Clone, PartialEq, Eq, Arbitrary)]
pub struct Case {
    /// The program.
    pub program: ProgramSpec,
    /// The parameters.
    pub params: ParamSpec,
    /// Inputs and faults.
    pub inputs: Vec<GenInput>,
    /// The comparison run.
    pub compare: Compare,
}

/// Simulated time limit of a generated run.
pub const TIME_LIMIT_US: u64 = 60_000_000;

impl ProgramSpec {
    /// Depth in nm.
    pub fn depth_nm(&self) -> i64 {
        500_000 + (self.depth % 200) as i64 * 100_000
    }
    /// Lead in nm.
    pub fn lead_nm(&self) -> i64 {
        250_000 + (self.lead % 12) as i64 * 250_000
    }
    /// Rigid tapping speed in rpm (before edges).
    pub fn speed_rpm(&self) -> u32 {
        100 + (self.speed % 30) as u32 * 100
    }
    /// Dwell in ms.
    pub fn dwell_ms(&self) -> u32 {
        (self.dwell % 5) as u32 * 250
    }
    /// Peck depth in nm.
    pub fn peck_nm(&self) -> i64 {
        500_000 + (self.peck_depth % 40) as i64 * 250_000
    }
    /// GSK peck retract in nm.
    pub fn retract_nm(&self) -> i64 {
        100_000 + (self.peck_retract % 20) as i64 * 100_000
    }
    /// K.
    pub fn repeats(&self) -> u32 {
        1 + (self.repeats % 3) as u32
    }
    /// The spindle before M29: signed rpm (0: stopped).
    pub fn spindle_before_rpm(&self) -> i64 {
        match self.spindle_before {
            None => 0,
            Some((fwd, raw)) => {
                let rpm = 200 + (raw % 20) as i64 * 100;
                if fwd {
                    rpm
                } else {
                    -rpm
                }
            }
        }
    }
}

impl Case {
    /// The dialect name.
    pub fn dialect(&self) -> &'static str {
        self.program.cycle.dialect()
    }

    /// The parameters as (id, axis, value), in a fixed order.
    pub fn param_list(&self) -> Vec<(String, Option<char>, f64)> {
        let p = &self.params;
        let gsk = self.program.cycle.gsk();
        let period = [1000.0, 2000.0, 4000.0, 8000.0][(p.period % 4) as usize];
        let rt_ramp = (p.rt_ramp % 41) as f64 * 10.0;
        let mut v: Vec<(&str, Option<char>, f64)> = vec![
            ("nc.period_us", None, period),
            ("nc.spindle_ramp_ms", None, (p.spindle_ramp % 21) as f64 * 100.0),
            ("plc.fin_ms", None, (p.fin % 51) as f64),
            ("plc.sppos_reach_ms", None, (p.sppos_reach % 31) as f64 * 10.0),
            ("plc.rgtap_ms", None, (p.rgtap % 51) as f64),
            ("plc.rgtap_fall_ms", None, (p.rgtap % 51) as f64),
        ];
        let backlash = (p.backlash % 51) as f64 / 1000.0;
        if gsk {
            let tap_axis = if self.program.cycle == Cycle::GskG88 { 'X' } else { 'Z' };
            v.extend([
                ("nc.rt_ramp_ms", None, rt_ramp),
                ("186.2", None, p.rtcrg as u8 as f64),
                ("186.5", None, p.overload_spindle as u8 as f64),
                ("186.7", None, p.rtori as u8 as f64),
                ("270", None, (p.overload_delay % 201) as f64),
                ("271", None, (p.overload_threshold % 301) as f64),
                ("182.7", None, p.q_in_mm as u8 as f64),
                ("34", Some(tap_axis), backlash),
            ]);
            if self.program.clamp {
                v.push(("170", None, 68.0));
            }
        } else if self.program.cycle == Cycle::GskG923 {
            // A threading cycle: no M29 handshake; the feed-hold bit and the Q unit are its own.
            v.retain(|(id, _, _)| !id.starts_with("plc.sppos") && !id.starts_with("plc.rgtap"));
            v.extend([
                ("nc.thread_retract", None, p.rtcrg as u8 as f64),
                ("182.7", None, p.q_in_mm as u8 as f64),
                ("34", Some('Z'), backlash),
            ]);
        } else if self.program.cycle == Cycle::KndG93 {
            // The KND lathe has no M29 handshake: no sppos/rgtap delays (KND-G93-03).
            v.retain(|(id, _, _)| !id.starts_with("plc.sppos") && !id.starts_with("plc.rgtap"));
            v.extend([
                ("nc.spindle_brake_ms", None, 1.0 + rt_ramp),
                ("003.RVDL", None, p.rtcrg as u8 as f64),
                ("nc.backlash_mm", Some('Z'), backlash),
            ]);
        } else if self.program.cycle == Cycle::LinuxcncG33_1 {
            // LinuxCNC has no M29 handshake either; the reversal follows `nc.spindle_ramp_ms`.
            v.retain(|(id, _, _)| !id.starts_with("plc.sppos") && !id.starts_with("plc.rgtap"));
            v.push(("nc.backlash_mm", Some('Z'), backlash));
        } else if self.program.cycle == Cycle::Heidenhain832 {
            // Cycle 832 has no M29 handshake either; the negative-diameter check may be off.
            v.retain(|(id, _, _)| !id.starts_with("plc.sppos") && !id.starts_with("plc.rgtap"));
            v.extend([
                ("hei.neg_diameter_alarm", None, p.rtcrg as u8 as f64),
                ("nc.backlash_mm", Some('Z'), backlash),
            ]);
        } else {
            v.extend([
                ("5261", None, rt_ramp),
                ("5200.5", None, (self.program.peck != Peck::HighSpeed) as u8 as f64),
                ("5200.6", None, p.fhd as u8 as f64),
                ("5211", None, (p.extraction % 201) as f64),
                ("1851", Some('Z'), backlash),
            ]);
        }
        v.into_iter().map(|(id, ax, val)| (id.to_string(), ax, val)).collect()
    }

    /// The machine with the case's parameters.
    pub fn machine(&self) -> Machine {
        let mut m = Machine::new(self.dialect()).expect("generated dialects exist");
        for (id, ax, val) in self.param_list() {
            m.params.set(&id, ax, val).expect("generated parameters are in range");
        }
        m
    }

    /// The schedule of the case's inputs.
    pub fn schedule(&self) -> InputSchedule {
        let mut s = InputSchedule::default();
        for gi in &self.inputs {
            let input = engine_input(gi.action);
            s = match gi.trigger {
                Trigger::AtMs(raw) => s.at(raw as u64 * 10_000, input),
                Trigger::Phase(k, occ, delay) => s.when(
                    Condition::Phase(phase(k)),
                    1 + (occ % 4) as u32,
                    (delay % 1000) as u64 * 1000,
                    input,
                ),
                Trigger::HoldLamp(occ, delay) => s.when(
                    Condition::Signal { signal: Signal::Spl, value: true },
                    1 + (occ % 3) as u32,
                    (delay % 1000) as u64 * 1000,
                    input,
                ),
            };
        }
        s
    }

    /// Run options: 1 ms samples, the time limit, no automatic cycle start, the inputs.
    pub fn options(&self) -> RunOptions {
        RunOptions {
            sample_us: 1000,
            time_limit_us: TIME_LIMIT_US,
            auto_cycle_start: false,
            inputs: self.schedule(),
            ..RunOptions::default()
        }
    }

    /// The comparison run of `compare`.
    pub fn compare_run(&self) -> Option<CompareRun> {
        match self.compare {
            Compare::None => None,
            Compare::DryRun(raw) => Some(CompareRun::DryRunAt(raw as u64 * 10_000)),
            Compare::MachineLock => Some(CompareRun::MachineLock),
        }
    }

    /// What the invariants need to know about this case.
    pub fn context(&self) -> Context {
        let p = &self.program;
        let gsk = p.cycle.gsk();
        let axis = axis_index(if p.cycle == Cycle::GskG88 { 'X' } else { 'Z' }).unwrap_or(2);
        let backlash = (self.params.backlash % 51) as i64 * 1000;
        let valid_lead = !matches!(p.edge, Some(Edge::LeadMax | Edge::LeadBeyond | Edge::LeadZero));
        let overridden = self.inputs.iter().any(|i| matches!(i.action, Action::SpindleOverride(_)));
        if matches!(p.cycle, Cycle::KndG93 | Cycle::GskG923 | Cycle::LinuxcncG33_1 | Cycle::Heidenhain832) {
            // G93, G92.3, G33.1 and cycle 832 are no GSK/Fanuc rigid tapping (no F76.3, no
            // RGSPP/RGSPM strokes): the sync, hold and
            // pre-M29 invariants have nothing to look at; INV-09 finds its axis itself.
            return Context {
                tap: None,
                range_alarm: self.program_text().1,
                pre_m29_mrpm: None,
                hold_suppressed: false,
            };
        }
        Context {
            tap: valid_lead.then_some(TapSpec {
                axis,
                lead_nm: p.lead_nm(),
                tolerance_nm: 2 * backlash + 2_000,
            }),
            range_alarm: self.program_text().1,
            pre_m29_mrpm: (!overridden).then_some(p.spindle_before_rpm() * 1000),
            hold_suppressed: gsk || !self.params.fhd,
        }
    }
}

fn phase(k: PhaseKind) -> Phase {
    match k {
        PhaseKind::Positioning => Phase::Positioning,
        PhaseKind::Cutting => Phase::Cutting,
        PhaseKind::Dwell => Phase::Dwell,
        PhaseKind::Retract => Phase::Retract,
    }
}

/// The engine input of an action.
pub fn engine_input(a: Action) -> Input {
    let answer = |k: AnswerKind| match k {
        AnswerKind::PositionModeReached => PlcAnswer::PositionModeReached,
        AnswerKind::Fin => PlcAnswer::Fin,
        AnswerKind::Rgtap => PlcAnswer::Rgtap,
        AnswerKind::ZeroSpeed => PlcAnswer::ZeroSpeed,
    };
    match a {
        Action::CycleStart => Input::CycleStart,
        Action::Reset => Input::Reset,
        Action::FeedHold => Input::FeedHold,
        Action::SingleBlock(b) => Input::SingleBlock(b),
        Action::DryRun(b) => Input::DryRun(b),
        Action::MachineLock(b) => Input::MachineLock(b),
        Action::FeedOverride(p) => Input::FeedOverride((p % 201) as u32),
        Action::SpindleOverride(p) => Input::SpindleOverride(50 + (p % 101) as u32),
        Action::EmergencyStop => Input::EmergencyStop(true),
        Action::MotorCurrent(spindle, p) => Input::MotorCurrent {
            source: if spindle { CurrentSource::Spindle } else { CurrentSource::FeedAxis },
            percent: (p % 201) as u32,
        },
        Action::Late(k, ms) => {
            Input::PlcAnswer { answer: answer(k), extra_us: Some((ms % 3001) as u64 * 1000) }
        }
        Action::Never(k) => Input::PlcAnswer { answer: answer(k), extra_us: None },
        Action::SpindleStall(b) => Input::SpindleStall(b),
    }
}
