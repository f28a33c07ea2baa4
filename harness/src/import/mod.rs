//! Importers: recorded controller traces (JSON Lines, CSV with a column map, VCD, MTConnect SHDR)
//! read as a stream of the engine's own [`TraceEvent`]s, so that a recorded trace and a reference
//! trace compare event for event (`docs/checking.md`, "Importing recorded traces").
//!
//! Owns the public API ([`open`], [`from_reader`], [`Importer`], [`RecordedMeta`], [`Format`] and
//! its auto-detection); one module per format does the reading. Every importer streams: memory
//! does not grow with the length of the file. Faults carry file, line and column
//! ([`ImportError`]); with `lenient`, faults of a row are counted as [`Warnings`] and the row is
//! left out, never silently.
//!
//! Times are delivered as recorded, in µs from the file's own origin (the `t_us` of a JSON Lines
//! trace, the CSV time column after its unit, scale and offset, VCD time × timescale, SHDR time
//! since the Unix epoch); [`RecordedMeta::first_t_us`] is the first event's time. Aligning a
//! recorded trace with the reference is the comparison's job.

pub mod ahead;
pub mod csv;
pub mod error;
pub mod fuzz;
pub mod gen;
pub mod jsonl;
mod jsonl_fast;
pub mod map;
pub mod num;
pub mod shdr;
pub mod vcd;

use std::collections::VecDeque;
use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use nc_engine::alarm::{Alarm, AlarmKind};
use nc_engine::trace::{AxisSpec, Signal, TraceEvent, TraceMeta};

pub use error::{ErrorKind, ImportError, Warnings};
pub use map::ColumnMap;

/// A recorded trace's format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Format {
    /// `nc-conform-trace/1` JSON Lines (`docs/trace-format.md`).
    Jsonl,
    /// Comma (or other) separated values, read through a [`ColumnMap`].
    Csv,
    /// Value Change Dump (IEEE 1364 §18).
    Vcd,
    /// MTConnect SHDR (`timestamp|key|value|...`).
    Shdr,
}

impl Format {
    /// Every format.
    pub const ALL: [Format; 4] = [Format::Jsonl, Format::Csv, Format::Vcd, Format::Shdr];

    /// The name used by `--format`.
    pub fn name(self) -> &'static str {
        match self {
            Format::Jsonl => "jsonl",
            Format::Csv => "csv",
            Format::Vcd => "vcd",
            Format::Shdr => "shdr",
        }
    }

    /// Looks a format up by its `--format` name.
    pub fn from_name(name: &str) -> Option<Format> {
        Format::ALL.into_iter().find(|f| f.name() == name)
    }

    /// Guesses the format from the first bytes of a file: `{` JSON Lines, `$` VCD, a first line
    /// `YYYY-MM-DDT...|...` (or an adapter line `* ...`) SHDR, anything else CSV.
    pub fn detect(head: &[u8]) -> Format {
        let head = head.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(head);
        let start = head.iter().position(|c| !c.is_ascii_whitespace()).unwrap_or(head.len());
        let first_line = head[start..].split(|&c| c == b'\n').next().unwrap_or(b"");
        match first_line.first() {
            Some(b'{') => Format::Jsonl,
            Some(b'$') => Format::Vcd,
            Some(b'*') => Format::Shdr,
            _ if shdr::looks_like_shdr(first_line) => Format::Shdr,
            _ => Format::Csv,
        }
    }
}

/// What an importer knows once the file's header is read (and its first event).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RecordedMeta {
    /// The file as named.
    pub file: String,
    /// Its format (detected or given).
    pub format: Format,
    /// The JSON Lines `meta` line, for a JSON Lines file.
    pub trace: Option<TraceMeta>,
    /// The axes a sample's positions are recorded for (the other slots stay 0).
    pub axes: Vec<AxisSpec>,
    /// Whether samples carry the spindle's speed and angle.
    pub spindle: (bool, bool),
    /// The signals the file declares (edges of the others never come, except in SHDR: there
    /// STL and SPL of `execution`, the map's signals and those named by a key in the lines up
    /// to the first event are declared, and a key named after another signal may still bring
    /// its edges later).
    pub signals: Vec<Signal>,
    /// The sample period the file declares, µs, when it declares one.
    pub sample_us: Option<u64>,
    /// The time of the first event, µs from the file's origin (`None`: the file has no events).
    pub first_t_us: Option<u64>,
}

/// How to import.
#[derive(Debug, Clone, Copy, Default)]
pub struct Options<'a> {
    /// The format; `None`: detected from the first bytes.
    pub format: Option<Format>,
    /// The column map (required for CSV; optional key names for SHDR).
    pub map: Option<&'a ColumnMap>,
    /// Count faults of a row as warnings and leave the row out instead of stopping.
    pub lenient: bool,
}

/// The shared state of a reader: file name, leniency and the warnings so far.
#[derive(Debug)]
pub(crate) struct Ctx {
    pub file: String,
    pub lenient: bool,
    pub warnings: Warnings,
    /// Read every JSON Lines line through serde_json and every CSV row through the general
    /// parser (no fast paths): the differential tests' reference.
    pub general_only: bool,
}

impl Ctx {
    /// An error of `kind` at `line:col`.
    pub fn err(&self, kind: ErrorKind, line: u64, col: u64, msg: impl Into<String>) -> ImportError {
        ImportError::new(kind, &self.file, line, col, msg)
    }

    /// A fault of a row: `Err` when strict (or not a row fault), otherwise counted.
    pub fn fault(&mut self, e: ImportError) -> Result<(), ImportError> {
        if self.lenient && e.kind.lenient_ok() {
            self.warnings.push(e);
            Ok(())
        } else {
            Err(e)
        }
    }
}

/// One format's reader after its header.
pub(crate) trait Source: Send {
    /// Reads on, pushing the next events to `out`; `Ok(false)` at the end of the file.
    fn fill(&mut self, ctx: &mut Ctx, out: &mut VecDeque<TraceEvent>) -> Result<bool, ImportError>;

    /// Signals the lines read so far name (SHDR keys), to declare after the first event.
    fn named_signals(&self) -> Vec<Signal> {
        Vec::new()
    }
}

/// A recorded trace being read: an iterator of events, in file order.
///
/// After the first `Err` the iterator ends. The warnings of lenient mode are in
/// [`Importer::warnings`].
pub struct Importer {
    meta: RecordedMeta,
    ctx: Ctx,
    src: Box<dyn Source>,
    queue: VecDeque<TraceEvent>,
    done: bool,
    pending_err: Option<ImportError>,
}

impl std::fmt::Debug for Importer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Importer").field("meta", &self.meta).field("done", &self.done).finish()
    }
}

impl Importer {
    /// What the file's header says.
    pub fn meta(&self) -> &RecordedMeta {
        &self.meta
    }

    /// The warnings counted so far (lenient mode).
    pub fn warnings(&self) -> &Warnings {
        &self.ctx.warnings
    }

    fn pull(&mut self) -> Option<Result<TraceEvent, ImportError>> {
        loop {
            if let Some(e) = self.queue.pop_front() {
                return Some(Ok(e));
            }
            if let Some(e) = self.pending_err.take() {
                self.done = true;
                return Some(Err(e));
            }
            if self.done {
                return None;
            }
            match self.src.fill(&mut self.ctx, &mut self.queue) {
                Ok(true) => {}
                Ok(false) => self.done = true,
                Err(e) => self.pending_err = Some(e),
            }
        }
    }
}

impl Iterator for Importer {
    type Item = Result<TraceEvent, ImportError>;

    fn next(&mut self) -> Option<Self::Item> {
        self.pull()
    }
}

/// Opens `path` for import.
///
/// # Errors
///
/// The file cannot be read, its format is not known, a CSV file comes without a column map, or
/// its header is wrong.
pub fn open(path: &Path, opts: &Options<'_>) -> Result<Importer, ImportError> {
    let name = path.display().to_string();
    let f = File::open(path)
        .map_err(|e| ImportError::new(ErrorKind::Io, &name, 0, 0, format!("cannot open: {e}")))?;
    from_reader(&name, Box::new(BufReader::with_capacity(256 * 1024, f)), opts)
}

/// Imports from `reader` (a file named `name` in messages).
///
/// # Errors
///
/// As [`open`].
pub fn from_reader(
    name: &str,
    reader: Box<dyn BufRead + Send>,
    opts: &Options<'_>,
) -> Result<Importer, ImportError> {
    from_reader_with(name, reader, opts, false)
}

/// [`from_reader`], with `general_only` to read JSON Lines and CSV without their fast paths.
pub(crate) fn from_reader_with(
    name: &str,
    mut reader: Box<dyn BufRead + Send>,
    opts: &Options<'_>,
    general_only: bool,
) -> Result<Importer, ImportError> {
    let mut ctx =
        Ctx { file: name.to_string(), lenient: opts.lenient, warnings: Warnings::default(), general_only };
    let format = match opts.format {
        Some(f) => f,
        None => {
            let head =
                reader.fill_buf().map_err(|e| ctx.err(ErrorKind::Io, 0, 0, format!("cannot read: {e}")))?;
            Format::detect(head)
        }
    };
    // An empty file is said to be empty, whatever its format (not "a CSV trace needs a map").
    let head = reader.fill_buf().map_err(|e| ctx.err(ErrorKind::Io, 0, 0, format!("cannot read: {e}")))?;
    if head.iter().all(u8::is_ascii_whitespace) {
        let what = if head.is_empty() { "the file is empty" } else { "the file holds only blank space" };
        return Err(ctx
            .err(ErrorKind::Header, 0, 0, what)
            .expected("a recorded trace: JSON Lines, CSV, VCD or MTConnect SHDR"));
    }
    let (meta, src): (RecordedMeta, Box<dyn Source>) = match format {
        Format::Jsonl => jsonl::open(&mut ctx, reader)?,
        Format::Csv => {
            let map = opts.map.ok_or_else(|| {
                ctx.err(ErrorKind::Header, 0, 0, "a CSV trace needs a column map")
                    .expected("--map FILE.yaml (docs/checking.md)")
            })?;
            csv::open(&mut ctx, reader, map)?
        }
        Format::Vcd => vcd::open(&mut ctx, reader)?,
        Format::Shdr => shdr::open(&mut ctx, reader, opts.map)?,
    };
    let mut imp = Importer { meta, ctx, src, queue: VecDeque::new(), done: false, pending_err: None };
    // Peek the first event for `first_t_us`; an error stays pending for the first `next`.
    match imp.pull() {
        Some(Ok(ev)) => {
            imp.meta.first_t_us = Some(ev.t_us);
            imp.queue.push_front(ev);
            for s in imp.src.named_signals() {
                if !imp.meta.signals.contains(&s) {
                    imp.meta.signals.push(s);
                }
            }
        }
        Some(Err(e)) => {
            imp.done = false;
            imp.pending_err = Some(e);
            imp.done = true;
        }
        None => {}
    }
    Ok(imp)
}

/// An alarm recorded with a vendor code the engine does not know (`NC-1120`): its detail is
/// `<code>: <text>` (the text left out when empty).
pub fn vendor_alarm(code: &str, text: &str) -> Alarm {
    let detail = if text.is_empty() { code.to_string() } else { format!("{code}: {text}") };
    Alarm::new(AlarmKind::UnknownVendorAlarm, detail)
}

/// The vendor code of an alarm made by [`vendor_alarm`] (None for the engine's own kinds).
pub fn vendor_code(a: &Alarm) -> Option<&str> {
    (a.kind == AlarmKind::UnknownVendorAlarm)
        .then(|| a.detail.split_once(": ").map_or(&a.detail[..], |(c, _)| c))
}

/// The alarm of a recorded code: the engine's kind with that code, else a [`vendor_alarm`].
pub(crate) fn recorded_alarm(code: &str, text: &str) -> Alarm {
    match AlarmKind::ALL.iter().copied().find(|k| k.code() == code && *k != AlarmKind::UnknownVendorAlarm) {
        Some(kind) => Alarm::new(kind, text),
        None => vendor_alarm(code, text),
    }
}

/// How far past its limit an over-long line is skipped looking for its end (64 MiB).
const SKIP_MAX: u64 = 64 << 20;

/// Reads one line (up to and without `\n`, and a `\r` before it) into `buf`; `Ok(false)` at the
/// end of the input. A line longer than `max` bytes is an error of its line.
pub(crate) fn read_line(
    ctx: &Ctx,
    r: &mut dyn BufRead,
    buf: &mut Vec<u8>,
    line_no: u64,
    max: usize,
) -> Result<bool, ImportError> {
    buf.clear();
    let n = r
        .take(max as u64 + 1)
        .read_until(b'\n', buf)
        .map_err(|e| ctx.err(ErrorKind::Io, line_no, 0, format!("cannot read: {e}")))?;
    if n == 0 {
        return Ok(false);
    }
    if buf.last() == Some(&b'\n') {
        buf.pop();
    } else if buf.len() > max {
        // Skip the rest of the line, so that a lenient reader goes on at the next one; a line
        // that does not end within `SKIP_MAX` more bytes (`/dev/zero`) ends the reading.
        let skipped = r
            .take(SKIP_MAX)
            .skip_until(b'\n')
            .map_err(|e| ctx.err(ErrorKind::Io, line_no, 0, format!("cannot read: {e}")))?;
        if skipped as u64 == SKIP_MAX {
            return Err(ctx
                .err(ErrorKind::Io, line_no, 1, format!("a line longer than {max} bytes that does not end"))
                .expected("a line end"));
        }
        return Err(ctx
            .err(ErrorKind::BadRow, line_no, 1, format!("a line longer than {max} bytes"))
            .expected("a line end"));
    }
    if buf.last() == Some(&b'\r') {
        buf.pop();
    }
    Ok(true)
}

/// The 1-based column, in characters, of byte offset `at` of `line`.
pub(crate) fn char_col(line: &[u8], at: usize) -> u64 {
    let at = at.min(line.len());
    String::from_utf8_lossy(&line[..at]).chars().count() as u64 + 1
}

#[cfg(test)]
mod tests;
