//! Reading discrete-event findings the way an engineer says them: an event recorded beyond its
//! window reads as one line ("RGSPP rises 150 ms late"), not as a missing and an extra event; a
//! recording that stops before the reference is called truncated, at its last time, not a list
//! of every reference event after it.

use super::compare::Comparator;
use super::events::Key;
use super::tolerance::ms_us;
use crate::scenario::timeline::ms;

/// A missing reference event and an extra recorded one of the same kind at most this far apart
/// are one event shifted in time, µs.
pub const MAX_SHIFT_US: i64 = 2_000_000;

/// `RGSPP rises`, `MF falls`, `M29 output`, `alarm 5002 raised`.
pub fn happens(k: &Key) -> String {
    match k {
        Key::Edge(s, true) => format!("{} rises", s.name()),
        Key::Edge(s, false) => format!("{} falls", s.name()),
        Key::Function(l, c) => format!("{l}{c} output"),
        Key::Alarm(c) => format!("alarm {c} raised"),
    }
}

/// One event shifted beyond its window: reference time `tr`, recorded `t`, window `w`.
pub(super) fn shifted(c: &mut Comparator, k: &Key, tr: i64, t: i64, w: i64) {
    let d = t - tr;
    let how = if d > 0 { "late" } else { "early" };
    c.diverge(
        k.topic(),
        "CHK-EVT-01",
        format!("{} {} {how}", happens(k), ms(d.unsigned_abs())),
        tr,
        format!("at {} ± {}", ms(tr.max(0) as u64), ms(w as u64)),
        format!("at {}", ms(t.max(0) as u64)),
        format!("{} beyond the window", ms((d.abs() - w).max(0) as u64)),
    );
}

/// At the end: pairs the missing reference events with the extra recorded ones of the same kind
/// (nearest first, within [`MAX_SHIFT_US`]) into shifts, collapses the reference events after
/// the recording's last time into one "truncated" line, and reports the rest.
pub(super) fn resolve(c: &mut Comparator) {
    let mut extras = std::mem::take(&mut c.extras);
    let mut missing: Vec<(Key, i64)> = std::mem::take(&mut c.missing_other);
    missing.append(&mut c.missing_edges);
    missing.sort_by_key(|m| m.1);
    let mut kept = Vec::new();
    for (k, tr) in missing {
        let near = extras
            .iter()
            .enumerate()
            .filter(|(_, (ke, t))| *ke == k && (t - tr).abs() <= MAX_SHIFT_US)
            .min_by_key(|(_, (_, t))| (t - tr).abs())
            .map(|(i, _)| i);
        match near {
            Some(i) => {
                let (_, t) = extras.remove(i);
                let w = c.tol.window_us(&k.window_name());
                shifted(c, &k, tr, t, w);
            }
            None => kept.push((k, tr)),
        }
    }
    // The recording stops before the reference: what comes after its last time was never
    // recorded because nothing was.
    let cut = c.last_recorded_t();
    let w = ms_us(c.tol.event_ms);
    let comparable = |c: &Comparator, k: &Key| match k {
        Key::Edge(s, _) => c.carries_signal(*s),
        _ => true,
    };
    let after: Vec<(Key, i64)> =
        kept.iter().filter(|(k, tr)| *tr > cut + w && comparable(c, k)).cloned().collect();
    if !after.is_empty() {
        kept.retain(|(k, tr)| !(*tr > cut + w && comparable(c, k)));
        let first = after.iter().map(|m| m.1).min().unwrap_or(cut);
        let last = c.r.end_us;
        let rule = c.rules_first();
        c.push(super::Divergence {
            rule,
            check: "CHK-EVT-02".into(),
            what: format!("recording truncated at {}", ms(cut.max(0) as u64)),
            t_us: Some(cut),
            expected: format!(
                "the run until {} ({} more reference events from {})",
                ms(last.max(0) as u64),
                after.len(),
                ms(first.max(0) as u64)
            ),
            actual: format!("nothing recorded after {}", ms(cut.max(0) as u64)),
            margin: format!("{} short", ms((last - cut).max(0) as u64)),
        });
    }
    for (k, tr) in kept {
        match k {
            Key::Edge(..) => c.missing_edges.push((k, tr)),
            _ => c.report_missing(k, tr),
        }
    }
    for (k, t) in extras {
        c.report_extra(k, t);
    }
}
