//! What a recording can show: its format and column map decide which kinds of reference events
//! can be compared at all. A CSV export has no M functions, an MTConnect agent no RGSPP strobe
//! unless a key names it: the reference events a recording cannot carry are left out of the
//! comparison and counted as "not comparable" in the report (never dropped silently), and the
//! default anchor falls back to an event the recording does carry (`docs/checking.md`,
//! "What a recording carries").

use nc_engine::trace::Signal;
use serde::Serialize;

use super::compare::Comparator;
use super::events::Key;
use super::reference::Reference;
use super::tolerance::Anchor;
use crate::import::{Format, RecordedMeta};
use crate::scenario::timeline::ms;

/// What kinds of events a recorded trace carries.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Carried {
    /// How the recording is named in "not comparable" lines (`csv`, `shdr`, ...).
    pub source: String,
    /// M/S/T functions.
    pub functions: bool,
    /// Alarms.
    pub alarms: bool,
    /// The signals the recording declares (`None`: every signal). A signal it does not declare
    /// is compared only when the recording shows an edge of it (an SHDR key named after it).
    pub signals: Option<Vec<Signal>>,
    /// The axis slots it records positions of (`None`: every axis).
    pub axes: Option<Vec<usize>>,
    /// Spindle speed.
    pub rpm: bool,
    /// Spindle angle.
    pub angle: bool,
    /// Signals are read from periodic samples (CSV rows): a pulse shorter than the gap between
    /// two rows may fall between them.
    pub sampled: bool,
    /// It shows no edge of a signal it does not declare (CSV, VCD: their columns and variables
    /// are known from the start; an SHDR key may name any signal).
    pub closed: bool,
}

impl Default for Carried {
    /// Everything (a JSON Lines trace, or events from memory).
    fn default() -> Self {
        Carried {
            source: "the recording".into(),
            functions: true,
            alarms: true,
            signals: None,
            axes: None,
            rpm: true,
            angle: true,
            sampled: false,
            closed: false,
        }
    }
}

impl Carried {
    /// What a file with this meta carries: JSON Lines everything; CSV the mapped axes, spindle
    /// values and signals (no functions, no alarms; signals sampled per row); VCD its variables
    /// (no functions, no alarms); SHDR positions, spindle, alarms, the execution state (STL,
    /// SPL) and the signals the map or a key names (no functions).
    pub fn of(meta: &RecordedMeta) -> Carried {
        let axes = Some(meta.axes.iter().map(|a| a.index).collect());
        let mut signals = meta.signals.clone();
        let base = Carried {
            source: meta.format.name().into(),
            functions: false,
            alarms: false,
            signals: None,
            axes,
            rpm: meta.spindle.0,
            angle: meta.spindle.1,
            sampled: false,
            closed: false,
        };
        match meta.format {
            Format::Jsonl => Carried { source: "jsonl".into(), ..Carried::default() },
            Format::Csv => Carried { signals: Some(signals), sampled: true, closed: true, ..base },
            Format::Vcd => Carried { signals: Some(signals), closed: true, ..base },
            Format::Shdr => {
                for s in [Signal::Stl, Signal::Spl] {
                    if !signals.contains(&s) {
                        signals.push(s);
                    }
                }
                Carried { signals: Some(signals), alarms: true, ..base }
            }
        }
    }

    /// Whether the recording declares `s`.
    pub fn declares(&self, s: Signal) -> bool {
        self.signals.as_ref().is_none_or(|v| v.contains(&s))
    }

    /// Whether the recording records the axis in `slot`.
    pub fn axis(&self, slot: usize) -> bool {
        self.axes.as_ref().is_none_or(|v| v.contains(&slot))
    }

    /// The default anchor for `reference` and this recording, the first that applies:
    /// 1. the first `M29` (the reference has one and the recording carries functions);
    /// 2. when the reference has an M29 the recording cannot show, the answer to it: the first
    ///    `F76.3` rise, else the first `RGTAP` rise (declared by the recording);
    /// 3. the first cycle start (`STL` rise; SHDR: `execution` going `ACTIVE`);
    /// 4. the first motion of the tap axis (when the recording records it);
    /// 5. the first spindle start (when it records the spindle speed and the reference turns it);
    /// 6. the first motion of the axis that moves first in the reference (a recorded one);
    /// 7. none: offset 0.
    pub fn default_anchor(&self, r: &Reference) -> Anchor {
        let tap_slot = r.tap.map(|t| t.slot);
        let m29 = r.summary.first(&Key::Function('M', 29)).is_some();
        let rises = |s: Signal| self.declares(s) && r.summary.first(&Key::Edge(s, true)).is_some();
        if m29 && self.functions {
            return Anchor::Function('M', 29);
        }
        if m29 {
            for s in [Signal::Rtap, Signal::Rgtap] {
                if rises(s) {
                    return Anchor::Edge(s, true);
                }
            }
        }
        if rises(Signal::Stl) {
            return Anchor::Edge(Signal::Stl, true);
        }
        if tap_slot.is_some_and(|s| self.axis(s)) {
            return Anchor::TapMotion;
        }
        if self.rpm && r.spindle_turns {
            return Anchor::SpindleStart;
        }
        if r.trace.meta.axes.iter().any(|a| self.axis(a.index) && r.moves[a.index]) {
            return Anchor::TapMotion;
        }
        Anchor::Offset(0)
    }
}

/// Reference events of one kind left out of the comparison because the recording cannot show
/// them.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct NotComparable {
    /// What was left out (`M29, M68, M69, M30`, `RGSPP edges`, `X position envelope`).
    pub what: String,
    /// How many reference events (0 for a whole check such as the envelope of an axis).
    pub count: usize,
    /// Why (`csv carries no M/S/T functions`).
    pub reason: String,
}

fn note(what: String, count: usize, reason: String) -> NotComparable {
    NotComparable { what, count, reason }
}

/// The names of the reference's keys that `pick` takes, in order of first appearance, joined,
/// and how many events they are.
fn names(r: &Reference, pick: impl Fn(&Key) -> bool) -> (String, usize) {
    let mut seen: Vec<String> = Vec::new();
    let mut n = 0;
    for (k, _, count) in r.summary.keys.iter().filter(|x| pick(&x.0)) {
        n += count;
        let d = k.describe();
        if !seen.contains(&d) {
            seen.push(d);
        }
    }
    (seen.join(", "), n)
}

/// What the recording cannot carry, known before it is read: functions, alarms, the envelope of
/// axes it does not record, the synchronisation error without a spindle angle, the final speed
/// without a spindle speed.
pub(super) fn left_out(r: &Reference, c: &Carried) -> (Vec<NotComparable>, Option<usize>) {
    let src = &c.source;
    let mut out = Vec::new();
    if !c.functions {
        let (what, n) = names(r, |k| matches!(k, Key::Function(..)));
        if n > 0 {
            out.push(note(what, n, format!("{src} carries no M/S/T functions")));
        }
    }
    if !c.alarms {
        let (what, n) = names(r, |k| matches!(k, Key::Alarm(_)));
        if n > 0 {
            out.push(note(what, n, format!("{src} carries no alarms")));
        }
    }
    for a in r.axes().iter().filter(|a| !c.axis(a.index)) {
        let l = a.letter;
        out.push(note(format!("{l} position envelope"), 0, format!("{src} records no {l} position")));
    }
    // Streamed, the synchronised moves are known at the end: their notes go here then.
    let sync_at = r.streamed.then_some(out.len());
    if !r.streamed {
        let per_slot = |slot: usize| r.sync.iter().filter(|w| w.slot == slot).count();
        out.extend(sync_notes(r, c, r.sync.len(), per_slot));
    }
    if !c.rpm {
        out.push(note("final spindle speed".into(), 0, format!("{src} records no spindle speed")));
    }
    (out, sync_at)
}

/// The notes on the synchronisation error of a reference with `n` synchronised moves, `per_slot`
/// of each axis, for a recording that cannot show it.
pub(super) fn sync_notes(
    r: &Reference,
    c: &Carried,
    n: usize,
    per_slot: impl Fn(usize) -> usize,
) -> Vec<NotComparable> {
    let src = &c.source;
    let mut out = Vec::new();
    if n == 0 {
        out.push(note(
            "synchronisation error".into(),
            0,
            "the reference has no synchronised move (rigid tapping stroke, thread pass, encoder-following move)"
                .into(),
        ));
    } else if !c.angle {
        out.push(note(
            format!("synchronisation error ({n} synchronised moves)"),
            n,
            format!("{src} records no spindle angle"),
        ));
    } else {
        for a in r.axes().iter().filter(|a| !c.axis(a.index)) {
            let n = per_slot(a.index);
            if n > 0 {
                let l = a.letter;
                out.push(note(
                    format!("synchronisation error ({n} synchronised moves of {l})"),
                    n,
                    format!("{src} records no {l} position"),
                ));
            }
        }
    }
    out
}

/// Judges the reference edges never recorded: those of a signal the recording neither declares
/// nor showed are not comparable; in a sampled recording (CSV rows), a pulse whose two edges
/// are both missing and which is shorter than the longest gap between two recorded samples may
/// have fallen between two rows: not observable; the others are missing (`CHK-EVT-02`).
pub(super) fn judge_missing_edges(c: &mut Comparator) {
    let missing = std::mem::take(&mut c.missing_edges);
    let src = c.carried.source.clone();
    let mut absent: Vec<(Signal, usize)> = Vec::new();
    let mut short: Vec<(Signal, usize)> = Vec::new();
    let bump = |v: &mut Vec<(Signal, usize)>, s: Signal| match v.iter_mut().find(|x| x.0 == s) {
        Some(x) => x.1 += 1,
        None => v.push((s, 1)),
    };
    // The edges of signals a closed recording does not declare, counted as they came instead of
    // listed (`Comparator::absent_refs`): every one is missing, each signal in the order of its
    // first edge (then of its key, as the matcher lists what it never matched).
    let mut firsts: Vec<((i64, Key), Signal, usize)> = Vec::new();
    for (k, n, t) in std::mem::take(&mut c.absent_refs) {
        let Key::Edge(s, _) = k else { continue };
        match firsts.iter_mut().find(|x| x.1 == s) {
            Some(x) => {
                x.2 += n;
                x.0 = x.0.clone().min((t, k));
            }
            None => firsts.push(((t, k), s, n)),
        }
    }
    firsts.sort_by(|a, b| a.0.cmp(&b.0));
    absent.extend(firsts.into_iter().map(|x| (x.1, x.2)));
    let is_missing =
        |s: Signal, v: bool, t: i64| missing.iter().any(|(k, tm)| *k == Key::Edge(s, v) && *tm == t);
    for (k, tr) in &missing {
        let Key::Edge(s, v) = *k else { continue };
        if !c.carries_signal(s) {
            bump(&mut absent, s);
            continue;
        }
        if c.carried.sampled {
            let edges: Vec<(u64, bool)> = c.r.edges(s);
            let i = edges.iter().position(|&(t, x)| t as i64 == *tr && x == v);
            let pulse = i.is_some_and(|i| {
                let near = |j: usize| {
                    edges.get(j).is_some_and(|&(t, x)| {
                        (t as i64 - tr).abs() < c.max_gap_us && is_missing(s, x, t as i64)
                    })
                };
                near(i + 1) || (i > 0 && near(i - 1))
            });
            if pulse {
                bump(&mut short, s);
                continue;
            }
        }
        c.report_missing(k.clone(), *tr);
    }
    for (s, n) in absent {
        c.not_comparable.push(note(
            format!("{} edges", s.name()),
            n,
            format!("{src} carries no {}", s.name()),
        ));
    }
    for (s, n) in short {
        c.not_comparable.push(note(
            format!("{} pulse edges", s.name()),
            n,
            format!(
                "pulses shorter than the longest gap between two samples of the {src} ({}) may fall between them",
                ms(c.max_gap_us.max(0) as u64)
            ),
        ));
    }
}

/// Whether the key points can be compared: the recording must carry the tap axis and the
/// stroke signals (RGSPP or RGSPM); otherwise they are noted as not comparable.
pub(super) fn key_points_comparable(c: &mut Comparator) -> bool {
    let what = "key points (pecks, depths, retract heights, bottom, pauses, return level, reversals)";
    let Some(tap) = c.r.tap else {
        if c.r.cuts {
            c.not_comparable.push(note(
                what.into(),
                0,
                "the reference has no RGSPP/RGSPM strokes to read them from (its cuts are compared by the envelope and the synchronisation error)".into(),
            ));
        }
        return false;
    };
    let src = c.carried.source.clone();
    let n = c.key_counts().0 + c.key_counts().1;
    if !c.carried.axis(tap.slot) {
        let l = c.r.axes().iter().find(|a| a.index == tap.slot).map_or('?', |a| a.letter);
        c.not_comparable.push(note(what.into(), n, format!("{src} records no {l} position (the tap axis)")));
        return false;
    }
    if !c.carries_signal(Signal::Rgspp) && !c.carries_signal(Signal::Rgspm) {
        c.not_comparable.push(note(
            what.into(),
            n,
            format!("{src} carries neither RGSPP nor RGSPM (the strokes)"),
        ));
        return false;
    }
    if !c.carries_signal(Signal::Rtap) && c.key_counts().1 > 0 {
        let n = c.key_counts().1;
        c.not_comparable.push(note(
            "return level and spindle reversals".into(),
            n,
            format!("{src} carries no F76.3"),
        ));
    }
    true
}

/// Whether a temporal rule's verdict is about signal `s` (its text names `S = v` or
/// `never_rises S`).
pub(super) fn mentions(v: &crate::scenario::expect::Verdict, s: Signal) -> bool {
    let name = s.name();
    [&v.what, &v.expected].iter().any(|text| {
        text.match_indices(name).any(|(i, _)| {
            let before = text[..i].chars().last();
            let after = &text[i + name.len()..];
            before.is_none_or(|c| !c.is_ascii_alphanumeric() && c != '.')
                && (after.starts_with(" = ")
                    || after.starts_with(")")
                    || after.is_empty()
                    || after.starts_with(','))
        })
    })
}
