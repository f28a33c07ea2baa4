//! Observe: the trace, the time-ordered record of what the machine did.
//!
//! Owns the event types and the [`TraceSink`] door through which the executor reports them.
//! Serialising a trace (JSON Lines, VCD, diagrams) is the harness's job, not this module's.

use crate::alarm::Alarm;
use crate::units::{Micros, Nm};

/// Axis slots of the engine, in this order everywhere (`[Nm; AXES]` arrays).
pub const AXIS_LETTERS: [char; AXES] = ['X', 'Y', 'Z', 'A', 'B', 'C'];
/// How many axis slots the engine has.
pub const AXES: usize = 6;

/// Index of an axis letter in [`AXIS_LETTERS`].
pub fn axis_index(letter: char) -> Option<usize> {
    AXIS_LETTERS.iter().position(|&l| l == letter)
}

/// How one axis of a dialect is reported.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AxisSpec {
    /// Axis letter.
    pub letter: char,
    /// Slot in the position arrays.
    pub index: usize,
    /// Reported as a diameter (a lathe's X): the trace shows twice the physical position.
    pub diameter: bool,
    /// A rotary axis (degrees) rather than a linear one (mm).
    pub rotary: bool,
}

/// What the trace's reader needs to know before the first event.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TraceMeta {
    /// Dialect name.
    pub dialect: &'static str,
    /// The axes in a sample, in order.
    pub axes: Vec<AxisSpec>,
    /// Interpolation period in µs.
    pub period_us: Micros,
    /// Sample period in µs (0: no samples).
    pub sample_us: Micros,
}

/// A PLC interface signal (CNC ↔ PLC ↔ spindle drive).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Signal {
    /// M function strobe (CNC → PLC).
    Mf,
    /// S function strobe (CNC → PLC).
    Sf,
    /// T function strobe (CNC → PLC).
    Tf,
    /// Completion of an M/S/T function (PLC → CNC).
    Fin,
    /// F76.3 RTAP: rigid tapping in progress (CNC → PLC).
    Rtap,
    /// G61.0 RGTAP: rigid tapping mode (PLC → CNC).
    Rgtap,
    /// Position-mode request to the servo spindle (PLC → drive).
    Sppos,
    /// Position-mode reached (drive → PLC).
    Spposa,
    /// F65.0 RGSPP: spindle turning forward under rigid tapping (CNC → PLC).
    Rgspp,
    /// F65.1 RGSPM: spindle turning in reverse under rigid tapping (CNC → PLC).
    Rgspm,
    /// Feed hold lamp: automatic operation is held (CNC → PLC).
    Spl,
    /// Cycle start lamp: automatic operation in progress (CNC → PLC).
    Stl,
    /// Emergency stop input (PLC → CNC), 1 = stop requested.
    Esp,
    /// Spindle zero-speed detected (drive → PLC).
    Zsp,
}

impl Signal {
    /// Every signal, in a fixed order (for diagrams and VCD).
    pub const ALL: [Signal; 14] = [
        Signal::Mf,
        Signal::Sf,
        Signal::Tf,
        Signal::Fin,
        Signal::Rtap,
        Signal::Rgtap,
        Signal::Sppos,
        Signal::Spposa,
        Signal::Rgspp,
        Signal::Rgspm,
        Signal::Spl,
        Signal::Stl,
        Signal::Esp,
        Signal::Zsp,
    ];

    /// The name written in traces and scenarios.
    pub fn name(self) -> &'static str {
        match self {
            Signal::Mf => "MF",
            Signal::Sf => "SF",
            Signal::Tf => "TF",
            Signal::Fin => "FIN",
            Signal::Rtap => "F76.3",
            Signal::Rgtap => "RGTAP",
            Signal::Sppos => "SPPOS",
            Signal::Spposa => "SPPOSA",
            Signal::Rgspp => "RGSPP",
            Signal::Rgspm => "RGSPM",
            Signal::Spl => "SPL",
            Signal::Stl => "STL",
            Signal::Esp => "ESP",
            Signal::Zsp => "ZSP",
        }
    }

    /// Looks a signal up by its trace name (also accepts `RTAP`, `G61.0`, `F65.0`, `F65.1`).
    pub fn from_name(name: &str) -> Option<Signal> {
        let alias = match name {
            "RTAP" => Some(Signal::Rtap),
            "G61.0" => Some(Signal::Rgtap),
            "F65.0" => Some(Signal::Rgspp),
            "F65.1" => Some(Signal::Rgspm),
            _ => None,
        };
        alias.or_else(|| Signal::ALL.iter().copied().find(|s| s.name() == name))
    }

    /// Slot in a [`Signals`] bit set.
    pub fn bit(self) -> u32 {
        1 << (self as u32)
    }
}

/// The state of every signal as a bit set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Signals(pub u32);

impl Signals {
    /// Whether `s` is 1.
    pub fn get(self, s: Signal) -> bool {
        self.0 & s.bit() != 0
    }
    /// Sets `s`.
    pub fn set(&mut self, s: Signal, v: bool) {
        if v {
            self.0 |= s.bit();
        } else {
            self.0 &= !s.bit();
        }
    }
}

/// The phase of the machining the control is in: scenarios and diagrams key on it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Phase {
    /// Not in a cycle.
    Idle,
    /// Positioning to the hole or the R plane.
    Positioning,
    /// Tapping into the hole (including each peck's cut).
    Cutting,
    /// Dwell at the hole bottom.
    Dwell,
    /// Coming back out (each peck's retract and the final return).
    Retract,
    /// Retract forced by motor overload.
    OverloadRetract,
}

impl Phase {
    /// The name written in traces and scenarios.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Idle => "idle",
            Phase::Positioning => "positioning",
            Phase::Cutting => "cutting",
            Phase::Dwell => "dwell",
            Phase::Retract => "retract",
            Phase::OverloadRetract => "overload_retract",
        }
    }

    /// Looks a phase up by name.
    pub fn from_name(name: &str) -> Option<Phase> {
        [
            Phase::Idle,
            Phase::Positioning,
            Phase::Cutting,
            Phase::Dwell,
            Phase::Retract,
            Phase::OverloadRetract,
        ]
        .into_iter()
        .find(|p| p.name() == name)
    }
}

/// Positions and spindle state at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Sample {
    /// Machine positions as reported (diameter for a lathe's X), nm or nano-degrees, by slot.
    pub axes: [Nm; AXES],
    /// Spindle speed in milli-rpm, signed: + forward (M03), − reverse.
    pub spindle_mrpm: i64,
    /// Spindle angle in milli-degrees, 0 ≤ angle < 360 000.
    pub spindle_mdeg: i64,
}

/// How the program ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum EndReason {
    /// M02 / M30 or the last block.
    ProgramEnd,
    /// Stopped on an alarm.
    Alarm,
    /// Stopped by reset and nothing restarted it.
    Reset,
    /// Held (feed hold, single block, M00) with no cycle start to go on.
    Stopped,
    /// The run's time limit was reached.
    TimeLimit,
    /// The trace sink asked the run to stop ([`TraceSink::wants_stop`]): the harness's output
    /// budget was spent.
    OutputLimit,
}

impl EndReason {
    /// The name written in traces.
    pub fn name(&self) -> &'static str {
        match self {
            EndReason::ProgramEnd => "program_end",
            EndReason::Alarm => "alarm",
            EndReason::Reset => "reset",
            EndReason::Stopped => "stopped",
            EndReason::TimeLimit => "time_limit",
            EndReason::OutputLimit => "output_limit",
        }
    }
}

/// The final state of a run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EndSummary {
    /// Why the run ended.
    pub reason: EndReason,
    /// Final machine positions and spindle state.
    pub state: Sample,
    /// Final command (program) positions in reported units, by slot (these advance under
    /// machine lock while the machine does not move).
    pub command: [Nm; AXES],
    /// Final signal states.
    pub signals: Signals,
    /// Active modal G codes, e.g. `["G00", "G17", "G90", "G94", "G98", "G21"]`.
    pub modal: Vec<String>,
    /// Number of alarms raised.
    pub alarms: u32,
    /// Number of blocks executed.
    pub blocks: u32,
}

/// One thing that happened.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Event {
    /// Periodic sample.
    Sample(Sample),
    /// A signal edge.
    Signal {
        /// Which signal.
        signal: Signal,
        /// Its new value.
        value: bool,
    },
    /// A block starts executing.
    Block {
        /// 1-based source line.
        line: u32,
        /// Source text.
        text: String,
    },
    /// An M, S or T function is output.
    Function {
        /// `M`, `S` or `T`.
        letter: char,
        /// Its number.
        code: u32,
    },
    /// An alarm.
    Alarm(Alarm),
    /// The machining phase changed.
    Phase(Phase),
    /// An operator input or fault took effect (name as in scenarios, e.g. `feed_hold`).
    Input {
        /// What acted.
        name: String,
        /// Its value as text (`on`, `off`, `120%`, ...).
        value: String,
    },
    /// The last event (boxed: it is written once, and every sample moved or kept is the size
    /// of the largest event).
    End(Box<EndSummary>),
}

/// An event with its time.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TraceEvent {
    /// Microseconds since the start.
    pub t_us: Micros,
    /// What happened.
    pub event: Event,
}

/// Receives the trace as it is produced (streaming: the engine keeps nothing).
pub trait TraceSink {
    /// Called once before the first event.
    fn start(&mut self, _meta: &TraceMeta) {}
    /// Called for every event, in time order.
    fn event(&mut self, ev: &TraceEvent);
    /// True when the sink wants no more events: the run then stops at once with end reason
    /// `output_limit` (the `End` event is still written). Default: never.
    fn wants_stop(&self) -> bool {
        false
    }
}

/// A whole trace in memory.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Trace {
    /// Header.
    pub meta: TraceMeta,
    /// Every event in order; the last is `End`.
    pub events: Vec<TraceEvent>,
}

impl Trace {
    /// The end summary (every finished trace has one).
    pub fn end(&self) -> Option<&EndSummary> {
        match self.events.last().map(|e| &e.event) {
            Some(Event::End(s)) => Some(s),
            _ => None,
        }
    }

    /// The alarms, in order.
    pub fn alarms(&self) -> impl Iterator<Item = (Micros, &Alarm)> {
        self.events.iter().filter_map(|e| match &e.event {
            Event::Alarm(a) => Some((e.t_us, a)),
            _ => None,
        })
    }

    /// The samples, in order.
    pub fn samples(&self) -> impl Iterator<Item = (Micros, &Sample)> {
        self.events.iter().filter_map(|e| match &e.event {
            Event::Sample(s) => Some((e.t_us, s)),
            _ => None,
        })
    }

    /// The edges of one signal, in order.
    pub fn edges(&self, sig: Signal) -> impl Iterator<Item = (Micros, bool)> + '_ {
        self.events.iter().filter_map(move |e| match e.event {
            Event::Signal { signal, value } if signal == sig => Some((e.t_us, value)),
            _ => None,
        })
    }

    /// The M/S/T functions, in order.
    pub fn functions(&self) -> impl Iterator<Item = (Micros, char, u32)> + '_ {
        self.events.iter().filter_map(|e| match e.event {
            Event::Function { letter, code } => Some((e.t_us, letter, code)),
            _ => None,
        })
    }

    /// The phase changes, in order.
    pub fn phases(&self) -> impl Iterator<Item = (Micros, Phase)> + '_ {
        self.events.iter().filter_map(|e| match e.event {
            Event::Phase(p) => Some((e.t_us, p)),
            _ => None,
        })
    }
}

/// A sink that keeps everything (tests, small runs).
#[derive(Debug, Default)]
pub struct VecSink {
    /// Header, once started.
    pub meta: Option<TraceMeta>,
    /// Events so far.
    pub events: Vec<TraceEvent>,
}

impl TraceSink for VecSink {
    fn start(&mut self, meta: &TraceMeta) {
        self.meta = Some(meta.clone());
    }
    fn event(&mut self, ev: &TraceEvent) {
        self.events.push(ev.clone());
    }
}

impl VecSink {
    /// The finished trace.
    pub fn into_trace(self) -> Trace {
        Trace {
            meta: self.meta.unwrap_or(TraceMeta {
                dialect: "",
                axes: Vec::new(),
                period_us: 0,
                sample_us: 0,
            }),
            events: self.events,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sample event is moved and copied for every sample of every run (sinks, batches, the
    /// check's kept events): the end summary, three times a sample's size, is not inline.
    #[test]
    fn a_trace_event_is_a_sample_and_little_more() {
        assert!(std::mem::size_of::<EndSummary>() > 2 * std::mem::size_of::<Sample>());
        assert!(
            std::mem::size_of::<TraceEvent>() <= std::mem::size_of::<Sample>() + 16,
            "{} bytes",
            std::mem::size_of::<TraceEvent>()
        );
    }
}
