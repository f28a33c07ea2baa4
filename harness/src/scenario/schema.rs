//! The scenario file format (`scenarios/**/*.yaml`, documented in `docs/scenarios.md`) as serde
//! types. Unknown keys are errors (`deny_unknown_fields`); values that need checking against the
//! engine (signal names, parameter ids, axes, phases) keep their location (`Spanned`) so the
//! loader can point at them.

use std::fmt;
use std::marker::PhantomData;

use serde::de::{Deserializer, MapAccess, Visitor};
use serde::Deserialize;
use serde_saphyr::Spanned;

use crate::params_yaml::ParamEntries;

/// A mapping kept in the order written, keys with their location.
#[derive(Debug, Clone)]
pub struct Keyed<V>(pub Vec<(Spanned<String>, V)>);

impl<V> Default for Keyed<V> {
    fn default() -> Self {
        Keyed(Vec::new())
    }
}

impl<'de, V: Deserialize<'de>> Deserialize<'de> for Keyed<V> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Vis<V>(PhantomData<V>);
        impl<'de, V: Deserialize<'de>> Visitor<'de> for Vis<V> {
            type Value = Keyed<V>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a mapping")
            }
            fn visit_unit<E: serde::de::Error>(self) -> Result<Keyed<V>, E> {
                Ok(Keyed(Vec::new()))
            }
            fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<Keyed<V>, A::Error> {
                let mut v = Vec::new();
                while let Some(k) = m.next_key::<Spanned<String>>()? {
                    v.push((k, m.next_value::<V>()?));
                }
                Ok(Keyed(v))
            }
        }
        d.deserialize_map(Vis(PhantomData))
    }
}

/// A whole scenario file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioFile {
    /// One line saying what the scenario shows.
    pub title: String,
    /// The rule ids (docs/rules) this scenario checks; at least one.
    pub rules: Vec<Spanned<String>>,
    /// Dialect name.
    pub dialect: Spanned<String>,
    /// Parameter overrides: id → number, or id → {axis: number} (as in a `--params` file).
    #[serde(default)]
    pub params: ParamEntries,
    /// The program text (exclusive with `program_file`).
    #[serde(default)]
    pub program: Option<Spanned<String>>,
    /// A program file, relative to the scenario file.
    #[serde(default)]
    pub program_file: Option<Spanned<String>>,
    /// Run options.
    #[serde(default)]
    pub options: Options,
    /// Operator actions and faults.
    #[serde(default)]
    pub inputs: Vec<Spanned<InputEntry>>,
    /// What must happen.
    #[serde(default)]
    pub expect: Expect,
    /// What the timing-diagram snapshot shows.
    #[serde(default)]
    pub snapshot: Option<SnapshotSpec>,
}

/// Run options.
#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields, default)]
pub struct Options {
    /// Sample period, µs (0: none). Default 1000.
    pub sample_us: u64,
    /// Stop after this much simulated time, ms. Default 600 000.
    pub time_limit_ms: u64,
    /// Press cycle start by itself at M00/M01. Default false (scenarios press it themselves).
    pub auto_cycle_start: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options { sample_us: 1000, time_limit_ms: 600_000, auto_cycle_start: false }
    }
}

/// When something acts or is checked: at a time, or when a condition first holds.
#[derive(Debug, Deserialize, Clone, Default)]
#[serde(deny_unknown_fields)]
pub struct When {
    /// A signal has this value (`{signal: RGTAP, value: 1}`).
    #[serde(default)]
    pub signal: Option<Spanned<String>>,
    /// The value for `signal` (0 or 1).
    #[serde(default)]
    pub value: Option<u8>,
    /// An axis (command position) goes below this, mm.
    #[serde(default)]
    pub axis: Option<Spanned<String>>,
    /// With `axis`: strictly below, mm.
    #[serde(default)]
    pub below: Option<f64>,
    /// With `axis`: strictly above, mm.
    #[serde(default)]
    pub above: Option<f64>,
    /// The block on this source line starts.
    #[serde(default)]
    pub block: Option<u32>,
    /// The phase is entered (`idle`, `positioning`, `cutting`, `dwell`, `retract`, `overload_retract`).
    #[serde(default)]
    pub phase: Option<Spanned<String>>,
    /// An M/S/T function is output (`M29`, `S1000`, `T2`).
    #[serde(default)]
    pub function: Option<Spanned<String>>,
    /// Which occurrence (1 = first). Default 1.
    #[serde(default)]
    pub occurrence: Option<u32>,
}

/// One input: exactly one trigger (`at_ms` or `when`) and exactly one action key.
#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct InputEntry {
    /// At this time, ms (decimals allowed: 0.5 = 500 µs).
    #[serde(default)]
    pub at_ms: Option<f64>,
    /// When a condition first holds.
    #[serde(default)]
    pub when: Option<Spanned<When>>,
    /// Extra delay after the condition, ms.
    #[serde(default)]
    pub delay_ms: Option<f64>,
    /// Cycle start button.
    #[serde(default)]
    pub cycle_start: Option<Empty>,
    /// Reset key.
    #[serde(default)]
    pub reset: Option<Empty>,
    /// Feed hold button.
    #[serde(default)]
    pub feed_hold: Option<Empty>,
    /// Single block switch.
    #[serde(default)]
    pub single_block: Option<bool>,
    /// Dry run switch.
    #[serde(default)]
    pub dry_run: Option<bool>,
    /// Machine lock switch.
    #[serde(default)]
    pub machine_lock: Option<bool>,
    /// Optional stop switch.
    #[serde(default)]
    pub optional_stop: Option<bool>,
    /// Feed override, %.
    #[serde(default)]
    pub feed_override: Option<u32>,
    /// Spindle override, %.
    #[serde(default)]
    pub spindle_override: Option<u32>,
    /// Emergency stop pressed (true) / released (false).
    #[serde(default)]
    pub emergency_stop: Option<bool>,
    /// Motor current.
    #[serde(default)]
    pub motor_current: Option<MotorCurrent>,
    /// A PLC or drive answer late or missing.
    #[serde(default)]
    pub plc_answer: Option<PlcAnswerSpec>,
    /// The spindle stalls (true) or recovers (false).
    #[serde(default)]
    pub spindle_stall: Option<bool>,
    /// A parameter changes.
    #[serde(default)]
    pub set_param: Option<SetParam>,
}

/// An action without arguments (`reset: {}`).
#[derive(Debug, Deserialize, Clone, Default)]
#[serde(deny_unknown_fields)]
pub struct Empty {}

/// Motor current input.
#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct MotorCurrent {
    /// `feed_axis` or `spindle`.
    pub source: Spanned<String>,
    /// % of rated current.
    pub percent: u32,
}

/// A late or missing PLC/drive answer.
#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct PlcAnswerSpec {
    /// `position_mode_reached`, `fin`, `rgtap`, `zero_speed`.
    pub answer: Spanned<String>,
    /// Extra delay, ms.
    #[serde(default)]
    pub late_ms: Option<f64>,
    /// The answer never comes.
    #[serde(default)]
    pub never: Option<bool>,
}

/// A parameter change.
#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct SetParam {
    /// Parameter id.
    pub id: Spanned<String>,
    /// Axis of a per-axis parameter.
    #[serde(default)]
    pub axis: Option<Spanned<String>>,
    /// New value.
    pub value: f64,
}

/// What must happen.
#[derive(Debug, Deserialize, Clone, Default)]
#[serde(deny_unknown_fields)]
pub struct Expect {
    /// The alarms, in order (exactly these). Absent: not checked; `[]`: none.
    #[serde(default)]
    pub alarms: Option<Vec<Spanned<ExpectAlarm>>>,
    /// The final state.
    #[serde(default)]
    pub end: Option<ExpectEnd>,
    /// State checks at a time or when a condition holds.
    #[serde(default)]
    pub checks: Vec<Spanned<Check>>,
    /// Temporal rules over the whole run.
    #[serde(default)]
    pub always: Vec<Spanned<TemporalRule>>,
    /// Proof that something actually happened.
    #[serde(default)]
    pub reached: Vec<Spanned<Reached>>,
    /// The program must be refused by the parser (a syntax error), here.
    #[serde(default)]
    pub refused: Option<Spanned<ExpectRefused>>,
    /// The engine's invariants (docs/invariants.md) must hold on this run.
    #[serde(default)]
    pub invariants: Option<Spanned<super::invariants::InvariantsSpec>>,
}

/// Where and why the parser must refuse the program.
#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct ExpectRefused {
    /// Program line (1-based).
    pub line: u32,
    /// Column (1-based), if checked.
    #[serde(default)]
    pub col: Option<u32>,
    /// A text the message must contain.
    #[serde(default)]
    pub message: Option<String>,
}

/// One expected alarm.
#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct ExpectAlarm {
    /// Code as in the trace (`"0204"`, `"NC-1011"`).
    pub code: Spanned<String>,
    /// Source line it names.
    #[serde(default)]
    pub line: Option<u32>,
    /// Raised at this time, ms (± `tolerance_ms`).
    #[serde(default)]
    pub at_ms: Option<f64>,
    /// Tolerance for `at_ms`, ms (default 0).
    #[serde(default)]
    pub tolerance_ms: Option<f64>,
}

/// A comparison of a number: a value, or bounds.
#[derive(Debug, Deserialize, Clone)]
#[serde(untagged)]
pub enum Compare {
    /// Exactly (within `tol` of the check, default 0.000001 mm / 0.001 rpm).
    Exact(f64),
    /// Bounds.
    Range(Bounds),
}

/// Bounds of a number.
#[derive(Debug, Deserialize, Clone, Default)]
#[serde(deny_unknown_fields)]
pub struct Bounds {
    /// Strictly below.
    #[serde(default)]
    pub below: Option<f64>,
    /// Strictly above.
    #[serde(default)]
    pub above: Option<f64>,
    /// At least.
    #[serde(default)]
    pub min: Option<f64>,
    /// At most.
    #[serde(default)]
    pub max: Option<f64>,
}

/// A state: the values that must hold together (all optional).
#[derive(Debug, Deserialize, Clone, Default)]
#[serde(deny_unknown_fields)]
pub struct StateSpec {
    /// Machine positions, mm (diameter for a lathe's X).
    #[serde(default)]
    pub axes: Keyed<Compare>,
    /// Command positions, mm.
    #[serde(default)]
    pub command: Keyed<Compare>,
    /// Spindle speed, rpm (signed).
    #[serde(default)]
    pub spindle_rpm: Option<Compare>,
    /// Signal values.
    #[serde(default)]
    pub signals: Keyed<u8>,
    /// The phase.
    #[serde(default)]
    pub phase: Option<Spanned<String>>,
}

/// The end of the run.
#[derive(Debug, Deserialize, Clone, Default)]
#[serde(deny_unknown_fields)]
pub struct ExpectEnd {
    /// `program_end`, `alarm`, `reset`, `stopped`, `time_limit`.
    #[serde(default)]
    pub reason: Option<Spanned<String>>,
    /// End time, ms (± tolerance_ms).
    #[serde(default)]
    pub at_ms: Option<f64>,
    /// Tolerance for `at_ms`.
    #[serde(default)]
    pub tolerance_ms: Option<f64>,
    /// Active modal codes that must be among the end summary's.
    #[serde(default)]
    pub modal: Vec<String>,
    /// The final state.
    #[serde(default)]
    pub state: StateSpec,
}

/// A state check at a time or condition.
#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct Check {
    /// The rule id this check proves.
    pub rule: Spanned<String>,
    /// At this time, ms.
    #[serde(default)]
    pub at_ms: Option<f64>,
    /// When a condition first holds (the check uses the state after the same-time events).
    #[serde(default)]
    pub when: Option<Spanned<When>>,
    /// Extra delay, ms.
    #[serde(default)]
    pub delay_ms: Option<f64>,
    /// What must hold then.
    pub state: StateSpec,
}

/// A temporal rule: over the window (`while` holds, or from `after` on), `holds` must hold at
/// every observed instant, or the listed property must hold.
#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct TemporalRule {
    /// Rule id.
    pub rule: Spanned<String>,
    /// Window: while this state holds.
    #[serde(default, rename = "while")]
    pub while_: Option<StateSpec>,
    /// Window: from the first time this condition holds to the end.
    #[serde(default)]
    pub after: Option<Spanned<When>>,
    /// This state holds at every instant of the window.
    #[serde(default)]
    pub holds: Option<StateSpec>,
    /// These axes (machine position) do not move in the window.
    #[serde(default)]
    pub still: Vec<Spanned<String>>,
    /// The spindle does not turn in the window (speed 0, angle unchanged).
    #[serde(default)]
    pub spindle_still: bool,
    /// This axis never goes further than where it was when the window opened, in this direction
    /// (`{axis: Z, direction: down}`: never deeper).
    #[serde(default)]
    pub never_beyond: Option<NeverBeyond>,
    /// These signals never rise in the window.
    #[serde(default)]
    pub never_rises: Vec<Spanned<String>>,
}

/// "Never goes further" property.
#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct NeverBeyond {
    /// Axis letter.
    pub axis: Spanned<String>,
    /// `down` (never below the opening position) or `up`.
    pub direction: Spanned<String>,
}

/// Proof that a situation really occurred: `state` held at some instant (while `during` holds,
/// if given), or an input named `input` acted while `during` held.
#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct Reached {
    /// Rule id.
    pub rule: Spanned<String>,
    /// The state that must occur.
    #[serde(default)]
    pub state: Option<StateSpec>,
    /// An input (trace `input` name, e.g. `feed_hold`) that must have acted.
    #[serde(default)]
    pub input: Option<String>,
    /// ... while this held.
    #[serde(default)]
    pub during: Option<StateSpec>,
}

/// What the timing-diagram snapshot shows.
#[derive(Debug, Deserialize, Clone, Default)]
#[serde(deny_unknown_fields)]
pub struct SnapshotSpec {
    /// Signal rows, in order.
    #[serde(default)]
    pub signals: Vec<Spanned<String>>,
    /// Axis rows (machine position as a level graph), in order.
    #[serde(default)]
    pub axes: Vec<Spanned<String>>,
    /// A spindle speed row.
    #[serde(default)]
    pub spindle: bool,
    /// Columns of the diagram (default 100).
    #[serde(default)]
    pub width: Option<u32>,
    /// Time window, ms (default: the whole run).
    #[serde(default)]
    pub from_ms: Option<f64>,
    /// End of the window, ms.
    #[serde(default)]
    pub to_ms: Option<f64>,
}
