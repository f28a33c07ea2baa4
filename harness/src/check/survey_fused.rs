//! The reference's second pass ([`super::survey::Survey`]: key points and the spans of the
//! synchronised moves) read in its first ([`super::survey::Skeleton`]), so that the engine runs
//! once less before the comparison starts.
//!
//! The second pass needs what the first finds: the tap (over the whole run) and the plan's
//! spans. Here the spans are read from their opening, as the planner lists them
//! (`sync::Planner::edges`), and the key points with the tap guessed from the first stroke (the
//! events before it waiting, a bounded number). At the end the guess and the spans are checked
//! against the run's tap and plan: when either differs, or the plan has lead blocks, nothing is
//! given and the second pass is run as before. What is given is what the second pass gives
//! (test `a_fused_survey_reads_as_the_second_pass`).

use nc_engine::trace::{Event, Sample, TraceEvent, TraceMeta};

use super::keypoints::{KeyPoints, KeyTracker};
use super::reference::Tap;
use super::survey::{held, track_spans, Span, TapFinder};
use super::sync::{Plan, SpanEdge};

/// Most events kept waiting for the tap's guess (about 80 bytes each).
const MAX_WAITING: usize = 1 << 16;

/// The second pass, read alongside the first.
#[derive(Default)]
pub(super) struct Fused {
    /// The tap guessed from the first stroke, once guessed (`Some(None)`: guessed, no tap).
    guess: Option<Option<Tap>>,
    keys: Option<KeyTracker>,
    /// Samples and signals read before the guess.
    waiting: Vec<(i64, Event)>,
    /// The spans in the order they opened, the end `i64::MAX` while open.
    spans: Vec<(i64, i64)>,
    out: Vec<Span>,
    /// The spans in the order they closed (the plan's).
    closed: Vec<usize>,
    /// The open stroke and the open phase's move.
    open: [Option<usize>; 2],
    active: Vec<(usize, Option<Sample>)>,
    prev: Option<(i64, Sample)>,
}

fn axes(meta: &Option<TraceMeta>) -> &[nc_engine::trace::AxisSpec] {
    meta.as_ref().map(|m| m.axes.as_slice()).unwrap_or(&[])
}

impl Fused {
    /// A discrete event, after the first pass read it (`edges`: the spans it opened or closed).
    /// False: given up.
    pub(super) fn event(
        &mut self,
        ev: &TraceEvent,
        edges: &[SpanEdge],
        tap: &TapFinder,
        meta: &Option<TraceMeta>,
    ) -> bool {
        for e in edges {
            if e.open {
                let i = self.spans.len();
                self.spans.push((e.t, i64::MAX));
                self.out.push(Span::default());
                // A sample at the opening's time read before it is the span's first.
                let first = self.prev.filter(|p| p.0 >= e.t).map(|p| p.1);
                self.active.push((i, first));
                self.open[e.which] = Some(i);
            } else if let Some(i) = self.open[e.which].take() {
                self.spans[i].1 = e.t;
                self.closed.push(i);
            }
        }
        if matches!(ev.event, Event::Signal { .. }) {
            return self.keys_event(ev.t_us as i64, &ev.event, tap, meta);
        }
        true
    }

    /// A sample, after the first pass read it. False: given up.
    pub(super) fn sample(&mut self, t: i64, s: &Sample, tap: &TapFinder, meta: &Option<TraceMeta>) -> bool {
        if !self.active.is_empty() {
            track_spans(&mut self.active, &self.spans, &mut self.out, &self.prev, t, s);
        }
        self.prev = Some((t, *s));
        if let Some(k) = &mut self.keys {
            k.event(t, &Event::Sample(*s));
            return true;
        }
        self.keys_event(t, &Event::Sample(*s), tap, meta)
    }

    fn keys_event(&mut self, t: i64, ev: &Event, tap: &TapFinder, meta: &Option<TraceMeta>) -> bool {
        if let Some(k) = &mut self.keys {
            k.event(t, ev);
            return true;
        }
        self.waiting.push((t, ev.clone()));
        if tap.between_strokes() {
            if let Some(g) = tap.finish(axes(meta)) {
                self.start_keys(Some(g));
            }
        }
        self.waiting.len() <= MAX_WAITING
    }

    fn start_keys(&mut self, tap: Option<Tap>) {
        let mut k = KeyTracker::new(tap);
        for (t, e) in std::mem::take(&mut self.waiting) {
            k.event(t, &e);
        }
        self.guess = Some(tap);
        self.keys = Some(k);
    }

    /// The key points and the plan's spans (its order), as the second pass reads them for the
    /// run's tap `tap` and `plan`; `None` when they cannot be given.
    pub(super) fn finish(mut self, tap: Option<Tap>, plan: &Plan) -> Option<(KeyPoints, Vec<Span>)> {
        if !plan.lead.is_empty() {
            return None;
        }
        if self.keys.is_none() {
            self.start_keys(tap);
        }
        let same = |a: &Option<Tap>, b: &Option<Tap>| match (a, b) {
            (None, None) => true,
            (Some(a), Some(b)) => (a.slot, a.into_sign, a.in_signal) == (b.slot, b.into_sign, b.in_signal),
            _ => false,
        };
        if !same(&self.guess?, &tap) {
            return None;
        }
        // Spans still open end with the run (after every sample: their end is never passed).
        for w in [1, 0] {
            if let Some(i) = self.open[w].take() {
                self.closed.push(i);
            }
        }
        let last = self.prev.map(|p| held(&p.1));
        if self.closed.len() != plan.spans.len() || self.out.len() != plan.spans.len() {
            return None;
        }
        for (&i, &(t0, t1)) in self.closed.iter().zip(&plan.spans) {
            let (a, b) = self.spans[i];
            if a != t0 || (b != t1 && b != i64::MAX) {
                return None;
            }
            for e in &mut self.out[i].ends {
                if e.is_none() {
                    *e = last;
                }
            }
        }
        // In the plan's order: mostly that of their openings already (kept in place: memory).
        let spans = if self.closed.iter().enumerate().all(|(k, &i)| k == i) {
            self.out
        } else {
            self.closed.iter().map(|&i| std::mem::take(&mut self.out[i])).collect()
        };
        Some((self.keys?.finish(), spans))
    }
}

#[cfg(test)]
mod tests {
    use crate::check::survey::{Skeleton, Source, Survey};
    use nc_engine::{Machine, RunOptions};

    /// The first pass's key points and spans against the second pass's (the oracle) for the same
    /// run: `None` when the first pass could not give them.
    fn fused_and_second(dialect: &str, text: &str) -> Option<bool> {
        let m = Machine::new(dialect).unwrap();
        let p = m.parse(text).unwrap();
        let run = |sink: &mut dyn nc_engine::trace::TraceSink| m.run(&p, &RunOptions::default(), sink);
        let mut sk = Skeleton::of(Source::Run(&run));
        let tap = sk.tap();
        let plan = sk.plan();
        let axes = sk.meta.as_ref().unwrap().axes.clone();
        let fused = sk.fused_survey(tap, &plan)?;
        let mut sv = Survey::new(tap, plan.spans.clone(), plan.lead.clone(), &axes);
        Source::Run(&run).replay(&mut sv);
        let (keys, spans, _) = sv.finish();
        assert_eq!(fused.0, keys, "{dialect}: key points");
        assert_eq!(format!("{:?}", fused.1), format!("{spans:?}"), "{dialect}: spans");
        Some(!spans.is_empty() && !keys.segments.is_empty())
    }

    /// Read in the first pass, the key points and the synchronised moves' spans are the second
    /// pass's: rigid holes (Fanuc), a LinuxCNC G33 thread and G33.1 tap, a GSK thread by phase.
    #[test]
    fn a_fused_survey_reads_as_the_second_pass() {
        let holes = crate::check::holes::program(5);
        let cases = [
            ("fanuc-mill", holes.as_str(), true),
            ("linuxcnc", "G18 G21 M3 S600\nG4 P0.5\nG0 X10 Z5\nG33 Z-20 K1.5\nG0 X12\nM2\n", false),
            ("linuxcnc", "G21 G90 G0 X0 Y0 Z5\nM3 S500\nG33.1 Z-10 K1.25\nG0 Z20\nM2\n", false),
            (
                "gsk-lathe",
                "G0 X40 Z5;\nM03 S500;\nG92.3 X36 Z-20 F4 J1 K2 D0.1 E1 Q0.5 A1;\nG0 X60;\nM30;\n",
                false,
            ),
        ];
        for (dialect, text, tapped) in cases {
            let r = fused_and_second(dialect, text);
            assert!(r.is_some(), "{dialect}: not read in the first pass");
            if tapped {
                assert_eq!(r, Some(true), "{dialect}: no stroke read");
            }
        }
    }

    /// Thread blocks found by their lead (KND G32 without phases) are left to the second pass.
    #[test]
    fn lead_blocks_are_left_to_the_second_pass() {
        let knd = "G00 X30 Z5;\nM03 S600;\nG32 Z-20 F2;\nG00 X40;\nZ5;\nG92 X28 Z-20 F2;\nX27;\nM30;\n";
        assert_eq!(fused_and_second("knd-lathe", knd), None);
    }

    /// A first stroke along another axis than the run's tap (one short hole in G18, along Y,
    /// then deep ones in G17, along Z): the guess is not the run's tap, and the second pass reads the key points.
    #[test]
    fn a_wrong_guess_is_left_to_the_second_pass() {
        let text = "G90 G00 X0 Y10 Z10\nG18\nM29 S2000\nG99 G84 X0 Y8 Z0 R9 F3000\nG80\nG17 G00 Z10\n\
                    M29 S2000\nG99 G84 X0 Y0 Z-20 R1 F3000\nX5\nX10\nG80\nM30\n";
        let m = Machine::new("fanuc-mill").unwrap();
        let p = m.parse(text).unwrap();
        let run = |sink: &mut dyn nc_engine::trace::TraceSink| m.run(&p, &RunOptions::default(), sink);
        let sk = Skeleton::of_lean(Source::Run(&run), true);
        assert_eq!(sk.tap().map(|t| t.slot), Some(2), "the run's tap is Z");
        assert_eq!(fused_and_second("fanuc-mill", text), None);
    }

    /// More events than are kept waiting before the first stroke (a 70 s dwell at 1 ms): left
    /// to the second pass, memory bounded.
    #[test]
    fn a_long_wait_for_the_first_stroke_is_left_to_the_second_pass() {
        let text = "G90 G00 X0 Y0 Z10\nG04 X70.\nM29 S2000\nG99 G84 X0 Y0 Z-5 R1 F3000\nG80\nM30\n";
        assert_eq!(fused_and_second("fanuc-mill", text), None);
        let short = "G90 G00 X0 Y0 Z10\nG04 X2.\nM29 S2000\nG99 G84 X0 Y0 Z-5 R1 F3000\nG80\nM30\n";
        assert_eq!(fused_and_second("fanuc-mill", short), Some(true));
    }
}
