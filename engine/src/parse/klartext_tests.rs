//! Tests of the Klartext parser (HDH-LEX-01, HDH-LEX-02).

use super::*;
use rstest::rstest;

fn kl(text: &str) -> Vec<(u32, Klartext)> {
    parse(text, "heidenhain")
        .unwrap_or_else(|e| panic!("{text:?}: {e}"))
        .blocks
        .into_iter()
        .map(|b| (b.line, *b.klartext.expect("a Klartext block")))
        .collect()
}

fn bad(text: &str) -> ParseError {
    match parse(text, "heidenhain") {
        Ok(p) => panic!("{text:?} parsed: {p:?}"),
        Err(e) => e,
    }
}

/// The seed's example, laid out as the seed shows it (a comment line after each parameter,
/// blank lines between).
const SEED: &str = include_str!("../../../examples/heidenhain_832_seed.h");

fn q_block(skip: Option<u16>, extra: &str) -> String {
    let mut s = String::from("1 CYCL DEF 832 THREAD EXTENDED ~\n");
    for q in Q832 {
        if Some(q) != skip {
            s.push_str(&format!("  Q{q}=+1 ;X ~\n"));
        }
    }
    s.push_str(extra);
    s.push_str("2 CYCL CALL\n");
    s
}

#[test]
fn the_seed_program_reads_block_by_block() {
    let b = kl(SEED);
    let lines: Vec<u32> = b.iter().map(|(l, _)| *l).collect();
    assert_eq!(lines, vec![1, 4, 5, 6, 7, 28, 29, 30, 31, 32]);
    let Klartext::CyclDef { number, params } = &b[4].1 else { panic!("{:?}", b[4]) };
    assert_eq!(number.value.as_int(), Some(832));
    assert_eq!(params.iter().map(|p| p.number).collect::<Vec<_>>(), Q832.to_vec());
    assert_eq!((params[1].number, params[1].v.line, params[1].v.col), (461, 9, 5));
    assert_eq!(params[14].v.value, Decimal { mantissa: 5, scale: 1, point: true });
    assert!(matches!(b[9].1, Klartext::EndPgm));
}

#[test]
fn the_seeds_own_layout_with_comment_lines_and_blank_lines() {
    let mut s = String::from("11 CYCL DEF 832 THREAD EXTENDED ~\n\n");
    for q in Q832 {
        s.push_str(&format!("Q{q}=+0\n\n;NAME ~\n\n"));
    }
    s.push_str("12 L X+80 Y+0 Z+2 FMAX M303\n\n13 CYCL CALL\n");
    let b = kl(&s);
    assert_eq!(b.len(), 3);
    let Klartext::CyclDef { params, .. } = &b[0].1 else { panic!() };
    assert_eq!(params.len(), 20);
    let Klartext::Line { x, y, z, feed, m, comp } = &b[1].1 else { panic!() };
    assert_eq!(x.map(|c| c.v.value.as_int()), Some(Some(80)));
    assert_eq!(y.map(|c| c.v.value.as_int()), Some(Some(0)));
    assert_eq!(z.map(|c| (c.incremental, c.v.col)), Some((false, 15)));
    assert_eq!((feed, comp), (&Some(KFeed::Max), &None));
    assert_eq!(m.iter().map(|v| v.value.as_int()).collect::<Vec<_>>(), vec![Some(303)]);
    assert!(matches!(b[2].1, Klartext::CyclCall { .. }));
}

#[rstest]
#[case::begin("0 BEGIN PGM X MM", Klartext::BeginPgm { inch: false, col: 15 })]
#[case::mode("FUNCTION MODE TURN", Klartext::Mode(true))]
#[case::mill("3 FUNCTION MODE MILL", Klartext::Mode(false))]
#[case::stop("STOP", Klartext::Misc { stop: true, m: vec![] })]
#[case::cc("5 CC X+0 Z+0", Klartext::NotModelled { what: "CC".into(), col: 3 })]
#[case::lbl("LBL 1", Klartext::NotModelled { what: "LBL".into(), col: 1 })]
#[case::fn_q("FN 0: Q1 = +5", Klartext::NotModelled { what: "FN".into(), col: 1 })]
#[case::q_assign("Q1 = 5", Klartext::NotModelled { what: "Q parameter assignment".into(), col: 1 })]
#[case::tool_def("TOOL DEF 3", Klartext::NotModelled { what: "TOOL DEF".into(), col: 1 })]
fn simple_blocks(#[case] text: &str, #[case] want: Klartext) {
    assert_eq!(kl(text), vec![(1, want)]);
}

#[test]
fn tool_call_turndata_incremental_and_continuation() {
    let b = kl("TOOL CALL \"THREAD OUT\" S800\nTOOL CALL 12 Z S500 F0.2\n\
                FUNCTION TURNDATA SPIN VCONST:OFF S650\nL IX-2 IZ+1.5 F150 M3 M8\nL X+1 ~\n  Z+2 FMAX\n");
    let s: Vec<Option<i64>> = b
        .iter()
        .filter_map(|(_, k)| match k {
            Klartext::ToolCall { s, .. } | Klartext::Spin { s, .. } => Some(s.and_then(|v| v.value.as_int())),
            _ => None,
        })
        .collect();
    assert_eq!(s, vec![Some(800), Some(500), Some(650)]);
    let Klartext::Line { x, feed: Some(KFeed::Rate(f)), m, .. } = &b[3].1 else { panic!("{:?}", b[3]) };
    assert!(x.unwrap().incremental);
    assert_eq!((f.value.to_f64(), m.len()), (150.0, 2));
    let Klartext::Line { x, z, feed, .. } = &b[4].1 else { panic!() };
    assert_eq!((x.is_some(), z.map(|c| c.v.line), feed), (true, Some(6), &Some(KFeed::Max)));
}

#[test]
fn lines_after_end_pgm_and_structure_items_are_ignored() {
    let b = kl("* - threading\n;note\n\n0 BEGIN PGM A MM\n1 END PGM A MM\nG0 X1 ###");
    assert_eq!(b.len(), 2);
}

const EXPECT: &str = EXPECT_BLOCK;

#[rstest]
#[case::gcode("G0 X10 Z2", "1:1+2", "`G0` looks like ISO G-code; dialect heidenhain reads Klartext", EXPECT)]
#[case::gcode_after_number("10 G84 Z-5", "1:4+3", "`G84` looks like ISO G-code", EXPECT)]
#[case::percent("%\nO1000", "1:1+1", "`%` looks like ISO G-code", EXPECT)]
#[case::word("HELLO", "1:1+5", "`HELLO` is not a Klartext block", EXPECT)]
#[case::bad_axis("L X+1 W+2", "1:7+3", "`W+2` in an L block", "X…, Z…")]
#[case::twice("L X+1 X+2", "1:7+3", "the axis is written twice", "X…")]
#[case::no_value("L X", "1:3+1", "`X` in an L block", "X…")]
#[case::bad_number("L X+1.2.3", "1:3+7", "`X+1.2.3`: not a number", "a number")]
#[case::unit("BEGIN PGM A CM", "1:13+2", "`CM` is not a program unit", "MM or INCH")]
#[case::begin_short("BEGIN PGM", "1:10+1", "BEGIN PGM is incomplete", "BEGIN PGM name MM")]
#[case::mode("FUNCTION MODE DRILL", "1:15+5", "not a machining mode", "TURN or MILL")]
#[case::cycl("CYCL RUN", "1:6+3", "`RUN` after CYCL", "CYCL DEF or CYCL CALL")]
#[case::call_m("CYCL CALL X+1", "1:11+3", "is not an M function", "M and a number")]
#[case::seq("123456789 L X+1", "1:1+9", "block number 123456789 is too large", "a block number")]
#[case::q_text("CYCL DEF 832\n Q471=abc", "2:2+8", "`Q471=abc`: not a number", "Qnnn=value")]
#[case::q_no_value("CYCL DEF 832\n Q471", "2:2+4", "`Q471` has no value", "Qnnn=value")]
#[case::q_number("CYCL DEF 832\n Q99999=1", "2:2+8", "`Q99999` is not a Q parameter", "Q0..Q1999")]
fn refused(#[case] text: &str, #[case] at: &str, #[case] message: &str, #[case] expected: &str) {
    let e = bad(text);
    let got = format!("{}:{}+{}", e.line, e.col, e.len);
    assert_eq!(got, at, "{text:?}: {e}");
    assert!(e.message.contains(message), "{text:?}: {}", e.message);
    assert!(e.expected.contains(expected), "{text:?}: {}", e.expected);
}

#[test]
fn cycle_832_needs_each_parameter_once() {
    assert_eq!(kl(&q_block(None, "")).len(), 2);
    let e = bad(&q_block(Some(467), ""));
    assert_eq!((e.line, e.col), (1, 3));
    assert_eq!(e.message, "cycle 832 lacks Q467");
    let e = bad(&q_block(None, "  Q471=+0 ;again\n"));
    assert_eq!((e.line, e.col, e.message.as_str()), (22, 3, "Q471 is given twice in cycle 832"));
    let e = bad(&q_block(None, "  Q200=+2\n"));
    assert_eq!((e.line, e.message.as_str()), (22, "Q200 is not a parameter of cycle 832"));
    assert!(e.expected.contains("Q471 Q461"), "{}", e.expected);
    // Another cycle keeps whatever parameters it has (it is refused when called).
    assert_eq!(kl("CYCL DEF 200 DRILLING\n Q200=+2\nCYCL CALL").len(), 2);
    // Spaces around `=` are fine.
    let b = kl(&q_block(None, "").replace("Q471=+1", "Q471 = +1"));
    let Klartext::CyclDef { params, .. } = &b[0].1 else { panic!() };
    assert_eq!(params[0].v.value.as_int(), Some(1));
}

#[test]
fn no_text_breaks_the_parser() {
    let tricky = "\u{feff}0 BEGIN PGM A MM\r\n1 CYCL DEF 832 ~\n Q471=+0 ;x ~\n Q461 = ~\n\u{0}Q=\n\
                  L X+1.2.3 IX-- FMAX M\nTOOL CALL \"a b S5\nFUNCTION TURNDATA SPIN VCONST:ON\n~\n~~\nQ1\n";
    for (i, _) in tricky.char_indices().chain([(tricky.len(), ' ')]) {
        let _ = parse(&tricky[..i], "heidenhain");
        let _ = parse(&tricky[i..], "heidenhain");
    }
    let long = format!("L X+{}", "9".repeat(100_000));
    assert!(bad(&long).message.contains("too many digits"));
    let many = "L X+1 Z-2 F100\n".repeat(20_000);
    assert_eq!(parse(&many, "heidenhain").unwrap().blocks.len(), 20_000);
}
