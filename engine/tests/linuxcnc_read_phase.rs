//! LinuxCNC's read-ahead and an error of its read phase (LCNC-LEX-05, DEC-150): run through the
//! adapter (issue 16), LinuxCNC reported "K word missing with g33/g33.1", G76's missing words and
//! the file's end without M2 16–17 ms into the run, when its task read ahead to the line, and
//! still ran the lines before it (a read error stops the reading without clearing the queue),
//! except a last straight feed its canonical layer still held back for blending.

use nc_engine::trace::{EndReason, Event, Trace};
use nc_engine::{Machine, RunOptions};

fn run(program: &str) -> Trace {
    let m = Machine::new("linuxcnc").unwrap();
    m.run_to_trace(&m.parse(program).unwrap(), &RunOptions::default())
}

fn alarms(t: &Trace) -> Vec<(u64, String, Option<u32>)> {
    t.alarms().map(|(at, a)| (at, a.kind.code().to_string(), a.line)).collect()
}

fn blocks(t: &Trace) -> Vec<u32> {
    t.events
        .iter()
        .filter_map(|e| match &e.event {
            Event::Block { line, .. } => Some(*line),
            _ => None,
        })
        .collect()
}

fn end_z(t: &Trace) -> f64 {
    t.end().unwrap().state.axes[2] as f64 / 1e6
}

#[test]
fn a_word_missing_is_reported_at_once_and_the_lines_before_run() {
    let t = run("G21 M3 S500\nG0 X0 Z5\nG33.1 Z-10\nM2\n");
    assert_eq!(alarms(&t), vec![(0, "NC-1096".to_string(), Some(3))]);
    let end = t.end().unwrap();
    assert_eq!(end.reason, EndReason::Alarm);
    assert_eq!(end_z(&t), 5.0, "the G0 before the bad line ran");
    assert!(end.state.spindle_mrpm > 0, "the spindle still turns");
    // The bad line itself never starts.
    assert_eq!(blocks(&t), vec![1, 2]);
    assert_eq!(end.alarms, 1);
}

#[test]
fn a_last_straight_feed_before_the_files_end_never_moves() {
    // The G1 is held back (nothing after it flushes it): Z stays.
    let t = run("G21 G90\nG0 X1 Y2\nG1 Z-1 F100\n");
    assert_eq!(alarms(&t), vec![(0, "NC-1090".to_string(), Some(3))]);
    assert_eq!(end_z(&t), 0.0);
    assert_eq!(t.end().unwrap().state.axes[0], 1_000_000);
    // Two feeds: the first is flushed by the second and runs, the last does not.
    let t = run("G21 G90\nG1 Z-1 F600\nG1 Z-2\n");
    assert_eq!(end_z(&t), -1.0);
    // A feed followed by a rapid runs, and so does the rapid.
    let t = run("G21 G90\nG1 Z-1 F600\nG0 Z3\n");
    assert_eq!(end_z(&t), 3.0);
    assert_eq!(t.end().unwrap().reason, EndReason::Alarm);
}

#[test]
fn an_error_beyond_a_program_stop_is_raised_where_the_program_reaches_it() {
    // M0 ends the read-ahead: the error is read, and raised, after the cycle start.
    let m = Machine::new("linuxcnc").unwrap();
    let opts = RunOptions { auto_cycle_start: true, ..RunOptions::default() };
    let t = m.run_to_trace(&m.parse("G21 M3 S500\nG0 Z5\nM0\nG33.1 Z-10\nM2\n").unwrap(), &opts);
    let a = alarms(&t);
    assert_eq!(a.len(), 1);
    assert!(a[0].0 > 0, "{a:?}");
    assert_eq!(blocks(&t), vec![1, 2, 3, 4]);
}
