//! Physical plausibility (`INV-11`..`INV-14`, `docs/invariants.md`): what the machine's axes and
//! spindle can do between two consecutive samples of any run, judged by the machine's own limits
//! ([`Limits`], from its plant configuration).
//!
//! - INV-11 `axis_limits`: no axis exceeds its speed limit (its rapid rate or the maximum cutting
//!   feed, whichever is higher) or its acceleration (rate / time constant; in a rigid tapping
//!   stroke the profile the dialect documents: the rigid tapping time constant × the lead);
//! - INV-12 `spindle_ramp`: no spindle speed change exceeds its ramp (speed mode) or the rigid
//!   tapping time constant (position mode), and no speed exceeds its maximum;
//! - INV-13 `spindle_angle_integral`: the spindle's angle advances by the integral of its speed;
//! - INV-14 `follows_spindle`: an axis locked to a spindle in speed mode (KND G93, LinuxCNC G33.1)
//!   never runs ahead of lead × spindle speed (it catches up within INV-11's limit).
//!
//! The tolerance is one interpolation period of quantisation: a control changes its commands
//! once per period, so a speed may be one period's worth of acceleration ahead of a smooth ramp
//! (and a following axis one period's worth of travel ahead of its spindle), once; beyond that
//! every excess accumulates and is caught. Rounding of the trace (1 nm, 1 mrpm, 1 mdeg) is added.
//!
//! Named exemptions, each because the fault breaks physics by design: a spindle stall (the angle
//! freezes, and an axis following its encoder stops with it: COM-INP-09, KND-G93-11) and an
//! emergency stop (the servos are cut: the machine is stopped at once in this model). From the
//! moment either acts, nothing more is checked. Nothing else is exempt.

use super::{violation, Invariant, TapSpec, Violation};
use crate::exec::PlantConfig;
use crate::trace::{Event, Sample, Signal, Signals, Trace, AXES};
use crate::units::{Micros, Nm};
use crate::Machine;

/// Milli-degrees per µs at 1 rpm.
const MDEG_PER_US_PER_RPM: f64 = 360_000.0 / 60e6;

/// A machine's physical limits, in the trace's units (nm, µs, rpm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Interpolation period, µs (the tolerance's quantum).
    pub period_us: Micros,
    /// Speed limit per axis slot, nm/µs: its rapid rate or the maximum cutting feed.
    pub axis_speed: [f64; AXES],
    /// Acceleration limit per axis slot, nm/µs²: rapid rate / rapid time constant or maximum
    /// cutting feed / cutting time constant, whichever is higher.
    pub axis_accel: [f64; AXES],
    /// Backlash per axis slot, nm (a reversal takes it up with a jolt of the table).
    pub backlash_nm: [Nm; AXES],
    /// Spindle speed limit, rpm (the higher of the speed-mode and rigid tapping maxima).
    pub spindle_max_rpm: f64,
    /// Spindle acceleration in speed mode, rpm/µs (maximum speed / its time constant).
    pub spindle_accel: f64,
    /// Spindle acceleration in position mode, rpm/µs (rigid maximum / rigid time constant).
    pub rigid_accel: f64,
    /// Deceleration of a braked spindle, rpm/µs (maximum speed / brake time; 0: no brake).
    pub spindle_brake: f64,
}

impl Limits {
    /// The limits of a plant configuration.
    pub fn of_plant(c: &PlantConfig) -> Limits {
        let mut axis_speed = [0.0; AXES];
        let mut axis_accel = [0.0; AXES];
        let feed_v = c.feed_max_nm_min / 60e6;
        let feed_a = feed_v / c.feed_ramp_us.max(1) as f64;
        for i in 0..AXES {
            let v = c.rapid_nm_min[i] / 60e6;
            axis_speed[i] = v.max(feed_v);
            axis_accel[i] = (v / c.rapid_ramp_us[i].max(1) as f64).max(feed_a);
        }
        Limits {
            period_us: c.period_us.max(1),
            axis_speed,
            axis_accel,
            backlash_nm: c.backlash_nm,
            spindle_max_rpm: c.spindle_max_rpm.max(c.rigid_max_rpm) as f64,
            spindle_accel: c.spindle_max_rpm as f64 / c.spindle_ramp_us.max(1) as f64,
            rigid_accel: c.rigid_max_rpm as f64 / c.rigid_ramp_us.max(1) as f64,
            spindle_brake: if c.spindle_brake_us > 0 {
                c.spindle_max_rpm as f64 / c.spindle_brake_us as f64
            } else {
                0.0
            },
        }
    }

    /// The limits of a machine (its dialect's plant configuration under its parameters).
    pub fn of(m: &Machine) -> Limits {
        Limits::of_plant(&m.dialect.plant_config(&m.params))
    }
}

/// A speed that may change by at most `a` per µs, plus one allowance once: the envelope of every
/// earlier speed `v_i + a·(t − t_i)` (upper) and `v_i − a·(t − t_i)` (lower).
#[derive(Debug, Clone, Copy, Default)]
struct Envelope {
    bounds: Option<(f64, f64)>,
}

impl Envelope {
    /// Checks `v` after `dt` µs at acceleration `a` with allowance `allow`; returns the excess.
    fn step(&mut self, v: f64, a: f64, dt: f64, allow: f64) -> Option<f64> {
        let (hi, lo) = match self.bounds {
            None => {
                self.bounds = Some((v, v));
                return None;
            }
            Some((hi, lo)) => (hi + a * dt, lo - a * dt),
        };
        let excess = if v > hi + allow {
            Some(v - hi)
        } else if v < lo - allow {
            Some(lo - v)
        } else {
            None
        };
        self.bounds = Some((hi.min(v), lo.max(v)));
        excess
    }

    fn reset(&mut self) {
        self.bounds = None;
    }
}

/// Signed angle change from `a` to `b` (mdeg) wrapped to (−180°, 180°] around `expect`.
fn wrapped_diff(a: &Sample, b: &Sample, expect: f64) -> f64 {
    let d = (b.spindle_mdeg - a.spindle_mdeg) as f64 - expect;
    d - (d / 360_000.0).round() * 360_000.0
}

/// Every physics invariant (INV-11..INV-14) on `trace` under `lim`; INV-14 needs the tap (its
/// axis and lead). The first violation of each.
pub fn check(trace: &Trace, lim: &Limits, tap: Option<TapSpec>) -> Vec<Violation> {
    let mut out: Vec<Violation> = Vec::new();
    let mut found = |v: Option<Violation>| {
        if let Some(v) = v {
            if !out.iter().any(|o| o.invariant == v.invariant) {
                out.push(v);
            }
        }
    };
    let axes: Vec<(usize, bool)> = trace.meta.axes.iter().map(|a| (a.index, a.diameter)).collect();
    let period = lim.period_us as f64;
    let mut signals = Signals::default();
    let mut prev: Option<(Micros, Sample)> = None;
    let mut prev_v = [0.0_f64; AXES];
    let mut env = [Envelope::default(); AXES];
    let mut spindle_env = Envelope::default();
    let mut last_dir = [0_i64; AXES];
    let mut reversal = [0_u8; AXES];
    // In the interval up to the next sample: a stroke ran, rigid mode was on, a cut ran.
    let mut stroke = false;
    let mut rigid = false;
    let mut cutting = false;
    let mut phase = crate::trace::Phase::Idle;
    // Lead of the present stroke, learnt from its samples (nm per revolution).
    let mut stroke_lead = 0.0_f64;
    for e in &trace.events {
        match &e.event {
            Event::Input { name, value } if name == "spindle_stall" && value == "on" => break,
            Event::Input { name, value } if name == "emergency_stop" && value == "on" => break,
            Event::Signal { signal, value } => {
                signals.set(*signal, *value);
                if matches!(signal, Signal::Rgspp | Signal::Rgspm) && *value {
                    stroke = true;
                }
                if *signal == Signal::Rtap && *value {
                    rigid = true;
                }
            }
            Event::Phase(p) => {
                phase = *p;
                cutting |= *p == crate::trace::Phase::Cutting;
            }
            Event::Sample(s) => {
                let t = e.t_us;
                if let Some((t0, p)) = prev {
                    let dt = (t - t0) as f64;
                    if dt > 0.0 {
                        // The spindle: speed, ramp, angle.
                        let (r0, r1) = (p.spindle_mrpm as f64 / 1000.0, s.spindle_mrpm as f64 / 1000.0);
                        let mut a_sp = if stroke || rigid {
                            lim.spindle_accel.max(lim.rigid_accel)
                        } else {
                            lim.spindle_accel
                        };
                        if r1.abs() < r0.abs() && r0 * r1 >= 0.0 {
                            // Slowing down: a braked spindle may use its brake.
                            a_sp = a_sp.max(lim.spindle_brake);
                        }
                        if r1.abs() > lim.spindle_max_rpm * (1.0 + 1e-9) + 0.002 {
                            found(violation(
                                Invariant::SpindleRamp,
                                t,
                                format!(
                                    "spindle at {r1:.3} rpm, above its maximum {:.0} rpm",
                                    lim.spindle_max_rpm
                                ),
                            ));
                        }
                        if let Some(x) = spindle_env.step(r1, a_sp, dt, a_sp * period + 0.002) {
                            found(violation(
                                Invariant::SpindleRamp,
                                t,
                                format!(
                                    "spindle speed {r0:.3} → {r1:.3} rpm in {dt} µs: {x:.3} rpm beyond its ramp ({:.0} rpm/s, one period allowed)",
                                    a_sp * 1e6
                                ),
                            ));
                        }
                        let expect = 0.5 * (r0 + r1) * dt * MDEG_PER_US_PER_RPM;
                        let tol = 0.5 * ((r1 - r0).abs() + a_sp * dt) * dt * MDEG_PER_US_PER_RPM + 3.0;
                        let diff = wrapped_diff(&p, s, expect);
                        if diff.abs() > tol {
                            found(violation(
                                Invariant::SpindleAngleIntegral,
                                t,
                                format!(
                                    "spindle angle {:.3}° → {:.3}° in {dt} µs at {r0:.3} → {r1:.3} rpm: {:.3}° off the integral of its speed (tolerance {:.3}°)",
                                    p.spindle_mdeg as f64 / 1000.0,
                                    s.spindle_mdeg as f64 / 1000.0,
                                    diff / 1000.0,
                                    tol / 1000.0
                                ),
                            ));
                        }
                        let revs = (expect + wrapped_diff(&p, s, expect)).abs() / 360_000.0;
                        // The axes.
                        for &(i, diameter) in &axes {
                            let half = |n: Nm| if diameter { n as f64 / 2.0 } else { n as f64 };
                            let d = half(s.axes[i]) - half(p.axes[i]);
                            let v = d / dt;
                            if stroke && revs > 1e-6 && d != 0.0 {
                                stroke_lead = stroke_lead.max(d.abs() / revs);
                            }
                            let mut a = lim.axis_accel[i];
                            if stroke {
                                // The tap axis on the rigid tapping profile (spindle and axis
                                // share the rigid time constant).
                                a = a.max(lim.rigid_accel * stroke_lead / 60e6);
                            }
                            let vmax = lim.axis_speed[i];
                            if v.abs() > vmax * (1.0 + 1e-9) + 2.0 / dt {
                                found(violation(
                                    Invariant::AxisLimits,
                                    t,
                                    format!(
                                        "axis {} at {:.3} mm/min, above its limit {:.3} mm/min",
                                        axis_name(trace, i),
                                        v.abs() * 60e6 / 1e6,
                                        vmax * 60e6 / 1e6
                                    ),
                                ));
                            }
                            let dir = (d as i64).signum();
                            if dir != 0 {
                                if last_dir[i] != 0 && last_dir[i] != dir && lim.backlash_nm[i] > 0 {
                                    reversal[i] = 2;
                                }
                                last_dir[i] = dir;
                            }
                            // A reversal takes up the backlash: the table is still until the
                            // motor has crossed the gap, then it is carried at the motor's speed.
                            let jolt = if reversal[i] > 0 && dir != 0 {
                                reversal[i] -= 1;
                                (2.0 * a * lim.backlash_nm[i] as f64).sqrt().min(vmax)
                            } else {
                                0.0
                            };
                            let excess = env[i].step(v, a, dt, a * period + 2.0 / dt + jolt);
                            if jolt > 0.0 {
                                // The jolt of a backlash is a fresh start of the table's speed.
                                env[i].bounds = Some((v, v));
                            }
                            if let Some(x) = excess {
                                found(violation(
                                    Invariant::AxisLimits,
                                    t,
                                    format!(
                                        "axis {} from {:.3} to {:.3} mm/min in {dt} µs: {:.3} mm/min beyond its acceleration ({:.1} mm/s², one period allowed)",
                                        axis_name(trace, i),
                                        prev_v[i] * 6e1,
                                        v * 6e1,
                                        x * 6e1,
                                        a * 1e6
                                    ),
                                ));
                            }
                            prev_v[i] = v;
                            // INV-14: a tap following its spindle in speed mode never runs
                            // ahead of lead × spindle speed (one period allowed).
                            if let Some(tap) = tap.filter(|tp| tp.axis == i && cutting && !stroke && !rigid) {
                                let lead = tap.lead_nm as f64;
                                let rmax = r0.abs().max(r1.abs());
                                let ahead = d.abs() - lead * rmax / 60e6 * dt;
                                let allow = lead * lim.spindle_accel * period / 60e6 * dt
                                    + (tap.tolerance_nm as f64).max(2.0);
                                if ahead > allow && rmax > 0.0 {
                                    found(violation(
                                        Invariant::FollowsSpindle,
                                        t,
                                        format!(
                                            "axis {} travelled {:.0} nm in {dt} µs, {:.0} nm more than lead × the spindle's {rmax:.3} rpm allow",
                                            axis_name(trace, i),
                                            d.abs(),
                                            ahead
                                        ),
                                    ));
                                }
                            }
                        }
                    } else {
                        for en in &mut env {
                            en.reset();
                        }
                        spindle_env.reset();
                    }
                }
                prev = Some((t, *s));
                let now_stroke = signals.get(Signal::Rgspp) || signals.get(Signal::Rgspm);
                if !now_stroke && !stroke {
                    stroke_lead = 0.0;
                }
                stroke = now_stroke;
                rigid = signals.get(Signal::Rtap);
                cutting = phase == crate::trace::Phase::Cutting;
            }
            _ => {}
        }
    }
    out.sort_by_key(|v| v.invariant);
    out
}

fn axis_name(trace: &Trace, i: usize) -> String {
    trace.meta.axes.iter().find(|a| a.index == i).map_or_else(|| format!("#{i}"), |a| a.letter.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::{AxisSpec, EndReason, EndSummary, Signals, TraceEvent, TraceMeta};

    /// Limits of a small machine: 6 m/min and 1 m/s² on Z, 3000 rpm with a 1 s ramp, 1 ms period.
    fn lim() -> Limits {
        let mut axis_speed = [0.0; AXES];
        let mut axis_accel = [0.0; AXES];
        axis_speed[2] = 6e9 / 60e6;
        axis_accel[2] = 1e-3;
        Limits {
            period_us: 1000,
            axis_speed,
            axis_accel,
            backlash_nm: [0; AXES],
            spindle_max_rpm: 3000.0,
            spindle_accel: 3000.0 / 1e6,
            rigid_accel: 3000.0 / 1e6,
            spindle_brake: 0.0,
        }
    }

    /// A trace of samples every ms: Z (nm) and spindle (rpm, mdeg) given per sample.
    fn trace(samples: &[(Nm, f64, f64)], inputs: &[(usize, &str)]) -> Trace {
        static AXES_Z: [AxisSpec; 1] = [AxisSpec { letter: 'Z', index: 2, diameter: false, rotary: false }];
        let mut events = Vec::new();
        for (k, &(z, rpm, deg)) in samples.iter().enumerate() {
            for (at, name) in inputs {
                if *at == k {
                    let ev = Event::Input { name: name.to_string(), value: "on".into() };
                    events.push(TraceEvent { t_us: k as Micros * 1000, event: ev });
                }
            }
            let mut axes = [0; AXES];
            axes[2] = z;
            let s = Sample {
                axes,
                spindle_mrpm: (rpm * 1000.0).round() as i64,
                spindle_mdeg: ((deg * 1000.0).round() as i64).rem_euclid(360_000),
            };
            events.push(TraceEvent { t_us: k as Micros * 1000, event: Event::Sample(s) });
        }
        let end = EndSummary {
            reason: EndReason::ProgramEnd,
            state: Sample::default(),
            command: [0; AXES],
            signals: Signals::default(),
            modal: Vec::new(),
            alarms: 0,
            blocks: 0,
        };
        events.push(TraceEvent { t_us: samples.len() as Micros * 1000, event: Event::End(Box::new(end)) });
        Trace {
            meta: TraceMeta { dialect: "", axes: AXES_Z.to_vec(), period_us: 1000, sample_us: 1000 },
            events,
        }
    }

    /// Z accelerating at `a` nm/µs² from rest for `n` ms, spindle still.
    fn accelerating(a: f64, n: usize) -> Vec<(Nm, f64, f64)> {
        (0..n).map(|k| ((0.5 * a * (k as f64 * 1000.0).powi(2)).round() as Nm, 0.0, 0.0)).collect()
    }

    fn ids(v: &[Violation]) -> Vec<&'static str> {
        v.iter().map(|v| v.invariant.id()).collect()
    }

    #[test]
    fn an_axis_within_its_acceleration_holds_and_one_above_it_does_not() {
        assert_eq!(check(&trace(&accelerating(1e-3, 80), &[]), &lim(), None), vec![]);
        // 1.5 × the limit for long enough to spend the one period allowed: INV-11.
        assert_eq!(ids(&check(&trace(&accelerating(1.5e-3, 60), &[]), &lim(), None)), ["INV-11"]);
        // A jump to full speed in one period (the known G33.1 violation): INV-11.
        let mut jump = vec![(0, 0.0, 0.0); 3];
        jump.extend((1..10).map(|k| (k * 50_000, 0.0, 0.0)));
        assert_eq!(ids(&check(&trace(&jump, &[]), &lim(), None)), ["INV-11"]);
    }

    #[test]
    fn a_speed_above_the_axis_rate_breaks_inv_11() {
        // 120 µm per ms = 7.2 m/min, above 6 m/min (reached within its acceleration? no: INV-11
        // reports the speed first or the acceleration; either way INV-11).
        let fast: Vec<_> = (0..10).map(|k| (k * 120_000, 0.0, 0.0)).collect();
        assert_eq!(ids(&check(&trace(&fast, &[]), &lim(), None)), ["INV-11"]);
    }

    #[test]
    fn a_spindle_step_breaks_its_ramp_and_the_angle_must_integrate_the_speed() {
        // 3 rpm/ms allowed: 2604 rpm -> 15 rpm in 1 ms (the known M29 violation): INV-12.
        let mut angle = 0.0;
        let mut s = Vec::new();
        for rpm in [2604.0, 2604.0, 15.0, 15.0] {
            s.push((0, rpm, angle));
            angle += rpm * 6e-3;
        }
        assert_eq!(ids(&check(&trace(&s, &[]), &lim(), None)), ["INV-12"]);
        // A steady spindle whose angle jumps 90° (an orientation that jumps): INV-13.
        let jump = vec![(0, 0.0, 10.0), (0, 0.0, 10.0), (0, 0.0, 100.0)];
        assert_eq!(ids(&check(&trace(&jump, &[]), &lim(), None)), ["INV-13"]);
        // Steady at 1000 rpm, 6° per ms: holds, across the 360° wrap too.
        let steady: Vec<_> = (0..100).map(|k| (0, 1000.0, k as f64 * 6.0)).collect();
        assert_eq!(check(&trace(&steady, &[]), &lim(), None), vec![]);
    }

    #[test]
    fn a_stall_and_an_emergency_stop_are_the_named_exemptions() {
        let mut s: Vec<_> = (0..5).map(|k| (0, 1000.0, k as f64 * 6.0)).collect();
        s.extend((0..5).map(|_| (0, 0.0, 24.0)));
        assert_eq!(ids(&check(&trace(&s, &[]), &lim(), None)), ["INV-12"]);
        assert_eq!(check(&trace(&s, &[(5, "spindle_stall")]), &lim(), None), vec![]);
        assert_eq!(check(&trace(&s, &[(5, "emergency_stop")]), &lim(), None), vec![]);
        assert!(!check(&trace(&s, &[(5, "reset")]), &lim(), None).is_empty(), "nothing else is exempt");
    }

    #[test]
    fn a_following_tap_never_runs_ahead_of_lead_times_speed() {
        // Lead 1 mm at 600 rpm: 10 µm per ms. The tap runs 20 µm per ms in the cut: INV-14.
        let tap = TapSpec { axis: 2, lead_nm: 1_000_000, tolerance_nm: 2_000 };
        let mut t = trace(&(0..10).map(|k| (-k * 20_000, 600.0, k as f64 * 3.6)).collect::<Vec<_>>(), &[]);
        t.events.insert(0, TraceEvent { t_us: 0, event: Event::Phase(crate::trace::Phase::Cutting) });
        let mut l = lim();
        l.axis_accel[2] = 1.0;
        assert_eq!(ids(&check(&t, &l, Some(tap))), ["INV-14"]);
        let mut ok = trace(&(0..10).map(|k| (-k * 10_000, 600.0, k as f64 * 3.6)).collect::<Vec<_>>(), &[]);
        ok.events.insert(0, TraceEvent { t_us: 0, event: Event::Phase(crate::trace::Phase::Cutting) });
        assert_eq!(check(&ok, &l, Some(tap)), vec![]);
    }
}
