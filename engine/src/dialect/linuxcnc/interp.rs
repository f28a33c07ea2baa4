//! The LinuxCNC interpreter's program flow (rules LCNC-LEX-02..04): each block
//! is parsed again from its text, its expressions evaluated against the parameter store and the
//! machine's position, and run by [`Machine`]. O-word structures are gathered from their first
//! line to their end line and run as one when the end is read (their steps belong to the block of
//! the end line; alarms keep the line of the statement that raised them). `sub` ... `endsub`
//! defines a subroutine, `call` runs it with `#1..#30` set from its arguments; `if`/`elseif`/
//! `else`, `while`, `do`/`while`, `repeat`, `break`, `continue`, `return`. A block may run at
//! most [`MAX_LINES`] statements and plan [`MAX_STEPS`] steps (an endless `while` ends in
//! NC-1098, never in a hang).

use std::collections::BTreeMap;

use super::eval::{param_index, Store};
use super::machine::{alarm, Eb, Machine};
use super::ngc::{parse_line, Ctrl, Line, Target};
use super::END_OF_FILE;
use crate::alarm::{Alarm, AlarmKind};
use crate::dialect::Interpreter;
use crate::params::Params;
use crate::parse::Block;
use crate::plan::{Pos, Step};
use crate::units::Nm;

/// Most statements one block may run (loops and calls included).
pub const MAX_LINES: u64 = 1_000_000;
/// Most steps one block may plan.
pub const MAX_STEPS: usize = 2_000_000;
/// Deepest subroutine nesting (LinuxCNC: "Too many subroutine levels").
const MAX_DEPTH: usize = 10;
/// Most o-word blocks (if, while, do, repeat, a subroutine's body) open inside one another at a
/// time: the interpreter walks them recursively, so the depth is bounded whatever the program
/// (a fuzzed program of 5 000 nested `if` blocks overflowed the stack, issue 15).
const MAX_NESTING: usize = 200;

/// How a run of statements ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Flow {
    Normal,
    Break,
    Continue,
    Return,
    End,
}

/// A structure being gathered at the top level.
#[derive(Debug)]
struct Gather {
    label: String,
    lines: Vec<Line>,
}

/// The `linuxcnc` interpreter.
#[derive(Debug)]
pub struct LcncInterp {
    m: Machine,
    store: Store,
    subs: BTreeMap<String, Vec<Line>>,
    gather: Option<Gather>,
    depth: usize,
    /// o-word blocks open now (at most [`MAX_NESTING`]).
    nesting: usize,
    budget: u64,
    /// Every line of the program, for subroutines defined after their call and `M98`.
    program: Vec<Line>,
    /// The value of the `return` / `endsub` that ended the present call.
    returned: Option<f64>,
    /// The parameters, for the read-ahead's own interpreter.
    params: Params,
    /// An error LinuxCNC's read-ahead finds before the program runs (LCNC-LEX-05): raised by the
    /// first block, before anything moves.
    refused: Option<Alarm>,
    /// An error of LinuxCNC's read phase its read-ahead finds (LCNC-LEX-05): reported by the first
    /// block without stopping; the lines queued before it run, then the program ends.
    read_error: Option<ReadError>,
}

/// A read-phase error found by the read-ahead, and where the program it stopped ends.
#[derive(Debug, Clone)]
struct ReadError {
    alarm: Alarm,
    /// Reported (by the first block).
    reported: bool,
    /// The last block whose steps LinuxCNC queued, and how many of its steps (the rest, a
    /// straight feed LinuxCNC's canon still held back, never reach motion): the run halts there.
    halt: Option<(u32, usize)>,
}

/// What a planned step is to LinuxCNC's canonical layer before motion: a straight feed is held
/// back (emccanon.cc `see_segment`: chained for blending until another canonical command flushes
/// it), bookkeeping makes no command, anything else flushes the held feed.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Queued {
    Feed,
    Flush,
    Quiet,
}

fn queued_as(s: &Step) -> Queued {
    match s {
        Step::Feed { .. } => Queued::Feed,
        Step::Phase(_) | Step::HoldSuppress(_) | Step::PathMode { .. } => Queued::Quiet,
        _ => Queued::Flush,
    }
}

/// Most steps LinuxCNC's task interprets ahead of motion (its interpreter list,
/// `EMC_TASK_INTERP_MAX_LEN`, holds 1000 canonical commands; one step here stands for one).
const READ_AHEAD_MAX: usize = 1000;

impl LcncInterp {
    /// Power-on state.
    pub fn new(p: &Params) -> Self {
        LcncInterp {
            m: Machine::new(p),
            store: Store::new(),
            subs: BTreeMap::new(),
            gather: None,
            depth: 0,
            nesting: 0,
            budget: 0,
            program: Vec::new(),
            returned: None,
            params: p.clone(),
            refused: None,
            read_error: None,
        }
    }

    /// LinuxCNC's task interprets the program ahead of motion, up to a queue buster (M0, M1,
    /// M60, the program end) or a full interpreter list: an execute-phase error found there
    /// aborts the program before any of it runs (LCNC-LEX-05, DEC-145; emctaskmain.cc
    /// readahead_reading: interp_list.clear() and emcAbortCleanup on an execute error; through
    /// the adapter: no M3, no move before the refusal). A copy of the interpreter reads ahead.
    fn read_ahead(&mut self, program: &crate::parse::Program) {
        let mut ahead = LcncInterp::new(&self.params);
        ahead.program = self.program.clone();
        let mut queued = 0;
        let mut out = Vec::new();
        // Each block read: its line and what its steps are to the canonical layer.
        let mut read: Vec<(u32, Vec<Queued>)> = Vec::new();
        for b in &program.blocks {
            out.clear();
            if let Err(a) = ahead.block(b, &mut out) {
                // Only an error of LinuxCNC's execute phase (converting a canned cycle, a spindle
                // that is not turning) aborts the read-ahead; an error of its read phase (a word
                // missing or misplaced, the file's end) stops the reading and the lines before
                // run (through the adapter: G76 without J, G33 without K, a file without M2):
                // it is reported at once and the program ends after them (DEC-150).
                // NC-1098 (this project's bound on a runaway block) and NC-1004 (not modelled)
                // are not LinuxCNC's errors: raised where the program reaches them.
                if ahead.m.cycle_error || a.kind == AlarmKind::LcncSpindle {
                    self.refused = Some(a);
                } else if !matches!(a.kind, AlarmKind::LcncLoopLimit | AlarmKind::NotModelled) {
                    self.read_error = Some(ReadError { alarm: a, reported: false, halt: halt_point(&read) });
                }
                return;
            }
            read.push((b.line, out.iter().map(queued_as).collect()));
            queued += out.len();
            let busts = out.iter().any(|s| matches!(s, Step::Stop { .. } | Step::End));
            if ahead.m.ended || busts || queued >= READ_AHEAD_MAX {
                return;
            }
        }
    }

    fn err(line: u32, text: impl Into<String>) -> Alarm {
        alarm(AlarmKind::LcncInterpreter, text, line, None)
    }

    /// Runs statements in order; structures are found by their labels.
    fn run_lines(&mut self, lines: &[Line], out: &mut Vec<Step>) -> Result<Flow, Alarm> {
        if self.nesting >= MAX_NESTING {
            let line = lines.first().map_or(0, |l| l.line);
            return Err(Self::err(line, format!("Too many nested o-word blocks (more than {MAX_NESTING})")));
        }
        self.nesting += 1;
        let flow = self.run_nested(lines, out);
        self.nesting -= 1;
        flow
    }

    fn run_nested(&mut self, lines: &[Line], out: &mut Vec<Step>) -> Result<Flow, Alarm> {
        let mut i = 0;
        while i < lines.len() {
            let l = &lines[i];
            self.tick(l.line, out)?;
            let Some(o) = &l.oword else {
                let flow = self.plain(l, out)?;
                if self.m.ended {
                    return Ok(Flow::End);
                }
                if flow != Flow::Normal {
                    return Ok(flow);
                }
                i += 1;
                continue;
            };
            let end_of = |pred: &dyn Fn(&Ctrl) -> bool| {
                lines[i + 1..]
                    .iter()
                    .position(|x| x.oword.as_ref().is_some_and(|p| p.label == o.label && pred(&p.ctrl)))
                    .map(|k| i + 1 + k)
                    .ok_or_else(|| Self::err(l.line, format!("o{} has no matching end", o.label)))
            };
            match &o.ctrl {
                Ctrl::Sub => {
                    let end = end_of(&|c| matches!(c, Ctrl::EndSub(_)))?;
                    if let Some(n) = lines[i + 1..end].iter().find(|x| is_sub(x)) {
                        return Err(Self::err(n.line, "Nested subroutine definition"));
                    }
                    // The body ends with its `endsub` (which may return a value).
                    self.subs.insert(o.label.clone(), lines[i + 1..=end].to_vec());
                    i = end + 1;
                }
                Ctrl::If(_) => {
                    let end = end_of(&|c| matches!(c, Ctrl::EndIf))?;
                    let flow = self.run_if(&lines[i..=end], out)?;
                    if flow != Flow::Normal {
                        return Ok(flow);
                    }
                    i = end + 1;
                }
                Ctrl::While(cond) => {
                    let end = end_of(&|c| matches!(c, Ctrl::EndWhile))?;
                    while self.truth(cond, l.line)? {
                        self.tick(l.line, out)?;
                        match self.run_lines(&lines[i + 1..end], out)? {
                            Flow::Break => break,
                            Flow::Normal | Flow::Continue => {}
                            f => return Ok(f),
                        }
                    }
                    i = end + 1;
                }
                Ctrl::Do => {
                    let end = end_of(&|c| matches!(c, Ctrl::While(_)))?;
                    let Some(Ctrl::While(cond)) = lines[end].oword.as_ref().map(|o| &o.ctrl) else {
                        return Err(Self::err(l.line, "do without while"));
                    };
                    loop {
                        self.tick(l.line, out)?;
                        match self.run_lines(&lines[i + 1..end], out)? {
                            Flow::Break => break,
                            Flow::Normal | Flow::Continue => {}
                            f => return Ok(f),
                        }
                        if !self.truth(cond, lines[end].line)? {
                            break;
                        }
                    }
                    i = end + 1;
                }
                Ctrl::Repeat(n) => {
                    let end = end_of(&|c| matches!(c, Ctrl::EndRepeat))?;
                    let n = self.value(n, l.line)?.max(0.0).round() as u64;
                    for _ in 0..n {
                        self.tick(l.line, out)?;
                        match self.run_lines(&lines[i + 1..end], out)? {
                            Flow::Break => break,
                            Flow::Normal | Flow::Continue => {}
                            f => return Ok(f),
                        }
                    }
                    i = end + 1;
                }
                Ctrl::Break => return Ok(Flow::Break),
                Ctrl::Continue => return Ok(Flow::Continue),
                Ctrl::Return(v) | Ctrl::EndSub(v) => {
                    if self.depth == 0 {
                        return Err(Self::err(l.line, "not in a subroutine definition"));
                    }
                    self.returned = v.as_ref().map(|v| self.value(v, l.line)).transpose()?;
                    return Ok(Flow::Return);
                }
                Ctrl::Call(args) => {
                    if self.call(&o.label, args, l.line, out)? == Flow::End {
                        return Ok(Flow::End);
                    }
                    i += 1;
                }
                Ctrl::ElseIf(_) | Ctrl::Else | Ctrl::EndIf | Ctrl::EndWhile | Ctrl::EndRepeat => {
                    return Err(Self::err(
                        l.line,
                        format!("o{}: end of a structure that was not started", o.label),
                    ));
                }
            }
        }
        Ok(Flow::Normal)
    }

    /// Counts one statement or loop turn against the block's budget (NC-1098 beyond it).
    fn tick(&mut self, line: u32, out: &[Step]) -> Result<(), Alarm> {
        self.budget += 1;
        if self.budget > MAX_LINES || out.len() > MAX_STEPS {
            return Err(alarm(
                AlarmKind::LcncLoopLimit,
                format!("more than {MAX_LINES} statements or {MAX_STEPS} steps in one block"),
                line,
                None,
            ));
        }
        Ok(())
    }

    /// `if` … `elseif` … `else` … `endif` (the slice ends at `endif`).
    fn run_if(&mut self, lines: &[Line], out: &mut Vec<Step>) -> Result<Flow, Alarm> {
        let label = lines[0].oword.as_ref().map(|o| o.label.clone()).unwrap_or_default();
        let heads: Vec<usize> =
            (0..lines.len()).filter(|&k| lines[k].oword.as_ref().is_some_and(|o| o.label == label)).collect();
        for w in heads.windows(2) {
            let (h, next) = (w[0], w[1]);
            let taken = match &lines[h].oword.as_ref().map(|o| &o.ctrl) {
                Some(Ctrl::If(c)) | Some(Ctrl::ElseIf(c)) => self.truth(c, lines[h].line)?,
                Some(Ctrl::Else) => true,
                _ => false,
            };
            if taken {
                return self.run_lines(&lines[h + 1..next], out);
            }
        }
        Ok(Flow::Normal)
    }

    fn call(
        &mut self,
        label: &str,
        args: &[super::ngc::Expr],
        line: u32,
        out: &mut Vec<Step>,
    ) -> Result<Flow, Alarm> {
        if !self.subs.contains_key(label) {
            self.define_later(label)?;
        }
        let Some(body) = self.subs.get(label).cloned() else {
            let text =
                if label.starts_with('<') { "Named oword not defined" } else { "Unknown oword number" };
            return Err(Self::err(line, format!("{text}: o{label}")));
        };
        if self.depth >= MAX_DEPTH {
            return Err(Self::err(line, "Too many subroutine levels"));
        }
        let values = args.iter().map(|a| self.value(a, line)).collect::<Result<Vec<f64>, Alarm>>()?;
        let saved = self.store.enter(&values);
        self.depth += 1;
        self.returned = None;
        let flow = self.run_lines(&body, out);
        self.depth -= 1;
        self.store.leave(&saved);
        let returned = self.returned.take();
        self.store.set_returned(returned);
        match flow? {
            Flow::End => Ok(Flow::End),
            Flow::Break | Flow::Continue => Err(Self::err(line, "break or continue outside a loop")),
            _ => Ok(Flow::Normal),
        }
    }

    fn value(&self, e: &super::ngc::Expr, line: u32) -> Result<f64, Alarm> {
        self.store.eval(e, &self.m.system()).map_err(|t| Self::err(line, t))
    }

    fn truth(&self, e: &super::ngc::Expr, line: u32) -> Result<bool, Alarm> {
        Ok(self.value(e, line)? != 0.0)
    }

    /// A subroutine called before its definition: LinuxCNC reads on in the file for it.
    fn define_later(&mut self, label: &str) -> Result<(), Alarm> {
        let is_end = |x: &Line| {
            x.oword.as_ref().is_some_and(|o| o.label == label && matches!(o.ctrl, Ctrl::EndSub(_)))
        };
        let start = self
            .program
            .iter()
            .position(|x| x.oword.as_ref().is_some_and(|o| o.label == label && matches!(o.ctrl, Ctrl::Sub)));
        let Some(start) = start else { return Ok(()) };
        let Some(len) = self.program[start + 1..].iter().position(is_end) else { return Ok(()) };
        let body = &self.program[start + 1..=start + 1 + len];
        if let Some(n) = body.iter().find(|x| is_sub(x)) {
            return Err(Self::err(n.line, "Nested subroutine definition"));
        }
        self.subs.insert(label.to_string(), body.to_vec());
        Ok(())
    }

    /// `M98 P<n> L<count>`: runs the lines after the program number `O<n>` up to its `M99`,
    /// `count` times, with the caller's parameters (Fanuc-style: no local `#1..#30`).
    fn subprogram(&mut self, n: f64, count: f64, line: u32, out: &mut Vec<Step>) -> Result<Flow, Alarm> {
        let number = n.round() as u32;
        let start = self.program.iter().position(|x| x.number == Some(number) && n >= 0.0);
        let Some(start) = start else {
            return Err(Self::err(line, format!("Unknown subprogram O{number} called by M98")));
        };
        let m99 =
            |x: &Line| x.words.iter().any(|w| w.letter == 'M' && w.value == super::ngc::Expr::Num(99.0));
        let Some(len) = self.program[start + 1..].iter().position(m99) else {
            return Err(Self::err(line, format!("Subprogram O{number} has no M99")));
        };
        let body = self.program[start + 1..=start + 1 + len].to_vec();
        if self.depth >= MAX_DEPTH {
            return Err(Self::err(line, "Too many subroutine levels"));
        }
        for _ in 0..count.round().max(0.0) as u64 {
            self.tick(line, out)?;
            self.depth += 1;
            let flow = self.run_lines(&body, out);
            self.depth -= 1;
            if flow? == Flow::End {
                return Ok(Flow::End);
            }
        }
        Ok(Flow::Normal)
    }

    /// A line of words and parameter settings; `M98` calls a subprogram after the line's other
    /// words, `M99` returns from one.
    fn plain(&mut self, l: &Line, out: &mut Vec<Step>) -> Result<Flow, Alarm> {
        let sys = self.m.system();
        let mut eb = Eb::new(l.line);
        let mut words = Vec::with_capacity(l.words.len());
        for w in &l.words {
            let v = self
                .store
                .eval(&w.value, &sys)
                .map_err(|t| alarm(AlarmKind::LcncInterpreter, t, l.line, Some(w.col)))?;
            words.push((w.letter, v, w.col));
        }
        let has_m = |n: f64| words.iter().any(|&(c, v, _)| c == 'M' && v == n);
        let (m98, m99) = (has_m(98.0), has_m(99.0));
        let (mut p, mut count) = (None, 1.0);
        for &(letter, v, col) in &words {
            if letter == 'M' && (v == 98.0 || v == 99.0) {
                continue;
            }
            if m98 && letter == 'P' {
                p = Some(v);
                continue;
            }
            if m98 && letter == 'L' {
                count = v;
                continue;
            }
            eb.push(letter, v, col).map_err(|t| alarm(AlarmKind::LcncInterpreter, t, l.line, Some(col)))?;
        }
        // Settings take effect after the whole line is read (RS274NGC), before it runs.
        let mut sets = Vec::with_capacity(l.sets.len());
        for (t, e) in &l.sets {
            let v = self.value(e, l.line)?;
            sets.push((t, v));
        }
        for (t, v) in sets {
            match t {
                Target::Named(n) => self.store.write_named(n, v).map_err(|e| Self::err(l.line, e))?,
                Target::Num(i) => {
                    let n = param_index(self.value(i, l.line)?).map_err(|e| Self::err(l.line, e))?;
                    self.store.write_num(n, v);
                }
            }
        }
        self.m.run(&eb, out)?;
        if m98 {
            let Some(p) = p else { return Err(Self::err(l.line, "P word missing with M98")) };
            return self.subprogram(p, count, l.line, out);
        }
        if m99 {
            if self.depth == 0 {
                return Err(alarm(
                    AlarmKind::NotModelled,
                    "M99 in the main program (an endless program loop) is not modelled",
                    l.line,
                    None,
                ));
            }
            return Ok(Flow::Return);
        }
        Ok(Flow::Normal)
    }
}

impl Interpreter for LcncInterp {
    fn block(&mut self, block: &Block, out: &mut Vec<Step>) -> Result<(), Alarm> {
        if let Some(a) = self.refused.take() {
            return Err(a);
        }
        if let Some(r) = &mut self.read_error {
            if !r.reported {
                r.reported = true;
                out.push(Step::Report(r.alarm.clone()));
            }
            let first = out.len();
            match r.halt {
                Some((line, keep)) if line == block.line => {
                    self.read_error = None;
                    if keep > 0 {
                        self.block(block, out)?;
                        out.truncate(first + keep);
                    }
                    out.push(Step::Halt);
                    return Ok(());
                }
                None => {
                    out.push(Step::Halt);
                    return Ok(());
                }
                Some(_) => {}
            }
        }
        self.budget = 0;
        if block.text == END_OF_FILE {
            return Err(Self::err(block.line, "File ended with no percent sign or program end"));
        }
        let line = parse_line(&block.text, block.line)
            .map_err(|e| Self::err(e.line, e.message).at(e.line, Some(e.col)))?;
        if let Some(g) = &mut self.gather {
            if is_sub(&g.lines[0]) && is_sub(&line) {
                self.gather = None;
                return Err(Self::err(line.line, "Nested subroutine definition"));
            }
            let closes = line.oword.as_ref().is_some_and(|o| {
                o.label == g.label
                    && matches!(
                        o.ctrl,
                        Ctrl::EndSub(_) | Ctrl::EndIf | Ctrl::EndWhile | Ctrl::EndRepeat | Ctrl::While(_)
                    )
            });
            let is_do = g.lines[0].oword.as_ref().is_some_and(|o| matches!(o.ctrl, Ctrl::Do));
            let is_while = g.lines[0].oword.as_ref().is_some_and(|o| matches!(o.ctrl, Ctrl::While(_)));
            // A `while` closes a `do`; `endwhile` closes a `while`.
            let closes = closes
                && !(is_while && line.oword.as_ref().is_some_and(|o| matches!(o.ctrl, Ctrl::While(_))))
                && !(is_do && line.oword.as_ref().is_some_and(|o| matches!(o.ctrl, Ctrl::EndWhile)));
            g.lines.push(line);
            if !closes {
                return Ok(());
            }
            let lines = std::mem::take(&mut g.lines);
            self.gather = None;
            return self.run_lines(&lines, out).map(|_| ());
        }
        if let Some(o) = &line.oword {
            if matches!(o.ctrl, Ctrl::Sub | Ctrl::If(_) | Ctrl::While(_) | Ctrl::Do | Ctrl::Repeat(_)) {
                self.gather = Some(Gather { label: o.label.clone(), lines: vec![line] });
                return Ok(());
            }
        }
        self.run_lines(std::slice::from_ref(&line), out).map(|_| ())
    }

    fn reset(&mut self, pos: Pos) {
        self.m.reset(pos);
        self.gather = None;
        self.depth = 0;
        self.nesting = 0;
    }

    fn set_position(&mut self, pos: Pos) {
        self.m.pos = pos;
    }

    fn modal(&self) -> Vec<String> {
        self.m.modal()
    }

    fn rigid_mode(&self) -> bool {
        false
    }

    fn set_params(&mut self, params: &Params) {
        self.m.cfg = super::machine::Cfg::from(params);
    }

    fn program(&mut self, program: &crate::parse::Program) {
        self.program = program
            .blocks
            .iter()
            .filter(|b| b.text != END_OF_FILE)
            .filter_map(|b| parse_line(&b.text, b.line).ok())
            .collect();
        self.read_ahead(program);
    }
}

/// Where a program whose read-ahead stopped on a read-phase error ends: after the last block
/// that queued something, without a straight feed that nothing flushed to motion after it (its
/// block's steps before it still run). None: nothing was queued.
fn halt_point(read: &[(u32, Vec<Queued>)]) -> Option<(u32, usize)> {
    let last_cmd = |k: usize| read[k].1.iter().rposition(|q| *q != Queued::Quiet);
    let mut k = read.iter().rposition(|(_, q)| q.iter().any(|q| *q != Queued::Quiet))?;
    let j = last_cmd(k)?;
    if read[k].1[j] != Queued::Feed {
        return Some((read[k].0, read[k].1.len()));
    }
    // The held feed: its block up to it, or the block before that queued something.
    if read[k].1[..j].iter().any(|q| *q != Queued::Quiet) {
        return Some((read[k].0, j));
    }
    k = read[..k].iter().rposition(|(_, q)| q.iter().any(|q| *q != Queued::Quiet))?;
    Some((read[k].0, read[k].1.len()))
}

/// Whether a line starts a subroutine definition.
fn is_sub(l: &Line) -> bool {
    l.oword.as_ref().is_some_and(|o| matches!(o.ctrl, Ctrl::Sub))
}

/// G2/G3 (LCNC-MOD-02): centre by I/J/K offsets (absolute under G90.1) or by radius R, in the
/// selected plane; under G7 the offsets are radii.
pub fn arc(m: &mut Machine, b: &Eb, cw: bool, out: &mut Vec<Step>) -> Result<(), Alarm> {
    let bad = |t: &str| alarm(AlarmKind::LcncInterpreter, t, b.line, None);
    let t = m.target(b)?;
    let (ia, ib, _) = m.plane.axes();
    let s = [m.work(0), m.work(1), m.work(2)];
    let (sa, sb, ea, eb) = (s[ia] as f64, s[ib] as f64, t[ia] as f64, t[ib] as f64);
    let offset_letter = |a: usize| ['I', 'J', 'K'][a];
    let centre = if let Some(r) = b.get('R') {
        if b.get(offset_letter(ia)).is_some() || b.get(offset_letter(ib)).is_some() {
            return Err(bad("Mixed radius ijk format for arc"));
        }
        let r = m.len(r, 2, b, 'R')? as f64;
        let (dx, dy) = (ea - sa, eb - sb);
        let chord = dx.hypot(dy);
        if chord == 0.0 {
            return Err(bad("Current point same as end point of arc"));
        }
        let half = chord / 2.0;
        if r.abs() < half - 1000.0 {
            return Err(bad("Arc radius too small to reach end point"));
        }
        let d = (r * r - half * half).max(0.0).sqrt();
        let sign = if cw { 1.0 } else { -1.0 } * r.signum();
        [sa + dx / 2.0 + dy / chord * d * sign, sb + dy / 2.0 - dx / chord * d * sign]
    } else {
        let (oa, ob) = (b.get(offset_letter(ia)), b.get(offset_letter(ib)));
        if oa.is_none() && ob.is_none() {
            return Err(bad("R i j k words all missing for arc"));
        }
        let conv =
            |v: Option<f64>, l| v.map(|v| m.len(v, 2, b, l)).transpose().map(|o| o.unwrap_or(0) as f64);
        let (oa, ob) = (conv(oa, offset_letter(ia))?, conv(ob, offset_letter(ib))?);
        let c = if m.arc_absolute { [oa, ob] } else { [sa + oa, sb + ob] };
        let r0 = (sa - c[0]).hypot(sb - c[1]);
        let r1 = (ea - c[0]).hypot(eb - c[1]);
        if (r0 - r1).abs() > (0.0005 * 25_400_000.0f64).max(r0 * 0.001) {
            return Err(bad("Radius to end of arc differs from radius to start"));
        }
        c
    };
    let target = m.machine(t);
    let center: [Nm; 2] = [
        (centre[0].round() as Nm).saturating_add(m.off[ia]),
        (centre[1].round() as Nm).saturating_add(m.off[ib]),
    ];
    out.push(Step::Arc { target, center, plane: m.plane, clockwise: cw, feed: m.feed_rate() });
    m.pos = target;
    Ok(())
}
