//! LinuxCNC 2.9's trajectory planner (`nc.trajectory_planner` 209, DEC-163): a G64 move that no
//! move follows in the planner's queue keeps its parabolic end condition and runs at half its
//! acceleration (tc.c `tcGetOverallMaxAccel`; the Debian 2.9 recordings g331 and g331_g91: Z
//! 1.006 mm 90 ms into the rapid before G33.1, 254 mm/s² of MAX_ACCELERATION 508). A move that
//! another follows, a move under G61.1 and a canned cycle's moves (run in G61 by rs274) keep the
//! full acceleration, and the default planner (after 2.9, LinuxCNC #4220) never halves it.

mod support;

use nc_engine::trace::{Event, Trace};
use nc_engine::RunOptions;

/// The recorded simulator's limits (`testdata/linuxcnc/linuxcnc-sim.params.yaml`): 30.48 mm/s,
/// 508 mm/s² per axis, 1 ms servo period; `planner` 209 or 210.
fn run(planner: f64, text: &str) -> Trace {
    let mut params = vec![("nc.period_us", None, 1000.0), ("nc.trajectory_planner", None, planner)];
    for ax in ['X', 'Y', 'Z'] {
        params.push(("nc.rapid_mm_min", Some(ax), 1828.8));
        params.push(("nc.rapid_ramp_ms", Some(ax), 60.0));
    }
    let opts = RunOptions { sample_us: 1000, ..RunOptions::default() };
    support::run("linuxcnc", &params, text, &opts)
}

/// Positions (mm) of one axis, one sample per ms.
fn axis(trace: &Trace, i: usize) -> Vec<f64> {
    trace
        .events
        .iter()
        .filter_map(|e| match &e.event {
            Event::Sample(s) => Some(s.axes[i] as f64 / 1e6),
            _ => None,
        })
        .collect()
}

/// The largest acceleration (mm/s², second difference at 1 ms) of an axis, and how long (ms) it
/// moves: from its first to its last change.
fn peak_accel_and_time(xs: &[f64]) -> (f64, usize) {
    let peak = xs.windows(3).map(|w| ((w[2] - 2.0 * w[1] + w[0]) * 1e6).abs()).fold(0.0, f64::max);
    let first = xs.windows(2).position(|w| w[1] != w[0]).unwrap_or(0);
    let last = xs.windows(2).rposition(|w| w[1] != w[0]).unwrap_or(0);
    (peak, last - first + 1)
}

#[test]
fn a_g64_rapid_that_no_move_follows_runs_at_half_acceleration_in_2_9() {
    let program = "G21 G90\nG0 Z5\nM2\n";
    let (a29, t29) = peak_accel_and_time(&axis(&run(209.0, program), 2));
    let (a210, t210) = peak_accel_and_time(&axis(&run(210.0, program), 2));
    // 5 mm at 30.48 mm/s: 164 ms of cruise plus one ramp time, 120 ms at 254 mm/s² (the
    // recording: 285 ms), 60 ms at 508.
    assert!((a29 - 254.0).abs() < 10.0 && (a210 - 508.0).abs() < 15.0, "{a29} / {a210} mm/s²");
    assert!((t29 as f64 - 284.0).abs() <= 3.0, "2.9: {t29} ms");
    assert!((t210 as f64 - 224.0).abs() <= 3.0, "after 2.9: {t210} ms");
}

#[test]
fn a_move_that_another_follows_keeps_its_acceleration_the_last_one_is_halved() {
    // The rapid up is followed by the rapid across (a move enters the queue: tangent, blend arc
    // or stop, never parabolic here); the rapid across by the program end.
    let t = run(209.0, "G21 G90\nG0 Z5\nG0 X10\nM2\n");
    let (az, _) = peak_accel_and_time(&axis(&t, 2));
    let (ax, tx) = peak_accel_and_time(&axis(&t, 0));
    assert!((az - 508.0).abs() < 15.0, "Z {az} mm/s²");
    assert!((ax - 254.0).abs() < 10.0, "X {ax} mm/s²");
    assert!((tx as f64 - (10.0 / 30.48 * 1000.0 + 120.0)).abs() <= 3.0, "X {tx} ms");
}

#[test]
fn a_rapid_before_g33_1_is_halved_one_before_g33_is_not() {
    // G33.1 is a rigid tap, which the task gives motion only once the motion has ended; G33 is a
    // move that enters the queue (its rapid then stops exactly for the synchronisation).
    let tap = run(209.0, "G21 G90\nM3 S600\nG0 Z5\nG33.1 Z-2 K1\nM5\nM2\n");
    let thread = run(209.0, "G21 G90\nM3 S600\nG0 Z5\nG33 Z-2 K1\nM5\nM2\n");
    let first_rise = |xs: &[f64]| {
        let k = xs.iter().position(|z| *z >= 4.999).unwrap();
        peak_accel_and_time(&xs[..=k]).0
    };
    let (a_tap, a_thread) = (first_rise(&axis(&tap, 2)), first_rise(&axis(&thread, 2)));
    assert!((a_tap - 254.0).abs() < 10.0, "before G33.1: {a_tap} mm/s²");
    assert!((a_thread - 508.0).abs() < 15.0, "before G33: {a_thread} mm/s²");
}

#[test]
fn exact_stop_and_canned_cycles_keep_the_full_acceleration() {
    // Under G61.1 nothing is halved; a canned cycle's moves run in G61, and the G64 rapid before
    // it is followed by the cycle's first rapid: the same motion as the planner after 2.9.
    for program in [
        "G21 G90 G61.1\nG0 Z5\nG0 X10\nM2\n",
        "G21 G90\nG0 X0 Y0 Z5\nG98 G81 X10 Y10 Z-5 R2 F300\nX30\nG80\nM2\n",
    ] {
        let (t29, t210) = (run(209.0, program), run(210.0, program));
        for i in 0..3 {
            assert_eq!(axis(&t29, i), axis(&t210, i), "{program}: axis {i}");
        }
    }
    // After the cycle (G64 again), a lone rapid is halved once more.
    let t = run(209.0, "G21 G90\nG0 Z5\nG81 X10 Z-1 R2 F300\nG80\nG0 X20\nM2\n");
    let xs = axis(&t, 0);
    let k = xs.iter().position(|x| *x > 10.0).unwrap();
    let (a, _) = peak_accel_and_time(&xs[k - 1..]);
    assert!((a - 254.0).abs() < 10.0, "the rapid after G80: {a} mm/s²");
}
