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
    // The rapid up is followed by the rapid back down (a move enters the queue: a reversal, which
    // stops exactly); the rapid down by the program end.
    let z = axis(&run(209.0, "G21 G90\nG0 Z5\nG0 Z0\nM2\n"), 2);
    let top = z.iter().position(|v| *v >= 5.0).unwrap();
    let (up, _) = peak_accel_and_time(&z[..=top]);
    let (down, t_down) = peak_accel_and_time(&z[top..]);
    assert!((up - 508.0).abs() < 15.0, "up {up} mm/s²");
    assert!((down - 254.0).abs() < 10.0, "down {down} mm/s²");
    assert!((t_down as f64 - (5.0 / 30.48 * 1000.0 + 120.0)).abs() <= 3.0, "down {t_down} ms");
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
    // Under G61.1 nothing is halved or blended: the same motion as the planner after 2.9.
    let program = "G21 G90 G61.1\nG0 Z5\nG0 X10\nM2\n";
    let (t29, t210) = (run(209.0, program), run(210.0, program));
    for i in 0..3 {
        assert_eq!(axis(&t29, i), axis(&t210, i), "axis {i}");
    }
    // A canned cycle's moves run in G61: once the G64 rapid before it has blended into the
    // cycle's first rapid, no Z ramp of the cycle runs at half acceleration (a halved 30.48 mm/s
    // ramp would show 120 samples near 254 mm/s²).
    let t = run(209.0, "G21 G90\nG0 X0 Y0 Z5\nG98 G81 X10 Y10 Z-5 R2 F300\nX30\nG80\nM2\n");
    let (x, z) = (axis(&t, 0), axis(&t, 2));
    let from = x.iter().position(|v| *v >= 10.0).unwrap();
    let halved = z[from..].windows(3).filter(|w| ((w[2] - 2.0 * w[1] + w[0]) * 1e6).abs() > 200.0).count();
    let full = z[from..].windows(3).filter(|w| ((w[2] - 2.0 * w[1] + w[0]) * 1e6).abs() > 400.0).count();
    assert!(halved - full < 30, "{halved} samples above 200 mm/s², {full} above 400");
    assert!(full > 200, "{full}");
    // After the cycle (G64 again), a lone rapid is halved once more.
    let t = run(209.0, "G21 G90\nG0 Z5\nG81 X10 Z-1 R2 F300\nG80\nG0 X20\nM2\n");
    let xs = axis(&t, 0);
    let k = xs.iter().position(|x| *x > 10.0).unwrap();
    let (a, _) = peak_accel_and_time(&xs[k - 1..]);
    assert!((a - 254.0).abs() < 10.0, "the rapid after G80: {a} mm/s²");
}

/// The magnitude of the acceleration vector (mm/s², second differences at 1 ms) at each sample.
fn accel_magnitudes(t: &Trace) -> Vec<f64> {
    let (x, y, z) = (axis(t, 0), axis(t, 1), axis(t, 2));
    (1..x.len() - 1)
        .map(|k| {
            let d = |v: &[f64]| (v[k + 1] - 2.0 * v[k] + v[k - 1]) * 1e6;
            (d(&x).powi(2) + d(&y).powi(2) + d(&z).powi(2)).sqrt()
        })
        .collect()
}

/// The time (ms) from the first move until every axis is at rest at the end.
fn run_time(t: &Trace) -> usize {
    let (x, z) = (axis(t, 0), axis(t, 2));
    let moving = |k: usize| x[k] != x[k - 1] || z[k] != z[k - 1];
    let first = (1..x.len()).find(|&k| moving(k)).unwrap();
    let last = (1..x.len()).rfind(|&k| moving(k)).unwrap();
    last - first + 1
}

#[test]
fn two_g64_rapids_that_turn_are_joined_by_2_9_s_blend_arc() {
    // Up 5 mm, then 10 mm across, at 30.48 mm/s and 508 mm/s² per axis (the g81 corner in one
    // plane): 2.9 turns on an arc of R = 30.48² / (√¾ · 508) ... the parabolic-equivalent radius
    // 2.33 mm (blendmath.c blendComputeParameters, DEC-164) at the full speed.
    let program = "G21 G90\nG0 Z5\nG0 X10\nM2\n";
    let (blended, exact) = (run(209.0, program), run(210.0, program));
    let (x, z) = (axis(&blended, 0), axis(&blended, 2));
    // X leaves before Z has arrived: where X starts, Z is 2.33 mm below the corner.
    let leave = x.iter().position(|v| *v > 0.0).unwrap();
    assert!((z[leave] - (5.0 - 2.33)).abs() < 0.05, "X leaves at Z {}", z[leave]);
    // It never reaches the corner: the closest is R·(√2 − 1) = 0.96 mm from it.
    let closest =
        x.iter().zip(&z).map(|(x, z)| (x * x + (z - 5.0).powi(2)).sqrt()).fold(f64::INFINITY, f64::min);
    assert!((closest - 2.33 * (2f64.sqrt() - 1.0)).abs() < 0.03, "{closest} mm from the corner");
    // The arc runs at 30.48 mm/s: its normal acceleration v²/R = 399 mm/s²; no sample of the
    // run exceeds the axes' 508 mm/s², for the vector as a whole.
    let peak = accel_magnitudes(&blended).into_iter().fold(0.0, f64::max);
    assert!(peak <= 508.0 * 1.03, "{peak} mm/s²");
    // The time: up to the arc from rest (a 60 ms ramp over 0.914 mm, then cruise), the arc
    // (R·π/2 at 30.48 mm/s), across at 30.48 mm/s and the stop at half acceleration (the program
    // end follows: 120 ms over 1.829 mm). Stopping at the corner instead: 224 + 388 ms.
    let (v, r) = (30.48e-3, 2.329);
    let expected =
        60.0 + (5.0 - r - 0.914) / v + r * std::f64::consts::FRAC_PI_2 / v + (10.0 - r - 1.829) / v + 120.0;
    let (tb, te) = (run_time(&blended), run_time(&exact));
    assert!((tb as f64 - expected).abs() <= 4.0, "blended {tb} ms, expected {expected}");
    assert!((te as f64 - 612.0).abs() <= 3.0, "exact {te} ms");
}

#[test]
fn no_arc_under_g61_1_or_between_a_rapid_and_a_feed() {
    for program in ["G21 G90 G61.1\nG0 Z5\nG0 X10\nM2\n", "G21 G90\nG0 Z5\nG1 X10 F600\nM2\n"] {
        let (x, z) = (axis(&run(209.0, program), 0), axis(&run(209.0, program), 2));
        let leave = x.iter().position(|v| *v > 0.0).unwrap();
        assert_eq!(z[leave], 5.0, "{program}");
    }
}

#[test]
fn a_g64_g76_pass_runs_on_into_its_exit_taper_through_2_9_s_blend_arc() {
    // testdata/linuxcnc/programs/g76.ngc: pass 1 cuts at X4.25 to Z-9.0757, then the 45°-ish
    // exit taper to X5.25 Z-9.5757 (rs274 -g). LinuxCNC 2.9 (debian-2.9/g76) leaves the thread
    // at Z -8.517, 0.559 mm before the joint (the arc R 0.905 mm of blendmath.c's rules), without
    // stopping; the exact-stop model (DEC-147, the default planner) stops at the joint.
    let program =
        "G21 G18 G90\nM3 S300\nG0 X5 Z2\nG76 P1.5 Z-10 I-0.5 J0.25 R1 K1 Q29.5 H1 E0.5 L2\nM5\nM2\n";
    let leave_z = |planner: f64| {
        let t = run(planner, program);
        let (x, z) = (axis(&t, 0), axis(&t, 2));
        // The first pass: X at 4.25 while Z runs down, then X moves out.
        let cut = x.iter().position(|v| (*v - 4.25).abs() < 1e-6).unwrap();
        let leave = cut + x[cut..].iter().position(|v| *v > 4.25 + 1e-6).unwrap();
        let speed = (z[leave - 1] - z[leave - 2]) * 1e3;
        (z[leave], speed)
    };
    let (z29, v29) = leave_z(209.0);
    let (z210, v210) = leave_z(210.0);
    assert!((z29 + 8.517).abs() < 0.01, "2.9 leaves the thread at Z {z29}");
    assert!((v29 + 7.5).abs() < 0.2, "at the thread's speed: {v29} mm/s");
    assert!((z210 + 9.0757).abs() < 0.005, "the default leaves at the joint: Z {z210}");
    assert!(v210.abs() < 0.5, "at rest: {v210} mm/s");
}

/// The slowest path speed (mm/s) through the corner X30 Y0: from X15 on the way there to Y10 on
/// the way on (both moves at full speed there).
fn corner_speed(t: &Trace) -> f64 {
    let (x, y) = (axis(t, 0), axis(t, 1));
    (1..x.len())
        .filter(|&k| x[k - 1] > 15.0 && y[k] < 10.0)
        .map(|k| ((x[k] - x[k - 1]).hypot(y[k] - y[k - 1])) * 1e3)
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn a_canned_cycle_leaves_canon_s_tolerance_and_g64_p_sets_one() {
    // rs274 restores G64 after a cycle with canon's tolerance, 0.001 inch until a G64 gives one
    // (emccanon.cc INIT_CANON): the next corner (90°, 30.48 mm/s) turns on an arc of
    // R = 0.0254 · cos 45° / (1 − sin 45°) · tan 45° = 0.061 mm at √(440 · 0.061) = 5.2 mm/s.
    let cycle = "G21 G90\nG0 Z5\nG81 X0 Z-1 R2 F300\nG80\n";
    let after = run(209.0, &format!("{cycle}G0 X30 Y0\nG0 X30 Y20\nM2\n"));
    let v = corner_speed(&after);
    assert!((v - 5.2).abs() < 0.3, "after a cycle: {v} mm/s at the corner");
    // G64 without P: no tolerance, the arc of the moves' lengths at the full speed.
    let g64 = run(209.0, &format!("{cycle}G64\nG0 X30 Y0\nG0 X30 Y20\nM2\n"));
    assert!(corner_speed(&g64) > 25.0, "{}", corner_speed(&g64));
    // G64 P0.5: R = 0.5 · 2.414 = 1.21 mm, √(440 · 1.21) = 23.1 mm/s.
    let p = run(209.0, &format!("{cycle}G64 P0.5\nG0 X30 Y0\nG0 X30 Y20\nM2\n"));
    assert!((corner_speed(&p) - 23.1).abs() < 0.5, "{}", corner_speed(&p));
}

/// The recorded programs and LinuxCNC's own example programs of the corpus run under 2.9's planner
/// within the machine's physical limits (no axis beyond its speed or acceleration: the blend arcs,
/// the entries at speed and the tracked tapers included).
#[test]
fn every_recorded_program_keeps_the_physics_under_2_9_s_planner() {
    use nc_engine::invariants::physics::{check, Limits};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut files: Vec<_> = std::fs::read_dir(root.join("testdata/linuxcnc/programs"))
        .unwrap()
        .chain(std::fs::read_dir(root.join("corpus")).unwrap())
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            p.extension().is_some_and(|e| e == "ngc")
                && (p.starts_with(root.join("testdata")) || name.starts_with("LinuxCNC__"))
        })
        .collect();
    files.sort();
    assert!(files.len() >= 20, "{files:?}");
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        let mut m = nc_engine::Machine::new("linuxcnc").unwrap();
        for (id, ax, v) in [("nc.period_us", None, 1000.0), ("nc.trajectory_planner", None, 209.0)] {
            m.params.set(id, ax, v).unwrap();
        }
        for ax in ['X', 'Y', 'Z'] {
            m.params.set("nc.rapid_mm_min", Some(ax), 1828.8).unwrap();
            m.params.set("nc.rapid_ramp_ms", Some(ax), 60.0).unwrap();
        }
        let Ok(prog) = m.parse(&text) else { continue };
        let trace = m.run_to_trace(&prog, &RunOptions::default());
        assert_eq!(check(&trace, &Limits::of(&m), None), vec![], "{}", f.display());
    }
}

/// Random G64 programs (rapids, feeds and G2/G3 arcs through a box, mode changes, G64 P, canned
/// cycles, G33.1, dwells and spindle commands), some with a feed hold and a cycle start or single block, run
/// under 2.9's planner to their end without a panic and within the machine's limits.
#[test]
fn random_g64_programs_keep_the_physics_under_2_9_s_planner() {
    use nc_engine::input::{Input, InputSchedule};
    use nc_engine::invariants::physics::{check, Limits};
    let mut seed: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut next = |n: u64| {
        seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        (seed >> 33) % n
    };
    for case in 0..60 {
        let mut text = String::from("G21 G90 G17\nM3 S800\n");
        for _ in 0..10 {
            let (x, y, z) = (next(40) as f64 - 20.0, next(40) as f64 - 20.0, next(20) as f64);
            text.push_str(&match next(16) {
                0 | 12 | 13 => format!("G1 X{x} Y{y} Z{z} F{}\n", 100 + next(2900)),
                // A feed to (x, y) in the plane, a G2/G3 about a centre 0.5..8 mm off through
                // 10°..350°, a feed on in the plane (lines meet the circle at any angle, convex
                // or concave), at a feed whose centripetal acceleration the circle allows (the
                // engine does not slow an arc for it).
                14 | 15 => {
                    let (r, a0) = (0.5 + next(75) as f64 / 10.0, next(360) as f64);
                    let a1 = a0 + if next(2) == 0 { -1.0 } else { 1.0 } * (10.0 + next(340) as f64);
                    let (cx, cy) = (x - r * a0.to_radians().cos(), y - r * a0.to_radians().sin());
                    let (ex, ey) = (cx + r * a1.to_radians().cos(), cy + r * a1.to_radians().sin());
                    let g = if a1 < a0 { 2 } else { 3 };
                    let f = 60.0 * (300.0 * r).sqrt() * (1 + next(9)) as f64 / 10.0;
                    let (x2, y2) = (next(40) as f64 - 20.0, next(40) as f64 - 20.0);
                    // Then a feed on, or a second circle of the same size about a centre at a
                    // random angle from the first one's end (G2 or G3: the corner any angle).
                    let on = if next(2) == 0 {
                        format!("G1 X{x2} Y{y2}\n")
                    } else {
                        let b = (next(360) as f64).to_radians();
                        let (dx, dy) = (r * b.cos(), r * b.sin());
                        format!(
                            "G{} X{:.4} Y{:.4} I{dx:.4} J{dy:.4}\n",
                            2 + next(2),
                            ex + 2.0 * dx,
                            ey + 2.0 * dy
                        )
                    };
                    format!(
                        "G1 X{x} Y{y} F{f:.0}\nG{g} X{ex:.4} Y{ey:.4} I{:.4} J{:.4}\n{on}",
                        cx - x,
                        cy - y
                    )
                }
                1 => "G61.1\n".into(),
                2 => format!("G64 P{}\n", next(5) as f64 * 0.05),
                3 => "G64\n".into(),
                4 => format!("G81 X{x} Y{y} Z-2 R{} F300\nG80\n", 1 + next(3)),
                5 => format!("G0 X{x} Y{y} Z5\nG33.1 Z-3 K1\n"),
                6 => format!("G4 P0.0{}\n", 1 + next(9)),
                7 => "M5\nM3 S600\n".into(),
                _ => format!("G0 X{x} Y{y} Z{z}\n"),
            });
        }
        text.push_str("M5\nM2\n");
        let mut m = nc_engine::Machine::new("linuxcnc").unwrap();
        m.params.set("nc.trajectory_planner", None, 209.0).unwrap();
        m.params.set("nc.period_us", None, 1000.0).unwrap();
        let prog = m.parse(&text).unwrap();
        let inputs = match case % 3 {
            0 => InputSchedule::default(),
            1 => InputSchedule::default()
                .at(200_000 + next(2_000_000), Input::FeedHold)
                .at(3_000_000, Input::CycleStart),
            _ => {
                let mut s = InputSchedule::default().at(0, Input::SingleBlock(true));
                for k in 1..60 {
                    s = s.at(k * 700_000, Input::CycleStart);
                }
                s
            }
        };
        let opts = RunOptions { inputs, time_limit_us: 120_000_000, ..RunOptions::default() };
        let trace = m.run_to_trace(&prog, &opts);
        assert_eq!(check(&trace, &Limits::of(&m), None), vec![], "case {case}:\n{text}");
    }
}

/// The closest the path comes to the point (`x`, `y`) (mm) and the slowest path speed (mm/s) while
/// within 1 mm of it.
fn pass_by(t: &Trace, (px, py): (f64, f64)) -> (f64, f64) {
    let (x, y) = (axis(t, 0), axis(t, 1));
    let near = |k: usize| (x[k] - px).hypot(y[k] - py);
    let closest = (0..x.len()).map(near).fold(f64::INFINITY, f64::min);
    let slowest = (1..x.len())
        .filter(|&k| near(k) < 1.0)
        .map(|k| (x[k] - x[k - 1]).hypot(y[k] - y[k - 1]) * 1e3)
        .fold(f64::INFINITY, f64::min);
    (closest, slowest)
}

/// `recordings/debian-2.9-g64/g64_arcs`: a G1 into a G2 half circle (R5 about X15) and out into a
/// G1, at F600, 90° corners both. 2.9 joins each with a blend arc tangent to the line and to the
/// circle (blendmath.c `blendInit3FromLineArc` / `blendLineArcPostProcess`, and the arc-to-line
/// pair), by hand: θ = 45°, v_plan = 10 · 1.2 = 12 mm/s (the feed override's top), the
/// parabolic-blend radius R = (12/254 · 12)/(π/2) = 0.3609 mm (≥ 12²/440), its centre R off the
/// line and 5 + R from the circle's: d_L = √(25 + 10R) − 5 = 0.3488 mm, the corner passed at
/// √(d_L² + R²) − R = 0.1410 mm, at the feed (10 mm/s: 277 mm/s² across). Under G64 P0.05 the
/// tolerance bounds it: d = 0.05 · cos 45°/(1 − sin 45°) = 0.1207 mm = R, √(440 · R) = 7.29 mm/s,
/// the corner passed at 0.049 mm. The planner after 2.9 stops at both corners.
#[test]
fn a_g64_line_and_a_g2_arc_are_joined_by_2_9_s_blend_arcs() {
    use nc_engine::invariants::physics::{check, Limits};
    let program = |g64: &str| {
        format!("G21 G90 G17 {g64}\nG0 X0 Y0 Z1\nG1 Z0 F600\nG1 X10\nG2 X20 Y0 I5 J0\nG1 X30\nG0 Z5\nM2\n")
    };
    let t = run(209.0, &program("G64"));
    for corner in [(10.0, 0.0), (20.0, 0.0)] {
        let (closest, slowest) = pass_by(&t, corner);
        assert!((closest - 0.1410).abs() < 0.003, "{corner:?}: {closest} mm");
        assert!(slowest > 9.9, "{corner:?}: {slowest} mm/s");
    }
    // Y leaves the line at X 10 − d_L = 9.651.
    let (x, y) = (axis(&t, 0), axis(&t, 1));
    let k = y.iter().position(|v| *v > 0.0).unwrap();
    assert!((x[k - 1] - 9.651).abs() < 0.011, "Y leaves at X {}", x[k - 1]);
    // The centripetal 10²/0.3609 = 277 mm/s² on Y, within √¾ of 508 and the axes' limits.
    let peak_y = peak_accel_and_time(&y).0;
    assert!((peak_y - 277.0).abs() < 12.0 && peak_y < 440.0, "{peak_y} mm/s²");
    let mut m = nc_engine::Machine::new("linuxcnc").unwrap();
    for (id, ax, v) in [("nc.period_us", None, 1000.0), ("nc.trajectory_planner", None, 209.0)] {
        m.params.set(id, ax, v).unwrap();
    }
    for ax in ['X', 'Y', 'Z'] {
        m.params.set("nc.rapid_mm_min", Some(ax), 1828.8).unwrap();
        m.params.set("nc.rapid_ramp_ms", Some(ax), 60.0).unwrap();
    }
    assert_eq!(check(&t, &Limits::of(&m), None), vec![]);
    // G64 P0.05: within the tolerance, slower.
    let p = run(209.0, &program("G64 P0.05"));
    for corner in [(10.0, 0.0), (20.0, 0.0)] {
        let (closest, slowest) = pass_by(&p, corner);
        assert!(closest <= 0.05 && closest > 0.045, "{corner:?}: {closest} mm");
        assert!((slowest - 7.29).abs() < 0.1, "{corner:?}: {slowest} mm/s");
    }
    // After 2.9 (and under G61.1): exact stops on the corners.
    for t in [run(210.0, &program("G64")), run(209.0, &program("G61.1"))] {
        for corner in [(10.0, 0.0), (20.0, 0.0)] {
            let (closest, slowest) = pass_by(&t, corner);
            assert!(closest < 1e-6 && slowest < 1.0, "{corner:?}: {closest} mm, {slowest} mm/s");
        }
    }
}

/// Two G2/G3 arcs meeting at 90°: `G3 X30 Y0 I5 J0` (from X20) into `G2 X30 Y-10 I0 J-5` at
/// F600, joined by 2.9's arc-to-arc blend (tp.c `tpCreateArcArcBlend`): the second circle is
/// convex at the corner (it bends away from the turn), so θ = 45° − (π/4)/4 and the arc is the
/// speed's: R = 12²/440 = 0.3273 mm, tangent to both circles, the corner passed at 0.1360 mm
/// (by hand: `exec/arc_blend.rs`), at the feed. Where two arcs continue tangentially (the G2's
/// end into the G3) there is none: 2.9's tangent join runs on at the feed.
#[test]
fn two_g64_arcs_that_turn_are_joined_by_2_9_s_blend_arc() {
    let program = "G21 G90 G17\nG0 X0 Y0 Z0\nG1 X10 F600\nG2 X20 Y0 I5 J0\nG3 X30 Y0 I5 J0\n\
                   G2 X30 Y-10 I0 J-5\nG1 X0 Y-10\nM2\n";
    let t = run(209.0, program);
    let (closest, slowest) = pass_by(&t, (30.0, 0.0));
    assert!((closest - 0.1360).abs() < 0.003, "{closest} mm");
    assert!(slowest > 9.9, "{slowest} mm/s");
    let (closest, slowest) = pass_by(&t, (20.0, 0.0));
    assert!(closest < 0.011 && slowest > 9.9, "{closest} mm, {slowest} mm/s");
    // Through the corner the centripetal 10²/0.3273 = 306 mm/s², within √¾ of 508.
    let (x, y) = (axis(&t, 0), axis(&t, 1));
    let acc = accel_magnitudes(&t);
    let peak =
        (1..x.len() - 1).filter(|&k| (x[k] - 30.0).hypot(y[k]) < 1.0).map(|k| acc[k - 1]).fold(0.0, f64::max);
    assert!((peak - 305.5).abs() < 10.0 && peak < 440.0, "{peak} mm/s²");
    let after = run(210.0, program);
    assert!(pass_by(&after, (30.0, 0.0)).0 < 0.001);
}

/// 2.9's tangent join (tp.c `tpSetupTangent`: `TC_TERM_COND_TANGENT` where the kink needs under a
/// tenth of the acceleration): two G1 in line, a G1 into a G3 that starts along it and the G3 into
/// a G1 that leaves along its end run on at the feed (10 mm/s), without an arc (the path through
/// the joins exact); the planner after 2.9, and G61.1, stop at each.
#[test]
fn g64_moves_that_continue_tangentially_run_on_at_the_feed_in_2_9() {
    let program = |mode: &str| {
        format!("G21 G90 G17 {mode}\nG0 X0 Y0 Z0\nG1 X10 F600\nG1 X20\nG3 X30 Y10 I0 J10\nG1 Y20\nM2\n")
    };
    let joins = [(10.0, 0.0), (20.0, 0.0), (30.0, 10.0)];
    let t = run(209.0, &program("G64"));
    for j in joins {
        let (closest, slowest) = pass_by(&t, j);
        assert!(closest < 0.011 && slowest > 9.9, "{j:?}: {closest} mm, {slowest} mm/s");
    }
    // On the path: Y stays 0 up to X20, X stays 30 from Y10.
    let (x, y) = (axis(&t, 0), axis(&t, 1));
    assert!(x.iter().zip(&y).all(|(x, y)| *x > 20.0 || *y == 0.0));
    assert!(x.iter().zip(&y).all(|(x, y)| *y < 10.0 || (*x - 30.0).abs() < 1e-6));
    for t in [run(210.0, &program("G64")), run(209.0, &program("G61.1"))] {
        for j in joins {
            let (closest, slowest) = pass_by(&t, j);
            assert!(closest < 0.001 && slowest < 1.0, "{j:?}: {closest} mm, {slowest} mm/s");
        }
    }
}
