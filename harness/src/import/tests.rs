//! Unit tests of the importers: each format's events, bad rows with their line and column
//! (rstest tables), lenient counting, format detection, the column map's located errors.

use std::io::Cursor;

use nc_engine::trace::{Event, Phase, Signal, TraceEvent};
use rstest::rstest;

use super::*;
use crate::import::map::ColumnMap;

const MAP: &str = "\
time: {column: time, unit: ms}
axes:
  - {axis: X, column: X_act, diameter: true}
  - {axis: Z, column: Z_act, scale: 0.001}
spindle:
  rpm: {column: S_act}
signals:
  - {signal: F76.3, column: flags, bit: 3}
  - {signal: ZSP, column: S_act, below: 5}
ignore: [note]
";

fn map() -> ColumnMap {
    ColumnMap::from_yaml("map.yaml", MAP).expect("map loads")
}

fn import(
    format: Option<Format>,
    text: &str,
    map: Option<&ColumnMap>,
    lenient: bool,
) -> (Vec<TraceEvent>, Result<(), ImportError>, Warnings) {
    let opts = Options { format, map, lenient };
    let imp = match from_reader("rec", Box::new(Cursor::new(text.as_bytes().to_vec())), &opts) {
        Ok(i) => i,
        Err(e) => return (Vec::new(), Err(e), Warnings::default()),
    };
    let mut imp = imp;
    let mut evs = Vec::new();
    let mut res = Ok(());
    for item in imp.by_ref() {
        match item {
            Ok(e) => evs.push(e),
            Err(e) => {
                res = Err(e);
                break;
            }
        }
    }
    (evs, res, imp.warnings().clone())
}

#[test]
fn csv_rows_become_samples_and_edges() {
    let text =
        "time,X_act,Z_act,S_act,flags,note\n0,50,0,0,0,a\n1.5,50.5,-1500,100,8,b\n2,50.5,-1500,100,8,c\n";
    let m = map();
    let (evs, res, _) = import(None, text, Some(&m), false);
    res.unwrap();
    let kinds: Vec<String> =
        evs.iter().map(|e| format!("{}:{:?}", e.t_us, std::mem::discriminant(&e.event))).collect();
    assert_eq!(evs.len(), 6, "{kinds:?}");
    // t=0: sample, ZSP on (speed 0 < 5).
    assert_eq!(evs[1].event, Event::Signal { signal: Signal::Zsp, value: true });
    let Event::Sample(s) = &evs[2].event else { panic!("{:?}", evs[2]) };
    assert_eq!(evs[2].t_us, 1500);
    assert_eq!(s.axes[0], 50_500_000);
    assert_eq!(s.axes[2], -1_500_000);
    assert_eq!(s.spindle_mrpm, 100_000);
    // Falls before rises within a row.
    assert_eq!(evs[3].event, Event::Signal { signal: Signal::Zsp, value: false });
    assert_eq!(evs[4].event, Event::Signal { signal: Signal::Rtap, value: true });
    assert_eq!(evs[5].t_us, 2000);
}

#[test]
fn csv_meta_and_first_time() {
    let m = map();
    let opts = Options { format: None, map: Some(&m), lenient: false };
    let text = "time,X_act,Z_act,S_act,flags,note\n7,0,0,0,0,\n";
    let imp = from_reader("rec", Box::new(Cursor::new(text.as_bytes().to_vec())), &opts).unwrap();
    assert_eq!(imp.meta().format, Format::Csv);
    assert_eq!(imp.meta().first_t_us, Some(7000));
    assert_eq!(imp.meta().axes.len(), 2);
    assert!(imp.meta().axes[0].diameter);
    assert_eq!(imp.meta().signals, vec![Signal::Rtap, Signal::Zsp]);
}

#[rstest]
#[case::bad_number("time,X_act,Z_act,S_act,flags,note\n0,5x,0,0,0,\n", 2, 3, "not a number")]
#[case::bad_time("time,X_act,Z_act,S_act,flags,note\n0,1,0,0,0,\nzz,1,0,0,0,\n", 3, 1, "not a number")]
#[case::short_row("time,X_act,Z_act,S_act,flags,note\n0,1,0,0\n", 2, 8, "the row has 4 fields")]
#[case::long_row("time,X_act,Z_act,S_act,flags,note\n0,1,0,0,0,,9\n", 2, 13, "the row has 7 fields")]
#[case::time_back("time,X_act,Z_act,S_act,flags,note\n5,1,0,0,0,\n4,1,0,0,0,\n", 3, 1, "time goes back")]
#[case::negative_time("time,X_act,Z_act,S_act,flags,note\n-1,1,0,0,0,\n", 2, 1, "negative time")]
#[case::bad_bits("time,X_act,Z_act,S_act,flags,note\n0,1,0,0,1.5,\n", 2, 9, "not an unsigned integer")]
#[case::open_quote("time,X_act,Z_act,S_act,flags,note\n0,1,0,0,0,\"abc\n", 2, 11, "quote is not closed")]
#[case::unknown_column(
    "time,X_act,Z_act,S_act,flags,note,extra\n0,1,0,0,0,,1\n",
    1,
    35,
    "column `extra` is not in the column map"
)]
#[case::missing_column(
    "time,X_act,S_act,flags\n",
    1,
    1,
    "column `Z_act` of the column map is not in the header"
)]
#[case::empty_field("time,X_act,Z_act,S_act,flags,note\n0,,0,0,0,\n", 2, 3, "not a number")]
fn csv_errors_name_line_and_column(
    #[case] text: &str,
    #[case] line: u64,
    #[case] col: u64,
    #[case] msg: &str,
) {
    let m = map();
    let (_, res, _) = import(None, text, Some(&m), false);
    let e = res.expect_err("an error");
    assert_eq!((e.line, e.col), (line, col), "{e}");
    assert!(e.message.contains(msg), "{e}");
    assert!(e.expected.is_some(), "{e}");
    let d: crate::diag::InputError = e.into();
    assert!(d.headline().starts_with(&format!("rec:{line}:{col}: ")), "{}", d.headline());
}

#[test]
fn csv_lenient_counts_and_skips_bad_rows() {
    let text = "time,X_act,Z_act,S_act,flags,note,extra\n0,1,0,0,0,,\n1,zz,0,0,0,,\n0.5,1,0,0,0,,\n2,1,0,0\n3,2,0,0,0,,\n";
    let m = map();
    let (evs, res, w) = import(None, text, Some(&m), true);
    res.unwrap();
    assert_eq!(w.count(ErrorKind::Unknown), 1);
    assert_eq!(w.count(ErrorKind::BadRow), 1);
    assert_eq!(w.count(ErrorKind::NonMonotonicTime), 0, "0.5 ms comes after 0 ms: in order");
    assert_eq!(w.count(ErrorKind::Truncated), 1);
    assert_eq!(w.total(), 3);
    let samples: Vec<u64> =
        evs.iter().filter(|e| matches!(e.event, Event::Sample(_))).map(|e| e.t_us).collect();
    assert_eq!(samples, vec![0, 500, 3000]);
    assert_eq!(w.first[1].line, 3);
}

#[test]
fn csv_lenient_counts_time_going_back() {
    let text = "time,X_act,Z_act,S_act,flags,note\n5,1,0,0,0,\n4,1,0,0,0,\n6,1,0,0,0,\n";
    let m = map();
    let (evs, res, w) = import(None, text, Some(&m), true);
    res.unwrap();
    assert_eq!(w.count(ErrorKind::NonMonotonicTime), 1);
    assert_eq!(evs.iter().filter(|e| matches!(e.event, Event::Sample(_))).count(), 2);
}

#[test]
fn csv_quotes_skip_rows_delimiter_and_no_header() {
    let m = ColumnMap::from_yaml(
        "m.yaml",
        "delimiter: \";\"\nskip_rows: 2\nheader: false\ntime: {column: 1, unit: s}\naxes: [{axis: Z, column: 3}]\nignore: []\n",
    )
    .unwrap();
    let text = "Trace tool v1\nexported 2024\n0.001;\"a;b\";-2.5\n0.002;\"x\"\"y\";-2.25\n";
    let (evs, res, _) = import(Some(Format::Csv), text, Some(&m), false);
    res.unwrap();
    assert_eq!(evs.len(), 2);
    assert_eq!(evs[1].t_us, 2000);
    let Event::Sample(s) = &evs[1].event else { panic!() };
    assert_eq!(s.axes[2], -2_250_000);
}

#[test]
fn csv_without_map_is_an_error() {
    let (_, res, _) = import(Some(Format::Csv), "a,b\n", None, false);
    assert!(res.unwrap_err().message.contains("column map"));
}

#[rstest]
#[case::unknown_key("time: {column: t}\nfoo: 1\n", 2, 1, "unknown field")]
#[case::bad_axis("time: {column: t}\naxes: [{axis: Q, column: q}]\n", 2, 15, "unknown axis")]
#[case::bad_signal("time: {column: t}\nsignals:\n  - {signal: NOPE, column: q}\n", 3, 14, "unknown signal")]
#[case::bad_unit("time: {column: t, unit: h}\n", 1, 25, "unknown time unit")]
#[case::bad_delim("delimiter: ab\ntime: {column: t}\n", 1, 12, "delimiter")]
#[case::two_levels(
    "time: {column: t}\nsignals:\n  - {signal: ZSP, column: q, bit: 1, above: 2}\n",
    3,
    14,
    "more than one"
)]
fn map_errors_are_located(#[case] text: &str, #[case] line: u32, #[case] col: u32, #[case] msg: &str) {
    let e = ColumnMap::from_yaml("m.yaml", text).expect_err("an error");
    let (span, _) = e.at.clone().expect("a location");
    assert_eq!((span.line, span.col), (line, col), "{}", e.headline());
    assert!(e.message.contains(msg), "{}", e.headline());
}

const JSONL: &str = r#"{"t_us":0,"kind":"meta","dialect":"gsk-lathe","axes":["X","Z","C"],"diameter":["X"],"period_us":1000,"sample_us":1000,"format":"nc-conform-trace/1"}
{"t_us":0,"kind":"signal","name":"STL","value":1}
{"t_us":0,"kind":"block","line":4,"text":"G0 X50 Z0"}
{"t_us":1000,"kind":"sample","axes":{"X":0.001328,"Z":-12.5,"C":0},"spindle":{"rpm":-250.5,"angle_deg":359.999}}
{"t_us":1000,"kind":"function","letter":"M","code":29}
{"t_us":1000,"kind":"phase","name":"cutting"}
{"t_us":1000,"kind":"input","name":"feed_override","value":"120%"}
{"t_us":2700,"kind":"alarm","code":"0204","message":"ILLEGAL AXIS OPERATION: Z moved (line 7, column 3)","line":7,"col":3}
{"t_us":3000,"kind":"end","reason":"alarm","axes":{"X":50,"Z":0,"C":0},"command":{"X":50,"Z":0,"C":0},"spindle":{"rpm":0,"angle_deg":0},"signals":{"STL":0,"ESP":1},"modal":["G00"],"alarms":1,"blocks":1}
"#;

#[test]
fn jsonl_reads_every_kind() {
    let (evs, res, _) = import(None, JSONL, None, false);
    res.unwrap();
    assert_eq!(evs.len(), 8);
    let Event::Sample(s) = &evs[2].event else { panic!("{:?}", evs[2]) };
    assert_eq!(
        (s.axes[0], s.axes[2], s.spindle_mrpm, s.spindle_mdeg),
        (1328, -12_500_000, -250_500, 359_999)
    );
    assert_eq!(evs[4].event, Event::Phase(Phase::Cutting));
    let Event::Alarm(a) = &evs[6].event else { panic!() };
    assert_eq!((a.detail.as_str(), a.line, a.col), ("Z moved", Some(7), Some(3)));
    assert_eq!(a.message(), "ILLEGAL AXIS OPERATION: Z moved (line 7, column 3)");
    let Event::End(end) = &evs[7].event else { panic!() };
    assert!(end.signals.get(Signal::Esp));
}

#[rstest]
#[case::not_json("{\"t_us\":5,\"kind\":\"signal\",\"name\":\"STL\",\"value\":1\n", 2, 48, "not JSON")]
#[case::unknown_key(
    "{\"t_us\":5,\"kind\":\"signal\",\"name\":\"STL\",\"value\":1,\"x\":2}\n",
    2,
    50,
    "unknown key `x`"
)]
#[case::bad_signal(
    "{\"t_us\":5,\"kind\":\"signal\",\"name\":\"NOPE\",\"value\":1}\n",
    2,
    27,
    "unknown signal"
)]
#[case::bad_value("{\"t_us\":5,\"kind\":\"signal\",\"name\":\"STL\",\"value\":2}\n", 2, 40, "`value` is 2")]
#[case::missing_key("{\"t_us\":5,\"kind\":\"block\",\"line\":3}\n", 2, 11, "without `text`")]
#[case::time_back(
    "{\"t_us\":5,\"kind\":\"phase\",\"name\":\"idle\"}\n{\"t_us\":4,\"kind\":\"phase\",\"name\":\"idle\"}\n",
    3,
    2,
    "time goes back"
)]
#[case::alarm_without_code(
    "{\"t_us\":5,\"kind\":\"alarm\",\"code\":\"\",\"message\":\"X\"}\n",
    2,
    26,
    "an alarm without a code"
)]
#[case::no_end("{\"t_us\":5,\"kind\":\"phase\",\"name\":\"idle\"}\n", 3, 0, "without its `end` line")]
#[case::axis_missing(
    "{\"t_us\":5,\"kind\":\"sample\",\"axes\":{\"X\":1},\"spindle\":{\"rpm\":0,\"angle_deg\":0}}\n",
    2,
    27,
    "has 1 axes"
)]
fn jsonl_errors_name_line_and_column(
    #[case] body: &str,
    #[case] line: u64,
    #[case] col: u64,
    #[case] msg: &str,
) {
    let meta = JSONL.lines().next().unwrap();
    let text = format!("{meta}\n{body}");
    let (_, res, _) = import(None, &text, None, false);
    let e = res.expect_err("an error");
    assert_eq!((e.line, e.col), (line, col), "{e}");
    assert!(e.message.contains(msg), "{e}");
}

#[rstest]
#[case::format(r#"{"t_us":0,"kind":"meta","dialect":"gsk-lathe","axes":[],"diameter":[],"period_us":1,"sample_us":1,"format":"other/2"}"#, "format `other/2`")]
#[case::dialect(r#"{"t_us":0,"kind":"meta","dialect":"nope","axes":[],"diameter":[],"period_us":1,"sample_us":1,"format":"nc-conform-trace/1"}"#, "unknown dialect")]
#[case::not_meta(r#"{"t_us":0,"kind":"phase","name":"idle"}"#, "not the meta line")]
fn jsonl_header_errors(#[case] meta: &str, #[case] msg: &str) {
    let (_, res, _) = import(Some(Format::Jsonl), &format!("{meta}\n"), None, true);
    let e = res.expect_err("a header error, even lenient");
    assert_eq!(e.line, 1);
    assert!(e.message.contains(msg), "{e}");
}

#[test]
fn jsonl_lenient_counts() {
    let meta = JSONL.lines().next().unwrap();
    let text = format!("{meta}\n{{\"t_us\":1,\"kind\":\"bogus\"}}\nnot json\n{{\"t_us\":2,\"kind\":\"phase\",\"name\":\"idle\"}}\n");
    let (evs, res, w) = import(None, &text, None, true);
    res.unwrap();
    assert_eq!(evs.len(), 1);
    assert_eq!(
        (w.count(ErrorKind::Unknown), w.count(ErrorKind::BadRow), w.count(ErrorKind::Truncated)),
        (1, 1, 1)
    );
}

const VCD: &str = "$timescale 1 ms $end
$scope module signals $end
$var wire 1 ! F76_3 $end
$var wire 1 \" STL $end
$upscope $end
$scope module axes $end
$var real 64 # Z $end
$upscope $end
$scope module cycle $end
$var reg 8 $ phase $end
$var integer 32 % line $end
$upscope $end
$enddefinitions $end
#0
$dumpvars
0!
1\"
r0 #
b0 $
b0 %
$end
#2
1!
r-1.5 #
b10 $
b111 %
#3
0!
";

#[test]
fn vcd_changes_become_events() {
    let (evs, res, _) = import(None, VCD, None, false);
    res.unwrap();
    let got: Vec<(u64, String)> = evs
        .iter()
        .map(|e| {
            let what = match &e.event {
                Event::Sample(s) => format!("sample {}", s.axes[2]),
                Event::Signal { signal, value } => format!("{} {}", signal.name(), u8::from(*value)),
                Event::Phase(p) => p.name().to_string(),
                Event::Block { line, .. } => format!("block {line}"),
                other => format!("{other:?}"),
            };
            (e.t_us, what)
        })
        .collect();
    let want: Vec<(u64, String)> = [
        (0, "sample 0"),
        (0, "STL 1"),
        (2000, "sample -1500000"),
        (2000, "F76.3 1"),
        (2000, "cutting"),
        (2000, "block 7"),
        (3000, "F76.3 0"),
    ]
    .into_iter()
    .map(|(t, s)| (t, s.to_string()))
    .collect();
    assert_eq!(got, want);
}

#[rstest]
#[case::unknown_var(
    "$scope module m $end\n$var wire 1 ! foo $end\n$upscope $end\n$enddefinitions $end\n",
    "unknown variable `m.foo`"
)]
#[case::time_back("$var wire 1 ! STL $end\n$enddefinitions $end\n#5\n1!\n#4\n0!\n", "time goes back")]
#[case::bad_char("$var wire 1 ! STL $end\n$enddefinitions $end\n#5\n?\n", "not VCD")]
#[case::undefined_id("$var wire 1 ! STL $end\n$enddefinitions $end\n#5\n1?\n", "no `$var` defines")]
fn vcd_errors_have_lines(#[case] text: &str, #[case] msg: &str) {
    let (_, res, _) = import(Some(Format::Vcd), text, None, false);
    let e = res.expect_err("an error");
    assert!(e.line >= 1, "{e}");
    assert!(e.message.contains(msg), "{e}");
}

const SHDR: &str = "\
* shdrVersion: 2
2024-05-01T10:00:00.000000Z|avail|AVAILABLE|execution|READY|Xact|50|Zact|0|Sspeed|0
2024-05-01T10:00:00.250Z|execution|ACTIVE|line|4|block|G0 X50 Z0
2024-05-01T10:00:00.5Z|Zact|-1.25|Sspeed|500|RGTAP|1
2024-05-01T10:00:01Z|alarm|EX|0204|FAULT|ACTIVE|Z moved
2024-05-01T10:00:02Z|execution|FEED_HOLD|estop|TRIGGERED|Xact|UNAVAILABLE
";

#[test]
fn shdr_lines_become_events() {
    let (evs, res, _) = import(None, SHDR, None, false);
    res.unwrap();
    let t0 = 1_714_557_600_000_000u64;
    assert_eq!(evs[0].t_us, t0);
    let got: Vec<(u64, String)> = evs
        .iter()
        .map(|e| {
            let what = match &e.event {
                Event::Sample(s) => format!("sample {} {} {}", s.axes[0], s.axes[2], s.spindle_mrpm),
                Event::Signal { signal, value } => format!("{} {}", signal.name(), u8::from(*value)),
                Event::Block { line, text } => format!("block {line} {text}"),
                Event::Alarm(a) => format!("alarm {} {}", a.kind.code(), a.detail),
                other => format!("{other:?}"),
            };
            (e.t_us - t0, what)
        })
        .collect();
    let want: Vec<(u64, &str)> = vec![
        (0, "sample 50000000 0 0"),
        (250_000, "STL 1"),
        (250_000, "block 4 G0 X50 Z0"),
        (500_000, "sample 50000000 -1250000 500000"),
        (500_000, "RGTAP 1"),
        (1_000_000, "alarm 0204 Z moved"),
        (2_000_000, "STL 0"),
        (2_000_000, "SPL 1"),
        (2_000_000, "ESP 1"),
    ];
    let want: Vec<(u64, String)> = want.into_iter().map(|(t, s)| (t, s.to_string())).collect();
    assert_eq!(got, want);
}

#[rstest]
#[case::bad_time("2024-05-01T10:00:0Z|Xact|1\n", 1, 1, "bad timestamp")]
#[case::unknown_key("2024-05-01T10:00:00Z|Xact|1|bogus|2\n", 1, 29, "unknown key `bogus`")]
#[case::bad_number("2024-05-01T10:00:00Z|Xact|1|Zact|q\n", 1, 34, "bad value `q`")]
#[case::missing_value("2024-05-01T10:00:00Z|Xact\n", 1, 26, "without its 1 value")]
#[case::time_back("2024-05-01T10:00:01Z|Xact|1\n2024-05-01T10:00:00Z|Xact|2\n", 2, 1, "time goes back")]
#[case::bad_exec("2024-05-01T10:00:00Z|execution|RUNNING\n", 1, 32, "bad value")]
#[case::alarm_without_code("2024-05-01T10:00:00Z|system|FAULT|||| no such\n", 1, 35, "without a code")]
fn shdr_errors_name_line_and_column(
    #[case] text: &str,
    #[case] line: u64,
    #[case] col: u64,
    #[case] msg: &str,
) {
    let (_, res, _) = import(Some(Format::Shdr), text, None, false);
    let e = res.expect_err("an error");
    assert_eq!((e.line, e.col), (line, col), "{e}");
    assert!(e.message.contains(msg), "{e}");
}

#[test]
fn shdr_lenient_leaves_the_whole_line_out() {
    let text =
        "2024-05-01T10:00:00Z|Xact|1\n2024-05-01T10:00:01Z|Xact|2|Zact|q\n2024-05-01T10:00:02Z|Xact|3\n";
    let (evs, res, w) = import(Some(Format::Shdr), text, None, true);
    res.unwrap();
    assert_eq!(w.count(ErrorKind::BadRow), 1);
    let xs: Vec<i64> = evs
        .iter()
        .filter_map(|e| if let Event::Sample(s) = &e.event { Some(s.axes[0]) } else { None })
        .collect();
    assert_eq!(xs, vec![1_000_000, 3_000_000]);
}

#[test]
fn shdr_keys_from_a_map() {
    let m = ColumnMap::from_yaml("m.yaml", "axes: [{axis: Z, column: pos_z, scale: 0.001}]\nsignals: [{signal: SPPOSA, column: ax_pos_reached}]\nignore: [foo]\n").unwrap();
    let text = "2024-05-01T10:00:00Z|pos_z|-1500|ax_pos_reached|ON|foo|1\n";
    let (evs, res, _) = import(Some(Format::Shdr), text, Some(&m), false);
    res.unwrap();
    let Event::Sample(s) = &evs[0].event else { panic!() };
    assert_eq!(s.axes[2], -1_500_000);
    assert_eq!(evs[1].event, Event::Signal { signal: Signal::Spposa, value: true });
}

#[rstest]
#[case("{\"t_us\":0}", Format::Jsonl)]
#[case("\n  $date today $end", Format::Vcd)]
#[case("2024-05-01T10:00:00.5Z|Xact|1", Format::Shdr)]
#[case("* shdrVersion: 2\n", Format::Shdr)]
#[case("time,X\n0,1\n", Format::Csv)]
#[case("\u{feff}Time;X\n", Format::Csv)]
fn formats_are_detected(#[case] head: &str, #[case] want: Format) {
    assert_eq!(Format::detect(head.as_bytes()), want);
}

#[test]
fn far_lines_keep_their_location_without_a_snippet() {
    let e = ImportError::new(ErrorKind::BadRow, "big.csv", 5_000_000, 7, "bad")
        .expected("good")
        .with_line(b"1,2");
    let d: crate::diag::InputError = e.into();
    assert_eq!(d.headline(), "big.csv:5000000:7: bad; expected good");
    let e = ImportError::new(ErrorKind::BadRow, "small.csv", 3, 2, "bad").expected("good").with_line(b"1,x");
    let d: crate::diag::InputError = e.into();
    assert_eq!(d.headline(), "small.csv:3:2: bad; expected good");
    assert!(d.render_plain().contains("3 | 1,x"), "{}", d.render_plain());
}

#[test]
fn alarms_of_unknown_vendor_codes_import_with_their_code() {
    use nc_engine::alarm::AlarmKind;
    let shdr = "2024-05-01T10:00:00Z|system|FAULT|9999||| spindle amp\n2024-05-01T10:00:01Z|alarm|EX|0204|FAULT|ACTIVE|Z moved\n";
    let (evs, res, _) = import(Some(Format::Shdr), shdr, None, false);
    res.unwrap();
    let alarms: Vec<_> = evs
        .iter()
        .filter_map(|e| match &e.event {
            Event::Alarm(a) => Some(a.clone()),
            _ => None,
        })
        .collect();
    assert_eq!(alarms.len(), 2, "{evs:?}");
    assert_eq!(alarms[0].kind, AlarmKind::UnknownVendorAlarm);
    assert_eq!(super::vendor_code(&alarms[0]), Some("9999"));
    assert_eq!(alarms[0].detail, "9999: spindle amp");
    assert_eq!(alarms[1].kind, AlarmKind::IllegalAxisOperation);
    assert_eq!(super::vendor_code(&alarms[1]), None);
    let jsonl = JSONL.replace(
        r#""code":"0204","message":"ILLEGAL AXIS OPERATION: Z moved (line 7, column 3)""#,
        r#""code":"SV0401","message":"V READY OFF""#,
    );
    assert_ne!(jsonl, JSONL);
    let (evs, res, _) = import(Some(Format::Jsonl), &jsonl, None, false);
    let a = evs.iter().find_map(|e| match &e.event {
        Event::Alarm(a) => Some(a.clone()),
        _ => None,
    });
    let a = a.unwrap_or_else(|| panic!("{res:?} {evs:?}"));
    assert_eq!(super::vendor_code(&a), Some("SV0401"));
}

/// The JSON Lines fast path reads a written sample line exactly as the full parser does, and
/// leaves every other form to it.
#[test]
fn jsonl_fast_sample_path_agrees_with_the_full_parser() {
    let head = "{\"t_us\":0,\"kind\":\"meta\",\"dialect\":\"gsk-lathe\",\"axes\":[\"X\",\"Z\",\"C\"],\"diameter\":[\"X\"],\"period_us\":1000,\"sample_us\":1000,\"format\":\"nc-conform-trace/1\"}\n";
    let lines = [
        "{\"t_us\":1000,\"kind\":\"sample\",\"axes\":{\"X\":38.008412,\"Z\":-0.000001,\"C\":0},\"spindle\":{\"rpm\":-1200.5,\"angle_deg\":359.999}}",
        "{\"t_us\":2000,\"kind\":\"sample\",\"axes\":{\"Z\":1,\"X\":2,\"C\":3},\"spindle\":{\"rpm\":0,\"angle_deg\":0}}",
        "{\"t_us\":3000,\"kind\":\"sample\",\"axes\":{\"X\":-0,\"Z\":12345.5,\"C\":0},\"spindle\":{\"rpm\":1,\"angle_deg\":0.5}}\r",
    ];
    let text = format!(
        "{head}{}\n{{\"t_us\":3000,\"kind\":\"signal\",\"name\":\"STL\",\"value\":1}}\n",
        lines.join("\n")
    );
    let opts = Options { format: None, map: None, lenient: true };
    let events: Vec<_> = from_reader("t.jsonl", Box::new(std::io::Cursor::new(text.into_bytes())), &opts)
        .unwrap()
        .map(|e| e.unwrap())
        .collect();
    let samples: Vec<_> = events.iter().filter(|e| matches!(e.event, Event::Sample(_))).collect();
    assert_eq!(samples.len(), 3);
    let Event::Sample(s) = &samples[0].event else { unreachable!() };
    assert_eq!((s.axes[0], s.axes[2], s.spindle_mrpm, s.spindle_mdeg), (38_008_412, -1, -1_200_500, 359_999));
    let Event::Sample(s) = &samples[1].event else { unreachable!() };
    assert_eq!((s.axes[0], s.axes[2]), (2_000_000, 1_000_000), "another key order: the full parser");
    // Forms the fast path leaves to the full parser.
    let axes = [
        nc_engine::trace::AxisSpec { letter: 'X', index: 0, diameter: true, rotary: false },
        nc_engine::trace::AxisSpec { letter: 'Z', index: 2, diameter: false, rotary: false },
    ];
    for bad in [
        "{\"t_us\":01,\"kind\":\"sample\",\"axes\":{\"X\":1,\"Z\":1},\"spindle\":{\"rpm\":0,\"angle_deg\":0}}",
        "{\"t_us\":1,\"kind\":\"sample\",\"axes\":{\"X\":1e-6,\"Z\":1},\"spindle\":{\"rpm\":0,\"angle_deg\":0}}",
        "{\"t_us\":1,\"kind\":\"sample\",\"axes\":{\"X\":1,\"Z\":1},\"spindle\":{\"rpm\":0,\"angle_deg\":0}} ",
        "{\"t_us\":1,\"kind\":\"sample\",\"axes\":{\"X\":1.,\"Z\":1},\"spindle\":{\"rpm\":0,\"angle_deg\":0}}",
        "{\"t_us\":1,\"kind\":\"sample\",\"axes\":{\"X\":1},\"spindle\":{\"rpm\":0,\"angle_deg\":0}}",
    ] {
        assert_eq!(super::jsonl::fast_sample(bad.as_bytes(), &axes), None, "{bad}");
    }
}
