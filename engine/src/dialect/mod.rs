//! Dialects: what the words of a program mean on one family of controls.
//!
//! Each dialect is data (lexical rules, axes, parameter table) plus a small [`Interpreter`] that
//! keeps the modal state and turns blocks into [`Step`]s. The same letter means different things
//! in each (G98 is feed per minute on a GSK lathe, return-to-initial-level on a Fanuc mill): the
//! dialect decides. Shared pieces (modal words, motion words, M/S/T) live in [`common`].

pub mod common;
pub mod fanuc_mill;
pub mod gsk_lathe;
pub mod heidenhain;
pub mod knd_lathe;
pub mod linuxcnc;

use crate::alarm::Alarm;
use crate::exec::PlantConfig;
use crate::params::{ParamDef, Params};
use crate::parse::{Block, LexRules, ParseError, Program};
use crate::plan::{Pos, Step};
use crate::trace::AxisSpec;

/// One dialect.
pub trait Dialect: Sync + std::fmt::Debug {
    /// Name used on the command line and in scenarios.
    fn name(&self) -> &'static str;
    /// Lexical rules.
    fn lex_rules(&self) -> &'static LexRules;
    /// Axes reported in the trace.
    fn axes(&self) -> &'static [AxisSpec];
    /// Parameter table (vendor numbers, defaults, ranges).
    fn param_table(&self) -> &'static [ParamDef];
    /// The plant model's settings from the parameters.
    fn plant_config(&self, params: &Params) -> PlantConfig;
    /// A fresh interpreter in the power-on state.
    fn interpreter(&self, params: &Params) -> Box<dyn Interpreter>;
    /// Parses a program: the shared letter-address lexer with [`Dialect::lex_rules`], unless the
    /// dialect has a program language of its own (`linuxcnc`: expressions, o-words; `heidenhain`:
    /// Klartext).
    fn parse(&self, text: &str) -> Result<Program, ParseError> {
        crate::parse::parse(text, self.lex_rules())
    }
}

/// Keeps the modal state of one run and turns blocks into steps.
pub trait Interpreter {
    /// Interprets one block, appending its steps to `out`. An `Err` is an alarm raised before the
    /// block moves anything.
    fn block(&mut self, block: &Block, out: &mut Vec<Step>) -> Result<(), Alarm>;
    /// CNC reset: cancels cycles and rigid tapping mode, resets the modal groups that a reset
    /// clears; `pos` is where the machine stands now.
    fn reset(&mut self, pos: Pos);
    /// The machine was moved outside the program (overload retract...): re-synchronise.
    fn set_position(&mut self, pos: Pos);
    /// Active modal G codes, for the end summary.
    fn modal(&self) -> Vec<String>;
    /// Whether rigid tapping mode is on (M29 given, not cancelled).
    fn rigid_mode(&self) -> bool;
    /// A parameter changed while running: read the new values (modal state stays).
    fn set_params(&mut self, params: &Params);
    /// The whole program, once, before its first block: a dialect whose calls look ahead in the
    /// file (LinuxCNC's subroutines defined after the main program, `M98` subprograms) keeps it.
    fn program(&mut self, _program: &crate::parse::Program) {}
}

/// Every dialect.
pub static ALL: &[&dyn Dialect] = &[
    &gsk_lathe::GskLathe,
    &fanuc_mill::FanucMill,
    &knd_lathe::KndLathe,
    &linuxcnc::Linuxcnc,
    &heidenhain::Heidenhain,
];

/// Looks a dialect up by name.
pub fn by_name(name: &str) -> Option<&'static dyn Dialect> {
    ALL.iter().copied().find(|d| d.name() == name)
}
