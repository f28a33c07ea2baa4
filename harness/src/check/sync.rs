//! Synchronisation of an axis with the spindle (`CHK-SYNC-01`), during every synchronised move of
//! the reference: rigid-tapping strokes (RGSPP/RGSPM on in the reference), thread passes (G32,
//! G92, G92.3, G76, G33, cycle 832) and moves that follow the spindle's encoder (KND G93,
//! LinuxCNC G33.1).
//!
//! The windows come from the **reference** (its stroke signals, its blocks and phases), never
//! from the recording: a stroke-end edge recorded late (a PLC scan) does not stretch a stroke
//! over the rapid that follows it, and a recording without stroke signals (LinuxCNC, a CSV of
//! positions) is still compared.
//!
//! At each recorded sample inside a window, the reference's time is found at which its window
//! axis stood where the recorded axis stands (the crossing nearest in time, within the event
//! window); the recorded spindle angle is compared with the reference's angle there, and the
//! difference turned into mm along the axis with the reference's local lead. That is the
//! position the axis has at the recorded angle: it measures the lead (its drift from the
//! window's first compared sample) and, where the reference starts its pass at a set angle
//! after the index (G92.3, cycle 832), the start angle too (the error itself), whatever the
//! clocks and sample times.

use nc_engine::trace::{AxisSpec, Event, Phase, Signal, Signals, Trace, TraceEvent};

use super::reference::{unwrap_delta, Reference};
use super::survey::{LeadBlock, Span};

/// What kind of synchronised move a window is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A rigid-tapping stroke (RGSPP or RGSPM on).
    Stroke,
    /// A thread pass (feed locked to the spindle).
    Thread,
    /// A move following the spindle's encoder (KND G93, LinuxCNC G33.1).
    Follow,
}

impl Kind {
    /// As text.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Stroke => "rigid tapping stroke",
            Kind::Thread => "thread pass",
            Kind::Follow => "synchronised move",
        }
    }
}

/// One synchronised move of the reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Window {
    /// Start and end, reference time.
    pub t0: i64,
    /// End.
    pub t1: i64,
    /// The axis locked to the spindle (the one that travels furthest).
    pub slot: usize,
    /// 2 for an axis reported as a diameter.
    pub div: f64,
    /// The kind.
    pub kind: Kind,
    /// The reference starts it at a set angle after the index: the angle itself is compared,
    /// not only the lead.
    pub locked: bool,
    /// Its number among the windows of its kind (1-based).
    pub n: usize,
    /// The G code of the block it belongs to (None: a rigid stroke, a Klartext cycle).
    pub code: Option<&'static str>,
    /// The reference's position of its axis at its start and end, nm.
    pub ends: [f64; 2],
}

/// The G codes of a dialect that lock the feed to the spindle: (threads, followers, the ones
/// that start at a set angle after the index).
fn sync_codes(dialect: &str) -> (&'static [&'static str], &'static [&'static str], &'static [&'static str]) {
    match dialect {
        "gsk-lathe" => (&["G32", "G92", "G92.3", "G76", "G33"], &[], &["G92.3"]),
        "knd-lathe" => (&["G32", "G92", "G76"], &["G93"], &[]),
        "linuxcnc" => (&["G33", "G76"], &["G33.1"], &[]),
        _ => (&[], &[], &[]),
    }
}

/// The motion-group G codes of a block's text (a later one wins), upper case, comments out.
fn motion_code(text: &str, lathe: bool) -> Option<String> {
    let mut out = None;
    let mut depth = 0;
    let up = text.to_ascii_uppercase();
    let b = up.as_bytes();
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'(' => depth += 1,
            b')' => depth -= 1,
            b';' if depth == 0 => break,
            b'G' if depth == 0 => {
                let j =
                    (i + 1..b.len()).find(|&k| !(b[k].is_ascii_digit() || b[k] == b'.')).unwrap_or(b.len());
                if let Ok(v) = up[i + 1..j].parse::<f64>() {
                    let code = format!("G{}", up[i + 1..j].trim_start_matches('0'));
                    let code = if code == "G" || code.starts_with("G.") {
                        format!("G0{}", &code[1..])
                    } else {
                        code
                    };
                    let motion = matches!(v as u32, 0..=3 | 32..=34 | 73..=89 | 92 | 93)
                        || (lathe && matches!(v as u32, 90 | 94));
                    if motion && (v != 92.0 || lathe) {
                        out = Some(code);
                    }
                }
                i = j;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    out
}

/// The value of the first word `letter` in a block's text (comments out).
fn word(text: &str, letter: char) -> Option<f64> {
    let up = text.to_ascii_uppercase();
    let up = up.split(';').next().unwrap_or("");
    let mut depth = 0;
    let b = up.as_bytes();
    for (i, &c) in b.iter().enumerate() {
        match c {
            b'(' => depth += 1,
            b')' => depth -= 1,
            c if depth == 0 && c == letter as u8 => {
                let j = (i + 1..b.len())
                    .find(|&k| !(b[k].is_ascii_digit() || b[k] == b'.' || b[k] == b'-'))
                    .unwrap_or(b.len());
                return up[i + 1..j].parse().ok();
            }
            _ => {}
        }
    }
    None
}

/// A synchronised move found from the reference's discrete events, before its samples are read:
/// a fixed interval, or the locked parts of a thread block the reference ran without phase
/// events (KND G32, G92: the parts of it where the axis that travels furthest advances the
/// block's F per spindle revolution, within 3 %, at least 20 ms; the rapids in and back are left
/// out), found by [`super::survey::Survey`].
#[derive(Debug)]
enum Raw {
    Fixed(i64, i64, Kind, bool, Option<&'static str>),
    Lead(usize, &'static str),
}

/// The synchronised moves of a reference, planned from its discrete events: the spans whose
/// samples decide their axis and ends, and the lead blocks.
pub struct Plan {
    raw: Vec<Raw>,
    /// The intervals of the fixed moves, in their order.
    pub spans: Vec<(i64, i64)>,
    /// The thread blocks without phase events.
    pub lead: Vec<LeadBlock>,
}

/// Plans the synchronised moves of a reference from its discrete events (`trace`: samples are
/// not looked at) ending at `end_us`.
pub fn plan(trace: &Trace, end_us: i64) -> Plan {
    let mut p = Planner::new(trace.meta.dialect);
    for e in &trace.events {
        p.event(e);
    }
    p.finish(end_us)
}

/// [`plan`] as the events stream by (the reference's first pass plans while it reads, so that
/// its blocks and phases need not be kept).
pub struct Planner {
    lathe: bool,
    heidenhain: bool,
    threads: &'static [&'static str],
    follows: &'static [&'static str],
    locked: &'static [&'static str],
    raw: Vec<Raw>,
    lead: Vec<LeadBlock>,
    sig: Signals,
    stroke_from: Option<i64>,
    code: Option<String>,
    open: Option<(i64, Kind, bool, Option<&'static str>)>,
    block: Option<(i64, &'static str, f64)>,
    phased: bool,
    feed: Option<f64>,
    /// The motion codes of the blocks read at one instant: a structure (a LinuxCNC loop, a
    /// subroutine call) is read at once, and its steps run after its last line was read.
    batch: (i64, Vec<String>),
    /// The fixed intervals' openings and closings as they are read (`Some`: listed), for a
    /// survey read in the same pass (`survey_fused`).
    pub(crate) edges: Option<Vec<SpanEdge>>,
    /// The fixed intervals are listed in the plan.
    keep_raw: bool,
}

/// A fixed interval of the plan opened (`open`) or closed at `t`: `which` 0 a rigid stroke, 1 a
/// phase's synchronised move (at most one of each is open at once), its kind. The closings come
/// in the order of [`Plan::spans`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SpanEdge {
    pub which: usize,
    pub open: bool,
    pub t: i64,
    pub kind: MoveKind,
}

/// A synchronised move's kind, whether it starts at a set angle, its G code.
pub(crate) type MoveKind = (Kind, bool, Option<&'static str>);

const STROKE: MoveKind = (Kind::Stroke, false, None);

impl Default for Planner {
    fn default() -> Self {
        Planner::new("")
    }
}

impl Planner {
    /// A planner for a run of `dialect`.
    pub fn new(dialect: &str) -> Planner {
        let (threads, follows, locked) = sync_codes(dialect);
        Planner {
            lathe: dialect.contains("lathe"),
            heidenhain: dialect == "heidenhain",
            threads,
            follows,
            locked,
            raw: Vec::new(),
            lead: Vec::new(),
            sig: Signals::default(),
            stroke_from: None,
            code: None,
            open: None,
            block: None,
            phased: false,
            feed: None,
            batch: (i64::MIN, Vec::new()),
            edges: None,
            keep_raw: true,
        }
    }

    fn edge(&mut self, which: usize, open: bool, t: i64, kind: MoveKind) {
        if let Some(e) = &mut self.edges {
            e.push(SpanEdge { which, open, t, kind });
        }
    }

    /// A fixed interval closed (listed unless the planner only finds whether there are lead
    /// blocks).
    fn fixed(&mut self, a: i64, b: i64, kind: MoveKind) {
        if self.keep_raw {
            self.raw.push(Raw::Fixed(a, b, kind.0, kind.1, kind.2));
        }
    }

    /// Lists no fixed interval (memory: the synchronised moves are then read alongside the
    /// comparison, `check::sync_stream`), only the lead blocks.
    pub(crate) fn without_list(mut self) -> Planner {
        self.keep_raw = false;
        self
    }

    /// Whether a thread block without phase events was read (its moves are found by their
    /// lead: `Survey`).
    pub(crate) fn has_lead_blocks(&self) -> bool {
        !self.lead.is_empty() || (self.block.is_some() && !self.phased)
    }

    fn by_lead(&mut self, t0: i64, t1: i64, g: &'static str, f: f64) {
        self.raw.push(Raw::Lead(self.lead.len(), g));
        self.lead.push(LeadBlock { t0, t1, lead_mm: f });
    }

    /// The next event of the run.
    pub fn event(&mut self, e: &TraceEvent) {
        let t = e.t_us as i64;
        match &e.event {
            Event::Signal { signal, value } if matches!(signal, Signal::Rgspp | Signal::Rgspm) => {
                self.sig.set(*signal, *value);
                let on = self.sig.get(Signal::Rgspp) || self.sig.get(Signal::Rgspm);
                match (on, self.stroke_from) {
                    (true, None) => {
                        self.stroke_from = Some(t);
                        self.edge(0, true, t, STROKE);
                    }
                    (false, Some(a)) => {
                        self.fixed(a, t, STROKE);
                        self.stroke_from = None;
                        self.edge(0, false, t, STROKE);
                    }
                    _ => {}
                }
            }
            Event::Block { text, .. } => {
                // A thread block that ran without phase events (KND G32/G92): its synchronised
                // parts are found by their lead.
                if let Some((b0, g, f)) = self.block.take() {
                    if !self.phased {
                        self.by_lead(b0, t, g, f);
                    }
                }
                if t != self.batch.0 {
                    self.batch = (t, Vec::new());
                }
                if let Some(c) = motion_code(text, self.lathe) {
                    self.batch.1.push(c.clone());
                    self.code = Some(c);
                }
                if let Some(v) = word(text, 'F') {
                    self.feed = Some(v);
                }
                let c = self.code.as_deref().unwrap_or("");
                self.block = self.threads.iter().find(|x| **x == c).zip(self.feed).map(|(g, f)| (t, *g, f));
                self.phased = false;
            }
            // The spindle given its own sense again ends a way out that follows it (LinuxCNC's
            // G33.1 at its start point: from there the tap brakes with the spindle turning
            // through zero, then moves back unsynchronised while it speeds up, DEC-149).
            Event::Function { letter: 'M', code: 3 | 4 }
                if self.open.is_some_and(|(_, k, ..)| k == Kind::Follow) =>
            {
                if let Some((a, k, l, g)) = self.open.take() {
                    self.fixed(a, t, (k, l, g));
                    self.edge(1, false, t, (k, l, g));
                }
            }
            Event::Phase(p) => {
                self.phased = true;
                if let Some((a, k, l, g)) = self.open.take() {
                    self.fixed(a, t, (k, l, g));
                    self.edge(1, false, t, (k, l, g));
                }
                let mut c = self.code.as_deref().unwrap_or("");
                // A phase of a synchronised move read within a structure whose last line is
                // another: the structure's one phase-making code, when it is a synchronised one.
                if !self.threads.contains(&c) && !self.follows.contains(&c) {
                    let mut phasing =
                        self.batch.1.iter().filter(|x| !matches!(x.as_str(), "G0" | "G1" | "G2" | "G3"));
                    if let Some(only) = phasing.next() {
                        let synced =
                            self.threads.contains(&only.as_str()) || self.follows.contains(&only.as_str());
                        if synced && phasing.all(|x| x == only) {
                            c = only.as_str();
                        }
                    }
                }
                let g = self.threads.iter().chain(self.follows).find(|x| **x == c).copied();
                let kind = if self.heidenhain && *p == Phase::Cutting {
                    Some((Kind::Thread, true))
                } else if self.follows.contains(&c) && matches!(p, Phase::Cutting | Phase::Retract) {
                    Some((Kind::Follow, false))
                } else if self.threads.contains(&c) && *p == Phase::Cutting {
                    Some((Kind::Thread, self.locked.contains(&c)))
                } else {
                    None
                };
                self.open = kind.map(|(k, l)| (t, k, l, g));
                if let Some((k, l)) = kind {
                    self.edge(1, true, t, (k, l, g));
                }
            }
            _ => {}
        }
    }

    /// The plan of the run, which ended at `end_us`.
    pub fn finish(mut self, end_us: i64) -> Plan {
        if let Some((a, k, l, g)) = self.open {
            self.raw.push(Raw::Fixed(a, end_us, k, l, g));
        }
        if let Some((b0, g, f)) = self.block.filter(|_| !self.phased) {
            self.by_lead(b0, end_us, g, f);
        }
        if let Some(a) = self.stroke_from {
            self.raw.push(Raw::Fixed(a, end_us, Kind::Stroke, false, None));
        }
        let spans = self
            .raw
            .iter()
            .filter_map(|w| match w {
                Raw::Fixed(a, b, ..) => Some((*a, *b)),
                Raw::Lead(..) => None,
            })
            .collect();
        Plan { raw: self.raw, spans, lead: self.lead }
    }
}

/// The synchronised moves of a reference, in time order, from its plan and what the survey of
/// its samples found (`spans` in the order of [`Plan::spans`], the locked parts of each lead
/// block).
pub fn build(
    plan: Plan,
    spans: Vec<Span>,
    lead_parts: Vec<Vec<(i64, i64, Span)>>,
    tap: Option<super::reference::Tap>,
    axes: &[AxisSpec],
) -> Vec<Window> {
    let mut spans = spans.into_iter();
    let mut lead_parts: Vec<Option<Vec<(i64, i64, Span)>>> = lead_parts.into_iter().map(Some).collect();
    // Each move with its axis (the tap's for a stroke, else the one that travels furthest) and
    // that axis' ends, found as it is listed: the span itself is not kept (memory).
    type Move = (i64, i64, Kind, bool, Option<&'static str>, usize, [f64; 2]);
    let pick = |kind: Kind, span: &Span| -> Option<(usize, [f64; 2])> {
        let slot = match kind {
            Kind::Stroke => tap?.slot,
            _ => span.furthest()?,
        };
        let end = |i: usize| span.ends[i].map_or(0.0, |e| e[slot]);
        Some((slot, [end(0), end(1)]))
    };
    let mut raw: Vec<Move> = Vec::new();
    for w in plan.raw {
        match w {
            Raw::Fixed(a, b, k, l, g) => {
                if let Some((slot, ends)) = pick(k, &spans.next().unwrap_or_default()) {
                    raw.push((a, b, k, l, g, slot, ends));
                }
            }
            Raw::Lead(i, g) => {
                for (a, b, span) in lead_parts.get_mut(i).and_then(Option::take).unwrap_or_default() {
                    if let Some((slot, ends)) = pick(Kind::Thread, &span) {
                        raw.push((a, b, Kind::Thread, false, Some(g), slot, ends));
                    }
                }
            }
        }
    }
    drop(spans);
    // Listed in time order as a rule: sorted (stably) only when not.
    if !raw.is_sorted_by_key(|w| w.0) {
        raw.sort_by_key(|w| w.0);
    }
    let mut counts = [0usize; 3];
    let mut out = Vec::with_capacity(raw.len());
    for (t0, t1, kind, locked, code, slot, ends) in raw {
        let div = if axes.iter().any(|a| a.index == slot && a.diameter) { 2.0 } else { 1.0 };
        let k = kind as usize;
        counts[k] += 1;
        out.push(Window { t0, t1, slot, div, kind, locked, n: counts[k], code, ends });
    }
    out
}

/// The synchronisation error at one recorded sample, nm along the axis (physical: a diameter
/// axis as a radius): recorded position − the reference's position at the recorded angle.
/// None where it cannot be told (no crossing near, the axis or the spindle standing, the axis
/// within `still_nm` of where the reference's move starts or ends: a recorded axis still waiting
/// there, for the index or a late edge, tells nothing of the lead).
pub fn error_at(
    r: &Reference,
    w: &Window,
    t: i64,
    pos: i64,
    angle_mdeg: i64,
    slack_us: i64,
    still_nm: i64,
) -> Option<f64> {
    let lo = (t - slack_us).max(w.t0);
    let hi = (t + slack_us).min(w.t1);
    if lo >= hi {
        return None;
    }
    if w.ends.iter().any(|&e| (pos as f64 - e).abs() <= still_nm as f64) {
        return None;
    }
    r.with_samples(lo, hi, t, |rt, rs, rc, [i0, i1, after_t]| {
        // Segments outward from the one at `t`; the crossing nearest in time wins (both sides of a
        // ring are looked at before stopping).
        let seg = |i: usize| -> Option<(i64, usize, f64)> {
            let (a, b) = (rs[i].axes[w.slot], rs[i + 1].axes[w.slot]);
            if (a - pos).signum() * (b - pos).signum() > 0 || (b - a).abs() < 100 {
                return None;
            }
            let f = (pos - a) as f64 / (b - a) as f64;
            Some((rt[i] + (f * (rt[i + 1] - rt[i]) as f64) as i64, i, f))
        };
        let last = i1.saturating_sub(1);
        let mid = after_t.saturating_sub(1).clamp(i0, last.max(i0));
        let mut best: Option<(i64, usize, f64)> = None;
        for d in 0..=(last.saturating_sub(i0)) {
            for i in [mid.checked_add(d), mid.checked_sub(d + 1)].into_iter().flatten() {
                if i < i0 || i >= last {
                    continue;
                }
                if let Some(c) = seg(i) {
                    if best.is_none_or(|(bt, _, _)| (c.0 - t).abs() < (bt - t).abs()) {
                        best = Some(c);
                    }
                }
            }
            if best.is_some() {
                break;
            }
        }
        let (_, i, f) = best?;
        let d_ang = rc[i + 1] - rc[i];
        if d_ang.abs() < 1.0 {
            return None;
        }
        let lead_nm_per_mdeg = (rs[i + 1].axes[w.slot] - rs[i].axes[w.slot]) as f64 / d_ang;
        let ref_angle = super::reference::rem_turn(rc[i] + f * d_ang);
        let mut delta = super::reference::rem_turn(angle_mdeg as f64 - ref_angle);
        if delta > 180_000.0 {
            delta -= 360_000.0;
        }
        Some(-delta * lead_nm_per_mdeg / w.div)
    })
}

/// The cumulative unwrapped spindle angle at each reference sample, milli-degrees.
pub fn cumulative_angle(r_t: &[i64], r_s: &[nc_engine::trace::Sample]) -> Vec<f64> {
    let mut out = Vec::with_capacity(r_s.len());
    let mut acc = r_s.first().map_or(0.0, |s| s.spindle_mdeg as f64);
    for (k, s) in r_s.iter().enumerate() {
        if k > 0 {
            let p = &r_s[k - 1];
            acc += unwrap_delta(
                p.spindle_mdeg,
                p.spindle_mrpm,
                s.spindle_mdeg,
                s.spindle_mrpm,
                r_t[k] - r_t[k - 1],
            );
        }
        out.push(acc);
    }
    out
}

/// Programs with synchronised moves of every kind (for the tests).
#[cfg(test)]
pub(crate) fn test_programs() -> Vec<(&'static str, String)> {
    vec![
        ("knd-lathe", "G00 X30 Z5;\nM03 S600;\nG32 Z-20 F2;\nG00 X40;\nZ5;\nG92 X28 Z-20 F2;\nX27;\nM30;\n".into()),
        ("gsk-lathe", "G0 X40 Z5;\nM03 S500;\nG92.3 X36 Z-20 F4 J1 K2 D0.1 E1 Q0.5 A1;\nG0 X60;\nM30;\n".into()),
        ("linuxcnc", "G18 G21 M3 S600\nG4 P0.5\nG0 X10 Z5\nG33 Z-20 K1.5\nG0 X12\nM2\n".into()),
        ("linuxcnc", "G21 G90 G0 X0 Y0 Z5\nM3 S500\nG33.1 Z-10 K1.25\nG0 Z20\nM2\n".into()),
        (
            "linuxcnc",
            "G21 G90 M3 S500\nG0 X0 Y0 Z3\nG91\no100 repeat [3]\n  G33.1 Z-8 K1.25\n  G0 X12 Y4\no100 endrepeat\nM2\n"
                .into(),
        ),
        ("fanuc-mill", crate::check::holes::program(3)),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn motion_codes_are_read_from_block_text() {
        assert_eq!(motion_code("G92.3 X36 Z-20 F4", true).as_deref(), Some("G92.3"));
        assert_eq!(motion_code("g33.1 z-10 k1.5 (g0 in a comment)", false).as_deref(), Some("G33.1"));
        assert_eq!(motion_code("G98 G21 X5", true), None);
        assert_eq!(motion_code("G92 X0 Y0", false), None, "Fanuc G92 sets coordinates");
        assert_eq!(motion_code("G00 X1 ; G32", true).as_deref(), Some("G0"));
    }

    fn follows(program: &str) -> usize {
        let m = nc_engine::Machine::new("linuxcnc").unwrap();
        let t = m.run_to_trace(&m.parse(program).unwrap(), &nc_engine::RunOptions::default());
        let end = t.events.last().map_or(0, |e| e.t_us as i64);
        plan(&t, end).raw.iter().filter(|r| matches!(r, Raw::Fixed(_, _, Kind::Follow, ..))).count()
    }

    #[test]
    fn a_synchronised_move_inside_a_loop_is_found() {
        // A LinuxCNC loop is read at once: its steps run after its last line (`endrepeat`) was
        // read, so the line before the phases is not the G33.1. Three holes: a cut and a way out
        // each, as when the lines are written out.
        let head = "G21 G90 M3 S500\nG0 X0 Y0 Z3\nG91\n";
        let looped = format!("{head}o100 repeat [3]\n  G33.1 Z-8 K1.25\n  G0 X12 Y4\no100 endrepeat\nM2\n");
        let flat = format!("{head}{}M2\n", "G33.1 Z-8 K1.25\nG0 X12 Y4\n".repeat(3));
        assert_eq!(follows(&flat), 6);
        assert_eq!(follows(&looped), 6);
        // A loop that also drills: its phases cannot be told apart by the lines, none is taken.
        let mixed = format!(
            "{head}o100 repeat [2]\n  G33.1 Z-8 K1.25\n  G81 Z-2 R1 F100\n  G80\no100 endrepeat\nM2\n"
        );
        assert_eq!(follows(&mixed), 0);
        let m = nc_engine::Machine::new("linuxcnc").unwrap();
        let t = m.run_to_trace(&m.parse(&mixed).unwrap(), &nc_engine::RunOptions::default());
        let cuts = t.events.iter().filter(|e| matches!(e.event, Event::Phase(Phase::Cutting))).count();
        assert!(cuts >= 4, "the mixed loop taps and drills twice: {cuts} cuts");
    }

    /// A G33.1's way out ends at the M3 that gives the spindle its own sense again at the start
    /// point: the move back after it is not synchronised while the spindle speeds up (DEC-149).
    #[test]
    fn a_g33_1_way_out_ends_where_the_spindle_is_given_its_sense_again() {
        let m = nc_engine::Machine::new("linuxcnc").unwrap();
        let program = "G21 G90 M3 S500\nG0 X0 Y0 Z5\nG33.1 Z-10 K1\nG0 Z20\nM2\n";
        let t = m.run_to_trace(&m.parse(program).unwrap(), &nc_engine::RunOptions::default());
        let end = t.events.last().map_or(0, |e| e.t_us as i64);
        let m3 = t
            .events
            .iter()
            .filter(|e| matches!(e.event, Event::Function { letter: 'M', code: 3 }))
            .map(|e| e.t_us as i64)
            .next_back()
            .unwrap();
        let idle = t
            .events
            .iter()
            .filter(|e| matches!(e.event, Event::Phase(Phase::Idle)))
            .map(|e| e.t_us as i64)
            .next_back()
            .unwrap();
        assert!(m3 < idle, "M3 at {m3} µs comes before the move back ends at {idle} µs");
        let ends: Vec<i64> = plan(&t, end)
            .raw
            .iter()
            .filter_map(|r| match r {
                Raw::Fixed(_, b, Kind::Follow, ..) => Some(*b),
                _ => None,
            })
            .collect();
        assert_eq!(ends.len(), 2, "{ends:?}");
        assert_eq!(ends[1], m3);
    }

    /// The first pass plans as it reads: the plan of a whole first pass is `plan` over its
    /// events, for thread blocks found by their lead (KND), thread passes by phase (GSK G92.3,
    /// LinuxCNC G33) and rigid strokes (Fanuc); a lean pass keeps the end only, its summary of
    /// the edges, functions and alarms the whole trace's (the moves and phases are read
    /// alongside the comparison: `sync_stream::tests`).
    #[test]
    fn the_first_pass_plans_as_it_reads() {
        use crate::check::survey::{Skeleton, Source};
        use nc_engine::{Machine, RunOptions};
        for (dialect, text) in test_programs() {
            let m = Machine::new(dialect).unwrap();
            let p = m.parse(&text).unwrap();
            let run = |sink: &mut dyn nc_engine::trace::TraceSink| m.run(&p, &RunOptions::default(), sink);
            let mut whole = Skeleton::of(Source::Run(&run));
            let mut lean = Skeleton::of_lean(Source::Run(&run), true);
            let pw = whole.plan();
            let trace = whole.trace();
            let pt = plan(&trace, whole.end_us);
            assert!(!pw.raw.is_empty(), "{dialect}: no synchronised move planned");
            assert_eq!(
                format!("{:?} {:?} {:?}", pw.raw, pw.spans, pw.lead),
                format!("{:?} {:?} {:?}", pt.raw, pt.spans, pt.lead),
                "{dialect}"
            );
            assert_eq!(lean.has_lead_blocks(), !pw.lead.is_empty(), "{dialect}");
            let whole_summary = crate::check::events::Summary::of(&trace);
            assert_eq!(
                format!("{:?} {} {:?}", whole_summary.keys, whole_summary.total, whole_summary.faults),
                format!("{:?} {} {:?}", lean.summary.keys, lean.summary.total, lean.summary.faults),
                "{dialect}"
            );
            assert_eq!(lean.trace().events, trace.events[trace.events.len() - 1..], "{dialect}");
        }
    }
}
