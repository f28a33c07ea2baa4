//! The VCD writer against a real reader (the `vcd` crate): what a waveform viewer reads back is
//! exactly the trace's signal edges, phases and positions. Also checks the text views of real
//! runs are well formed.

use std::collections::BTreeMap;

use nc_conform::render::events::event_listing;
use nc_conform::render::timing::{timing_diagram, DiagramSpec};
use nc_conform::render::vcd::{phase_code, signal_var_name, write_vcd};
use nc_engine::trace::{Event, Signal, Trace};
use nc_engine::units::fixed_string;
use nc_engine::{Machine, RunOptions};
use rstest::rstest;
use vcd::{Command, IdCode, SimulationCommand, TimescaleUnit, Value};

const GSK_PECK: &str = "G98;\nG0 X50 Z0;\nM29 S1000;\nG88 X-50 P3000 Q20000 R0.5 F2;\nG80;\nM30;\n";
const FANUC_G84: &str = "G90 G0 X0 Y0 Z50\nM29 S100\nG84 Z-40 R5 Q5 F100\nG80\nM30\n";

fn run(dialect: &str, text: &str) -> Trace {
    let m = Machine::new(dialect).expect("dialect");
    let prog = m.parse(text).expect("parse");
    m.run_to_trace(&prog, &RunOptions::default())
}

/// A value read back.
#[derive(Debug, Clone, PartialEq)]
enum Val {
    Bit(bool),
    Real(f64),
    Int(u64),
}

/// The VCD of `trace` read back: header, and per identifier code its changes after `$dumpvars`
/// (time, value), plus the `$dumpvars` values and the last timestamp.
struct ReadBack {
    header: vcd::Header,
    initial: BTreeMap<IdCode, Val>,
    changes: BTreeMap<IdCode, Vec<(u64, Val)>>,
    last_t: u64,
}

impl ReadBack {
    fn code(&self, scope: &str, name: &str) -> IdCode {
        self.header.find_var(&[scope, name]).unwrap_or_else(|| panic!("no {scope}.{name}")).code
    }

    fn changes(&self, scope: &str, name: &str) -> &[(u64, Val)] {
        self.changes.get(&self.code(scope, name)).map_or(&[], Vec::as_slice)
    }

    /// The value at the end: the last change, or the initial value.
    fn last(&self, scope: &str, name: &str) -> Val {
        let code = self.code(scope, name);
        self.changes(scope, name).last().map(|c| c.1.clone()).unwrap_or_else(|| self.initial[&code].clone())
    }
}

fn read_back(trace: &Trace) -> ReadBack {
    let mut bytes = Vec::new();
    write_vcd(trace, &mut bytes).unwrap();
    let mut parser = vcd::Parser::new(&bytes[..]);
    let header = parser.parse_header().unwrap();
    let mut rb = ReadBack { header, initial: BTreeMap::new(), changes: BTreeMap::new(), last_t: 0 };
    let mut in_dumpvars = false;
    let mut t = None;
    for cmd in parser {
        let (code, v) = match cmd.unwrap() {
            Command::Timestamp(now) => {
                assert!(t.is_none_or(|t| now > t), "timestamps must increase: {t:?} then {now}");
                t = Some(now);
                continue;
            }
            Command::Begin(SimulationCommand::Dumpvars) => {
                in_dumpvars = true;
                continue;
            }
            Command::End(SimulationCommand::Dumpvars) => {
                in_dumpvars = false;
                continue;
            }
            Command::ChangeScalar(code, v) => (code, Val::Bit(v == Value::V1)),
            Command::ChangeReal(code, v) => (code, Val::Real(v)),
            Command::ChangeVector(code, v) => {
                let n = v.iter().fold(0u64, |n, b| n * 2 + u64::from(b == Value::V1));
                (code, Val::Int(n))
            }
            other => panic!("unexpected {other:?}"),
        };
        let now = t.expect("a change before the first timestamp");
        if in_dumpvars {
            assert_eq!(now, 0);
            assert!(rb.initial.insert(code, v).is_none());
        } else {
            rb.changes.entry(code).or_default().push((now, v));
        }
    }
    rb.last_t = t.unwrap();
    rb
}

/// `v` as the exact decimal it was written from, in units of 10^-decimals.
fn exact(v: &Val, decimals: u32) -> i64 {
    let Val::Real(f) = v else { panic!("not a real: {v:?}") };
    let units = (f * 10f64.powi(decimals as i32)).round() as i64;
    assert_eq!(fixed_string(units, decimals).parse::<f64>().unwrap(), *f);
    units
}

#[rstest]
#[case::gsk_peck("gsk-lathe", GSK_PECK)]
#[case::fanuc_g84("fanuc-mill", FANUC_G84)]
fn vcd_reads_back_as_the_trace(#[case] dialect: &str, #[case] program: &str) {
    let trace = run(dialect, program);
    let edges_seen = assert_reads_back(&trace);
    assert!(edges_seen > 10, "the program should toggle signals: {edges_seen}");
}

/// Every scenario of the library: the VCD of its trace reads back with the same edges, phases and
/// positions (so every VCD `nc-conform run SCENARIO --format vcd` writes is checked).
#[test]
fn every_scenario_vcd_reads_back() {
    fn files(dir: &std::path::Path, out: &mut Vec<std::path::PathBuf>) {
        for e in std::fs::read_dir(dir).into_iter().flatten() {
            let p = e.unwrap().path();
            if p.is_dir() {
                files(&p, out);
            } else if p.extension().is_some_and(|e| e == "yaml") {
                out.push(p);
            }
        }
    }
    let mut all = Vec::new();
    files(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios"), &mut all);
    assert!(!all.is_empty());
    for p in all {
        let name = p.display().to_string();
        let s =
            nc_conform::scenario::load::load(&p, &name).unwrap_or_else(|e| panic!("{}", e.render_plain()));
        let outcome = nc_conform::scenario::run::run(&s);
        assert_reads_back(&outcome.trace);
    }
}

/// Writes the trace as VCD, reads it back and compares; returns the number of signal edges.
fn assert_reads_back(trace: &Trace) -> usize {
    let end = trace.end().expect("end").clone();
    let rb = read_back(trace);
    assert_eq!(rb.header.version.as_deref(), Some("nc-conform"));
    assert_eq!(rb.header.timescale, Some((1, TimescaleUnit::US)));
    assert_eq!(rb.last_t, trace.events.last().unwrap().t_us);

    let mut edges_seen = 0;
    for sig in Signal::ALL {
        let name = signal_var_name(sig);
        assert_eq!(rb.initial[&rb.code("signals", &name)], Val::Bit(false), "{name}");
        // The trace's edges, dropping any that restate the level (the engine writes none).
        let mut level = false;
        let want: Vec<(u64, Val)> = trace
            .edges(sig)
            .filter(|&(_, v)| std::mem::replace(&mut level, v) != v)
            .map(|(t, v)| (t, Val::Bit(v)))
            .collect();
        assert_eq!(rb.changes("signals", &name), want.as_slice(), "{name}");
        assert_eq!(rb.last("signals", &name), Val::Bit(end.signals.get(sig)), "{name}");
        edges_seen += want.len();
    }

    // Phases, as numbers.
    let mut phase = 0;
    let want: Vec<(u64, Val)> = trace
        .phases()
        .filter(|&(_, p)| std::mem::replace(&mut phase, phase_code(p)) != phase_code(p))
        .map(|(t, p)| (t, Val::Int(u64::from(phase_code(p)))))
        .collect();
    assert_eq!(rb.changes("cycle", "phase"), want.as_slice());

    // Every axis: the sampled values (and the end state) with repeats dropped; the last is the
    // end state exactly.
    for a in &trace.meta.axes {
        let name = a.letter.to_string();
        let mut values: Vec<(u64, i64)> = Vec::new();
        for e in &trace.events {
            let v = match &e.event {
                Event::Sample(s) => s.axes[a.index],
                Event::End(end) => end.state.axes[a.index],
                _ => continue,
            };
            if values.last().is_none_or(|l| l.1 != v) {
                values.push((e.t_us, v));
            }
        }
        let initial = exact(&rb.initial[&rb.code("axes", &name)], 6);
        let got: Vec<(u64, i64)> = std::iter::once((0, initial))
            .chain(rb.changes("axes", &name).iter().map(|(t, v)| (*t, exact(v, 6))))
            .collect();
        assert_eq!(got, values, "{name}");
        assert_eq!(exact(&rb.last("axes", &name), 6), end.state.axes[a.index], "{name}");
    }
    assert_eq!(exact(&rb.last("spindle", "rpm"), 3), end.state.spindle_mrpm);
    assert_eq!(exact(&rb.last("spindle", "angle_deg"), 3), end.state.spindle_mdeg);
    assert_eq!(rb.last("cycle", "alarms"), Val::Int(u64::from(end.alarms)));
    edges_seen
}

#[rstest]
#[case::gsk_peck("gsk-lathe", GSK_PECK)]
#[case::fanuc_g84("fanuc-mill", FANUC_G84)]
fn views_of_real_runs_are_well_formed(#[case] dialect: &str, #[case] program: &str) {
    let trace = run(dialect, program);
    let listing = event_listing(&trace);
    assert!(listing.lines().all(|l| l.ends_with(" |")));
    assert!(listing.lines().last().unwrap().contains(" end program_end "), "{listing}");
    for width in [10, 100, 200] {
        let spec = DiagramSpec { width, ..DiagramSpec::for_trace(&trace) };
        let text = timing_diagram(&trace, &spec);
        let widths: Vec<usize> = text.lines().map(|l| l.chars().count()).collect();
        assert!(widths.iter().all(|w| *w == widths[0]), "{text}");
        assert!(text.lines().all(|l| l.ends_with('|')), "{text}");
    }
    let mut a = Vec::new();
    let mut b = Vec::new();
    write_vcd(&trace, &mut a).unwrap();
    write_vcd(&trace, &mut b).unwrap();
    assert_eq!(a, b);
}
