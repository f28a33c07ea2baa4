//! Fuzz target `nesting`: deep nesting built from a structured input (`arbitrary`), so that the
//! fuzzer reaches depths that random bytes never spell: LinuxCNC expressions (brackets, unary
//! functions, long sums and products, unary minus), o-word blocks nested in each other,
//! subroutines calling themselves, and VCD scopes. The depth goes up to [`MAX_DEPTH`], far past
//! any limit the readers set, so that a reader whose recursion follows the input overflows its
//! stack (an abort, which no test can catch) where it should refuse the input with a located
//! error.

use arbitrary::{Arbitrary, Unstructured};
use nc_engine::invariants::time_ordered_ends;
use nc_engine::{Machine, RunOptions};

/// The deepest nesting an input asks for.
pub const MAX_DEPTH: u32 = 200_000;

/// Unary functions of LinuxCNC's expression language.
const FUNCTIONS: [&str; 10] = ["sin", "cos", "tan", "asin", "acos", "abs", "exp", "ln", "sqrt", "fix"];
/// Binary operators of LinuxCNC's expression language.
const OPERATORS: [&str; 12] = ["+", "-", "*", "/", "**", "mod", "and", "or", "xor", "eq", "lt", "ge"];

/// One level of an expression.
#[derive(Debug, Clone, Copy, Arbitrary)]
enum Level {
    /// `[ ... ]`
    Bracket,
    /// `sin[ ... ]`, ...
    Function(u8),
    /// `-[ ... ]`
    Minus,
    /// `atan[ ... ]/[1]`
    Atan,
    /// `[ ... ] OP 1`
    Left(u8),
    /// `1 OP [ ... ]`
    Right(u8),
}

/// What is nested.
#[derive(Debug, Arbitrary)]
enum Shape {
    /// An expression whose levels cycle through the list.
    Expression(Vec<Level>),
    /// `1 OP 1 OP 1 ...`: a flat chain of binary operations (the parser may still recurse).
    Chain(u8),
    /// `o100 if [1]` nested in each other.
    If,
    /// `o100 while [...]` nested in each other (each loop runs once).
    While,
    /// `o100 repeat [1]` nested in each other.
    Repeat,
    /// A subroutine that calls itself until a counter reaches the depth.
    Recursion,
    /// VCD `$scope`s nested in each other.
    VcdScope,
}

/// One `nesting` input.
#[derive(Debug, Arbitrary)]
struct Nesting {
    depth: u32,
    /// The expression is the value of a parameter (`#1 = ...`) rather than a word (`G0 X...`).
    in_assignment: bool,
    shape: Shape,
}

/// Fuzz target `nesting`: build the nested text and read it as a user's file would be read.
///
/// # Panics
///
/// On a bug: a panic of the parser, interpreter or importer, a parse error without a location,
/// a trace that is not time-ordered or does not end with one `end` event. A stack overflow
/// aborts the process (libFuzzer reports it as a crash).
pub fn nesting(data: &[u8]) {
    let Ok(n) = Nesting::arbitrary_take_rest(Unstructured::new(data)) else { return };
    let depth = (n.depth % (MAX_DEPTH + 1)) as usize;
    match &n.shape {
        Shape::VcdScope => crate::import::fuzz::import_vcd(vcd_scopes(depth).as_bytes()),
        shape => run_linuxcnc(&program(shape, depth, n.in_assignment)),
    }
}

/// The LinuxCNC program of a shape.
fn program(shape: &Shape, depth: usize, in_assignment: bool) -> String {
    let expression = |e: String| {
        if in_assignment {
            format!("#1 = {e}\nM2\n")
        } else {
            format!("G0 X[{e}]\nM2\n")
        }
    };
    match shape {
        Shape::Expression(levels) => expression(nested_expression(levels, depth)),
        Shape::Chain(op) => {
            let op = OPERATORS[*op as usize % OPERATORS.len()];
            let mut e = String::with_capacity(depth * (op.len() + 3) + 1);
            e.push('1');
            for _ in 0..depth {
                e.push(' ');
                e.push_str(op);
                e.push_str(" 1");
            }
            expression(e)
        }
        Shape::If | Shape::While | Shape::Repeat => {
            let (open, close) = match shape {
                Shape::If => ("if [1]", "endif"),
                Shape::While => ("while [#<_n> lt 1]", "endwhile"),
                _ => ("repeat [1]", "endrepeat"),
            };
            let mut p = String::from("#<_n> = 0\n");
            for i in 0..depth {
                p.push_str(&format!("o{} {open}\n", 100 + i));
            }
            p.push_str("#<_n> = 1\n");
            for i in (0..depth).rev() {
                p.push_str(&format!("o{} {close}\n", 100 + i));
            }
            p.push_str("M2\n");
            p
        }
        Shape::Recursion => format!(
            "o100 sub\n#<_n> = [#<_n> + 1]\no101 if [#<_n> lt {depth}]\no100 call\no101 endif\no100 endsub\n\
             #<_n> = 0\no100 call\nM2\n"
        ),
        Shape::VcdScope => unreachable!("VCD scopes are not a program"),
    }
}

/// An expression nested `depth` levels deep, the levels taken in turn from `levels`.
fn nested_expression(levels: &[Level], depth: usize) -> String {
    let levels = if levels.is_empty() { &[Level::Bracket][..] } else { levels };
    let mut open = String::new();
    let mut close = Vec::with_capacity(depth);
    for i in 0..depth {
        match levels[i % levels.len()] {
            Level::Bracket => {
                open.push('[');
                close.push("]".to_string());
            }
            Level::Function(f) => {
                open.push_str(FUNCTIONS[f as usize % FUNCTIONS.len()]);
                open.push('[');
                close.push("]".to_string());
            }
            Level::Minus => {
                open.push_str("-[");
                close.push("]".to_string());
            }
            Level::Atan => {
                open.push_str("atan[");
                close.push("]/[1]".to_string());
            }
            Level::Left(op) => {
                open.push('[');
                close.push(format!("] {} 1", OPERATORS[op as usize % OPERATORS.len()]));
            }
            Level::Right(op) => {
                open.push_str(&format!("1 {} [", OPERATORS[op as usize % OPERATORS.len()]));
                close.push("]".to_string());
            }
        }
    }
    open.push('1');
    for c in close.iter().rev() {
        open.push_str(c);
    }
    open
}

/// A VCD file whose one variable sits `depth` scopes deep.
fn vcd_scopes(depth: usize) -> String {
    let mut v = String::from("$timescale 1 us $end\n");
    for i in 0..depth {
        v.push_str(&format!("$scope module m{i} $end\n"));
    }
    v.push_str("$var wire 1 ! STL $end\n");
    for _ in 0..depth {
        v.push_str("$upscope $end\n");
    }
    v.push_str("$enddefinitions $end\n#0\n1!\n#1000\n0!\n");
    v
}

/// Parses and runs a LinuxCNC program as `nc-conform run` does (simulated time bounded).
fn run_linuxcnc(text: &str) {
    let machine = Machine::new("linuxcnc").expect("the linuxcnc dialect exists");
    match machine.parse(text) {
        Ok(program) => {
            let opts = RunOptions {
                sample_us: 0,
                time_limit_us: super::GCODE_TIME_LIMIT_US,
                auto_cycle_start: true,
                ..RunOptions::default()
            };
            let trace = machine.run_to_trace(&program, &opts);
            if let Some(v) = time_ordered_ends(&trace) {
                panic!("linuxcnc: {v}");
            }
        }
        Err(e) => {
            assert!(e.line >= 1 && e.col >= 1, "parse error without a location: {e:?}");
            assert!(!e.message.is_empty(), "parse error without a message: {e:?}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_build_the_texts_they_name() {
        assert_eq!(nested_expression(&[Level::Bracket], 2), "[[1]]");
        assert_eq!(nested_expression(&[Level::Function(0), Level::Minus], 2), "sin[-[1]]");
        assert_eq!(nested_expression(&[Level::Left(0)], 2), "[[1] + 1] + 1");
        assert_eq!(nested_expression(&[Level::Atan], 1), "atan[1]/[1]");
        assert_eq!(program(&Shape::If, 1, true), "#<_n> = 0\no100 if [1]\n#<_n> = 1\no100 endif\nM2\n");
        assert_eq!(program(&Shape::Chain(0), 2, false), "G0 X[1 + 1 + 1]\nM2\n");
        assert!(vcd_scopes(2).contains("$scope module m1 $end\n$var"));
    }

    #[test]
    fn seeds_decode_to_the_shapes_they_are_named_after() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus/nesting");
        let decode = |name: &str| {
            let data = std::fs::read(dir.join(name)).unwrap();
            Nesting::arbitrary_take_rest(Unstructured::new(&data)).unwrap()
        };
        let n = decode("sin_minus_30");
        assert_eq!(n.depth, 30);
        let Shape::Expression(levels) = &n.shape else { panic!("{n:?}") };
        assert!(matches!(levels[..], [Level::Function(0), Level::Minus]), "{levels:?}");
        assert!(matches!(decode("vcd_scopes_50").shape, Shape::VcdScope));
        assert!(matches!(decode("recursion_5").shape, Shape::Recursion));
        assert!(matches!(decode("chain_power_50").shape, Shape::Chain(4)));
    }
}
