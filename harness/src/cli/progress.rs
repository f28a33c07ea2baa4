//! A progress line on standard error for a long `run` or `check`: after [`DELAY`], when standard
//! error is a terminal, a spinner with the events so far and the machine time reached (`run`), or
//! a bar up to the machine time the work ends at with the time left (`check`, whose reference's
//! end is known before the recording is read). Nothing is
//! drawn otherwise (pipes, files, tests, scripts), and the line is cleared when the work ends, so
//! the command's own output is unchanged.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use nc_engine::trace::{TraceEvent, TraceMeta, TraceSink};

/// How long a command runs before its progress line appears.
pub const DELAY: Duration = Duration::from_secs(2);

/// Events between two looks at the clock.
const EVERY: u64 = 8192;

/// The progress of one command.
pub struct Progress {
    what: &'static str,
    tty: bool,
    start: Instant,
    events: u64,
    /// The machine time the work ends at, when known (`check`: the reference's end): a bar with
    /// the share done, instead of a spinner.
    total_us: Option<u64>,
    bar: Option<ProgressBar>,
}

impl Progress {
    /// The progress of `what` (`run`, `check`), starting now.
    pub fn new(what: &'static str) -> Self {
        Progress {
            what,
            tty: std::io::stderr().is_terminal(),
            start: Instant::now(),
            events: 0,
            total_us: None,
            bar: None,
        }
    }

    /// The same progress as a bar up to machine time `total_us` (0: none).
    pub fn with_total(mut self, total_us: u64) -> Self {
        self.total_us = (total_us > 0).then_some(total_us);
        self
    }

    /// One more event, at machine time `t_us`.
    pub fn tick(&mut self, t_us: u64) {
        self.events += 1;
        if !self.tty || !self.events.is_multiple_of(EVERY) {
            return;
        }
        if self.bar.is_none() && self.start.elapsed() >= DELAY {
            let bar = ProgressBar::with_draw_target(self.total_us, ProgressDrawTarget::stderr())
                .with_elapsed(self.start.elapsed());
            let template = match self.total_us {
                Some(_) => "{spinner} {prefix} [{bar:20}] {percent:>3}% {msg} ({elapsed}, {eta} left)",
                None => "{spinner} {prefix}: {human_pos} events, {msg} ({elapsed})",
            };
            let style =
                ProgressStyle::with_template(template).unwrap_or_else(|_| ProgressStyle::default_spinner());
            bar.set_style(style.progress_chars("=> "));
            bar.set_prefix(self.what);
            self.bar = Some(bar);
        }
        if let Some(bar) = &self.bar {
            match self.total_us {
                Some(total) => {
                    bar.set_position(t_us.min(total));
                    bar.set_message(format!("{:.0} of {:.0} s", t_us as f64 / 1e6, total as f64 / 1e6));
                }
                None => {
                    bar.set_position(self.events);
                    bar.set_message(format!("{:.1} s of machine time", t_us as f64 / 1e6));
                }
            }
        }
    }

    /// Clears the line (if it was drawn).
    pub fn done(self) {
        if let Some(bar) = self.bar {
            bar.finish_and_clear();
        }
    }
}

/// A trace sink that ticks a [`Progress`] for every event it passes on.
pub struct Watched<S> {
    /// The sink watched.
    pub inner: S,
    progress: Progress,
}

impl<S: TraceSink> Watched<S> {
    /// Watches `inner` as `what`.
    pub fn new(what: &'static str, inner: S) -> Self {
        Watched { inner, progress: Progress::new(what) }
    }

    /// Clears the progress line; returns the sink.
    pub fn done(self) -> S {
        self.progress.done();
        self.inner
    }
}

impl<S: TraceSink> TraceSink for Watched<S> {
    fn start(&mut self, meta: &TraceMeta) {
        self.inner.start(meta);
    }
    fn event(&mut self, ev: &TraceEvent) {
        self.progress.tick(ev.t_us);
        self.inner.event(ev);
    }
    fn wants_stop(&self) -> bool {
        self.inner.wants_stop()
    }
}
