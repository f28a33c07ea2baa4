//! Unit tests of the parameter file reader.

use super::*;

fn gsk() -> Machine {
    Machine::new("gsk-lathe").expect("gsk-lathe dialect")
}

/// The text at a span.
fn at(text: &str, s: Span) -> &str {
    &text[s.offset..s.offset + s.len]
}

#[test]
fn reads_numbers_bits_and_per_axis_values_in_order() {
    let text = "params:\n  170: 68\n  \"186.2\": 1\n  186.7: true\n  34: {X: 0.01, z: 0.005}\n  nc.rt_ramp_ms: 150\n";
    let s = parse(text).unwrap();
    let got: Vec<(&str, Option<char>, f64)> = s.iter().map(|s| (s.id.as_str(), s.axis, s.value)).collect();
    assert_eq!(
        got,
        [
            ("170", None, 68.0),
            ("186.2", None, 1.0),
            ("186.7", None, 1.0),
            ("34", Some('X'), 0.01),
            ("34", Some('Z'), 0.005),
            ("nc.rt_ramp_ms", None, 150.0),
        ]
    );
    assert_eq!((s[0].id_span.line, s[0].id_span.col), (2, 3));
    assert_eq!((s[0].value_span.line, s[0].value_span.col), (2, 8));
    assert_eq!(at(text, s[0].value_span), "68");
    assert_eq!(at(text, s[4].value_span), "0.005");
    assert_eq!(at(text, s[4].axis_span.unwrap()), "z");

    let mut m = gsk();
    assert_eq!(apply(text, &mut m).unwrap(), 6);
    assert_eq!(m.params.get("170"), 68.0);
    assert!(m.params.bit("186.2"));
    assert!(m.params.bit("186.7"));
    assert_eq!(m.params.get_axis("34", Some('Z')), 0.005);
    assert_eq!(m.params.get("nc.rt_ramp_ms"), 150.0);
}

#[test]
fn numeric_ids_keep_their_written_form() {
    let text = "params:\n  3401.0: 0\n  5200.5: 0\n  1851: {Y: 0.25}\n";
    let s = parse(text).unwrap();
    let ids: Vec<&str> = s.iter().map(|s| s.id.as_str()).collect();
    assert_eq!(ids, ["3401.0", "5200.5", "1851"]);
    let mut m = Machine::new("fanuc-mill").unwrap();
    apply(text, &mut m).unwrap();
    assert!(!m.params.bit("3401.0"));
    assert!(!m.params.bit("5200.5"));
    assert_eq!(m.params.get_axis("1851", Some('Y')), 0.25);
}

#[test]
fn empty_files_set_nothing() {
    for text in ["", "\n# nothing\n", "params:\n", "params: {}\n"] {
        assert_eq!(parse(text).unwrap(), Vec::new(), "{text:?}");
    }
}

#[test]
fn unknown_id_points_at_the_id() {
    let text = "params:\n  170: 68\n  9999: 1\n";
    let e = apply(text, &mut gsk()).unwrap_err();
    assert_eq!((e.span.line, e.span.col), (3, 3), "{e}");
    assert_eq!(at(text, e.span), "9999");
    assert!(e.message.contains("unknown parameter `9999`"), "{e}");
    assert!(e.expected.as_deref().unwrap().contains("170"), "{e}");
}

#[test]
fn out_of_range_points_at_the_value() {
    let text = "params:\n  271: 301\n";
    let e = apply(text, &mut gsk()).unwrap_err();
    assert_eq!((e.span.line, e.span.col), (2, 8), "{e}");
    assert_eq!(at(text, e.span), "301");
    assert!(e.message.contains("out of range"), "{e}");
    assert_eq!(e.expected.as_deref(), Some("0 to 300 %"));
}

#[test]
fn per_axis_mismatches_are_located() {
    // A single number for a per-axis parameter: at the value.
    let text = "params:\n  34: 0.01\n";
    let e = apply(text, &mut gsk()).unwrap_err();
    assert_eq!(at(text, e.span), "0.01", "{e}");
    assert!(e.message.contains("per axis"), "{e}");
    // Per-axis values for a single-valued parameter: at the value.
    let text = "params:\n  170: {X: 1}\n";
    let e = apply(text, &mut gsk()).unwrap_err();
    assert_eq!(at(text, e.span), "1", "{e}");
    // An axis the dialect does not have: at the axis letter.
    let text = "params:\n  34: {Y: 0.01}\n";
    let e = apply(text, &mut gsk()).unwrap_err();
    assert_eq!((e.span.line, e.span.col), (2, 8), "{e}");
    assert!(e.message.contains("not an axis of dialect gsk-lathe"), "{e}");
    assert_eq!(e.expected.as_deref(), Some("one of X Z C"));
    // Not a letter at all.
    let text = "params:\n  34: {XY: 0.01}\n";
    let e = apply(text, &mut gsk()).unwrap_err();
    assert_eq!(at(text, e.span), "XY", "{e}");
}

#[test]
fn yaml_errors_are_located() {
    let cases = [
        ("params:\n  170: [1, 2]\n", 2),
        ("params:\n  170: abc\n", 2),
        ("parms:\n  170: 1\n", 1),
        ("params:\n  170: 1\n  170: 2\n", 3),
        ("params:\n  170: 1\n bad: [\n", 3),
        ("params:\n  34: {X: a}\n", 2),
        ("- 1\n- 2\n", 1),
    ];
    for (text, line) in cases {
        let e = parse(text).unwrap_err();
        assert_eq!(e.span.line, line, "{text:?}: {e}");
        assert!(e.span.col >= 1, "{e}");
        assert!(e.message.starts_with("invalid parameter file: "), "{e}");
        assert!(!e.message.contains(" at line "), "{e}");
    }
}

#[test]
fn unknown_top_level_keys_are_named() {
    let e = parse("params: {}\nmachine: gsk-lathe\n").unwrap_err();
    assert_eq!(e.span.line, 2, "{e}");
    assert!(e.message.contains("machine"), "{e}");
}

#[test]
fn a_file_may_name_its_dialect_and_is_refused_on_another() {
    let f = parse_file("dialect: linuxcnc\nparams:\n  nc.feed_ramp_ms: 80\n").unwrap();
    assert_eq!(f.dialect.as_ref().map(|(d, s)| (d.as_str(), s.line, s.col)), Some(("linuxcnc", 1, 10)));
    assert!(f.fits("linuxcnc") && !f.fits("fanuc-mill"));
    assert_eq!(f.settings.len(), 1);
    assert!(ParamsFile::default().fits("gsk-lathe"), "no dialect named: any");
    let mut m = nc_engine::Machine::new("fanuc-mill").unwrap();
    let e = apply("dialect: linuxcnc\nparams:\n  nc.feed_ramp_ms: 80\n", &mut m).unwrap_err();
    assert_eq!((e.span.line, e.span.col), (1, 10), "{e}");
    assert!(e.message.contains("parameters of dialect linuxcnc, not of dialect fanuc-mill"), "{e}");
    let e = parse_file("dialect: fanuc\n").unwrap_err();
    assert!(e.message.contains("unknown dialect `fanuc`"), "{e}");
}
