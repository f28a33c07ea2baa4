//! The column map: a YAML file that says how the columns of a CSV export (or the keys of an
//! MTConnect SHDR stream) become samples and signal edges (`docs/checking.md`).
//!
//! Read with serde + serde-saphyr: unknown keys are refused, and every error carries the line and
//! column of the key or value at fault, like parameter and scenario files.

use nc_engine::trace::{axis_index, AxisSpec, Signal};
use serde::Deserialize;
use serde_saphyr::Spanned;

use crate::diag::InputError;
use crate::params_yaml::{span_of, yaml_error};

/// Where a value is: a header name, or a 1-based column number.
#[derive(Debug, Clone, PartialEq)]
pub enum ColRef {
    /// A column by its header name (or an SHDR key).
    Name(String),
    /// A column by its 1-based position.
    Index(usize),
}

impl std::fmt::Display for ColRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ColRef::Name(n) => write!(f, "`{n}`"),
            ColRef::Index(i) => write!(f, "column {i}"),
        }
    }
}

/// A numeric column: the value read is `raw × scale + offset`.
#[derive(Debug, Clone, PartialEq)]
pub struct ValueMap {
    /// The column.
    pub column: ColRef,
    /// Multiplier.
    pub scale: f64,
    /// Added after the multiplier.
    pub offset: f64,
}

/// The time column: `(raw × scale + offset)` in `unit`, turned into µs.
#[derive(Debug, Clone, PartialEq)]
pub struct TimeMap {
    /// The column and its scale and offset.
    pub value: ValueMap,
    /// µs per unit (`s` 1e6, `ms` 1e3, `us` 1, `ns` 1e-3).
    pub us_per_unit: f64,
}

/// An axis position column, in mm (degrees for A/B/C) after scale and offset.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisMap {
    /// The axis (slot, diameter, rotary).
    pub axis: AxisSpec,
    /// The column.
    pub value: ValueMap,
}

/// How a column gives a signal's level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Level {
    /// Not zero: 1.
    NonZero,
    /// Bit `n` (0: least significant) of an integer column.
    Bit(u32),
    /// 1 when the value (after scale and offset) is above the threshold.
    Above(f64),
    /// 1 when the value (after scale and offset) is below the threshold.
    Below(f64),
}

/// A signal column.
#[derive(Debug, Clone, PartialEq)]
pub struct SignalMap {
    /// Which signal.
    pub signal: Signal,
    /// The column and its scale and offset (for thresholds).
    pub value: ValueMap,
    /// How the level is read.
    pub level: Level,
    /// The level is inverted (active low).
    pub invert: bool,
}

/// A whole column map.
#[derive(Debug, Clone, PartialEq)]
pub struct ColumnMap {
    /// Field delimiter.
    pub delimiter: u8,
    /// Lines to skip before the header (or before the data, without a header).
    pub skip_rows: u64,
    /// Whether the first line after the skipped ones names the columns.
    pub header: bool,
    /// The time column.
    pub time: Option<TimeMap>,
    /// Axis columns.
    pub axes: Vec<AxisMap>,
    /// Spindle speed column (rpm, signed).
    pub rpm: Option<ValueMap>,
    /// Spindle angle column (degrees).
    pub angle: Option<ValueMap>,
    /// Signal columns.
    pub signals: Vec<SignalMap>,
    /// Columns (or SHDR keys) that are read and ignored; any other unmapped column is an error.
    pub ignore: Vec<String>,
}

#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum RawCol {
    Index(u64),
    Name(String),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawValue {
    column: Spanned<RawCol>,
    #[serde(default)]
    scale: Option<f64>,
    #[serde(default)]
    offset: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTime {
    column: Spanned<RawCol>,
    #[serde(default)]
    unit: Option<Spanned<String>>,
    #[serde(default)]
    scale: Option<f64>,
    #[serde(default)]
    offset: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawAxis {
    axis: Spanned<String>,
    column: Spanned<RawCol>,
    #[serde(default)]
    scale: Option<f64>,
    #[serde(default)]
    offset: Option<f64>,
    #[serde(default)]
    diameter: bool,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSpindle {
    #[serde(default)]
    rpm: Option<RawValue>,
    #[serde(default)]
    angle_deg: Option<RawValue>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSignal {
    signal: Spanned<String>,
    column: Spanned<RawCol>,
    #[serde(default)]
    bit: Option<Spanned<u32>>,
    #[serde(default)]
    above: Option<f64>,
    #[serde(default)]
    below: Option<f64>,
    #[serde(default)]
    scale: Option<f64>,
    #[serde(default)]
    offset: Option<f64>,
    #[serde(default)]
    invert: bool,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMap {
    #[serde(default)]
    delimiter: Option<Spanned<String>>,
    #[serde(default)]
    skip_rows: u64,
    #[serde(default)]
    header: Option<bool>,
    #[serde(default)]
    time: Option<RawTime>,
    #[serde(default)]
    axes: Vec<RawAxis>,
    #[serde(default)]
    spindle: Option<RawSpindle>,
    #[serde(default)]
    signals: Vec<RawSignal>,
    #[serde(default)]
    ignore: Vec<String>,
}

impl ColumnMap {
    /// Reads a column map file.
    ///
    /// # Errors
    ///
    /// The file cannot be read, or an error of [`ColumnMap::from_yaml`].
    pub fn load(path: &std::path::Path) -> Result<ColumnMap, InputError> {
        let name = path.display().to_string();
        let text = crate::input::read_utf8(path, crate::input::YAML)?;
        ColumnMap::from_yaml(&name, &text)
    }

    /// Parses a column map; `name` names the file in errors.
    ///
    /// # Errors
    ///
    /// YAML errors, unknown keys, unknown axis or signal names, a bad delimiter or time unit,
    /// with their line and column.
    pub fn from_yaml(name: &str, text: &str) -> Result<ColumnMap, InputError> {
        let options = serde_saphyr::options! { strict_booleans: true, with_snippet: false };
        let raw: RawMap = serde_saphyr::from_str_with_options(text, options).map_err(|e| {
            let p = yaml_error(text, &e);
            let msg = p.message.replace("invalid parameter file", "invalid column map");
            InputError::at(name, text, p.span, msg, p.expected)
        })?;
        let bad = |loc: &serde_saphyr::Location, msg: String, exp: &str| {
            InputError::at(name, text, span_of(text, loc), msg, Some(exp.to_string()))
        };
        let col = |c: &Spanned<RawCol>| -> Result<ColRef, InputError> {
            match &c.value {
                RawCol::Name(n) => Ok(ColRef::Name(n.clone())),
                RawCol::Index(i) if *i >= 1 => Ok(ColRef::Index(*i as usize)),
                RawCol::Index(_) => Err(bad(&c.referenced, "column 0".into(), "a column number from 1")),
            }
        };
        let value =
            |c: &Spanned<RawCol>, scale: Option<f64>, offset: Option<f64>| -> Result<ValueMap, InputError> {
                Ok(ValueMap { column: col(c)?, scale: scale.unwrap_or(1.0), offset: offset.unwrap_or(0.0) })
            };
        let delimiter = match &raw.delimiter {
            None => b',',
            Some(d) => match d.value.as_str() {
                "\\t" | "tab" => b'\t',
                s if s.len() == 1 && s != "\"" && s != "\n" && s != "\r" => s.as_bytes()[0],
                s => {
                    return Err(bad(
                        &d.referenced,
                        format!("delimiter `{s}`"),
                        "one ASCII character other than a quote or line end (`,`, `;`, `\\t`, `|`)",
                    ))
                }
            },
        };
        let time = match &raw.time {
            None => None,
            Some(t) => {
                let us_per_unit = match t.unit.as_ref().map(|u| (u.value.as_str(), u)) {
                    None | Some(("s", _)) => 1e6,
                    Some(("ms", _)) => 1e3,
                    Some(("us", _)) => 1.0,
                    Some(("ns", _)) => 1e-3,
                    Some((u, s)) => {
                        return Err(bad(&s.referenced, format!("unknown time unit `{u}`"), "s, ms, us or ns"))
                    }
                };
                Some(TimeMap { value: value(&t.column, t.scale, t.offset)?, us_per_unit })
            }
        };
        let mut axes: Vec<AxisMap> = Vec::new();
        for a in &raw.axes {
            let letter = a.axis.value.chars().next().filter(|_| a.axis.value.chars().count() == 1);
            let index = letter.and_then(axis_index);
            let (Some(letter), Some(index)) = (letter, index) else {
                return Err(bad(
                    &a.axis.referenced,
                    format!("unknown axis `{}`", a.axis.value),
                    "X, Y, Z, A, B or C",
                ));
            };
            if axes.iter().any(|x| x.axis.letter == letter) {
                return Err(bad(&a.axis.referenced, format!("axis {letter} mapped twice"), "each axis once"));
            }
            let axis =
                AxisSpec { letter, index, diameter: a.diameter, rotary: matches!(letter, 'A' | 'B' | 'C') };
            axes.push(AxisMap { axis, value: value(&a.column, a.scale, a.offset)? });
        }
        let (mut rpm, mut angle) = (None, None);
        if let Some(s) = &raw.spindle {
            if let Some(r) = &s.rpm {
                rpm = Some(value(&r.column, r.scale, r.offset)?);
            }
            if let Some(r) = &s.angle_deg {
                angle = Some(value(&r.column, r.scale, r.offset)?);
            }
        }
        let mut signals: Vec<SignalMap> = Vec::new();
        for s in &raw.signals {
            let Some(signal) = Signal::from_name(&s.signal.value) else {
                return Err(bad(
                    &s.signal.referenced,
                    format!("unknown signal `{}`", s.signal.value),
                    "a signal of docs/trace-format.md (MF, SF, TF, FIN, F76.3, RGTAP, SPPOS, SPPOSA, RGSPP, RGSPM, SPL, STL, ESP, ZSP)",
                ));
            };
            if signals.iter().any(|x| x.signal == signal) {
                return Err(bad(
                    &s.signal.referenced,
                    format!("signal {} mapped twice", signal.name()),
                    "each signal once",
                ));
            }
            let level = match (&s.bit, s.above, s.below) {
                (None, None, None) => Level::NonZero,
                (Some(b), None, None) if b.value < 64 => Level::Bit(b.value),
                (Some(b), None, None) => {
                    return Err(bad(&b.referenced, format!("bit {}", b.value), "a bit number 0..63"))
                }
                (None, Some(t), None) => Level::Above(t),
                (None, None, Some(t)) => Level::Below(t),
                _ => {
                    return Err(bad(
                        &s.signal.referenced,
                        format!("signal {} has more than one of bit, above, below", signal.name()),
                        "one of bit, above or below (or none: not zero is 1)",
                    ))
                }
            };
            signals.push(SignalMap {
                signal,
                value: value(&s.column, s.scale, s.offset)?,
                level,
                invert: s.invert,
            });
        }
        Ok(ColumnMap {
            delimiter,
            skip_rows: raw.skip_rows,
            header: raw.header.unwrap_or(true),
            time,
            axes,
            rpm,
            angle,
            signals,
            ignore: raw.ignore,
        })
    }
}
