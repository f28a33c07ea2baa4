//! Reading the oracle: `rs274`'s canonical output (`canon/NAME.canon`) and the engine's plan for the
//! same program, both reduced to the same thing: the end point of every move, in mm, and the
//! refusal (line and text) if the program was refused.

use nc_engine::plan::{expand_all, FollowKind, Step};
use nc_engine::{Event, Machine, RunOptions};

/// What kind of move: `T` STRAIGHT_TRAVERSE, `F` STRAIGHT_FEED, `A` ARC_FEED, `R` RIGID_TAP.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Move {
    /// `T`, `F`, `A` or `R`.
    pub kind: char,
    /// End point X, Y, Z in mm (for `R`: the bottom of the tap).
    pub p: [f64; 3],
    /// The program line whose block planned it (engine side only).
    pub line: Option<u32>,
    /// How far apart two printed values may be, mm (half the last printed digit, plus slack).
    pub tol: f64,
}

/// A refusal: the line (its text, as rs274 prints it, or its number) and the message.
#[derive(Debug, Clone, PartialEq)]
pub struct Refusal {
    /// 1-based line of the program (engine), or 0 when only the text is known.
    pub line: u32,
    /// The line's text, trimmed.
    pub text: String,
    /// The error message.
    pub message: String,
}

/// The moves and the refusal of one run.
#[derive(Debug, Clone, Default)]
pub struct Outcome {
    /// Moves, zero-length ones left out.
    pub moves: Vec<Move>,
    /// The refusal, if the program was refused.
    pub refusal: Option<Refusal>,
}

/// Appends a move unless it goes nowhere from `cur`; `cur` becomes `after`.
fn push(out: &mut Vec<Move>, cur: &mut [f64; 3], m: Move, after: [f64; 3]) {
    let nowhere = m.p.iter().zip(cur.iter()).all(|(a, b)| (a - b).abs() <= m.tol);
    if !nowhere {
        out.push(m);
    }
    *cur = after;
}

/// Reads rs274's output: `   SEQ N..... COMMAND(ARGS)` lines, anything else is printed text
/// (PRINT, the error and the refused line).
pub fn parse_canon(text: &str) -> Outcome {
    let mut o = Outcome::default();
    let mut unit = 1.0; // mm per program unit
    let mut plane = "XY";
    let mut offset = [0.0; 3]; // G92 + G5x, mm
    let (mut g92, mut g5x) = ([0.0; 3], [0.0; 3]);
    let mut cur = [0.0; 3];
    // Printed text after the last command that is not ON_RESET.
    let mut tail: Vec<String> = Vec::new();
    for line in text.lines() {
        let Some((name, args)) = command(line) else {
            if line != "executing" {
                tail.push(line.to_string());
            }
            continue;
        };
        if name != "ON_RESET" {
            tail.clear();
        }
        let nums: Vec<f64> = args.split(',').filter_map(|a| a.trim().parse::<f64>().ok()).collect();
        let xyz = |v: &[f64], unit: f64| [v[0] * unit, v[1] * unit, v[2] * unit];
        match name {
            "USE_LENGTH_UNITS" => unit = if args.contains("INCHES") { 25.4 } else { 1.0 },
            "SELECT_PLANE" => {
                plane = if args.contains("XZ") {
                    "XZ"
                } else if args.contains("YZ") {
                    "YZ"
                } else {
                    "XY"
                }
            }
            "SET_G92_OFFSET" if nums.len() >= 3 => g92 = xyz(&nums, unit),
            "SET_G5X_OFFSET" if nums.len() >= 4 => g5x = xyz(&nums[1..], unit),
            "STRAIGHT_TRAVERSE" | "STRAIGHT_FEED" | "ARC_FEED" | "RIGID_TAP" => {
                offset = [g92[0] + g5x[0], g92[1] + g5x[1], g92[2] + g5x[2]];
                let p = match name {
                    // ARC_FEED(first_end, second_end, first_centre, second_centre, turn, axis_end, ...)
                    "ARC_FEED" => match plane {
                        "XZ" => [nums[1], nums[5], nums[0]],
                        "YZ" => [nums[5], nums[0], nums[1]],
                        _ => [nums[0], nums[1], nums[5]],
                    },
                    _ => [nums[0], nums[1], nums[2]],
                };
                let p = [0, 1, 2].map(|a| p[a] * unit + offset[a]);
                let kind = match name {
                    "STRAIGHT_TRAVERSE" => 'T',
                    "STRAIGHT_FEED" => 'F',
                    "ARC_FEED" => 'A',
                    _ => 'R',
                };
                let m = Move { kind, p, line: None, tol: 0.6e-4 * unit + 1e-5 };
                let after = if kind == 'R' { cur } else { p };
                push(&mut o.moves, &mut cur, m, after);
            }
            _ => {}
        }
    }
    let _ = offset;
    if tail.len() >= 2 {
        o.refusal = Some(Refusal {
            line: 0,
            text: tail[tail.len() - 1].trim().to_string(),
            message: tail[tail.len() - 2].clone(),
        });
    } else if let Some(m) = tail.last() {
        o.refusal = Some(Refusal { line: 0, text: String::new(), message: m.clone() });
    }
    o
}

/// `   12 N..... NAME(ARGS)` or `   12 N10    NAME(ARGS)` → (NAME, ARGS).
fn command(line: &str) -> Option<(&str, &str)> {
    let rest = line.trim_start();
    let digits = rest.find(|c: char| !c.is_ascii_digit())?;
    if digits == 0 {
        return None;
    }
    // `N.....`, or the line's own N number padded (`N10   `).
    let rest = rest[digits..].strip_prefix(" N")?;
    let rest = rest.trim_start_matches(|c: char| c.is_ascii_digit() || c == '.' || c == ' ');
    let open = rest.find('(')?;
    let args = rest[open + 1..].strip_suffix(')')?;
    Some((&rest[..open], args))
}

/// Runs `text` on the `linuxcnc` dialect: the moves its interpreter plans, block by block (each
/// with its block's line), up to the block where the run stopped, and the alarm that stopped it
/// (the interpreter's, or the executor's in a whole run of the program).
pub fn run_engine(text: &str) -> Result<Outcome, String> {
    let m = Machine::new("linuxcnc").ok_or("no linuxcnc dialect")?;
    let program = m.parse(text).map_err(|e| format!("{}:{}: {}", e.line, e.col, e.message))?;
    let source: Vec<&str> = text.lines().collect();
    let line_text = |l: u32| source.get(l as usize - 1).map(|s| s.trim().to_string()).unwrap_or_default();
    // The whole run, for alarms raised while executing (spindle, feed) and for the block reached.
    let opts = RunOptions { sample_us: 0, time_limit_us: 24 * 3600 * 1_000_000, ..RunOptions::default() };
    let trace = m.run_to_trace(&program, &opts);
    let mut last_block = None;
    let mut alarm = None;
    for e in &trace.events {
        match &e.event {
            Event::Block { line, text } => last_block = Some((*line, text.clone())),
            Event::Alarm(a) => {
                alarm = Some((a.clone(), last_block));
                break;
            }
            _ => {}
        }
    }
    let mut o = Outcome::default();
    let mut interp = m.dialect.interpreter(&m.params);
    interp.program(&program);
    // An error of reading a line found by the read-ahead is reported by the first block and the
    // run goes on (DEC-150): the interpreter still plans every block up to the bad one.
    let mut probe = m.dialect.interpreter(&m.params);
    probe.program(&program);
    let mut first = Vec::new();
    let reported = program.blocks.first().is_some_and(|b| {
        probe.block(b, &mut first).is_ok() && first.iter().any(|s| matches!(s, Step::Report(_)))
    });
    if let (true, Some((_, at))) = (reported, &mut alarm) {
        *at = None;
    }
    let mut cur = [0.0; 3];
    let nm = |v: i64| v as f64 / 1e6;
    for b in &program.blocks {
        if let Some((_, Some((line, text)))) = &alarm {
            if b.line == *line && b.text == *text {
                break;
            }
        }
        let mut steps = Vec::new();
        if let Err(a) = interp.block(b, &mut steps) {
            if alarm.is_none() {
                alarm = Some((a, Some((b.line, b.text.clone()))));
            }
            break;
        }
        let ended = steps.contains(&Step::End);
        for s in expand_all(steps) {
            let line = Some(b.line);
            let mv = |kind, t: [i64; 6]| Move { kind, p: [nm(t[0]), nm(t[1]), nm(t[2])], line, tol: 1e-5 };
            match s {
                Step::Rapid { target } => {
                    let m = mv('T', target);
                    push(&mut o.moves, &mut cur, m, m.p)
                }
                Step::Feed { target, .. } => {
                    let m = mv('F', target);
                    push(&mut o.moves, &mut cur, m, m.p)
                }
                Step::Arc { target, .. } => {
                    let m = mv('A', target);
                    push(&mut o.moves, &mut cur, m, m.p)
                }
                // A synchronised pass (G33, each G76 pass): rs274's STRAIGHT_FEEDs end at its
                // knots (the drive and infeed axes), the other axes at the pass' end.
                Step::Thread(p) => {
                    for &(a, c) in &p.knots[1..p.n] {
                        let mut t = p.target;
                        t[p.along] = a.round() as i64;
                        t[p.across] = c.round() as i64;
                        let m = mv('F', t);
                        push(&mut o.moves, &mut cur, m, m.p)
                    }
                }
                Step::Follow(f) => {
                    let mut p = cur;
                    p[f.axis] = nm(f.target);
                    match f.kind {
                        FollowKind::Cut => {
                            let (m, back) = (Move { kind: 'R', p, line, tol: 1e-5 }, cur);
                            push(&mut o.moves, &mut cur, m, back)
                        }
                        FollowKind::Return { .. } | FollowKind::Through { .. } | FollowKind::Unsynced => {
                            cur = p
                        }
                        FollowKind::Brake { .. } | FollowKind::Reversal => {}
                    }
                }
                _ => {}
            }
        }
        if ended {
            break;
        }
    }
    if let Some((a, _)) = alarm {
        let line = a.line.unwrap_or(0);
        o.refusal = Some(Refusal { line, text: line_text(line), message: a.detail.clone() });
    }
    Ok(o)
}
