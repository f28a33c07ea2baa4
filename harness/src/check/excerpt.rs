//! Excerpts of a long run for the reports: the timing diagrams around the first divergence and
//! the HTML page's zoomed views need the samples near the divergences, its plots one sample per
//! time bucket. A comparison keeps neither trace whole; after it, the reference is replayed and
//! the recording read again to take just these samples.

use nc_engine::trace::{Event, Trace, TraceEvent, TraceMeta, TraceSink};

use super::{Report, Source};

/// Half the width of a diagram or a zoomed view, µs.
pub const HALF_US: i64 = 150_000;

/// Zoomed views of the HTML page, at most.
pub const MAX_ZOOMS: usize = 8;

/// The intervals of the reference's time whose samples the reports show: ± [`HALF_US`] around
/// the first divergence and around each divergence of the first [`MAX_ZOOMS`] zoomed views
/// (merged where they overlap), in time order.
pub fn windows(rep: &Report) -> Vec<(i64, i64)> {
    let mut zooms: Vec<(i64, i64)> = Vec::new();
    for t in rep.sorted().iter().filter_map(|d| d.t_us) {
        let n = zooms.len();
        match zooms.last_mut() {
            Some(z) if t - HALF_US <= z.1 => z.1 = t + HALF_US,
            _ if n >= MAX_ZOOMS => break,
            _ => zooms.push((t - HALF_US, t + HALF_US)),
        }
    }
    zooms
}

/// The reference run `source` with its discrete events, its samples within `windows` and one
/// sample per `bucket_us` elsewhere (for the plots of the whole run).
pub fn reference(source: Source, windows: &[(i64, i64)], bucket_us: i64) -> Trace {
    let mut sink = Keep { meta: None, events: Vec::new(), windows, bucket_us: bucket_us.max(1), last: None };
    source.replay(&mut sink);
    let meta = sink.meta.unwrap_or(TraceMeta { dialect: "", axes: Vec::new(), period_us: 0, sample_us: 0 });
    Trace { meta, events: sink.events }
}

struct Keep<'w> {
    meta: Option<TraceMeta>,
    events: Vec<TraceEvent>,
    windows: &'w [(i64, i64)],
    bucket_us: i64,
    last: Option<i64>,
}

impl TraceSink for Keep<'_> {
    fn start(&mut self, meta: &TraceMeta) {
        self.meta = Some(meta.clone());
    }
    fn event(&mut self, ev: &TraceEvent) {
        let t = ev.t_us as i64;
        if matches!(ev.event, Event::Sample(_)) {
            let inside = self.windows.iter().any(|w| w.0 <= t && t <= w.1);
            if !inside && self.last.is_some_and(|l| t - l < self.bucket_us) {
                return;
            }
            if !inside {
                self.last = Some(t);
            }
        }
        self.events.push(ev.clone());
    }
}

/// Adds to the compact recorded trace of `rep` the recorded events within `windows` (reference
/// time) later than those it holds (it keeps the first ones only): `recorded` is the recording read again (time as recorded, in
/// order), aligned with the report's offset.
pub fn fill_recorded(
    rep: &mut Report,
    windows: &[(i64, i64)],
    recorded: impl IntoIterator<Item = TraceEvent>,
) {
    let have: Vec<u64> =
        rep.recorded.events.iter().filter(|e| matches!(e.event, Event::Sample(_))).map(|e| e.t_us).collect();
    let mut add = Vec::new();
    for ev in recorded {
        if !matches!(ev.event, Event::Sample(_)) {
            continue;
        }
        let t = ev.t_us as i64 + rep.offset_us;
        if t < 0 || !windows.iter().any(|w| w.0 <= t && t <= w.1) || have.binary_search(&(t as u64)).is_ok() {
            continue;
        }
        add.push(TraceEvent { t_us: t as u64, event: ev.event });
    }
    if add.is_empty() {
        return;
    }
    let end = rep.recorded.events.pop();
    rep.recorded.events.extend(add);
    // Stable: at one time the sample stays before the other events, as in a trace.
    rep.recorded.events.sort_by_key(|e| (e.t_us, !matches!(e.event, Event::Sample(_))));
    rep.recorded.events.extend(end);
}
