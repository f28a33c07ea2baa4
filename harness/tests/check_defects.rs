//! `nc-conform check` catches real defects: one recorded trace per defect class, derived from a
//! reference run of a library scenario, each caught with the right rule id; and conformant
//! traces with realistic jitter, noise, another clock, another sample rate and lost samples
//! pass (`docs/checking.md`).

mod check_util;

use check_util::*;
use nc_engine::trace::{Event, Phase, Sample, Signal, Trace, TraceEvent};

/// Asserts the report cites `rule`, printing the summary otherwise.
fn caught(r: &nc_conform::check::Report, reference: &Trace, rule: &str) {
    assert!(r.has_rule(rule), "{rule} not cited:\n{}", show(r, reference));
}

#[test]
fn conformant_traces_with_jitter_noise_and_lost_samples_pass() {
    for rel in [
        "scenarios/common/doc_examples/quick_start.yaml",
        "scenarios/gsk/peck/high_speed_seed_example.yaml",
        "scenarios/gsk/peck/deep_peck_seed_example.yaml",
        "scenarios/gsk/peck/standard_seed_example.yaml",
        "scenarios/gsk/feed_hold/during_cutting.yaml",
        "scenarios/gsk/clamp/clamp_codes_frame_the_hole.yaml",
        "scenarios/gsk/overload/spindle_current_retracts.yaml",
        "scenarios/common/inp/reset_during_rigid_tapping.yaml",
        "scenarios/gsk/dry_run/tapping_unchanged_by_dry_run.yaml",
        "scenarios/gsk/machine_lock/tap_under_machine_lock.yaml",
        "scenarios/knd/g93/standard.yaml",
        "scenarios/fanuc/seed/peck_rigid_example.yaml",
        "scenarios/fanuc/seed/usage_two_holes_g99_g98.yaml",
        "scenarios/fanuc/rigid/g74_left_hand.yaml",
        "scenarios/fanuc/rigid/peck_pcp0_high_speed.yaml",
    ] {
        let s = scenario(rel);
        let reference = reference(&s);
        for rec in [Rec::EXACT, Rec::REALISTIC, Rec { sample_us: 2500, shift_us: 17, ..Rec::REALISTIC }] {
            let r = check(&s, &reference, record(&reference, rec));
            assert!(r.conformant(), "{rel} with {rec:?}:\n{}", show(&r, &reference));
        }
    }
}

#[test]
fn feed_hold_honoured_mid_tap_is_caught_gsk_rt_27() {
    let s = scenario("scenarios/gsk/feed_hold/during_cutting.yaml");
    let reference = reference(&s);
    let (cut, _) = phase_spans(&reference, Phase::Cutting)[0];
    let t = feed_hold_at(&reference, cut + 300_000, 400_000);
    let r = check(&s, &reference, record(&t, Rec::REALISTIC));
    caught(&r, &reference, "GSK-RT-27");
}

#[test]
fn dry_run_applied_to_the_tap_feed_is_caught_gsk_rt_23() {
    let s = scenario("scenarios/gsk/dry_run/tapping_unchanged_by_dry_run.yaml");
    let reference = reference(&s);
    let (a, b) = phase_spans(&reference, Phase::Cutting)[0];
    let k = 0.6;
    let saved = ((b - a) as f64 * (1.0 - k)) as u64;
    let t = warp(&reference, |x| {
        Some(if x <= a {
            x
        } else if x <= b {
            a + ((x - a) as f64 * k) as u64
        } else {
            x - saved
        })
    });
    let r = check(&s, &reference, record(&t, Rec::REALISTIC));
    caught(&r, &reference, "GSK-RT-23");
}

#[test]
fn machine_lock_ignored_is_caught_gsk_rt_24() {
    let s = scenario("scenarios/gsk/machine_lock/tap_under_machine_lock.yaml");
    let reference = reference(&s);
    let mut opts = s.opts.clone();
    opts.inputs.inputs.retain(|i| i.input.name() != "machine_lock");
    let defective = s.machine.run_to_trace(&s.program, &opts);
    let r = check(&s, &reference, record(&defective, Rec::REALISTIC));
    caught(&r, &reference, "GSK-RT-24");
}

#[test]
fn no_retract_after_overload_is_caught_gsk_rt_26() {
    let s = scenario("scenarios/gsk/overload/spindle_current_retracts.yaml");
    let reference = reference(&s);
    let mut opts = s.opts.clone();
    opts.inputs.inputs.retain(|i| i.input.name() != "motor_current");
    let defective = s.machine.run_to_trace(&s.program, &opts);
    let r = check(&s, &reference, record(&defective, Rec::REALISTIC));
    caught(&r, &reference, "GSK-RT-26");
}

#[test]
fn late_retract_after_overload_is_caught_gsk_rt_26() {
    let s = scenario("scenarios/gsk/overload/spindle_current_retracts.yaml");
    let reference = reference(&s);
    // The overload acts 2 mm deeper than it should: the retract comes late.
    let late = scenario_edited("scenarios/gsk/overload/spindle_current_retracts.yaml", |t| {
        t.replace("below: -5}", "below: -7}").replace("below: -8}", "below: -10}")
    });
    let defective = late.machine.run_to_trace(&late.program, &late.opts);
    let r = check(&s, &reference, record(&defective, Rec::REALISTIC));
    caught(&r, &reference, "GSK-RT-26");
    // The deeper hole and the late return themselves, not only the late alarm, cite GSK-RT-26.
    for check in ["CHK-KEY-04", "CHK-ENV-01"] {
        assert!(
            r.divergences.iter().any(|d| d.check == check && d.rule == "GSK-RT-26"),
            "{check}:\n{}",
            show(&r, &reference)
        );
    }
}

#[test]
fn rgtap_dropped_before_f76_3_is_caught_com_plc_05() {
    let s = scenario("scenarios/common/doc_examples/quick_start.yaml");
    let reference = reference(&s);
    let fall = edge_time(&reference, Signal::Rtap, false, 0);
    let mut t = reference.clone();
    t.events.retain(|e| !matches!(e.event, Event::Signal { signal: Signal::Rgtap, value: false }));
    insert(
        &mut t,
        vec![TraceEvent { t_us: fall - 3000, event: Event::Signal { signal: Signal::Rgtap, value: false } }],
    );
    let r = check(&s, &reference, record(&t, Rec::REALISTIC));
    caught(&r, &reference, "COM-PLC-05");
    assert!(r.divergences.iter().any(|d| d.check == "CHK-EVT-04"), "{}", show(&r, &reference));
}

fn clamp_scenario() -> (nc_conform::scenario::load::Scenario, Trace) {
    let s = scenario("scenarios/gsk/clamp/clamp_codes_frame_the_hole.yaml");
    let reference = reference(&s);
    (s, reference)
}

#[test]
fn missing_clamp_m_code_is_caught_gsk_rt_11() {
    let (s, reference) = clamp_scenario();
    let mut t = reference.clone();
    let k =
        t.events.iter().position(|e| matches!(e.event, Event::Function { letter: 'M', code: 68 })).unwrap();
    t.events.remove(k);
    let r = check(&s, &reference, record(&t, Rec::REALISTIC));
    caught(&r, &reference, "GSK-RT-11");
}

#[test]
fn duplicated_clamp_m_code_is_caught_gsk_rt_11() {
    let (s, reference) = clamp_scenario();
    let mut t = reference.clone();
    let e = t
        .events
        .iter()
        .find(|e| matches!(e.event, Event::Function { letter: 'M', code: 68 }))
        .unwrap()
        .clone();
    insert(&mut t, vec![TraceEvent { t_us: e.t_us + 2000, event: e.event }]);
    let r = check(&s, &reference, record(&t, Rec::REALISTIC));
    caught(&r, &reference, "GSK-RT-11");
}

#[test]
fn wrong_peck_count_and_depth_are_caught_gsk_rt_08() {
    let rel = "scenarios/gsk/peck/high_speed_seed_example.yaml";
    let s = scenario(rel);
    let reference = reference(&s);
    let text = std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(rel))
        .unwrap();
    let q = text
        .split_whitespace()
        .find(|w| w.starts_with('Q'))
        .expect("a Q word")
        .trim_end_matches(';')
        .to_string();
    let v: f64 = q[1..].parse().unwrap();
    let wrong = scenario_edited(rel, |t| t.replacen(&q, &format!("Q{}", v * 1.5), 1));
    let defective = wrong.machine.run_to_trace(&wrong.program, &wrong.opts);
    let r = check(&s, &reference, record(&defective, Rec::REALISTIC));
    caught(&r, &reference, "GSK-RT-08");
    assert!(
        r.divergences.iter().any(|d| d.check == "CHK-KEY-01" || d.check == "CHK-KEY-02"),
        "{}",
        show(&r, &reference)
    );
}

#[test]
fn sync_error_above_tolerance_is_caught_com_sync_01() {
    let s = scenario("scenarios/common/doc_examples/quick_start.yaml");
    let reference = reference(&s);
    let (a, b) = phase_spans(&reference, Phase::Cutting)[0];
    let slot = 2; // Z
    let mut t = reference.clone();
    for e in t.events.iter_mut() {
        if let Event::Sample(Sample { axes, .. }) = &mut e.event {
            if e.t_us > a && e.t_us <= b {
                // The axis lags the spindle by up to 40 µm in the middle of the cut.
                let f = (e.t_us - a) as f64 / (b - a) as f64;
                axes[slot] += (40_000.0 * (std::f64::consts::PI * f).sin()) as i64;
            }
        }
    }
    let r = check(&s, &reference, record(&t, Rec::REALISTIC));
    caught(&r, &reference, "COM-SYNC-01");
    assert!(r.divergences.iter().any(|d| d.check == "CHK-SYNC-01"), "{}", show(&r, &reference));
}

#[test]
fn dwell_too_short_is_caught_gsk_rt_04() {
    let s = scenario("scenarios/gsk/peck/standard_seed_example.yaml");
    let reference = reference(&s);
    let (a, b) = phase_spans(&reference, Phase::Dwell)[0];
    let cut = (b - a) / 2;
    let t = warp(&reference, |x| {
        if x > a && x <= a + cut {
            None
        } else if x > a + cut {
            Some(x - cut)
        } else {
            Some(x)
        }
    });
    let r = check(&s, &reference, record(&t, Rec::REALISTIC));
    caught(&r, &reference, "GSK-RT-04");
}

#[test]
fn spindle_not_restored_after_reset_is_caught_gsk_rt_25() {
    let s = scenario("scenarios/common/inp/reset_during_rigid_tapping.yaml");
    let reference = reference(&s);
    let (t_reset, _) = reference
        .events
        .iter()
        .find_map(|e| match &e.event {
            Event::Input { name, .. } if name == "reset" => Some((e.t_us, ())),
            _ => None,
        })
        .expect("a reset");
    let frozen = sample_before(&reference, t_reset);
    let mut t = reference.clone();
    for e in t.events.iter_mut().filter(|e| e.t_us > t_reset) {
        if let Event::Sample(smp) = &mut e.event {
            smp.spindle_mrpm = 0;
            smp.spindle_mdeg = frozen.spindle_mdeg;
        }
    }
    let r = check(&s, &reference, record(&t, Rec::REALISTIC));
    caught(&r, &reference, "GSK-RT-25");
}

#[test]
fn knd_tap_keeps_going_in_and_never_retracts_is_caught_knd_g93_07() {
    let s = scenario("scenarios/knd/g93/standard.yaml");
    let reference = reference(&s);
    let (t_ret, _) = phase_spans(&reference, Phase::Retract)[0];
    let at = sample_before(&reference, t_ret);
    let z = 2; // Z slot
               // The controller of the forum: the tap goes on into the hole at 1.5 mm per 200 ms and never
               // comes back; nothing else happens after the end point.
    let mut t = reference.clone();
    t.events.retain(|e| e.t_us <= t_ret || matches!(e.event, Event::Sample(_)));
    for e in t.events.iter_mut().filter(|e| e.t_us > t_ret) {
        if let Event::Sample(smp) = &mut e.event {
            *smp = at;
            smp.axes[z] -= ((e.t_us - t_ret) as i64 * 7_500 / 1000).min(5_000_000);
        }
    }
    let r = check(&s, &reference, record(&t, Rec::REALISTIC));
    caught(&r, &reference, "KND-G93-07");
}

#[test]
fn a_recording_far_longer_than_the_reference_is_streamed_in_bounded_memory() {
    let s = scenario("scenarios/common/doc_examples/quick_start.yaml");
    let reference = reference(&s);
    let head = record(&reference, Rec::EXACT);
    let last = *reference.samples().last().unwrap().1;
    let end = reference.events.last().unwrap().t_us;
    // Ten minutes more of samples at 1 ms, produced lazily: the controller never stops.
    let tail = (1..=600_000u64).map(move |k| TraceEvent { t_us: end + k * 1000, event: Event::Sample(last) });
    let r = nc_conform::check::check(&reference, head.into_iter().chain(tail), &Default::default());
    assert!(r.figures.recorded_samples > 600_000);
    assert!(
        r.recorded.events.len() < 4 * reference.events.len(),
        "compact copy: {}",
        r.recorded.events.len()
    );
    assert!(r.series.len() < 4000, "plot points: {}", r.series.len());
    assert!(r.conformant(), "{}", show(&r, &reference));
}

#[test]
fn alignment_by_offset_or_another_anchor_and_a_missing_anchor() {
    use nc_conform::check::{Anchor, CheckSpec};
    let s = scenario("scenarios/gsk/peck/high_speed_seed_example.yaml");
    let reference = reference(&s);
    let rec = record(&reference, Rec::REALISTIC);
    let shift = Rec::REALISTIC.shift_us as i64;
    for anchor in [Anchor::Offset(-shift), Anchor::Edge(Signal::Rgtap, true), Anchor::Function('M', 29)] {
        let spec = CheckSpec { anchor: Some(anchor.clone()), expect: Some(&s.expect), ..Default::default() };
        let r = nc_conform::check::check(&reference, rec.clone(), &spec);
        assert!(r.conformant(), "{anchor:?}:\n{}", show(&r, &reference));
        assert!((r.offset_us + shift).abs() <= 1000, "{anchor:?}: offset {}", r.offset_us);
    }
    // A recording without any M29: aligned on its first event, and said so.
    let no_m29: Vec<TraceEvent> =
        rec.into_iter().filter(|e| !matches!(e.event, Event::Function { letter: 'M', code: 29 })).collect();
    let r = nc_conform::check::check(&reference, no_m29, &CheckSpec::default());
    assert!(r.divergences.iter().any(|d| d.check == "CHK-ALIGN-01"), "{}", show(&r, &reference));
}
