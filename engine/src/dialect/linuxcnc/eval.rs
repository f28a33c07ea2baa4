//! Parameters and expression evaluation of the `linuxcnc` dialect (LCNC-LEX-02): numbered
//! parameters `#1`..`#5399` (0 until set), named parameters (`#<name>` local to the subroutine
//! call that sets it, `#<_name>` global), the read-only system parameters the corpus reads
//! (`#<_x>`, `#<_y>`, `#<_z>`, `#<_metric>`, `#<_imperial>`, `#<_absolute>`, `#<_incremental>`,
//! `#<_lathe_diameter_mode>`), and the RS274NGC operators with LinuxCNC's error texts.
//!
//! Arithmetic is IEEE double as in LinuxCNC; transcendental functions go through `libm` so every
//! platform gets the same bits (determinism).

use std::collections::BTreeMap;

use super::ngc::{Expr, Func, Op};

/// Highest numbered parameter (LinuxCNC `RS274NGC_MAX_PARAMETERS` - 1).
pub const MAX_PARAM: i64 = 5601;

/// System values a program may read through named parameters.
#[derive(Debug, Clone, Copy, Default)]
pub struct System {
    /// Current position X, Y, Z in program units and work coordinates (X in diameter under G7).
    pub xyz: [f64; 3],
    /// G21.
    pub metric: bool,
    /// G90.
    pub absolute: bool,
    /// G7.
    pub diameter: bool,
}

/// The parameter store.
#[derive(Debug, Clone, Default)]
pub struct Store {
    numbered: BTreeMap<i64, f64>,
    globals: BTreeMap<String, f64>,
    /// One frame of local named parameters per active subroutine call (the bottom one is the
    /// main program's).
    locals: Vec<BTreeMap<String, f64>>,
}

impl Store {
    /// An empty store with the main program's frame.
    pub fn new() -> Self {
        let mut s = Store { locals: vec![BTreeMap::new()], ..Store::default() };
        s.set_returned(None);
        s
    }

    /// What the last subroutine returned: `#<_value>` (0 when it returned nothing) and
    /// `#<_value_returned>`.
    pub fn set_returned(&mut self, v: Option<f64>) {
        self.globals.insert("_value".into(), v.unwrap_or(0.0));
        self.globals.insert("_value_returned".into(), f64::from(u8::from(v.is_some())));
    }

    /// Opens a subroutine frame: `#1..#30` take the call's arguments (the caller's are returned
    /// to restore them on return).
    pub fn enter(&mut self, args: &[f64]) -> Vec<f64> {
        let saved: Vec<f64> = (1..=30).map(|i| self.num(i)).collect();
        for i in 1..=30 {
            let v = args.get(i as usize - 1).copied().unwrap_or(0.0);
            self.numbered.insert(i, v);
        }
        self.locals.push(BTreeMap::new());
        saved
    }

    /// Closes a subroutine frame and restores `#1..#30`.
    pub fn leave(&mut self, saved: &[f64]) {
        if self.locals.len() > 1 {
            self.locals.pop();
        }
        for (i, v) in saved.iter().enumerate() {
            self.numbered.insert(i as i64 + 1, *v);
        }
    }

    fn num(&self, i: i64) -> f64 {
        self.numbered.get(&i).copied().unwrap_or(0.0)
    }

    /// Stores a value.
    pub fn write_num(&mut self, n: i64, v: f64) {
        self.numbered.insert(n, v);
    }

    /// Stores a named value (global when the name starts with `_`).
    pub fn write_named(&mut self, name: &str, v: f64) -> Result<(), String> {
        if name.starts_with('_') {
            if is_system(name) {
                return Err(format!("Cannot assign to read-only parameter #<{name}>"));
            }
            self.globals.insert(name.to_string(), v);
        } else if let Some(frame) = self.locals.last_mut() {
            frame.insert(name.to_string(), v);
        }
        Ok(())
    }

    fn named(&self, name: &str, sys: &System) -> Option<f64> {
        if let Some(v) = system(name, sys) {
            return Some(v);
        }
        if name.starts_with('_') {
            self.globals.get(name).copied()
        } else {
            self.locals.last().and_then(|f| f.get(name).copied())
        }
    }

    /// Evaluates an expression.
    pub fn eval(&self, e: &Expr, sys: &System) -> Result<f64, String> {
        let v = match e {
            Expr::Num(v) => *v,
            Expr::Param(i) => {
                let i = self.eval(i, sys)?;
                let n = param_index(i)?;
                self.num(n)
            }
            Expr::Named(n) => {
                self.named(n, sys).ok_or_else(|| format!("Named parameter #<{n}> not defined"))?
            }
            Expr::Exists(n) => f64::from(u8::from(self.named(n, sys).is_some())),
            Expr::Unary(f, a) => unary(*f, self.eval(a, sys)?)?,
            Expr::Atan(a, b) => libm::atan2(self.eval(a, sys)?, self.eval(b, sys)?).to_degrees(),
            Expr::Bin(op, a, b) => binary(*op, self.eval(a, sys)?, self.eval(b, sys)?)?,
        };
        if v.is_finite() {
            Ok(v)
        } else {
            Err("Expression result is not a finite number".into())
        }
    }
}

/// The number of a numbered parameter from its (evaluated) index.
pub fn param_index(i: f64) -> Result<i64, String> {
    let n = i.round();
    if (i - n).abs() > 1e-4 || !(1.0..=MAX_PARAM as f64).contains(&n) {
        return Err("Parameter number out of range".into());
    }
    Ok(n as i64)
}

fn is_system(name: &str) -> bool {
    system(name, &System::default()).is_some()
}

fn system(name: &str, s: &System) -> Option<f64> {
    let b = |v: bool| Some(f64::from(u8::from(v)));
    match name {
        "_x" => Some(s.xyz[0]),
        "_y" => Some(s.xyz[1]),
        "_z" => Some(s.xyz[2]),
        "_metric" => b(s.metric),
        "_imperial" => b(!s.metric),
        "_absolute" => b(s.absolute),
        "_incremental" => b(!s.absolute),
        "_lathe_diameter_mode" => b(s.diameter),
        "_lathe_radius_mode" => b(!s.diameter),
        _ => None,
    }
}

fn unary(f: Func, a: f64) -> Result<f64, String> {
    let rad = a.to_radians();
    Ok(match f {
        Func::Abs => a.abs(),
        Func::Acos => {
            if !(-1.0..=1.0).contains(&a) {
                return Err("Argument to acos out of range".into());
            }
            libm::acos(a).to_degrees()
        }
        Func::Asin => {
            if !(-1.0..=1.0).contains(&a) {
                return Err("Argument to asin out of range".into());
            }
            libm::asin(a).to_degrees()
        }
        Func::Cos => libm::cos(rad),
        Func::Exp => libm::exp(a),
        Func::Fix => a.floor(),
        Func::Fup => a.ceil(),
        Func::Round => a.round(),
        Func::Ln => {
            if a <= 0.0 {
                return Err("Zero or negative argument to ln".into());
            }
            libm::log(a)
        }
        Func::Sin => libm::sin(rad),
        Func::Sqrt => {
            if a < 0.0 {
                return Err("Negative argument to sqrt".into());
            }
            libm::sqrt(a)
        }
        Func::Tan => libm::tan(rad),
        Func::Neg => -a,
        Func::Plus => a,
    })
}

fn binary(op: Op, a: f64, b: f64) -> Result<f64, String> {
    let t = |v: bool| f64::from(u8::from(v));
    // LinuxCNC compares with a tolerance of 1e-6 (TOLERANCE_EQUAL).
    let eq = (a - b).abs() < 1e-6;
    Ok(match op {
        Op::Pow => {
            if a < 0.0 && b.fract() != 0.0 {
                return Err("Attempt to raise negative to non integer power".into());
            }
            libm::pow(a, b)
        }
        Op::Mul => a * b,
        Op::Div => {
            if b == 0.0 {
                return Err("Attempt to divide by zero".into());
            }
            a / b
        }
        Op::Mod => {
            if b == 0.0 {
                return Err("Attempt to divide by zero".into());
            }
            let m = a % b;
            if m < 0.0 {
                m + b.abs()
            } else {
                m
            }
        }
        Op::Add => a + b,
        Op::Sub => a - b,
        Op::Eq => t(eq),
        Op::Ne => t(!eq),
        Op::Gt => t(a > b && !eq),
        Op::Ge => t(a > b || eq),
        Op::Lt => t(a < b && !eq),
        Op::Le => t(a < b || eq),
        Op::And => t(a != 0.0 && b != 0.0),
        Op::Or => t(a != 0.0 || b != 0.0),
        Op::Xor => t((a != 0.0) != (b != 0.0)),
    })
}

#[cfg(test)]
mod tests {
    use super::super::ngc::parse_line;
    use super::*;

    fn ev(store: &Store, src: &str) -> Result<f64, String> {
        let l = parse_line(&format!("#1 = {src}"), 1).unwrap();
        store.eval(&l.sets[0].1, &System::default())
    }

    #[test]
    fn arithmetic_functions_and_comparisons() {
        let s = Store::new();
        assert_eq!(ev(&s, "[1 + 2 * 3]"), Ok(7.0));
        assert_eq!(ev(&s, "[2 ** 3 ** 2]"), Ok(512.0));
        assert_eq!(ev(&s, "ABS[-2.5]"), Ok(2.5));
        assert_eq!(ev(&s, "[7 MOD 3]"), Ok(1.0));
        assert_eq!(ev(&s, "[1 LE 1.0000001]"), Ok(1.0));
        assert_eq!(ev(&s, "[0 EQ 0 OR 1 EQ 0]"), Ok(1.0));
        assert!((ev(&s, "TAN[45]").unwrap() - 1.0).abs() < 1e-12);
        assert!((ev(&s, "ATAN[1]/[1]").unwrap() - 45.0).abs() < 1e-12);
    }

    #[test]
    fn linuxcnc_error_texts() {
        let s = Store::new();
        assert_eq!(ev(&s, "[1 / 0]"), Err("Attempt to divide by zero".into()));
        assert_eq!(ev(&s, "SQRT[-1]"), Err("Negative argument to sqrt".into()));
        assert_eq!(ev(&s, "#<nope>"), Err("Named parameter #<nope> not defined".into()));
        assert_eq!(ev(&s, "#99999"), Err("Parameter number out of range".into()));
    }

    #[test]
    fn locals_belong_to_their_call_and_numbered_arguments_are_restored() {
        let mut s = Store::new();
        s.write_num(1, 9.0);
        s.write_named("a", 1.0).unwrap();
        s.write_named("_g", 2.0).unwrap();
        let saved = s.enter(&[5.0]);
        assert_eq!(ev(&s, "#1"), Ok(5.0));
        assert!(ev(&s, "#<a>").is_err());
        assert_eq!(ev(&s, "#<_g>"), Ok(2.0));
        s.leave(&saved);
        assert_eq!(ev(&s, "#1"), Ok(9.0));
        assert_eq!(ev(&s, "#<a>"), Ok(1.0));
        assert!(s.write_named("_x", 1.0).is_err());
    }
}
