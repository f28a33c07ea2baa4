//! The Klartext parser: Heidenhain conversational program text → [`Program`] whose blocks carry
//! a [`Klartext`] block (rules HDH-LEX-* in `docs/rules/heidenhain.md`).
//!
//! Line based: every block is one line (`11 L X+80 Z+2 R0 FMAX M303`), with an optional block
//! number, keywords, and `;` starting a comment to the end of the line. `CYCL DEF` takes the
//! `Qnnn=value` parameter lines that follow it (`~` marks the continuation and is optional);
//! another block whose line ends with `~` goes on in the next line. `*` lines (structure items),
//! comment lines and blank lines execute nothing; `END PGM` ends the program (later lines are
//! ignored). It checks the form of the text and, for cycle 832, that its parameter list is
//! complete (no parameter missing, unknown or repeated); values and their ranges are the
//! dialect's. Never panics.

use super::{Block, ParseError, Program};
use crate::units::Decimal;

/// Most significant digits of a value (as in the letter-address lexer).
const MAX_DIGITS: u32 = 18;
/// Largest block number.
const MAX_SEQ: i64 = 99_999_999;
/// What may start a block.
const EXPECT_BLOCK: &str =
    "a Klartext block: BEGIN PGM, FUNCTION MODE TURN, TOOL CALL, L, CYCL DEF, CYCL CALL, \
     M function, STOP or END PGM";

/// The parameters of cycle 832 THREAD EXTENDED in the order of its dialog (seed 004).
pub const Q832: [u16; 20] =
    [471, 461, 460, 472, 473, 464, 491, 492, 493, 494, 469, 474, 465, 466, 463, 467, 468, 470, 475, 476];

/// A number with where it was written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KValue {
    /// The value exactly as written.
    pub value: Decimal,
    /// 1-based line.
    pub line: u32,
    /// 1-based column of the address (`X`, `S`, `Q471`).
    pub col: u32,
}

/// A coordinate of an `L` block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KCoord {
    /// Incremental (`IX`, `IZ`).
    pub incremental: bool,
    /// The value and its place.
    pub v: KValue,
}

/// The feed of an `L` block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum KFeed {
    /// `FMAX`: rapid traverse.
    Max,
    /// `F…`: feed rate in mm/min.
    Rate(KValue),
}

/// One `Qnnn=value` parameter of a cycle definition.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QParam {
    /// The parameter number (471 for Q471).
    pub number: u16,
    /// Its value and place.
    pub v: KValue,
}

/// What one Klartext block says.
#[derive(Debug, Clone, PartialEq)]
pub enum Klartext {
    /// `BEGIN PGM name MM|INCH`.
    BeginPgm {
        /// Inch program.
        inch: bool,
        /// Column of the unit.
        col: u32,
    },
    /// `END PGM name MM|INCH`.
    EndPgm,
    /// `FUNCTION MODE TURN` (true) or `FUNCTION MODE MILL` (false).
    Mode(bool),
    /// `FUNCTION TURNDATA SPIN …`: `S` with `VCONST:OFF`, or the column of `VCONST:ON`.
    Spin {
        /// The speed `S`, rpm.
        s: Option<KValue>,
        /// Column of `VCONST:ON` (constant cutting speed), when written.
        vconst_on: Option<u32>,
    },
    /// `TOOL CALL tool [axis] [S…] [F…]`.
    ToolCall {
        /// Tool number, when given as a number.
        tool: Option<KValue>,
        /// Spindle speed, rpm.
        s: Option<KValue>,
    },
    /// `L` straight line (positioning or feed).
    Line {
        /// `X` / `IX` (diameter).
        x: Option<KCoord>,
        /// `Y` / `IY` (a lathe has none: only a zero move is accepted when it runs).
        y: Option<KCoord>,
        /// `Z` / `IZ`.
        z: Option<KCoord>,
        /// Column of `RL` / `RR` (radius compensation), when written.
        comp: Option<u32>,
        /// `FMAX` or `F…`.
        feed: Option<KFeed>,
        /// M functions, in order.
        m: Vec<KValue>,
    },
    /// A block of M functions only, or `STOP` (with its M functions).
    Misc {
        /// `STOP` was written.
        stop: bool,
        /// M functions.
        m: Vec<KValue>,
    },
    /// `CYCL DEF number …` with its parameters.
    CyclDef {
        /// The cycle number.
        number: KValue,
        /// Its parameters in the order written.
        params: Vec<QParam>,
    },
    /// `CYCL CALL [M…]`.
    CyclCall {
        /// M functions.
        m: Vec<KValue>,
    },
    /// A Klartext function the engine recognises but does not model (`CC`, `C`, `LBL`, `FN`…):
    /// an alarm when it runs.
    NotModelled {
        /// The keyword.
        what: String,
        /// Its column.
        col: u32,
    },
}

/// One blank-separated token of a line: its text and 1-based column.
#[derive(Debug, Clone, Copy)]
struct Tok<'a> {
    s: &'a str,
    col: u32,
    line: u32,
}

fn err(line: u32, col: u32, len: usize, message: String, expected: impl Into<String>) -> ParseError {
    ParseError {
        line,
        col,
        len: (len.max(1)).min(u32::MAX as usize) as u32,
        message,
        expected: expected.into(),
    }
}

fn tok_err(t: &Tok<'_>, message: String, expected: impl Into<String>) -> ParseError {
    err(t.line, t.col, t.s.chars().count(), message, expected)
}

/// The code part of a line (before `;`), split into tokens with their columns.
fn tokens(line: &str, line_no: u32) -> Vec<Tok<'_>> {
    let code = line.split(';').next().unwrap_or("");
    let mut out = Vec::new();
    let mut start: Option<(usize, u32)> = None;
    let mut col = 0u32;
    for (i, c) in code.char_indices() {
        col = col.saturating_add(1);
        let blank = c.is_whitespace() || c == '~';
        match (blank, start) {
            (true, Some((b, c0))) => {
                out.push(Tok { s: &code[b..i], col: c0, line: line_no });
                start = None;
            }
            (false, None) => start = Some((i, col)),
            _ => {}
        }
    }
    if let Some((b, c0)) = start {
        out.push(Tok { s: &code[b..], col: c0, line: line_no });
    }
    out
}

/// Parses a signed decimal (`+80`, `-35.5`, `.5`); the error says what is wrong.
fn decimal(s: &str) -> Result<Decimal, &'static str> {
    let (negative, digits) = match s.as_bytes().first() {
        Some(b'+') => (false, &s[1..]),
        Some(b'-') => (true, &s[1..]),
        _ => (false, s),
    };
    let (mut mantissa, mut n, mut scale) = (0i64, 0u32, 0u32);
    let (mut any, mut point) = (false, false);
    for c in digits.chars() {
        match c {
            '0'..='9' => {
                any = true;
                if point {
                    scale += 1;
                }
                if point || mantissa != 0 || c != '0' {
                    n += 1;
                }
                if n > MAX_DIGITS {
                    return Err("too many digits");
                }
                mantissa = mantissa * 10 + i64::from(c as u8 - b'0');
            }
            '.' if !point => point = true,
            _ => return Err("not a number"),
        }
    }
    if !any {
        return Err("no value");
    }
    Ok(Decimal { mantissa: if negative { -mantissa } else { mantissa }, scale: scale as u8, point })
}

/// The value after an address of `skip` characters (`X+80` → `+80`), located at the token.
fn value(t: &Tok<'_>, skip: usize, example: &str) -> Result<KValue, ParseError> {
    let rest: String = t.s.chars().skip(skip).collect();
    match decimal(&rest) {
        Ok(value) => Ok(KValue { value, line: t.line, col: t.col }),
        Err(why) => Err(tok_err(t, format!("`{}`: {why}", t.s), format!("a number, e.g. {example}"))),
    }
}

/// Whether a token is an address followed by a number (`M303`, `S500`).
fn is_addr(t: &str, addr: char) -> bool {
    let mut c = t.chars();
    c.next() == Some(addr) && c.next().is_some_and(|d| d.is_ascii_digit() || matches!(d, '+' | '-' | '.'))
}

/// M functions from the remaining tokens (each `M` and a whole number).
fn m_list(rest: &[Tok<'_>]) -> Result<Vec<KValue>, ParseError> {
    rest.iter()
        .map(|t| {
            if !is_addr(t.s, 'M') {
                return Err(tok_err(
                    t,
                    format!("`{}` is not an M function", t.s),
                    "M and a number, e.g. M30",
                ));
            }
            value(t, 1, "M30")
        })
        .collect()
}

/// Parses a whole program. Never panics.
///
/// # Errors
///
/// The first error, with its line and column.
pub fn parse(text: &str, dialect: &str) -> Result<Program, ParseError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let lines: Vec<&str> = text.split('\n').map(|l| l.strip_suffix('\r').unwrap_or(l)).collect();
    let mut blocks = Vec::new();
    let mut i = 0usize;
    while i < lines.len() {
        let line_no = u32::try_from(i + 1).unwrap_or(u32::MAX);
        let raw = lines[i];
        i += 1;
        let trimmed = raw.trim();
        if trimmed.is_empty() || trimmed.starts_with(';') || trimmed.starts_with('*') {
            continue;
        }
        let mut toks = tokens(raw, line_no);
        let mut seq = None;
        if let Some(first) = toks.first().copied() {
            if first.s.chars().all(|c| c.is_ascii_digit()) {
                match first.s.parse::<i64>().ok().filter(|n| *n <= MAX_SEQ) {
                    Some(n) => seq = u32::try_from(n).ok(),
                    None => {
                        return Err(tok_err(
                            &first,
                            format!("block number {} is too large", first.s),
                            "a block number up to 99999999",
                        ))
                    }
                }
                toks.remove(0);
            }
        }
        // A line holding only a block number (and comments) executes nothing.
        let Some(head) = toks.first().copied() else { continue };
        if head.s.starts_with('*') {
            continue;
        }
        let key = head.s.to_ascii_uppercase();
        let is_cycl_def = key == "CYCL" && toks.get(1).is_some_and(|t| t.s.eq_ignore_ascii_case("DEF"));
        if is_cycl_def {
            // The parameter lines that follow (blank and comment lines between them too).
            let mut params = Vec::new();
            params_in(&toks[3.min(toks.len())..], &mut params)?;
            while i < lines.len() {
                let t = lines[i].trim_start();
                let q_line = t.starts_with('Q') && t[1..].starts_with(|c: char| c.is_ascii_digit());
                if !(t.trim().is_empty() || t.starts_with(';') || q_line) {
                    break;
                }
                let n = u32::try_from(i + 1).unwrap_or(u32::MAX);
                params_in(&tokens(lines[i], n), &mut params)?;
                i += 1;
            }
            let kb = cycl_def(&toks, params, raw, line_no)?;
            blocks.push(block(line_no, raw, seq, kb));
            continue;
        }
        // Any other block whose line ends with `~` goes on in the next line.
        while raw.trim_end().ends_with('~') && i < lines.len() {
            let n = u32::try_from(i + 1).unwrap_or(u32::MAX);
            toks.extend(tokens(lines[i], n));
            let more = lines[i].trim_end().ends_with('~');
            i += 1;
            if !more {
                break;
            }
        }
        let kb = match key.as_str() {
            "BEGIN" | "END" => pgm(&toks, key == "END")?,
            "BLK" => continue,
            "FUNCTION" => function(&toks)?,
            "TOOL" => tool(&toks)?,
            "L" => line(&toks)?,
            "CYCL" => cycl_call(&toks)?,
            "STOP" => Klartext::Misc { stop: true, m: m_list(&toks[1..])? },
            _ if is_addr(head.s, 'M') => Klartext::Misc { stop: false, m: m_list(&toks)? },
            "C" | "CC" | "CR" | "CT" | "CP" | "RND" | "CHF" | "LBL" | "CALL" | "FN" | "APPR" | "DEP"
            | "PLANE" | "LN" | "LP" | "CTP" | "SEL" | "TCH" | "DECLARE" => {
                Klartext::NotModelled { what: head.s.to_string(), col: head.col }
            }
            _ if key.starts_with('Q') && key[1..].starts_with(|c: char| c.is_ascii_digit()) => {
                Klartext::NotModelled { what: "Q parameter assignment".into(), col: head.col }
            }
            _ => return Err(not_klartext(&head, dialect)),
        };
        let end = matches!(kb, Klartext::EndPgm);
        blocks.push(block(line_no, raw, seq, kb));
        if end {
            break;
        }
    }
    Ok(Program { blocks })
}

fn block(line: u32, raw: &str, seq: Option<u32>, kb: Klartext) -> Block {
    Block {
        line,
        text: raw.trim().to_string(),
        seq,
        block_delete: false,
        words: Vec::new(),
        klartext: Some(Box::new(kb)),
    }
}

/// The error for a line that is no Klartext block, naming G-code where it looks like it.
fn not_klartext(t: &Tok<'_>, dialect: &str) -> ParseError {
    let c0 = t.s.chars().next().unwrap_or(' ');
    let gcode =
        matches!(c0.to_ascii_uppercase(), 'G' | 'N' | 'O' | 'X' | 'Z' | 'T' | 'S' | 'F' | '%' | '(' | '/')
            && (t.s.len() == 1
                || t.s.chars().nth(1).is_some_and(|c| c.is_ascii_digit() || "-+.(".contains(c)));
    let shown: String = t.s.chars().take(24).map(|c| if c.is_control() { '?' } else { c }).collect();
    let message = if gcode {
        format!(
            "`{shown}` looks like ISO G-code; dialect {dialect} reads Klartext (Heidenhain conversational)"
        )
    } else {
        format!("`{shown}` is not a Klartext block")
    };
    tok_err(t, message, EXPECT_BLOCK)
}

fn word<'a>(
    toks: &[Tok<'a>],
    i: usize,
    what: &str,
    last: &Tok<'_>,
    want: &str,
) -> Result<Tok<'a>, ParseError> {
    toks.get(i).copied().ok_or_else(|| {
        err(last.line, last.col + last.s.chars().count() as u32, 1, format!("{what} is incomplete"), want)
    })
}

/// `BEGIN PGM name MM` / `END PGM name MM`.
fn pgm(toks: &[Tok<'_>], end: bool) -> Result<Klartext, ParseError> {
    let want = if end { "END PGM name MM" } else { "BEGIN PGM name MM" };
    let kw = if end { "END PGM" } else { "BEGIN PGM" };
    let p = word(toks, 1, kw, &toks[0], want)?;
    if !p.s.eq_ignore_ascii_case("PGM") {
        return Err(tok_err(&p, format!("`{}` after {}", p.s, toks[0].s), want));
    }
    let _name = word(toks, 2, kw, &p, want)?;
    let unit = word(toks, 3, kw, &toks[2], want)?;
    let inch = match unit.s.to_ascii_uppercase().as_str() {
        "MM" => false,
        "INCH" => true,
        _ => return Err(tok_err(&unit, format!("`{}` is not a program unit", unit.s), "MM or INCH")),
    };
    if let Some(extra) = toks.get(4) {
        return Err(tok_err(extra, format!("`{}` after the program unit", extra.s), "end of block"));
    }
    Ok(if end { Klartext::EndPgm } else { Klartext::BeginPgm { inch, col: unit.col } })
}

/// `FUNCTION MODE TURN|MILL`, `FUNCTION TURNDATA SPIN …`; other functions are not modelled.
fn function(toks: &[Tok<'_>]) -> Result<Klartext, ParseError> {
    let what = word(toks, 1, "FUNCTION", &toks[0], "FUNCTION MODE TURN")?;
    match what.s.to_ascii_uppercase().as_str() {
        "MODE" => {
            let m = word(toks, 2, "FUNCTION MODE", &what, "TURN or MILL")?;
            match m.s.to_ascii_uppercase().as_str() {
                "TURN" => Ok(Klartext::Mode(true)),
                "MILL" => Ok(Klartext::Mode(false)),
                _ => Err(tok_err(&m, format!("`{}` is not a machining mode", m.s), "TURN or MILL")),
            }
        }
        "TURNDATA" => {
            let (mut s, mut vconst_on) = (None, None);
            for t in &toks[2..] {
                let u = t.s.to_ascii_uppercase();
                if u == "SPIN" || u == "VCONST:OFF" {
                } else if u == "VCONST:ON" {
                    vconst_on = Some(t.col);
                } else if is_addr(t.s, 'S') {
                    s = Some(value(t, 1, "S500")?);
                } else if u.starts_with("VC:") || u.starts_with("SMAX") || u.starts_with("SMIN") {
                } else {
                    return Err(tok_err(
                        t,
                        format!("`{}` in FUNCTION TURNDATA SPIN", t.s),
                        "VCONST:OFF S…, VCONST:ON VC:…, SMAX…",
                    ));
                }
            }
            Ok(Klartext::Spin { s, vconst_on })
        }
        _ => Ok(Klartext::NotModelled { what: format!("FUNCTION {}", what.s), col: toks[0].col }),
    }
}

/// `TOOL CALL tool [axis] [S…] [F…] [DL…]`; `TOOL DEF` is not modelled.
fn tool(toks: &[Tok<'_>]) -> Result<Klartext, ParseError> {
    let call = word(toks, 1, "TOOL", &toks[0], "TOOL CALL")?;
    if call.s.eq_ignore_ascii_case("DEF") {
        return Ok(Klartext::NotModelled { what: "TOOL DEF".into(), col: toks[0].col });
    }
    if !call.s.eq_ignore_ascii_case("CALL") {
        return Err(tok_err(&call, format!("`{}` after TOOL", call.s), "TOOL CALL"));
    }
    let (mut tool, mut s) = (None, None);
    let mut k = 2;
    match toks.get(2) {
        Some(t) if t.s.starts_with(|c: char| c.is_ascii_digit()) => {
            tool = Some(value(t, 0, "TOOL CALL 12")?);
            k = 3;
        }
        Some(t) if t.s.starts_with('"') => {
            // A tool name in quotes, possibly with blanks.
            let mut end = t.s.len() > 1 && t.s.ends_with('"');
            k = 3;
            while !end && k < toks.len() {
                end = toks[k].s.ends_with('"');
                k += 1;
            }
        }
        _ => {}
    }
    for t in &toks[k.min(toks.len())..] {
        if is_addr(t.s, 'S') {
            s = Some(value(t, 1, "S500")?);
        } else if is_addr(t.s, 'F')
            || t.s.starts_with("DL")
            || t.s.starts_with("DR")
            || matches!(t.s, "X" | "Y" | "Z")
        {
        } else {
            return Err(tok_err(
                t,
                format!("`{}` in TOOL CALL", t.s),
                "TOOL CALL tool [X|Y|Z] [S…] [F…] [DL…] [DR…]",
            ));
        }
    }
    Ok(Klartext::ToolCall { tool, s })
}

/// `L [X…|IX…] [Y…] [Z…|IZ…] [R0|RL|RR] [FMAX|F…] [M…]…`.
fn line(toks: &[Tok<'_>]) -> Result<Klartext, ParseError> {
    let (mut x, mut y, mut z, mut comp, mut feed) = (None, None, None, None, None);
    let mut m = Vec::new();
    const WANT: &str = "X…, Z…, IX…, IZ…, R0, FMAX, F… or M…";
    for t in &toks[1..] {
        let u = t.s.to_ascii_uppercase();
        let (inc, rest) = match u.strip_prefix('I') {
            Some(r) if r.starts_with(['X', 'Y', 'Z']) => (true, r),
            _ => (false, u.as_str()),
        };
        let slot = match rest.chars().next() {
            Some('X') if is_addr(rest, 'X') => Some(&mut x),
            Some('Y') if is_addr(rest, 'Y') => Some(&mut y),
            Some('Z') if is_addr(rest, 'Z') => Some(&mut z),
            _ => None,
        };
        if let Some(slot) = slot {
            if slot.is_some() {
                return Err(tok_err(t, format!("`{}`: the axis is written twice", t.s), WANT));
            }
            *slot = Some(KCoord { incremental: inc, v: value(t, usize::from(inc) + 1, "X+80")? });
        } else if u == "R0" || u == "RL" || u == "RR" {
            comp = if u == "R0" { None } else { Some(t.col) };
        } else if u == "FMAX" || is_addr(&u, 'F') {
            if feed.is_some() {
                return Err(tok_err(t, format!("`{}`: the feed is written twice", t.s), WANT));
            }
            feed = Some(if u == "FMAX" { KFeed::Max } else { KFeed::Rate(value(t, 1, "F200")?) });
        } else if is_addr(&u, 'M') {
            m.push(value(t, 1, "M3")?);
        } else {
            return Err(tok_err(t, format!("`{}` in an L block", t.s), WANT));
        }
    }
    Ok(Klartext::Line { x, y, z, comp, feed, m })
}

/// Reads the `Qnnn=value` assignments among `toks` (the rest of the line is comment).
fn params_in(toks: &[Tok<'_>], out: &mut Vec<QParam>) -> Result<(), ParseError> {
    let mut k = 0;
    while k < toks.len() {
        let t = toks[k];
        if !(t.s.starts_with('Q') && t.s[1..].starts_with(|c: char| c.is_ascii_digit())) {
            // Words of the cycle's name (`THREAD EXTENDED`) are not parameters.
            if out.is_empty() && t.s.chars().all(|c| c.is_ascii_uppercase() || c == '-' || c == '_') {
                k += 1;
                continue;
            }
            return Err(tok_err(
                &t,
                format!("`{}` is not a cycle parameter", t.s),
                "Qnnn=value, e.g. Q471=+0",
            ));
        }
        // `Q471=+0`, `Q471 =+0`, `Q471= +0`, `Q471 = +0`.
        let mut text: String = t.s.to_string();
        while !text.contains('=') || text.ends_with('=') {
            k += 1;
            match toks.get(k) {
                Some(n) if n.line == t.line => text.push_str(n.s),
                _ => return Err(tok_err(&t, format!("`{}` has no value", t.s), "Qnnn=value, e.g. Q471=+0")),
            }
        }
        k += 1;
        let (name, val) = text.split_once('=').unwrap_or((&text, ""));
        let number = name[1..].parse::<u16>().ok().filter(|n| *n <= 1999);
        let Some(number) = number else {
            return Err(tok_err(&t, format!("`{name}` is not a Q parameter"), "Q0..Q1999"));
        };
        let value = match decimal(val) {
            Ok(v) => v,
            Err(why) => {
                return Err(err(
                    t.line,
                    t.col,
                    text.chars().count(),
                    format!("`{text}`: {why}"),
                    "Qnnn=value, e.g. Q471=+0",
                ))
            }
        };
        out.push(QParam { number, v: KValue { value, line: t.line, col: t.col } });
    }
    Ok(())
}

/// `CYCL DEF n [name]` and its parameters; cycle 832 must have each of its parameters once.
fn cycl_def(toks: &[Tok<'_>], params: Vec<QParam>, raw: &str, line_no: u32) -> Result<Klartext, ParseError> {
    let n = word(toks, 2, "CYCL DEF", &toks[1], "CYCL DEF 832 THREAD EXTENDED")?;
    let number = value(&n, 0, "832")?;
    if number.value.as_int() == Some(832) {
        for (k, p) in params.iter().enumerate() {
            if !Q832.contains(&p.number) {
                return Err(err(
                    p.v.line,
                    p.v.col,
                    1 + p.number.to_string().len(),
                    format!("Q{} is not a parameter of cycle 832", p.number),
                    q_list(),
                ));
            }
            if params[..k].iter().any(|o| o.number == p.number) {
                return Err(err(
                    p.v.line,
                    p.v.col,
                    1 + p.number.to_string().len(),
                    format!("Q{} is given twice in cycle 832", p.number),
                    "each parameter once",
                ));
            }
        }
        let missing: Vec<String> = Q832
            .iter()
            .filter(|q| !params.iter().any(|p| p.number == **q))
            .map(|q| format!("Q{q}"))
            .collect();
        if !missing.is_empty() {
            return Err(err(
                line_no,
                toks[0].col,
                raw.trim().chars().count(),
                format!("cycle 832 lacks {}", missing.join(", ")),
                q_list(),
            ));
        }
    }
    Ok(Klartext::CyclDef { number, params })
}

fn q_list() -> String {
    let l: Vec<String> = Q832.iter().map(|q| format!("Q{q}")).collect();
    format!("the parameters of cycle 832: {}", l.join(" "))
}

/// `CYCL CALL [M…]`.
fn cycl_call(toks: &[Tok<'_>]) -> Result<Klartext, ParseError> {
    let c = word(toks, 1, "CYCL", &toks[0], "CYCL DEF or CYCL CALL")?;
    if !c.s.eq_ignore_ascii_case("CALL") {
        return Err(tok_err(&c, format!("`{}` after CYCL", c.s), "CYCL DEF or CYCL CALL"));
    }
    Ok(Klartext::CyclCall { m: m_list(&toks[2..])? })
}

#[cfg(test)]
#[path = "klartext_tests.rs"]
mod tests;
