//! Recorded traces derived from reference runs, for the tests of `nc-conform check`: a defect
//! is a mutation of the reference trace (a hold inserted, time compressed, an edge moved, a
//! function dropped, ...), then the trace is "recorded": stripped of what a control does not
//! report (phases, inputs, blocks, the end line), shifted in time, resampled at another period,
//! jittered, noised and thinned.
#![allow(dead_code)]

use std::path::Path;

use nc_conform::check::reference::unwrap_delta;
use nc_conform::scenario::load::{self, Scenario};
use nc_engine::trace::{Event, Phase, Sample, Signal, Trace, TraceEvent};

/// Loads a scenario of the library (path relative to the workspace root).
pub fn scenario(rel: &str) -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(rel);
    load::load(&path, rel).unwrap_or_else(|e| panic!("{rel}: {}", e.headline()))
}

/// Loads a scenario with its text changed by `edit` (a defective program or schedule).
pub fn scenario_edited(rel: &str, edit: impl Fn(&str) -> String) -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(rel);
    let text = std::fs::read_to_string(&path).expect("scenario");
    let edited = edit(&text);
    assert_ne!(edited, text, "the edit changed nothing");
    load::load_text(&edited, rel, path.parent().unwrap())
        .unwrap_or_else(|e| panic!("{rel}: {}", e.headline()))
}

/// The reference trace of a scenario.
pub fn reference(s: &Scenario) -> Trace {
    s.machine.run_to_trace(&s.program, &s.opts)
}

/// How a trace is "recorded".
#[derive(Debug, Clone, Copy)]
pub struct Rec {
    /// Added to every time (the recorder's clock starts elsewhere).
    pub shift_us: u64,
    /// Sample period of the recorder (0: the samples as they are).
    pub sample_us: u64,
    /// Sample time stamps jittered by up to ± this (values at the true time).
    pub jitter_us: u64,
    /// Position noise, ± nm.
    pub noise_nm: i64,
    /// Angle noise, ± milli-degrees.
    pub noise_mdeg: i64,
    /// Drop one sample in this many (0: none).
    pub drop_one_in: u64,
    /// Discrete events rounded up to this scan period (0: exact).
    pub scan_us: u64,
    /// Discrete events later still by this (a PLC's scan plus its export latency): with
    /// `scan_us` = 6 ms and `late_us` = 2 ms every edge comes 2–8 ms late, in its order.
    pub late_us: u64,
}

impl Rec {
    /// Exactly the reference's events (phases, inputs and blocks stripped), no shift.
    pub const EXACT: Rec = Rec {
        shift_us: 0,
        sample_us: 0,
        jitter_us: 0,
        noise_nm: 0,
        noise_mdeg: 0,
        drop_one_in: 0,
        scan_us: 0,
        late_us: 0,
    };
    /// A realistic recorder: another clock, 4 ms samples with ± 300 µs jitter, 1 µm and 0.05°
    /// noise, one sample in 40 lost, a 1 ms PLC scan.
    pub const REALISTIC: Rec = Rec {
        shift_us: 3_712_345,
        sample_us: 4000,
        jitter_us: 300,
        noise_nm: 1000,
        noise_mdeg: 50,
        drop_one_in: 40,
        scan_us: 1000,
        late_us: 0,
    };
    /// A PLC-scan recorder: as [`Rec::REALISTIC`], but every edge, function and alarm 2–8 ms
    /// late (a 6 ms scan and 2 ms of latency).
    pub const PLC_SCAN: Rec = Rec { scan_us: 6000, late_us: 2000, ..Rec::REALISTIC };
}

/// A small deterministic generator.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        self.0 >> 33
    }
    fn pm(&mut self, a: i64) -> i64 {
        if a == 0 {
            0
        } else {
            (self.next() % (2 * a as u64 + 1)) as i64 - a
        }
    }
}

/// The sample at `t`, interpolated between the samples around it.
pub fn sample_at(samples: &[(u64, Sample)], t: u64) -> Sample {
    let k = samples.partition_point(|s| s.0 <= t);
    if k == 0 {
        return samples[0].1;
    }
    let (t0, a) = samples[k - 1];
    let Some(&(t1, b)) = samples.get(k) else { return a };
    let f = (t - t0) as f64 / (t1 - t0).max(1) as f64;
    let mut s = a;
    for i in 0..s.axes.len() {
        s.axes[i] = a.axes[i] + ((b.axes[i] - a.axes[i]) as f64 * f).round() as i64;
    }
    s.spindle_mrpm = a.spindle_mrpm + ((b.spindle_mrpm - a.spindle_mrpm) as f64 * f).round() as i64;
    let d = unwrap_delta(a.spindle_mdeg, a.spindle_mrpm, b.spindle_mdeg, b.spindle_mrpm, (t1 - t0) as i64);
    s.spindle_mdeg = (a.spindle_mdeg + (d * f).round() as i64).rem_euclid(360_000);
    s
}

/// The recorded stream of `trace`.
pub fn record(trace: &Trace, rec: Rec) -> Vec<TraceEvent> {
    let samples: Vec<(u64, Sample)> = trace.samples().map(|(t, s)| (t, *s)).collect();
    let mut out: Vec<(u64, u8, TraceEvent)> = Vec::new();
    let mut rng = Lcg(0x5eed);
    for e in &trace.events {
        match e.event {
            Event::Sample(_)
            | Event::Phase(_)
            | Event::Input { .. }
            | Event::Block { .. }
            | Event::End(_) => {}
            _ => {
                let t = if rec.scan_us > 0 { e.t_us.div_ceil(rec.scan_us) * rec.scan_us } else { e.t_us };
                let t = t + rec.late_us;
                out.push((
                    t + rec.shift_us,
                    1,
                    TraceEvent { t_us: t + rec.shift_us, event: e.event.clone() },
                ));
            }
        }
    }
    let end = trace.events.last().map_or(0, |e| e.t_us);
    let times: Vec<u64> = match end.checked_div(rec.sample_us) {
        None => samples.iter().map(|s| s.0).collect(),
        Some(n) => (0..=n).map(|k| k * rec.sample_us).collect(),
    };
    for (n, t) in times.into_iter().enumerate() {
        if rec.drop_one_in > 0 && rng.next().is_multiple_of(rec.drop_one_in) && n > 0 {
            continue;
        }
        if samples.is_empty() {
            break;
        }
        let mut s = sample_at(&samples, t);
        for a in s.axes.iter_mut() {
            *a += rng.pm(rec.noise_nm);
        }
        s.spindle_mdeg = (s.spindle_mdeg + rng.pm(rec.noise_mdeg)).rem_euclid(360_000);
        let stamp = (t + rec.shift_us).saturating_add_signed(rng.pm(rec.jitter_us as i64));
        out.push((stamp, 0, TraceEvent { t_us: stamp, event: Event::Sample(s) }));
    }
    out.sort_by_key(|e| (e.0, e.1));
    out.into_iter().map(|e| e.2).collect()
}

/// The intervals of a phase in the reference.
pub fn phase_spans(trace: &Trace, phase: Phase) -> Vec<(u64, u64)> {
    let ph: Vec<(u64, Phase)> = trace.phases().collect();
    let end = trace.events.last().map_or(0, |e| e.t_us);
    ph.iter()
        .enumerate()
        .filter(|(_, p)| p.1 == phase)
        .map(|(k, p)| (p.0, ph.get(k + 1).map_or(end, |n| n.0)))
        .collect()
}

/// Re-times every event by `f` (samples and events alike), keeping the order.
pub fn warp(trace: &Trace, f: impl Fn(u64) -> Option<u64>) -> Trace {
    let mut events: Vec<TraceEvent> = trace
        .events
        .iter()
        .filter_map(|e| f(e.t_us).map(|t| TraceEvent { t_us: t, event: e.event.clone() }))
        .collect();
    events.sort_by_key(|e| e.t_us);
    Trace { meta: trace.meta.clone(), events }
}

/// A controller that honours a feed hold `hold` µs long at `at` (where the reference does not):
/// everything after `at` comes `hold` later, the machine stands still meanwhile with the
/// spindle stopped, STL off and SPL on.
pub fn feed_hold_at(reference: &Trace, at: u64, hold: u64) -> Trace {
    let mut t = warp(reference, |x| Some(if x > at { x + hold } else { x }));
    let mut frozen = sample_before(reference, at);
    frozen.spindle_mrpm = 0;
    let ev = |t_us, event| TraceEvent { t_us, event };
    let sig = |signal, value| Event::Signal { signal, value };
    insert(
        &mut t,
        vec![
            ev(at, Event::Sample(frozen)),
            ev(at, sig(Signal::Stl, false)),
            ev(at, sig(Signal::Spl, true)),
            ev(at + hold, Event::Sample(frozen)),
            ev(at + hold, sig(Signal::Spl, false)),
            ev(at + hold, sig(Signal::Stl, true)),
        ],
    );
    t
}

/// Inserts events into a trace, in time order (after those already at the same time).
pub fn insert(trace: &mut Trace, new: Vec<TraceEvent>) {
    trace.events.extend(new);
    trace.events.sort_by_key(|e| e.t_us);
}

/// The first edge of `signal` to `value` at or after `from`.
pub fn edge_time(trace: &Trace, signal: Signal, value: bool, from: u64) -> u64 {
    trace.edges(signal).find(|&(t, v)| v == value && t >= from).map(|e| e.0).expect("edge")
}

/// The last sample at or before `t`.
pub fn sample_before(trace: &Trace, t: u64) -> Sample {
    *trace.samples().take_while(|s| s.0 <= t).last().expect("sample").1
}

/// Runs a check with the scenario's expectations and rules and the default tolerances.
pub fn check(s: &Scenario, reference: &Trace, recorded: Vec<TraceEvent>) -> nc_conform::check::Report {
    let spec = nc_conform::check::CheckSpec {
        expect: Some(&s.expect),
        rules: s.rules.clone(),
        ..Default::default()
    };
    nc_conform::check::check(reference, recorded, &spec)
}

/// The summary of a report, for failure messages.
pub fn show(r: &nc_conform::check::Report, reference: &Trace) -> String {
    nc_conform::check::report::summary(r, reference, "check")
}
