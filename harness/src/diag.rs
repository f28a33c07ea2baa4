//! Diagnostics for input errors: a message, what was expected, and where in which file.
//!
//! One type, [`InputError`], for every error the user can fix in what they gave the harness (an
//! unreadable file, a parse error, a bad parameter file). It renders two ways:
//! - on a terminal, with miette's graphical handler (source snippet, label at the span; no colour
//!   when `NO_COLOR` is set);
//! - otherwise (a pipe, a file, a test), as plain text whose first line is
//!   `file:line:col: message; expected …`, followed by the source line and a caret.
//!
//! Both forms always contain the `file:line:col` text, so scripts and tests can grep for it.

use std::fmt::Write as _;
use std::io::{IsTerminal, Write as _};

/// A place in a source text: 1-based line and column (in characters), and the byte range.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Span {
    /// 1-based line.
    pub line: u32,
    /// 1-based column, counted in characters.
    pub col: u32,
    /// Byte offset of the start in the source text.
    pub offset: usize,
    /// Length in bytes (0 for a point).
    pub len: usize,
}

impl Span {
    /// The span at `line:col` (1-based, characters) of `text`, `len_chars` characters long
    /// (clamped to the end of that line).
    pub fn from_line_col(text: &str, line: u32, col: u32, len_chars: u32) -> Span {
        let line_start = line_start_offset(text, line);
        let rest = &text[line_start..];
        let line_text = rest.split('\n').next().unwrap_or("");
        let line_text = line_text.strip_suffix('\r').unwrap_or(line_text);
        let mut chars = line_text.char_indices().skip(col.saturating_sub(1) as usize);
        let start = chars.next().map_or(line_text.len(), |(i, _)| i);
        let end = line_text[start..]
            .char_indices()
            .nth(len_chars as usize)
            .map_or(line_text.len(), |(i, _)| start + i);
        Span { line, col, offset: line_start + start, len: end - start }
    }
}

/// Byte offset of the start of 1-based `line` in `text` (the end of the text if it has fewer).
fn line_start_offset(text: &str, line: u32) -> usize {
    if line <= 1 {
        return 0;
    }
    text.match_indices('\n').nth(line as usize - 2).map_or(text.len(), |(i, _)| i + 1)
}

/// The largest char boundary of `s` at or before `i` (clamped to the end of `s`).
fn floor_char_boundary(s: &str, i: usize) -> usize {
    let mut i = i.min(s.len());
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// Characters of a source line shown before the marked span (the rest is cut, `…`).
const SNIPPET_BEFORE: usize = 80;
/// Characters of a source line shown from the marked span on.
const SNIPPET_WIDTH: usize = 160;
/// The largest source shown by miette (a larger one is shown in the plain form).
const FANCY_MAX_SOURCE: usize = 1 << 20;

/// A character of a source line as shown in a snippet: itself, or for a control character its
/// picture (`␛` for ESC, `␀` for NUL, U+2400..), for other invisible or direction-changing
/// characters `�` — always one character for one, so that carets stay aligned.
fn visible(c: char) -> char {
    match c {
        '\t' | '\n' => c,
        '\u{0}'..='\u{1f}' => char::from_u32(0x2400 + c as u32).unwrap_or('\u{fffd}'),
        '\u{7f}' => '\u{2421}',
        c if c.is_control() || matches!(c, '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}') => '\u{fffd}',
        c => c,
    }
}

/// An error in something the user gave the harness.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InputError {
    /// The file as the user named it (or `--dialect` and the like for a non-file input).
    pub file: String,
    /// What is wrong.
    pub message: String,
    /// What would have been accepted, when known.
    pub expected: Option<String>,
    /// Where in the file, with the file's text, when known.
    pub at: Option<(Span, String)>,
}

impl InputError {
    /// An error about a whole file (or other input), without a location.
    pub fn new(file: impl Into<String>, message: impl Into<String>) -> Self {
        InputError { file: file.into(), message: message.into(), expected: None, at: None }
    }

    /// An error at `span` of the file whose text is `source`.
    pub fn at(
        file: impl Into<String>,
        source: &str,
        span: Span,
        message: impl Into<String>,
        expected: Option<String>,
    ) -> Self {
        InputError {
            file: file.into(),
            message: message.into(),
            expected,
            at: Some((span, source.to_string())),
        }
    }

    /// `file:line:col` (or just `file` without a location).
    pub fn location(&self) -> String {
        match &self.at {
            Some((s, _)) => format!("{}:{}:{}", self.file, s.line, s.col),
            None => self.file.clone(),
        }
    }

    /// `file:line:col: message; expected …`, the first line of the plain form (what it echoes
    /// from the input made printable, see [`printable`]).
    pub fn headline(&self) -> String {
        let location = printable(&self.location(), 300);
        let message = printable(&self.message, 600);
        match &self.expected {
            Some(e) => format!("{location}: {message}; expected {}", printable(e, 600)),
            None => format!("{location}: {message}"),
        }
    }

    /// The plain form: the headline, then the source line with a caret under the span.
    pub fn render_plain(&self) -> String {
        let mut out = format!("error: {}\n", self.headline());
        if let Some((span, source)) = &self.at {
            // The text line holding the span's first byte. Found from the offset, not the line
            // number: YAML also breaks lines at a lone CR, so a YAML location's line number may
            // not count `\n`s (found by fuzzing). Every index is kept on a char boundary.
            let offset = floor_char_boundary(source, span.offset);
            let start = source[..offset].rfind('\n').map_or(0, |i| i + 1);
            let line_text = source[start..].split('\n').next().unwrap_or("");
            let line_text = line_text.strip_suffix('\r').unwrap_or(line_text);
            let num = span.line.to_string();
            let pad = " ".repeat(num.len());
            let in_line = floor_char_boundary(line_text, offset - start);
            let end = floor_char_boundary(line_text, in_line.saturating_add(span.len));
            // A window of the line around the span (a line may be megabytes long), each
            // character shown as one printable character so that the caret stays under it.
            let before: Vec<char> = line_text[..in_line].chars().collect();
            let skip = before.len().saturating_sub(SNIPPET_BEFORE);
            let marked = line_text[in_line..end].chars().count().clamp(1, SNIPPET_WIDTH);
            let shown: String =
                line_text[..].chars().skip(skip).take(SNIPPET_WIDTH + SNIPPET_BEFORE).map(visible).collect();
            let cut = line_text.chars().count() > skip + SNIPPET_WIDTH + SNIPPET_BEFORE;
            let (lead, tail) = (if skip > 0 { "…" } else { "" }, if cut { "…" } else { "" });
            let _ = writeln!(out, "{pad} |");
            let _ = writeln!(out, "{num} | {lead}{shown}{tail}");
            let prefix: String = before[skip..].iter().map(|&c| if c == '\t' { '\t' } else { ' ' }).collect();
            let lead_pad = if skip > 0 { " " } else { "" };
            let _ = writeln!(out, "{pad} | {lead_pad}{prefix}{}", "^".repeat(marked));
        }
        out
    }

    /// The graphical form (miette), with or without colour; the plain form for a source that
    /// is too large or whose line is too long to show whole.
    pub fn render_fancy(&self, color: bool) -> String {
        if let Some((span, text)) = &self.at {
            let at = floor_char_boundary(text, span.offset);
            let line_start = text[..at].rfind('\n').map_or(0, |i| i + 1);
            let line_len = text[line_start..].find('\n').unwrap_or(text.len() - line_start);
            if text.len() > FANCY_MAX_SOURCE || line_len > SNIPPET_WIDTH {
                return self.render_plain();
            }
        }
        let theme =
            if color { miette::GraphicalTheme::unicode() } else { miette::GraphicalTheme::unicode_nocolor() };
        let handler = miette::GraphicalReportHandler::new_themed(theme).without_primary_span_start();
        let diag = Fancy::from(self);
        let mut out = String::new();
        if handler.render_report(&mut out, &diag).is_err() {
            return self.render_plain();
        }
        out
    }

    /// Prints the error to standard error: graphical on a terminal, plain otherwise.
    pub fn report(&self) {
        let stderr = std::io::stderr();
        let text = if stderr.is_terminal() {
            let no_color = std::env::var_os("NO_COLOR").is_some_and(|v| !v.is_empty());
            self.render_fancy(!no_color)
        } else {
            self.render_plain()
        };
        let mut lock = stderr.lock();
        let _ = lock.write_all(text.as_bytes());
        let _ = lock.flush();
    }
}

impl std::fmt::Display for InputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.headline())
    }
}

impl std::error::Error for InputError {}

/// The miette view of an [`InputError`].
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
#[error("{headline}")]
struct Fancy {
    headline: String,
    #[source_code]
    src: Option<miette::NamedSource<String>>,
    #[label("{label}")]
    span: Option<miette::SourceSpan>,
    label: String,
}

impl From<&InputError> for Fancy {
    fn from(e: &InputError) -> Self {
        let headline = format!("{}: {}", printable(&e.location(), 300), printable(&e.message, 600));
        let label = e
            .expected
            .as_deref()
            .map_or_else(|| "here".to_string(), |x| format!("expected {}", printable(x, 600)));
        match &e.at {
            Some((span, text)) => {
                // Kept inside the text and on char boundaries, whatever the span says.
                let start = floor_char_boundary(text, span.offset);
                let end = floor_char_boundary(text, span.offset.saturating_add(span.len)).max(start);
                // Shown with control characters as visible ones; the span follows the change
                // of byte lengths.
                let shown = |s: &str| s.replace("\r\n", "\n").chars().map(visible).collect::<String>();
                let (new_start, marked) = (shown(&text[..start]).len(), shown(&text[start..end]).len());
                Fancy {
                    headline,
                    src: Some(miette::NamedSource::new(printable(&e.file, 300), shown(text))),
                    span: Some(miette::SourceSpan::new(new_start.into(), marked)),
                    label,
                }
            }
            None => Fancy {
                headline: match &e.expected {
                    Some(x) => format!("{headline}; expected {}", printable(x, 600)),
                    None => headline,
                },
                src: None,
                span: None,
                label,
            },
        }
    }
}

/// Text from a file, a program or an adapter made safe to echo on a terminal: control
/// characters (escape sequences, NUL, a lone CR, bidirectional overrides) are written as
/// `\u{1b}`, a tab as a space; at most `max` characters are kept, then `…`.
pub fn printable(s: &str, max: usize) -> String {
    let mut out = String::with_capacity(s.len().min(max * 2));
    for (n, c) in s.chars().enumerate() {
        if n >= max {
            out.push('…');
            break;
        }
        match c {
            '\t' => out.push(' '),
            c if c.is_control() || matches!(c, '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}') => {
                let _ = write!(out, "\\u{{{:x}}}", c as u32);
            }
            c => out.push(c),
        }
    }
    out
}

/// A message of the YAML library in the project's words: the library speaks of its own types and
/// options ("invalid u64", "set DuplicateKeyPolicy in Options", "budget breached: Nodes {..}"),
/// which mean nothing to the person who wrote the file.
pub fn yaml_wording(message: &str) -> String {
    if let Some(rest) = message.strip_prefix("duplicate mapping key") {
        let key = rest.strip_prefix(": ").and_then(|k| k.split(", set DuplicateKeyPolicy").next());
        return match key {
            Some(k) => {
                format!("key `{}` given twice (each key may appear once in a mapping)", printable(k, 60))
            }
            None => "a key given twice (each key may appear once in a mapping)".into(),
        };
    }
    if let Some(rest) = message.strip_prefix("budget breached: ") {
        let what = rest.split([' ', '{']).next().unwrap_or("");
        let plain = match what {
            "Nodes" | "Events" => "too many values",
            "ScalarBytes" | "InputBytes" | "CommentBytes" => "a value or the file is too long",
            "Depth" | "InclusionDepth" | "PropertyExpansionDepth" => "nested too deeply",
            "Aliases"
            | "Anchors"
            | "AliasAnchorRatio"
            | "RecordedAnchorEvents"
            | "RecordedAnchorBytes"
            | "MergeKeys" => "too many anchors, aliases or merge keys",
            "Documents" => "more than one document",
            _ => "too large",
        };
        return format!("the YAML is beyond what the tool reads: {plain}");
    }
    let mut out = message.to_string();
    for (lib, ours) in [
        ("invalid u8", "expected a whole number of 0 or more, within range"),
        ("invalid u16", "expected a whole number of 0 or more, within range"),
        ("invalid u32", "expected a whole number of 0 or more, within range"),
        ("invalid u64", "expected a whole number of 0 or more, within range"),
        ("invalid usize", "expected a whole number of 0 or more, within range"),
        ("invalid i8", "expected a whole number, within range"),
        ("invalid i16", "expected a whole number, within range"),
        ("invalid i32", "expected a whole number, within range"),
        ("invalid i64", "expected a whole number, within range"),
        ("invalid f32", "expected a number"),
        ("invalid f64", "expected a number"),
        ("invalid floating point", "expected a number"),
    ] {
        if out == lib || out.starts_with(&format!("{lib}:")) || out.starts_with(&format!("{lib} ")) {
            out = out.replacen(lib, ours, 1);
        }
    }
    out
}

/// A report of several lines made safe for a terminal: as [`printable`] line by line (line
/// breaks and tabs kept, nothing cut), for reports that quote what a recorded trace or an
/// adapter said.
pub fn printable_lines(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '\n' | '\t' => out.push(c),
            c if c.is_control() || matches!(c, '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}') => {
                let _ = write!(out, "\\u{{{:x}}}", c as u32);
            }
            c => out.push(c),
        }
    }
    out
}

/// A parse error of `text` (the file `name`) as an input error at its span.
pub fn parse_error(name: &str, text: &str, e: &nc_engine::ParseError) -> InputError {
    let span = Span::from_line_col(text, e.line, e.col, e.len.max(1));
    let expected = (!e.expected.is_empty()).then(|| e.expected.clone());
    InputError::at(name, text, span, e.message.clone(), expected)
}

#[cfg(test)]
mod tests {
    use super::*;

    const SRC: &str = "G98\r\n\tG0 X50\n#1=5\n";

    #[test]
    fn span_from_line_col_counts_characters_and_clamps() {
        let s = Span::from_line_col(SRC, 2, 2, 2);
        assert_eq!((s.offset, s.len), (6, 2));
        assert_eq!(&SRC[s.offset..s.offset + s.len], "G0");
        let s = Span::from_line_col(SRC, 3, 1, 1);
        assert_eq!(&SRC[s.offset..s.offset + s.len], "#");
        let s = Span::from_line_col(SRC, 2, 6, 10);
        assert_eq!(&SRC[s.offset..s.offset + s.len], "50");
        let s = Span::from_line_col("é#", 1, 2, 1);
        assert_eq!((s.offset, s.len), (2, 1));
        let s = Span::from_line_col("ab", 9, 9, 1);
        assert_eq!((s.offset, s.len), (2, 0));
    }

    fn err() -> InputError {
        let span = Span::from_line_col(SRC, 3, 1, 1);
        InputError::at("prog.nc", SRC, span, "macro variables", Some("a word letter".into()))
    }

    #[test]
    fn plain_form_has_location_snippet_and_caret() {
        let text = err().render_plain();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "error: prog.nc:3:1: macro variables; expected a word letter");
        assert_eq!(lines[2], "3 | #1=5");
        assert_eq!(lines[3], "  | ^");
    }

    #[test]
    fn plain_caret_keeps_tabs_aligned() {
        let span = Span::from_line_col(SRC, 2, 5, 3);
        let text = InputError::at("p.nc", SRC, span, "m", None).render_plain();
        assert!(text.contains("2 | \tG0 X50\n  | \t   ^^^\n"), "{text}");
    }

    #[test]
    fn fancy_form_has_location_and_label() {
        let text = err().render_fancy(false);
        assert!(text.contains("prog.nc:3:1: macro variables"), "{text}");
        assert!(text.contains("#1=5"), "{text}");
        assert!(text.contains("expected a word letter"), "{text}");
        assert!(!text.contains('\x1b'), "{text}");
    }

    #[test]
    fn a_span_off_its_line_or_inside_a_character_renders() {
        // A YAML location after a lone CR: line 2 for YAML, still line 1 by `\n`; the offset
        // decides which text is shown. Then spans that end or start inside `é` (2 bytes).
        let src = "a: 1\rbé: 2\nc: 3\n";
        let span = Span { line: 2, col: 1, offset: 5, len: 3 };
        let text = InputError::at("s.yaml", src, span, "unknown field", None).render_plain();
        // The lone CR is shown as its picture: written raw it would return the cursor.
        assert!(text.contains("2 | a: 1␍bé: 2\n"), "{text}");
        for (offset, len) in [(5, 2), (7, 1), (7, 99), (99, 1), (0, usize::MAX)] {
            let e = InputError::at("s.yaml", src, Span { line: 9, col: 1, offset, len }, "m", None);
            assert!(e.render_plain().starts_with("error: s.yaml:9:1: m"));
            assert!(e.render_fancy(false).contains("s.yaml:9:1: m"));
        }
    }

    #[test]
    fn errors_without_location_name_the_file() {
        let e = InputError::new("missing.nc", "cannot read: No such file");
        assert_eq!(e.render_plain(), "error: missing.nc: cannot read: No such file\n");
        assert!(e.render_fancy(false).contains("missing.nc: cannot read"));
    }

    #[test]
    fn printable_escapes_control_characters_and_truncates() {
        assert_eq!(printable("G0\u{1b}[2J\tX1\0", 100), "G0\\u{1b}[2J X1\\u{0}");
        assert_eq!(printable("abcdef", 3), "abc…");
        assert_eq!(printable("a\u{202e}b", 10), "a\\u{202e}b");
    }

    #[test]
    fn yaml_errors_are_said_in_the_projects_words() {
        assert_eq!(yaml_wording("invalid u64"), "expected a whole number of 0 or more, within range");
        assert_eq!(
            yaml_wording("duplicate mapping key: title, set DuplicateKeyPolicy in Options if acceptable"),
            "key `title` given twice (each key may appear once in a mapping)"
        );
        assert_eq!(
            yaml_wording("budget breached: ScalarBytes { total_scalar_bytes: 1 }"),
            "the YAML is beyond what the tool reads: a value or the file is too long"
        );
        for m in ["budget breached: Nodes { nodes: 250001 }", "invalid floating point", "invalid i32"] {
            let w = yaml_wording(m);
            assert!(!w.contains("budget") && !w.contains("invalid") && !w.contains("Options"), "{w}");
        }
    }

    #[test]
    fn parse_errors_keep_line_col_and_expected() {
        let text = "G98\n#1=5\n";
        let e = nc_engine::ParseError {
            line: 2,
            col: 1,
            len: 1,
            message: "macro".into(),
            expected: "a word".into(),
        };
        let ie = parse_error("p.nc", text, &e);
        assert_eq!(ie.headline(), "p.nc:2:1: macro; expected a word");
        let (span, _) = ie.at.unwrap();
        assert_eq!(&text[span.offset..span.offset + span.len], "#");
    }
}
