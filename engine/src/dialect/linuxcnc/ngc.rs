//! The RS274NGC line syntax of LinuxCNC: words whose values may be expressions (`Z[#1*2]`,
//! `X#<dia>`, `I-#<peak>`), parameter settings (`#1 = 2`, `#<name> = [..]`), o-word control lines
//! (`o100 sub`, `o<name> call [1][2]`, `o1 if [..]`), comments `( )` and `;` (LCNC-LEX-01..03).
//!
//! Lexical only: a line becomes a [`Line`] (or a [`ParseError`] located at its column); the
//! interpreter evaluates it when the line runs, because parameters change as the program runs.

use crate::parse::ParseError;

/// A unary function of an expression (angles in degrees).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Func {
    /// `ABS`.
    Abs,
    /// `ACOS`.
    Acos,
    /// `ASIN`.
    Asin,
    /// `COS`.
    Cos,
    /// `EXP`.
    Exp,
    /// `FIX` (round down).
    Fix,
    /// `FUP` (round up).
    Fup,
    /// `ROUND`.
    Round,
    /// `LN`.
    Ln,
    /// `SIN`.
    Sin,
    /// `SQRT`.
    Sqrt,
    /// `TAN`.
    Tan,
    /// Unary minus.
    Neg,
    /// Unary plus.
    Plus,
}

/// A binary operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Op {
    /// `**`.
    Pow,
    /// `*`.
    Mul,
    /// `/`.
    Div,
    /// `MOD`.
    Mod,
    /// `+`.
    Add,
    /// `-`.
    Sub,
    /// `EQ`.
    Eq,
    /// `NE`.
    Ne,
    /// `GT`.
    Gt,
    /// `GE`.
    Ge,
    /// `LT`.
    Lt,
    /// `LE`.
    Le,
    /// `AND`.
    And,
    /// `OR`.
    Or,
    /// `XOR`.
    Xor,
}

impl Op {
    /// Binding strength: higher binds tighter.
    fn precedence(self) -> u8 {
        match self {
            Op::Pow => 5,
            Op::Mul | Op::Div | Op::Mod => 4,
            Op::Add | Op::Sub => 3,
            Op::Eq | Op::Ne | Op::Gt | Op::Ge | Op::Lt | Op::Le => 2,
            Op::And | Op::Or | Op::Xor => 1,
        }
    }
}

/// An expression.
#[derive(Debug, Clone, PartialEq)]
pub enum Expr {
    /// A number.
    Num(f64),
    /// `#n` or `#[expr]`: a numbered parameter.
    Param(Box<Expr>),
    /// `#<name>`: a named parameter (lower case, blanks removed).
    Named(String),
    /// `EXISTS[#<name>]`.
    Exists(String),
    /// A unary function.
    Unary(Func, Box<Expr>),
    /// `ATAN[a]/[b]`, degrees.
    Atan(Box<Expr>, Box<Expr>),
    /// A binary operation.
    Bin(Op, Box<Expr>, Box<Expr>),
}

/// Where a parameter setting writes.
#[derive(Debug, Clone, PartialEq)]
pub enum Target {
    /// `#n = ` (the number may be an expression).
    Num(Expr),
    /// `#<name> = `.
    Named(String),
}

/// A word: a letter and its value.
#[derive(Debug, Clone, PartialEq)]
pub struct NWord {
    /// Upper-case letter.
    pub letter: char,
    /// The value.
    pub value: Expr,
    /// 1-based column of the letter.
    pub col: u32,
}

/// What an o-word line does.
#[derive(Debug, Clone, PartialEq)]
pub enum Ctrl {
    /// `sub`.
    Sub,
    /// `endsub [value]`.
    EndSub,
    /// `call [a][b]...`.
    Call(Vec<Expr>),
    /// `return [value]`.
    Return,
    /// `if [cond]`.
    If(Expr),
    /// `elseif [cond]`.
    ElseIf(Expr),
    /// `else`.
    Else,
    /// `endif`.
    EndIf,
    /// `while [cond]` (also the end of a `do` loop).
    While(Expr),
    /// `endwhile`.
    EndWhile,
    /// `do`.
    Do,
    /// `break`.
    Break,
    /// `continue`.
    Continue,
    /// `repeat [count]`.
    Repeat(Expr),
    /// `endrepeat`.
    EndRepeat,
}

/// An o-word line.
#[derive(Debug, Clone, PartialEq)]
pub struct OWord {
    /// The label, lower case (`100`, `<g76diam>`).
    pub label: String,
    /// What it does.
    pub ctrl: Ctrl,
}

/// One parsed line.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Line {
    /// 1-based line number.
    pub line: u32,
    /// `/` block delete.
    pub block_delete: bool,
    /// The o-word, when the line is a control line.
    pub oword: Option<OWord>,
    /// Words in order.
    pub words: Vec<NWord>,
    /// Parameter settings, applied after the line's words are read.
    pub sets: Vec<(Target, Expr)>,
}

impl Line {
    /// Whether the line does anything.
    pub fn is_empty(&self) -> bool {
        self.oword.is_none() && self.words.is_empty() && self.sets.is_empty()
    }
}

/// Letters LinuxCNC accepts as words.
pub const LETTERS: &str = "ABCDEFGHIJKLMPQRSTUVWXYZ";

struct Cur<'a> {
    chars: Vec<char>,
    i: usize,
    line: u32,
    _src: &'a str,
}

impl Cur<'_> {
    fn peek(&self) -> Option<char> {
        self.chars.get(self.i).copied()
    }
    fn col(&self) -> u32 {
        self.i as u32 + 1
    }
    fn skip_blanks(&mut self) {
        while self.peek().is_some_and(|c| c == ' ' || c == '\t' || c == '\r') {
            self.i += 1;
        }
    }
    fn err(&self, message: impl Into<String>, expected: impl Into<String>) -> ParseError {
        ParseError {
            line: self.line,
            col: self.col(),
            len: 1,
            message: message.into(),
            expected: expected.into(),
        }
    }
    /// Case-insensitive keyword at the cursor (after blanks); consumed when present.
    fn keyword(&mut self, kw: &str) -> bool {
        self.skip_blanks();
        let n = kw.len();
        let ok = self.chars.len() >= self.i + n
            && self.chars[self.i..self.i + n].iter().zip(kw.chars()).all(|(a, b)| a.eq_ignore_ascii_case(&b));
        if ok {
            self.i += n;
        }
        ok
    }
    fn expect(&mut self, c: char, what: &str) -> Result<(), ParseError> {
        self.skip_blanks();
        if self.peek() == Some(c) {
            self.i += 1;
            Ok(())
        } else {
            Err(self.err(format!("`{c}` missing {what}"), format!("`{c}`")))
        }
    }
}

/// The longest line LinuxCNC's interpreter reads, in bytes without the line ending: `rs274`
/// answers "Command too long" from 253 bytes on (LCNC-LEX-01). The limit also bounds how deep an
/// expression can nest (`[[[..]]]`, `-----1`, `SIN[SIN[..]]`, a long `1+1+..` sum), so the
/// recursive parser and evaluator below never follow an unbounded depth.
pub const MAX_LINE_BYTES: usize = 252;

/// Parses one line (without its line ending). Never panics.
pub fn parse_line(text: &str, line: u32) -> Result<Line, ParseError> {
    if text.len() > MAX_LINE_BYTES {
        return Err(ParseError {
            line,
            col: u32::try_from(text.char_indices().take_while(|(i, _)| *i < MAX_LINE_BYTES).count() + 1)
                .unwrap_or(u32::MAX),
            len: 1,
            message: "Command too long".into(),
            expected: format!("a line of at most {MAX_LINE_BYTES} characters (LinuxCNC's limit)"),
        });
    }
    let mut c = Cur { chars: text.chars().collect(), i: 0, line, _src: text };
    let mut out = Line { line, ..Line::default() };
    c.skip_blanks();
    if c.peek() == Some('/') {
        c.i += 1;
        out.block_delete = true;
    }
    c.skip_blanks();
    if c.peek().is_some_and(|ch| ch.eq_ignore_ascii_case(&'n')) {
        c.i += 1;
        c.skip_blanks();
        let start = c.i;
        while c.peek().is_some_and(|ch| ch.is_ascii_digit() || ch == '.') {
            c.i += 1;
        }
        if c.i == start {
            return Err(c.err("line number N without digits", "N and digits, e.g. N120"));
        }
    }
    c.skip_blanks();
    if c.peek().is_some_and(|ch| ch.eq_ignore_ascii_case(&'o')) {
        c.i += 1;
        out.oword = oword(&mut c)?;
    }
    loop {
        c.skip_blanks();
        let Some(ch) = c.peek() else { break };
        match ch {
            '(' => comment(&mut c)?,
            ';' => break,
            '%' if out.words.is_empty() && out.oword.is_none() => break,
            '#' => {
                c.i += 1;
                let target = param_ref(&mut c)?;
                c.expect('=', "in parameter setting")?;
                let value = real_value(&mut c)?;
                let target = match target {
                    Expr::Named(n) => Target::Named(n),
                    Expr::Param(e) => Target::Num(*e),
                    _ => unreachable_target(),
                };
                out.sets.push((target, value));
            }
            ch if ch.is_ascii_alphabetic() => {
                let col = c.col();
                let letter = ch.to_ascii_uppercase();
                if !LETTERS.contains(letter) {
                    return Err(c.err(
                        format!("word letter `{letter}` is not used by dialect linuxcnc"),
                        format!("one of the letters {LETTERS}"),
                    ));
                }
                c.i += 1;
                let value = real_value(&mut c)?;
                out.words.push(NWord { letter, value, col });
            }
            _ => {
                return Err(c.err(
                    format!("unexpected `{ch}`"),
                    "a word (letter and value), a comment or end of line",
                ))
            }
        }
    }
    Ok(out)
}

/// A parameter reference is always named or numbered; keeps the match in `parse_line` total.
fn unreachable_target() -> Target {
    Target::Num(Expr::Num(0.0))
}

fn comment(c: &mut Cur) -> Result<(), ParseError> {
    let at = c.col();
    c.i += 1;
    while let Some(ch) = c.peek() {
        c.i += 1;
        if ch == ')' {
            return Ok(());
        }
    }
    Err(ParseError {
        line: c.line,
        col: at,
        len: 1,
        message: "Unclosed comment found".into(),
        expected: ")".into(),
    })
}

/// An o-word line; `None` for a bare program number (`O0001`), which names the program.
fn oword(c: &mut Cur) -> Result<Option<OWord>, ParseError> {
    c.skip_blanks();
    let mut label = String::new();
    if c.peek() == Some('<') {
        c.i += 1;
        label.push('<');
        loop {
            match c.peek() {
                Some('>') => {
                    c.i += 1;
                    break;
                }
                Some(ch) if ch != ' ' && ch != '\t' => {
                    label.push(ch.to_ascii_lowercase());
                    c.i += 1;
                }
                Some(_) => c.i += 1,
                None => return Err(c.err("Named oword not terminated", "`>`")),
            }
        }
        label.push('>');
    } else {
        while let Some(ch) = c.peek().filter(|ch| ch.is_ascii_digit()) {
            label.push(ch);
            c.i += 1;
        }
        if label.is_empty() {
            return Err(c.err("o-word without a number or <name>", "o100 or o<name>"));
        }
    }
    c.skip_blanks();
    if !label.starts_with('<') && matches!(c.peek(), None | Some('(' | ';')) {
        return Ok(None);
    }
    // Longest keywords first: `endsub` before `end...`, `elseif` before `else`.
    let ctrl = if c.keyword("endsub") {
        let _ = opt_bracket(c)?;
        Ctrl::EndSub
    } else if c.keyword("endwhile") {
        Ctrl::EndWhile
    } else if c.keyword("endrepeat") {
        Ctrl::EndRepeat
    } else if c.keyword("endif") {
        Ctrl::EndIf
    } else if c.keyword("elseif") {
        Ctrl::ElseIf(bracket(c)?)
    } else if c.keyword("else") {
        Ctrl::Else
    } else if c.keyword("sub") {
        Ctrl::Sub
    } else if c.keyword("call") {
        let mut args = Vec::new();
        while let Some(e) = opt_bracket(c)? {
            args.push(e);
        }
        Ctrl::Call(args)
    } else if c.keyword("return") {
        let _ = opt_bracket(c)?;
        Ctrl::Return
    } else if c.keyword("if") {
        Ctrl::If(bracket(c)?)
    } else if c.keyword("while") {
        Ctrl::While(bracket(c)?)
    } else if c.keyword("do") {
        Ctrl::Do
    } else if c.keyword("break") {
        Ctrl::Break
    } else if c.keyword("continue") {
        Ctrl::Continue
    } else if c.keyword("repeat") {
        Ctrl::Repeat(bracket(c)?)
    } else {
        return Err(c.err(
            "Unknown control command in o word",
            "sub, endsub, call, return, if, elseif, else, endif, while, endwhile, do, break, continue, repeat, endrepeat",
        ));
    };
    Ok(Some(OWord { label, ctrl }))
}

fn opt_bracket(c: &mut Cur) -> Result<Option<Expr>, ParseError> {
    c.skip_blanks();
    if c.peek() == Some('[') {
        Ok(Some(bracket(c)?))
    } else {
        Ok(None)
    }
}

/// `[ expression ]`.
fn bracket(c: &mut Cur) -> Result<Expr, ParseError> {
    c.expect('[', "before an expression")?;
    let e = expression(c, 0)?;
    c.skip_blanks();
    if c.peek() != Some(']') {
        return Err(c.err("Unclosed expression", "an operator or `]`"));
    }
    c.i += 1;
    Ok(e)
}

/// Operators by precedence climbing.
fn expression(c: &mut Cur, min: u8) -> Result<Expr, ParseError> {
    let mut lhs = real_value(c)?;
    loop {
        c.skip_blanks();
        let save = c.i;
        let Some(op) = operator(c) else { break };
        if op.precedence() < min {
            c.i = save;
            break;
        }
        // Left associative, except `**`.
        let next = if op == Op::Pow { op.precedence() } else { op.precedence() + 1 };
        let rhs = expression(c, next)?;
        lhs = Expr::Bin(op, Box::new(lhs), Box::new(rhs));
    }
    Ok(lhs)
}

fn operator(c: &mut Cur) -> Option<Op> {
    let table: [(&str, Op); 15] = [
        ("**", Op::Pow),
        ("*", Op::Mul),
        ("/", Op::Div),
        ("mod", Op::Mod),
        ("+", Op::Add),
        ("-", Op::Sub),
        ("eq", Op::Eq),
        ("ne", Op::Ne),
        ("gt", Op::Gt),
        ("ge", Op::Ge),
        ("lt", Op::Lt),
        ("le", Op::Le),
        ("and", Op::And),
        ("or", Op::Or),
        ("xor", Op::Xor),
    ];
    table.iter().find(|(kw, _)| c.keyword(kw)).map(|(_, op)| *op)
}

/// A value: number, parameter, bracketed expression, function, with an optional sign.
fn real_value(c: &mut Cur) -> Result<Expr, ParseError> {
    c.skip_blanks();
    match c.peek() {
        Some('-') => {
            c.i += 1;
            Ok(Expr::Unary(Func::Neg, Box::new(real_value(c)?)))
        }
        Some('+') => {
            c.i += 1;
            Ok(Expr::Unary(Func::Plus, Box::new(real_value(c)?)))
        }
        Some('[') => bracket(c),
        Some('#') => {
            c.i += 1;
            param_ref(c)
        }
        Some(ch) if ch.is_ascii_digit() || ch == '.' => number(c),
        Some(ch) if ch.is_ascii_alphabetic() => function(c),
        _ => Err(c.err(
            "No characters found in reading real value",
            "a number, #parameter, [expression] or function",
        )),
    }
}

fn number(c: &mut Cur) -> Result<Expr, ParseError> {
    let start = c.i;
    let mut digits = 0;
    let mut point = false;
    while let Some(ch) = c.peek() {
        if ch.is_ascii_digit() {
            digits += 1;
        } else if ch == '.' && !point {
            point = true;
        } else {
            break;
        }
        c.i += 1;
    }
    if digits == 0 {
        c.i = start;
        return Err(c.err("No digits found where real number should be", "digits, e.g. 12.5"));
    }
    let s: String = c.chars[start..c.i].iter().collect();
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(Expr::Num(v)),
        _ => Err(c.err("Bad number format", "a number, e.g. 12.5")),
    }
}

/// After `#`: a number, `<name>` or `[expr]` (or another `#`).
fn param_ref(c: &mut Cur) -> Result<Expr, ParseError> {
    c.skip_blanks();
    match c.peek() {
        Some('<') => Ok(Expr::Named(name(c)?)),
        _ => Ok(Expr::Param(Box::new(real_value(c)?))),
    }
}

/// `<name>`: lower case, blanks removed.
fn name(c: &mut Cur) -> Result<String, ParseError> {
    c.i += 1;
    let mut n = String::new();
    loop {
        match c.peek() {
            Some('>') => {
                c.i += 1;
                return Ok(n);
            }
            Some(' ' | '\t') => c.i += 1,
            Some(ch) => {
                n.push(ch.to_ascii_lowercase());
                c.i += 1;
            }
            None => return Err(c.err("Named parameter not terminated", "`>`")),
        }
    }
}

fn function(c: &mut Cur) -> Result<Expr, ParseError> {
    let table: [(&str, Func); 12] = [
        ("abs", Func::Abs),
        ("acos", Func::Acos),
        ("asin", Func::Asin),
        ("cos", Func::Cos),
        ("exp", Func::Exp),
        ("fix", Func::Fix),
        ("fup", Func::Fup),
        ("round", Func::Round),
        ("ln", Func::Ln),
        ("sin", Func::Sin),
        ("sqrt", Func::Sqrt),
        ("tan", Func::Tan),
    ];
    if c.keyword("atan") {
        let a = bracket(c)?;
        c.expect('/', "after the first ATAN argument")?;
        let b = bracket(c)?;
        return Ok(Expr::Atan(Box::new(a), Box::new(b)));
    }
    if c.keyword("exists") {
        c.expect('[', "after EXISTS")?;
        c.expect('#', "in EXISTS")?;
        c.skip_blanks();
        if c.peek() != Some('<') {
            return Err(c.err("EXISTS needs a named parameter", "#<name>"));
        }
        let n = name(c)?;
        c.expect(']', "after EXISTS")?;
        return Ok(Expr::Exists(n));
    }
    for (kw, f) in table {
        if c.keyword(kw) {
            return Ok(Expr::Unary(f, Box::new(bracket(c)?)));
        }
    }
    Err(c.err(
        "Unknown word where unary operation could be",
        "ABS, ACOS, ASIN, ATAN, COS, EXP, FIX, FUP, ROUND, LN, SIN, SQRT, TAN, EXISTS",
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_with_expressions_and_parameters() {
        let l = parse_line("G76 P[#<pitch> * 2] Z#<end_z> I-#<peak> J.5 (c) ; rest", 3).unwrap();
        let letters: String = l.words.iter().map(|w| w.letter).collect();
        assert_eq!(letters, "GPZIJ");
        assert_eq!(l.words[4].value, Expr::Num(0.5));
        assert!(matches!(l.words[3].value, Expr::Unary(Func::Neg, _)));
        assert_eq!(l.words[2].col, 21);
    }

    #[test]
    fn precedence_of_operators() {
        let l = parse_line("#1 = [1 + 2 * 3 ** 2 EQ 19]", 1).unwrap();
        let (_, e) = &l.sets[0];
        assert!(matches!(e, Expr::Bin(Op::Eq, _, _)));
    }

    #[test]
    fn owords() {
        let l = parse_line("o<g76diam> call [1][2.5][#3]", 1).unwrap();
        let o = l.oword.unwrap();
        assert_eq!(o.label, "<g76diam>");
        assert!(matches!(o.ctrl, Ctrl::Call(ref a) if a.len() == 3));
        assert!(matches!(
            parse_line("O52 ELSEIF [#1 GT 0.5]", 1).unwrap().oword.unwrap().ctrl,
            Ctrl::ElseIf(_)
        ));
        assert!(matches!(parse_line("o100 endsub", 1).unwrap().oword.unwrap().ctrl, Ctrl::EndSub));
    }

    #[test]
    fn errors_are_located() {
        let e = parse_line("G1 X[1 + 2", 4).unwrap_err();
        assert_eq!((e.line, e.message.as_str()), (4, "Unclosed expression"));
        let e = parse_line("G1 X1 (open", 2).unwrap_err();
        assert_eq!((e.col, e.message.as_str()), (7, "Unclosed comment found"));
        assert!(parse_line("o1 frobnicate", 1).is_err());
        assert!(parse_line("G1 X$", 1).is_err());
        // rs274 refuses a line of 253 bytes ("Command too long") and reads one of 252.
        let at = |n: usize| format!("G0 X1 ({})", "a".repeat(n - 8));
        assert!(parse_line(&at(252), 1).is_ok());
        let e = parse_line(&at(253), 7).unwrap_err();
        assert_eq!((e.line, e.col, e.message.as_str()), (7, 253, "Command too long"));
        assert_eq!(parse_line("O0001 (name)", 1).unwrap().oword, None);
    }
}
