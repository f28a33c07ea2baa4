//! The lexer: program text → [`Program`], one pass over the characters of each line.
//!
//! Framing: the first line whose first non-blank character is `%` starts the program (earlier
//! lines are ignored, errors in them too) and the text after that `%` is lexed as a block; the
//! second such line ends it (that line and everything after it are ignored). Without any `%` line
//! the whole text is the program. Within a line: `(` … `)` comments, `;` (end of block or comment to
//! end of line: either way the rest of the line is ignored), a leading `/` (block delete), a
//! leading `N` (sequence number) and words `letter [blanks] [+|-] digits [. digits]`.

use std::iter::Peekable;
use std::str::Chars;

use super::{Block, LexRules, ParseError, Program, Word};
use crate::units::Decimal;

/// Most significant digits a value may have (keeps the mantissa and `10^scale` inside `i64`).
const MAX_DIGITS: u32 = 18;
/// Largest sequence number.
const MAX_SEQ: i64 = 99_999_999;
/// What a block may contain at any point between words.
const EXPECT_WORD: &str = "a word (letter and number), a comment in parentheses, or end of block";

/// Lexes a whole program. Never panics.
///
/// # Errors
///
/// The first lexical error in the program (or, without a `%` line, in the whole text).
pub fn parse(text: &str, rules: &LexRules) -> Result<Program, ParseError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut blocks = Vec::new();
    // An error before any `%` line only counts if no `%` line follows.
    let mut deferred: Option<ParseError> = None;
    let mut framed = false;
    let mut line_no: u32 = 0;
    for raw in text.split('\n') {
        line_no = line_no.saturating_add(1);
        let line = raw.strip_suffix('\r').unwrap_or(raw);
        if line.trim_start_matches(is_blank).starts_with('%') {
            if framed {
                break;
            }
            framed = true;
            blocks.clear();
            deferred = None;
        } else if !framed && deferred.is_some() {
            continue;
        }
        match lex_line(line, line_no, rules) {
            Ok(Some(block)) => blocks.push(block),
            Ok(None) => {}
            Err(e) if framed => return Err(e),
            Err(e) => deferred = Some(e),
        }
    }
    match deferred {
        Some(e) => Err(e),
        None => Ok(Program { blocks }),
    }
}

/// Blanks between words (a stray `\r` inside a line counts as one).
fn is_blank(c: char) -> bool {
    matches!(c, ' ' | '\t' | '\r' | '\x0b' | '\x0c')
}

/// Characters of one line with the 1-based column of the next one.
struct Cursor<'a> {
    chars: Peekable<Chars<'a>>,
    col: u32,
}

impl Cursor<'_> {
    fn peek(&mut self) -> Option<char> {
        self.chars.peek().copied()
    }

    fn bump(&mut self) -> Option<char> {
        let c = self.chars.next();
        if c.is_some() {
            self.col = self.col.saturating_add(1);
        }
        c
    }
}

/// A program-name line: `O` followed by a name rather than a number (`O ENTER OP AND LAST 3
/// DIGITS`, `OSTRT`). It names the program and executes nothing (COM-PARSE-07).
fn is_program_name(line: &str) -> bool {
    let t = line.trim_start().trim_start_matches('%').trim_start();
    let mut c = t.chars();
    matches!(c.next(), Some('O' | 'o'))
        && c.find(|ch| !is_blank(*ch)).is_some_and(|ch| ch.is_ascii_alphabetic() || ch == '_')
}

fn error(line: u32, col: u32, len: u32, message: String, expected: impl Into<String>) -> ParseError {
    ParseError { line, col, len: len.max(1), message, expected: expected.into() }
}

/// Lexes one line (without its line ending). `Ok(None)` when it holds no word to execute.
fn lex_line(line: &str, line_no: u32, rules: &LexRules) -> Result<Option<Block>, ParseError> {
    if is_program_name(line) {
        return Ok(None);
    }
    let mut cur = Cursor { chars: line.chars().peekable(), col: 1 };
    let mut seq = None;
    let mut block_delete = false;
    let mut words = Vec::new();
    let mut leading = true; // only blanks (and the framing `%`) so far
    let mut first_word = true;
    while let Some(c) = cur.peek() {
        let col = cur.col;
        if is_blank(c) {
            cur.bump();
            continue;
        }
        let at_start = std::mem::replace(&mut leading, false);
        match c {
            '%' if at_start => {
                cur.bump();
                leading = true;
            }
            '/' if at_start => {
                cur.bump();
                block_delete = true;
            }
            '(' => {
                cur.bump();
                // Parentheses inside a comment nest (`(#508= (MILL_.25_PROFILE))`, CAM output).
                let mut depth = 1u32;
                loop {
                    match cur.bump() {
                        Some(')') => {
                            depth -= 1;
                            if depth == 0 {
                                break;
                            }
                        }
                        Some('(') => depth += 1,
                        Some(_) => {}
                        None => return Err(error(line_no, col, 1, "unclosed comment".into(), ")")),
                    }
                }
            }
            ';' => break,
            c if c.is_ascii_alphabetic() => {
                cur.bump();
                let letter = c.to_ascii_uppercase();
                if !rules.letters.chars().any(|l| l.to_ascii_uppercase() == letter) {
                    return Err(error(
                        line_no,
                        col,
                        1,
                        format!("word letter `{letter}` is not used by dialect {}", rules.dialect),
                        format!("one of the letters {}", rules.letters),
                    ));
                }
                while cur.peek().is_some_and(is_blank) {
                    cur.bump();
                }
                // `X#1`, `Z[#2*3]`: name the macro feature rather than a missing value.
                if let Some(m @ ('#' | '[')) = cur.peek() {
                    return Err(error(
                        line_no,
                        cur.col,
                        1,
                        unexpected(m, rules.dialect),
                        format!("a number after {letter}, e.g. {letter}12.5"),
                    ));
                }
                let value = number(&mut cur, letter, line_no, col)?;
                let len = cur.col.saturating_sub(col);
                if letter == 'N' {
                    if !first_word {
                        return Err(error(
                            line_no,
                            col,
                            len,
                            "sequence number N must start the block".into(),
                            "N only as the first word of a block",
                        ));
                    }
                    match value.as_int().filter(|n| (0..=MAX_SEQ).contains(n)) {
                        Some(n) => seq = u32::try_from(n).ok(),
                        _ => {
                            return Err(error(
                                line_no,
                                col,
                                len,
                                format!(
                                    "sequence number N{} is not a whole number from 0 to {MAX_SEQ}",
                                    value.display()
                                ),
                                "N and up to 8 digits, e.g. N120",
                            ))
                        }
                    }
                } else {
                    words.push(Word { letter, value, col });
                }
                first_word = false;
            }
            _ => return Err(error(line_no, col, 1, unexpected(c, rules.dialect), EXPECT_WORD)),
        }
    }
    if words.is_empty() {
        return Ok(None);
    }
    Ok(Some(Block { line: line_no, text: line.trim().to_string(), seq, block_delete, words, klartext: None }))
}

/// The message for a character that cannot appear between words.
fn unexpected(c: char, dialect: &str) -> String {
    match c {
        '#' => format!("macro variables (`#`) are not supported by dialect {dialect}"),
        '[' | ']' => format!("bracketed expressions are not supported by dialect {dialect}"),
        '=' => format!("parameter assignment (`=`) is not supported by dialect {dialect}"),
        _ if invisible(c) => format!("unexpected character `{}`", c.escape_unicode()),
        _ => format!("unexpected character `{c}`"),
    }
}

/// Characters that would not show in a message: written as `\u{..}` instead.
fn invisible(c: char) -> bool {
    c.is_control()
        || c.is_whitespace()
        || matches!(c, '\u{200b}'..='\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2060}'..='\u{2064}')
        || c == '\u{feff}'
}

/// Lexes the value of a word whose letter (at `col`) was just consumed.
fn number(cur: &mut Cursor<'_>, letter: char, line_no: u32, col: u32) -> Result<Decimal, ParseError> {
    while cur.peek().is_some_and(is_blank) {
        cur.bump();
    }
    let start = cur.col;
    let negative = match cur.peek() {
        Some(s @ ('+' | '-')) => {
            cur.bump();
            s == '-'
        }
        _ => false,
    };
    let (mut mantissa, mut digits, mut scale) = (0i64, 0u32, 0u32);
    let (mut any_digit, mut point) = (false, false);
    loop {
        match cur.peek() {
            Some(d @ '0'..='9') => {
                cur.bump();
                any_digit = true;
                if point {
                    scale = scale.saturating_add(1);
                }
                // Leading zeros of the integer part are not significant; all fraction digits are.
                if point || mantissa != 0 || d != '0' {
                    digits = digits.saturating_add(1);
                }
                if digits <= MAX_DIGITS {
                    mantissa = mantissa * 10 + i64::from(d as u8 - b'0');
                }
            }
            Some('.') if !point => {
                cur.bump();
                point = true;
            }
            _ => break,
        }
    }
    if !any_digit {
        let consumed = cur.col.saturating_sub(start);
        let len = if consumed == 0 { 1 } else { cur.col.saturating_sub(col) };
        return Err(error(
            line_no,
            col,
            len,
            format!("word {letter} has no value"),
            format!("a number after {letter}, e.g. {letter}12.5"),
        ));
    }
    if digits > MAX_DIGITS {
        return Err(error(
            line_no,
            col,
            cur.col.saturating_sub(col),
            "too many digits".into(),
            format!("at most {MAX_DIGITS} significant digits after {letter}, e.g. {letter}12.5"),
        ));
    }
    // scale <= digits <= MAX_DIGITS, so it fits.
    Ok(Decimal { mantissa: if negative { -mantissa } else { mantissa }, scale: scale as u8, point })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    const LATHE: LexRules =
        LexRules { dialect: "gsk-lathe", letters: "DFGHIKLMNOPQRSTUWXZ", semicolon_ends_block: true };
    const LCNC: LexRules =
        LexRules { dialect: "linuxcnc", letters: "ABCDEFGHIJKLMNOPQRSTUVWXYZ", semicolon_ends_block: false };

    /// Each block as `line:[/][Nseq ]words`, e.g. `3:/N10 G0 X1.`.
    fn render(text: &str, rules: &LexRules) -> Vec<String> {
        let program = parse(text, rules).unwrap_or_else(|e| panic!("{text:?}: {e}"));
        program
            .blocks
            .iter()
            .map(|b| {
                let mut s = format!("{}:", b.line);
                if b.block_delete {
                    s.push('/');
                }
                let mut parts: Vec<String> = b.seq.iter().map(|n| format!("N{n}")).collect();
                parts.extend(b.words.iter().map(|w| format!("{}{}", w.letter, w.value.display())));
                s + &parts.join(" ")
            })
            .collect()
    }

    fn err(text: &str, rules: &LexRules) -> ParseError {
        match parse(text, rules) {
            Ok(p) => panic!("{text:?} parsed: {p:?}"),
            Err(e) => e,
        }
    }

    fn one_word(text: &str) -> Word {
        let p = parse(text, &LCNC).unwrap_or_else(|e| panic!("{text:?}: {e}"));
        assert_eq!(p.blocks.len(), 1);
        assert_eq!(p.blocks[0].words.len(), 1, "{text:?}");
        p.blocks[0].words[0]
    }

    #[rstest]
    #[case("X-.3937", 'X', -3937, 4, true)]
    #[case("Z+2", 'Z', 2, 0, false)]
    #[case("X50.", 'X', 50, 0, true)]
    #[case("X50", 'X', 50, 0, false)]
    #[case("P.5", 'P', 5, 1, true)]
    #[case("F.4", 'F', 4, 1, true)]
    #[case("G84.2", 'G', 842, 1, true)]
    #[case("M251.", 'M', 251, 0, true)]
    #[case("x 12.5", 'X', 125, 1, true)]
    #[case("z\t-0.25", 'Z', -25, 2, true)]
    #[case("X-0", 'X', 0, 0, false)]
    #[case("X0.0001", 'X', 1, 4, true)]
    #[case("X000123.4500", 'X', 1_234_500, 4, true)]
    #[case("X999999999999999999", 'X', 999_999_999_999_999_999, 0, false)]
    #[case("X-999999999.999999999", 'X', -999_999_999_999_999_999, 9, true)]
    #[case("X0.000000000000000001", 'X', 1, 18, true)]
    #[case("X0000000000000000000000000007", 'X', 7, 0, false)]
    fn number_forms(
        #[case] text: &str,
        #[case] letter: char,
        #[case] mantissa: i64,
        #[case] scale: u8,
        #[case] point: bool,
    ) {
        let w = one_word(text);
        assert_eq!((w.letter, w.value, w.col), (letter, Decimal { mantissa, scale, point }, 1));
    }

    #[test]
    fn words_without_separators_keep_their_columns() {
        let p = parse("  G0X50Z0 (c) f.4\r\n", &LATHE).unwrap();
        let b = &p.blocks[0];
        assert_eq!((b.line, b.text.as_str(), b.seq, b.block_delete), (1, "G0X50Z0 (c) f.4", None, false));
        let got: Vec<(char, i64, u32)> =
            b.words.iter().map(|w| (w.letter, w.value.mantissa, w.col)).collect();
        assert_eq!(got, vec![('G', 0, 3), ('X', 50, 5), ('Z', 0, 8), ('F', 4, 15)]);
        assert_eq!(b.word('X').map(|w| w.value), Some(Decimal::int(50)));
    }

    #[rstest]
    #[case::no_percent("G0 X1\nG1 Z2", &["1:G0 X1", "2:G1 Z2"])]
    #[case::framed("junk #[]\n%\nG0 X1\n%\nG1 Z2 ###", &["3:G0 X1"])]
    #[case::header_on_percent_line("%O1200(TOKARKA)\nG0X1\n%", &["1:O1200", "2:G0 X1"])]
    #[case::text_after_closing_percent_ignored("%\nG0\n% M30 #", &["2:G0"])]
    #[case::single_percent_runs_to_end("  %  \nG0\n", &["2:G0"])]
    #[case::empty_program("%\n%\nG0", &[])]
    #[case::percent_after_error_discards_it("G0 ##\nG1 [\n%\nG1 Z1", &["4:G1 Z1"])]
    #[case::crlf("%\r\nG0 X1\r\n\r\n%\r\n", &["2:G0 X1"])]
    #[case::bom_percent("\u{feff}%\nG0", &["2:G0"])]
    #[case::empty("", &[])]
    #[case::blank_lines("\n \n\t\n", &[])]
    #[case::comments("(only comment)\nG0 (move) X1 (日本語 ü #[=*)", &["2:G0 X1"])]
    #[case::parens_nest_inside_comments("G0 (a (b) c) X1", &["1:G0 X1"])]
    #[case::semicolon_vendor_note("G98;-----每分钟进给方式", &["1:G98"])]
    #[case::semicolon_rest_ignored("G0 X1 ; Z2 # (", &["1:G0 X1"])]
    #[case::semicolon_only(";comment only\nM30", &["2:M30"])]
    #[case::semicolon_inside_comment("G0 X1 (a;b) Z2", &["1:G0 X1 Z2"])]
    #[case::block_delete("/G0 X1", &["1:/G0 X1"])]
    #[case::block_delete_blanks_and_seq("  / N10 G1 Z-2.", &["1:/N10 G1 Z-2."])]
    #[case::block_delete_alone("/\n/ (x)", &[])]
    #[case::block_delete_after_percent("%/G0\n%", &["1:/G0"])]
    #[case::seq("N10 G0\nN0 G1\nN99999999 M30", &["1:N10 G0", "2:N0 G1", "3:N99999999 M30"])]
    #[case::seq_lower_case("n5 m3", &["1:N5 M3"])]
    #[case::seq_with_point("N10. G0", &["1:N10 G0"])]
    #[case::seq_only_omitted("N30\nN40 (c)\nN50 G0", &["3:N50 G0"])]
    fn programs(#[case] text: &str, #[case] want: &[&str]) {
        for rules in [&LATHE, &LCNC] {
            assert_eq!(render(text, rules), want, "{text:?} with {}", rules.dialect);
        }
    }

    #[test]
    fn block_text_is_trimmed_source() {
        let p = parse("\u{feff}%\r\n  N10 G0 X1 ; note \r\n%\r\n", &LATHE).unwrap();
        assert_eq!(p.blocks[0].text, "N10 G0 X1 ; note");
        let p = parse("\u{feff}G0 X1", &LATHE).unwrap();
        assert_eq!(p.blocks[0].words[1].col, 4);
    }

    const NO_VALUE: &str = "a number after X, e.g. X12.5";
    const DIGITS: &str = "at most 18 significant digits after X, e.g. X12.5";
    const SEQ_FIRST: &str = "N only as the first word of a block";
    const SEQ_RANGE: &str = "N and up to 8 digits, e.g. N120";
    const LETTERS: &str = "one of the letters DFGHIKLMNOPQRSTUWXZ";

    #[rstest]
    #[case::macro_var(
        "G0\nG1\nG1 X1 #1",
        "3:7+1",
        "macro variables (`#`) are not supported by dialect gsk-lathe",
        EXPECT_WORD
    )]
    #[case::bracket(
        "G1 X1 [X2]",
        "1:7+1",
        "bracketed expressions are not supported by dialect gsk-lathe",
        EXPECT_WORD
    )]
    #[case::close_bracket(
        "G1 X1 ]",
        "1:7+1",
        "bracketed expressions are not supported by dialect gsk-lathe",
        EXPECT_WORD
    )]
    #[case::assignment(
        "G1 X1 =5",
        "1:7+1",
        "parameter assignment (`=`) is not supported by dialect gsk-lathe",
        EXPECT_WORD
    )]
    #[case::star("G1 X1*", "1:6+1", "unexpected character `*`", EXPECT_WORD)]
    #[case::chinese_after_comment("(进给) G1 字", "1:9+1", "unexpected character `字`", EXPECT_WORD)]
    #[case::nul("G0\u{0}", "1:3+1", "unexpected character `\\u{0}`", EXPECT_WORD)]
    #[case::ideographic_space("G0\u{3000}X1", "1:3+1", "unexpected character `\\u{3000}`", EXPECT_WORD)]
    #[case::percent_mid_line("G0 X1 %", "1:7+1", "unexpected character `%`", EXPECT_WORD)]
    #[case::slash_mid_line("G0 / X1", "1:4+1", "unexpected character `/`", EXPECT_WORD)]
    #[case::lone_minus("-5", "1:1+1", "unexpected character `-`", EXPECT_WORD)]
    #[case::lone_point("G0 .", "1:4+1", "unexpected character `.`", EXPECT_WORD)]
    #[case::second_point("G0 X1.2.3", "1:8+1", "unexpected character `.`", EXPECT_WORD)]
    #[case::unclosed("G0 X1 (oops", "1:7+1", "unclosed comment", ")")]
    #[case::unclosed_crlf("%\r\n(a\r\n%", "2:1+1", "unclosed comment", ")")]
    #[case::no_value_eol("G0 X", "1:4+1", "word X has no value", NO_VALUE)]
    #[case::no_value_blank("G0 X Z1", "1:4+1", "word X has no value", NO_VALUE)]
    #[case::minus_only("G0 X-", "1:4+2", "word X has no value", NO_VALUE)]
    #[case::point_only("G0 X.", "1:4+2", "word X has no value", NO_VALUE)]
    #[case::minus_point("G0 X -.", "1:4+4", "word X has no value", NO_VALUE)]
    #[case::too_many("X1234567890123456789", "1:1+20", "too many digits", DIGITS)]
    #[case::too_many_fraction("X0.0000000000000000001", "1:1+22", "too many digits", DIGITS)]
    #[case::too_many_trailing_zeros("X1.000000000000000000", "1:1+21", "too many digits", DIGITS)]
    #[case::seq_not_first("G0 N10", "1:4+3", "sequence number N must start the block", SEQ_FIRST)]
    #[case::seq_twice("N1 N2", "1:4+2", "sequence number N must start the block", SEQ_FIRST)]
    #[case::seq_fraction(
        "N1.5 G0",
        "1:1+4",
        "sequence number N1.5 is not a whole number from 0 to 99999999",
        SEQ_RANGE
    )]
    #[case::seq_negative(
        "N-1",
        "1:1+3",
        "sequence number N-1 is not a whole number from 0 to 99999999",
        SEQ_RANGE
    )]
    #[case::seq_too_big(
        "N123456789",
        "1:1+10",
        "sequence number N123456789 is not a whole number from 0 to 99999999",
        SEQ_RANGE
    )]
    #[case::letter("G0 Y1", "1:4+1", "word letter `Y` is not used by dialect gsk-lathe", LETTERS)]
    #[case::letter_lower("g0 y1", "1:4+1", "word letter `Y` is not used by dialect gsk-lathe", LETTERS)]
    #[case::letter_without_value("A", "1:1+1", "word letter `A` is not used by dialect gsk-lathe", LETTERS)]
    #[case::inside_frame(
        "junk\n%\nG0\nG1 X1 #\n%",
        "4:7+1",
        "macro variables (`#`) are not supported by dialect gsk-lathe",
        EXPECT_WORD
    )]
    #[case::first_error_wins(
        "G0 #\nG1 *",
        "1:4+1",
        "macro variables (`#`) are not supported by dialect gsk-lathe",
        EXPECT_WORD
    )]
    #[case::before_frame_without_percent("G0\nG1 字", "2:4+1", "unexpected character `字`", EXPECT_WORD)]
    fn errors(#[case] text: &str, #[case] at: &str, #[case] message: &str, #[case] expected: &str) {
        let e = err(text, &LATHE);
        let got = (format!("{}:{}+{}", e.line, e.col, e.len), e.message.as_str(), e.expected.as_str());
        assert_eq!(got, (at.to_string(), message, expected), "{text:?}");
    }

    #[test]
    fn letters_follow_the_dialect() {
        assert_eq!(render("G17 Y1 A90 B0 C0 E1 J2 V3", &LCNC), ["1:G17 Y1 A90 B0 C0 E1 J2 V3"]);
        for c in "ABCEJVY".chars() {
            assert!(parse(&format!("G0 {c}1"), &LATHE).is_err(), "{c}");
        }
        let lower = LexRules { dialect: "lower", letters: "gxz", semicolon_ends_block: true };
        assert_eq!(render("G0 x1 Z2", &lower), ["1:G0 X1 Z2"]);
        assert_eq!(err("G0 Y1", &lower).message, "word letter `Y` is not used by dialect lower");
    }

    #[test]
    fn displays_line_col_message_and_expectation() {
        let e = err("G0\nG0 X", &LATHE);
        assert_eq!(e.to_string(), "2:4: word X has no value; expected a number after X, e.g. X12.5");
    }

    #[test]
    fn every_prefix_and_suffix_of_tricky_text_is_safe() {
        let tricky = "\u{feff} %O1(字)\r\n/N10 g0x-.5z+2.(a;b) ;注 #\r\nN2 G84.2 X1.2.3 Y[#1=2]*\n\
                      (unclosed\nX99999999999999999999.9 P. F- \u{0}\u{3000}\t%\n%tail(";
        for rules in [&LATHE, &LCNC] {
            for (i, _) in tricky.char_indices().chain([(tricky.len(), ' ')]) {
                let _ = parse(&tricky[..i], rules);
                let _ = parse(&tricky[i..], rules);
            }
        }
        // Pseudo-random bytes from a fixed LCG, decoded lossily.
        let mut state: u64 = 0x2545_f491_4f6c_dd1d;
        let alphabet = b"GXZNnx0123456789.-+ ()%/;#[]=*\r\n\t\xe5\xad\x97\xff";
        for _ in 0..2000 {
            let len = (state >> 60) as usize * 4;
            let bytes: Vec<u8> = (0..len)
                .map(|_| {
                    state =
                        state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
                    alphabet[(state >> 33) as usize % alphabet.len()]
                })
                .collect();
            let text = String::from_utf8_lossy(&bytes);
            for rules in [&LATHE, &LCNC] {
                let _ = parse(&text, rules);
            }
        }
    }

    #[test]
    fn program_name_lines_execute_nothing() {
        let rules = LexRules { dialect: "t", letters: "GOXN", semicolon_ends_block: true };
        assert_eq!(render("O ENTER OP\nOSTRT\nO0001 (W)\nG0 X1", &rules), vec!["3:O1", "4:G0 X1"]);
    }

    #[test]
    fn huge_inputs_do_not_panic() {
        let digits = format!("X{}", "9".repeat(100_000));
        assert_eq!(err(&digits, &LATHE).message, "too many digits");
        let zeros = format!("X{}1", "0".repeat(100_000));
        assert_eq!(one_word(&zeros).value, Decimal::int(1));
        let long = "G1 X1 ".repeat(200_000);
        assert_eq!(parse(&long, &LATHE).unwrap().blocks[0].words.len(), 400_000);
        let many = "G1 X1.5 Z-2.\n".repeat(29_000);
        let p = parse(&format!("%\n{many}%\n"), &LATHE).unwrap();
        assert_eq!((p.blocks.len(), p.blocks[28_999].line), (29_000, 29_001));
    }
}
