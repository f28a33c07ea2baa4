//! Loading a scenario file: YAML → a machine, a parsed program, run options with the input
//! schedule, resolved expectations and the diagram to snapshot. Every error names the file, line
//! and column and what was expected.

use std::path::{Path, PathBuf};

use nc_engine::input::{CurrentSource, Input, InputSchedule, PlcAnswer, Trigger};
use nc_engine::trace::Signal;
use nc_engine::{Machine, Program, RunOptions};
use serde_saphyr::Spanned;

use super::expect::{self, Expectations};
use super::resolve::{ms_to_us, Ctx};
use super::schema::{ExpectRefused, InputEntry, ScenarioFile};
use crate::diag::{InputError, Span};
use crate::params_yaml::{self, span_of};
use crate::render::timing::DiagramSpec;

/// A scenario ready to run.
#[derive(Debug)]
pub struct Scenario {
    /// The file as named (e.g. `scenarios/gsk/feed_hold/during_peck_retract.yaml`).
    pub name: String,
    /// One line saying what it shows.
    pub title: String,
    /// Rule ids it checks.
    pub rules: Vec<String>,
    /// The machine (dialect and parameters).
    pub machine: Machine,
    /// The program.
    pub program: Program,
    /// How to run it, with the inputs.
    pub opts: RunOptions,
    /// What must happen.
    pub expect: Expectations,
    /// The timing diagram to snapshot.
    pub diagram: DiagramSpec,
    /// `expect.invariants`, if given.
    pub invariants: Option<super::invariants::InvariantCheck>,
    /// The parser's refusal, when the scenario expects one (`expect.refused`): the program is
    /// then empty and the verdict compares this error with the expectation.
    pub refusal: Option<(Option<nc_engine::ParseError>, ExpectRefused, String)>,
    /// The scenario's own parameters that replace a machine's (loaded over [`MachineParams`]):
    /// `nc.spindle_ramp_ms = 20000 (the machine's: 1000)`, one per value the scenario sets.
    pub over_machine: Vec<String>,
}

/// A machine's own parameters (`conform --params FILE`), under every scenario's: the scenario's
/// parameters are its conditions and set on top of them.
#[derive(Debug, Clone)]
pub struct MachineParams {
    /// The file as named.
    pub name: String,
    /// Its text (for the location of an error).
    pub text: String,
    /// What it sets, and the dialect it names.
    pub file: params_yaml::ParamsFile,
}

impl MachineParams {
    /// Reads a parameter file.
    ///
    /// # Errors
    ///
    /// Unreadable, or not a parameter file (located).
    pub fn read(path: &Path) -> Result<MachineParams, InputError> {
        let name = crate::input::display_name(path);
        let text = crate::input::read_utf8(path, crate::input::YAML)?;
        let file = params_yaml::parse_file(&text).map_err(|e| at(&name, &text, e))?;
        Ok(MachineParams { name, text, file })
    }

    /// Sets them on `machine` when they are of its dialect (a file naming another dialect leaves
    /// it alone); returns whether it did.
    ///
    /// # Errors
    ///
    /// A value the dialect refuses, located in the parameter file.
    pub fn apply(&self, machine: &mut Machine) -> Result<bool, InputError> {
        if !self.file.fits(machine.dialect.name()) {
            return Ok(false);
        }
        params_yaml::apply_settings(&self.file.settings, machine)
            .map_err(|e| at(&self.name, &self.text, e))?;
        Ok(true)
    }
}

/// Reads and checks a scenario file. `name` is how errors and reports name it.
///
/// # Errors
///
/// Unreadable files, YAML errors, unknown keys, bad values, program syntax errors, each located.
pub fn load(path: &Path, name: &str) -> Result<Scenario, InputError> {
    load_over(path, name, &[])
}

/// [`load`] on a machine's own parameters: each file of `machine` in turn (those of the
/// scenario's dialect, a later file over an earlier), the scenario's on top.
///
/// # Errors
///
/// As [`load`]; also a machine parameter the scenario's dialect refuses.
pub fn load_over(path: &Path, name: &str, machine: &[MachineParams]) -> Result<Scenario, InputError> {
    let bytes = crate::input::read_capped(path, crate::input::YAML).map_err(|m| InputError::new(name, m))?;
    let text = String::from_utf8(bytes)
        .map_err(|_| InputError::new(name, "cannot read: stream did not contain valid UTF-8"))?;
    load_text_over(&text, name, path.parent().unwrap_or(Path::new(".")), machine)
}

/// The most samples a scenario's run may write (`options.time_limit_ms` / `options.sample_us`):
/// its trace is held in memory, about 100 bytes a sample.
pub const MAX_SAMPLES: u64 = 1_000_000;

/// [`load`] from text; `dir` is where `program_file` paths start.
///
/// # Errors
///
/// As [`load`].
pub fn load_text(text: &str, name: &str, dir: &Path) -> Result<Scenario, InputError> {
    load_text_over(text, name, dir, &[])
}

/// [`load_text`] on a machine's own parameters, as [`load_over`].
///
/// # Errors
///
/// As [`load_over`].
pub fn load_text_over(
    text: &str,
    name: &str,
    dir: &Path,
    base: &[MachineParams],
) -> Result<Scenario, InputError> {
    let options = serde_saphyr::options! { strict_booleans: true, with_snippet: false };
    let mut file: ScenarioFile = serde_saphyr::from_str_with_options(text, options).map_err(|e| {
        let pe = params_yaml::yaml_error(text, &e);
        let message = pe.message.replacen("invalid parameter file: ", "invalid scenario: ", 1);
        InputError::at(name, text, pe.span, message, pe.expected)
    })?;
    let dialect = &file.dialect;
    let mut machine = Machine::new(&dialect.value).ok_or_else(|| {
        InputError::at(
            name,
            text,
            span_of(text, &dialect.referenced),
            format!("unknown dialect `{}`", dialect.value),
            Some(format!("one of {}", nc_engine::dialect_names().join(", "))),
        )
    })?;
    let settings =
        params_yaml::settings_from(text, std::mem::take(&mut file.params)).map_err(|e| at(name, text, e))?;
    let mut over_machine = Vec::new();
    let mut applied = false;
    for file in base {
        applied |= file.apply(&mut machine)?;
    }
    if applied {
        for st in &settings {
            let was = machine.params.get_axis(&st.id, st.axis);
            if machine.params.def(&st.id).is_some() && was != st.value {
                let axis = st.axis.map_or(String::new(), |a| format!(" {a}"));
                over_machine.push(format!("{}{axis} = {} (the machine's: {was})", st.id, st.value));
            }
        }
    }
    params_yaml::apply_settings(&settings, &mut machine).map_err(|e| at(name, text, e))?;
    let ctx = Ctx { file: name, text, axes: machine.dialect.axes() };

    if file.rules.is_empty() {
        return Err(InputError::at(
            name,
            text,
            Span::from_line_col(text, 1, 1, 1),
            "a scenario names the rule ids it checks",
            Some("rules: [GSK-RT-07, ...] with at least one id".into()),
        ));
    }
    let rules: Vec<String> = file.rules.iter().map(|r| r.value.clone()).collect();
    let (program, refusal) = match &file.expect.refused {
        None => (program(&file, &machine, &ctx, dir)?, None),
        Some(r) => {
            let text = match (&file.program, &file.program_file) {
                (Some(p), None) => p.value.clone(),
                _ => return Err(ctx.err(r, "`expect.refused` needs an inline `program`", "program: | ...")),
            };
            let parsed = machine.parse(&text);
            let err = parsed.err();
            (Program::default(), Some((err, r.value.clone(), text)))
        }
    };
    let mut inputs = InputSchedule::default();
    for entry in &file.inputs {
        let (trigger, input) = input(&ctx, entry)?;
        inputs.inputs.push(nc_engine::input::ScheduledInput { trigger, input });
    }
    // A scenario's trace is held in memory: its samples are bounded (docs/input-limits.md).
    let samples = match file.options.sample_us {
        0 => 0,
        s => file.options.time_limit_ms.saturating_mul(1000) / s,
    };
    if samples > MAX_SAMPLES {
        let mut e = InputError::new(
            ctx.file,
            format!(
                "options: time_limit_ms {} at sample_us {} would hold {samples} samples, more than the {MAX_SAMPLES} a scenario may",
                file.options.time_limit_ms, file.options.sample_us
            ),
        );
        e.expected = Some("a larger sample_us or a shorter time_limit_ms".into());
        return Err(e);
    }
    let opts = RunOptions {
        sample_us: file.options.sample_us,
        time_limit_us: file.options.time_limit_ms.saturating_mul(1000),
        auto_cycle_start: file.options.auto_cycle_start,
        inputs,
        ..RunOptions::default()
    };
    let expect = expect::resolve(&ctx, &file.expect, &rules[0])?;
    let diagram = diagram(&ctx, &file)?;
    let invariants =
        file.expect.invariants.as_ref().map(|i| super::invariants::resolve(&ctx, i)).transpose()?;
    Ok(Scenario {
        name: name.to_string(),
        title: file.title,
        rules,
        machine,
        program,
        opts,
        expect,
        diagram,
        invariants,
        refusal,
        over_machine,
    })
}

fn at(name: &str, text: &str, e: params_yaml::ParamsFileError) -> InputError {
    InputError::at(name, text, e.span, e.message, e.expected)
}

/// The program: inline (errors located inside the YAML file) or from `program_file`.
fn program(file: &ScenarioFile, machine: &Machine, ctx: &Ctx, dir: &Path) -> Result<Program, InputError> {
    match (&file.program, &file.program_file) {
        (Some(p), None) => {
            machine.parse(&p.value).map_err(|e| {
                // Where the program's first line stands in the YAML file.
                let span = ctx.span(p);
                let (line0, indent) = block_scalar_origin(ctx.text, span);
                let span = Span::from_line_col(ctx.text, line0 + e.line - 1, indent + e.col, e.len);
                InputError::at(ctx.file, ctx.text, span, e.message, Some(e.expected))
            })
        }
        (None, Some(f)) => {
            let path: PathBuf = dir.join(&f.value);
            let text = crate::input::read_capped(&path, crate::input::PROGRAM)
                .map_err(|err| {
                    ctx.err(
                        f,
                        format!("program file {}: {err}", path.display()),
                        "a readable file, relative to the scenario",
                    )
                })
                .map(crate::input::lossy_text)?;
            let shown = path.display().to_string();
            machine.parse(&text).map_err(|e| {
                let span = Span::from_line_col(&text, e.line, e.col, e.len);
                InputError::at(shown.clone(), &text, span, e.message, Some(e.expected))
            })
        }
        _ => Err(InputError::at(
            ctx.file,
            ctx.text,
            Span::from_line_col(ctx.text, 1, 1, 1),
            "a scenario has exactly one of `program` and `program_file`",
            Some("program: | (inline G-code) or program_file: path/to/program.nc".into()),
        )),
    }
}

/// First line and column offset (0-based) of the content of the scalar at `span`: a block scalar
/// (`|`, `>`) starts on the next line at its indentation.
fn block_scalar_origin(text: &str, span: Span) -> (u32, u32) {
    let rest = &text[span.offset.min(text.len())..];
    if rest.starts_with('|') || rest.starts_with('>') {
        let next = rest.find('\n').map_or(text.len(), |i| span.offset + i + 1);
        let line = &text[next.min(text.len())..];
        let indent = line.chars().take_while(|c| *c == ' ').count() as u32;
        (span.line + 1, indent)
    } else {
        (span.line, span.col - 1)
    }
}

/// One input entry: its trigger and action.
fn input(ctx: &Ctx, e: &Spanned<InputEntry>) -> Result<(Trigger, Input), InputError> {
    let v = &e.value;
    let trigger = match (v.at_ms, &v.when) {
        (Some(ms), None) => Trigger::At(ms_to_us(ms + v.delay_ms.unwrap_or(0.0))),
        (None, Some(w)) => {
            let (condition, occurrence, delay_us) = ctx.condition(w, v.delay_ms)?;
            Trigger::When { condition, occurrence, delay_us }
        }
        _ => {
            return Err(ctx.err(
                e,
                "an input has exactly one of `at_ms` and `when`",
                "at_ms: 500, or when: {signal: RGTAP, value: 1}",
            ))
        }
    };
    let mut actions: Vec<Input> = Vec::new();
    if v.cycle_start.is_some() {
        actions.push(Input::CycleStart);
    }
    if v.reset.is_some() {
        actions.push(Input::Reset);
    }
    if v.feed_hold.is_some() {
        actions.push(Input::FeedHold);
    }
    type Switch = (Option<bool>, fn(bool) -> Input);
    let switches: [Switch; 6] = [
        (v.single_block, Input::SingleBlock),
        (v.dry_run, Input::DryRun),
        (v.machine_lock, Input::MachineLock),
        (v.optional_stop, Input::OptionalStop),
        (v.emergency_stop, Input::EmergencyStop),
        (v.spindle_stall, Input::SpindleStall),
    ];
    for (b, f) in switches {
        if let Some(b) = b {
            actions.push(f(b));
        }
    }
    if let Some(p) = v.feed_override {
        actions.push(Input::FeedOverride(p));
    }
    if let Some(p) = v.spindle_override {
        actions.push(Input::SpindleOverride(p));
    }
    if let Some(m) = &v.motor_current {
        let source = match m.source.value.as_str() {
            "feed_axis" => CurrentSource::FeedAxis,
            "spindle" => CurrentSource::Spindle,
            _ => {
                return Err(ctx.err(
                    &m.source,
                    format!("unknown current source `{}`", m.source.value),
                    "feed_axis or spindle",
                ))
            }
        };
        actions.push(Input::MotorCurrent { source, percent: m.percent });
    }
    if let Some(p) = &v.plc_answer {
        let answer = match p.answer.value.as_str() {
            "position_mode_reached" => PlcAnswer::PositionModeReached,
            "fin" => PlcAnswer::Fin,
            "rgtap" => PlcAnswer::Rgtap,
            "zero_speed" => PlcAnswer::ZeroSpeed,
            _ => {
                return Err(ctx.err(
                    &p.answer,
                    format!("unknown PLC answer `{}`", p.answer.value),
                    "position_mode_reached, fin, rgtap or zero_speed",
                ))
            }
        };
        let extra_us = match (p.late_ms, p.never) {
            (Some(ms), None | Some(false)) => Some(ms_to_us(ms)),
            (None, Some(true)) => None,
            _ => {
                return Err(ctx.err(
                    &p.answer,
                    "a PLC answer fault has exactly one of `late_ms` and `never: true`",
                    "late_ms: 200, or never: true",
                ))
            }
        };
        actions.push(Input::PlcAnswer { answer, extra_us });
    }
    if let Some(sp) = &v.set_param {
        let axis = match &sp.axis {
            Some(a) => Some(ctx.axis(a)?.letter),
            None => None,
        };
        actions.push(Input::SetParam { id: sp.id.value.clone(), axis, value: sp.value });
    }
    match actions.len() {
        1 => Ok((trigger, actions.pop().unwrap())),
        _ => Err(ctx.err(
            e,
            format!("an input has exactly one action, this one has {}", actions.len()),
            "one of cycle_start, reset, feed_hold, single_block, dry_run, machine_lock, optional_stop, feed_override, spindle_override, emergency_stop, motor_current, plc_answer, spindle_stall, set_param",
        )),
    }
}

/// The diagram of the snapshot: the file's choice, or the rigid tapping signals and every axis.
fn diagram(ctx: &Ctx, file: &ScenarioFile) -> Result<DiagramSpec, InputError> {
    let default_signals =
        [Signal::Mf, Signal::Fin, Signal::Rtap, Signal::Rgtap, Signal::Rgspp, Signal::Rgspm, Signal::Spl];
    let Some(s) = &file.snapshot else {
        return Ok(DiagramSpec {
            signals: default_signals.to_vec(),
            axes: ctx.axes.iter().filter(|a| !a.rotary).copied().collect(),
            spindle: true,
            width: 100,
            from_us: None,
            to_us: None,
        });
    };
    let signals = if s.signals.is_empty() {
        default_signals.to_vec()
    } else {
        s.signals.iter().map(|n| ctx.signal(n)).collect::<Result<_, _>>()?
    };
    let axes = s.axes.iter().map(|a| ctx.axis(a)).collect::<Result<_, _>>()?;
    Ok(DiagramSpec {
        signals,
        axes,
        spindle: s.spindle,
        width: s.width.unwrap_or(100).clamp(10, 400) as usize,
        from_us: s.from_ms.map(ms_to_us),
        to_us: s.to_ms.map(ms_to_us),
    })
}
