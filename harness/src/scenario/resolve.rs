//! Turning the names a scenario file writes (signals, axes, phases, conditions) into engine
//! values, with an error located at the offending text when they are wrong.

use nc_engine::input::Condition;
use nc_engine::trace::{AxisSpec, Phase, Signal};
use nc_engine::units::{Micros, Nm};
use serde_saphyr::Spanned;

use super::schema::When;
use crate::diag::{InputError, Span};
use crate::params_yaml::span_of;

/// What resolution needs: the file (for locations) and the dialect's axes.
#[derive(Debug, Clone)]
pub struct Ctx<'a> {
    /// The file as the user named it.
    pub file: &'a str,
    /// Its text.
    pub text: &'a str,
    /// The dialect's axes.
    pub axes: &'a [AxisSpec],
}

impl Ctx<'_> {
    /// Where a spanned value was written.
    pub fn span<T>(&self, s: &Spanned<T>) -> Span {
        span_of(self.text, &s.referenced)
    }

    /// An error at a spanned value.
    pub fn err<T>(
        &self,
        at: &Spanned<T>,
        message: impl Into<String>,
        expected: impl Into<String>,
    ) -> InputError {
        InputError::at(self.file, self.text, self.span(at), message, Some(expected.into()))
    }

    /// A signal name.
    pub fn signal(&self, s: &Spanned<String>) -> Result<Signal, InputError> {
        Signal::from_name(&s.value).ok_or_else(|| {
            let names: Vec<&str> = Signal::ALL.iter().map(|s| s.name()).collect();
            self.err(s, format!("unknown signal `{}`", s.value), format!("one of {}", names.join(", ")))
        })
    }

    /// An axis letter of the dialect.
    pub fn axis(&self, s: &Spanned<String>) -> Result<AxisSpec, InputError> {
        let found =
            self.axes.iter().find(|a| s.value.len() == 1 && a.letter.to_string() == s.value.to_uppercase());
        found.copied().ok_or_else(|| {
            let letters: Vec<String> = self.axes.iter().map(|a| a.letter.to_string()).collect();
            self.err(
                s,
                format!("`{}` is not an axis of this dialect", s.value),
                format!("one of {}", letters.join(" ")),
            )
        })
    }

    /// A phase name.
    pub fn phase(&self, s: &Spanned<String>) -> Result<Phase, InputError> {
        Phase::from_name(&s.value).ok_or_else(|| {
            self.err(
                s,
                format!("unknown phase `{}`", s.value),
                "one of idle, positioning, cutting, dwell, retract, overload_retract",
            )
        })
    }

    /// A condition, its occurrence (from 1) and the extra delay.
    pub fn condition(
        &self,
        w: &Spanned<When>,
        delay_ms: Option<f64>,
    ) -> Result<(Condition, u32, Micros), InputError> {
        let c = &w.value;
        let kinds = [
            c.signal.is_some(),
            c.axis.is_some(),
            c.block.is_some(),
            c.phase.is_some(),
            c.function.is_some(),
        ];
        if kinds.iter().filter(|k| **k).count() != 1 {
            return Err(self.err(
                w,
                "a condition names exactly one of signal, axis, block, phase, function",
                "e.g. `{signal: RGTAP, value: 1}`, `{axis: Z, below: -10}`, `{block: 5}`, `{phase: cutting}`, `{function: M29}`",
            ));
        }
        let cond = if let Some(s) = &c.signal {
            let value = match c.value {
                Some(0) => false,
                Some(1) => true,
                _ => {
                    return Err(self.err(
                        w,
                        "a signal condition needs `value: 0` or `value: 1`",
                        "value: 0 or 1",
                    ))
                }
            };
            Condition::Signal { signal: self.signal(s)?, value }
        } else if let Some(a) = &c.axis {
            let spec = self.axis(a)?;
            match (c.below, c.above) {
                (Some(v), None) => Condition::AxisBelow { axis: spec.index, nm: mm_to_nm(v) },
                (None, Some(v)) => Condition::AxisAbove { axis: spec.index, nm: mm_to_nm(v) },
                _ => {
                    return Err(self.err(
                        w,
                        "an axis condition needs one of `below` or `above` (mm)",
                        "below: -10",
                    ))
                }
            }
        } else if let Some(line) = c.block {
            Condition::Block { line }
        } else if let Some(p) = &c.phase {
            Condition::Phase(self.phase(p)?)
        } else {
            let f = c.function.as_ref().unwrap();
            let mut chars = f.value.chars();
            let letter = chars.next().map(|l| l.to_ascii_uppercase());
            match (letter, chars.as_str().parse::<u32>()) {
                (Some(l @ ('M' | 'S' | 'T')), Ok(code)) => Condition::Function { letter: l, code },
                _ => {
                    return Err(self.err(
                        f,
                        format!("`{}` is not an M, S or T function", f.value),
                        "e.g. M29, S1000, T2",
                    ))
                }
            }
        };
        let occurrence = c.occurrence.unwrap_or(1);
        if occurrence == 0 {
            return Err(self.err(w, "occurrence counts from 1", "occurrence: 1 or more"));
        }
        Ok((cond, occurrence, ms_to_us(delay_ms.unwrap_or(0.0))))
    }
}

/// mm (as written, reported units) to nm.
pub fn mm_to_nm(mm: f64) -> Nm {
    (mm * 1e6).round() as Nm
}

/// ms (decimals allowed) to µs; negative values count as 0.
pub fn ms_to_us(ms: f64) -> Micros {
    if ms.is_finite() && ms > 0.0 {
        (ms * 1000.0).round() as Micros
    } else {
        0
    }
}
