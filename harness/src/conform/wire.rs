//! The adapter protocol's JSON values (`docs/adapter-protocol.md`): inputs, conditions, jobs,
//! and trace events as `nc-conform-trace/1` lines. Both ends use these: the process adapter
//! writes them, [`super::serve`] reads them.

use nc_engine::input::{Condition, CurrentSource, Input, PlcAnswer};
use nc_engine::trace::{axis_index, Phase, Signal, TraceEvent, TraceMeta, AXIS_LETTERS};
use serde_json::{json, Map, Value};

use super::{Job, ParamValue};
use crate::jsonl::JsonlWriter;
use crate::scenario::timeline::fixed;

/// An input as a JSON object: `{"name":"feed_hold"}`, `{"name":"dry_run","on":true}`, ...
pub fn input_json(input: &Input) -> Value {
    let name = input.name();
    match input {
        Input::CycleStart | Input::Reset | Input::FeedHold => json!({ "name": name }),
        Input::SingleBlock(b)
        | Input::DryRun(b)
        | Input::MachineLock(b)
        | Input::OptionalStop(b)
        | Input::EmergencyStop(b)
        | Input::SpindleStall(b) => json!({ "name": name, "on": b }),
        Input::FeedOverride(p) | Input::SpindleOverride(p) => json!({ "name": name, "percent": p }),
        Input::MotorCurrent { source, percent } => {
            let s = match source {
                CurrentSource::FeedAxis => "feed_axis",
                CurrentSource::Spindle => "spindle",
            };
            json!({ "name": name, "source": s, "percent": percent })
        }
        Input::PlcAnswer { answer, extra_us } => {
            let mut o = json!({ "name": name, "answer": answer_name(*answer) });
            match extra_us {
                Some(us) => o["late_us"] = json!(us),
                None => o["never"] = json!(true),
            }
            o
        }
        Input::SetParam { id, axis, value } => {
            let mut o = json!({ "name": name, "id": id, "value": value });
            if let Some(a) = axis {
                o["axis"] = json!(a.to_string());
            }
            o
        }
    }
}

fn answer_name(a: PlcAnswer) -> &'static str {
    match a {
        PlcAnswer::PositionModeReached => "position_mode_reached",
        PlcAnswer::Fin => "fin",
        PlcAnswer::Rgtap => "rgtap",
        PlcAnswer::ZeroSpeed => "zero_speed",
    }
}

fn str_of<'v>(o: &'v Map<String, Value>, key: &str) -> Result<&'v str, String> {
    o.get(key).and_then(Value::as_str).ok_or_else(|| format!("`{key}` must be a string"))
}

fn u32_of(o: &Map<String, Value>, key: &str) -> Result<u32, String> {
    o.get(key)
        .and_then(Value::as_u64)
        .and_then(|v| u32::try_from(v).ok())
        .ok_or_else(|| format!("`{key}` must be an unsigned integer"))
}

fn bool_of(o: &Map<String, Value>, key: &str) -> Result<bool, String> {
    o.get(key).and_then(Value::as_bool).ok_or_else(|| format!("`{key}` must be true or false"))
}

fn axis_of(s: &str) -> Result<char, String> {
    let mut ch = s.chars();
    match (ch.next(), ch.next()) {
        (Some(c), None) if axis_index(c.to_ascii_uppercase()).is_some() => Ok(c.to_ascii_uppercase()),
        _ => Err(format!("`{s}` is not an axis letter (X Y Z A B C)")),
    }
}

/// Reads an input object.
///
/// # Errors
///
/// Unknown name, missing or mistyped keys.
pub fn input_from(v: &Value) -> Result<Input, String> {
    let o = v.as_object().ok_or("an input is a JSON object")?;
    let name = str_of(o, "name")?;
    Ok(match name {
        "cycle_start" => Input::CycleStart,
        "reset" => Input::Reset,
        "feed_hold" => Input::FeedHold,
        "single_block" => Input::SingleBlock(bool_of(o, "on")?),
        "dry_run" => Input::DryRun(bool_of(o, "on")?),
        "machine_lock" => Input::MachineLock(bool_of(o, "on")?),
        "optional_stop" => Input::OptionalStop(bool_of(o, "on")?),
        "emergency_stop" => Input::EmergencyStop(bool_of(o, "on")?),
        "spindle_stall" => Input::SpindleStall(bool_of(o, "on")?),
        "feed_override" => Input::FeedOverride(u32_of(o, "percent")?),
        "spindle_override" => Input::SpindleOverride(u32_of(o, "percent")?),
        "motor_current" => Input::MotorCurrent {
            source: match str_of(o, "source")? {
                "feed_axis" => CurrentSource::FeedAxis,
                "spindle" => CurrentSource::Spindle,
                s => return Err(format!("unknown current source `{s}` (feed_axis or spindle)")),
            },
            percent: u32_of(o, "percent")?,
        },
        "plc_answer" => {
            let answer = match str_of(o, "answer")? {
                "position_mode_reached" => PlcAnswer::PositionModeReached,
                "fin" => PlcAnswer::Fin,
                "rgtap" => PlcAnswer::Rgtap,
                "zero_speed" => PlcAnswer::ZeroSpeed,
                s => return Err(format!("unknown PLC answer `{s}`")),
            };
            let extra_us = match o.get("late_us") {
                Some(v) => Some(v.as_u64().ok_or("`late_us` must be an unsigned integer")?),
                None => None,
            };
            Input::PlcAnswer { answer, extra_us }
        }
        "set_param" => Input::SetParam {
            id: str_of(o, "id")?.to_string(),
            axis: o.get("axis").and_then(Value::as_str).map(axis_of).transpose()?,
            value: o.get("value").and_then(Value::as_f64).ok_or("`value` must be a number")?,
        },
        other => return Err(format!("unknown input `{other}`")),
    })
}

/// A number with `digits` implied decimals as a JSON number (exact decimal text).
fn decimal(v: i64, digits: u32) -> Value {
    serde_json::from_str(&fixed(v, digits)).unwrap_or(Value::Null)
}

/// A condition as the object a scenario's `when:` writes: `{"signal":"RGTAP","value":1}`,
/// `{"axis":"Z","below":-10.5}`, `{"block":7}`, `{"phase":"cutting"}`, `{"function":"M29"}`.
pub fn condition_json(c: &Condition) -> Value {
    match c {
        Condition::Signal { signal, value } => json!({ "signal": signal.name(), "value": *value as u8 }),
        Condition::AxisBelow { axis, nm } | Condition::AxisAbove { axis, nm } => {
            let letter = AXIS_LETTERS.get(*axis).copied().unwrap_or('?').to_string();
            let key = if matches!(c, Condition::AxisBelow { .. }) { "below" } else { "above" };
            let mut o = Map::new();
            o.insert("axis".into(), json!(letter));
            o.insert(key.into(), decimal(*nm, 6));
            Value::Object(o)
        }
        Condition::Block { line } => json!({ "block": line }),
        Condition::Phase(p) => json!({ "phase": p.name() }),
        Condition::Function { letter, code } => json!({ "function": format!("{letter}{code}") }),
    }
}

/// Reads a condition object.
///
/// # Errors
///
/// Unknown names, missing or mistyped keys.
pub fn condition_from(v: &Value) -> Result<Condition, String> {
    let o = v.as_object().ok_or("a condition is a JSON object")?;
    if let Some(s) = o.get("signal") {
        let name = s.as_str().ok_or("`signal` must be a string")?;
        let signal = Signal::from_name(name).ok_or_else(|| format!("unknown signal `{name}`"))?;
        return Ok(Condition::Signal { signal, value: u32_of(o, "value")? != 0 });
    }
    if let Some(a) = o.get("axis") {
        let letter = axis_of(a.as_str().ok_or("`axis` must be a string")?)?;
        let axis = axis_index(letter).unwrap_or(0);
        let nm = |v: &Value| v.as_f64().map(|mm| (mm * 1e6).round() as i64).ok_or("a number of mm");
        return match (o.get("below"), o.get("above")) {
            (Some(b), None) => Ok(Condition::AxisBelow { axis, nm: nm(b)? }),
            (None, Some(b)) => Ok(Condition::AxisAbove { axis, nm: nm(b)? }),
            _ => Err("an axis condition has exactly one of `below` and `above`".into()),
        };
    }
    if o.contains_key("block") {
        return Ok(Condition::Block { line: u32_of(o, "block")? });
    }
    if let Some(p) = o.get("phase") {
        let name = p.as_str().ok_or("`phase` must be a string")?;
        return Phase::from_name(name).map(Condition::Phase).ok_or_else(|| format!("unknown phase `{name}`"));
    }
    if let Some(f) = o.get("function") {
        let text = f.as_str().ok_or("`function` must be a string like M29")?;
        let mut ch = text.chars();
        let letter = ch.next().map(|c| c.to_ascii_uppercase()).filter(|c| matches!(c, 'M' | 'S' | 'T'));
        let code = ch.as_str().parse::<u32>().ok();
        return match (letter, code) {
            (Some(letter), Some(code)) => Ok(Condition::Function { letter, code }),
            _ => Err(format!("`{text}` is not an M, S or T function")),
        };
    }
    Err("a condition has one of `signal`, `axis`, `block`, `phase`, `function`".into())
}

/// The `load` message of a job.
pub fn load_json(job: &Job) -> Value {
    let params: Vec<Value> = job
        .params
        .iter()
        .map(|p| match p.axis {
            Some(a) => json!({ "id": p.id, "axis": a.to_string(), "value": p.value }),
            None => json!({ "id": p.id, "value": p.value }),
        })
        .collect();
    json!({
        "op": "load",
        "dialect": job.dialect,
        "program": job.program,
        "params": params,
        "sample_us": job.sample_us,
        "time_limit_us": job.time_limit_us,
        "auto_cycle_start": job.auto_cycle_start,
    })
}

/// Reads a `load` message.
///
/// # Errors
///
/// Missing or mistyped keys.
pub fn job_from(o: &Map<String, Value>) -> Result<Job, String> {
    let u64_of = |k: &str| {
        o.get(k).and_then(Value::as_u64).ok_or_else(|| format!("`{k}` must be an unsigned integer"))
    };
    let mut params = Vec::new();
    for p in o.get("params").and_then(Value::as_array).map_or(&[][..], Vec::as_slice) {
        let po = p.as_object().ok_or("a parameter is a JSON object")?;
        params.push(ParamValue {
            id: str_of(po, "id")?.to_string(),
            axis: po.get("axis").and_then(Value::as_str).map(axis_of).transpose()?,
            value: po.get("value").and_then(Value::as_f64).ok_or("a parameter's `value` must be a number")?,
        });
    }
    Ok(Job {
        dialect: str_of(o, "dialect")?.to_string(),
        program: str_of(o, "program")?.to_string(),
        params,
        sample_us: u64_of("sample_us")?,
        time_limit_us: u64_of("time_limit_us")?,
        auto_cycle_start: bool_of(o, "auto_cycle_start")?,
    })
}

/// Trace events as `nc-conform-trace/1` lines (without the `meta` line), each without its `\n`.
pub fn event_lines(meta: &TraceMeta, events: &[TraceEvent]) -> Vec<String> {
    let mut w = JsonlWriter::new(Vec::new());
    w.write_meta(meta);
    for e in events {
        w.write_event(e);
    }
    let bytes = w.finish().unwrap_or_default();
    String::from_utf8_lossy(&bytes).lines().skip(1).map(str::to_string).collect()
}

/// The trace header of a job's machine (dialect, axes, periods), or None for an unknown dialect
/// or parameter.
pub fn meta_of(job: &Job) -> Option<TraceMeta> {
    let mut machine = nc_engine::Machine::new(&job.dialect)?;
    for p in &job.params {
        machine.params.set(&p.id, p.axis, p.value).ok()?;
    }
    let opts = nc_engine::RunOptions { sample_us: job.sample_us, time_limit_us: 0, ..Default::default() };
    Some(machine.run_to_trace(&nc_engine::Program::default(), &opts).meta)
}

/// The `meta` line the events of a dialect are read under.
pub fn meta_line(meta: &TraceMeta) -> String {
    let mut w = JsonlWriter::new(Vec::new());
    w.write_meta(meta);
    let bytes = w.finish().unwrap_or_default();
    String::from_utf8_lossy(&bytes).trim_end().to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nc_engine::trace::Phase;

    #[test]
    fn every_input_survives_the_wire() {
        let inputs = [
            Input::CycleStart,
            Input::Reset,
            Input::FeedHold,
            Input::SingleBlock(true),
            Input::DryRun(false),
            Input::MachineLock(true),
            Input::OptionalStop(true),
            Input::EmergencyStop(true),
            Input::SpindleStall(false),
            Input::FeedOverride(120),
            Input::SpindleOverride(50),
            Input::MotorCurrent { source: CurrentSource::Spindle, percent: 150 },
            Input::PlcAnswer { answer: PlcAnswer::Fin, extra_us: Some(5000) },
            Input::PlcAnswer { answer: PlcAnswer::Rgtap, extra_us: None },
            Input::SetParam { id: "34".into(), axis: Some('Z'), value: 0.05 },
            Input::SetParam { id: "271".into(), axis: None, value: 120.0 },
        ];
        for i in inputs {
            let v = input_json(&i);
            assert_eq!(v["name"], i.name());
            assert_eq!(input_from(&serde_json::from_str(&v.to_string()).unwrap()), Ok(i));
        }
    }

    #[test]
    fn every_condition_survives_the_wire() {
        let conds = [
            Condition::Signal { signal: Signal::Rgtap, value: true },
            Condition::AxisBelow { axis: 2, nm: -10_500_000 },
            Condition::AxisAbove { axis: 0, nm: 1 },
            Condition::Block { line: 7 },
            Condition::Phase(Phase::Cutting),
            Condition::Function { letter: 'M', code: 29 },
        ];
        for c in conds {
            let text = condition_json(&c).to_string();
            assert_eq!(condition_from(&serde_json::from_str(&text).unwrap()), Ok(c), "{text}");
        }
        assert_eq!(
            condition_json(&Condition::AxisBelow { axis: 2, nm: -10_500_000 }).to_string(),
            r#"{"axis":"Z","below":-10.5}"#
        );
    }

    #[test]
    fn bad_values_say_what_was_expected() {
        let bad = |s: &str| input_from(&serde_json::from_str(s).unwrap()).unwrap_err();
        assert_eq!(bad(r#"{"name":"jog"}"#), "unknown input `jog`");
        assert_eq!(bad(r#"{"name":"dry_run"}"#), "`on` must be true or false");
        assert_eq!(
            bad(r#"{"name":"set_param","id":"34","axis":"Q","value":1}"#),
            "`Q` is not an axis letter (X Y Z A B C)"
        );
        let c = |s: &str| condition_from(&serde_json::from_str(s).unwrap()).unwrap_err();
        assert_eq!(c(r#"{"function":"G84"}"#), "`G84` is not an M, S or T function");
        assert_eq!(c(r#"{"axis":"Z"}"#), "an axis condition has exactly one of `below` and `above`");
        assert_eq!(c(r#"{"signal":"NOPE","value":1}"#), "unknown signal `NOPE`");
    }

    #[test]
    fn a_job_survives_the_wire() {
        let job = Job {
            dialect: "gsk-lathe".into(),
            program: "G98;\nM29 S500;\n".into(),
            params: vec![ParamValue { id: "34".into(), axis: Some('Z'), value: 0.05 }],
            sample_us: 1000,
            time_limit_us: 60_000_000,
            auto_cycle_start: false,
        };
        let v: Value = serde_json::from_str(&load_json(&job).to_string()).unwrap();
        assert_eq!(job_from(v.as_object().unwrap()), Ok(job));
    }
}
