//! Heidenhain cycle 832 THREAD EXTENDED (seed 004): every pass follows the spindle on the same
//! helix (HDH-C832-05), each start offset by 360° / Q475 (HDH-C832-10), every parameter's range
//! (HDH-C832-01), the cautions (HDH-C832-12, HDH-C832-13).

mod support;

use nc_engine::trace::Phase;
use nc_engine::RunOptions;
use rstest::rstest;
use support::run;

const ORDER: [u16; 20] =
    [471, 461, 460, 472, 473, 464, 491, 492, 493, 494, 469, 474, 465, 466, 463, 467, 468, 470, 475, 476];
const BASE: [&str; 20] = [
    "0", "0", "1", "1", "0.3", "0", "20", "0", "20", "-6", "0", "0", "1", "1", "0.2", "30", "1", "0", "1",
    "0",
];

/// The program of `scenarios/heidenhain/c832/longitudinal_outside.yaml` with some parameters
/// changed; Q471 is on line 6, each next parameter one line further.
fn program(changes: &[(u16, &str)]) -> String {
    let mut s = String::from(
        "0 BEGIN PGM T MM\n1 FUNCTION MODE TURN\n2 TOOL CALL 1 S600\n3 L X+30 Z+5 R0 FMAX M303\n\
         4 CYCL DEF 832 THREAD EXTENDED\n",
    );
    for (q, v) in ORDER.iter().zip(BASE) {
        let v = changes.iter().find(|c| c.0 == *q).map_or(v, |c| c.1);
        s.push_str(&format!("  Q{q}={v}\n"));
    }
    s + "5 CYCL CALL\n6 L X+40 Z+20 FMAX M305\n7 M30\n8 END PGM T MM\n"
}

fn sampled() -> RunOptions {
    RunOptions { sample_us: 1000, ..RunOptions::default() }
}

/// For every pass (cutting phase), the helix phase (Z − the pass' shift + pitch × angle / 360°)
/// modulo the pitch, nm, over the samples where the pass cruises on the thread.
fn phases_per_pass(changes: &[(u16, &str)], pitch_nm: i64, shifts: &[i64]) -> Vec<Vec<i64>> {
    let t = run("heidenhain", &[], &program(changes), &sampled());
    assert_eq!(t.alarms().count(), 0, "{:?}", t.alarms().collect::<Vec<_>>());
    let cuts: Vec<(u64, u64)> = {
        let ph: Vec<(u64, Phase)> = t.phases().collect();
        ph.windows(2).filter(|w| w[0].1 == Phase::Cutting).map(|w| (w[0].0, w[1].0)).collect()
    };
    cuts.iter()
        .enumerate()
        .map(|(k, &(a, b))| {
            t.samples()
                .filter(|(ts, s)| *ts > a && *ts < b && (-5_000_000..-1_000_000).contains(&s.axes[2]))
                .map(|(_, s)| {
                    let turn = s.spindle_mdeg as i128 * pitch_nm as i128 / 360_000;
                    (s.axes[2] as i128 - shifts[k % shifts.len()] as i128 + turn).rem_euclid(pitch_nm as i128)
                        as i64
                })
                .collect()
        })
        .collect()
}

fn spread(v: &[i64], pitch: i64) -> i64 {
    // Distance on the circle of one pitch from the first value.
    v.iter()
        .map(|x| {
            let d = (x - v[0]).rem_euclid(pitch);
            d.min(pitch - d)
        })
        .max()
        .unwrap_or(0)
}

#[test]
fn hdh_c832_05_every_pass_cuts_the_same_helix_and_starts_are_offset_by_360_over_q475() {
    // Two passes of 0.15 mm at 30°: shifts 0.15·tan 30° and 0.3·tan 30° (towards +Z); two starts,
    // one air cut (same shift as the last infeed).
    let s1 = (150_000.0 * 30f64.to_radians().tan()).round() as i64;
    let s2 = (300_000.0 * 30f64.to_radians().tan()).round() as i64;
    let per = phases_per_pass(&[(475, "2"), (476, "1"), (470, "45")], 1_000_000, &[s1, s2, s2]);
    assert_eq!(per.len(), 6);
    assert!(per.iter().all(|p| p.len() > 300), "{:?}", per.iter().map(Vec::len).collect::<Vec<_>>());
    let start0: Vec<i64> = per[..3].iter().flatten().copied().collect();
    let start1: Vec<i64> = per[3..].iter().flatten().copied().collect();
    assert!(spread(&start0, 1_000_000) <= 20, "start 0 wanders {} nm", spread(&start0, 1_000_000));
    assert!(spread(&start1, 1_000_000) <= 20, "start 1 wanders {} nm", spread(&start1, 1_000_000));
    // The second start lies half a pitch from the first (180° of spindle angle).
    let d = (start1[0] - start0[0]).rem_euclid(1_000_000);
    assert!((d - 500_000).abs() <= 20, "{d}");
}

#[test]
fn hdh_c832_10_the_start_angle_moves_the_helix() {
    let a = phases_per_pass(&[(470, "0")], 1_000_000, &[86_603, 173_205])[0][0];
    let b = phases_per_pass(&[(470, "90")], 1_000_000, &[86_603, 173_205])[0][0];
    // Starting 90° later puts the groove a quarter pitch further on: Z + P·θ/360 grows by P/4.
    assert!(((b - a).rem_euclid(1_000_000) - 250_000).abs() <= 20, "{a} {b}");
}

#[rstest]
#[case(471, "2")]
#[case(471, "-1")]
#[case(461, "0.5")]
#[case(460, "1000")]
#[case(460, "-0.001")]
#[case(472, "100000")]
#[case(473, "1000")]
#[case(464, "5")]
#[case(491, "-100000")]
#[case(492, "100000")]
#[case(493, "100000")]
#[case(494, "-100000")]
#[case(469, "180.001")]
#[case(469, "-181")]
#[case(474, "1000")]
#[case(465, "0.099")]
#[case(465, "100")]
#[case(466, "0.05")]
#[case(466, "99.91")]
#[case(463, "0.0009")]
#[case(463, "1000")]
#[case(467, "60.001")]
#[case(467, "-1")]
#[case(468, "2")]
#[case(470, "360000")]
#[case(470, "-1")]
#[case(475, "0")]
#[case(475, "501")]
#[case(475, "2.5")]
#[case(476, "256")]
#[case(476, "1.5")]
fn hdh_c832_01_out_of_range_parameters_raise_nc_1070_at_their_line(#[case] q: u16, #[case] v: &str) {
    let t = run("heidenhain", &[], &program(&[(q, v)]), &RunOptions::default());
    let alarms: Vec<_> = t.alarms().map(|(_, a)| (a.kind.code(), a.line, a.col)).collect();
    let line = 6 + ORDER.iter().position(|o| *o == q).unwrap() as u32;
    assert_eq!(alarms, vec![("NC-1070", Some(line), Some(3))], "Q{q}={v}");
}

#[rstest]
#[case(460, "999.999")]
#[case(465, "0.1")]
#[case(466, "99.9")]
#[case(463, "999.999")]
#[case(467, "0")]
#[case(470, "359999")]
#[case(475, "500")]
#[case(476, "255")]
#[case(469, "-180")]
fn hdh_c832_01_the_limits_themselves_are_accepted(#[case] q: u16, #[case] v: &str) {
    let t = run(
        "heidenhain",
        &[],
        &program(&[(q, v)]),
        &RunOptions { time_limit_us: 1, ..RunOptions::default() },
    );
    assert!(t.alarms().all(|(_, a)| a.kind.code() != "NC-1070"), "Q{q}={v}");
}

#[test]
fn hdh_c832_12_13_the_cautions_follow_their_parameters() {
    let p = program(&[(467, "35")]);
    let t = run("heidenhain", &[("hei.flank_angle_deg", None, 40.0)], &p, &RunOptions::default());
    assert_eq!(t.alarms().count(), 0);
    let t = run("heidenhain", &[], &p, &RunOptions::default());
    assert_eq!(t.alarms().map(|(_, a)| a.kind.code()).collect::<Vec<_>>(), ["NC-1074"]);
}

#[test]
fn hdh_c832_07_a_tiny_maximum_cut_is_planned_in_chunks_and_runs_as_far_as_it_gets() {
    // Constant chip section with Q463 = 0.001 on 0.3 mm: 90 000 passes; the run stops at its
    // time limit after a few without planning the rest.
    let p = program(&[(468, "0"), (463, "0.001")]);
    let t = run("heidenhain", &[], &p, &RunOptions { time_limit_us: 5_000_000, ..RunOptions::default() });
    assert_eq!(t.end().unwrap().reason, nc_engine::trace::EndReason::TimeLimit);
    assert!(t.phases().filter(|p| p.1 == Phase::Cutting).count() >= 3);
}
