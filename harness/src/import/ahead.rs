//! Reading ahead: an [`Importer`] parsed on a thread of its own, a few batches ahead of its
//! reader, so that parsing a recording and comparing it use two cores (`check`, issue 14 §4).
//!
//! The events, errors and warnings are exactly those of the importer read in place: the thread
//! only runs it. Memory stays bounded: at most [`DEPTH`] batches of [`BATCH`] events wait, and
//! the batches go back to the thread to be filled again (no allocation per batch).

use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::thread::JoinHandle;

use nc_engine::trace::TraceEvent;

use super::{ImportError, Importer};

/// Events per batch.
pub const BATCH: usize = 2048;

/// Batches parsed ahead of the reader, at most.
pub const DEPTH: usize = 4;

type Item = Result<TraceEvent, ImportError>;

/// An importer running on its own thread (see the module's comment); an iterator of the same
/// items as the [`Importer`] it runs.
pub struct ReadAhead {
    full: Receiver<Vec<Item>>,
    empty: SyncSender<Vec<Item>>,
    cur: Vec<Item>,
    /// The next item of `cur` (taken from the front without moving the rest).
    at: usize,
    thread: Option<JoinHandle<Importer>>,
    /// The importer, once its thread has ended.
    ended: Option<Importer>,
}

impl Importer {
    /// This importer, run on a thread of its own a few batches ahead of its reader.
    pub fn read_ahead(self) -> ReadAhead {
        let (full_tx, full) = sync_channel::<Vec<Item>>(DEPTH);
        let (empty, empty_rx) = sync_channel::<Vec<Item>>(DEPTH + 2);
        let thread = std::thread::spawn(move || {
            let mut imp = self;
            loop {
                let mut batch = empty_rx.try_recv().unwrap_or_else(|_| Vec::with_capacity(BATCH));
                batch.clear();
                batch.extend(imp.by_ref().take(BATCH));
                let last = batch.len() < BATCH;
                if batch.is_empty() || full_tx.send(batch).is_err() || last {
                    return imp;
                }
            }
        });
        ReadAhead { full, empty, cur: Vec::new(), at: 0, thread: Some(thread), ended: None }
    }
}

impl ReadAhead {
    /// Waits for the thread and returns the importer (its warnings, its meta).
    pub fn finish(mut self) -> Importer {
        self.join();
        self.ended.take().expect("the reading thread returns its importer")
    }

    /// Ends the thread (unblocked if it waits to send: the batches still queued are dropped);
    /// a panic on it goes on here.
    fn join(&mut self) {
        if let Some(t) = self.thread.take() {
            let (_, dead) = sync_channel(0);
            drop(std::mem::replace(&mut self.full, dead));
            match t.join() {
                Ok(imp) => self.ended = Some(imp),
                Err(p) => std::panic::resume_unwind(p),
            }
        }
    }
}

impl Iterator for ReadAhead {
    type Item = Item;

    fn next(&mut self) -> Option<Item> {
        loop {
            if self.at < self.cur.len() {
                let k = self.at;
                self.at += 1;
                // Moved out, a placeholder left in its slot: the batch's allocation is kept.
                return Some(std::mem::replace(&mut self.cur[k], Ok(PLACEHOLDER)));
            }
            let Ok(next) = self.full.recv() else {
                self.join();
                return None;
            };
            let spent = std::mem::replace(&mut self.cur, next);
            self.at = 0;
            let _ = self.empty.try_send(spent);
        }
    }
}

/// What an item taken out of a batch is replaced with (never read).
const PLACEHOLDER: TraceEvent =
    TraceEvent { t_us: 0, event: nc_engine::trace::Event::Phase(nc_engine::trace::Phase::Idle) };

impl Drop for ReadAhead {
    fn drop(&mut self) {
        if let Some(t) = self.thread.take() {
            let (_, dead) = sync_channel(0);
            drop(std::mem::replace(&mut self.full, dead));
            let _ = t.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{from_reader, gen, ColumnMap, Options};

    /// The same events and errors, in the same order, read in place and read ahead, whole and
    /// stopped early; the warnings come back with the importer.
    #[test]
    fn read_ahead_gives_what_the_importer_gives() {
        let open =
            || from_reader("gen.jsonl", Box::new(gen::GenJsonl::new(10_000)), &Options::default()).unwrap();
        let direct: Vec<_> = open().collect();
        let ahead: Vec<_> = open().read_ahead().collect();
        assert!(direct.len() > 2 * super::BATCH);
        assert_eq!(direct, ahead);
        let first: Vec<_> = open().read_ahead().take(5000).collect();
        assert_eq!(&direct[..5000], &first[..]);
        // An error ends the stream after it, read ahead as in place.
        let map = ColumnMap::from_yaml("map.yaml", gen::MAP).unwrap();
        let text = format!("{}0,1,0,0,0,0,0,0\n1,oops,0,0,0,0,0,0\n2,3,0,0,0,0,0,0\n", gen::HEADER);
        let opts = Options { format: None, map: Some(&map), lenient: false };
        let rd = || {
            from_reader("bad.csv", Box::new(std::io::Cursor::new(text.clone().into_bytes())), &opts).unwrap()
        };
        let a: Vec<_> = rd().collect();
        let b: Vec<_> = rd().read_ahead().collect();
        assert_eq!(format!("{a:?}"), format!("{b:?}"));
        let mut r = rd().read_ahead();
        for _ in r.by_ref() {}
        assert_eq!(r.finish().warnings().total(), rd().warnings().total());
    }
}
