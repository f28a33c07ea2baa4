//! The one thread-pass executor (`Step::Thread`, `exec/thread.rs`) on every cycle that uses it:
//! GSK G92.3 (locked law after a catch-up ramp, variable lead, DEC-146), Heidenhain cycle 832, KND
//! G32/G92 and LinuxCNC G33/G76 (accelerated law, constant lead). For each: the spindle-angle law
//! sample by sample, and the pass' thread starting at the spindle's index plus the pass' phase.
//! Plus the proof that folding the two former executors into one left the 832 traces as they were
//! (digests of the traces of the executor before the change).

mod support;

use nc_engine::input::{Condition, Input, InputSchedule};
use nc_engine::trace::{Event, Phase, Trace};
use nc_engine::RunOptions;
use support::run;

const MM: f64 = 1e6;

fn sampled(inputs: InputSchedule) -> RunOptions {
    RunOptions { inputs, sample_us: 1000, ..RunOptions::default() }
}

/// One pass as sampled: the spindle's unwrapped revolutions (absolute: the index is at whole
/// numbers) when the cutting phase began, at the last sample before the drive axis moved, and at
/// every sample from the first that moved on, with the drive axis' travel there (nm).
struct Pass {
    at_phase: f64,
    still: f64,
    moving: Vec<(f64, f64)>,
}

/// Every cutting phase of `t` in which `axis` (scaled by `scale`: 0.5 for a lathe's diameter X)
/// moves.
fn passes(t: &Trace, axis: usize, scale: f64) -> Vec<Pass> {
    let phases: Vec<(u64, Phase)> = t.phases().collect();
    let cuts: Vec<(u64, u64)> =
        phases.windows(2).filter(|w| w[0].1 == Phase::Cutting).map(|w| (w[0].0, w[1].0)).collect();
    let mut revs = Vec::new();
    let (mut r, mut last) = (0.0, None);
    for (tu, s) in t.samples() {
        if let Some(l) = last {
            r += ((s.spindle_mdeg - l) as f64).rem_euclid(360_000.0) / 360_000.0;
        } else {
            r = s.spindle_mdeg as f64 / 360_000.0;
        }
        last = Some(s.spindle_mdeg);
        revs.push((tu, r, s.axes[axis] as f64 * scale));
    }
    let mut out = Vec::new();
    for (a, b) in cuts {
        let i0 = revs.iter().rposition(|s| s.0 <= a).unwrap();
        let start = revs[i0].2;
        let Some(i1) = (i0 + 1..revs.len()).find(|&i| revs[i].0 < b && revs[i].2 != start) else {
            continue;
        };
        let moving = revs[i1..].iter().take_while(|s| s.0 <= b).map(|s| (s.1, (s.2 - start).abs())).collect();
        out.push(Pass { at_phase: revs[i0].1, still: revs[i1 - 1].1, moving });
    }
    out
}

/// For a dialect without phase events (KND): every run of samples in which Z goes down (the
/// threads of the program; its rapids go up or along X), the sample before it standing for the
/// phase's start.
fn passes_down_z(t: &Trace) -> Vec<Pass> {
    let mut out: Vec<Pass> = Vec::new();
    let (mut r, mut last, mut prev) = (0.0, None::<i64>, None::<(f64, f64)>);
    let mut open = false;
    let mut z0 = 0.0;
    for (_, s) in t.samples() {
        if let Some(l) = last {
            r += ((s.spindle_mdeg - l) as f64).rem_euclid(360_000.0) / 360_000.0;
        } else {
            r = s.spindle_mdeg as f64 / 360_000.0;
        }
        last = Some(s.spindle_mdeg);
        let z = s.axes[2] as f64;
        match prev {
            Some((pr, pz)) if z < pz => {
                if !open {
                    out.push(Pass { at_phase: pr, still: pr, moving: Vec::new() });
                    open = true;
                    z0 = pz;
                }
                out.last_mut().unwrap().moving.push((r, z0 - z));
            }
            _ => open = false,
        }
        prev = Some((r, z));
    }
    out
}

/// The first revolution count at or after `from` whose fraction is `phase`.
fn next_angle(from: f64, phase: f64) -> f64 {
    let k = (from - phase).ceil();
    k + phase
}

/// Accelerated law, constant lead `lead` nm/rev, start at index + `phase(k)` of pass k: the pass
/// starts at the first such angle after its cutting phase began (a steady spindle), between the
/// last still sample and the first moving one, and once at speed the drive axis is exactly
/// `lead × (revolutions since that angle) − v²/(2a)`, the same constant on every pass. Returns
/// the waits (revolutions from the phase to the start) and the constant.
fn check_accelerated(ps: &[Pass], lead: f64, phase: impl Fn(usize) -> f64) -> (Vec<f64>, f64) {
    assert!(!ps.is_empty());
    let mut waits = Vec::new();
    let mut lag = None;
    let q = 1.0 / 360_000.0;
    for (k, p) in ps.iter().enumerate() {
        let start = next_angle(p.at_phase - q, phase(k));
        assert!(
            p.still - q <= start && start <= p.moving[0].0 + q,
            "pass {k}: {} {start} {}",
            p.still,
            p.moving[0].0
        );
        waits.push(start - p.at_phase);
        // Cruise: the travel per revolution between consecutive samples is the lead.
        let cruise: Vec<&(f64, f64)> = p
            .moving
            .windows(2)
            .filter(|w| w[1].0 > w[0].0 && ((w[1].1 - w[0].1) / (w[1].0 - w[0].0) - lead).abs() < lead * 1e-3)
            .map(|w| &w[1])
            .collect();
        assert!(cruise.len() > 20, "pass {k}: {} cruise samples", cruise.len());
        for &&(r, s) in &cruise {
            let l = lead * (r - start) - s;
            let want = *lag.get_or_insert(l);
            // Angle in milli-degrees (lead/360000 nm), positions in nm.
            assert!((l - want).abs() < lead * q + 2.0, "pass {k} at {r}: lag {l} vs {want}");
        }
    }
    (waits, lag.unwrap())
}

/// Locked law with lead `f` and lead change `d` (DEC-146): pass k's law starts at the first
/// index + `phase(k)` after its last still sample; the drive axis itself started before that
/// angle, on its catch-up ramp, and once caught up every sample is on `f·n + d·n²/2` (n
/// revolutions since that angle), travel per turn sqrt(f² + 2·d·s), until the deceleration before
/// `len`: every pass on its own groove, whatever the ramp.
fn check_locked(ps: &[Pass], f: f64, d: f64, len: f64, phase: impl Fn(usize) -> f64) {
    let law = |n: f64| f * n + d * n * n / 2.0;
    for (k, p) in ps.iter().enumerate() {
        let start = next_angle(p.still, phase(k));
        assert!(p.still < start && p.moving[0].0 < start, "pass {k}: the ramp starts before the angle");
        // The first sample on the law, then every one until 1 mm before the end.
        let first = p.moving.iter().position(|&(r, s)| (s - law(r - start)).abs() < 15.0);
        let first = first.unwrap_or_else(|| panic!("pass {k} never on the law"));
        let mut checked = 0;
        for w in p.moving[first..].windows(2) {
            let (r, s) = w[1];
            if s >= len - 1e6 {
                break;
            }
            // The law at every sample: within the quantisation of the sampled angle (1 mdeg).
            let n = r - start;
            assert!((s - law(n)).abs() < 15.0, "pass {k}, n {n}: {s} vs {}", law(n));
            // Travel per turn between samples: sqrt(F² + 2·D·s) at the middle.
            let (dn, ds) = (w[1].0 - w[0].0, w[1].1 - w[0].1);
            let per_turn = (f * f + 2.0 * d * 0.5 * (w[0].1 + w[1].1)).sqrt();
            assert!((ds / dn - per_turn).abs() < per_turn * 1e-3, "{} vs {per_turn}", ds / dn);
            checked += 1;
        }
        assert!(checked > 500, "{checked}");
        // Caught up within the ramp's travel: v²/2a at most (0.56 mm at 33 mm/s, 1000 mm/s²).
        assert!(p.moving[first].1 < 0.6e6, "pass {k}: caught up at {}", p.moving[first].1);
    }
}

const G923: &str = "G0 X40 Z5;\nM03 S500;\nG92.3 X36 Z-20 F4 J1 K2 D0.1 E1 Q0.5 A1;\nG0 X60;\nM30;\n";

#[test]
fn g923_locked_law_with_variable_lead_from_index_plus_phase() {
    // Seed 002's example: F4 D0.1, E1 Q0.5 A1: 5 passes started 0, 1/8 .. 4/8 of a turn after
    // the index; travel after n turns F·n + D·n²/2, i.e. travel per turn sqrt(F² + 2·D·s).
    let t = run("gsk-lathe", &[], G923, &sampled(InputSchedule::default()));
    assert_eq!(t.alarms().count(), 0);
    let ps = passes(&t, 2, 1.0);
    assert_eq!(ps.len(), 5);
    for (k, p) in ps.iter().enumerate() {
        // Each pass' law starts at the first of its start angles after it is reached; the axis
        // leaves the cut start before it, on its catch-up ramp (DEC-146).
        let start = next_angle(p.at_phase, k as f64 / 8.0);
        assert!(p.still < start && p.moving[0].0 < start, "pass {k}");
    }
    check_locked(&ps, 4.0 * MM, 0.1 * MM, 25.0 * MM, |k| k as f64 / 8.0);
}

#[test]
fn g923_a_feed_hold_during_the_wait_for_the_start_angle_keeps_the_pass_on_its_groove() {
    // With thread retract on, a feed hold 1 ms into the third pass' cutting phase falls in its wait
    // for the index + 1/4 turn (no motion to retract): the control holds there; cycle start 0.3 s
    // later waits for the start angle again (not the one that passed meanwhile).
    let hold = InputSchedule::default()
        .when(Condition::Phase(Phase::Cutting), 3, 1000, Input::FeedHold)
        .when(Condition::Phase(Phase::Cutting), 3, 301_000, Input::CycleStart);
    let t = run("gsk-lathe", &[("nc.thread_retract", None, 1.0)], G923, &sampled(hold));
    assert_eq!(t.alarms().count(), 0, "{}", support::events(&t));
    let ps = passes(&t, 2, 1.0);
    assert_eq!(ps.len(), 5);
    // The third pass started after the cycle start, at least 0.3 s (2.5 turns at S500) late.
    assert!(ps[2].moving[0].0 - ps[2].at_phase > 2.5, "{}", ps[2].moving[0].0 - ps[2].at_phase);
    check_locked(&ps, 4.0 * MM, 0.1 * MM, 25.0 * MM, |k| k as f64 / 8.0);
}

#[test]
fn c832_accelerated_law_from_the_start_angle_same_helix_every_pass() {
    // Two starts (Q475=2) from Q470=30°: passes of start j begin at 30° + j·180°.
    let mut s = String::from(
        "0 BEGIN PGM T MM\n1 FUNCTION MODE TURN\n2 TOOL CALL 1 S600\n3 L X+30 Z+5 R0 FMAX M303\n\
         4 CYCL DEF 832 THREAD EXTENDED\n",
    );
    let q = [
        (471, "0"),
        (461, "0"),
        (460, "1"),
        (472, "1.5"),
        (473, "0.6"),
        (464, "0"),
        (491, "20"),
        (492, "0"),
        (493, "20"),
        (494, "-20"),
        (469, "0"),
        (474, "0"),
        (465, "2"),
        (466, "2"),
        (463, "0.2"),
        (467, "30"),
        (468, "1"),
        (470, "30"),
        (475, "2"),
        (476, "0"),
    ];
    for (n, v) in q {
        s.push_str(&format!("  Q{n}={v}\n"));
    }
    s.push_str("5 CYCL CALL\n6 L X+40 Z+20 FMAX M305\n7 M30\n8 END PGM T MM\n");
    let t = run("heidenhain", &[], &s, &sampled(InputSchedule::default()));
    assert_eq!(t.alarms().count(), 0, "{}", support::events(&t));
    let ps = passes(&t, 2, 1.0);
    let per_start = ps.len() / 2;
    assert!(per_start >= 3, "{}", ps.len());
    let (waits, lag) = check_accelerated(&ps, 1.5 * MM, |k| (30.0 + 180.0 * (k / per_start) as f64) / 360.0);
    // v = 1.5 mm x 10 rev/s = 15 mm/s, a = 6000 mm/min per 100 ms = 1000 mm/s²: v²/2a = 0.1125 mm.
    assert!((lag - 112_500.0).abs() < 200.0, "{lag}");
    assert!(waits.iter().all(|w| (0.0..1.0).contains(w)), "{waits:?}");
}

#[test]
fn knd_g32_and_g92_start_at_the_one_revolution_signal_at_lead_times_speed() {
    // Seed 001: "螺纹切削开始是从检测出主轴上的位置编程器一转信号后才开始的": every pass of the
    // same thread starts at the index, so the passes cut one groove.
    let prog = "G00 X30 Z5;\nM03 S600;\nG04 P500;\nG32 Z-20 F2;\nG00 X40;\nZ5;\nG92 X29 Z-20 F2;\nX28.5;\nX28;\nM30;\n";
    let t = run("knd-lathe", &[], prog, &sampled(InputSchedule::default()));
    assert_eq!(t.alarms().count(), 0, "{}", support::events(&t));
    let ps = passes_down_z(&t);
    assert_eq!(ps.len(), 4);
    // (Without phase events the wait cannot be measured; the start angle and the one groove can.)
    let (_, lag) = check_accelerated(&ps, 2.0 * MM, |_| 0.0);
    // 2 mm x 10 rev/s = 20 mm/s at 1000 mm/s²: 0.2 mm behind the locked law.
    assert!((lag - 200_000.0).abs() < 200.0, "{lag}");
}

#[test]
fn knd_g32_taper_lead_is_along_the_long_axis() {
    // Seed 001: "F 是公制螺纹的螺距,为主轴转一圈长轴的位移量" - Z (25 mm) is the long axis of
    // X30 → X40 (5 mm radius) over Z5 → Z-20.
    let prog = "G00 X30 Z5;\nM03 S600;\nG04 P500;\nG32 X40 Z-20 F2;\nM30;\n";
    let t = run("knd-lathe", &[], prog, &sampled(InputSchedule::default()));
    assert_eq!(t.alarms().count(), 0);
    check_accelerated(&passes_down_z(&t), 2.0 * MM, |_| 0.0);
}

/// LinuxCNC's planner sees the index one servo period after the period it falls in (the encoder
/// clears index-enable after motion has run, motion copies the pin into its status after its
/// planner; tp.c tpCheckAtSpeed, control.c), so its pass starts 1 ms after the start angle: at
/// S600, 0.01 of a turn (DEC-157; adapter run of `g331/g33_index`: index in the period ending at
/// 750 ms, the planner's first step at 752 ms).
const LCNC_INDEX_LATENCY_REV: f64 = 600.0 / 60_000.0;

#[test]
fn linuxcnc_g33_starts_at_the_next_index_pulse() {
    // LinuxCNC's motion controller waits for the encoder's index (index-enable, cleared at the
    // next index pulse) before a synchronised move: anything from 0 to one revolution.
    let prog = "G18 G21 M3 S600\nG4 P0.5\nG0 X10 Z5\nG33 Z-20 K1.5\nG0 X12\nG0 Z5\nG0 X10\nG4 P0.033\nG33 Z-20 K1.5\nM2\n";
    let t = run("linuxcnc", &[], prog, &sampled(InputSchedule::default()));
    assert_eq!(t.alarms().count(), 0, "{}", support::events(&t));
    let ps = passes(&t, 2, 1.0);
    assert_eq!(ps.len(), 2);
    let (waits, _) = check_accelerated(&ps, 1.5 * MM, |_| LCNC_INDEX_LATENCY_REV);
    assert!(waits.iter().all(|w| (0.0..1.0).contains(w)) && waits.iter().any(|w| *w > 0.05), "{waits:?}");
}

#[test]
fn linuxcnc_g76_every_pass_starts_at_the_next_index_pulse_on_one_groove() {
    let prog =
        "G18 G21 G8 M3 S600\nG4 P0.5\nG0 X7 Z3\nG76 P1.5 Z-20 I-1 J0.25 K0.92 R2 Q0 H1 E2 L2\nG0 X20\nM2\n";
    let t = run("linuxcnc", &[], prog, &sampled(InputSchedule::default()));
    assert_eq!(t.alarms().count(), 0, "{}", support::events(&t));
    let ps = passes(&t, 2, 1.0);
    assert_eq!(ps.len(), 15);
    let (waits, lag) = check_accelerated(&ps, 1.5 * MM, |_| LCNC_INDEX_LATENCY_REV);
    // Q0: every pass starts at Z3, so one groove means one lag: 15 mm/s at 1000 mm/s² (0.1125 mm).
    assert!((lag - 112_500.0).abs() < 200.0, "{lag}");
    assert!(waits.iter().all(|w| (0.0..1.0).contains(w)), "{waits:?}");
}

/// LinuxCNC's G76 with an entry taper (L3): each pass first feeds in along X, synchronised at the
/// taper's lead and waiting for the index (interp_convert.cc `threading_pass`), then the taper and
/// the thread track it without a new index. Z therefore starts a fraction of a turn after the
/// index, but every pass cuts the one groove: Z's travel less lead × revolutions is the same
/// constant, modulo one lead, on the thread of every pass.
#[test]
fn linuxcnc_g76_with_an_entry_taper_feeds_in_synchronised_and_keeps_one_groove() {
    let prog =
        "G18 G21 G8 M3 S600\nG4 P0.5\nG0 X7 Z3\nG76 P1.5 Z-20 I-1 J0.25 K0.92 R2 Q0 H1 E2 L3\nG0 X20\nM2\n";
    let t = run("linuxcnc", &[], prog, &sampled(InputSchedule::default()));
    assert_eq!(t.alarms().count(), 0, "{}", support::events(&t));
    let ps = passes(&t, 2, 1.0);
    assert_eq!(ps.len(), 15);
    // The groove: (lead × revolutions − Z travel) / lead, modulo 1, late in each pass (on the
    // thread, at speed).
    let lead = 1.5 * MM;
    let grooves: Vec<f64> = ps
        .iter()
        .map(|p| {
            let (r, z) = p.moving[p.moving.len() * 2 / 3];
            ((lead * r - z) / lead).rem_euclid(1.0)
        })
        .collect();
    for g in &grooves {
        let d = (g - grooves[0]).rem_euclid(1.0);
        assert!(d.min(1.0 - d) < 1e-3, "{grooves:?}");
    }
    // Z waits for the infeed: 1 mm of X at the taper's lead, 1.5 × √(2² + 0.92²) / 2 = 1.651
    // mm per turn, with its ramp: Z starts over 0.6 of a turn after the index the pass took
    // (where a rapid infeed had it start at the index itself), and within a turn and a half.
    let q = 1.0 / 360_000.0;
    for (k, p) in ps.iter().enumerate() {
        let index = next_angle(p.at_phase - q, LCNC_INDEX_LATENCY_REV);
        let late = p.still - index;
        assert!((0.6..1.5).contains(&late), "pass {k}: Z starts {late} turns after the index");
    }
}

/// DEC-170: LinuxCNC's second G33 straight after a first goes on with the synchronisation (tp.c
/// waits for the index only "if we aren't already synced"): Z stands at the first's end for at
/// most two servo periods (exact stop), whatever the spindle's angle there; a new index would
/// cost up to a turn (100 ms at 600 rpm). Recorded on 2.9: `debian-2.9-fresh/g33_g91_chain`
/// and `_g61_1`.
#[test]
fn linuxcnc_a_g33_after_a_g33_takes_no_new_index() {
    for s in [577, 600, 613, 641] {
        let prog =
            format!("G18 G21 G61.1 M3 S{s}\nG4 P0.5\nG0 X10 Z5\nG33 Z-5 K1.5\nG33 X11 Z-10 K1.5\nM2\n");
        let t = run("linuxcnc", &[], &prog, &sampled(InputSchedule::default()));
        assert_eq!(t.alarms().count(), 0, "{}", support::events(&t));
        let at_joint: Vec<u64> = t
            .samples()
            .filter(|(_, x)| (x.axes[2] - (-5 * MM as i64)).abs() < 1_000 && x.axes[0] < 10_001_000)
            .map(|(tu, _)| tu)
            .collect();
        let still = at_joint.last().unwrap() - at_joint.first().unwrap();
        assert!(still <= 2_000, "S{s}: Z stood {still} µs at the joint");
    }
}

/// FNV-1a over the trace: every event, samples with all axes, speed and angle.
fn digest(events: &[nc_engine::trace::TraceEvent]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for e in events {
        let line = match &e.event {
            Event::Sample(s) => format!("{} {:?} {} {}\n", e.t_us, s.axes, s.spindle_mrpm, s.spindle_mdeg),
            other => format!("{} {other:?}\n", e.t_us),
        };
        for b in line.bytes() {
            h = (h ^ b as u64).wrapping_mul(0x100_0000_01b3);
        }
    }
    h
}

#[test]
fn the_one_executor_gives_the_traces_of_the_two_it_replaced() {
    // Digests of whole traces (1 ms samples) written by `exec/thread_832.rs` (cycle 832) before
    // it was folded into the one executor. (The G92.3 digests of `exec/thread.rs` went with
    // DEC-146: its passes now start on a catch-up ramp instead of at thread speed, by design.)
    let c832 = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenarios/heidenhain/c832/longitudinal_outside.yaml"
    ))
    .unwrap();
    let prog: String = c832
        .split("program: |\n")
        .nth(1)
        .unwrap()
        .lines()
        .take_while(|l| l.starts_with("  ") || l.is_empty())
        .map(|l| format!("{}\n", l.strip_prefix("  ").unwrap_or(l)))
        .collect();
    let t = run("heidenhain", &[], &prog, &sampled(InputSchedule::default()));
    assert_eq!(digest(&t.events), C832_BEFORE);
}

const C832_BEFORE: u64 = 11174102450272644338;

#[test]
fn a_pass_that_finds_the_spindle_stalled_raises_its_dialects_alarm() {
    // The pass carries its dialect's alarm: GSK's and KND's 0011. (LinuxCNC waits for the spindle
    // at speed instead: the next test.)
    let stall = || InputSchedule::default().at(600_000, Input::SpindleStall(true));
    let cases = [
        ("knd-lathe", "G00 X30 Z5;\nM03 S600;\nG04 P700;\nG32 Z-20 F2;\nM30;\n", "0011"),
        ("gsk-lathe", "G0 X40 Z5;\nM03 S500;\nG04 P700;\nG92.3 X36 Z-20 F4 E1 Q0.5 A1;\nM30;\n", "0011"),
    ];
    for (dialect, prog, code) in cases {
        let t = run(dialect, &[], prog, &sampled(stall()));
        let codes: Vec<&str> = t.alarms().map(|(_, a)| a.kind.code()).collect();
        assert_eq!(codes, [code], "{dialect}: {}", support::events(&t));
    }
}

#[test]
fn a_linuxcnc_pass_waits_for_a_stalled_spindle_to_be_at_speed() {
    // LinuxCNC's planner starts a position-synchronised move that is not yet synchronised only
    // once spindle.0.at-speed is true (tp.c `needs_atspeed`): a stalled spindle never gives it,
    // so G33 and every G76 pass wait where they stand, without an alarm, until the time limit.
    let stall = InputSchedule::default().at(600_000, Input::SpindleStall(true));
    let opts = RunOptions { time_limit_us: 3_000_000, ..sampled(stall) };
    for prog in [
        "G18 G21 M3 S600\nG4 P0.7\nG33 Z-20 K1.5\nM2\n",
        "G18 G21 M3 S600\nG0 X7 Z3\nG4 P0.7\nG76 P1.5 Z-20 I-1 J0.25 K0.92\nM2\n",
    ] {
        let t = run("linuxcnc", &[], prog, &opts);
        assert_eq!(t.alarms().count(), 0, "{prog}: {}", support::events(&t));
        let end = t.end().unwrap_or_else(|| panic!("{prog}: no end"));
        assert_eq!(end.reason.name(), "time_limit", "{prog}");
        let last = t.samples().last().map(|(_, s)| s.axes).unwrap_or_else(|| panic!("{prog}: no sample"));
        assert!(last[2] >= 0, "{prog}: the pass has not started, Z = {}", last[2]);
    }
}
