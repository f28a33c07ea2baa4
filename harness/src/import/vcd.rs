//! VCD importer (IEEE 1364 §18, through the `vcd` crate's streaming parser): the variables that
//! `render/vcd.rs` writes become events again, so a VCD file written by `nc-conform` imports back
//! to the same signal edges and samples.
//!
//! Variables are recognised by scope and name: a 1-bit variable named after a signal
//! (`F76_3` or `F76.3`, any scope) gives edges; `real` variables named `X`..`C` (scope `axes`)
//! give positions in mm (degrees), `rpm` and `angle_deg` (scope `spindle`) the spindle; `phase`,
//! `line` (scope `cycle`) give phase changes and blocks (without text). `alarms` (scope `cycle`)
//! is read and left out: a count carries no alarm code. Any other variable is an unknown one.
//! `x`/`z` levels read as 0. Times are `#t × $timescale` in whole µs.
//!
//! Samples: with the `$comment ... sample_us N $end` that `nc-conform` writes, one sample every
//! N µs (at multiples of N, up to the last timestamp), holding the last values written, as the
//! engine sampled them; without it, one sample at each timestamp where a real variable changed.
//! Either way a sample at time t comes before the other events at t.

use std::collections::{HashMap, VecDeque};
use std::io::BufRead;

use nc_engine::trace::{axis_index, AxisSpec, Event, Phase, Sample, Signal, TraceEvent};
use vcd::{Command, IdCode, ScopeItem, Value, VarType};

mod scope_depth;

use super::num::f64_to_fixed;
use super::{Ctx, ErrorKind, Format, ImportError, RecordedMeta, Source};

/// What a variable feeds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Target {
    Signal(Signal),
    Axis(usize),
    Rpm,
    Angle,
    Phase,
    Line,
    Ignored,
}

const PHASES: [Phase; 6] =
    [Phase::Idle, Phase::Positioning, Phase::Cutting, Phase::Dwell, Phase::Retract, Phase::OverloadRetract];

/// The most events one `fill` call queues (grid samples over a long gap come in pieces).
const BATCH: usize = 1024;

struct VcdSource {
    p: vcd::Parser<Box<dyn BufRead + Send>>,
    vars: HashMap<IdCode, Vec<Target>>,
    /// µs = ticks × num / den.
    num: u128,
    den: u128,
    sample_us: Option<u64>,
    has_reals: bool,
    /// Time of the timestamp being read (µs) and whether any real changed in it.
    cur: u64,
    started: bool,
    real_changed: bool,
    /// Values before the current timestamp's changes, and with them.
    before: Sample,
    now: Sample,
    sig: [bool; Signal::ALL.len()],
    /// The phase so far (idle before the first change).
    phase: Phase,
    /// Events of the current timestamp other than samples.
    pending: Vec<TraceEvent>,
    /// Next grid time not yet sampled.
    next_grid: u64,
    /// Grid samples still to write: (from, up to and without, values).
    gap: Option<(u64, u64, Sample)>,
    /// The closed timestamp's own sample.
    tail: Option<TraceEvent>,
    /// A timestamp is closed and not all written out.
    closed: bool,
    eof: bool,
}

fn io_err(ctx: &Ctx, line: u64, e: &std::io::Error) -> ImportError {
    let parse = e.get_ref().and_then(|x| x.downcast_ref::<vcd::ParseError>());
    match parse {
        Some(p) => ctx
            .err(ErrorKind::BadRow, p.line(), 1, format!("not VCD: {}", p.kind()))
            .expected("a VCD command"),
        None if e.kind() == std::io::ErrorKind::UnexpectedEof => {
            ctx.err(ErrorKind::Truncated, line, 1, "the file ends inside a command").expected("`$end`")
        }
        None if e.kind() == std::io::ErrorKind::InvalidData => {
            ctx.err(ErrorKind::BadRow, line, 1, format!("not VCD: {e}")).expected("a VCD command")
        }
        None => ctx.err(ErrorKind::Io, line, 0, format!("cannot read: {e}")),
    }
}

/// The target of a variable in scope `scope`.
fn target(scope: &str, v: &vcd::Var) -> Option<Target> {
    let name = v.reference.as_str();
    if v.size == 1 && matches!(v.var_type, VarType::Wire | VarType::Reg | VarType::Integer)
        || scope == "signals"
    {
        let dotted = name.replace('_', ".");
        if let Some(s) = Signal::from_name(name).or_else(|| Signal::from_name(&dotted)) {
            return Some(Target::Signal(s));
        }
    }
    match (scope, name) {
        ("spindle", "rpm") => Some(Target::Rpm),
        ("spindle", "angle_deg") => Some(Target::Angle),
        ("cycle", "phase") => Some(Target::Phase),
        ("cycle", "line") => Some(Target::Line),
        ("cycle", "alarms") => Some(Target::Ignored),
        (_, n) if v.var_type == VarType::Real && n.len() == 1 => {
            n.chars().next().and_then(axis_index).map(Target::Axis)
        }
        _ => None,
    }
}

/// Reads the definitions up to `$enddefinitions`.
pub(crate) fn open(
    ctx: &mut Ctx,
    r: Box<dyn BufRead + Send>,
) -> Result<(RecordedMeta, Box<dyn Source>), ImportError> {
    let mut p = vcd::Parser::new(Box::new(scope_depth::ScopeDepth::new(r)) as Box<dyn BufRead + Send>);
    let header = p.parse_header().map_err(|e| {
        let mut e = io_err(ctx, p.line(), &e);
        if e.kind != ErrorKind::Io {
            e.kind = ErrorKind::Header;
        }
        e
    })?;
    let (num, den) = match header.timescale {
        Some((n, unit)) => (u128::from(n) * 1_000_000, u128::from(unit.divisor())),
        None => (1, 1),
    };
    let mut vars: HashMap<IdCode, Vec<Target>> = HashMap::new();
    let mut axes: Vec<AxisSpec> = Vec::new();
    let mut signals: Vec<Signal> = Vec::new();
    let (mut rpm, mut angle) = (false, false);
    let mut sample_us = None;
    let mut stack: Vec<(&str, std::slice::Iter<'_, ScopeItem>)> = vec![("", header.items.iter())];
    while let Some((scope, it)) = stack.last_mut() {
        let scope: &str = scope;
        let Some(item) = it.next() else {
            stack.pop();
            continue;
        };
        match item {
            ScopeItem::Scope(s) => stack.push((s.identifier.as_str(), s.items.iter())),
            ScopeItem::Comment(c) => {
                let words: Vec<&str> = c.split_whitespace().collect();
                if let Some(i) = words.iter().position(|w| *w == "sample_us") {
                    sample_us = words.get(i + 1).and_then(|w| w.parse::<u64>().ok()).filter(|s| *s > 0);
                }
            }
            ScopeItem::Var(v) => {
                let Some(t) = target(scope, v) else {
                    ctx.fault(
                        ctx.err(ErrorKind::Unknown, p.line(), 1, format!("unknown variable `{scope}.{}`", v.reference)).expected(
                            "a signal (MF, F76_3, ...), an axis X..C, spindle.rpm, spindle.angle_deg, cycle.phase or cycle.line",
                        ),
                    )?;
                    vars.entry(v.code).or_default().push(Target::Ignored);
                    continue;
                };
                match t {
                    Target::Signal(s) if !signals.contains(&s) => signals.push(s),
                    Target::Axis(i) if !axes.iter().any(|a| a.index == i) => {
                        let letter = nc_engine::trace::AXIS_LETTERS[i];
                        axes.push(AxisSpec {
                            letter,
                            index: i,
                            diameter: false,
                            rotary: matches!(letter, 'A' | 'B' | 'C'),
                        });
                    }
                    Target::Rpm => rpm = true,
                    Target::Angle => angle = true,
                    _ => {}
                }
                vars.entry(v.code).or_default().push(t);
            }
            _ => {}
        }
    }
    let has_reals = !axes.is_empty() || rpm || angle;
    let meta = RecordedMeta {
        file: ctx.file.clone(),
        format: Format::Vcd,
        trace: None,
        axes,
        spindle: (rpm, angle),
        signals,
        sample_us,
        first_t_us: None,
    };
    let src = VcdSource {
        p,
        vars,
        num,
        den,
        sample_us: sample_us.filter(|_| has_reals),
        has_reals,
        cur: 0,
        started: false,
        real_changed: false,
        before: Sample::default(),
        now: Sample::default(),
        sig: [false; Signal::ALL.len()],
        phase: Phase::Idle,
        pending: Vec::new(),
        next_grid: 0,
        gap: None,
        tail: None,
        closed: false,
        eof: false,
    };
    Ok((meta, Box::new(src)))
}

impl VcdSource {
    /// Ends the current timestamp: queues the grid samples before it, its own sample and its
    /// events (written out by [`VcdSource::flush`], grid samples a batch at a time).
    fn close_timestamp(&mut self) {
        if !self.started {
            return;
        }
        let t = self.cur;
        match self.sample_us {
            Some(step) => {
                if self.next_grid < t {
                    self.gap = Some((self.next_grid, t, self.before));
                }
                if t.is_multiple_of(step) {
                    self.tail = Some(TraceEvent { t_us: t, event: Event::Sample(self.now) });
                    self.next_grid = t.saturating_add(step);
                } else {
                    self.next_grid = self.next_grid.max(t.div_ceil(step).saturating_mul(step));
                }
            }
            None => {
                if self.has_reals && self.real_changed {
                    self.tail = Some(TraceEvent { t_us: t, event: Event::Sample(self.now) });
                }
            }
        }
        self.closed = true;
        self.real_changed = false;
        self.before = self.now;
    }

    /// Writes up to [`BATCH`] grid samples, then (once they are all out) the closed timestamp's
    /// sample and events. Returns whether everything of the closed timestamp is out.
    fn flush(&mut self, out: &mut VecDeque<TraceEvent>) -> bool {
        if let (Some(step), Some((mut g, end, s))) = (self.sample_us, self.gap.take()) {
            let mut n = 0;
            while g < end && n < BATCH {
                out.push_back(TraceEvent { t_us: g, event: Event::Sample(s) });
                g = g.saturating_add(step);
                n += 1;
            }
            if g < end {
                self.gap = Some((g, end, s));
                return false;
            }
        }
        self.gap = None;
        if self.closed {
            out.extend(self.tail.take());
            out.extend(self.pending.drain(..));
            self.closed = false;
        }
        true
    }

    fn change(
        &mut self,
        ctx: &mut Ctx,
        id: IdCode,
        f: impl Fn(Target) -> Result<Option<Event>, String>,
    ) -> Result<(), ImportError> {
        let Some(targets) = self.vars.get(&id) else {
            return ctx.fault(
                ctx.err(
                    ErrorKind::Unknown,
                    self.p.line(),
                    1,
                    format!("a change of `{id}`, which no `$var` defines"),
                )
                .expected("an identifier code defined in the header"),
            );
        };
        for t in targets.clone() {
            match f(t) {
                Ok(Some(ev)) => self.apply(t, ev),
                Ok(None) => {}
                Err(msg) => {
                    ctx.fault(
                        ctx.err(ErrorKind::BadRow, self.p.line(), 1, msg)
                            .expected("a value of the variable's kind"),
                    )?;
                }
            }
        }
        Ok(())
    }

    fn apply(&mut self, t: Target, ev: Event) {
        match (t, ev) {
            (Target::Signal(s), Event::Signal { value, .. }) => {
                let i = Signal::ALL.iter().position(|x| *x == s).unwrap_or(0);
                if self.sig[i] != value {
                    self.sig[i] = value;
                    self.pending
                        .push(TraceEvent { t_us: self.cur, event: Event::Signal { signal: s, value } });
                }
            }
            (Target::Axis(_) | Target::Rpm | Target::Angle, Event::Sample(s)) => {
                self.now = s;
                self.real_changed = true;
            }
            (Target::Phase, Event::Phase(p)) => {
                if self.phase != p {
                    self.phase = p;
                    self.pending.push(TraceEvent { t_us: self.cur, event: Event::Phase(p) });
                }
            }
            (_, ev) => self.pending.push(TraceEvent { t_us: self.cur, event: ev }),
        }
    }
}

impl Source for VcdSource {
    fn fill(&mut self, ctx: &mut Ctx, out: &mut VecDeque<TraceEvent>) -> Result<bool, ImportError> {
        loop {
            if self.closed {
                self.flush(out);
                return Ok(true);
            }
            if self.eof {
                return Ok(false);
            }
            if out.len() >= BATCH {
                return Ok(true);
            }
            let cmd = match self.p.next() {
                None => {
                    self.close_timestamp();
                    self.eof = true;
                    continue;
                }
                Some(Err(e)) => {
                    let e = io_err(ctx, self.p.line(), &e);
                    // A parse error leaves the parser inside a command: not safe to go on.
                    return Err(e);
                }
                Some(Ok(c)) => c,
            };
            match cmd {
                Command::Timestamp(ticks) => {
                    let us = u128::from(ticks) * self.num / self.den;
                    let Ok(us) = u64::try_from(us) else {
                        return Err(ctx
                            .err(ErrorKind::BadRow, self.p.line(), 1, format!("time #{ticks} out of range"))
                            .expected("a time that fits in µs"));
                    };
                    if self.started && us < self.cur {
                        ctx.fault(
                            ctx.err(
                                ErrorKind::NonMonotonicTime,
                                self.p.line(),
                                1,
                                format!("time goes back: #{ticks} ({us} µs) after {} µs", self.cur),
                            )
                            .expected(format!("a time ≥ {} µs", self.cur)),
                        )?;
                        continue;
                    }
                    if self.started && us == self.cur {
                        continue;
                    }
                    self.close_timestamp();
                    self.cur = us;
                    self.started = true;
                }
                Command::ChangeScalar(id, v) => {
                    self.started = true;
                    let value = v == Value::V1;
                    self.change(ctx, id, |t| match t {
                        Target::Signal(signal) => Ok(Some(Event::Signal { signal, value })),
                        Target::Ignored => Ok(None),
                        _ => Err(format!("a 1-bit change `{v}` of a variable that is not a signal")),
                    })?;
                }
                Command::ChangeVector(id, vec) => {
                    self.started = true;
                    let mut n: u64 = 0;
                    let mut overflow = false;
                    for b in &vec {
                        overflow |= n >> 63 != 0;
                        n = n << 1 | u64::from(b == Value::V1);
                    }
                    self.change(ctx, id, |t| match t {
                        Target::Signal(signal) => Ok(Some(Event::Signal { signal, value: n & 1 == 1 })),
                        Target::Phase => PHASES
                            .get(n as usize)
                            .filter(|_| !overflow)
                            .map(|p| Some(Event::Phase(*p)))
                            .ok_or_else(|| format!("phase {n}; not 0..5")),
                        Target::Line if overflow || n > u64::from(u32::MAX) => {
                            Err(format!("line {n} out of range"))
                        }
                        Target::Line if n == 0 => Ok(None),
                        Target::Line => Ok(Some(Event::Block { line: n as u32, text: String::new() })),
                        Target::Ignored => Ok(None),
                        _ => Err("a vector change of a real variable".to_string()),
                    })?;
                }
                Command::ChangeReal(id, x) => {
                    self.started = true;
                    let now = self.now;
                    self.change(ctx, id, |t| {
                        let mut s = now;
                        let conv = |d| f64_to_fixed(x, d).ok_or_else(|| format!("value {x} out of range"));
                        match t {
                            Target::Axis(i) => s.axes[i] = conv(6)?,
                            Target::Rpm => s.spindle_mrpm = conv(3)?,
                            Target::Angle => s.spindle_mdeg = conv(3)?.rem_euclid(360_000),
                            Target::Ignored => return Ok(None),
                            _ => return Err(format!("a real change `{x}` of a variable that is not real")),
                        }
                        Ok(Some(Event::Sample(s)))
                    })?;
                }
                Command::ChangeString(id, _) => {
                    self.change(ctx, id, |t| match t {
                        Target::Ignored => Ok(None),
                        _ => Err("a string change of a variable that is not a string".to_string()),
                    })?;
                }
                _ => {}
            }
        }
    }
}
