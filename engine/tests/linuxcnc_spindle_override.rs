//! LinuxCNC's spindle override during spindle-synchronised moves (LCNC-G331-04, LCNC-G76-04,
//! DEC-142): motion scales the spindle's commanded speed in every servo period (control.c:
//! `speed_out = speed × net_scale`, SS_ENABLED disabled only by DISABLE_SPEED_OVERRIDE, which
//! rs274 emits around G84/G74 only), so an override acts on the turning spindle at once and the
//! synchronised axis follows it: the tap and the thread pass stay in their groove.

mod support;

use nc_engine::input::{Condition, Input, InputSchedule};
use nc_engine::trace::{Phase, Trace};
use nc_engine::RunOptions;
use support::run;

/// The spindle's unwrapped revolutions and the Z position (nm) at every sample of the `k`-th
/// cutting phase (1-based) and the retract phase right after it.
fn synchronised(t: &Trace, k: usize) -> Vec<(u64, f64, f64, f64)> {
    let phases: Vec<(u64, Phase)> = t.phases().collect();
    let cuts: Vec<usize> = (0..phases.len()).filter(|&i| phases[i].1 == Phase::Cutting).collect();
    let i = cuts[k - 1];
    let from = phases[i].0;
    // Through the retract after the cut (G33.1's way out is synchronised too), not the positioning.
    let mut to = u64::MAX;
    for p in &phases[i + 1..] {
        if p.1 != Phase::Retract {
            to = p.0;
            break;
        }
    }
    let (mut revs, mut last) = (0.0, None::<f64>);
    let mut out = Vec::new();
    for (ts, s) in t.samples() {
        let a = s.spindle_mdeg as f64 / 1000.0;
        if let Some(l) = last {
            let mut d = a - l;
            if d > 180.0 {
                d -= 360.0;
            } else if d < -180.0 {
                d += 360.0;
            }
            revs += d / 360.0;
        }
        last = Some(a);
        if ts > from && ts < to {
            out.push((ts, revs, s.axes[2] as f64, s.spindle_mrpm as f64 / 1000.0));
        }
    }
    out
}

/// LinuxCNC's `G33.1 Z-10 K1` at S500, the spindle override set to 50 % 500 ms into the tap.
fn g33_1_at_half_spindle_override() -> Trace {
    let inputs = InputSchedule::default().when(
        Condition::Phase(Phase::Cutting),
        1,
        500_000,
        Input::SpindleOverride(50),
    );
    let opts = RunOptions { inputs, sample_us: 1000, ..RunOptions::default() };
    run("linuxcnc", &[], "G21 M3 S500\nG0 X0 Z5\nG33.1 Z-10 K1\nG0 Z20\nM2\n", &opts)
}

#[test]
fn g33_1_follows_a_spindle_override_at_once_in_its_groove() {
    let t = g33_1_at_half_spindle_override();
    assert_eq!(t.alarms().count(), 0);
    let s = synchronised(&t, 1);
    // K = 1 mm per revolution: Z + 1 mm × revolutions is constant once the tap has caught up
    // (the first 100 ms), through the override, the reversal and the way out up to the start (Z5;
    // past it the spindle reverses again and the tap moves back unsynchronised).
    let locked: Vec<f64> =
        s.iter().filter(|r| r.0 > s[0].0 + 100_000 && r.2 < 4.5e6).map(|r| r.2 + 1e6 * r.1).collect();
    let (lo, hi) = locked.iter().fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    assert!(hi - lo < 2_000.0, "the tap left its groove by {} nm", hi - lo);
    // The spindle turned at 250 rpm from 42 ms after the override (the ramp) to the reversal.
    assert!(s.iter().any(|r| (r.3 - 250.0).abs() < 1e-6), "no 250 rpm");
    assert!(s.iter().any(|r| (r.3 + 250.0).abs() < 1e-6), "no -250 rpm on the way out");
    assert!(!s.iter().any(|r| r.3.abs() > 500.0 + 1e-6));
}

/// The reversal at Z runs at the spindle's ramp from the speed it turns at: LinuxCNC (the adapter,
/// `g331/spindle_override`, issue 16) reversed 250 rpm (S500 at 50 %) in 100 ms through zero and
/// bottomed at Z-10.086; the reference braked in the time computed for S500 (half the rate) and
/// bottomed at Z-10.174, 60 ms behind for the rest of the tap (DEC-149).
#[test]
fn g33_1_reverses_an_overridden_spindle_at_its_ramp() {
    let t = g33_1_at_half_spindle_override();
    let bottom = t.samples().map(|(_, s)| s.axes[2]).min().unwrap() as f64 / 1e6;
    assert!((bottom + 10.086).abs() < 0.01, "bottom Z{bottom}, LinuxCNC Z-10.086");
}

#[test]
fn a_g76_pass_follows_a_spindle_override_at_once_in_its_groove() {
    let inputs = InputSchedule::default().when(
        Condition::Phase(Phase::Cutting),
        2,
        300_000,
        Input::SpindleOverride(50),
    );
    let opts = RunOptions { inputs, sample_us: 1000, ..RunOptions::default() };
    let prog = "G18 G21 G8 M3 S600\nG0 X7 Z3\nG76 P1.5 Z-10 I-1 J0.4 K0.92 R1 Q0 H3 E0 L0\nG0 X20\nM2\n";
    let t = run("linuxcnc", &[], prog, &opts);
    assert_eq!(t.alarms().count(), 0);
    let s = synchronised(&t, 2);
    // P = 1.5 mm per revolution towards -Z: Z + 1.5 mm × revolutions is constant once the pass is
    // at speed, before and after the override, until the pass decelerates at its end.
    let cruise: Vec<f64> =
        s.iter().filter(|r| r.0 > s[0].0 + 150_000 && r.2 > -9.5e6).map(|r| r.2 + 1.5e6 * r.1).collect();
    let (lo, hi) = cruise.iter().fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    assert!(hi - lo < 2_000.0, "the pass left its groove by {} nm", hi - lo);
    assert!(s.iter().any(|r| (r.3 - 600.0).abs() < 1e-6) && s.iter().any(|r| (r.3 - 300.0).abs() < 1e-6));
}
