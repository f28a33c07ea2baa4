//! Parameter files: machine parameter values in YAML (`--params FILE.yaml`).
//!
//! The format (documented in `docs/parameters-format.md`):
//!
//! ```yaml
//! params:
//!   170: 68            # a number
//!   "186.2": 1         # a bit (quoted or not: 186.2 reads the same)
//!   34: {X: 0.01, Z: 0.005}   # one value per axis
//! ```
//!
//! The top level is a mapping with the key `params` and, optionally, `dialect` (the dialect whose
//! parameters these are: a file written for one machine is refused on another's dialect; any
//! other key is an error); `params` maps parameter ids to a number (`true`/`false` read as 1/0)
//! or to a mapping of axis letter to number. Every error carries the line and column of the key
//! or value at fault.

use std::fmt;

use nc_engine::trace::axis_index;
use nc_engine::Machine;
use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::Deserialize;
use serde_saphyr::{Location, Spanned};

use crate::diag::Span;

/// One parameter value from the file, with where it was written.
#[derive(Debug, Clone, PartialEq)]
pub struct Setting {
    /// Parameter id as written (`170`, `186.2`, `nc.period_us`).
    pub id: String,
    /// The axis, for a per-axis value.
    pub axis: Option<char>,
    /// The value.
    pub value: f64,
    /// Where the id was written.
    pub id_span: Span,
    /// Where the axis letter was written (per-axis values only).
    pub axis_span: Option<Span>,
    /// Where the value was written.
    pub value_span: Span,
}

/// An error in a parameter file: where, what is wrong, what would have been accepted.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParamsFileError {
    /// Where in the file.
    pub span: Span,
    /// What is wrong.
    pub message: String,
    /// What would have been accepted.
    pub expected: Option<String>,
}

impl fmt::Display for ParamsFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}: {}", self.span.line, self.span.col, self.message)?;
        if let Some(e) = &self.expected {
            write!(f, "; expected {e}")?;
        }
        Ok(())
    }
}

impl std::error::Error for ParamsFileError {}

/// Reads the settings of a parameter file, in the order written. An empty file (or one with an
/// empty `params:`) has none.
///
/// # Errors
///
/// YAML syntax errors, unknown top-level keys, ids or axes that are not strings or numbers, and
/// values that are not numbers, with their location.
pub fn parse(text: &str) -> Result<Vec<Setting>, ParamsFileError> {
    parse_file(text).map(|f| f.settings)
}

/// A parameter file read whole: the dialect it names, if any, and its settings.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ParamsFile {
    /// `dialect:` as written, with where: the only dialect the file may be applied to.
    pub dialect: Option<(String, Span)>,
    /// The settings, in the order written.
    pub settings: Vec<Setting>,
}

impl ParamsFile {
    /// Whether the file may be applied to a machine of `dialect` (it names none, or that one).
    pub fn fits(&self, dialect: &str) -> bool {
        self.dialect.as_ref().is_none_or(|(d, _)| d == dialect)
    }
}

/// [`parse`], with the `dialect:` the file names.
///
/// # Errors
///
/// As [`parse`]; also a `dialect` that is not one of the engine's.
pub fn parse_file(text: &str) -> Result<ParamsFile, ParamsFileError> {
    if text.trim().is_empty() {
        return Ok(ParamsFile::default());
    }
    // YAML 1.2 booleans only: `Y` and `N` are axis letters, not yes and no.
    let options = serde_saphyr::options! { strict_booleans: true, with_snippet: false };
    let file: File = serde_saphyr::from_str_with_options(text, options).map_err(|e| yaml_error(text, &e))?;
    let dialect = match file.dialect {
        None => None,
        Some(d) => {
            let span = span_of(text, &d.referenced);
            if !nc_engine::dialect_names().contains(&d.value.as_str()) {
                return Err(ParamsFileError {
                    span,
                    message: format!("unknown dialect `{}`", d.value),
                    expected: Some(format!("one of {}", nc_engine::dialect_names().join(", "))),
                });
            }
            Some((d.value, span))
        }
    };
    Ok(ParamsFile { dialect, settings: settings_from(text, file.params.unwrap_or_default())? })
}

/// The settings of a `params` mapping read as part of a larger YAML file (`text` is that file).
///
/// # Errors
///
/// An axis key that is not one letter.
pub fn settings_from(text: &str, entries: ParamEntries) -> Result<Vec<Setting>, ParamsFileError> {
    let mut out = Vec::new();
    for (key, value) in entries.0 {
        let id_span = span_of(text, &key.referenced);
        let id = key.value.written(text, id_span);
        match value.value {
            Value::Scalar(v) => out.push(Setting {
                id,
                axis: None,
                value: v,
                id_span,
                axis_span: None,
                value_span: span_of(text, &value.referenced),
            }),
            Value::PerAxis(entries) => {
                for (axis_key, v) in entries {
                    let axis_span = span_of(text, &axis_key.referenced);
                    let letter = axis_key.value.written(text, axis_span);
                    let mut chars = letter.chars();
                    let axis = match (chars.next(), chars.next()) {
                        (Some(c), None) => c.to_ascii_uppercase(),
                        _ => {
                            return Err(ParamsFileError {
                                span: axis_span,
                                message: format!("`{letter}` is not an axis letter"),
                                expected: Some("one axis letter (X Y Z A B C)".into()),
                            })
                        }
                    };
                    out.push(Setting {
                        id: id.clone(),
                        axis: Some(axis),
                        value: v.value.0,
                        id_span,
                        axis_span: Some(axis_span),
                        value_span: span_of(text, &v.referenced),
                    });
                }
            }
        }
    }
    Ok(out)
}

/// Reads a parameter file and sets each value on `machine`, in the order written.
///
/// # Errors
///
/// The first error: a [`parse`] error, or a value the machine's parameter table refuses (unknown
/// id, out of range, per-axis mismatch, an axis the dialect does not have), located at the id
/// for an unknown id, at the axis letter for a bad axis, else at the value.
pub fn apply(text: &str, machine: &mut Machine) -> Result<usize, ParamsFileError> {
    let file = parse_file(text)?;
    if let Some((d, span)) = &file.dialect {
        if !file.fits(machine.dialect.name()) {
            return Err(ParamsFileError {
                span: *span,
                message: format!(
                    "these are parameters of dialect {d}, not of dialect {}",
                    machine.dialect.name()
                ),
                expected: Some(format!("`dialect: {}` or no `dialect` key", machine.dialect.name())),
            });
        }
    }
    apply_settings(&file.settings, machine)
}

/// Sets each value on `machine`, in order, with [`apply`]'s checks and error locations.
///
/// # Errors
///
/// As [`apply`].
pub fn apply_settings(settings: &[Setting], machine: &mut Machine) -> Result<usize, ParamsFileError> {
    for s in settings {
        let def = machine.params.def(&s.id);
        if let (Some(def), Some(axis), Some(axis_span)) = (def, s.axis, s.axis_span) {
            let axes = machine.dialect.axes();
            if def.per_axis && !axes.iter().any(|a| a.letter == axis) {
                let letters: Vec<String> = axes.iter().map(|a| a.letter.to_string()).collect();
                return Err(ParamsFileError {
                    span: axis_span,
                    message: format!("`{axis}` is not an axis of dialect {}", machine.dialect.name()),
                    expected: Some(format!("one of {}", letters.join(" "))),
                });
            }
        }
        if let Err(e) = machine.params.set(&s.id, s.axis, s.value) {
            let span = match (def, s.axis, s.axis_span) {
                (None, _, _) => s.id_span,
                (Some(_), Some(a), Some(axis_span)) if axis_index(a).is_none() => axis_span,
                _ => s.value_span,
            };
            return Err(ParamsFileError { span, message: e.message, expected: Some(e.expected) });
        }
    }
    Ok(settings.len())
}

/// A saphyr location as a [`Span`] of `text`.
pub(crate) fn span_of(text: &str, loc: &Location) -> Span {
    let line = u32::try_from(loc.line()).unwrap_or(u32::MAX).max(1);
    let col = u32::try_from(loc.column()).unwrap_or(u32::MAX).max(1);
    let span = loc.span();
    match (span.byte_offset(), span.byte_len()) {
        (Some(off), Some(len)) if (off + len) as usize <= text.len() => {
            Span { line, col, offset: off as usize, len: len as usize }
        }
        _ => Span::from_line_col(text, line, col, u32::try_from(span.len()).unwrap_or(1).max(1)),
    }
}

/// A saphyr error with its location (start of the file when it has none).
pub(crate) fn yaml_error(text: &str, e: &serde_saphyr::Error) -> ParamsFileError {
    let loc = e.location();
    let span = match &loc {
        Some(l) if l.line() > 0 => span_of(text, l),
        _ => Span::from_line_col(text, 1, 1, 1),
    };
    let mut message = e.without_snippet().to_string();
    // The message ends with the location, which the caller writes in front of it.
    let suffix = format!(" at line {}, column {}", span.line, span.col);
    if let Some(m) = message.strip_suffix(&suffix) {
        message = m.to_string();
    }
    let message = format!("invalid parameter file: {}", crate::diag::yaml_wording(&message));
    ParamsFileError { span, message, expected: None }
}

/// The whole file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    #[serde(default)]
    dialect: Option<Spanned<String>>,
    #[serde(default)]
    params: Option<ParamEntries>,
}

/// The `params` mapping, in the order written.
/// A `params` mapping as written: ids (numbers or strings) to a number or a per-axis mapping.
#[derive(Debug, Default)]
pub struct ParamEntries(Vec<(Spanned<Key>, Spanned<Value>)>);

impl<'de> Deserialize<'de> for ParamEntries {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = ParamEntries;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a mapping of parameter id to value")
            }
            fn visit_unit<E: de::Error>(self) -> Result<ParamEntries, E> {
                Ok(ParamEntries::default())
            }
            fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<ParamEntries, A::Error> {
                let mut v = Vec::new();
                while let Some(k) = m.next_key::<Spanned<Key>>()? {
                    v.push((k, m.next_value::<Spanned<Value>>()?));
                }
                Ok(ParamEntries(v))
            }
        }
        d.deserialize_map(V)
    }
}

/// A parameter id or axis letter: a string, or a number (whose text is then taken from the
/// source, so that `3401.0` stays `3401.0`).
#[derive(Debug)]
struct Key {
    text: String,
    numeric: bool,
}

impl Key {
    /// The id as written: the source text for a number, else the string.
    fn written(self, text: &str, span: Span) -> String {
        match text.get(span.offset..span.offset + span.len) {
            Some(raw) if self.numeric && !raw.trim().is_empty() => raw.trim().to_string(),
            _ => self.text,
        }
    }
}

impl<'de> Deserialize<'de> for Key {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Key;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a parameter id or axis letter")
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<Key, E> {
                Ok(Key { text: s.to_string(), numeric: false })
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Key, E> {
                Ok(Key { text: v.to_string(), numeric: true })
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Key, E> {
                Ok(Key { text: v.to_string(), numeric: true })
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Key, E> {
                Ok(Key { text: v.to_string(), numeric: true })
            }
        }
        d.deserialize_any(V)
    }
}

/// A parameter's value: one number, or one per axis.
#[derive(Debug)]
enum Value {
    Scalar(f64),
    PerAxis(Vec<(Spanned<Key>, Spanned<Number>)>),
}

/// A number (`true`/`false` read as 1/0).
#[derive(Debug)]
struct Number(f64);

struct NumberVisitor;

impl Visitor<'_> for NumberVisitor {
    type Value = f64;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a number")
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<f64, E> {
        Ok(v as f64)
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<f64, E> {
        Ok(v as f64)
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<f64, E> {
        Ok(v)
    }
    fn visit_bool<E: de::Error>(self, v: bool) -> Result<f64, E> {
        Ok(f64::from(u8::from(v)))
    }
}

impl<'de> Deserialize<'de> for Number {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(NumberVisitor).map(Number)
    }
}

impl<'de> Deserialize<'de> for Value {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Value;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number or a mapping of axis letter to number")
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Value, E> {
                NumberVisitor.visit_u64(v).map(Value::Scalar)
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Value, E> {
                NumberVisitor.visit_i64(v).map(Value::Scalar)
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Value, E> {
                NumberVisitor.visit_f64(v).map(Value::Scalar)
            }
            fn visit_bool<E: de::Error>(self, v: bool) -> Result<Value, E> {
                NumberVisitor.visit_bool(v).map(Value::Scalar)
            }
            fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<Value, A::Error> {
                let mut v = Vec::new();
                while let Some(k) = m.next_key::<Spanned<Key>>()? {
                    v.push((k, m.next_value::<Spanned<Number>>()?));
                }
                Ok(Value::PerAxis(v))
            }
        }
        d.deserialize_any(V)
    }
}

#[cfg(test)]
#[path = "params_yaml_tests.rs"]
mod tests;
