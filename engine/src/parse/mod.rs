//! Parse: program text → blocks of words, with line and column for every word.
//!
//! Owns the lexical layer only: program framing (`%`, `O` numbers), sequence numbers, comments,
//! block delete, words and their exact decimal values, and which letters a dialect accepts
//! ([`LexRules`]). It knows nothing of what a word means: the dialect's interpreter does.
//! Heidenhain Klartext, line and keyword based, has its own parser ([`klartext`]) with the same
//! [`ParseError`] and the same "never panics" rule.

pub mod klartext;
mod lexer;

pub use lexer::parse;

use crate::units::Decimal;

/// The lexical rules of one dialect.
#[derive(Debug, Clone, Copy)]
pub struct LexRules {
    /// Dialect name, for messages.
    pub dialect: &'static str,
    /// Word letters the dialect accepts (upper case).
    pub letters: &'static str,
    /// `;` ends the block and the rest of the line is ignored (GSK/KND/Fanuc end-of-block).
    /// When false, `;` starts a comment to the end of the line (LinuxCNC).
    pub semicolon_ends_block: bool,
}

/// A whole program: the blocks to execute, in order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Program {
    /// Blocks that carry at least one word (comment-only and blank lines are left out).
    pub blocks: Vec<Block>,
}

/// One block (one line of the program, up to an end-of-block).
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    /// 1-based line in the source text.
    pub line: u32,
    /// The source line, trimmed, without its line ending.
    pub text: String,
    /// `N` sequence number, when the block starts with one.
    pub seq: Option<u32>,
    /// True when the block starts with `/` (optional block skip).
    pub block_delete: bool,
    /// The words in the order written (the `N` word is not repeated here).
    pub words: Vec<Word>,
    /// A Klartext block (dialect `heidenhain`); `None` for letter-address blocks.
    pub klartext: Option<Box<klartext::Klartext>>,
}

/// One address word: a letter and its value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Word {
    /// Upper-case letter.
    pub letter: char,
    /// The value exactly as written.
    pub value: Decimal,
    /// 1-based column of the letter (counted in characters).
    pub col: u32,
}

/// A lexical error: where, what is wrong, what was expected.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParseError {
    /// 1-based line.
    pub line: u32,
    /// 1-based column (characters).
    pub col: u32,
    /// Length of the offending text in characters (at least 1).
    pub len: u32,
    /// What is wrong, e.g. "`#` (macro variable) is not supported by dialect gsk-lathe".
    pub message: String,
    /// What would have been accepted, e.g. "a word letter (A C D E F ...)".
    pub expected: String,
}

impl std::fmt::Display for ParseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}: {}; expected {}", self.line, self.col, self.message, self.expected)
    }
}

impl std::error::Error for ParseError {}

impl Block {
    /// The first word with this letter.
    pub fn word(&self, letter: char) -> Option<&Word> {
        self.words.iter().find(|w| w.letter == letter)
    }
}
