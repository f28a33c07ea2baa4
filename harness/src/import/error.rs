//! Import errors and lenient-mode warnings: every fault of a recorded file with its file, line,
//! column, message and what was expected, convertible into [`crate::diag::InputError`].

use std::collections::BTreeMap;
use std::fmt;

use crate::diag::{InputError, Span};

/// What went wrong, as a category (lenient mode counts warnings by it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ErrorKind {
    /// The file could not be read.
    Io,
    /// The header (meta line, CSV header, VCD definitions, column map) is wrong: never lenient.
    Header,
    /// A row or line that does not parse (bad number, wrong field count, bad JSON...).
    BadRow,
    /// A time earlier than the one before it.
    NonMonotonicTime,
    /// A column, key, signal or variable the importer does not know.
    Unknown,
    /// The file ends before it should (no `end` line, a cut line).
    Truncated,
}

impl ErrorKind {
    /// The name of the kind, for warning counts.
    pub fn name(self) -> &'static str {
        match self {
            ErrorKind::Io => "io",
            ErrorKind::Header => "header",
            ErrorKind::BadRow => "bad_row",
            ErrorKind::NonMonotonicTime => "non_monotonic_time",
            ErrorKind::Unknown => "unknown",
            ErrorKind::Truncated => "truncated",
        }
    }

    /// Whether `--lenient` may turn an error of this kind into a counted warning.
    pub fn lenient_ok(self) -> bool {
        !matches!(self, ErrorKind::Io | ErrorKind::Header)
    }
}

/// An error in a recorded file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ImportError {
    /// The file as the user named it.
    pub file: String,
    /// 1-based line (0: the whole file).
    pub line: u64,
    /// 1-based column in characters (0: the whole line or file).
    pub col: u64,
    /// What is wrong.
    pub message: String,
    /// What would have been accepted.
    pub expected: Option<String>,
    /// The category.
    pub kind: ErrorKind,
    /// The text of the line at fault (for the diagnostic's snippet), when known.
    pub line_text: Option<String>,
}

/// Lines above this are reported without a source snippet (the snippet's text would hold one
/// newline per line before it).
const MAX_SNIPPET_LINE: u64 = 1_000_000;

impl ImportError {
    /// An error at `line:col` of `file`.
    pub fn new(kind: ErrorKind, file: &str, line: u64, col: u64, message: impl Into<String>) -> Self {
        ImportError {
            file: file.to_string(),
            line,
            col,
            message: message.into(),
            expected: None,
            kind,
            line_text: None,
        }
    }

    /// Sets what was expected.
    #[must_use]
    pub fn expected(mut self, e: impl Into<String>) -> Self {
        self.expected = Some(e.into());
        self
    }

    /// Sets the text of the line at fault (lossy UTF-8, without its line end).
    #[must_use]
    pub fn with_line(mut self, text: &[u8]) -> Self {
        let t = String::from_utf8_lossy(text);
        self.line_text = Some(t.trim_end_matches(['\r', '\n']).to_string());
        self
    }

    /// `file:line:col` (or less where not known).
    pub fn location(&self) -> String {
        match (self.line, self.col) {
            (0, _) => self.file.clone(),
            (l, 0) => format!("{}:{l}", self.file),
            (l, c) => format!("{}:{l}:{c}", self.file),
        }
    }
}

impl fmt::Display for ImportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.location(), self.message)?;
        if let Some(e) = &self.expected {
            write!(f, "; expected {e}")?;
        }
        Ok(())
    }
}

impl std::error::Error for ImportError {}

impl From<ImportError> for InputError {
    fn from(e: ImportError) -> Self {
        match (&e.line_text, e.line, e.col) {
            (Some(text), line @ 1..=MAX_SNIPPET_LINE, col) => {
                let line32 = u32::try_from(line).unwrap_or(u32::MAX);
                let col32 = u32::try_from(col.max(1)).unwrap_or(u32::MAX);
                let mut source = "\n".repeat((line - 1) as usize);
                source.push_str(text);
                let span = Span::from_line_col(&source, line32, col32, 1);
                InputError::at(e.file, &source, span, e.message, e.expected)
            }
            (_, 0, _) => InputError { file: e.file, message: e.message, expected: e.expected, at: None },
            _ => {
                // No snippet: the location goes in the file name so that the headline keeps it.
                let file = e.location();
                InputError { file, message: e.message, expected: e.expected, at: None }
            }
        }
    }
}

/// How many faults `--lenient` turned into warnings, by kind, with the first few in full.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Warnings {
    /// Warnings by kind.
    pub by_kind: BTreeMap<ErrorKind, u64>,
    /// The first [`Warnings::KEEP`] warnings in full.
    pub first: Vec<ImportError>,
}

impl Warnings {
    /// How many warnings are kept in full.
    pub const KEEP: usize = 20;

    /// Counts `e`.
    pub fn push(&mut self, e: ImportError) {
        *self.by_kind.entry(e.kind).or_insert(0) += 1;
        if self.first.len() < Self::KEEP {
            self.first.push(e);
        }
    }

    /// Total number of warnings.
    pub fn total(&self) -> u64 {
        self.by_kind.values().sum()
    }

    /// Warnings of one kind.
    pub fn count(&self, kind: ErrorKind) -> u64 {
        self.by_kind.get(&kind).copied().unwrap_or(0)
    }
}
