//! The importers on real engine traces: JSON Lines and VCD written by the harness's own writers
//! read back to the same events (JSON Lines: every event; VCD: every signal edge and every
//! sample), a CSV export of a real run, and a generated multi-million-row CSV streamed without
//! collecting (memory stays flat: see `examples/import_rss.rs` for the peak RSS figure).

use std::io::Cursor;

use nc_conform::import::{from_reader, gen, ColumnMap, Format, Options};
use nc_conform::jsonl::JsonlWriter;
use nc_conform::render::vcd::write_vcd;
use nc_engine::trace::{Event, Signal, Trace, TraceEvent};
use nc_engine::{Machine, RunOptions};
use rstest::rstest;

const GSK_PECK: &str = "G98;\nG0 X50 Z0;\nM29 S1000;\nG88 X-50 P3000 Q20000 R0.5 F2;\nG80;\nM30;\n";
const FANUC_G84: &str = "G90 G0 X0 Y0 Z50\nM29 S100\nG84 Z-40 R5 Q5 F100\nG80\nM30\n";
const FANUC_BAD: &str = "G90 G0 X0 Y0 Z50\nM29 S100\nG0 X5\nG84 Z-40 R5 F100\nM30\n";

fn run(dialect: &str, text: &str) -> Trace {
    let m = Machine::new(dialect).expect("dialect");
    let prog = m.parse(text).expect("parse");
    m.run_to_trace(&prog, &RunOptions::default())
}

fn import_all(
    name: &str,
    bytes: Vec<u8>,
    format: Option<Format>,
    map: Option<&ColumnMap>,
) -> Vec<TraceEvent> {
    let opts = Options { format, map, lenient: false };
    let imp = from_reader(name, Box::new(Cursor::new(bytes)), &opts).expect("opens");
    imp.collect::<Result<Vec<_>, _>>().unwrap_or_else(|e| panic!("{e}"))
}

#[rstest]
#[case("gsk-lathe", GSK_PECK)]
#[case("fanuc-mill", FANUC_G84)]
#[case("fanuc-mill", FANUC_BAD)]
fn jsonl_round_trip_gives_the_same_events(#[case] dialect: &str, #[case] program: &str) {
    let trace = run(dialect, program);
    let mut sink = JsonlWriter::new(Vec::new());
    sink.write_meta(&trace.meta);
    for e in &trace.events {
        sink.write_event(e);
    }
    let bytes = sink.finish().expect("written");
    let opts = Options::default();
    let imp = from_reader("t.jsonl", Box::new(Cursor::new(bytes)), &opts).expect("opens");
    assert_eq!(imp.meta().format, Format::Jsonl);
    assert_eq!(imp.meta().trace.as_ref(), Some(&trace.meta));
    assert_eq!(imp.meta().first_t_us, trace.events.first().map(|e| e.t_us));
    let events: Vec<TraceEvent> = imp.collect::<Result<_, _>>().expect("imports");
    assert_eq!(events.len(), trace.events.len());
    for (a, b) in events.iter().zip(&trace.events) {
        assert_eq!(a, b);
    }
}

#[rstest]
#[case("gsk-lathe", GSK_PECK)]
#[case("fanuc-mill", FANUC_G84)]
#[case("fanuc-mill", FANUC_BAD)]
fn vcd_round_trip_gives_the_same_edges_and_samples(#[case] dialect: &str, #[case] program: &str) {
    let trace = run(dialect, program);
    let mut bytes = Vec::new();
    write_vcd(&trace, &mut bytes).expect("written");
    let events = import_all("t.vcd", bytes, None, None);
    let end_t = trace.events.last().map_or(0, |e| e.t_us);
    for s in Signal::ALL {
        let want: Vec<(u64, bool)> = trace.edges(s).collect();
        let got: Vec<(u64, bool)> = events
            .iter()
            .filter_map(|e| match e.event {
                Event::Signal { signal, value } if signal == s => Some((e.t_us, value)),
                _ => None,
            })
            .collect();
        // Edges to the level the signal already has (the engine may repeat one) are not in a VCD.
        let mut level = false;
        let want: Vec<(u64, bool)> = want
            .into_iter()
            .filter(|&(_, v)| {
                let keep = v != level;
                level = v;
                keep
            })
            .collect();
        assert_eq!(got, want, "edges of {}", s.name());
    }
    // Samples before the end (a sample at the end's own time shares its timestamp with the end
    // state, which a VCD cannot tell apart).
    let want: Vec<_> = trace.samples().filter(|(t, _)| *t < end_t).map(|(t, s)| (t, *s)).collect();
    let got: Vec<_> = events
        .iter()
        .filter_map(|e| match &e.event {
            Event::Sample(s) if e.t_us < end_t => Some((e.t_us, *s)),
            _ => None,
        })
        .collect();
    assert_eq!(got.len(), want.len());
    assert_eq!(got, want);
    // Phases too.
    let want: Vec<_> = trace.phases().collect();
    let got: Vec<_> = events
        .iter()
        .filter_map(|e| if let Event::Phase(p) = e.event { Some((e.t_us, p)) } else { None })
        .collect();
    let mut last = nc_engine::trace::Phase::Idle;
    let want: Vec<_> = want
        .into_iter()
        .filter(|&(_, p)| {
            let keep = p != last;
            last = p;
            keep
        })
        .collect();
    assert_eq!(got, want);
}

/// A CSV export of a real run (samples as rows, signals as 0/1 columns) reads back to the run's
/// samples, and to its edges at sample resolution.
#[test]
fn csv_export_of_a_run_reads_back() {
    let trace = run("gsk-lathe", GSK_PECK);
    let mut csv = String::from("Time [s];X pos;Z pos;Speed;RTAP;RGTAP\n");
    let mut levels = [false; 2];
    for e in &trace.events {
        match &e.event {
            Event::Signal { signal: Signal::Rtap, value } => levels[0] = *value,
            Event::Signal { signal: Signal::Rgtap, value } => levels[1] = *value,
            Event::Sample(s) => csv.push_str(&format!(
                "{};{};{};{};{};{}\n",
                e.t_us as f64 / 1e6,
                s.axes[0] as f64 / 1e6,
                s.axes[2] as f64 / 1e6,
                s.spindle_mrpm as f64 / 1e3,
                u8::from(levels[0]),
                u8::from(levels[1])
            )),
            _ => {}
        }
    }
    let map = ColumnMap::from_yaml(
        "m.yaml",
        "delimiter: \";\"\ntime: {column: \"Time [s]\", unit: s}\naxes:\n  - {axis: X, column: X pos, diameter: true}\n  - {axis: Z, column: Z pos}\nspindle: {rpm: {column: Speed}}\nsignals:\n  - {signal: F76.3, column: RTAP}\n  - {signal: RGTAP, column: RGTAP}\n",
    )
    .expect("map");
    let events = import_all("run.csv", csv.into_bytes(), None, Some(&map));
    let got: Vec<_> = events
        .iter()
        .filter_map(|e| {
            if let Event::Sample(s) = &e.event {
                Some((e.t_us, s.axes, s.spindle_mrpm))
            } else {
                None
            }
        })
        .collect();
    let want: Vec<_> = trace.samples().map(|(t, s)| (t, s.axes, s.spindle_mrpm)).collect();
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(&want) {
        assert_eq!(g.0, w.0);
        assert_eq!(g.1[0], w.1[0]);
        assert_eq!(g.1[2], w.1[2]);
        assert_eq!(g.2, w.2);
    }
    let rtap =
        events.iter().filter(|e| matches!(e.event, Event::Signal { signal: Signal::Rtap, .. })).count();
    assert_eq!(rtap, trace.edges(Signal::Rtap).count());
}

#[test]
fn a_multi_million_row_csv_streams() {
    let rows = 2_000_000;
    let map = ColumnMap::from_yaml("gen.yaml", gen::MAP).expect("map");
    let opts = Options { format: None, map: Some(&map), lenient: false };
    let imp = from_reader("gen.csv", Box::new(gen::GenCsv::new(rows)), &opts).expect("opens");
    let (mut samples, mut edges, mut last) = (0u64, 0u64, 0u64);
    for ev in imp {
        let ev = ev.expect("a good row");
        assert!(ev.t_us >= last);
        last = ev.t_us;
        match ev.event {
            Event::Sample(_) => samples += 1,
            Event::Signal { .. } => edges += 1,
            _ => unreachable!(),
        }
    }
    assert_eq!(samples, rows);
    assert_eq!(last, (rows - 1) * 1000);
    // flags = (r % 1000 / 50) % 16: bit 0 changes every 50 rows (from row 50 on), bit 3 twice
    // per 1000 rows (rows 400 and 800).
    assert_eq!(edges, (rows / 50 - 1) + rows / 1000 * 2);
}
