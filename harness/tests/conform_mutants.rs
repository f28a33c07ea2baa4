//! Mutation proof of the conformance suite: deliberately defective controllers, each a mutant
//! of the reference (it changes the parameters it obeys, the inputs it heeds, the program it
//! reads or the trace it reports), must each be killed by the bundled scenarios, and the
//! failure must name a rule of the expected family. A mutant that survives means a scenario is
//! missing.
//!
//! To stay small for CI each mutant runs only on the scenario directories where its defect
//! shows (listed with it), not on the whole library.

use std::path::PathBuf;

use nc_conform::conform::reference::Reference;
use nc_conform::conform::suite::{run_one, scenario_files};
use nc_conform::conform::{Advanced, Controller, ControllerError, Identity, Job, Loaded, ParamValue};
use nc_engine::input::{Condition, CurrentSource, Input};
use nc_engine::trace::{Event, Signal, TraceEvent};
use nc_engine::units::Micros;

/// A trace rewriter with its own state (one per run).
type Rewrite = Box<dyn FnMut(TraceEvent) -> Option<TraceEvent>>;

/// What is wrong with a mutant.
#[derive(Clone, Copy)]
enum Defect {
    /// It runs with these parameter values whatever it is told (on this dialect).
    Force(&'static str, &'static [(&'static str, Option<char>, f64)]),
    /// It ignores the inputs this picks.
    Deaf(fn(&Input) -> bool),
    /// It reads the program differently.
    Reads(fn(&str) -> String),
    /// It reports its trace through this rewriter.
    Reports(fn() -> Rewrite),
    /// It runs programs the reference refuses, leaving out the refused lines.
    Lenient,
}

/// A defective controller: the reference with one defect.
struct Mutant {
    inner: Reference,
    defect: Defect,
    rewrite: Option<Rewrite>,
}

impl Mutant {
    fn new(defect: Defect) -> Self {
        Mutant { inner: Reference::new(), defect, rewrite: None }
    }
}

impl Controller for Mutant {
    fn identity(&mut self) -> Result<Identity, ControllerError> {
        self.inner.identity()
    }

    fn load(&mut self, job: &Job) -> Result<Loaded, ControllerError> {
        let mut job = job.clone();
        self.rewrite = None;
        match self.defect {
            Defect::Force(dialect, values) if job.dialect == dialect => {
                for &(id, axis, value) in values {
                    job.params.retain(|p| !(p.id == id && p.axis == axis));
                    job.params.push(ParamValue { id: id.into(), axis, value });
                }
            }
            Defect::Reads(f) => job.program = f(&job.program),
            Defect::Reports(f) => self.rewrite = Some(f()),
            Defect::Lenient => {
                for _ in 0..8 {
                    match self.inner.load(&job)? {
                        Loaded::Refused { line, .. } => {
                            let kept: Vec<&str> = job
                                .program
                                .lines()
                                .enumerate()
                                .map(|(i, l)| if i + 1 == line as usize { "" } else { l })
                                .collect();
                            job.program = kept.join("\n");
                        }
                        other => return Ok(other),
                    }
                }
            }
            _ => {}
        }
        self.inner.load(&job)
    }

    fn input(&mut self, t_us: Micros, input: &Input) -> Result<(), ControllerError> {
        match self.defect {
            Defect::Deaf(f) if f(input) => Ok(()),
            _ => self.inner.input(t_us, input),
        }
    }

    fn advance(&mut self, until_us: Micros, stop_on: &[Condition]) -> Result<Advanced, ControllerError> {
        self.inner.advance(until_us, stop_on)
    }

    fn read(&mut self) -> Result<Vec<TraceEvent>, ControllerError> {
        let events = self.inner.read()?;
        Ok(match self.rewrite.as_mut() {
            Some(f) => events.into_iter().filter_map(f).collect(),
            None => events,
        })
    }
}

// ---------------------------------------------------------------------------------------------
// Trace rewriters

/// After a reset the spindle stays in position mode: RGSPP/RGSPM/SPPOS never fall again.
fn reset_keeps_position_mode() -> Rewrite {
    let mut reset = false;
    let held = [Signal::Rgspp, Signal::Rgspm, Signal::Sppos];
    Box::new(move |mut e| {
        match &mut e.event {
            Event::Input { name, .. } if name == "reset" => reset = true,
            Event::Signal { signal, value: false } if reset && held.contains(signal) => return None,
            Event::End(end) if reset => end.signals.set(Signal::Rgspp, true),
            _ => {}
        }
        Some(e)
    })
}

/// The tap axis (Z) runs 2 % long while cutting: a lead error.
fn lead_error() -> Rewrite {
    let mut cutting = false;
    let mut start: Option<i64> = None;
    Box::new(move |mut e| {
        match &mut e.event {
            Event::Phase(p) => {
                cutting = p.name() == "cutting";
                start = None;
            }
            Event::Sample(s) if cutting => {
                let z0 = *start.get_or_insert(s.axes[2]);
                s.axes[2] += (s.axes[2] - z0) / 50;
            }
            _ => {}
        }
        Some(e)
    })
}

/// Alarms are not reported (the control stops without saying why).
fn silent_alarms() -> Rewrite {
    Box::new(|e| (!matches!(e.event, Event::Alarm(_))).then_some(e))
}

/// Samples are stamped one interpolation period late.
fn late_samples() -> Rewrite {
    Box::new(|mut e| {
        if matches!(e.event, Event::Sample(_)) {
            e.t_us += 1000;
        }
        Some(e)
    })
}

/// The end summary leaves out the last modal group.
fn short_modal_list() -> Rewrite {
    Box::new(|mut e| {
        if let Event::End(end) = &mut e.event {
            end.modal.pop();
        }
        Some(e)
    })
}

/// Phase changes are not reported.
fn no_phases() -> Rewrite {
    Box::new(|e| (!matches!(e.event, Event::Phase(_))).then_some(e))
}

/// Incremental words U and W read as the absolute X and Z.
fn incremental_as_absolute(p: &str) -> String {
    p.replace('U', "X").replace('W', "Z")
}

/// G98 and G99 swapped.
fn swap_return_levels(p: &str) -> String {
    p.replace("G98", "G9#").replace("G99", "G98").replace("G9#", "G99")
}

/// Rewrites every word (a letter and the number after it) through `f`; `None` drops the word.
fn map_words(p: &str, mut f: impl FnMut(char, &str) -> Option<String>) -> String {
    let mut out = String::with_capacity(p.len());
    let mut chars = p.chars().peekable();
    while let Some(c) = chars.next() {
        if !c.is_ascii_alphabetic() {
            out.push(c);
            continue;
        }
        let mut number = String::new();
        while let Some(&d) = chars.peek() {
            if !(d.is_ascii_digit() || matches!(d, '.' | '-' | '+')) {
                break;
            }
            number.push(d);
            chars.next();
        }
        if let Some(w) = f(c.to_ascii_uppercase(), &number) {
            out.push_str(&w);
        }
    }
    out
}

/// G92.3: the lead change D is not read (a constant lead).
fn no_lead_change(p: &str) -> String {
    map_words(p, |c, n| (c != 'D').then(|| format!("{c}{n}")))
}

/// G92.3: the run-out words J and K are not read (no run-out).
fn no_runout(p: &str) -> String {
    map_words(p, |c, n| (!matches!(c, 'J' | 'K')).then(|| format!("{c}{n}")))
}

/// G92.3 cuts `(F − E − A) / Q` passes, without the `+ 1`: as if the tool were Q wider (the
/// programs this runs on give A and Q with a decimal point, in the same block).
fn one_pass_less(p: &str) -> String {
    p.lines()
        .map(|line| {
            let mut q = 0.0;
            map_words(line, |c, n| {
                if c == 'Q' {
                    q = n.parse().unwrap_or(0.0);
                }
                Some(String::new())
            });
            map_words(line, |c, n| match (c, n.parse::<f64>()) {
                ('A', Ok(a)) => Some(format!("A{:.4}", a + q)),
                _ => Some(format!("{c}{n}")),
            })
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// G92.3: a zero axial step Q is not refused but taken as the largest (a single pass).
fn zero_step_accepted(p: &str) -> String {
    map_words(p, |c, n| match (c, n.parse::<f64>()) {
        ('Q', Ok(0.0)) => Some("Q9999.".into()),
        _ => Some(format!("{c}{n}")),
    })
}

/// G92.3: the threads per inch I read as a lead F in mm (no 25.4 / I).
fn inch_count_as_lead(p: &str) -> String {
    map_words(p, |c, n| Some(format!("{}{n}", if c == 'I' { 'F' } else { c })))
}

/// G92.3: the taper R is not read (a straight thread).
fn no_taper(p: &str) -> String {
    map_words(p, |c, n| (c != 'R').then(|| format!("{c}{n}")))
}

// ---------------------------------------------------------------------------------------------
// The mutants

struct Case {
    name: &'static str,
    defect: Defect,
    /// Scenario paths (under scenarios/) containing one of these are run.
    scenarios: &'static [&'static str],
    /// The failure must name a rule of one of these families.
    families: &'static [&'static str],
}

const MAX: f64 = 100_000.0;

fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "feed hold honoured mid-tap (Fanuc FHD forced)",
            defect: Defect::Force("fanuc-mill", &[("5200.6", None, 1.0)]),
            scenarios: &["fanuc/feed_hold/"],
            families: &["FAN-RT"],
        },
        Case {
            name: "feed hold ignored",
            defect: Defect::Deaf(|i| *i == Input::FeedHold),
            scenarios: &["gsk/feed_hold/"],
            families: &["GSK-RT", "COM-INP"],
        },
        Case {
            name: "dry run ignored",
            defect: Defect::Deaf(|i| matches!(i, Input::DryRun(_))),
            scenarios: &["gsk/dry_run/"],
            families: &["GSK-RT", "COM-INP"],
        },
        Case {
            name: "machine lock ignored",
            defect: Defect::Deaf(|i| matches!(i, Input::MachineLock(_))),
            scenarios: &["gsk/machine_lock/"],
            families: &["GSK-RT", "COM-INP"],
        },
        Case {
            name: "no overload retract",
            defect: Defect::Deaf(|i| {
                matches!(i, Input::MotorCurrent { source: CurrentSource::FeedAxis, .. })
            }),
            scenarios: &["gsk/overload/"],
            families: &["GSK-RT"],
        },
        Case {
            name: "reset leaves the spindle in position mode",
            defect: Defect::Reports(reset_keeps_position_mode),
            scenarios: &["gsk/reset/"],
            families: &["GSK-RT", "COM-INP"],
        },
        Case {
            name: "RGTAP not awaited after cancel (RTCRG forced 1)",
            defect: Defect::Force("gsk-lathe", &[("186.2", None, 1.0)]),
            scenarios: &["gsk/cancel/"],
            families: &["GSK-RT"],
        },
        Case {
            name: "wrong peck retract (5213 forced 3 mm)",
            defect: Defect::Force("fanuc-mill", &[("5213", None, 3.0)]),
            scenarios: &["fanuc/rigid/peck"],
            families: &["FAN-RT", "FAN-CYC"],
        },
        Case {
            name: "clamp M code missing (170 forced 0)",
            defect: Defect::Force("gsk-lathe", &[("170", None, 0.0)]),
            scenarios: &["gsk/clamp/"],
            families: &["GSK-RT"],
        },
        Case {
            name: "G98/G99 return level swapped",
            defect: Defect::Reads(swap_return_levels),
            scenarios: &["fanuc/return_level/", "fanuc/initial_level/"],
            families: &["FAN-CYC", "FAN-RT"],
        },
        Case {
            name: "KND reversal before the spindle stops (no zero-speed wait)",
            defect: Defect::Force(
                "knd-lathe",
                &[("plc.zsp_ms", None, 0.0), ("nc.spindle_brake_ms", None, 0.0)],
            ),
            scenarios: &["knd/g93/standard", "knd/g93/never_retracts_zero_speed"],
            families: &["KND-G93"],
        },
        Case {
            name: "KND reversal without backlash take-up (RVDL forced 0)",
            defect: Defect::Force("knd-lathe", &[("003.RVDL", None, 0.0)]),
            scenarios: &["knd/g93/never_retracts_backlash"],
            families: &["KND-G93"],
        },
        Case {
            name: "no M29 answer timer (alarm 5002 never)",
            defect: Defect::Force("gsk-lathe", &[("plc.m29_timeout_ms", None, MAX)]),
            scenarios: &["gsk/m29/", "common/plc/"],
            families: &["GSK-RT", "COM-PLC"],
        },
        Case {
            name: "no FIN timer (NC-1020 never)",
            defect: Defect::Force("gsk-lathe", &[("plc.fin_timeout_ms", None, MAX)]),
            scenarios: &["common/plc/fin_never"],
            families: &["COM-PLC"],
        },
        Case {
            name: "no spindle stall timer (5074 never)",
            defect: Defect::Force("gsk-lathe", &[("plc.spindle_stall_ms", None, MAX)]),
            scenarios: &["common/inp/spindle_slow_stall"],
            families: &["COM-INP", "COM-PLC", "GSK-RT"],
        },
        Case {
            name: "emergency stop ignored",
            defect: Defect::Deaf(|i| matches!(i, Input::EmergencyStop(_))),
            scenarios: &["common/inp/"],
            families: &["COM-INP"],
        },
        Case {
            name: "single block ignored",
            defect: Defect::Deaf(|i| matches!(i, Input::SingleBlock(_))),
            scenarios: &["gsk/single_block/"],
            families: &["GSK-RT", "COM-INP"],
        },
        Case {
            name: "backlash not compensated (34.Z forced 0)",
            defect: Defect::Force("gsk-lathe", &[("34", Some('Z'), 0.0)]),
            scenarios: &["gsk/backlash/"],
            families: &["COM-MOT", "GSK-RT"],
        },
        Case {
            name: "lead error of 2 % in the cut",
            defect: Defect::Reports(lead_error),
            scenarios: &["common/sync/"],
            families: &["COM-SYNC"],
        },
        Case {
            name: "alarms not reported",
            defect: Defect::Reports(silent_alarms),
            scenarios: &["fanuc/alarms/02"],
            families: &["FAN-RT"],
        },
        Case {
            name: "samples stamped a period late",
            defect: Defect::Reports(late_samples),
            scenarios: &["common/time/sample_shows"],
            families: &["COM-TIME"],
        },
        Case {
            name: "orientation before tapping skipped (RTORI forced 0)",
            defect: Defect::Force("gsk-lathe", &[("186.7", None, 0.0)]),
            scenarios: &["gsk/orientation/"],
            families: &["GSK-RT"],
        },
        Case {
            name: "G84 rigid without M29 not supported (5200.0 forced 0)",
            defect: Defect::Force("fanuc-mill", &[("5200.0", None, 0.0)]),
            scenarios: &["fanuc/rigid/param_5200_0"],
            families: &["FAN-RT"],
        },
        Case {
            name: "extraction override ignored (5211 forced 100)",
            defect: Defect::Force("fanuc-mill", &[("5211", None, 100.0)]),
            scenarios: &["fanuc/rigid/extraction_override"],
            families: &["FAN-RT"],
        },
        Case {
            name: "lenient parser (runs what it should refuse)",
            defect: Defect::Lenient,
            scenarios: &["common/parse/"],
            families: &["COM-PARSE"],
        },
        Case {
            name: "lenient KND parser",
            defect: Defect::Lenient,
            scenarios: &["common/parse/macro_variable_refused_knd"],
            families: &["COM-PARSE"],
        },
        Case {
            name: "GSK words without decimal point read in increments (nc.dpi forced 0)",
            defect: Defect::Force("gsk-lathe", &[("nc.dpi", None, 0.0)]),
            scenarios: &["gsk/lex/"],
            families: &["GSK-LEX"],
        },
        Case {
            name: "Fanuc words without decimal point read in increments (3401.0 forced 0)",
            defect: Defect::Force("fanuc-mill", &[("3401.0", None, 0.0)]),
            scenarios: &["fanuc/words/"],
            families: &["FAN-LEX"],
        },
        Case {
            name: "KND U/W read as absolute X/Z",
            defect: Defect::Reads(incremental_as_absolute),
            scenarios: &["knd/lex/"],
            families: &["KND-LEX"],
        },
        Case {
            name: "end summary without the last modal group",
            defect: Defect::Reports(short_modal_list),
            scenarios: &["fanuc/modal/"],
            families: &["FAN-MOD"],
        },
        Case {
            name: "phase changes not reported",
            defect: Defect::Reports(no_phases),
            scenarios: &["common/trace/"],
            families: &["COM-TRACE"],
        },
        Case {
            name: "G92.3 feed hold always finishes the pass (nc.thread_retract forced 0)",
            defect: Defect::Force("gsk-lathe", &[("nc.thread_retract", None, 0.0)]),
            scenarios: &["gsk/g92_3/feed_hold_thread_retract"],
            families: &["GSK-G923"],
        },
        Case {
            name: "G92.3 feed hold always retracts (nc.thread_retract forced 1)",
            defect: Defect::Force("gsk-lathe", &[("nc.thread_retract", None, 1.0)]),
            scenarios: &["gsk/g92_3/feed_hold_finishes_the_pass"],
            families: &["GSK-G923"],
        },
        Case {
            name: "G92.3 lead change D ignored (constant lead)",
            defect: Defect::Reads(no_lead_change),
            scenarios: &["gsk/g92_3/lead_shrinks_d_negative", "gsk/g92_3/seed_example"],
            families: &["GSK-G923"],
        },
        Case {
            name: "G92.3 run-out J/K ignored",
            defect: Defect::Reads(no_runout),
            scenarios: &["gsk/g92_3/seed_example"],
            families: &["GSK-G923"],
        },
        Case {
            name: "G92.3 pass count (F-E-A)/Q without the +1",
            defect: Defect::Reads(one_pass_less),
            scenarios: &["gsk/g92_3/pass_count_rounded_up", "gsk/g92_3/seed_example"],
            families: &["GSK-G923"],
        },
        Case {
            name: "G92.3 Q0 accepted (NC-1063 never)",
            defect: Defect::Reads(zero_step_accepted),
            scenarios: &["gsk/g92_3/step_q_zero_nc1063"],
            families: &["GSK-G923"],
        },
        Case {
            name: "G92.3 single block ignored",
            defect: Defect::Deaf(|i| matches!(i, Input::SingleBlock(_))),
            scenarios: &["gsk/g92_3/single_block_every_pass"],
            families: &["GSK-G923"],
        },
        Case {
            name: "G92.3 threads per inch I read as a lead in mm",
            defect: Defect::Reads(inch_count_as_lead),
            scenarios: &["gsk/g92_3/taper_inch_i", "gsk/g92_3/straight_inch_i_lead"],
            families: &["GSK-G923"],
        },
        Case {
            name: "G92.3 taper R ignored (a straight thread)",
            defect: Defect::Reads(no_taper),
            scenarios: &["gsk/g92_3/taper_inch_i"],
            families: &["GSK-G923"],
        },
        Case {
            name: "cycle 832 air cuts Q476 not made",
            defect: Defect::Reads(no_air_cuts),
            scenarios: &["heidenhain/c832/multi_start_air_cuts"],
            families: &["HDH-C832"],
        },
        Case {
            name: "cycle 832 multi-start Q475 cut as one start",
            defect: Defect::Reads(one_start),
            scenarios: &["heidenhain/c832/multi_start_air_cuts"],
            families: &["HDH-C832"],
        },
        Case {
            name: "cycle 832 infeed angle not checked against the flank (hei.flank_angle_deg forced 90)",
            defect: Defect::Force("heidenhain", &[("hei.flank_angle_deg", None, 90.0)]),
            scenarios: &["heidenhain/c832/caution_infeed_above_flank"],
            families: &["HDH-C832"],
        },
        Case {
            name: "cycle 832 negative-diameter pre-position not checked (hei.neg_diameter_alarm forced 0)",
            defect: Defect::Force("heidenhain", &[("hei.neg_diameter_alarm", None, 0.0)]),
            scenarios: &["heidenhain/c832/caution_negative_diameter"],
            families: &["HDH-C832"],
        },
        Case {
            name: "LinuxCNC G84 under G98 returns to R (Fanuc habit)",
            defect: Defect::Reads(swap_return_levels),
            scenarios: &["linuxcnc/cycles/g84_g98_orderings"],
            families: &["LCNC-CYC", "LCNC-TAP"],
        },
        Case {
            name: "LinuxCNC canned cycle repeats L ignored",
            defect: Defect::Reads(no_repeats),
            scenarios: &["linuxcnc/cycles/g84_g98_orderings"],
            families: &["LCNC-CYC", "LCNC-TAP"],
        },
        Case {
            name: "LinuxCNC G33.1 overshoot not limited (nc.rigid_overshoot_pitches forced 100)",
            defect: Defect::Force("linuxcnc", &[("nc.rigid_overshoot_pitches", None, 100.0)]),
            scenarios: &["linuxcnc/g331/overshoot"],
            families: &["LCNC-G331"],
        },
        Case {
            name: "LinuxCNC G76 spring passes H ignored",
            defect: Defect::Reads(no_spring_passes),
            scenarios: &["linuxcnc/g76/passes"],
            families: &["LCNC-G76"],
        },
    ]
}

/// Cycle 832: the value of Klartext parameter `q` (e.g. `Q476=`) replaced by `value` wherever it
/// is set.
fn set_q(p: &str, q: &str, value: &str) -> String {
    let mut out = String::with_capacity(p.len());
    let mut rest = p;
    while let Some(i) = rest.find(q) {
        let (head, tail) = rest.split_at(i + q.len());
        out.push_str(head);
        let end =
            tail.find(|c: char| !(c.is_ascii_digit() || matches!(c, '+' | '-' | '.'))).unwrap_or(tail.len());
        out.push_str(value);
        rest = &tail[end..];
    }
    out.push_str(rest);
    out
}

/// Cycle 832: air cuts Q476 not made.
fn no_air_cuts(p: &str) -> String {
    set_q(p, "Q476=", "+0")
}

/// Cycle 832: one start whatever Q475 says.
fn one_start(p: &str) -> String {
    set_q(p, "Q475=", "+1")
}

/// LinuxCNC: the repeat count L of a canned cycle is not read.
fn no_repeats(p: &str) -> String {
    map_words(p, |c, n| (c != 'L').then(|| format!("{c}{n}")))
}

/// LinuxCNC G76: spring passes H are not read.
fn no_spring_passes(p: &str) -> String {
    map_words(p, |c, n| (c != 'H').then(|| format!("{c}{n}")))
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The scenario files (path, name) whose name contains one of `wanted`.
fn matching(wanted: &[&str]) -> Vec<(PathBuf, String)> {
    scenario_files(&root().join("scenarios"))
        .into_iter()
        .map(|p| {
            let name = p.strip_prefix(root()).unwrap().display().to_string().replace('\\', "/");
            (p, name)
        })
        .filter(|(_, name)| wanted.iter().any(|s| name.contains(s)))
        .collect()
}

#[test]
fn every_mutant_is_killed_and_the_rule_named() {
    let dialects = Reference::new().identity().unwrap().dialects;
    let cases = cases();
    let mut survivors = Vec::new();
    let mut killed = 0;
    for case in &cases {
        let files = matching(case.scenarios);
        assert!(!files.is_empty(), "{}: no scenario matches {:?}", case.name, case.scenarios);
        let mut kills = Vec::new();
        for (p, name) in &files {
            let v = run_one(&mut Mutant::new(case.defect), &dialects, p, name).unwrap();
            if v.failed() {
                let rules: Vec<&str> = v.failures.iter().map(|f| f.rule.as_str()).collect();
                kills.push((name, rules.join(" "), case.families.iter().any(|f| v.names_family(f))));
            }
        }
        if let Some(k) = kills.iter().find(|k| k.2) {
            killed += 1;
            eprintln!("killed  {} by {} ({})", case.name, k.0, k.1);
        } else {
            survivors.push(format!("{} survived {} scenarios (failures: {kills:?})", case.name, files.len()));
        }
    }
    eprintln!("kill rate: {killed}/{}", cases.len());
    assert!(cases.len() >= 20);
    assert!(survivors.is_empty(), "{}", survivors.join("\n"));
}

#[test]
fn the_unmutated_reference_passes_the_mutant_scenarios() {
    // The control group: the kills above are the defects', not the harness'.
    let dialects = Reference::new().identity().unwrap().dialects;
    let wanted: Vec<&str> = cases().iter().flat_map(|c| c.scenarios.iter().copied()).collect();
    for (p, name) in matching(&wanted) {
        let v = run_one(&mut Reference::new(), &dialects, &p, &name).unwrap();
        assert!(!v.failed(), "{name}: {}", v.failure_text());
    }
}
