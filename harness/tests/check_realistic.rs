//! Verdicts on realistic recordings (issue 14): recordings derived from reference runs the way a
//! real recorder sees a conformant machine (another clock, 4 ms samples with jitter, 1 µm encoder
//! noise, lost samples, every PLC edge 2–8 ms late, no block lines) must be conformant, for every
//! dialect; and a recording with one defect must be divergent, naming it.

mod check_util;

use std::path::PathBuf;

use check_util::*;
use nc_conform::conform::suite::scenario_files;
use nc_conform::scenario::load;
use nc_engine::trace::{Event, Signal, Trace, TraceEvent};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every scenario of the library that runs, recorded by a PLC-scan recorder from its own
/// reference run (4 ms samples, ± 300 µs jitter, 1 µm and 0.05° noise, one sample in 40 lost,
/// every edge 2–8 ms late, no block lines, no phases, another clock), is conformant. Before
/// issue 14: 97 of 456 were not (block-windowed rules "never opened", G98 sync error under a
/// late stroke-end edge, the final speed of a ramping spindle, a late F76.3 fall counting a
/// reversal).
#[test]
fn every_library_scenario_recorded_with_plc_scan_lateness_is_conformant() {
    let mut bad = Vec::new();
    let mut n = 0;
    for p in scenario_files(&root().join("scenarios")) {
        let name = p.strip_prefix(root()).unwrap().display().to_string();
        let s = load::load(&p, &name).unwrap();
        if s.refusal.is_some() {
            continue;
        }
        n += 1;
        let reference = reference(&s);
        let r = check(&s, &reference, record(&reference, Rec::PLC_SCAN));
        if !r.conformant() {
            bad.push(format!("{name}\n{}", show(&r, &reference)));
        }
    }
    assert!(n > 400, "the library is found");
    assert!(bad.is_empty(), "{} of {n} diverge:\n{}", bad.len(), bad.join("\n"));
}

/// Issue 14 §1: Fanuc rigid G84 under G98: the rapid up starts in the millisecond the retract
/// ends, so a stroke-end edge (RGSPP/RGSPM falling) recorded a few ms late, the rest on time,
/// once gave a 0.03–0.10 mm "sync error": the sync windows now come from the reference.
#[test]
fn g98_rigid_tap_with_a_late_stroke_end_edge_is_conformant() {
    for rel in [
        "scenarios/fanuc/return_level/g99_then_g98_rigid.yaml",
        "scenarios/fanuc/seed/peck_rigid_example.yaml",
    ] {
        let s = scenario(rel);
        let reference = reference(&s);
        for late in [2000, 4000, 8000] {
            // Each stroke end not followed at once by the next stroke (the end of a hole).
            let rises: Vec<u64> = reference
                .events
                .iter()
                .filter(|e| {
                    matches!(e.event, Event::Signal { signal: Signal::Rgspp | Signal::Rgspm, value: true })
                })
                .map(|e| e.t_us)
                .collect();
            let mut t = reference.clone();
            let mut moved = 0;
            for e in &mut t.events {
                if matches!(e.event, Event::Signal { signal: Signal::Rgspp | Signal::Rgspm, value: false })
                    && !rises.iter().any(|&r| r >= e.t_us && r <= e.t_us + 50_000)
                {
                    e.t_us += late;
                    moved += 1;
                }
            }
            assert!(moved > 0);
            t.events.sort_by_key(|e| e.t_us);
            let r = check(&s, &reference, record(&t, Rec::REALISTIC));
            assert!(r.conformant(), "{rel}, stroke ends {late} µs late:\n{}", show(&r, &reference));
            assert!(r.figures.sync_samples > 0, "the strokes were compared");
        }
    }
}

/// The thread axis of every sample inside the reference's synchronised moves moved away from
/// where the move started by `k` times its reference travel (a lead error of (k − 1)).
fn scale_lead(reference: &Trace, k: f64) -> Trace {
    let r = nc_conform::check::reference::Reference::new(reference);
    let windows = r.sync.clone();
    let mut t = reference.clone();
    for e in &mut t.events {
        let Event::Sample(s) = &mut e.event else { continue };
        let at = e.t_us as i64;
        if let Some(w) = windows.iter().find(|w| w.t0 <= at && at <= w.t1) {
            let p0 = r.pos_at(w.t0, w.slot).unwrap();
            let p = s.axes[w.slot] as f64;
            s.axes[w.slot] = (p0 + (p - p0) * k).round() as i64;
        }
    }
    t
}

/// Issue 14 §2: a thread cut with a 0.3 % lead error, recorded realistically, fails on the
/// synchronisation with the spindle (it passed: no sync comparison outside rigid strokes, and
/// the ± 20 ms envelope is about ± 0.6 mm at thread feed); the same recording without the error
/// passes. Every synchronised move: G92.3, cycle 832, G33.1, G33, G76, KND G93.
#[test]
fn a_lead_error_of_three_per_mille_is_caught_in_every_synchronised_move() {
    for (rel, rule) in [
        ("scenarios/gsk/g92_3/seed_example.yaml", "GSK-G923-11"),
        ("scenarios/heidenhain/c832/seed_example.yaml", "HDH-C832-05"),
        ("scenarios/linuxcnc/g331/standard.yaml", "LCNC-G331-01"),
        ("scenarios/linuxcnc/g331/g33.yaml", "LCNC-G33-01"),
        ("scenarios/linuxcnc/g76/passes.yaml", "LCNC-G76-01"),
        ("scenarios/knd/g93/standard.yaml", "KND-G93-03"),
        ("scenarios/knd/lex/threading.yaml", "KND-LEX-08"),
        ("scenarios/knd/css/taper_thread.yaml", "KND-LEX-08"),
        ("scenarios/gsk/peck/standard_seed_example.yaml", "COM-SYNC-01"),
    ] {
        let s = scenario(rel);
        let reference = reference(&s);
        let r = nc_conform::check::reference::Reference::new(&reference);
        assert!(!r.sync.is_empty(), "{rel}: synchronised moves found from the reference");
        let good = check(&s, &reference, record(&reference, Rec::PLC_SCAN));
        assert!(good.conformant(), "{rel}:\n{}", show(&good, &reference));
        assert!(good.figures.sync_samples > 10, "{rel}: compared");
        let bad = check(&s, &reference, record(&scale_lead(&reference, 1.003), Rec::PLC_SCAN));
        assert!(
            bad.divergences.iter().any(|d| d.check == "CHK-SYNC-01" && d.rule == rule),
            "{rel}: a 0.3 % lead error not caught under {rule}:\n{}",
            show(&bad, &reference)
        );
    }
}

/// Issue 14 §2: a G92.3 pass started 20° late after the index (the lead right) is caught; the
/// start angle of a LinuxCNC G33 (which the reference does not tie to the index) is not judged.
#[test]
fn a_thread_pass_started_at_the_wrong_angle_is_caught() {
    let s = scenario("scenarios/gsk/g92_3/seed_example.yaml");
    let reference = reference(&s);
    let r = nc_conform::check::reference::Reference::new(&reference);
    let mut t = reference.clone();
    for e in &mut t.events {
        let Event::Sample(x) = &mut e.event else { continue };
        if r.sync.iter().any(|w| w.t0 <= e.t_us as i64 && e.t_us as i64 <= w.t1) {
            x.spindle_mdeg = (x.spindle_mdeg + 20_000).rem_euclid(360_000);
        }
    }
    let rep = check(&s, &reference, record(&t, Rec::PLC_SCAN));
    let d = rep.divergences.iter().find(|d| d.check == "CHK-SYNC-01");
    assert!(d.is_some_and(|d| d.what.contains("start angle")), "{}", show(&rep, &reference));
}

/// Issue 14 §2: LinuxCNC has no RGSPP/RGSPM: the key points are said to be not compared (n/a),
/// never "0 mm", and the synchronisation of its G33.1 is compared from the reference's blocks
/// and phases, in a recording of positions and spindle only.
#[test]
fn linuxcnc_without_stroke_signals_says_na_and_still_compares_the_sync() {
    let s = scenario("scenarios/linuxcnc/g331/standard.yaml");
    let reference = reference(&s);
    let rec: Vec<TraceEvent> = record(&reference, Rec::PLC_SCAN)
        .into_iter()
        .filter(|e| matches!(e.event, Event::Sample(_)))
        .collect();
    let r = check(&s, &reference, rec);
    let text = show(&r, &reference);
    assert!(text.contains("n/a  key points"), "{text}");
    assert!(r.figures.sync_samples > 10, "{text}");
    let fig = nc_conform::check::report::summary(&r, &reference, "x");
    assert!(!fig.contains("max sync error 0 mm"), "{fig}");
    let s = scenario("scenarios/linuxcnc/cycles/drilling.yaml");
    let drilling = check_util::reference(&s);
    let r = check(&s, &drilling, record(&drilling, Rec::PLC_SCAN));
    assert!(show(&r, &drilling).contains("max sync error n/a"), "{}", show(&r, &drilling));
}

/// Issue 14 §2: MF falling 10 ms before FIN rises passed (both are in the same µs in the
/// reference, within 20 ms of it in the recording, and the order check fired only on a strictly
/// earlier reference time): the handshake is a protocol fact checked on the recording itself.
#[test]
fn a_strobe_falling_before_its_fin_is_caught_com_plc_01() {
    let s = scenario("scenarios/gsk/clamp/clamp_codes_frame_the_hole.yaml");
    let reference = reference(&s);
    let fin_rises: Vec<u64> = reference.edges(Signal::Fin).filter(|e| e.1).map(|e| e.0).collect();
    let mut t = reference.clone();
    let mut moved = 0;
    for e in &mut t.events {
        if matches!(e.event, Event::Signal { signal: Signal::Mf, value: false })
            && fin_rises.contains(&e.t_us)
        {
            e.t_us -= 10_000;
            moved += 1;
        }
    }
    assert!(moved > 0);
    t.events.sort_by_key(|e| e.t_us);
    let good = check(&s, &reference, record(&reference, Rec::PLC_SCAN));
    assert!(good.conformant(), "{}", show(&good, &reference));
    for rec in [Rec::EXACT, Rec::PLC_SCAN] {
        let r = check(&s, &reference, record(&t, rec));
        let d = r.divergences.iter().find(|d| d.check == "CHK-EVT-05");
        assert!(
            d.is_some_and(|d| d.rule == "COM-PLC-01" && d.what.contains("MF ↓ before FIN ↑")),
            "{}",
            show(&r, &reference)
        );
    }
}

/// Issue 14 §5: a timing shift beyond its window reads as one line ("RGSPP rises 150 ms early"),
/// not as a missing and an extra event; late ones the same.
#[test]
fn a_timing_shift_beyond_its_window_reads_as_one_line() {
    let s = scenario("scenarios/common/doc_examples/quick_start.yaml");
    let reference = reference(&s);
    let rise = edge_time(&reference, Signal::Rgspp, true, 0);
    for (shift, word) in [(-150_000i64, "early"), (150_000, "late")] {
        let mut t = reference.clone();
        for e in &mut t.events {
            if e.t_us == rise && matches!(e.event, Event::Signal { signal: Signal::Rgspp, value: true }) {
                e.t_us = (e.t_us as i64 + shift) as u64;
            }
        }
        t.events.sort_by_key(|e| e.t_us);
        let r = check(&s, &reference, record(&t, Rec::EXACT));
        let text = show(&r, &reference);
        assert!(
            r.divergences
                .iter()
                .any(|d| d.what == format!("RGSPP rises 150 ms {word}") && d.check == "CHK-EVT-01"),
            "{text}"
        );
        assert!(
            !r.divergences
                .iter()
                .any(|d| d.what.starts_with("RGSPP")
                    && matches!(d.check.as_str(), "CHK-EVT-02" | "CHK-EVT-03")),
            "no missing/extra line for the shifted edge:\n{text}"
        );
    }
}

/// Issue 14 §5: a recording that stops early is called truncated, at its last time, in one line.
#[test]
fn a_recording_that_stops_early_is_called_truncated() {
    let s = scenario("scenarios/gsk/peck/high_speed_seed_example.yaml");
    let reference = reference(&s);
    let end = reference.events.last().unwrap().t_us;
    let rec: Vec<TraceEvent> = record(&reference, Rec::PLC_SCAN)
        .into_iter()
        .filter(|e| e.t_us < Rec::PLC_SCAN.shift_us + end / 2)
        .collect();
    let r = check(&s, &reference, rec);
    let text = show(&r, &reference);
    let trunc: Vec<_> =
        r.divergences.iter().filter(|d| d.what.starts_with("recording truncated at")).collect();
    assert_eq!(trunc.len(), 1, "{text}");
    assert!(!r.divergences.iter().any(|d| d.what.ends_with("missing")), "{text}");
}

/// Issue 14 §3: the recordings of LinuxCNC's real motion controller (`../shared/linuxcnc-real`,
/// CSV of positions and spindle, no M functions, no STL, no tap strokes) align by themselves on
/// the first spindle start, at the offset that had to be computed by hand there (the first row
/// with the spindle turning tied to the reference's 1 ms), and the report says how it aligned
/// and how well it fits.
#[test]
fn real_linuxcnc_recordings_align_by_themselves() {
    let dir = root().join("../shared/linuxcnc-real");
    assert!(dir.is_dir(), "{} (the project's shared material) is missing", dir.display());
    let out = std::env::temp_dir().join(format!("nc-conform-lcnc-align-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    for p in ["g331", "g84", "g81"] {
        let csv = dir.join(format!("recordings/csv/{p}.csv"));
        let text = std::fs::read_to_string(&csv).unwrap();
        let mut lines = text.lines();
        let col = lines.next().unwrap().split(',').position(|c| c == "spindle_rpm").unwrap();
        let first: i64 = lines
            .find(|l| l.split(',').nth(col).unwrap().parse::<f64>().unwrap() != 0.0)
            .map(|l| l.split(',').next().unwrap().parse().unwrap())
            .unwrap();
        let by_hand = (1 - first) * 1000;
        let report = out.join(format!("{p}.json"));
        let run = std::process::Command::new(env!("CARGO_BIN_EXE_nc-conform"))
            .current_dir(&dir)
            .args(["check", &format!("programs/{p}.ngc"), "--dialect", "linuxcnc"])
            .args(["--params", "linuxcnc-sim.params.yaml", "--map", "linuxcnc-map.yaml"])
            .args(["--trace", &format!("recordings/csv/{p}.csv"), "--report"])
            .arg(&report)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&run.stdout);
        assert!(
            run.status.code().is_some_and(|c| c <= 1),
            "{p}: {stdout}{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        let rep = &json["report"];
        assert_eq!(rep["anchor"], "first spindle start", "{p}: {stdout}");
        let off = rep["offset_us"].as_i64().unwrap();
        assert!((off - by_hand).abs() <= 2000, "{p}: offset {off} µs, by hand {by_hand} µs");
        assert!(!rep["divergences"].as_array().unwrap().iter().any(|d| d["check"] == "CHK-ALIGN-01"), "{p}");
        assert!(rep["figures"]["fit_rms_mm"].as_f64().is_some(), "{p}: the fit is reported");
        assert!(stdout.contains("fit positions rms"), "{p}: {stdout}");
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// Issue 14 §3: `calibrate` estimates a machine's timing (rigid tapping time constant included)
/// from a recording of a known-good run;
/// checking the same recording with the parameters it writes is conformant at tight tolerances
/// (it is not with the defaults), and a recording with one defect still fails.
#[test]
fn calibrated_parameters_make_a_known_good_recording_conformant_at_tight_tolerances() {
    use nc_conform::check::{calibrate, CheckSpec, Tolerances};
    // M29 after the spindle has come to rest (G04 P0.5 after M05): a drive answer measured with
    // the spindle still turning is the ramp down, not the drive (calibrate leaves it out).
    let program = "G98;\nG0 X100 Z60;\nM03 S800;\nG0 X20 Z2;\nM05;\nG04 P500;\nM29 S1000;\nG84 Z-5 F1;\nG80;\nG0 X100 Z60;\nM30;\n";
    let truth = "params:\n  nc.rapid_mm_min: {X: 5000, Z: 7000}\n  nc.rapid_ramp_ms: {X: 80, Z: 120}\n  nc.spindle_ramp_ms: 1500\n  plc.fin_ms: 40\n  plc.fin_fall_ms: 12\n  plc.sppos_reach_ms: 90\n  nc.rt_ramp_ms: 350\n";
    let mut machine = nc_engine::Machine::new("gsk-lathe").unwrap();
    nc_conform::params_yaml::apply(truth, &mut machine).unwrap();
    let prog = machine.parse(program).unwrap();
    let opts = nc_engine::RunOptions { auto_cycle_start: true, ..Default::default() };
    let good = machine.run_to_trace(&prog, &opts);
    let recorded = record(&good, Rec::REALISTIC);

    let base = nc_engine::Machine::new("gsk-lathe").unwrap();
    let est = calibrate::estimate(&base, &good.meta.axes, &recorded);
    let file = calibrate::params_file(&base, &est, "good.jsonl");
    for id in
        ["nc.rapid_mm_min", "nc.rapid_ramp_ms", "nc.spindle_ramp_ms", "plc.fin_ms", "plc.sppos_reach_ms"]
    {
        assert!(file.contains(id), "{id} estimated:\n{file}");
    }
    let got =
        |id: &str, axis: Option<char>| est.iter().find(|e| e.id == id && e.axis == axis).map(|e| e.value);
    for (id, axis, truth, within) in [
        ("nc.rapid_mm_min", Some('X'), 5000.0, 10.0),
        ("nc.rapid_mm_min", Some('Z'), 7000.0, 14.0),
        ("nc.rapid_ramp_ms", Some('X'), 80.0, 3.0),
        ("nc.rapid_ramp_ms", Some('Z'), 120.0, 3.0),
        ("nc.spindle_ramp_ms", None, 1500.0, 15.0),
        ("plc.fin_ms", None, 40.0, 1.0),
        ("plc.sppos_reach_ms", None, 90.0, 1.0),
        ("nc.rt_ramp_ms", None, 350.0, 8.0),
    ] {
        let v = got(id, axis).unwrap_or(f64::NAN);
        eprintln!("{id} {axis:?}: {v} (truth {truth})");
        assert!((v - truth).abs() <= within, "{id} {axis:?}: {v}, truth {truth}\n{file}");
    }
    let mut calibrated = nc_engine::Machine::new("gsk-lathe").unwrap();
    nc_conform::params_yaml::apply(&file, &mut calibrated).unwrap_or_else(|e| panic!("{e:?}\n{file}"));

    let tight = Tolerances {
        event_ms: 5.0,
        envelope_ms: 5.0,
        position_mm: 0.02,
        keypoint_mm: 0.01,
        sync_mm: 0.01,
        dwell_ms: 5.0,
        ..Tolerances::default()
    };
    let spec = CheckSpec { tolerances: tight, ..Default::default() };
    let reference_of = |m: &nc_engine::Machine| m.run_to_trace(&prog, &opts);
    let cal_ref = reference_of(&calibrated);
    let r = nc_conform::check::check(&cal_ref, recorded.clone(), &spec);
    assert!(r.conformant(), "calibrated:\n{file}\n{}", show(&r, &cal_ref));
    // The rigid tapping time constant at its default does not fit.
    let mut no_rt = nc_engine::Machine::new("gsk-lathe").unwrap();
    let text: String =
        file.lines().filter(|l| !l.contains("nc.rt_ramp_ms:")).map(|l| format!("{l}\n")).collect();
    nc_conform::params_yaml::apply(&text, &mut no_rt).unwrap();
    let r = nc_conform::check::check(&reference_of(&no_rt), recorded.clone(), &spec);
    assert!(!r.conformant(), "nc.rt_ramp_ms at its default fits too");
    let default_ref = reference_of(&base);
    let r = nc_conform::check::check(&default_ref, recorded.clone(), &spec);
    assert!(!r.conformant(), "the defaults should not fit this machine");
    // One defect: RGTAP answered 15 ms late.
    let mut bad = good.clone();
    let t = edge_time(&good, Signal::Rgtap, true, 0);
    for e in &mut bad.events {
        if e.t_us == t && matches!(e.event, Event::Signal { signal: Signal::Rgtap, value: true }) {
            e.t_us += 15_000;
        }
    }
    bad.events.sort_by_key(|e| e.t_us);
    let r = nc_conform::check::check(&cal_ref, record(&bad, Rec::REALISTIC), &spec);
    assert!(r.divergences.iter().any(|d| d.what.starts_with("RGTAP rises")), "{}", show(&r, &cal_ref));
}

/// Issue 14 §5: the JSON report lists divergences in time order, each margin also as a number
/// with its unit; the JUnit report has `time` attributes.
#[test]
fn json_divergences_in_time_order_with_numeric_margins_and_junit_times() {
    let s = scenario("scenarios/gsk/peck/high_speed_seed_example.yaml");
    let reference = reference(&s);
    let end = reference.events.last().unwrap().t_us;
    let rec: Vec<TraceEvent> = record(&reference, Rec::PLC_SCAN)
        .into_iter()
        .filter(|e| e.t_us < Rec::PLC_SCAN.shift_us + end / 2)
        .collect();
    let mut t = reference.clone();
    for e in &mut t.events {
        if let Event::Sample(x) = &mut e.event {
            x.axes[2] += 300_000; // Z 0.3 mm off everywhere
        }
    }
    let mut all = record(&t, Rec::PLC_SCAN);
    all.truncate(rec.len());
    let r = check(&s, &reference, all);
    assert!(r.divergences.len() >= 2, "{}", show(&r, &reference));
    let json: serde_json::Value =
        serde_json::from_str(&nc_conform::check::report::json(&r, "a", "b")).unwrap();
    let ds = json["report"]["divergences"].as_array().unwrap();
    let times: Vec<i64> = ds.iter().map(|d| d["t_us"].as_i64().unwrap_or(i64::MAX)).collect();
    assert!(times.windows(2).all(|w| w[0] <= w[1]), "time order: {times:?}");
    let env = ds.iter().find(|d| d["check"] == "CHK-ENV-01").expect("an envelope divergence");
    assert!(env["margin_value"].as_f64().is_some_and(|v| v > 0.2), "{env}");
    assert_eq!(env["margin_unit"], "mm");
    let junit = nc_conform::check::report::junit(&r, "x");
    assert!(junit.contains("<testsuite name=\"x\"") && junit.contains(" time=\""), "{junit}");
}

/// Issue 14 §4: the report is bounded per kind: a chattering signal (thousands of extra edges)
/// lists its first 1000 and counts the rest, and a divergence of another kind after them is
/// still listed.
#[test]
fn the_report_is_bounded_per_kind_and_keeps_the_others() {
    let s = scenario("scenarios/common/doc_examples/quick_start.yaml");
    let reference = reference(&s);
    let mut t = reference.clone();
    let end = reference.events.last().unwrap().t_us;
    let mut chatter = Vec::new();
    for k in 0..3000u64 {
        let at = 1000 + k * (end / 4000);
        chatter.push(TraceEvent { t_us: at, event: Event::Signal { signal: Signal::Esp, value: true } });
        chatter
            .push(TraceEvent { t_us: at + 10, event: Event::Signal { signal: Signal::Esp, value: false } });
    }
    insert(&mut t, chatter);
    let rise = edge_time(&reference, Signal::Rgspp, true, 0);
    for e in &mut t.events {
        if e.t_us == rise && matches!(e.event, Event::Signal { signal: Signal::Rgspp, value: true }) {
            e.t_us += 100_000;
        }
    }
    t.events.sort_by_key(|e| e.t_us);
    let r = check(&s, &reference, record(&t, Rec::EXACT));
    let extras = r.divergences.iter().filter(|d| d.check == "CHK-EVT-03").count();
    assert_eq!(extras, nc_conform::check::MAX_PER_CHECK);
    assert_eq!(r.omitted_by_check.get("CHK-EVT-03"), Some(&(6000 - nc_conform::check::MAX_PER_CHECK)));
    assert!(r.divergences.iter().any(|d| d.what == "RGSPP rises 100 ms late"), "the other kind is listed");
    assert!(show(&r, &reference).contains("CHK-EVT-03: 5000"));
}
