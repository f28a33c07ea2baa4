//! CSV importer: rows of a servo/PLC trace tool's export, read through a [`ColumnMap`] into
//! samples and signal edges. One row at a time (memory does not grow with the file), parsed in
//! place in the reader's buffer; a plain row (unquoted, plain decimals) in one pass over its
//! bytes ([`fast`]), any other through the general parser, which gives the same values and
//! every error.
//!
//! A row gives one `sample` (every mapped axis and the spindle; unmapped slots are 0), then an
//! edge for each mapped signal whose level changed, at the row's time. Before the first row every
//! signal is taken as 0, so a signal at 1 in the first row gives an edge at the first time.
//! Fields may be quoted (`"..."`, `""` for a quote inside).

use std::collections::VecDeque;
use std::io::BufRead;

use nc_engine::trace::{Event, Sample, Signal, TraceEvent};

use super::map::{ColRef, ColumnMap, Level};
use super::num::{f64_to_fixed, parse_f64, parse_u64};
use super::{char_col, read_line, Ctx, ErrorKind, Format, ImportError, RecordedMeta, Source};

pub(crate) mod fast;

/// The longest line read, bytes.
const MAX_LINE: usize = 1 << 20;

/// What a column feeds.
#[derive(Debug, Clone, Copy)]
enum Action {
    Time,
    Axis { slot: usize, scale: f64, offset: f64 },
    Rpm { scale: f64, offset: f64 },
    Angle { scale: f64, offset: f64 },
    Signal { i: usize },
}

struct SigCol {
    signal: Signal,
    level: Level,
    invert: bool,
    scale: f64,
    offset: f64,
}

struct CsvSource {
    r: Box<dyn BufRead + Send>,
    /// A line that is not wholly in the reader's buffer, copied.
    buf: Vec<u8>,
    rows: Rows,
}

/// Rows read in a batch from the reader's buffer before the events are handed on.
const BATCH_ROWS: usize = 256;

/// The row parser: everything but the reader, so that a row is parsed in place in the reader's
/// buffer.
struct Rows {
    delim: u8,
    line_no: u64,
    unquoted: Vec<u8>,
    fields: Vec<(usize, usize)>,
    /// Actions by column (0-based); a column may feed several signals.
    actions: Vec<Vec<Action>>,
    /// Columns the rows must have (`None` until the first row, without a header).
    n_cols: Option<usize>,
    /// The most columns any action needs.
    min_cols: usize,
    time_scale: f64,
    time_offset: f64,
    us_per_unit: f64,
    sigs: Vec<SigCol>,
    levels: Vec<bool>,
    new_levels: Vec<bool>,
    last_t: Option<u64>,
    /// Rows are tried on the fast path first (not when the delimiter could be read as part of a
    /// decimal, nor with `general_only`).
    fast: bool,
    /// The actions in column order (the order of [`Rows::row`]), each with its column.
    flat: Vec<(usize, Action)>,
    /// Columns with an action, by column.
    used: Vec<bool>,
    /// The fast path's decimals, by column.
    decs: Vec<fast::Dec>,
}

/// Splits `line` at `delim` into `fields` (ranges of the returned bytes): `line` itself when no
/// field is quoted, else the unquoted copy in `tmp`. `Err(col)` for a quote left open.
fn split<'a>(
    line: &'a [u8],
    delim: u8,
    tmp: &'a mut Vec<u8>,
    fields: &mut Vec<(usize, usize)>,
) -> Result<&'a [u8], usize> {
    fields.clear();
    // Short rows: one plain pass over the bytes beats `memchr` set-up per field.
    let mut start = 0;
    let mut quoted = false;
    for (i, &c) in line.iter().enumerate() {
        if c == delim {
            fields.push((start, i));
            start = i + 1;
        } else if c == b'"' {
            quoted = true;
            break;
        }
    }
    if !quoted {
        fields.push((start, line.len()));
        return Ok(line);
    }
    fields.clear();
    tmp.clear();
    let mut i = 0;
    loop {
        let start = tmp.len();
        // Leading spaces before a quote are dropped.
        let mut j = i;
        while j < line.len() && line[j] == b' ' {
            j += 1;
        }
        if j < line.len() && line[j] == b'"' {
            let open = j;
            j += 1;
            loop {
                match line[j..].iter().position(|&c| c == b'"') {
                    None => return Err(open),
                    Some(k) => {
                        tmp.extend_from_slice(&line[j..j + k]);
                        j += k + 1;
                        if line.get(j) == Some(&b'"') {
                            tmp.push(b'"');
                            j += 1;
                        } else {
                            break;
                        }
                    }
                }
            }
            // Anything up to the delimiter after the closing quote is kept as written.
            let end = memchr::memchr(delim, &line[j..]).map_or(line.len(), |k| j + k);
            tmp.extend_from_slice(&line[j..end]);
            fields.push((start, tmp.len()));
            i = end;
        } else {
            let end = memchr::memchr(delim, &line[i..]).map_or(line.len(), |k| i + k);
            tmp.extend_from_slice(&line[i..end]);
            fields.push((start, tmp.len()));
            i = end;
        }
        if i >= line.len() {
            break;
        }
        i += 1; // the delimiter
        if i == line.len() {
            fields.push((tmp.len(), tmp.len()));
            break;
        }
    }
    Ok(tmp)
}

/// Byte offset in `line` where field `n` starts (for error columns; quoted fields included).
fn field_offset(line: &[u8], delim: u8, n: usize) -> usize {
    if n == 0 {
        return 0;
    }
    let mut in_quote = false;
    let mut seen = 0;
    for (i, &c) in line.iter().enumerate() {
        if c == b'"' {
            in_quote = !in_quote;
        } else if c == delim && !in_quote {
            seen += 1;
            if seen == n {
                return i + 1;
            }
        }
    }
    line.len()
}

/// Opens a CSV file: skips the map's `skip_rows`, reads the header and resolves the columns.
pub(crate) fn open(
    ctx: &mut Ctx,
    mut r: Box<dyn BufRead + Send>,
    map: &ColumnMap,
) -> Result<(RecordedMeta, Box<dyn Source>), ImportError> {
    let Some(time) = &map.time else {
        return Err(ctx
            .err(ErrorKind::Header, 0, 0, "the column map has no `time` column")
            .expected("`time: {column: ..., unit: s|ms|us|ns}` in the column map"));
    };
    let mut buf = Vec::new();
    let mut line_no = 0u64;
    for _ in 0..map.skip_rows {
        line_no += 1;
        if !read_line(ctx, r.as_mut(), &mut buf, line_no, MAX_LINE)? {
            return Err(ctx
                .err(ErrorKind::Truncated, line_no, 0, "the file ends in the rows to skip")
                .expected(format!("{} rows to skip, then the header", map.skip_rows)));
        }
    }
    let mut names: Vec<String> = Vec::new();
    let mut header_line = Vec::new();
    if map.header {
        line_no += 1;
        if !read_line(ctx, r.as_mut(), &mut buf, line_no, MAX_LINE)? {
            return Err(ctx
                .err(ErrorKind::Truncated, line_no, 0, "the file ends before its header")
                .expected("a header row"));
        }
        let line = buf.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&buf);
        let (mut tmp, mut fields) = (Vec::new(), Vec::new());
        let data = split(line, map.delimiter, &mut tmp, &mut fields).map_err(|at| {
            ctx.err(ErrorKind::Header, line_no, char_col(line, at), "a quote is not closed")
                .expected("a closing `\"`")
                .with_line(line)
        })?;
        names =
            fields.iter().map(|&(a, b)| String::from_utf8_lossy(&data[a..b]).trim().to_string()).collect();
        header_line = line.to_vec();
    }
    let header_err = |ctx: &Ctx, msg: String, exp: String| {
        ctx.err(ErrorKind::Header, line_no.max(1), 1, msg).expected(exp).with_line(&header_line)
    };
    let resolve = |ctx: &Ctx, c: &ColRef| -> Result<usize, ImportError> {
        match c {
            ColRef::Index(i) => {
                if map.header && *i > names.len() {
                    return Err(header_err(
                        ctx,
                        format!("column {i} of the column map is past the header's {} columns", names.len()),
                        format!("a column number 1..{}", names.len()),
                    ));
                }
                Ok(i - 1)
            }
            ColRef::Name(n) if !map.header => Err(header_err(
                ctx,
                format!("column `{n}` is named but the map says `header: false`"),
                "column numbers (1-based) without a header".into(),
            )),
            ColRef::Name(n) => {
                let mut hits = names.iter().enumerate().filter(|(_, h)| *h == n).map(|(i, _)| i);
                match (hits.next(), hits.next()) {
                    (Some(i), None) => Ok(i),
                    (Some(_), Some(_)) => Err(header_err(
                        ctx,
                        format!("column `{n}` is in the header twice"),
                        "a column name that is unique (or its number)".into(),
                    )),
                    (None, _) => {
                        let mut list: Vec<String> = names.iter().take(12).map(|h| format!("`{h}`")).collect();
                        if names.len() > 12 {
                            list.push("...".into());
                        }
                        Err(header_err(
                            ctx,
                            format!("column `{n}` of the column map is not in the header"),
                            format!("one of {}", list.join(", ")),
                        ))
                    }
                }
            }
        }
    };
    let mut actions: Vec<Vec<Action>> = Vec::new();
    let mut add = |col: usize, a: Action| {
        if actions.len() <= col {
            actions.resize(col + 1, Vec::new());
        }
        actions[col].push(a);
    };
    add(resolve(ctx, &time.value.column)?, Action::Time);
    for a in &map.axes {
        add(
            resolve(ctx, &a.value.column)?,
            Action::Axis { slot: a.axis.index, scale: a.value.scale, offset: a.value.offset },
        );
    }
    if let Some(v) = &map.rpm {
        add(resolve(ctx, &v.column)?, Action::Rpm { scale: v.scale, offset: v.offset });
    }
    if let Some(v) = &map.angle {
        add(resolve(ctx, &v.column)?, Action::Angle { scale: v.scale, offset: v.offset });
    }
    let mut sigs = Vec::new();
    for (i, s) in map.signals.iter().enumerate() {
        add(resolve(ctx, &s.value.column)?, Action::Signal { i });
        sigs.push(SigCol {
            signal: s.signal,
            level: s.level,
            invert: s.invert,
            scale: s.value.scale,
            offset: s.value.offset,
        });
    }
    if map.header {
        for (i, n) in names.iter().enumerate() {
            let used = actions.get(i).is_some_and(|a| !a.is_empty());
            if !used && !map.ignore.iter().any(|x| x == n) {
                let col = char_col(&header_line, field_offset(&header_line, map.delimiter, i));
                ctx.fault(
                    ctx.err(
                        ErrorKind::Unknown,
                        line_no,
                        col,
                        format!("column `{n}` is not in the column map"),
                    )
                    .expected("a mapped column, or its name under `ignore:`")
                    .with_line(&header_line),
                )?;
            }
        }
    }
    let n_cols = map.header.then_some(names.len());
    let min_cols = actions.len();
    let meta = RecordedMeta {
        file: ctx.file.clone(),
        format: Format::Csv,
        trace: None,
        axes: map.axes.iter().map(|a| a.axis).collect(),
        spindle: (map.rpm.is_some(), map.angle.is_some()),
        signals: map.signals.iter().map(|s| s.signal).collect(),
        sample_us: None,
        first_t_us: None,
    };
    let n_sigs = sigs.len();
    let flat: Vec<(usize, Action)> =
        actions.iter().enumerate().flat_map(|(c, acts)| acts.iter().map(move |&a| (c, a))).collect();
    let used: Vec<bool> = actions.iter().map(|a| !a.is_empty()).collect();
    let fast = !ctx.general_only && !b"0123456789+-.eE\"".contains(&map.delimiter);
    let rows = Rows {
        delim: map.delimiter,
        line_no,
        unquoted: Vec::new(),
        fields: Vec::new(),
        actions,
        n_cols,
        min_cols,
        time_scale: time.value.scale,
        time_offset: time.value.offset,
        us_per_unit: time.us_per_unit,
        sigs,
        levels: vec![false; n_sigs],
        new_levels: vec![false; n_sigs],
        last_t: None,
        fast,
        flat,
        decs: vec![fast::Dec::default(); used.len()],
        used,
    };
    Ok((meta, Box::new(CsvSource { r, buf, rows })))
}

impl Rows {
    /// Parses the row `line`: `Ok(t)` with the sample and new levels set.
    fn row(&mut self, ctx: &Ctx, line: &[u8], sample: &mut Sample) -> Result<u64, ImportError> {
        let line_no = self.line_no;
        let data = split(line, self.delim, &mut self.unquoted, &mut self.fields).map_err(|at| {
            ctx.err(ErrorKind::BadRow, line_no, char_col(line, at), "a quote is not closed")
                .expected("a closing `\"`")
                .with_line(line)
        })?;
        let n = self.fields.len();
        let want = *self.n_cols.get_or_insert(n);
        if n != want || n < self.min_cols {
            let want = want.max(self.min_cols);
            let kind = if n < want { ErrorKind::Truncated } else { ErrorKind::BadRow };
            let col = char_col(line, line.len());
            let what = if self.n_cols.is_some() && want == self.n_cols.unwrap_or(0) {
                "the header has"
            } else {
                "the map needs"
            };
            return Err(ctx
                .err(kind, line_no, col, format!("the row has {n} fields, {what} {want}"))
                .expected(format!("{want} fields separated by `{}`", self.delim as char))
                .with_line(line));
        }
        let mut t = None;
        for (c, acts) in self.actions.iter().enumerate() {
            if acts.is_empty() {
                continue;
            }
            let (a, b) = self.fields[c];
            let field = &data[a..b];
            let bad = |what: &str, exp: &str| {
                ctx.err(
                    ErrorKind::BadRow,
                    line_no,
                    char_col(line, field_offset(line, self.delim, c)),
                    format!("{what} `{}`", String::from_utf8_lossy(field).trim()),
                )
                .expected(exp.to_string())
                .with_line(line)
            };
            for act in acts {
                match *act {
                    Action::Signal { i } => {
                        let s = &self.sigs[i];
                        let level = match s.level {
                            Level::Bit(bit) => {
                                let v = parse_u64(field).ok_or_else(|| {
                                    bad(
                                        "not an unsigned integer:",
                                        "an integer (decimal or 0x hexadecimal) for a bit",
                                    )
                                })?;
                                v >> bit & 1 == 1
                            }
                            lv => {
                                let v = parse_f64(field).ok_or_else(|| bad("not a number:", "a number"))?
                                    * s.scale
                                    + s.offset;
                                match lv {
                                    Level::Above(th) => v > th,
                                    Level::Below(th) => v < th,
                                    _ => v != 0.0,
                                }
                            }
                        };
                        self.new_levels[i] = level != s.invert;
                    }
                    _ => {
                        let v = parse_f64(field).ok_or_else(|| bad("not a number:", "a number"))?;
                        match *act {
                            Action::Time => {
                                let us = (v * self.time_scale + self.time_offset) * self.us_per_unit;
                                let us = f64_to_fixed(us, 0)
                                    .ok_or_else(|| bad("time out of range:", "a time that fits in µs"))?;
                                let us = u64::try_from(us).map_err(|_| {
                                    bad(
                                        "negative time:",
                                        "a time ≥ 0 (an `offset` on the time column shifts it)",
                                    )
                                })?;
                                t = Some(us);
                            }
                            Action::Axis { slot, scale, offset } => {
                                sample.axes[slot] = f64_to_fixed(v * scale + offset, 6).ok_or_else(|| {
                                    bad("position out of range:", "a position in mm (degrees)")
                                })?;
                            }
                            Action::Rpm { scale, offset } => {
                                sample.spindle_mrpm = f64_to_fixed(v * scale + offset, 3)
                                    .ok_or_else(|| bad("speed out of range:", "a speed in rpm"))?;
                            }
                            Action::Angle { scale, offset } => {
                                let m = f64_to_fixed(v * scale + offset, 3)
                                    .ok_or_else(|| bad("angle out of range:", "an angle in degrees"))?;
                                sample.spindle_mdeg = m.rem_euclid(360_000);
                            }
                            Action::Signal { .. } => {}
                        }
                    }
                }
            }
        }
        let t = t.unwrap_or(0);
        if let Some(last) = self.last_t {
            if t < last {
                let tc = self
                    .actions
                    .iter()
                    .position(|a| a.iter().any(|x| matches!(x, Action::Time)))
                    .unwrap_or(0);
                return Err(ctx
                    .err(
                        ErrorKind::NonMonotonicTime,
                        line_no,
                        char_col(line, field_offset(line, self.delim, tc)),
                        format!("time goes back: {t} µs after {last} µs"),
                    )
                    .expected(format!("a time ≥ {last} µs"))
                    .with_line(line));
            }
        }
        Ok(t)
    }
}

impl Rows {
    /// One line (its number already counted): a blank line is skipped; a row gives its sample
    /// and then its edges, falls before rises (a row cannot tell the order of changes between
    /// two rows, and a handshake such as RGSPP off / RGSPM on never has both on); a faulty row
    /// is an error, or counted when lenient.
    fn line(
        &mut self,
        ctx: &mut Ctx,
        line: &[u8],
        out: &mut VecDeque<TraceEvent>,
    ) -> Result<(), ImportError> {
        if line.first().is_none_or(u8::is_ascii_whitespace) && line.iter().all(u8::is_ascii_whitespace) {
            return Ok(());
        }
        let mut sample = Sample::default();
        self.new_levels.copy_from_slice(&self.levels);
        let fast = if self.fast { self.fast_row(line, &mut sample) } else { None };
        let res = match fast {
            Some(t) => Ok(t),
            None => {
                if self.fast {
                    sample = Sample::default();
                    self.new_levels.copy_from_slice(&self.levels);
                }
                self.row(ctx, line, &mut sample)
            }
        };
        match res {
            Ok(t) => {
                self.last_t = Some(t);
                out.push_back(TraceEvent { t_us: t, event: Event::Sample(sample) });
                for rise in [false, true] {
                    for (i, s) in self.sigs.iter().enumerate() {
                        if self.new_levels[i] != self.levels[i] && self.new_levels[i] == rise {
                            self.levels[i] = rise;
                            out.push_back(TraceEvent {
                                t_us: t,
                                event: Event::Signal { signal: s.signal, value: rise },
                            });
                        }
                    }
                }
                Ok(())
            }
            Err(e) => ctx.fault(e),
        }
    }
}

impl Source for CsvSource {
    fn fill(&mut self, ctx: &mut Ctx, out: &mut VecDeque<TraceEvent>) -> Result<bool, ImportError> {
        loop {
            // The complete lines in the reader's buffer, parsed in place (no copy), a batch at
            // a time.
            let mut used = 0;
            let mut n = 0;
            if let Ok(avail) = self.r.fill_buf() {
                if avail.is_empty() {
                    return Ok(false);
                }
                while n < BATCH_ROWS {
                    let Some(i) = memchr::memchr(b'\n', &avail[used..]).filter(|&i| i <= MAX_LINE) else {
                        break;
                    };
                    let end = if i > 0 && avail[used + i - 1] == b'\r' { used + i - 1 } else { used + i };
                    self.rows.line_no += 1;
                    let res = self.rows.line(ctx, &avail[used..end], out);
                    used += i + 1;
                    n += 1;
                    if let Err(e) = res {
                        self.r.consume(used);
                        return Err(e);
                    }
                }
            }
            if n > 0 {
                self.r.consume(used);
                if !out.is_empty() {
                    return Ok(true);
                }
                continue;
            }
            // A line that ends beyond the buffer (or the last one, without a line end): copied.
            self.rows.line_no += 1;
            if !read_line(ctx, self.r.as_mut(), &mut self.buf, self.rows.line_no, MAX_LINE)? {
                return Ok(false);
            }
            let line = std::mem::take(&mut self.buf);
            let res = self.rows.line(ctx, &line, out);
            self.buf = line;
            res?;
            if !out.is_empty() {
                return Ok(true);
            }
        }
    }
}
