//! Issue 14 §4: `check` streams. The reference run is replayed (the engine again, through its
//! public API) and its samples held only in a window around the recorded time, so the verdict
//! of a long recording is the one a whole reference in memory gives, and the window does not
//! grow with the length.

use nc_conform::check::{self, CheckSpec, Report, Source};
use nc_engine::trace::{Event, Signal, Trace, TraceSink};
use nc_engine::{Machine, RunOptions};

/// `n` rigid holes on a fanuc mill (M29, G84), 5 mm apart.
fn holes(n: usize) -> String {
    let mut p = String::from("G90 G00 X0 Y0 Z10\nM29 S2000\nG99 G84 X0 Y0 Z-5 R1 F3000\n");
    for i in 1..n {
        p.push_str(&format!("X{} Y{}\n", (i % 100) * 5, (i / 100) * 5));
    }
    p.push_str("G80\nM30\n");
    p
}

/// The reference of `n` holes, and a recording of it whose Z stands 0.2 mm high from the
/// second stroke's start to the third's (a defect in hole 1).
fn reference_and_recording(n: usize) -> (Machine, nc_engine::parse::Program, Trace, Trace) {
    let m = Machine::new("fanuc-mill").unwrap();
    let p = m.parse(&holes(n)).unwrap();
    let t = m.run_to_trace(&p, &RunOptions::default());
    let rises: Vec<u64> = t.edges(Signal::Rgspp).filter(|e| e.1).map(|e| e.0).collect();
    let (a, b) = (rises[1], rises[2]);
    let z = t.meta.axes.iter().find(|x| x.letter == 'Z').unwrap().index;
    let mut rec = t.clone();
    for e in &mut rec.events {
        if let Event::Sample(s) = &mut e.event {
            if e.t_us >= a && e.t_us < b {
                s.axes[z] += 200_000;
            }
        }
    }
    (m, p, t, rec)
}

fn streamed(m: &Machine, p: &nc_engine::parse::Program, rec: &Trace) -> Report {
    let run = |sink: &mut dyn TraceSink| m.run(p, &RunOptions::default(), sink);
    check::check_source(Source::Run(&run), rec.events.iter().cloned(), &CheckSpec::default())
}

fn same(a: &Report, b: &Report, what: &str) {
    assert_eq!(a.divergences, b.divergences, "{what}: divergences");
    assert_eq!(a.omitted, b.omitted, "{what}");
    assert_eq!(a.anchor, b.anchor, "{what}");
    assert_eq!(a.offset_us, b.offset_us, "{what}");
    assert_eq!(a.not_comparable, b.not_comparable, "{what}");
    assert_eq!(a.figures, b.figures, "{what}: figures");
}

/// The comparison with the reference's whole index (a first pass that keeps its events, moves,
/// phases and key points: DEC-162's oracle).
fn whole(m: &Machine, p: &nc_engine::parse::Program, rec: &Trace) -> Report {
    let run = |sink: &mut dyn TraceSink| m.run(p, &RunOptions::default(), sink);
    let source = Source::Run(&run);
    let skeleton = check::survey::Skeleton::of_lean(source, false);
    check::check_surveyed(source, skeleton, rec.events.iter().cloned(), &CheckSpec::default())
}

#[test]
fn the_engine_replayed_alongside_gives_the_verdict_of_the_reference_in_memory() {
    let (m, p, t, rec) = reference_and_recording(12);
    let in_memory = check::check(&t, rec.events.iter().cloned(), &CheckSpec::default());
    let streamed = streamed(&m, &p, &rec);
    assert!(!in_memory.conformant(), "the defect is found");
    assert!(in_memory.divergences.iter().any(|d| d.check == "CHK-ENV-01"), "{:?}", in_memory.divergences);
    same(&in_memory, &streamed, "12 holes");
    // The defect's envelope run began before the moves and phases the comparison holds when it
    // ends: attributed at the end, as the whole index attributes it.
    same(&whole(&m, &p, &rec), &streamed, "12 holes, the whole index");
    // The good recording passes both ways.
    let good = check::check(&t, t.events.iter().cloned(), &CheckSpec::default());
    assert!(good.conformant(), "{:?}", good.divergences);
    same(&good, &streamed_good(&m, &p, &t), "12 holes, good");
}

fn streamed_good(m: &Machine, p: &nc_engine::parse::Program, t: &Trace) -> Report {
    streamed(m, p, t)
}

#[test]
fn a_long_recording_finds_what_a_short_one_finds_in_a_window_that_does_not_grow() {
    let (m, p, _, short) = reference_and_recording(10);
    let short_rep = streamed(&m, &p, &short);
    let (m2, p2, t2, long) = reference_and_recording(400);
    let long_rep = streamed(&m2, &p2, &long);
    assert!(long.events.len() > 30 * short.events.len() / 2, "a long recording");
    // The same defect in hole 1, the same divergences (the holes after it conform).
    assert_eq!(short_rep.divergences, long_rep.divergences);
    assert!(!long_rep.conformant());
    assert_eq!(long_rep.figures.pecks, (400, 400));
    // The reference's samples held at once do not follow the length.
    assert!(long_rep.reference_samples_held > 0);
    // (dropped in blocks of at least 4096 once they are half of it; pulled in batches of 2048)
    for r in [&short_rep, &long_rep] {
        assert!(r.reference_samples_held <= 2 * 4096 + 2048, "held {}", r.reference_samples_held);
    }
    // Nor do its other records (edges and functions waiting to be matched, synchronised moves,
    // phases, key points waiting for their pair): 400 holes are 2,400 edges, 800 strokes.
    assert!(long_rep.reference_records_held > 0);
    assert!(
        long_rep.reference_records_held <= short_rep.reference_records_held + 8,
        "held {} for 400 holes, {} for 10",
        long_rep.reference_records_held,
        short_rep.reference_records_held
    );
    assert!(long_rep.reference_records_held < 100, "held {}", long_rep.reference_records_held);
    let samples = t2.samples().count();
    assert!(
        long_rep.reference_samples_held * 10 < samples,
        "{} of {samples}",
        long_rep.reference_samples_held
    );
    // The compact copy and the plot are bounded.
    assert!(long_rep.recorded.events.len() <= 2 * check::compare::MAX_COMPACT_EVENTS + 1);
    assert!(long_rep.series.len() <= 2 * 1600, "{}", long_rep.series.len());
}
