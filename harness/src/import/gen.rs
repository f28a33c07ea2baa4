//! A generated CSV trace for the import benchmark, the streaming test and the peak-memory
//! example: `rows` rows of 8 columns at 1 kHz, produced a chunk at a time (never held whole), so
//! that a 1-hour trace costs no disk and no memory. Rows are cheap to make (the time formatted,
//! the other 7 columns copied from a table of 1000 pre-formatted tails), so the reader's cost
//! dominates.

use std::io::{BufRead, Read};

/// The header of the generated file.
pub const HEADER: &str = "time_ms,X,Y,Z,S_rpm,S_deg,flags,load\n";

/// The column map of the generated file.
pub const MAP: &str = "\
time: {column: time_ms, unit: ms}
axes:
  - {axis: X, column: X}
  - {axis: Y, column: Y}
  - {axis: Z, column: Z}
spindle:
  rpm: {column: S_rpm}
  angle_deg: {column: S_deg}
signals:
  - {signal: F76.3, column: flags, bit: 3}
  - {signal: RGTAP, column: flags, bit: 0}
ignore: [load]
";

/// How many distinct row tails there are: row `r` ends with tail `r % TAILS`, whose `flags` is
/// `(r % TAILS / 50) % 16` (bit 0 toggles every 50 rows, bit 3 every 400, both reset each 1000).
pub const TAILS: u64 = 1000;

/// A stream of the generated CSV text.
#[derive(Debug)]
pub struct GenCsv {
    row: u64,
    rows: u64,
    tails: Vec<Vec<u8>>,
    buf: Vec<u8>,
    pos: usize,
    header: bool,
}

impl GenCsv {
    /// `rows` rows after the header.
    pub fn new(rows: u64) -> Self {
        let tails = (0..TAILS)
            .map(|r| {
                let z = -((r % 500) as f64) * 0.0015;
                format!(
                    ",{}.{:03},12.5,{z:.6},{},{}.{},{},{}\n",
                    r % 100,
                    r % 1000,
                    (r % 300) as i64 - 150,
                    r % 360,
                    r % 10,
                    (r / 50) % 16,
                    r % 97
                )
                .into_bytes()
            })
            .collect();
        GenCsv { row: 0, rows, tails, buf: Vec::with_capacity(70 * 1024), pos: 0, header: true }
    }

    fn refill(&mut self) {
        self.buf.clear();
        self.pos = 0;
        if self.header {
            self.buf.extend_from_slice(HEADER.as_bytes());
            self.header = false;
        }
        let mut itoa = itoa::Buffer::new();
        while self.buf.len() < 64 * 1024 && self.row < self.rows {
            self.buf.extend_from_slice(itoa.format(self.row).as_bytes());
            self.buf.extend_from_slice(&self.tails[(self.row % TAILS) as usize]);
            self.row += 1;
        }
    }
}

impl Read for GenCsv {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        let avail = self.fill_buf()?;
        let n = avail.len().min(out.len());
        out[..n].copy_from_slice(&avail[..n]);
        self.consume(n);
        Ok(n)
    }
}

impl BufRead for GenCsv {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        if self.pos >= self.buf.len() {
            self.refill();
        }
        Ok(&self.buf[self.pos..])
    }

    fn consume(&mut self, n: usize) {
        self.pos = (self.pos + n).min(self.buf.len());
    }
}

/// A stream of a generated JSON Lines trace (`nc-conform-trace/1`, gsk-lathe axes X and Z):
/// the meta line, `rows` samples at 1 kHz with a signal line every 50 samples, and the end line,
/// written by [`crate::jsonl::JsonlWriter`] a chunk at a time (never held whole).
#[derive(Debug)]
pub struct GenJsonl {
    row: u64,
    rows: u64,
    buf: Vec<u8>,
    pos: usize,
    started: bool,
    ended: bool,
}

impl GenJsonl {
    /// `rows` sample lines between the meta and the end line.
    pub fn new(rows: u64) -> Self {
        GenJsonl { row: 0, rows, buf: Vec::with_capacity(80 * 1024), pos: 0, started: false, ended: false }
    }

    fn meta() -> nc_engine::trace::TraceMeta {
        use nc_engine::trace::{AxisSpec, TraceMeta};
        let axis = |letter, index, diameter| AxisSpec { letter, index, diameter, rotary: false };
        TraceMeta {
            dialect: "gsk-lathe",
            axes: vec![axis('X', 0, true), axis('Z', 2, false)],
            period_us: 1000,
            sample_us: 1000,
        }
    }

    fn refill(&mut self) {
        use nc_engine::trace::{EndReason, EndSummary, Event, Sample, Signal, TraceEvent};
        self.buf.clear();
        self.pos = 0;
        if self.ended {
            return;
        }
        let mut w = crate::jsonl::JsonlWriter::new(std::mem::take(&mut self.buf));
        // The meta line sets the writer's axes; only the first chunk keeps it.
        w.write_meta(&Self::meta());
        let skip_meta = std::mem::replace(&mut self.started, true);
        let mut n = 0;
        while n < 700 && self.row < self.rows {
            let r = self.row;
            let t_us = r * 1000;
            if r.is_multiple_of(50) {
                let event = Event::Signal { signal: Signal::ALL[0], value: (r / 50) % 2 == 1 };
                w.write_event(&TraceEvent { t_us, event });
            }
            let mut axes = [0; nc_engine::trace::AXES];
            axes[0] = 50_000_000 - (r % 1000) as i64 * 1500;
            axes[2] = -((r % 500) as i64) * 1_500;
            let s = Sample {
                axes,
                spindle_mrpm: 1_000_000 - (r % 7) as i64,
                spindle_mdeg: (r * 6000 % 360_000) as i64,
            };
            w.write_event(&TraceEvent { t_us, event: Event::Sample(s) });
            self.row += 1;
            n += 1;
        }
        if self.row >= self.rows {
            let end = EndSummary {
                reason: EndReason::ProgramEnd,
                state: Sample::default(),
                command: [0; nc_engine::trace::AXES],
                signals: Default::default(),
                modal: vec!["G00".to_string()],
                alarms: 0,
                blocks: 1,
            };
            w.write_event(&TraceEvent { t_us: self.rows * 1000, event: Event::End(Box::new(end)) });
            self.ended = true;
        }
        self.buf = w.finish().unwrap_or_default();
        if skip_meta {
            self.pos = self.buf.iter().position(|&c| c == b'\n').map_or(0, |i| i + 1);
        }
    }
}

impl Read for GenJsonl {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        let avail = self.fill_buf()?;
        let n = avail.len().min(out.len());
        out[..n].copy_from_slice(&avail[..n]);
        self.consume(n);
        Ok(n)
    }
}

impl BufRead for GenJsonl {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        if self.pos >= self.buf.len() {
            self.refill();
        }
        Ok(&self.buf[self.pos..])
    }

    fn consume(&mut self, n: usize) {
        self.pos = (self.pos + n).min(self.buf.len());
    }
}
