//! The PLC ladder and spindle drive model: answers to the CNC's strobes and rigid tapping
//! signals after configurable delays, timers that raise the PLC alarms, and the faults (late or
//! missing answers) that scenarios inject.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use super::config::PlcConfig;
use crate::input::PlcAnswer;
use crate::trace::Signal;
use crate::units::Micros;

/// Something the PLC or drive does at a time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum PlcAction {
    /// A signal edge.
    Set(Signal, bool),
    /// The M29 answer timer of strobe `n` ran out.
    M29Timer(u64),
    /// The FIN timer of strobe `n` ran out.
    FinTimer(u64),
    /// The stalled-spindle timer ran out.
    StallTimer,
    /// The tap axis ran ahead of a stalled spindle by the excess-error limit.
    ExcessError,
    /// The CNC's timer of wait `n` (`Step::AwaitSignal`) ran out: raise the alarm.
    AwaitTimer(u64, crate::alarm::AlarmKind),
    /// The spindle's ramp to a stop ends: the drive reports zero speed if it is still stopped.
    ZeroSpeed,
}

/// The ladder's pending actions and injected faults.
#[derive(Debug)]
pub struct Plc {
    /// Timing.
    pub cfg: PlcConfig,
    queue: BinaryHeap<Reverse<(Micros, u64, PlcAction)>>,
    seq: u64,
    /// Serial number of the present strobe.
    pub strobe_no: u64,
    /// Extra delay per answer: `Some(None)` = never answers.
    faults: [Option<Option<Micros>>; 4],
}

fn slot(a: PlcAnswer) -> usize {
    match a {
        PlcAnswer::PositionModeReached => 0,
        PlcAnswer::Fin => 1,
        PlcAnswer::Rgtap => 2,
        PlcAnswer::ZeroSpeed => 3,
    }
}

impl Plc {
    /// A ladder with no faults.
    pub fn new(cfg: PlcConfig) -> Plc {
        Plc { cfg, queue: BinaryHeap::new(), seq: 0, strobe_no: 0, faults: [None; 4] }
    }

    /// Injects a fault: answer `a` comes `extra` µs late, or never (`None`).
    pub fn set_fault(&mut self, a: PlcAnswer, extra: Option<Micros>) {
        self.faults[slot(a)] = Some(extra);
    }

    /// Schedules `action` at `t`.
    pub fn at(&mut self, t: Micros, action: PlcAction) {
        self.seq += 1;
        self.queue.push(Reverse((t, self.seq, action)));
    }

    /// Schedules an answer after `delay`, honouring its fault.
    pub fn answer(&mut self, now: Micros, delay: Micros, a: PlcAnswer, action: PlcAction) {
        match self.faults[slot(a)] {
            None => self.at(now + delay, action),
            Some(Some(extra)) => self.at(now + delay + extra, action),
            Some(None) => {}
        }
    }

    /// Time of the next action.
    pub fn next_time(&self) -> Option<Micros> {
        self.queue.peek().map(|Reverse((t, _, _))| *t)
    }

    /// The next action due at or before `t`.
    pub fn pop_due(&mut self, t: Micros) -> Option<PlcAction> {
        match self.queue.peek() {
            Some(Reverse((at, _, _))) if *at <= t => self.queue.pop().map(|Reverse((_, _, a))| a),
            _ => None,
        }
    }

    /// Drops every pending action (reset, emergency stop).
    pub fn clear(&mut self) {
        self.queue.clear();
    }

    /// The CNC raised an M/S/T strobe.
    pub fn strobe(&mut self, now: Micros, fin_us: Micros) {
        self.strobe_no += 1;
        let n = self.strobe_no;
        self.answer(now, fin_us, PlcAnswer::Fin, PlcAction::Set(Signal::Fin, true));
        self.at(now + self.cfg.fin_timeout_us, PlcAction::FinTimer(n));
    }

    /// The CNC dropped its strobe: FIN falls after the ladder's delay.
    pub fn strobe_dropped(&mut self, now: Micros) {
        self.at(now + self.cfg.fin_fall_us, PlcAction::Set(Signal::Fin, false));
    }

    /// M29: the ladder asks the drive for position mode.
    pub fn rigid_strobe(&mut self, now: Micros) {
        self.strobe_no += 1;
        self.at(now + self.cfg.sppos_request_us, PlcAction::Set(Signal::Sppos, true));
    }

    /// F76.3 fell: RGTAP and the position-mode request drop.
    pub fn rigid_exit(&mut self, now: Micros) {
        self.at(now + self.cfg.rgtap_fall_us, PlcAction::Set(Signal::Rgtap, false));
        self.at(now + self.cfg.rgtap_fall_us, PlcAction::Set(Signal::Sppos, false));
    }

    /// The drive or ladder reacts to an edge it sees. `spindle_rest` is when the spindle's
    /// present ramp to a stop ends (or `now` when it stands): the drive reports position mode
    /// `sppos_reach_us` after SPPOS, but never before the spindle has come down at its ramp and
    /// switched to position control (seed 000's timing chart; issue 12: it used to answer while
    /// the spindle still turned at 2604 rpm). The M29 timer still counts from SPPOS.
    pub fn react(&mut self, now: Micros, sig: Signal, v: bool, rtap: bool, spindle_rest: Micros) {
        match (sig, v) {
            (Signal::Sppos, true) => {
                self.answer(
                    now,
                    spindle_rest.saturating_sub(now).max(self.cfg.sppos_reach_us),
                    PlcAnswer::PositionModeReached,
                    PlcAction::Set(Signal::Spposa, true),
                );
                self.at(now + self.cfg.m29_timeout_us, PlcAction::M29Timer(self.strobe_no));
            }
            (Signal::Sppos, false) => {
                self.at(now + self.cfg.sppos_reach_us, PlcAction::Set(Signal::Spposa, false))
            }
            (Signal::Spposa, true) if rtap => {
                self.answer(now, self.cfg.rgtap_us, PlcAnswer::Rgtap, PlcAction::Set(Signal::Rgtap, true));
                self.answer(now, self.cfg.rgtap_us, PlcAnswer::Fin, PlcAction::Set(Signal::Fin, true));
            }
            _ => {}
        }
    }
}
