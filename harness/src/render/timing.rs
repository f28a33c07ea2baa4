//! ASCII timing diagrams, in the style of the timing charts of the controller manuals: the
//! signals, the machining phase, axis positions and the spindle speed on one shared time axis.
//!
//! # Layout
//!
//! Every line is `label column`, ` |`, `width` cells, `|`: the label column is as wide as the
//! longest label, so every line has the same number of characters, and the closing `|` is a
//! visible border (no line ends in whitespace). From top to bottom:
//!
//! - header lines: dialect, window (`from .. to ms`) and ms per column, wrapped to the diagram's
//!   width;
//! - `phase`: the phase in force at each cell's end, by its first letter (`p` positioning, `c`
//!   cutting, `d` dwell, `r` retract, `o` overload retract, `.` idle), in capitals in the cell
//!   where the phase was entered;
//! - one line per requested signal;
//! - `alarm/input` (only when the window has alarms or inputs): `A` in a cell with an alarm, else
//!   `I` in a cell with an input, else blank;
//! - per requested axis, then the spindle: a plot of [`PLOT_LINES`] lines (see below);
//! - the time axis: `+` at each tick, `-` between, and a line of tick labels in ms.
//!
//! # Time
//!
//! The window `[from, to]` (default: 0 to the time of the last event) is split into `width`
//! cells at the boundaries `b_i = from + (to − from)·i / width` (integer division, µs), cell `i`
//! covering `(b_i, b_i+1]` (the first also takes `from` itself). An event belongs to the cell
//! whose interval holds its time; events before `from` only set the starting state, events
//! after `to` are not shown. A window with `to ≤ from` (a trace that ends at 0) becomes one µs
//! per column. The first column is labelled with `from`; further ticks fall on
//! round times (1, 2 or 5 × 10ⁿ µs) at least 10 columns apart, each in the column whose start it
//! is at or after; a label is left out when it would touch the previous one or pass the right
//! border.
//!
//! # Signals
//!
//! A cell shows the signal's level at the cell's end, `_` for 0 and `‾` (U+203E) for 1, unless
//! the signal changed inside the cell: one change gives `/` (rising, now 1) or `\` (falling, now
//! 0), more than one gives `X` (a pulse or glitch shorter than a cell; zoom in to see it).
//! Signals start at 0.
//!
//! # Plots
//!
//! Axis positions (mm, or degrees for a rotary axis, as reported: diameter for a lathe's X) and
//! the spindle speed (rpm, signed, + forward) come from the samples and the end state. The range
//! is the minimum to maximum value shown (for the spindle it always includes 0); the top line is
//! labelled with the maximum, the bottom line with the minimum, and a value is drawn on line
//! `round((v − min)·(lines − 1)/(max − min))` from the bottom (the middle when the value is
//! constant). Each cell draws a step, with box-drawing characters, from the previous cell's last
//! value to its own last value through every value sampled inside it (a cell without samples
//! carries the last value on; cells before the first known value stay blank). The spindle plot
//! marks its zero line with `·` where nothing else is drawn.

use nc_engine::trace::{AxisSpec, Event, Phase, Sample, Signal, Trace};
use nc_engine::units::Micros;

use super::{end_time, fixed, ms_trim, wrap};

/// Text lines of one plot.
pub const PLOT_LINES: usize = 5;
/// Columns of a diagram unless told.
pub const DEFAULT_WIDTH: usize = 100;
/// A signal at 1.
pub const HIGH: char = '\u{203E}';
/// A signal at 0.
pub const LOW: char = '_';

/// What a diagram shows.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DiagramSpec {
    /// One line each, in this order.
    pub signals: Vec<Signal>,
    /// One plot each, in this order (the position is read from the sample slot `index`).
    pub axes: Vec<AxisSpec>,
    /// A plot of the spindle speed.
    pub spindle: bool,
    /// Columns of the time axis (at least 1).
    pub width: usize,
    /// Start of the window in µs (default 0).
    pub from_us: Option<u64>,
    /// End of the window in µs (default the time of the last event).
    pub to_us: Option<u64>,
}

impl Default for DiagramSpec {
    fn default() -> Self {
        DiagramSpec {
            signals: Vec::new(),
            axes: Vec::new(),
            spindle: false,
            width: DEFAULT_WIDTH,
            from_us: None,
            to_us: None,
        }
    }
}

impl DiagramSpec {
    /// Everything of interest in `trace`: the signals that change (in [`Signal::ALL`] order), every
    /// axis of its meta, the spindle, the whole trace at the default width.
    pub fn for_trace(trace: &Trace) -> DiagramSpec {
        let signals = Signal::ALL.iter().copied().filter(|s| trace.edges(*s).next().is_some()).collect();
        DiagramSpec { signals, axes: trace.meta.axes.clone(), spindle: true, ..DiagramSpec::default() }
    }
}

/// Where a time falls in the window.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Place {
    Before,
    In(usize),
    After,
}

/// The time axis: `width` cells between `from` and `to`.
struct Grid {
    from: Micros,
    to: Micros,
    width: usize,
    bounds: Vec<Micros>,
}

impl Grid {
    fn new(trace: &Trace, spec: &DiagramSpec) -> Grid {
        let width = spec.width.max(1);
        let mut from = spec.from_us.unwrap_or(0);
        let mut to = spec.to_us.unwrap_or_else(|| end_time(trace));
        if to <= from {
            // An empty window: one µs per column.
            from = from.min(u64::MAX - width as u64);
            to = from + width as u64;
        }
        let span = u128::from(to - from);
        let bounds = (0..=width).map(|i| from + (span * i as u128 / width as u128) as u64).collect();
        Grid { from, to, width, bounds }
    }

    fn place(&self, t: Micros) -> Place {
        if t < self.from {
            Place::Before
        } else if t > self.to {
            Place::After
        } else if t == self.from {
            Place::In(0)
        } else {
            Place::In(self.bounds.partition_point(|&b| b < t) - 1)
        }
    }

    /// The column whose start is at or before `t` (ticks).
    fn column(&self, t: Micros) -> usize {
        (u128::from(t - self.from) * self.width as u128 / u128::from(self.to - self.from)) as usize
    }
}

/// One line of the diagram: label (left part, right-aligned part) and cells.
struct Row {
    left: String,
    right: String,
    cells: Vec<char>,
}

impl Row {
    fn new(left: impl Into<String>, cells: Vec<char>) -> Row {
        Row { left: left.into(), right: String::new(), cells }
    }

    fn label_width(&self) -> usize {
        let (l, r) = (self.left.chars().count(), self.right.chars().count());
        if r == 0 {
            l
        } else if l == 0 {
            r
        } else {
            l + 1 + r
        }
    }
}

/// Renders `trace` as a timing diagram (see the module doc for the layout).
pub fn timing_diagram(trace: &Trace, spec: &DiagramSpec) -> String {
    let g = Grid::new(trace, spec);
    let mut rows = vec![Row::new("phase", phase_cells(trace, &g))];
    for s in &spec.signals {
        rows.push(Row::new(s.name(), signal_cells(trace, &g, *s)));
    }
    if let Some(cells) = mark_cells(trace, &g) {
        rows.push(Row::new("alarm/input", cells));
    }
    for a in &spec.axes {
        let unit = if a.rotary { "deg" } else { "mm" };
        let slot = a.index;
        rows.extend(plot_rows(trace, &g, &format!("{} {unit}", a.letter), 6, false, |s| {
            s.axes.get(slot).copied().unwrap_or(0)
        }));
    }
    if spec.spindle {
        rows.extend(plot_rows(trace, &g, "S rpm", 3, true, |s| s.spindle_mrpm));
    }
    let (ticks, labels) = tick_rows(&g);
    rows.push(Row::new("", ticks));
    rows.push(Row::new("ms", labels));

    let lw = rows.iter().map(Row::label_width).max().unwrap_or(0);
    let total = lw + 2 + g.width + 1;
    let dialect = if trace.meta.dialect.is_empty() { "trace" } else { trace.meta.dialect };
    let per_column = i64::try_from(u128::from(g.to - g.from) * 1000 / g.width as u128).unwrap_or(i64::MAX);
    let header = [
        dialect.to_string(),
        format!("{} .. {} ms,", ms_trim(g.from), ms_trim(g.to)),
        format!("{} ms/column", fixed(per_column, 6)),
    ];
    let mut out = String::new();
    for line in wrap(&header, total - 1) {
        out.push_str(&line);
        out.extend(std::iter::repeat_n(' ', total - 1 - line.chars().count()));
        out.push_str("|\n");
    }
    for r in &rows {
        out.push_str(&r.left);
        let pad = lw - r.left.chars().count() - r.right.chars().count();
        out.extend(std::iter::repeat_n(' ', pad));
        out.push_str(&r.right);
        out.push_str(" |");
        out.extend(r.cells.iter());
        out.push_str("|\n");
    }
    out
}

/// Per cell: how many times a stepwise value (starting at `init`) changed in it, and its value
/// at the cell's end. Entries that restate the current value are not changes.
fn steps<T: Copy + PartialEq>(
    g: &Grid,
    init: T,
    changes: impl Iterator<Item = (Micros, T)>,
) -> Vec<(u32, T)> {
    let mut cells: Vec<(u32, Option<T>)> = vec![(0, None); g.width];
    let (mut now, mut start) = (init, init);
    for (t, v) in changes {
        if v == now {
            continue;
        }
        now = v;
        match g.place(t) {
            Place::Before => start = v,
            Place::In(i) => cells[i] = (cells[i].0 + 1, Some(v)),
            Place::After => break,
        }
    }
    let mut v = start;
    cells
        .into_iter()
        .map(|(n, last)| {
            v = last.unwrap_or(v);
            (n, v)
        })
        .collect()
}

fn signal_cells(trace: &Trace, g: &Grid, sig: Signal) -> Vec<char> {
    let cell = |(n, v)| match (n, v) {
        (0, true) => HIGH,
        (0, false) => LOW,
        (1, true) => '/',
        (1, false) => '\\',
        _ => 'X',
    };
    steps(g, false, trace.edges(sig)).into_iter().map(cell).collect()
}

fn phase_cells(trace: &Trace, g: &Grid) -> Vec<char> {
    let cell = |(n, p): (u32, Phase)| match p.name().chars().next() {
        _ if p == Phase::Idle => '.',
        Some(c) if n > 0 => c.to_ascii_uppercase(),
        Some(c) => c,
        None => '?',
    };
    steps(g, Phase::Idle, trace.phases()).into_iter().map(cell).collect()
}

fn mark_cells(trace: &Trace, g: &Grid) -> Option<Vec<char>> {
    let mut cells = vec![' '; g.width];
    let mut any = false;
    for e in &trace.events {
        let mark = match e.event {
            Event::Alarm(_) => 'A',
            Event::Input { .. } => 'I',
            _ => continue,
        };
        if let Place::In(i) = g.place(e.t_us) {
            any = true;
            if cells[i] != 'A' {
                cells[i] = mark;
            }
        }
    }
    any.then_some(cells)
}

const L: u8 = 1;
const R: u8 = 2;
const U: u8 = 4;
const D: u8 = 8;

/// The box-drawing character joining the given sides of a cell.
fn box_char(sides: u8) -> char {
    [' ', '╴', '╶', '─', '╵', '╯', '╰', '┴', '╷', '╮', '╭', '┬', '│', '┤', '├', '┼'][usize::from(sides & 15)]
}

/// A plot of [`PLOT_LINES`] lines of the value `get` of the samples (and the end state).
fn plot_rows(
    trace: &Trace,
    g: &Grid,
    name: &str,
    decimals: u32,
    with_zero: bool,
    get: impl Fn(&Sample) -> i64,
) -> Vec<Row> {
    let mut carry: Option<i64> = None;
    // Per cell: lowest, highest and last value sampled in it.
    let mut cells: Vec<Option<(i64, i64, i64)>> = vec![None; g.width];
    for e in &trace.events {
        let v = match &e.event {
            Event::Sample(s) => get(s),
            Event::End(end) => get(&end.state),
            _ => continue,
        };
        match g.place(e.t_us) {
            Place::Before => carry = Some(v),
            Place::In(i) => {
                let c = cells[i].get_or_insert((v, v, v));
                *c = (c.0.min(v), c.1.max(v), v);
            }
            Place::After => break,
        }
    }
    let values = carry.into_iter().chain(cells.iter().flatten().flat_map(|c| [c.0, c.1]));
    let values = values.chain(with_zero.then_some(0));
    let (min, max) = values.fold((i64::MAX, i64::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let n = PLOT_LINES;
    let mut grid = vec![vec![0u8; g.width]; n];
    let level = |v: i64| -> usize {
        if max <= min {
            return n / 2;
        }
        let (num, den) =
            ((i128::from(v) - i128::from(min)) * (n as i128 - 1), i128::from(max) - i128::from(min));
        ((2 * num + den) / (2 * den)) as usize
    };
    // Line index from the top of a level.
    let line = |lv: usize| n - 1 - lv;
    let mut prev = carry;
    for (i, c) in cells.iter().enumerate() {
        let (lo, hi, end) = match (c, prev) {
            (Some(c), _) => *c,
            (None, Some(p)) => (p, p, p),
            (None, None) => continue,
        };
        let mut bottom = level(lo).min(level(end));
        let mut top = level(hi).max(level(end));
        if let Some(p) = prev {
            bottom = bottom.min(level(p));
            top = top.max(level(p));
            grid[line(level(p))][i] |= L;
        }
        grid[line(level(end))][i] |= R;
        for lv in bottom..=top {
            if lv < top {
                grid[line(lv)][i] |= U;
            }
            if lv > bottom {
                grid[line(lv)][i] |= D;
            }
        }
        prev = Some(end);
    }
    let zero_line = (with_zero && min <= 0 && max >= 0).then(|| line(level(0)));
    grid.iter()
        .enumerate()
        .map(|(k, sides)| {
            let cells = sides
                .iter()
                .map(|&s| if s == 0 && zero_line == Some(k) { '·' } else { box_char(s) })
                .collect();
            let mut row = Row::new(if k == 0 { name } else { "" }, cells);
            if min <= max && (k == 0 || k == n - 1) {
                row.right = fixed(if k == 0 { max } else { min }, decimals);
            }
            row
        })
        .collect()
}

/// The tick line and the tick label line.
fn tick_rows(g: &Grid) -> (Vec<char>, Vec<char>) {
    let span = g.to - g.from;
    let min_step = (u128::from(span) * 10).div_ceil(g.width as u128).max(1);
    let mut step: u128 = 1;
    'find: for k in 0..20 {
        for m in [1u128, 2, 5] {
            step = m * 10u128.pow(k);
            if step >= min_step {
                break 'find;
            }
        }
    }
    let step = u64::try_from(step).unwrap_or(u64::MAX);
    let mut ticks = vec!['-'; g.width];
    let mut labels = vec![' '; g.width];
    // The window's start is always labelled.
    let start: Vec<char> = ms_trim(g.from).chars().collect();
    ticks[0] = '+';
    let mut free = 0;
    if start.len() <= g.width {
        labels[..start.len()].copy_from_slice(&start);
        free = start.len() + 1;
    }
    let mut t = g.from.div_ceil(step).saturating_mul(step);
    while t <= g.to {
        let col = g.column(t);
        if col < g.width {
            ticks[col] = '+';
            let text: Vec<char> = ms_trim(t).chars().collect();
            if col >= free && col + text.len() <= g.width {
                labels[col..col + text.len()].copy_from_slice(&text);
                free = col + text.len() + 1;
            }
        }
        t = match t.checked_add(step) {
            Some(t) => t,
            None => break,
        };
    }
    (ticks, labels)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nc_engine::trace::{EndReason, EndSummary, Signals, TraceEvent, TraceMeta};
    use rstest::rstest;

    const X: AxisSpec = AxisSpec { letter: 'X', index: 0, diameter: false, rotary: false };

    fn sample(x_mm: i64, rpm: i64) -> Event {
        let mut s = Sample { spindle_mrpm: rpm * 1000, ..Sample::default() };
        s.axes[0] = x_mm * 1_000_000;
        Event::Sample(s)
    }

    fn end(x_mm: i64) -> Event {
        let mut state = Sample::default();
        state.axes[0] = x_mm * 1_000_000;
        Event::End(Box::new(EndSummary {
            reason: EndReason::ProgramEnd,
            state,
            command: [0; 6],
            signals: Signals::default(),
            modal: vec![],
            alarms: 0,
            blocks: 0,
        }))
    }

    fn sig(signal: Signal, value: bool) -> Event {
        Event::Signal { signal, value }
    }

    fn trace(events: Vec<(u64, Event)>) -> Trace {
        Trace {
            meta: TraceMeta { dialect: "test", axes: vec![X], period_us: 100, sample_us: 100 },
            events: events.into_iter().map(|(t_us, event)| TraceEvent { t_us, event }).collect(),
        }
    }

    /// 10 cells of 100 µs over 0..1000 µs.
    fn hand_made() -> Trace {
        let mut ev = vec![(0, Event::Phase(Phase::Positioning))];
        for i in 0..10 {
            ev.push((i * 100, sample(i as i64 * 10, if i < 5 { 500 } else { -500 })));
        }
        ev.extend([
            (100, sig(Signal::Mf, true)),
            (250, sig(Signal::Fin, true)),
            (300, sig(Signal::Mf, false)),
            (301, sig(Signal::Fin, false)),
            (450, Event::Phase(Phase::Cutting)),
            (610, sig(Signal::Rtap, true)),
            (650, sig(Signal::Rtap, false)),
            (700, Event::Input { name: "feed_hold".into(), value: "on".into() }),
            (1000, end(90)),
        ]);
        ev.sort_by_key(|e| e.0);
        trace(ev)
    }

    fn spec(width: usize) -> DiagramSpec {
        DiagramSpec {
            signals: vec![Signal::Mf, Signal::Fin, Signal::Rtap],
            axes: vec![X],
            spindle: true,
            width,
            ..DiagramSpec::default()
        }
    }

    fn row<'a>(text: &'a str, label: &str) -> &'a str {
        let line = text.lines().find(|l| l.starts_with(label)).unwrap();
        let cells = line.split_once(" |").unwrap().1;
        cells.strip_suffix('|').unwrap()
    }

    #[test]
    fn hand_made_trace_exactly() {
        let want = "\
test 0 .. 1 ms,        |
0.1 ms/column          |
phase       |PpppCccccc|
MF          |/‾\\_______|
FIN         |__/\\______|
F76.3       |______X___|
alarm/input |      I   |
X mm     90 |       ╭──|
            |     ╭─╯  |
            |   ╭─╯    |
            | ╭─╯      |
          0 |╶╯        |
S rpm   500 |╶───╮     |
            |    │     |
            |····│····╭|
            |    │    │|
       -500 |    ╰────╯|
            |+---------|
ms          |0         |
";
        assert_eq!(timing_diagram(&hand_made(), &spec(10)), want);
    }

    #[rstest]
    #[case(1)]
    #[case(10)]
    #[case(37)]
    #[case(100)]
    #[case(200)]
    fn every_line_ends_with_the_border_and_has_the_same_width(#[case] width: usize) {
        for t in [hand_made(), trace(vec![(0, end(0))]), trace(vec![])] {
            let text = timing_diagram(&t, &spec(width));
            let widths: Vec<usize> = text.lines().map(|l| l.chars().count()).collect();
            assert!(widths.iter().all(|w| *w == widths[0]), "{widths:?}\n{text}");
            assert!(text.lines().all(|l| l.ends_with('|')), "{text}");
            assert!(!text.contains(" \n"));
            assert_eq!(row(&text, "MF").chars().count(), width);
            assert_eq!(text, timing_diagram(&t, &spec(width)));
        }
    }

    #[test]
    fn edges_fall_in_their_cells() {
        let text = timing_diagram(&hand_made(), &spec(10));
        // MF rises at 100 µs (end of cell 0) and falls at 300 µs (end of cell 2).
        assert_eq!(row(&text, "MF"), "/‾\\_______");
        // FIN rises at 250 and falls at 301: one change each in cells 2 and 3.
        assert_eq!(row(&text, "FIN"), "__/\\______");
        // F76.3 rises and falls inside cell 6.
        assert_eq!(row(&text, "F76.3"), "______X___");
        let text = timing_diagram(&hand_made(), &spec(20));
        assert_eq!(row(&text, "FIN"), "____/‾\\_____________");
        // 50 µs cells: 610 and 650 µs are both in (600, 650].
        assert_eq!(row(&text, "F76.3"), "____________X_______");
    }

    #[test]
    fn only_an_end_event_renders() {
        let text = timing_diagram(&trace(vec![(0, end(0))]), &spec(10));
        assert_eq!(row(&text, "phase"), "..........");
        assert_eq!(row(&text, "MF"), "__________");
        assert!(text.starts_with("test 0 .. 0.01 ms, |\n0.001 ms/column    |\n"), "{text}");
    }

    #[test]
    fn windows_start_from_the_state_before_them() {
        let s = DiagramSpec { from_us: Some(200), to_us: Some(400), ..spec(4) };
        let text = timing_diagram(&hand_made(), &s);
        assert!(text.starts_with("test           |\n0.2 .. 0.4 ms, |\n"), "{text}");
        assert_eq!(row(&text, "ms"), "0.2 ");
        // MF is already 1 at 200 µs and falls at 300 µs (end of cell 1); FIN rises at 250 µs
        // (end of cell 0 includes 200 itself) and falls at 301 µs (cell 2).
        assert_eq!(row(&text, "MF"), "‾\\__");
        assert_eq!(row(&text, "FIN"), "/‾\\_");
        assert_eq!(row(&text, "phase"), "pppp");
        assert!(!text.contains("alarm/input"));
    }

    #[test]
    fn extreme_windows_and_values_render() {
        let wild = Sample { axes: [i64::MIN, 0, 0, 0, 0, 0], spindle_mrpm: i64::MAX, spindle_mdeg: 0 };
        let t = trace(vec![(0, sample(0, 0)), (5, Event::Sample(wild)), (10, end(0))]);
        let windows = [(Some(u64::MAX), None), (Some(u64::MAX - 1), Some(u64::MAX)), (None, Some(u64::MAX))];
        for (from_us, to_us) in windows.into_iter().chain([(Some(7), Some(3))]) {
            let text = timing_diagram(&t, &DiagramSpec { from_us, to_us, ..spec(10) });
            assert!(text.lines().all(|l| l.ends_with('|')), "{text}");
        }
    }

    #[test]
    fn ticks_fall_on_round_times() {
        let text = timing_diagram(&hand_made(), &spec(100));
        let ticks = text.lines().rev().nth(1).unwrap();
        assert_eq!(ticks.matches('+').count(), 10);
        let labels = row(&text, "ms");
        assert!(labels.starts_with("0         0.1       0.2 "), "{labels}");
    }
}
