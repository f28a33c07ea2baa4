//! A LinuxCNC machine's INI file as `linuxcnc` dialect parameters (`nc-conform params
//! --from-ini`, issue 13): a LinuxCNC user has an INI file, not a parameter file.
//!
//! What is mapped, each value written with the INI keys it came from:
//! - `[EMCMOT] SERVO_PERIOD` (ns) → `nc.period_us` (one of the four periods, else not mapped);
//! - per axis of `[TRAJ] COORDINATES` (trivkins: joint *i* is the *i*-th letter): the smaller of
//!   `[AXIS_L]` and `[JOINT_i]` `MAX_VELOCITY` (units/s) → `nc.rapid_mm_min`, and velocity over the
//!   smaller `MAX_ACCELERATION` → `nc.rapid_ramp_ms`; `[JOINT_i] BACKLASH` → `nc.backlash_mm`;
//! - `[TRAJ] MAX_LINEAR_VELOCITY` and `MAX_LINEAR_ACCELERATION` cap every move, a one-axis rapid
//!   too: an axis faster than them is written at them;
//! - the cutting feed: the smallest axis velocity, capped by `[TRAJ] MAX_LINEAR_VELOCITY`, →
//!   `nc.feed_max_mm_min`, over the smallest acceleration (capped by `MAX_LINEAR_ACCELERATION`) →
//!   `nc.feed_ramp_ms` (whole milliseconds, rounded);
//! - `[RS274NGC] RS274NGC_STARTUP_CODE`: its last path mode, when G64, → `nc.startup_g64_p_mm`
//!   (its P, 0 without one; DEC-169);
//! - `[SPINDLE_0] MAX_FORWARD_VELOCITY` (rpm) → `nc.spindle_max_rpm`;
//! - `[DISPLAY] MAX_FEED_OVERRIDE`, `MIN_/MAX_SPINDLE_OVERRIDE` (factors) → the override
//!   percentages (DEC-112).
//!
//! `[TRAJ] LINEAR_UNITS` inch (or `in`, `imperial`) scales lengths by 25.4. What cannot be mapped
//! is named in the output with the reason (the spindle's ramp lives in the HAL, not the INI). Knows
//! no command line.

use std::fmt::Write as _;

use nc_engine::Machine;

/// One `KEY = value` line: key, value, line number.
type Entry = (String, String, u32);

/// A value and the INI keys it came from.
type Sourced = Option<(f64, String)>;

/// A parsed INI file: sections of `KEY = value` lines, in order (a key given twice keeps the
/// first, as LinuxCNC's `iniFind` does).
#[derive(Debug, Default)]
pub struct Ini {
    sections: Vec<(String, Vec<Entry>)>,
}

/// An error in the INI file, with its line.
#[derive(Debug, Clone, PartialEq)]
pub struct IniError {
    /// 1-based line.
    pub line: u32,
    /// What is wrong.
    pub message: String,
}

impl Ini {
    /// Parses INI text: `[SECTION]` headers, `KEY = value` lines, `#` and `;` comment lines.
    ///
    /// # Errors
    ///
    /// A line that is none of these, or a key before any section.
    pub fn parse(text: &str) -> Result<Ini, IniError> {
        let mut ini = Ini::default();
        for (i, raw) in text.lines().enumerate() {
            let line = u32::try_from(i + 1).unwrap_or(u32::MAX);
            let l = raw.trim();
            if l.is_empty() || l.starts_with('#') || l.starts_with(';') {
                continue;
            }
            if let Some(name) = l.strip_prefix('[') {
                let Some(name) = name.strip_suffix(']') else {
                    return Err(IniError { line, message: format!("`{l}`: a section header ends with `]`") });
                };
                ini.sections.push((name.trim().to_string(), Vec::new()));
                continue;
            }
            let Some((k, v)) = l.split_once('=') else {
                return Err(IniError { line, message: format!("`{l}`: expected KEY = value or [SECTION]") });
            };
            let Some((_, keys)) = ini.sections.last_mut() else {
                return Err(IniError { line, message: format!("`{}` comes before any [SECTION]", k.trim()) });
            };
            keys.push((k.trim().to_string(), v.trim().to_string(), line));
        }
        Ok(ini)
    }

    /// The first value of `key` in `section`, with its line.
    pub fn get(&self, section: &str, key: &str) -> Option<(&str, u32)> {
        self.sections
            .iter()
            .filter(|(s, _)| s == section)
            .flat_map(|(_, keys)| keys.iter())
            .find(|(k, _, _)| k == key)
            .map(|(_, v, l)| (v.as_str(), *l))
    }

    fn num(&self, section: &str, key: &str, notes: &mut Vec<String>) -> Option<(f64, u32)> {
        let (v, line) = self.get(section, key)?;
        match v.parse::<f64>() {
            Ok(x) if x.is_finite() => Some((x, line)),
            _ => {
                notes.push(format!("[{section}] {key} = {v} (line {line}): not a number"));
                None
            }
        }
    }
}

/// One mapped value: parameter id, axis, value, and where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Mapped {
    /// Parameter id.
    pub id: &'static str,
    /// Axis letter of a per-axis parameter.
    pub axis: Option<char>,
    /// Value in the parameter's unit.
    pub value: f64,
    /// The INI keys it came from.
    pub source: String,
}

/// The INI's values as `linuxcnc` parameters, and what could not be mapped (with why).
#[derive(Debug, Default)]
pub struct Mapping {
    /// Mapped values, each within its parameter's range.
    pub values: Vec<Mapped>,
    /// What was not mapped, one line each.
    pub not_mapped: Vec<String>,
}

fn round(x: f64, places: i32) -> f64 {
    let f = 10f64.powi(places);
    (x * f).round() / f
}

/// The power-on path mode a startup code leaves: its last G64 (Some(Some(P)), P 0 when it has
/// none; in mm when the code's G20/G21 before it says its unit, else in the machine's units
/// `scale` converts), G61 or G61.1 (Some(None)), or no path mode (None). Words as the interpreter
/// reads them: case and spaces do not matter, a comment in parentheses is skipped.
fn startup_g64(code: &str, scale: f64) -> Option<Option<f64>> {
    let mut text = String::new();
    let mut depth = 0;
    for c in code.chars() {
        match c {
            '(' => depth += 1,
            ')' if depth > 0 => depth -= 1,
            c if depth == 0 && !c.is_whitespace() => text.push(c.to_ascii_uppercase()),
            _ => {}
        }
    }
    let mut words: Vec<(char, &str)> = Vec::new();
    let mut rest = text.as_str();
    while let Some(letter) = rest.chars().next() {
        let tail = &rest[letter.len_utf8()..];
        let end = tail
            .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == '+'))
            .unwrap_or(tail.len());
        words.push((letter, &tail[..end]));
        rest = &tail[end..];
    }
    let mut mode = None;
    let mut in_g64 = false;
    let mut unit = scale;
    for (letter, num) in words {
        match (letter, num.parse::<f64>().ok()) {
            ('G', Some(g)) if (g - 20.0).abs() < 1e-9 => unit = 25.4,
            ('G', Some(g)) if (g - 21.0).abs() < 1e-9 => unit = 1.0,
            ('G', Some(g)) if (g - 64.0).abs() < 1e-9 => {
                mode = Some(Some(0.0));
                in_g64 = true;
            }
            ('G', Some(g)) if (g - 61.0).abs() < 1e-9 || (g - 61.1).abs() < 1e-9 => {
                mode = Some(None);
                in_g64 = false;
            }
            ('G', _) => in_g64 = false,
            ('P', Some(p)) if in_g64 && p >= 0.0 => mode = Some(Some(p * unit)),
            _ => {}
        }
    }
    mode
}

/// Maps an INI file onto the `linuxcnc` dialect's parameters.
pub fn map(ini: &Ini) -> Mapping {
    let mut m = Mapping::default();
    let notes = &mut m.not_mapped;
    let mut out: Vec<Mapped> = Vec::new();
    let units = ini.get("TRAJ", "LINEAR_UNITS").map_or("mm", |(u, _)| u).to_ascii_lowercase();
    let scale = match units.as_str() {
        "mm" | "metric" => 1.0,
        "inch" | "in" | "imperial" => 25.4,
        other => {
            notes.push(format!("[TRAJ] LINEAR_UNITS = {other}: unknown unit, mm assumed"));
            1.0
        }
    };
    if let Some((ns, line)) = ini.num("EMCMOT", "SERVO_PERIOD", notes) {
        let us = ns / 1000.0;
        if [1000.0, 2000.0, 4000.0, 8000.0].contains(&us) {
            out.push(Mapped {
                id: "nc.period_us",
                axis: None,
                value: us,
                source: format!("[EMCMOT] SERVO_PERIOD = {ns} ns (line {line})"),
            });
        } else {
            notes.push(format!(
                "[EMCMOT] SERVO_PERIOD = {ns} ns (line {line}): the model's periods are 1, 2, 4 or 8 ms"
            ));
        }
    }
    if let Some((code, line)) = ini.get("RS274NGC", "RS274NGC_STARTUP_CODE") {
        match startup_g64(code, scale) {
            Some(Some(p)) => out.push(Mapped {
                id: "nc.startup_g64_p_mm",
                axis: None,
                value: round(p, 6),
                source: format!("[RS274NGC] RS274NGC_STARTUP_CODE = {code} (line {line})"),
            }),
            Some(None) => notes.push(format!(
                "[RS274NGC] RS274NGC_STARTUP_CODE = {code} (line {line}): powers on in G61 or G61.1; \
                 the reference powers on in G64 (give the mode in the program)"
            )),
            None => {}
        }
    }
    let coords: Vec<char> = ini
        .get("TRAJ", "COORDINATES")
        .map_or("X Y Z", |(c, _)| c)
        .chars()
        .filter(char::is_ascii_alphabetic)
        .map(|c| c.to_ascii_uppercase())
        .collect();
    let (mut feed_v, mut feed_a): (Sourced, Sourced) = (None, None);
    // [TRAJ]'s limits cap every move's vector, a one-axis rapid too: an axis faster than them
    // runs at them.
    let traj = |key: &str, notes: &mut Vec<String>| -> Sourced {
        ini.num("TRAJ", key, notes)
            .filter(|(v, _)| *v > 0.0)
            .map(|(v, l)| (v, format!("[TRAJ] {key} = {v} (line {l}), below the axis' own, caps it")))
    };
    let traj_v = traj("MAX_LINEAR_VELOCITY", notes);
    let traj_a = traj("MAX_LINEAR_ACCELERATION", notes);
    for (j, &letter) in coords.iter().enumerate() {
        if !matches!(letter, 'X' | 'Y' | 'Z') {
            notes.push(format!("axis {letter} (joint {j}): the linuxcnc dialect models X, Y and Z only"));
            continue;
        }
        let axis_sec = format!("AXIS_{letter}");
        let joint_sec = format!("JOINT_{j}");
        let smaller = |key: &str, notes: &mut Vec<String>| -> Sourced {
            let a = ini
                .num(&axis_sec, key, notes)
                .map(|(v, l)| (v, format!("[{axis_sec}] {key} = {v} (line {l})")));
            let b = ini
                .num(&joint_sec, key, notes)
                .map(|(v, l)| (v, format!("[{joint_sec}] {key} = {v} (line {l})")));
            match (a, b) {
                (Some(a), Some(b)) => Some(if b.0 < a.0 { b } else { a }),
                (a, b) => a.or(b),
            }
        };
        let capped = |own: Sourced, cap: &Sourced| match (own, cap) {
            (Some(o), Some(c)) if c.0 < o.0 => Some(c.clone()),
            (o, _) => o,
        };
        let v = capped(smaller("MAX_VELOCITY", notes), &traj_v);
        let a = capped(smaller("MAX_ACCELERATION", notes), &traj_a);
        match &v {
            Some((vel, src)) if *vel > 0.0 => {
                out.push(Mapped {
                    id: "nc.rapid_mm_min",
                    axis: Some(letter),
                    value: round(vel * scale * 60.0, 3),
                    source: format!("{src} × 60{}", if scale == 1.0 { "" } else { " × 25.4" }),
                });
                if let Some((acc, asrc)) = a.as_ref().filter(|(acc, _)| *acc > 0.0) {
                    out.push(Mapped {
                        id: "nc.rapid_ramp_ms",
                        axis: Some(letter),
                        value: round(vel / acc * 1000.0, 1),
                        source: format!("{src} / {asrc}"),
                    });
                } else {
                    notes.push(format!(
                        "{letter}: no MAX_ACCELERATION, its rapid time constant stays the default"
                    ));
                }
                if feed_v.as_ref().is_none_or(|(f, _)| vel < f) {
                    feed_v = Some((*vel, src.clone()));
                }
            }
            _ => notes.push(format!(
                "{letter}: no MAX_VELOCITY in [{axis_sec}] or [{joint_sec}], rate stays the default"
            )),
        }
        if let Some((acc, asrc)) = a.filter(|(acc, _)| *acc > 0.0) {
            if feed_a.as_ref().is_none_or(|(f, _)| acc < *f) {
                feed_a = Some((acc, asrc));
            }
        }
        if let Some((b, l)) = ini.num(&joint_sec, "BACKLASH", notes) {
            out.push(Mapped {
                id: "nc.backlash_mm",
                axis: Some(letter),
                value: round(b * scale, 6),
                source: format!("[{joint_sec}] BACKLASH = {b} (line {l})"),
            });
        }
    }
    if let Some((tv, l)) = ini.num("TRAJ", "MAX_LINEAR_VELOCITY", notes) {
        if feed_v.as_ref().is_none_or(|(f, _)| tv < *f) {
            feed_v = Some((tv, format!("[TRAJ] MAX_LINEAR_VELOCITY = {tv} (line {l})")));
        }
    }
    if let Some((ta, l)) = ini.num("TRAJ", "MAX_LINEAR_ACCELERATION", notes) {
        if feed_a.as_ref().is_none_or(|(f, _)| ta < *f) {
            feed_a = Some((ta, format!("[TRAJ] MAX_LINEAR_ACCELERATION = {ta} (line {l})")));
        }
    }
    if let Some((fv, fsrc)) = feed_v.filter(|(f, _)| *f > 0.0) {
        out.push(Mapped {
            id: "nc.feed_max_mm_min",
            axis: None,
            value: round(fv * scale * 60.0, 3),
            source: format!("the smallest of the axes' and [TRAJ]'s velocities: {fsrc} × 60"),
        });
        if let Some((fa, asrc)) = feed_a {
            // The cutting time constant is whole milliseconds.
            let ms = fv / fa * 1000.0;
            let rounded =
                if ms == ms.round() { String::new() } else { format!(" ({} ms rounded)", round(ms, 3)) };
            out.push(Mapped {
                id: "nc.feed_ramp_ms",
                axis: None,
                value: ms.round(),
                source: format!("that velocity / the smallest acceleration, {asrc}{rounded}"),
            });
        }
    }
    if let Some((rpm, l)) = ini.num("SPINDLE_0", "MAX_FORWARD_VELOCITY", notes) {
        out.push(Mapped {
            id: "nc.spindle_max_rpm",
            axis: None,
            value: rpm.round(),
            source: format!("[SPINDLE_0] MAX_FORWARD_VELOCITY = {rpm} (line {l})"),
        });
    }
    notes.push(
        "the spindle's ramp (nc.spindle_ramp_ms) is not in the INI: it is the HAL's (e.g. limit2 maxv \
         before sim_spindle, or the drive's own ramp); measure it, or use nc-conform calibrate"
            .into(),
    );
    for (key, id) in [
        ("MAX_FEED_OVERRIDE", "nc.feed_override_max_pct"),
        ("MIN_SPINDLE_OVERRIDE", "nc.spindle_override_min_pct"),
        ("MAX_SPINDLE_OVERRIDE", "nc.spindle_override_max_pct"),
    ] {
        if let Some((f, l)) = ini.num("DISPLAY", key, notes) {
            out.push(Mapped {
                id,
                axis: None,
                value: (f * 100.0).round(),
                source: format!("[DISPLAY] {key} = {f} (line {l}) × 100"),
            });
        }
    }
    // Only values within the parameter's range are written.
    let machine = Machine::new("linuxcnc").expect("the linuxcnc dialect exists");
    let mut params = machine.params.clone();
    for v in out {
        match params.set(v.id, v.axis, v.value) {
            Ok(()) => m.values.push(v),
            Err(e) => m.not_mapped.push(format!(
                "{} {} = {} from {}: {e:?}",
                v.id,
                v.axis.map(String::from).unwrap_or_default(),
                v.value,
                v.source
            )),
        }
    }
    m
}

/// The mapping as a parameter file (`docs/parameters-format.md`) with a comment on each value's
/// source and the list of what was not mapped.
pub fn params_file(m: &Mapping, source: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# nc-conform params --from-ini {source}: the linuxcnc dialect's parameters from the INI file."
    );
    let _ = writeln!(s, "dialect: linuxcnc");
    let _ = writeln!(s, "params:");
    let mut done: Vec<&str> = Vec::new();
    for v in &m.values {
        if v.axis.is_some() {
            if done.contains(&v.id) {
                continue;
            }
            done.push(v.id);
            let _ = writeln!(s, "  {}:", v.id);
            for x in m.values.iter().filter(|x| x.id == v.id) {
                let _ = writeln!(s, "    {}: {}   # {}", x.axis.unwrap_or('?'), x.value, x.source);
            }
        } else {
            let _ = writeln!(s, "  {}: {}   # {}", v.id, v.value, v.source);
        }
    }
    if !m.not_mapped.is_empty() {
        let _ = writeln!(s, "# Not mapped:");
        for n in &m.not_mapped {
            let _ = writeln!(s, "#   {n}");
        }
    }
    s
}
