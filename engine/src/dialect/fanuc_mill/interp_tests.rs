//! Unit tests of the `fanuc-mill` interpreter: programs in, step lists out (no executor).

use super::*;
use crate::dialect::fanuc_mill::{FanucMill, PARAMS};
use crate::dialect::Dialect;
use crate::plan::TapMove;
use crate::units::nm_to_mm_string as mm;
use rstest::rstest;

const MM: Nm = NM_PER_MM;

fn interp(params: &[(&str, f64)]) -> FanucInterp {
    let mut p = Params::new(PARAMS);
    for &(id, v) in params {
        p.set(id, None, v).unwrap();
    }
    FanucInterp::new(&p)
}

/// Runs `text` on `it`: the steps of each block, up to the first alarm.
fn blocks_on(it: &mut FanucInterp, text: &str) -> Result<Vec<Vec<Step>>, Alarm> {
    let prog = crate::parse::parse(text, FanucMill.lex_rules()).unwrap();
    let mut all = Vec::new();
    for b in &prog.blocks {
        let mut out = Vec::new();
        it.block(b, &mut out)?;
        all.push(out);
    }
    Ok(all)
}

fn run_with(params: &[(&str, f64)], text: &str) -> Result<Vec<Step>, Alarm> {
    Ok(blocks_on(&mut interp(params), text)?.concat())
}

fn steps(text: &str) -> Vec<Step> {
    run_with(&[], text).unwrap_or_else(|a| panic!("{}", a.message()))
}

fn xyz(p: &Pos) -> String {
    format!("{} {} {}", mm(p[0]), mm(p[1]), mm(p[2]))
}

fn feed(f: &Feed) -> String {
    match f {
        Feed::PerMin(v) => format!("F{}/min", mm(*v as Nm)),
        Feed::PerRev(v) => format!("F{}/rev", mm(*v as Nm)),
    }
}

/// The steps as short words: `G0(x y z)`, `G1(x y z)F120/min`, `M5`, `P300ms`, `[cutting]`, ...
fn story(steps: &[Step]) -> String {
    let s: Vec<String> = steps
        .iter()
        .map(|s| match s {
            Step::Phase(p) => format!("[{}]", p.name()),
            Step::Rapid { target } => format!("G0({})", xyz(target)),
            Step::Feed { target, feed: f } => format!("G1({}){}", xyz(target), feed(f)),
            Step::Arc { target, center, clockwise, feed: f, .. } => format!(
                "{}({} c{},{}){}",
                if *clockwise { "G2" } else { "G3" },
                xyz(target),
                mm(center[0]),
                mm(center[1]),
                feed(f)
            ),
            Step::Dwell { us } => format!("P{}ms", us / 1000),
            Step::Function { letter, code, .. } => format!("{letter}{code}"),
            Step::RigidEnter { code, rpm } => format!("M{code}<{rpm}>"),
            Step::RigidCheck { .. } => "CHK".into(),
            Step::RigidExit { .. } => "EXIT".into(),
            Step::Tap(t) => format!("TAP({}{})", mm(t.target), if t.cutting { " cut" } else { "" }),
            Step::HoldSuppress(b) => if *b { "HOLD-" } else { "HOLD+" }.into(),
            Step::Overload(_) => "OL".into(),
            Step::Stop { optional } => if *optional { "M01" } else { "M00" }.into(),
            Step::End => "END".into(),
            Step::Alarm(a) => format!("ALARM {}", a.kind.code()),
            other => format!("{other:?}"),
        })
        .collect();
    s.join(" ")
}

fn taps(steps: &[Step]) -> Vec<TapMove> {
    steps
        .iter()
        .filter_map(|s| match s {
            Step::Tap(t) => Some(*t),
            _ => None,
        })
        .collect()
}

fn feeds(steps: &[Step]) -> Vec<Pos> {
    steps
        .iter()
        .filter_map(|s| match s {
            Step::Feed { target, .. } => Some(*target),
            _ => None,
        })
        .collect()
}

#[test]
fn seed_003_g84_two_holes_g99_then_g98() {
    let mut it = interp(&[]);
    let b = blocks_on(
        &mut it,
        "N150 M6 T2\nN160 G90 G00 X60 Y28 Z12 S100 M03\nN170 G99 G84 X60 Y28 Z-17 P300 R2 F120\n\
         N180 G98 Y12\nN190 G91 G80 G28 X0 Y0 Z0 M05\nN200 M30",
    )
    .unwrap();
    let s: Vec<String> = b.iter().map(|v| story(v)).collect();
    assert_eq!(s[0], "T2 M6");
    assert_eq!(s[1], "S100 M3 G0(60 28 12)");
    let body = |y: &str| {
        format!(
            "HOLD- [cutting] G1(60 {y} -17)F120/min [dwell] P300ms M5 M4 [retract] G1(60 {y} 2)F120/min M5 M3 HOLD+"
        )
    };
    assert_eq!(s[2], format!("[positioning] G0(60 28 12) G0(60 28 2) {} [idle]", body("28")));
    assert_eq!(s[3], format!("[positioning] G0(60 12 2) G0(60 12 2) {} G0(60 12 12) [idle]", body("12")));
    assert_eq!(s[4], "G0(60 12 12) G0(0 0 0) M5");
    assert_eq!(s[5], "M30 END");
    assert_eq!(it.modal()[6], "G80");
}

#[test]
fn seed_003_rigid_peck_returns_to_r_between_nine_cuts() {
    let mut it = interp(&[]);
    let b = blocks_on(&mut it, "G90 G00 X30 Y50\nG43 Z50 H01\nM29 S100\nG84 Z-40 R5 Q5 F100\nG80").unwrap();
    assert_eq!(story(&b[2]), "S100 M29<100>");
    assert!(
        story(&b[3]).starts_with("[positioning] G0(30 50 50) G0(30 50 5) CHK HOLD- OL [cutting] TAP(0 cut)")
    );
    assert!(story(&b[3]).ends_with("OL [retract] TAP(5) HOLD+ G0(30 50 50) [idle]"));
    let t = taps(&b[3]);
    let cuts: Vec<Nm> = t.iter().filter(|t| t.cutting).map(|t| t.target).collect();
    assert_eq!(cuts, (1..=9).map(|i| 5 * MM - 5 * MM * i).collect::<Vec<_>>());
    assert!(t.iter().filter(|t| !t.cutting).all(|t| t.target == 5 * MM));
    assert_eq!(t.len(), 18);
    assert!(t.iter().all(|t| t.lead_nm == MM && t.rpm == 100 && t.axis == 2));
    assert!(t.iter().all(|t| t.spindle_forward == t.cutting));
    assert_eq!(story(&b[4]), "EXIT");
    assert!(!it.rigid_mode());
}

#[rstest]
#[case::g84_spindle_stopped("G84 X0 Z-10 R2 F100", "NC-1017", 1, Some(1))]
#[case::g84_after_m05("S100 M03\nM05\nG84 X0 Z-10 R2 F100", "NC-1017", 3, Some(1))]
#[case::g74_spindle_forward("S100 M03\nG74 X0 Z-10 R2 F100", "NC-1017", 2, Some(1))]
fn conventional_tap_spindle_check_is_a_parameter(
    #[case] text: &str,
    #[case] code: &str,
    #[case] line: u32,
    #[case] col: Option<u32>,
) {
    // FAN-RT-17, DEC-40: refused by default; nc.tap_spindle_check = 0 lets it feed at F.
    assert!(run_with(&[("nc.tap_spindle_check", 0.0)], text).is_ok());
    let a = run_with(&[], text).unwrap_err();
    assert_eq!((a.kind.code(), a.line, a.col), (code, Some(line), col), "{}", a.message());
}

#[test]
fn arc_end_off_the_circle_alarms_only_with_a_3410_tolerance() {
    // 3410 = 0 (default) runs it as a spiral; 3410 = 0.01 mm refuses it.
    assert!(run_with(&[], "G02 X10 I3 F100").is_ok());
    let a = run_with(&[("3410", 0.01)], "G02 X10 I3 F100").unwrap_err();
    assert_eq!((a.kind.code(), a.line, a.col), ("NC-1001", Some(1), Some(1)));
}

#[rstest]
#[case::g01_without_f("G01 X10", "0011", 1, Some(1))]
#[case::g01_f0("G01 X10 F0", "0011", 1, Some(9))]
#[case::f_lost_on_g95("G01 X1 F100\nG95\nG01 X2", "0011", 3, Some(1))]
#[case::improper_g("G84.1 X1", "0010", 1, Some(1))]
#[case::m98("G00 X1\nM98 P100", "NC-1004", 2, Some(1))]
#[case::g65("G65 P9000", "NC-1004", 1, Some(1))]
#[case::g10("G17 G10 L2", "NC-1004", 1, Some(5))]
#[case::coord_range("X100000", "NC-1001", 1, Some(1))]
#[case::feed_range("G01 X1 F240001", "NC-1001", 1, Some(8))]
#[case::feed_rev_range("G95 G01 X1 F501", "NC-1001", 1, Some(12))]
#[case::feed_negative("G01 X1 F-1", "NC-1001", 1, Some(8))]
#[case::feed_below_increment("G01 X1 F0.000001", "NC-1001", 1, Some(8))]
#[case::s_range("S8001", "NC-1001", 1, Some(1))]
#[case::k_range("G81 X0 Z-5 R1 F100 K10000", "NC-1001", 1, Some(20))]
#[case::p_range("G04 P-1", "NC-1001", 1, Some(5))]
#[case::q_negative_peck("G83 X0 Z-5 R1 Q-1 F100", "NC-1001", 1, Some(15))]
#[case::q_negative_tap("S100 M03\nG84 X0 Z-5 R1 Q-1 F100", "NC-1001", 2, Some(15))]
#[case::h_range("H1000", "NC-1001", 1, Some(1))]
#[case::d_range("G41 D1000", "NC-1001", 1, Some(5))]
#[case::arc_radius_too_small("G02 X10 R4 F100", "NC-1001", 1, Some(9))]
#[case::m29_without_s("M29", "0200", 1, Some(1))]
#[case::m29_twice("S100\nM29\nM29", "0203", 3, Some(1))]
#[case::s_change_in_rigid("S100\nM29\nS200", "0203", 3, Some(1))]
#[case::axis_after_m29("S100\nM29\nX10\nG84 Z-10 R2 F100", "0204", 3, Some(1))]
#[case::g00_after_m29("S100\nM29\nG00 Y10", "0204", 3, Some(5))]
#[case::axis_in_m29_block("S100\nM29 Z5", "0204", 2, Some(5))]
#[case::rigid_without_f("S100\nM29\nG84 X0 Z-10 R2", "0201", 3, Some(1))]
#[case::rigid_f0("S100\nM29\nG84 X0 Z-10 R2 F0", "0011", 3, Some(16))]
#[case::rigid_s_too_high("S5000 M03\nM29\nG84 X0 Z-10 R2 F100", "0200", 3, Some(1))]
#[case::g84_2_without_s("G84.2 X0 Z-10 R2 F1", "0200", 1, Some(1))]
#[case::plane_change_rigid("S100\nM29\nG18", "0206", 3, Some(1))]
#[case::plane_change_rigid_cycle("S100\nM29\nG84 X0 Z-10 R2 F100\nG19 X5", "0206", 4, Some(1))]
#[case::too_many_m("M03 M08 M01 M05", "NC-1016", 1, Some(13))]
#[case::g83_without_q("S100 M03\nG83 X0 Z-10 R2 F100", "NC-1002", 2, Some(1))]
#[case::g83_q0("S100 M03\nG83 X0 Z-10 R2 Q0 F100", "NC-1001", 2, Some(16))]
#[case::g73_q0("S100 M03\nG73 X0 Z-10 R2 Q0 F100", "NC-1001", 2, Some(16))]
#[case::g73_q0_retained("S100 M03\nG81 X0 Z-10 R2 Q0 F100\nG73 X5", "NC-1001", 3, Some(1))]
#[case::cycle_without_r("G81 X0 Z-10 F100", "NC-1002", 1, Some(1))]
#[case::modal_cycle_without_z("G81 R2 F100 K0\nX5", "NC-1002", 2, None)]
#[case::arc_without_centre("G02 X10 F100", "NC-1002", 1, Some(1))]
#[case::letter_e("G00 X10 E5", "NC-1005", 1, Some(9))]
#[case::dwell_x_and_p("G04 X1. P100", "NC-1005", 1, Some(5))]
#[case::dwell_with_axis("G04 P100 Z1", "NC-1005", 1, Some(10))]
#[case::twice("G00 X1 X2", "NC-1005", 1, Some(8))]
#[case::r_outside("G00 X1 R2", "NC-1005", 1, Some(8))]
#[case::k_and_l("S100 M03\nG84 X0 Z-10 R2 F100 L2 K2", "NC-1005", 2, Some(21))]
#[case::cycle_with_g28("G28 G81 X0 Z-10 R2 F100", "NC-1005", 1, Some(5))]
fn alarms(#[case] text: &str, #[case] code: &str, #[case] line: u32, #[case] col: Option<u32>) {
    let a = run_with(&[], text).unwrap_err();
    assert_eq!((a.kind.code(), a.line, a.col), (code, Some(line), col), "{}", a.message());
}

#[test]
fn an_alarm_leaves_no_steps_and_no_state_change() {
    let mut it = interp(&[]);
    let prog = crate::parse::parse(
        "S100 M03\nG81 X0 Z-5 R2 F100\nG91 G18 X5 Y100000 M05\nX7",
        FanucMill.lex_rules(),
    )
    .unwrap();
    let mut out = Vec::new();
    it.block(&prog.blocks[0], &mut out).unwrap();
    it.block(&prog.blocks[1], &mut out).unwrap();
    let n = out.len();
    let before = it.clone();
    assert!(it.block(&prog.blocks[2], &mut out).is_err());
    assert_eq!(out.len(), n);
    assert_eq!(
        (it.pos, it.abs, it.plane, it.spindle),
        (before.pos, before.abs, before.plane, before.spindle)
    );
    it.block(&prog.blocks[3], &mut out).unwrap();
    assert_eq!(feeds(&out[n..]), vec![[7 * MM, 0, -5 * MM, 0, 0, 0]]);
}

#[test]
fn g91_k3_makes_a_row_of_three_holes() {
    let s = steps("G90 G00 X0 Y0 Z10\nS100 M03\nG91 G81 X10 Z-5 R-8 F100 K3");
    // Initial level 10, R = 10 - 8 = 2, bottom = 2 - 5 = -3; G98: back to 10 after each hole.
    let f = feeds(&s);
    assert_eq!(f.iter().map(|p| (p[0], p[2])).collect::<Vec<_>>(), [10, 20, 30].map(|x| (x * MM, -3 * MM)));
    assert!(story(&s).ends_with("[positioning] G0(30 0 10) G0(30 0 2) [cutting] G1(30 0 -3)F100/min [retract] G0(30 0 2) G0(30 0 10) [idle]"));
}

#[test]
fn g90_k_repeats_the_same_hole_and_l_is_k() {
    for w in ["K2", "L2"] {
        let f = feeds(&steps(&format!("S100 M03\nG81 X4 Z-5 R2 F100 {w}")));
        assert_eq!(f, vec![[4 * MM, 0, -5 * MM, 0, 0, 0]; 2]);
    }
}

#[test]
fn k0_stores_the_data_and_makes_no_hole() {
    let mut it = interp(&[]);
    let b = blocks_on(&mut it, "S100 M03\nG81 X5 Z-5 R2 F100 K0\nX10").unwrap();
    assert_eq!(story(&b[1]), "");
    assert_eq!(feeds(&b[2]), vec![[10 * MM, 0, -5 * MM, 0, 0, 0]]);
    assert_eq!(it.modal()[6], "G81");
}

#[test]
fn a_block_without_hole_words_makes_no_hole() {
    let mut it = interp(&[]);
    let b = blocks_on(&mut it, "S100 M03\nG81 X5 Z-5 R2 F100\nM08\nF200\nG04 P100\nA90").unwrap();
    assert_eq!(story(&b[2]), "M8");
    assert_eq!(story(&b[3]), "");
    assert_eq!(story(&b[4]), "P100ms");
    assert_eq!(story(&b[5]), "G0(5 0 0)");
    assert_eq!(it.pos[3], 90 * MM);
}

#[test]
fn g80_cancels_and_clears_the_cycle_data() {
    let mut it = interp(&[]);
    let b = blocks_on(&mut it, "S100 M03\nG81 X0 Z-5 R2 F100\nG80\nX10").unwrap();
    assert_eq!(story(&b[2]), "");
    assert_eq!(story(&b[3]), "G0(10 0 0)");
    let e = blocks_on(&mut it, "G81 X20").unwrap_err();
    assert_eq!(e.kind, AlarmKind::WordMissing);
}

#[test]
fn a_group_01_code_cancels_the_cycle_but_keeps_its_data() {
    let mut it = interp(&[]);
    let b = blocks_on(&mut it, "S100 M03\nG81 X0 Z-5 R2 F100\nG01 X10 F200\nG81 X20").unwrap();
    assert_eq!(story(&b[2]), "G1(10 0 0)F200/min");
    assert_eq!(feeds(&b[3]), vec![[20 * MM, 0, -5 * MM, 0, 0, 0]]);
    // The one written last wins.
    let b = blocks_on(&mut interp(&[]), "S100 M03\nG81 G00 X1 Z-5 F100\nG00 G81 X1 Z-5 R2").unwrap();
    assert_eq!(story(&b[1]), "G0(1 0 -5)");
    assert_eq!(feeds(&b[2]).len(), 1);
}

#[rstest]
#[case::g80("G80", "EXIT")]
#[case::g00("G00 X10", "EXIT G0(10 0 2)")]
#[case::g81(
    "G81 X10",
    "EXIT [positioning] G0(10 0 2) G0(10 0 2) [cutting] G1(10 0 -10)F100/min [retract] G0(10 0 2) [idle]"
)]
#[case::m30("M30", "EXIT M30 END")]
#[case::plane_with_g80("G80 G18", "EXIT")]
fn rigid_mode_ends(#[case] block: &str, #[case] want: &str) {
    let mut it = interp(&[]);
    blocks_on(&mut it, "S100 M03\nG99\nM29\nG84 X0 Z-10 R2 F100").unwrap();
    assert!(it.rigid_mode());
    let b = blocks_on(&mut it, block).unwrap();
    assert_eq!(story(&b[0]), want);
    assert!(!it.rigid_mode());
}

#[test]
fn rigid_mode_stays_on_between_holes_and_across_g74() {
    let mut it = interp(&[]);
    let b = blocks_on(&mut it, "S100\nM29 G84 X5 Z-10 R2 F100\nX10\nG74 X15\nG84 X20 S100").unwrap();
    assert_eq!(story(&b[1]).matches("CHK").count(), 1);
    assert!(!story(&b[2]).contains("EXIT") && !story(&b[3]).contains("EXIT"));
    assert!(taps(&b[2])[0].spindle_forward && !taps(&b[3])[0].spindle_forward);
    assert!(it.rigid_mode());
}

#[test]
fn parameter_5200_0_makes_g84_rigid_without_m29() {
    let mut it = interp(&[("5200.0", 1.0)]);
    let b = blocks_on(&mut it, "S200 M03\nG84 X0 Z-10 R2 F300\nX5").unwrap();
    assert!(story(&b[1]).starts_with("M29<200> [positioning]"));
    assert_eq!(taps(&b[1])[0].lead_nm, 1_500_000);
    assert!(!story(&b[2]).contains("M29"));
    assert!(it.rigid_mode());
    assert_eq!(blocks_on(&mut it, "M29").unwrap_err().kind, AlarmKind::ProgramMissRigid);
}

#[test]
fn g84_2_is_rigid_and_g84_3_left_hand() {
    let b = run_with(&[], "S300\nG84.3 X0 Z-10 R2 F300").unwrap();
    assert!(story(&b).starts_with("S300 M29<300>"));
    assert!(!taps(&b)[0].spindle_forward);
}

#[rstest]
#[case::pcp_deep(1.0, vec![-3, 2, -8, 2, -10, 2])]
#[case::pcp_high_speed(0.0, vec![-3, -2, -8, -7, -10, 2])]
fn rigid_peck_mode_follows_5200_5(#[case] pcp: f64, #[case] want: Vec<i64>) {
    let s = run_with(&[("5200.5", pcp)], "S100\nM29\nG84 X0 Z-10 R2 Q5 F100").unwrap();
    assert_eq!(
        taps(&s).iter().map(|t| t.target).collect::<Vec<_>>(),
        want.iter().map(|v| v * MM).collect::<Vec<_>>()
    );
}

#[rstest]
#[case::g94("G94", "F150", 1_500_000)]
#[case::g95("G95", "F1.25", 1_250_000)]
#[case::g94_rounded("G94", "F100.0003", 1_000_003)]
fn rigid_lead(#[case] mode: &str, #[case] f: &str, #[case] lead: i64) {
    let s = run_with(&[], &format!("{mode}\nS100\nM29\nG84 X0 Z-10 R2 {f}")).unwrap();
    assert!(taps(&s).iter().all(|t| t.lead_nm == lead));
}

#[rstest]
#[case(0.0, 100)]
#[case(150.0, 150)]
fn extraction_override_5211(#[case] v: f64, #[case] pct: u32) {
    let s = run_with(&[("5211", v)], "S100\nM29\nG84 X0 Z-10 R2 F100").unwrap();
    let t = taps(&s);
    assert_eq!((t[0].override_pct, t[1].override_pct), (100, pct));
}

#[test]
fn conventional_tapping_in_g95_feeds_per_rev_and_ignores_q() {
    let s = steps("G95 S100 M03\nG99 G84 X0 Z-10 R2 Q3 F1.5 M05");
    assert_eq!(
        story(&s),
        "S100 M3 [positioning] G0(0 0 0) G0(0 0 2) HOLD- [cutting] G1(0 0 -10)F1.5/rev M5 M4 [retract] \
         G1(0 0 2)F1.5/rev M5 M3 HOLD+ [idle] M5"
    );
}

#[test]
fn g74_conventional_reverses_to_m03_and_back_to_m04() {
    let s = steps("S100 M04\nG74 X0 Z-10 R2 F100");
    assert!(story(&s).contains("M5 M3 [retract] G1(0 0 2)F100/min M5 M4 HOLD+ G0(0 0 0)"));
}

#[test]
fn the_tool_axis_follows_the_plane() {
    // G18: plane Z X, tool along Y; the hole is positioned in Z and X.
    let s = steps("G18\nS100 M03\nG99 G81 Z5 X7 Y-10 R2 F100");
    assert_eq!(feeds(&s), vec![[7 * MM, -10 * MM, 5 * MM, 0, 0, 0]]);
    assert!(story(&s).contains("G0(7 0 5) G0(7 2 5)"));
}

#[test]
fn block_order_s_t_m_motion_m05_m09_end() {
    assert_eq!(story(&steps("X1 S100 T2 M09 M03 M30")), "S100 T2 M3 G0(1 0 0) M9 M30 END");
    assert_eq!(story(&steps("M01 M19 M00")), "M19 M1 M01 M0 M00");
    assert_eq!(story(&steps("M29 S300")), "S300 M29<300>");
    assert_eq!(story(&steps("S300\nM29\nS300 M08")), "S300 M29<300> M8");
    assert_eq!(story(&steps("M5 M123")), "M123 M5");
}

#[rstest]
#[case::p_ms("G04 P300", 300)]
#[case::p_seconds("G04 P1.5", 1500)]
#[case::x_seconds("G04 X2.", 2000)]
#[case::x_ms("G04 X250", 250)]
fn dwell_forms(#[case] text: &str, #[case] ms: u64) {
    assert_eq!(steps(text), vec![Step::Dwell { us: ms * 1000 }]);
}

#[rstest]
#[case::cw_ijk("G02 X10 I5 F100", "G2(10 0 0 c5,0)F100/min")]
#[case::full_circle("G03 I5 F100", "G3(0 0 0 c5,0)F100/min")]
#[case::helical("G03 Z5 I5 F100", "G3(0 0 5 c5,0)F100/min")]
#[case::r_semicircle("G03 X10 R5 F100", "G3(10 0 0 c5,0)F100/min")]
#[case::r_zero_length("G02 X0 R5 F100", "")]
#[case::g18_centre("G18 G02 Z10 K5 F100", "G2(0 0 10 c5,0)F100/min")]
#[case::g19_centre("G19 G02 Y10 J5 F100", "G2(0 10 0 c5,0)F100/min")]
fn arcs(#[case] text: &str, #[case] want: &str) {
    assert_eq!(story(&steps(text)), want);
}

#[rstest]
#[case::g02_short("G02 X10 R5.1", -1)]
#[case::g02_long("G02 X10 R-5.1", 1)]
#[case::g03_short("G03 X10 R5.1", 1)]
#[case::g03_long("G03 X10 R-5.1", -1)]
fn r_arcs_take_the_side_of_the_sign(#[case] text: &str, #[case] side: i64) {
    let s = steps(&format!("{text} F100"));
    let Step::Arc { center, .. } = s[0] else { panic!("{s:?}") };
    assert_eq!(center[0], 5 * MM);
    assert_eq!(center[1].signum(), side);
    assert!((center[1].abs() - 1_004_988).abs() <= 1, "{center:?}");
}

#[rstest]
#[case::dpi_inch(1.0, "G20 G00 X1. Y1", [25_400_000, 25_400_000, 0])]
#[case::is_b_inch(0.0, "G20 G00 X1. Y1", [25_400_000, 2540, 0])]
#[case::is_b_metric(0.0, "G21 G00 X1. Y1 Z-5", [MM, 1000, -5000])]
fn units(#[case] dpi: f64, #[case] text: &str, #[case] want: [Nm; 3]) {
    let s = run_with(&[("3401.0", dpi)], text).unwrap();
    let Step::Rapid { target } = s[0] else { panic!() };
    assert_eq!(&target[..3], &want);
}

#[test]
fn rotary_axes_stay_in_degrees_in_inch() {
    let s = steps("G20 G91 G00 A90. B-1.5");
    assert_eq!(s, vec![Step::Rapid { target: [0, 0, 0, 90 * MM, -1_500_000, 0] }]);
}

#[test]
fn g28_g30_and_g53() {
    assert_eq!(story(&steps("G00 X5 Y5 Z5\nG28 Z10")), "G0(5 5 5) G0(5 5 10) G0(5 5 0)");
    assert_eq!(story(&steps("G00 X5 Z5\nG91 G30 P2 X1")), "G0(5 0 5) G0(6 0 5) G0(0 0 5)");
    assert_eq!(story(&steps("G00 X5\nG91 G53 X1 Z-3")), "G0(5 0 0) G0(1 0 -3)");
    assert_eq!(story(&steps("G28")), "");
}

#[test]
fn modal_groups_in_order() {
    let mut it = interp(&[]);
    assert_eq!(it.modal(), ["G00", "G17", "G90", "G94", "G98", "G21", "G80", "G40", "G49", "G54"]);
    blocks_on(&mut it, "G01 G91 G19 G95 G99 G20 G41 D1 G43 H1 G55 G61 G05.1 Q1 G09 G15\nG81").unwrap();
    assert_eq!(
        it.modal(),
        ["G01", "G19", "G91", "G95", "G99", "G20", "G81", "G41", "G43", "G55", "G61", "G05.1 Q1"]
    );
    blocks_on(&mut it, "G80 G54.1 P2 G43.4 G64 G05.1 Q0 G49").unwrap();
    assert_eq!(&it.modal()[6..], ["G80", "G41", "G49", "G54.1 P2"]);
    blocks_on(&mut it, "G84.2").unwrap_err();
}

#[test]
fn reset_cancels_cycle_and_rigid_mode() {
    let mut it = interp(&[]);
    blocks_on(&mut it, "S100\nM29\nG84 X0 Z-10 R2 F100").unwrap();
    it.reset([MM, 0, 3 * MM, 0, 0, 0]);
    assert!(!it.rigid_mode());
    assert_eq!(it.modal()[6], "G80");
    assert_eq!(story(&blocks_on(&mut it, "G91 X1").unwrap()[0]), "G0(2 0 3)");
    it.set_position([0; AXES]);
    assert_eq!(story(&blocks_on(&mut it, "X1").unwrap()[0]), "G0(1 0 0)");
}

#[test]
fn g98_return_is_skipped_when_already_at_the_initial_level() {
    // Initial level 2 = R: nothing to return to.
    let s = steps("G00 Z2\nS100 M03\nG81 X0 Z-5 R2 F100");
    assert!(story(&s).ends_with("[retract] G0(0 0 2) [idle]"));
}

#[test]
fn other_cycles_use_the_drill_bodies() {
    let s = steps("S100 M03\nG99 G82 X0 Z-5 R2 P200 F100\nG86 X1\nG76 X2\nG89 X3");
    let st = story(&s);
    assert!(st.contains("G1(0 0 -5)F100/min [dwell] P200ms [retract] G0(0 0 2)"));
    assert!(st.contains("G1(1 0 -5)F100/min M5 [retract] G0(1 0 2) M3"));
    assert!(st.contains("G1(2 0 -5)F100/min [dwell] P200ms M19 [retract] G0(2 0 2) M3"));
    assert!(st.contains("G1(3 0 -5)F100/min [dwell] P200ms [retract] G1(3 0 2)F100/min"));
}

#[test]
fn m29_and_the_tapping_block_may_carry_axis_words() {
    let mut it = interp(&[]);
    let b = blocks_on(&mut it, "S100\nM29 G84 X5 Z-10 R2 F100\nX10\nG80\nX0").unwrap();
    assert_eq!(taps(&b[2]).len(), 2);
    assert_eq!(story(&b[3]), "EXIT");
    assert_eq!(story(&b[4]), "G0(0 0 0)");
}
