//! Machine parameters: numbered as the vendor numbers them, with defaults and range checks.
//!
//! Owns the generic mechanism (a table of [`ParamDef`] per dialect, a [`Params`] store that
//! refuses out-of-range values). Each dialect owns its table. Parameters with no vendor number
//! are named `nc.*` (engine model) or `plc.*` (the PLC ladder model).

use std::collections::BTreeMap;

/// How a parameter's value is read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamKind {
    /// A bit, 0 or 1 (ids like `186.2`: parameter 186, bit 2).
    Bit,
    /// A whole number.
    Int,
    /// A real number (mm, mm/min, %, ...).
    Real,
}

/// One parameter's definition.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamDef {
    /// Number as the vendor writes it (`170`, `186.2`, `5200.5`) or `nc.*` / `plc.*`.
    pub id: &'static str,
    /// Short symbolic name (`RTCRG`) or a description.
    pub name: &'static str,
    /// Value type.
    pub kind: ParamKind,
    /// Smallest accepted value.
    pub min: f64,
    /// Largest accepted value.
    pub max: f64,
    /// Value when not set.
    pub default: f64,
    /// Unit, for documentation and messages (`ms`, `mm`, `%`, ``).
    pub unit: &'static str,
    /// Takes one value per axis (`34: {X: 0.01, Z: 0.02}`).
    pub per_axis: bool,
    /// What it does.
    pub doc: &'static str,
}

/// A refused parameter value.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamError {
    /// What is wrong.
    pub message: String,
    /// What would have been accepted.
    pub expected: String,
}

impl std::fmt::Display for ParamError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}; expected {}", self.message, self.expected)
    }
}

impl std::error::Error for ParamError {}

/// The parameter values of one machine: a table plus the values set over its defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct Params {
    table: &'static [ParamDef],
    values: BTreeMap<(&'static str, Option<char>), f64>,
}

impl Params {
    /// All defaults of `table`.
    pub fn new(table: &'static [ParamDef]) -> Self {
        Params { table, values: BTreeMap::new() }
    }

    /// The table.
    pub fn table(&self) -> &'static [ParamDef] {
        self.table
    }

    /// Finds a definition.
    pub fn def(&self, id: &str) -> Option<&'static ParamDef> {
        self.table.iter().find(|d| d.id == id)
    }

    /// Sets a value after checking the id, the axis and the range.
    pub fn set(&mut self, id: &str, axis: Option<char>, value: f64) -> Result<(), ParamError> {
        let def = self.def(id).ok_or_else(|| ParamError {
            message: format!("unknown parameter `{id}`"),
            expected: format!("one of: {}", self.table.iter().map(|d| d.id).collect::<Vec<_>>().join(", ")),
        })?;
        match (def.per_axis, axis) {
            (true, None) => {
                return Err(ParamError {
                    message: format!("parameter {id} ({}) takes one value per axis", def.name),
                    expected: format!("a map of axis letter to value, e.g. `{id}: {{Z: 0.01}}`"),
                })
            }
            (false, Some(a)) => {
                return Err(ParamError {
                    message: format!("parameter {id} ({}) has no per-axis value `{a}`", def.name),
                    expected: "a single number".into(),
                })
            }
            _ => {}
        }
        if let Some(a) = axis {
            if crate::trace::axis_index(a).is_none() {
                return Err(ParamError {
                    message: format!("`{a}` is not an axis"),
                    expected: "one of X Y Z A B C".into(),
                });
            }
        }
        check_value(def, value)?;
        self.values.insert((def.id, axis), value);
        Ok(())
    }

    /// The value of `id` (its default when unset). Unknown ids give 0: callers use ids from the
    /// same dialect's table, which a unit test checks.
    pub fn get(&self, id: &str) -> f64 {
        self.get_axis(id, None)
    }

    /// The value of a per-axis parameter for `axis`.
    pub fn get_axis(&self, id: &str, axis: Option<char>) -> f64 {
        match self.def(id) {
            Some(d) => self.values.get(&(d.id, axis)).copied().unwrap_or(d.default),
            None => 0.0,
        }
    }

    /// A bit parameter.
    pub fn bit(&self, id: &str) -> bool {
        self.get(id) != 0.0
    }

    /// Every value that differs from the table (for reports).
    pub fn overrides(&self) -> impl Iterator<Item = (&'static str, Option<char>, f64)> + '_ {
        self.values.iter().map(|(&(id, ax), &v)| (id, ax, v))
    }
}

/// The values `nc.period_us` takes (DEC-17).
pub const PERIODS_US: [f64; 4] = [1000.0, 2000.0, 4000.0, 8000.0];

/// Checks a value against a definition.
pub fn check_value(def: &ParamDef, value: f64) -> Result<(), ParamError> {
    let range = || match def.kind {
        ParamKind::Bit => "0 or 1".to_string(),
        _ => format!("{} to {}{}", def.min, def.max, unit_suffix(def.unit)),
    };
    if !value.is_finite() || value < def.min || value > def.max {
        return Err(ParamError {
            message: format!("parameter {} ({}) = {value} is out of range", def.id, def.name),
            expected: range(),
        });
    }
    // The interpolation period is one of four (DEC-17): 1500 is refused, not taken as 2000.
    if def.id == "nc.period_us" && value.is_finite() && !PERIODS_US.contains(&value) {
        return Err(ParamError {
            message: format!("parameter {} ({}) = {value} is not one of the four periods", def.id, def.name),
            expected: "1000, 2000, 4000 or 8000 us".into(),
        });
    }
    if matches!(def.kind, ParamKind::Bit | ParamKind::Int) && value.fract() != 0.0 {
        return Err(ParamError {
            message: format!("parameter {} ({}) = {value} must be a whole number", def.id, def.name),
            expected: range(),
        });
    }
    Ok(())
}

fn unit_suffix(unit: &str) -> String {
    if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    }
}

/// Shorthand for table entries.
pub(crate) const fn bit(id: &'static str, name: &'static str, default: f64, doc: &'static str) -> ParamDef {
    ParamDef { id, name, kind: ParamKind::Bit, min: 0.0, max: 1.0, default, unit: "", per_axis: false, doc }
}

/// Shorthand for table entries.
#[allow(clippy::too_many_arguments)]
pub(crate) const fn num(
    id: &'static str,
    name: &'static str,
    kind: ParamKind,
    min: f64,
    max: f64,
    default: f64,
    unit: &'static str,
    doc: &'static str,
) -> ParamDef {
    ParamDef { id, name, kind, min, max, default, unit, per_axis: false, doc }
}

/// Shorthand for per-axis table entries.
pub(crate) const fn axis(
    id: &'static str,
    name: &'static str,
    min: f64,
    max: f64,
    default: f64,
    unit: &'static str,
    doc: &'static str,
) -> ParamDef {
    ParamDef { id, name, kind: ParamKind::Real, min, max, default, unit, per_axis: true, doc }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    static T: &[ParamDef] = &[
        bit("186.2", "RTCRG", 0.0, "doc"),
        num("271", "overload", ParamKind::Int, 0.0, 300.0, 0.0, "%", "doc"),
        axis("34", "backlash", 0.0, 2.0, 0.0, "mm", "doc"),
    ];

    #[rstest]
    #[case("271", None, 300.0, true)]
    #[case("271", None, 301.0, false)]
    #[case("271", None, -1.0, false)]
    #[case("271", None, 1.5, false)]
    #[case("186.2", None, 1.0, true)]
    #[case("186.2", None, 2.0, false)]
    #[case("34", Some('Z'), 2.0, true)]
    #[case("34", None, 0.1, false)]
    #[case("34", Some('Q'), 0.1, false)]
    #[case("999", None, 0.0, false)]
    fn set_checks_range_and_shape(
        #[case] id: &str,
        #[case] axis: Option<char>,
        #[case] v: f64,
        #[case] ok: bool,
    ) {
        let mut p = Params::new(T);
        assert_eq!(p.set(id, axis, v).is_ok(), ok, "{id} {axis:?} {v}");
    }

    #[test]
    fn defaults_and_overrides() {
        let mut p = Params::new(T);
        assert_eq!(p.get("271"), 0.0);
        p.set("271", None, 120.0).unwrap();
        assert_eq!(p.get("271"), 120.0);
        p.set("34", Some('Z'), 0.02).unwrap();
        assert_eq!(p.get_axis("34", Some('Z')), 0.02);
        assert_eq!(p.get_axis("34", Some('X')), 0.0);
        assert!(!p.bit("186.2"));
    }

    #[test]
    fn error_names_the_range() {
        let mut p = Params::new(T);
        let e = p.set("271", None, 400.0).unwrap_err();
        assert!(e.message.contains("271"), "{e}");
        assert_eq!(e.expected, "0 to 300 %");
    }
}
