//! Deeply nested o-word blocks end in a located interpreter error, never a stack overflow
//! (issue 15; found by the `nesting` fuzz target: 5 000 nested `o<n> if [1]` blocks, every line
//! under LinuxCNC's 252 characters, aborted the whole process).

use nc_engine::{Machine, RunOptions};

fn nested(kind: &str, depth: usize) -> String {
    let (open, close) = match kind {
        "if" => ("if [1]", "endif"),
        _ => ("repeat [1]", "endrepeat"),
    };
    let mut text = String::from("G21 G90\n");
    for n in 1..=depth {
        text.push_str(&format!("o{n} {open}\n"));
    }
    text.push_str("G0 X1\n");
    for n in (1..=depth).rev() {
        text.push_str(&format!("o{n} {close}\n"));
    }
    text.push_str("M2\n");
    text
}

fn first_alarm(text: &str) -> Option<(u32, String)> {
    let m = Machine::new("linuxcnc").unwrap();
    let p = m.parse(text).expect("parses");
    let t = m.run_to_trace(&p, &RunOptions::default());
    let first = t.alarms().next().map(|(_, a)| (a.line.unwrap_or(0), a.message()));
    first
}

#[test]
fn five_thousand_nested_blocks_are_refused_at_a_line() {
    for kind in ["if", "repeat"] {
        let (line, message) = first_alarm(&nested(kind, 5_000)).expect("an alarm, not a crash");
        assert!(message.contains("Too many nested o-word blocks"), "{kind}: {message}");
        // Line 1 is G21 G90; the 201st block opens on line 202.
        assert_eq!(line, 202, "{kind}: {message}");
    }
}

#[test]
fn nesting_up_to_the_limit_runs() {
    for kind in ["if", "repeat"] {
        assert_eq!(first_alarm(&nested(kind, 150)), None, "{kind}");
    }
}
