//! LinuxCNC's single block is its step (LCNC-INP-01, DEC-160): the task ends a step when it takes
//! up a command of another line, and only the moves carry their line (emctaskmain.cc
//! `STEPPING_CHECK`, emccanon.cc `interp_list.set_line_number`): a line that moves nothing, a
//! dwell too, runs in the step of the line before it. Other dialects stop after every block.

use nc_engine::input::{Input, InputSchedule};
use nc_engine::trace::{EndReason, Event, Signal, Trace};
use nc_engine::{Machine, RunOptions};

/// Runs `program` under single block with a cycle start every 2 s (more than the program needs).
fn stepped(dialect: &str, program: &str) -> Trace {
    let mut inputs = InputSchedule::default().at(0, Input::SingleBlock(true));
    for k in 1..=8 {
        inputs = inputs.at(k * 2_000_000, Input::CycleStart);
    }
    let m = Machine::new(dialect).unwrap();
    let opts = RunOptions { inputs, auto_cycle_start: false, ..RunOptions::default() };
    m.run_to_trace(&m.parse(program).unwrap(), &opts)
}

/// The time each block was shown.
fn block_times(t: &Trace) -> Vec<(u32, u64)> {
    t.events
        .iter()
        .filter_map(|e| match &e.event {
            Event::Block { line, .. } => Some((*line, e.t_us)),
            _ => None,
        })
        .collect()
}

#[test]
fn lcnc_inp_01_a_dwell_and_a_coolant_line_run_in_the_step_of_the_move_before_them() {
    // Line 1 is a step of its own; line 2 moves; lines 3 and 4 move nothing (DWELL takes the
    // line of the move before it); line 5 moves; M2 ends the program in line 5's step.
    let program = "G21 M3 S500\nG0 X10\nG4 P0.5\nM8\nG0 X20\nM2\n";
    let t = stepped("linuxcnc", program);
    assert_eq!(t.end().unwrap().reason, EndReason::ProgramEnd);
    assert_eq!(t.edges(Signal::Spl).filter(|e| e.1).count(), 2, "stops before lines 2 and 5");
    let b = block_times(&t);
    let at = |line: u32| b.iter().find(|(l, _)| *l == line).unwrap().1;
    assert_eq!(at(2), 2_000_000);
    assert_eq!(at(5), 4_000_000);
    assert!(at(3) < at(5) && at(4) < 4_000_000, "{b:?}");
    assert!(t.events.last().unwrap().t_us < 6_000_000, "no stop before M2");
}

#[test]
fn com_inp_03_other_dialects_still_stop_after_every_block() {
    let program = "G21 M3 S500\nG0 X10\nG4 X0.5\nM8\nG0 X20\nM30\n";
    let t = stepped("fanuc-mill", program);
    assert_eq!(t.end().unwrap().reason, EndReason::ProgramEnd);
    assert_eq!(t.edges(Signal::Spl).filter(|e| e.1).count(), 5);
}
