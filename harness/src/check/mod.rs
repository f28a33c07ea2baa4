//! `nc-conform check`: does a recorded controller trace behave as the reference says?
//! (`docs/checking.md`)
//!
//! The reference [`Trace`] is kept in memory; the recorded trace arrives as a stream of
//! [`TraceEvent`]s (from `crate::import` or any other source) and is never kept whole:
//!
//! - [`tolerance`]: tolerances, the alignment anchor, rule attribution;
//! - [`reference`]: the reference indexed for interpolation, its tap axis and lead;
//! - [`compare`]: the streaming comparator (alignment, events, sync error, envelope);
//! - [`events`]: discrete-event matching; [`keypoints`], [`keypoints_cmp`]: key points;
//! - [`report`]: JSON, JUnit XML and the human summary; [`html`]: the self-contained HTML page.
//!
//! The scenario's temporal rules run on a compact copy of the recorded trace through
//! [`crate::scenario::expect::evaluate_discrete`].

pub mod calibrate;
pub mod carried;
pub mod compare;
pub mod events;
pub mod excerpt;
pub mod handshake;
pub mod holes;
pub mod html;
pub mod keypoints;
pub mod keypoints_cmp;
pub mod reference;
pub mod report;
pub mod shift;
pub mod survey;
mod survey_fused;
pub mod sync;
mod sync_stream;
pub mod tolerance;
pub mod window;

use nc_engine::trace::{Signal, Trace, TraceEvent, TraceSink};
use serde::Serialize;

use crate::scenario::expect::{self, Expectations, Verdict};
pub use carried::{Carried, NotComparable};
pub use survey::Source;
pub use tolerance::{Anchor, Tolerances};

/// Most divergences listed one by one (the rest are counted).
pub const MAX_DIVERGENCES: usize = 10_000;

/// Most divergences of one check (`CHK-ENV-01`, ...) listed one by one: the first ones, the rest
/// counted per check (`omitted_by_check`), so that one kind repeated over a long recording does
/// not hide the others.
pub const MAX_PER_CHECK: usize = 1_000;

/// One way the recorded trace differs from the reference beyond tolerance.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Divergence {
    /// The rule id it breaks (`GSK-RT-27`, `COM-PLC-05`, ...).
    pub rule: String,
    /// The comparison that found it (`CHK-EVT-01`, ..., `docs/checking.md`).
    pub check: String,
    /// What was compared.
    pub what: String,
    /// When, in the reference's time base (µs).
    pub t_us: Option<i64>,
    /// What the reference says, with its tolerance.
    pub expected: String,
    /// What was recorded.
    pub actual: String,
    /// How far beyond the tolerance.
    pub margin: String,
}

impl Divergence {
    /// A divergence found at `t` µs by the comparison `check`, its rule not yet attributed.
    pub(crate) fn found(
        check: &str,
        what: String,
        t: i64,
        expected: String,
        actual: String,
        margin: String,
    ) -> Self {
        Divergence { rule: String::new(), check: check.into(), what, t_us: Some(t), expected, actual, margin }
    }
}

/// One point of a plotted series (reference time base).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Point {
    /// Time, µs.
    pub t: i64,
    /// Tap axis position, nm as reported.
    pub tap: Option<i64>,
    /// Spindle speed, milli-rpm.
    pub rpm: i64,
    /// Synchronisation error, nm (inside strokes).
    pub sync_nm: Option<f64>,
}

/// What to compare against and how.
#[derive(Debug, Clone, Default)]
pub struct CheckSpec<'a> {
    /// Tolerances.
    pub tolerances: Tolerances,
    /// The anchor (None: the first M29, else the first cycle start STL ↑).
    pub anchor: Option<Anchor>,
    /// The scenario's expectations, whose temporal rules run on the recorded trace.
    pub expect: Option<&'a Expectations>,
    /// The scenario's rule ids (preferred in attribution).
    pub rules: Vec<String>,
    /// What the recording can carry (default: everything); `Carried::of(importer.meta())`.
    pub carried: Carried,
}

/// Counts and extremes of a comparison.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Figures {
    /// Recorded events read.
    pub recorded_events: u64,
    /// Recorded samples read.
    pub recorded_samples: u64,
    /// Reference discrete events (edges, functions, alarms).
    pub reference_events: usize,
    /// Of those, matched by a recorded event.
    pub matched_events: usize,
    /// Largest |sync error|, mm.
    pub max_sync_error_mm: f64,
    /// Recorded samples at which the synchronisation with the spindle was compared (0: the
    /// sync error was not compared at all: "n/a", not 0 mm).
    pub sync_samples: u64,
    /// Largest position excess beyond the envelope, mm.
    pub max_envelope_excess_mm: f64,
    /// Pecks (cuts) in the reference / recorded.
    pub pecks: (usize, usize),
    /// How well the alignment fits: the root mean square of recorded − reference positions at
    /// the same time over every recorded axis and sample within the reference's run, mm (None:
    /// no position compared).
    pub fit_rms_mm: Option<f64>,
    /// Position values in that figure.
    pub fit_values: u64,
}

/// The outcome of a comparison.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Every divergence, by time (those without a time last); in JSON each also has its margin
    /// as a number with its unit (`margin_value`, `margin_unit`).
    #[serde(serialize_with = "divergences_json")]
    pub divergences: Vec<Divergence>,
    /// Divergences beyond [`MAX_DIVERGENCES`] or [`MAX_PER_CHECK`], not listed.
    pub omitted: usize,
    /// Of those, how many of each check.
    pub omitted_by_check: std::collections::BTreeMap<String, usize>,
    /// The scenario's temporal rules on the recorded trace.
    pub rules: Vec<Verdict>,
    /// The anchor used.
    pub anchor: String,
    /// Reference time = recorded time + offset, µs.
    pub offset_us: i64,
    /// The tolerances used.
    pub tolerances: Tolerances,
    /// Reference events and checks left out because the recording cannot show them.
    pub not_comparable: Vec<NotComparable>,
    /// Counts and extremes.
    pub figures: Figures,
    /// The compact recorded trace, aligned (for diagrams).
    #[serde(skip)]
    pub recorded: Trace,
    /// Plot points of the recorded trace (the least and the greatest of each time bucket).
    #[serde(skip)]
    pub series: Vec<Point>,
    /// The reference's discrete events (every event but its samples), the end last.
    #[serde(skip)]
    pub reference: Trace,
    /// Most reference samples held at once by the comparison.
    #[serde(skip)]
    pub reference_samples_held: usize,
    /// Most other records of the reference held at once by the comparison (its events waiting
    /// to be matched, synchronised moves, phases, key points waiting for their pair).
    #[serde(skip)]
    pub reference_records_held: usize,
    /// Wall time of the comparison, s (JUnit `time`).
    pub seconds: f64,
}

/// A margin's number and unit (`0.139809 mm`, `130 ms beyond the window`, `5 rpm`); None for
/// `-`.
pub fn margin_number(margin: &str) -> Option<(f64, &str)> {
    let mut it = margin.split_whitespace();
    let v: f64 = it.next()?.parse().ok()?;
    Some((v, it.next().unwrap_or("")))
}

fn divergences_json<S: serde::Serializer>(ds: &[Divergence], s: S) -> Result<S::Ok, S::Error> {
    #[derive(Serialize)]
    struct WithNumber<'a> {
        #[serde(flatten)]
        d: &'a Divergence,
        margin_value: Option<f64>,
        margin_unit: Option<&'a str>,
    }
    let mut v: Vec<&Divergence> = ds.iter().collect();
    v.sort_by_key(|d| d.t_us.unwrap_or(i64::MAX));
    s.collect_seq(v.into_iter().map(|d| {
        let m = margin_number(&d.margin);
        WithNumber { d, margin_value: m.map(|x| x.0), margin_unit: m.map(|x| x.1) }
    }))
}

impl Report {
    /// No divergence.
    pub fn conformant(&self) -> bool {
        self.divergences.is_empty() && self.omitted == 0
    }

    /// The divergences by time (those without a time last).
    pub fn sorted(&self) -> Vec<&Divergence> {
        let mut v: Vec<_> = self.divergences.iter().collect();
        v.sort_by_key(|d| d.t_us.unwrap_or(i64::MAX));
        v
    }

    /// Whether a divergence cites `rule`.
    pub fn has_rule(&self, rule: &str) -> bool {
        self.divergences.iter().any(|d| d.rule == rule)
    }
}

/// The default anchor for `reference` recorded in a format that carries everything: its first
/// M29, else its first STL ↑, else offset 0 (see [`Carried::default_anchor`] for the others).
pub fn default_anchor(reference: &Trace) -> Anchor {
    if reference.functions().any(|(_, l, c)| l == 'M' && c == 29) {
        Anchor::Function('M', 29)
    } else if reference.edges(Signal::Stl).any(|(_, v)| v) {
        Anchor::Edge(Signal::Stl, true)
    } else {
        Anchor::Offset(0)
    }
}

/// Compares the recorded events (time as recorded, in order) with `reference`.
pub fn check(reference: &Trace, recorded: impl IntoIterator<Item = TraceEvent>, spec: &CheckSpec) -> Report {
    check_source(Source::Trace(reference), recorded, spec)
}

/// Compares the recorded events with the reference run `source`. A run (the engine) is replayed
/// once to index it (its tap, a summary of its events; with temporal rules, or thread blocks
/// found by their lead, its discrete events, key points and synchronised moves too, in one or
/// two passes), then once more on another thread, alongside the recorded stream: its samples,
/// and without temporal rules its events, key points, synchronised moves and phases, held only
/// around the recorded time (DEC-162; one more replay at the end attributes divergences at times
/// no longer held): memory does not follow the length of the run or of the recording.
pub fn check_source(
    source: Source,
    recorded: impl IntoIterator<Item = TraceEvent>,
    spec: &CheckSpec,
) -> Report {
    check_surveyed(source, survey::Skeleton::of_lean(source, spec.expect.is_none()), recorded, spec)
}

/// As [`check_source`], the first pass over the reference (`skeleton`, [`survey::Skeleton::of`])
/// done already (to refuse a run that does not end before reading the recording).
pub fn check_surveyed(
    source: Source,
    skeleton: survey::Skeleton,
    recorded: impl IntoIterator<Item = TraceEvent>,
    spec: &CheckSpec,
) -> Report {
    // Thread blocks found by their lead (KND G32 without phases) are read from a whole first
    // pass, their moves in a second (`survey::Survey`): not alongside the comparison.
    let skeleton = if skeleton.is_lean() && skeleton.has_lead_blocks() {
        survey::Skeleton::of_lean(source, false)
    } else {
        skeleton
    };
    match source {
        Source::Trace(t) => {
            let r = reference::Reference::build_from(
                source,
                skeleton,
                window::Feed::Trace(t.events.iter()),
                spec.expect.is_some(),
            );
            compare(r, recorded, spec)
        }
        Source::Run(run) => std::thread::scope(|sc| {
            let (tx, rx) = std::sync::mpsc::sync_channel(4);
            let (keyed, tap) = (skeleton.is_lean(), skeleton.tap());
            sc.spawn(move || {
                let mut sink = window::ChannelSink::new(tx, keyed, tap);
                run(&mut sink as &mut dyn TraceSink);
                sink.finish();
            });
            let r = reference::Reference::build_from(
                source,
                skeleton,
                window::Feed::Channel(rx),
                spec.expect.is_some(),
            );
            compare(r, recorded, spec)
        }),
    }
}

fn compare(
    mut r: reference::Reference,
    recorded: impl IntoIterator<Item = TraceEvent>,
    spec: &CheckSpec,
) -> Report {
    let started = std::time::Instant::now();
    let anchor = spec.anchor.clone().unwrap_or_else(|| spec.carried.default_anchor(&r));
    let totals = r.summary.total;
    // Without temporal rules the reference's discrete events are read once, here, then dropped
    // (when the first pass kept them: else they come with the samples).
    let keep_all = spec.expect.is_some();
    let full = if keep_all || r.streamed { None } else { Some(r.slim()) };
    let skeleton = full.as_ref().unwrap_or(&r.trace);
    let mut c =
        compare::Comparator::new(&r, skeleton, spec.tolerances.clone(), anchor.clone(), spec.rules.clone())
            .carrying(spec.carried.clone(), skeleton)
            .keeping_all(keep_all);
    drop(full);
    for ev in recorded {
        c.event(ev);
    }
    let (compact, pecks) = c.finish();
    let mut rules = Vec::new();
    if let Some(exp) = spec.expect {
        rules = expect::evaluate_discrete(exp, &compact);
        // A rule over a signal the recording does not carry cannot be judged on it.
        rules.retain(|v| {
            match Signal::ALL.iter().find(|&&s| !c.carries_signal(s) && carried::mentions(v, s)) {
                Some(s) => {
                    c.not_comparable.push(NotComparable {
                        what: format!("scenario rule {} {}", v.rule, v.what),
                        count: 0,
                        reason: format!("{} carries no {}", spec.carried.source, s.name()),
                    });
                    false
                }
                None => true,
            }
        });
        for v in rules.iter().filter(|v| !v.pass) {
            c.push(Divergence {
                rule: v.rule.clone(),
                check: "CHK-RULE-01".into(),
                what: format!("scenario {}", v.what),
                t_us: v.t_us.map(|t| t as i64),
                expected: v.expected.clone(),
                actual: v.actual.clone(),
                margin: "-".into(),
            });
        }
    }
    let figures = Figures {
        recorded_events: c.events_seen,
        recorded_samples: c.samples_seen,
        reference_events: totals,
        matched_events: 0,
        max_sync_error_mm: c.max_sync_nm / 1e6,
        sync_samples: c.sync_samples,
        max_envelope_excess_mm: c.max_env_nm / 1e6,
        pecks,
        fit_rms_mm: (c.fit.1 > 0).then(|| (c.fit.0 / c.fit.1 as f64).sqrt() / 1e6),
        fit_values: c.fit.1,
    };
    let report = Report {
        divergences: std::mem::take(&mut c.divergences),
        omitted: c.omitted,
        omitted_by_check: std::mem::take(&mut c.omitted_by_check),
        rules,
        anchor: if c.anchored { anchor.describe() } else { format!("{} (not found)", anchor.describe()) },
        offset_us: c.offset(),
        tolerances: spec.tolerances.clone(),
        not_comparable: std::mem::take(&mut c.not_comparable),
        figures: Figures { matched_events: c.matched(), ..figures },
        recorded: compact,
        series: std::mem::take(&mut c.series),
        reference: Trace { meta: r.trace.meta.clone(), events: Vec::new() },
        reference_samples_held: r.win.borrow().peak,
        reference_records_held: c.records_held,
        seconds: started.elapsed().as_secs_f64(),
    };
    drop(c);
    Report { reference: std::mem::replace(&mut r.trace, report.reference.clone()), ..report }
}
