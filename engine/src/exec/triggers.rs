//! Inputs on conditions: each waits for its condition to begin to hold for the n-th time, then is
//! scheduled `delay` later. Signals, blocks, phases and functions are checked as they happen; an
//! axis crossing is found in closed form on the present motion, so it acts at its exact time.

use super::motion::Path;
use super::Exec;
use crate::input::{Condition, Input};
use crate::trace::Event;
use crate::units::Micros;

/// An input waiting for its condition.
#[derive(Debug, Clone)]
pub(super) struct Pending {
    pub cond: Condition,
    pub remaining: u32,
    pub delay_us: Micros,
    pub input: Input,
    /// The condition held at the last check (level conditions count transitions into it).
    pub was: bool,
}

impl Exec<'_> {
    /// Checks the waiting inputs against what just happened (`event`, or a time step when None).
    pub(super) fn check_triggers(&mut self, event: Option<&Event>) {
        if self.pending.is_empty() {
            return;
        }
        let mut fired = Vec::new();
        let mut k = 0;
        while k < self.pending.len() {
            let holds = self.condition_holds(&self.pending[k].cond, event);
            let p = &mut self.pending[k];
            let pulse = matches!(p.cond, Condition::Block { .. } | Condition::Function { .. });
            let counts = if pulse { holds } else { holds && !p.was };
            p.was = holds;
            if counts {
                p.remaining -= 1;
                if p.remaining == 0 {
                    let p = self.pending.remove(k);
                    fired.push((self.now + p.delay_us, p.input));
                    continue;
                }
            }
            k += 1;
        }
        for (t, input) in fired {
            let at = self.inputs[self.next_input..].iter().position(|(ti, _)| *ti > t);
            let at = at.map_or(self.inputs.len(), |i| self.next_input + i);
            self.inputs.insert(at, (t, input));
        }
    }

    fn condition_holds(&self, c: &Condition, event: Option<&Event>) -> bool {
        match c {
            Condition::Signal { signal, value } => self.signals.get(*signal) == *value,
            Condition::Phase(p) => self.phase == *p,
            Condition::Block { line } => matches!(event, Some(Event::Block { line: l, .. }) if l == line),
            Condition::Function { letter, code } => {
                matches!(event, Some(Event::Function { letter: l, code: c }) if l == letter && c == code)
            }
            Condition::AxisBelow { axis, nm } => self.reported_machine(self.now, *axis) < *nm,
            Condition::AxisAbove { axis, nm } => self.reported_machine(self.now, *axis) > *nm,
        }
    }

    /// Machine position of an axis in reported units (diameter for a lathe's X): what the trace's
    /// samples show, so that inputs and checks on the same condition agree.
    fn reported_machine(&self, t: Micros, axis: usize) -> i64 {
        let v = self.machine_pos(t)[axis];
        if axis == 0 && self.diameter_x {
            v * 2
        } else {
            v
        }
    }

    /// The first time after now at which a waiting axis condition begins to hold on the present
    /// motion.
    pub(super) fn next_axis_crossing(&self) -> Option<Micros> {
        let m = self.motion.as_ref()?;
        let mut best: Option<Micros> = None;
        for p in &self.pending {
            let (axis, below, nm) = match p.cond {
                Condition::AxisBelow { axis, nm } => (axis, true, nm),
                Condition::AxisAbove { axis, nm } => (axis, false, nm),
                _ => continue,
            };
            if p.was {
                continue;
            }
            let holds = |t: Micros| {
                let v = self.reported_machine(t, axis);
                if below {
                    v < nm
                } else {
                    v > nm
                }
            };
            let (start, end) = (self.now, m.end());
            let found = if matches!(m.path, Path::Arc { .. }) {
                // Not monotonic: step through the interpolation ticks.
                let step = self.cfg.period_us.max(1);
                (start / step + 1..=end / step).map(|k| k * step).find(|&t| holds(t))
            } else if holds(end) {
                let (mut lo, mut hi) = (start, end);
                while hi - lo > 1 {
                    let mid = lo + (hi - lo) / 2;
                    if holds(mid) {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                Some(hi)
            } else {
                None
            };
            if let Some(t) = found {
                best = Some(best.map_or(t, |b| b.min(t)));
            }
        }
        best
    }
}
