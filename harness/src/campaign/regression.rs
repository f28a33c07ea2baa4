//! A failing case written back as a scenario file (`scenarios/regressions/`), so that plain
//! `cargo test` replays it: the program, parameters and inputs of the case, and an
//! `expect.invariants` section that checks the invariants it broke (docs/invariants.md).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nc_engine::invariants::Violation;
use nc_engine::trace::AXIS_LETTERS;

use super::case::{mm, Action, AnswerKind, Case, Compare, PhaseKind, Trigger};

fn phase_name(k: PhaseKind) -> &'static str {
    match k {
        PhaseKind::Positioning => "positioning",
        PhaseKind::Cutting => "cutting",
        PhaseKind::Dwell => "dwell",
        PhaseKind::Retract => "retract",
    }
}

fn answer_name(k: AnswerKind) -> &'static str {
    match k {
        AnswerKind::PositionModeReached => "position_mode_reached",
        AnswerKind::Fin => "fin",
        AnswerKind::Rgtap => "rgtap",
        AnswerKind::ZeroSpeed => "zero_speed",
    }
}

/// The action as a scenario input key and value.
fn action_yaml(a: Action) -> String {
    use nc_engine::input::Input;
    match super::case::engine_input(a) {
        Input::CycleStart => "cycle_start: {}".into(),
        Input::Reset => "reset: {}".into(),
        Input::FeedHold => "feed_hold: {}".into(),
        Input::SingleBlock(b) => format!("single_block: {b}"),
        Input::DryRun(b) => format!("dry_run: {b}"),
        Input::MachineLock(b) => format!("machine_lock: {b}"),
        Input::OptionalStop(b) => format!("optional_stop: {b}"),
        Input::FeedOverride(p) => format!("feed_override: {p}"),
        Input::SpindleOverride(p) => format!("spindle_override: {p}"),
        Input::EmergencyStop(b) => format!("emergency_stop: {b}"),
        Input::MotorCurrent { source, percent } => {
            let s = match source {
                nc_engine::input::CurrentSource::FeedAxis => "feed_axis",
                nc_engine::input::CurrentSource::Spindle => "spindle",
            };
            format!("motor_current: {{source: {s}, percent: {percent}}}")
        }
        Input::PlcAnswer { extra_us, .. } => {
            let k = match a {
                Action::Late(k, _) | Action::Never(k) => answer_name(k),
                _ => "fin",
            };
            match extra_us {
                Some(us) => format!("plc_answer: {{answer: {k}, late_ms: {}}}", us / 1000),
                None => format!("plc_answer: {{answer: {k}, never: true}}"),
            }
        }
        Input::SpindleStall(b) => format!("spindle_stall: {b}"),
        Input::SetParam { id, value, .. } => format!("set_param: {{id: \"{id}\", value: {value}}}"),
    }
}

/// The scenario text of `case`, titled with the violations it reproduces and where it came from.
pub fn scenario_yaml(case: &Case, violations: &[Violation], origin: &str) -> String {
    let mut y = String::new();
    let first = violations.first().map_or("no violation".to_string(), |v| v.to_string());
    let title = format!("Regression ({origin}): {first}").replace('"', "'");
    let _ = writeln!(y, "title: \"{title}\"");
    let mut ids: Vec<&str> = violations.iter().map(|v| v.invariant.id()).collect();
    ids.dedup();
    if ids.is_empty() {
        ids.push("INV-01");
    }
    let _ = writeln!(y, "rules: [{}]", ids.join(", "));
    let _ = writeln!(y, "dialect: {}", case.dialect());
    let _ = writeln!(y, "params:");
    for (id, axis, value) in case.param_list() {
        match axis {
            Some(a) => {
                let _ = writeln!(y, "  \"{id}\": {{{a}: {value}}}");
            }
            None => {
                let _ = writeln!(y, "  \"{id}\": {value}");
            }
        }
    }
    let _ =
        writeln!(y, "options:\n  sample_us: 1000\n  time_limit_ms: {}", super::case::TIME_LIMIT_US / 1000);
    let (text, _) = case.program_text();
    let _ = writeln!(y, "program: |");
    for line in text.lines() {
        let _ = writeln!(y, "  {line}");
    }
    if !case.inputs.is_empty() {
        let _ = writeln!(y, "inputs:");
    }
    for gi in &case.inputs {
        match gi.trigger {
            Trigger::AtMs(raw) => {
                let _ = writeln!(y, "  - at_ms: {}", raw as u64 * 10);
            }
            Trigger::Phase(k, occ, delay) => {
                let _ = writeln!(y, "  - when: {{phase: {}, occurrence: {}}}", phase_name(k), 1 + occ % 4);
                let _ = writeln!(y, "    delay_ms: {}", delay % 1000);
            }
            Trigger::HoldLamp(occ, delay) => {
                let _ = writeln!(y, "  - when: {{signal: SPL, value: 1, occurrence: {}}}", 1 + occ % 3);
                let _ = writeln!(y, "    delay_ms: {}", delay % 1000);
            }
        }
        let _ = writeln!(y, "    {}", action_yaml(gi.action));
    }
    let ctx = case.context();
    let _ = writeln!(y, "expect:\n  invariants:");
    if let Some(tap) = ctx.tap {
        let _ = writeln!(
            y,
            "    tap: {{axis: {}, lead: {}, tolerance: {}}}",
            AXIS_LETTERS[tap.axis],
            mm(tap.lead_nm),
            mm(tap.tolerance_nm)
        );
    }
    if let Some(ra) = ctx.range_alarm {
        let _ = writeln!(y, "    range_alarm: {{code: \"{}\", line: {}}}", ra.kind.code(), ra.line);
    }
    if let Some(rpm) = ctx.pre_m29_mrpm {
        let _ = writeln!(y, "    pre_m29_rpm: {}", rpm / 1000);
    }
    let _ = writeln!(y, "    hold_suppressed: {}", ctx.hold_suppressed);
    match case.compare {
        Compare::None => {}
        Compare::DryRun(raw) => {
            let _ = writeln!(y, "    compare: {{dry_run_at_ms: {}}}", raw as u64 * 10);
        }
        Compare::MachineLock => {
            let _ = writeln!(y, "    compare: {{machine_lock: true}}");
        }
    }
    let tap_axis = ctx.tap.map_or('Z', |t| AXIS_LETTERS[t.axis]);
    let _ = writeln!(
        y,
        "snapshot:\n  signals: [F76.3, RGTAP, RGSPP, RGSPM, SPL]\n  axes: [{tap_axis}]\n  spindle: true"
    );
    y
}

/// Writes the scenario of a failing case under `dir` as `<name>.yaml` and returns its path.
///
/// # Errors
///
/// When the directory cannot be made or the file written.
pub fn write(dir: &Path, name: &str, yaml: &str) -> std::io::Result<PathBuf> {
    std::fs::create_dir_all(dir)?;
    let path = dir.join(format!("{name}.yaml"));
    std::fs::write(&path, yaml)?;
    Ok(path)
}
