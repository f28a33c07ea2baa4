//! How a generated case becomes program text, per dialect and cycle: the words of the cycle
//! block from the case's raw choices, the edge word (at or beyond its range) and the alarm an
//! invalid one must raise.

use nc_engine::invariants::RangeAlarm;
use nc_engine::AlarmKind;

use super::case::{Cancel, Case, Cycle, Edge, Peck};

/// mm with up to four decimals, as a program word value (`12.5`, `-0.25`, `3`).
pub fn mm(nm: i64) -> String {
    let neg = nm < 0;
    let a = nm.unsigned_abs();
    let (int, frac) = (a / 1_000_000, a % 1_000_000);
    let mut s = if frac == 0 { format!("{int}.") } else { format!("{int}.{frac:06}") };
    while s.ends_with('0') {
        s.pop();
    }
    if neg {
        format!("-{s}")
    } else {
        s
    }
}

impl Case {
    /// The rigid tapping speed after the edge words.
    fn speed(&self) -> u32 {
        let max = if self.program.cycle.gsk() { 3000 } else { 4000 };
        match self.program.edge {
            Some(Edge::SpeedMax) => max,
            Some(Edge::SpeedBeyond) => max + 1,
            _ => self.program.speed_rpm(),
        }
    }

    /// The program text and, when an edge word is invalid, its alarm.
    pub fn program_text(&self) -> (String, Option<RangeAlarm>) {
        let mut b = Blocks::default();
        match self.program.cycle {
            Cycle::GskG84 | Cycle::GskG88 => self.gsk_program(&mut b),
            Cycle::FanucG84 => self.fanuc_program(&mut b),
            Cycle::KndG93 => self.knd_program(&mut b),
            Cycle::GskG923 => self.g923_program(&mut b),
            Cycle::LinuxcncG33_1 => self.linuxcnc_program(&mut b),
            Cycle::Heidenhain832 => self.heidenhain_program(&mut b),
        }
        (b.text, b.alarm)
    }

    fn gsk_program(&self, b: &mut Blocks) {
        let p = &self.program;
        let g88 = p.cycle == Cycle::GskG88;
        let (x0, z0) = (60_000_000i64, 5_000_000i64);
        b.line("G98;");
        if p.feed_move_before {
            b.line(&format!("G1 X{} Z{} F800;", mm(x0 + 10_000_000), mm(z0 + 5_000_000)));
        }
        b.line(&format!("G0 X{} Z{};", mm(x0), mm(z0)));
        let before = p.spindle_before_rpm();
        if before != 0 {
            b.line(&format!("{} S{};", if before > 0 { "M03" } else { "M04" }, before.abs()));
        }
        let s = self.speed();
        let speed_edge = matches!(p.edge, Some(Edge::SpeedBeyond));
        let m29 = format!("M29 S{s}");
        if !p.m29_in_block {
            b.line(&format!("{m29};"));
            if speed_edge {
                b.alarm(AlarmKind::WordOutOfRange);
            }
        }
        let mut w: Vec<String> = Vec::new();
        let depth = p.depth_nm();
        if g88 {
            w.push("G88 Z5. C0".into());
            w.push(format!("X{}", mm(x0 - 2 * depth)));
        } else {
            w.push("G84 X60. C0".into());
            w.push(format!("Z{}", mm(z0 - depth)));
        }
        let dwell = p.dwell_ms();
        match p.edge {
            Some(Edge::DwellMax) => w.push("P99999999".into()),
            Some(Edge::DwellBeyond) => w.push("P100000000".into()),
            Some(Edge::DwellNegative) => w.push("P-1".into()),
            _ if dwell > 0 => w.push(format!("P{dwell}")),
            _ => {}
        }
        let q = |nm: i64| {
            if self.params.q_in_mm {
                format!("Q{}", mm(nm))
            } else {
                format!("Q{}", nm / 100)
            }
        };
        match p.edge {
            Some(Edge::PeckMax) => {
                w.push(if self.params.q_in_mm { "Q9999.9999".into() } else { "Q99999999".into() })
            }
            Some(Edge::PeckBeyond) => {
                w.push(if self.params.q_in_mm { "Q10000".into() } else { "Q100000000".into() })
            }
            _ if p.peck != Peck::Standard => w.push(q(p.peck_nm())),
            _ => {}
        }
        match p.edge {
            Some(Edge::RetractMax) => w.push("R999.9999".into()),
            Some(Edge::RetractBeyond) => w.push("R1000.".into()),
            _ if p.peck == Peck::HighSpeed => w.push(format!("R{}", mm(p.retract_nm()))),
            _ => {}
        }
        let hand = if p.left_hand { -1 } else { 1 };
        match p.edge {
            Some(Edge::LeadMax) => w.push(format!("F{}", if p.left_hand { "-500." } else { "500." })),
            Some(Edge::LeadBeyond) => {
                w.push(format!("F{}", if p.left_hand { "-500.0001" } else { "500.0001" }))
            }
            Some(Edge::LeadZero) => w.push("F0".into()),
            _ => w.push(format!("F{}", mm(hand * p.lead_nm()))),
        }
        match p.edge {
            Some(Edge::JBeyond) => w.push("J2".into()),
            _ if p.peck == Peck::Deep => w.push("J1".into()),
            _ => {}
        }
        match p.edge {
            Some(Edge::RepeatMin) => w.push("K1".into()),
            Some(Edge::RepeatZero) => w.push("K0".into()),
            Some(Edge::RepeatBeyond) => w.push("K10000".into()),
            _ if p.repeats() > 1 => w.push(format!("K{}", p.repeats())),
            _ => {}
        }
        if p.clamp && !p.m29_in_block {
            w.push("M68".into());
        }
        match p.edge {
            Some(Edge::OverloadMax) => w.push("D150".into()),
            Some(Edge::OverloadBeyond) => w.push("D151".into()),
            _ => {
                if let Some(d) = p.overload {
                    w.push(format!("D{}", d % 151));
                }
            }
        }
        if p.m29_in_block {
            w.push(m29);
        }
        b.line(&format!("{};", w.join(" ")));
        let invalid = matches!(
            p.edge,
            Some(
                Edge::DwellBeyond
                    | Edge::DwellNegative
                    | Edge::RepeatZero
                    | Edge::RepeatBeyond
                    | Edge::RetractBeyond
                    | Edge::PeckBeyond
                    | Edge::OverloadBeyond
                    | Edge::JBeyond
                    | Edge::LeadBeyond
                    | Edge::LeadZero
            )
        ) || (speed_edge && p.m29_in_block);
        if invalid {
            b.alarm(AlarmKind::WordOutOfRange);
        }
        if p.second_hole {
            b.line("C90.;");
        }
        b.line(match p.cancel {
            Cancel::G80 => "G80;",
            Cancel::Rapid => "G0 X60. Z5.;",
            Cancel::Feed => "G1 X60. Z5. F500;",
            Cancel::ProgramEnd => "",
        });
        b.line("M30;");
    }

    /// The start of a KND or GSK threading program: G98, the optional G01, the start point X40
    /// Z5, the spindle before the cycle (turning at least at `min_rpm`; none when that is 0 and
    /// the case has none). Returns the signed speed commanded.
    fn lathe_start(&self, b: &mut Blocks, min_rpm: i64) -> i64 {
        b.line("G98;");
        if self.program.feed_move_before {
            b.line("G1 X50. Z10. F800;");
        }
        b.line("G0 X40. Z5.;");
        let before = self.program.spindle_before_rpm();
        let rpm = if before < 0 { before.min(-min_rpm) } else { before.max(min_rpm) };
        if rpm != 0 {
            b.line(&format!("{} S{};", if rpm > 0 { "M03" } else { "M04" }, rpm.abs()));
        }
        rpm
    }

    /// KND G93 (seed 001): the spindle turns before the cycle (else NC-1017, KND-G93-02); G93
    /// taps from Z5 to the depth; a second hole repeats the modal G93 with a new end point; a G00
    /// block leaves it. Edge words are not generated for this cycle.
    fn knd_program(&self, b: &mut Blocks) {
        let p = &self.program;
        let before = self.lathe_start(b, 0);
        let depth = p.depth_nm();
        b.line(&format!("G93 Z{} F{};", mm(5_000_000 - depth), mm(p.lead_nm())));
        if before == 0 {
            b.alarm(AlarmKind::SpindleNotTurning);
        }
        if p.second_hole {
            b.line(&format!("Z{};", mm(5_000_000 - depth / 2)));
        }
        b.line(match p.cancel {
            Cancel::G80 | Cancel::Rapid => "G0 Z10.;",
            Cancel::Feed => "G1 Z10. F500;",
            Cancel::ProgramEnd => "",
        });
        b.line("M30;");
    }

    /// GSK G92.3 (GSK-G923-*): a thread from Z5 down by the depth, tip and tool width a quarter
    /// of the lead each, 1..3 steps of Q, a lead change D with a deep or high-speed peck choice
    /// (negative for a left-hand choice when the lead stays positive), run-out with the clamp
    /// choice; the edges that apply to its words.
    fn g923_program(&self, b: &mut Blocks) {
        let p = &self.program;
        // The thread follows the spindle: it always turns (a stopped one is 0011 after the X
        // rapid, which is no range alarm).
        self.lathe_start(b, 300);
        let depth = p.depth_nm();
        let lead = p.lead_nm();
        let width = lead / 4;
        let widen = lead - 2 * width;
        let q = (widen / p.repeats() as i64 / 100 * 100).max(100);
        let mut w = vec![format!("G92.3 X36. Z{}", mm(5_000_000 - depth))];
        match p.edge {
            Some(Edge::LeadBeyond) => w.push("F500.0001".into()),
            Some(Edge::LeadZero) => w.push("F0".into()),
            _ => w.push(format!("F{}", mm(lead))),
        }
        if p.edge == Some(Edge::JBeyond) {
            w.push("J-1. K1.".into());
        } else if p.clamp {
            w.push("J0.5 K1.".into());
        }
        if p.edge == Some(Edge::OverloadBeyond) {
            w.push("D501.".into());
        } else if p.peck != Peck::Standard {
            let k = 1 + p.dwell_ms() as i64 / 250;
            // |D| below F²/(4·travel) keeps the lead above 0.7 F (GSK-G923-10).
            let shrink_ok = lead * lead / (4 * depth) >= k * 1000;
            let d = if p.left_hand && shrink_ok { -k * 1000 } else { k * 1000 };
            w.push(format!("D{}", mm(d)));
        }
        w.push(format!("E{} A{}", mm(width), mm(width)));
        match p.edge {
            Some(Edge::PeckBeyond) => w.push("Q-1.".into()),
            _ => w.push(format!("Q{}", mm(q))),
        }
        b.line(&format!("{};", w.join(" ")));
        match p.edge {
            Some(Edge::LeadBeyond | Edge::LeadZero) => b.alarm(AlarmKind::ThreadLeadOutOfRange),
            Some(Edge::JBeyond | Edge::PeckBeyond) => b.alarm(AlarmKind::WordOutOfRange),
            Some(Edge::OverloadBeyond) => b.alarm(AlarmKind::LeadChangeOutOfRange),
            _ => {}
        }
        if p.second_hole {
            b.line("X35.;");
        }
        b.line(match p.cancel {
            Cancel::G80 | Cancel::Rapid => "G0 X50.;",
            Cancel::Feed => "G1 X50. F500;",
            Cancel::ProgramEnd => "",
        });
        b.line("M30;");
    }

    /// `linuxcnc` G33.1 (LCNC-G331-01): one or two holes, the spindle turning either way or not
    /// at all ("Spindle not turning in G33.1", NC-1095).
    fn linuxcnc_program(&self, b: &mut Blocks) {
        let p = &self.program;
        b.line("G21 G90 G94 G17");
        if p.feed_move_before {
            b.line("G1 X5. Z10. F800");
        }
        b.line("G0 X0 Y0 Z5.");
        let before = p.spindle_before_rpm();
        if before != 0 {
            b.line(&format!("{} S{}", if before > 0 { "M3" } else { "M4" }, before.abs()));
        }
        let depth = p.depth_nm();
        b.line(&format!("G33.1 Z{} K{}", mm(5_000_000 - depth), mm(p.lead_nm())));
        if before == 0 {
            b.alarm(AlarmKind::LcncSpindle);
        }
        if p.second_hole {
            b.line("G0 X10.");
            b.line(&format!("G33.1 Z{} K{}", mm(5_000_000 - depth / 2), mm(p.lead_nm())));
        }
        b.line(match p.cancel {
            Cancel::G80 | Cancel::Rapid => "G0 Z10.",
            Cancel::Feed => "G1 Z10. F500",
            Cancel::ProgramEnd => "",
        });
        b.line("M2");
    }

    /// Heidenhain cycle 832 (seed 004) in Klartext: a longitudinal or face thread (Q461 from
    /// `per_revolution`), outside or inside (Q471 from `left_hand`), over the case's depth, lead
    /// and speed (the thread feed kept within 3000 mm/min so that 2 mm of approach and overrun
    /// suffice), constant chip section or depth (Q468 from the peck mode), 1..3 starts, 0..1 air
    /// cuts, a run-out or not. Some edge words put one parameter out of its range (NC-1070 at
    /// its line); without a spindle the call raises NC-1017.
    fn heidenhain_program(&self, b: &mut Blocks) {
        let p = &self.program;
        b.line("0 BEGIN PGM CASE MM");
        b.line("1 FUNCTION MODE TURN");
        let lead = p.lead_nm();
        let rpm = (p.speed_rpm() as i64).min(3_000 * 1_000_000 / lead).max(1);
        b.line(&format!("2 TOOL CALL 1 Z S{rpm}"));
        if p.feed_move_before {
            b.line("3 L X+50 Z+10 F800");
        }
        let before = p.spindle_before_rpm();
        let m = match before.signum() {
            1 => " M303",
            -1 => " M304",
            _ => "",
        };
        b.line(&format!("4 L X+40 Z+5 R0 FMAX{m}"));
        let depth = p.depth_nm();
        let face = p.per_revolution;
        let (x_end, z_end) = if face { (30_000_000 - 2 * depth, 0) } else { (30_000_000, -depth) };
        let angle = 7.5 * (1 + p.dwell % 4) as f64;
        let q: [(u16, String); 20] = [
            (471, (p.left_hand as u8).to_string()),
            (461, (face as u8).to_string()),
            (460, "1".into()),
            (472, mm(lead)),
            (473, "0".into()),
            (464, "0".into()),
            (491, "30".into()),
            (492, "0".into()),
            (493, mm(x_end)),
            (494, mm(z_end)),
            (469, "0".into()),
            (474, if p.m29_in_block { "0.5".into() } else { "0".into() }),
            (465, "2".into()),
            (466, "2".into()),
            (463, mm(50_000 + (p.peck_depth % 40) as i64 * 50_000)),
            (467, format!("{angle}")),
            (468, ((p.peck == Peck::Deep) as u8).to_string()),
            (470, (p.speed as u32 % 360).to_string()),
            (475, p.repeats().to_string()),
            (476, (p.clamp as u8).to_string()),
        ];
        let beyond = match p.edge {
            Some(Edge::DwellBeyond) => Some((476, "256")),
            Some(Edge::RepeatBeyond) => Some((475, "501")),
            Some(Edge::RepeatZero) => Some((475, "0")),
            Some(Edge::PeckBeyond) => Some((463, "0.0009")),
            Some(Edge::RetractBeyond) => Some((465, "0.099")),
            Some(Edge::LeadBeyond) => Some((472, "100000")),
            _ => None,
        };
        b.line("5 CYCL DEF 832 THREAD EXTENDED");
        for (n, v) in &q {
            match beyond {
                Some((bn, bv)) if bn == *n => {
                    b.line(&format!("  Q{n}={bv}"));
                    b.alarm(AlarmKind::QParamOutOfRange);
                }
                _ => b.line(&format!("  Q{n}={v}")),
            }
        }
        b.line("6 CYCL CALL");
        if before == 0 {
            b.alarm(AlarmKind::SpindleNotTurning);
        }
        b.line("7 L X+60 Z+20 FMAX M305");
        b.line("8 M30");
        b.line("9 END PGM CASE MM");
    }

    fn fanuc_program(&self, b: &mut Blocks) {
        let p = &self.program;
        let s = self.speed();
        b.line("G90 G17 G94");
        if p.feed_move_before {
            b.line("G1 X5. Y5. Z30. F800");
        }
        if p.per_revolution {
            b.line("G95");
        }
        b.line("G0 X0 Y0 Z20.");
        let before = p.spindle_before_rpm();
        if before != 0 {
            b.line(&format!("S{} {}", before.abs(), if before > 0 { "M03" } else { "M04" }));
        }
        if !p.m29_in_block {
            b.line(&format!("M29 S{s}"));
        }
        let mut w = vec![format!(
            "{} G84 X10. Y10. Z{} R3.",
            if p.return_initial { "G98" } else { "G99" },
            mm(-p.depth_nm())
        )];
        let dwell = p.dwell_ms();
        match p.edge {
            Some(Edge::DwellMax) => w.push("P99999999".into()),
            Some(Edge::DwellBeyond) => w.push("P100000000".into()),
            _ if dwell > 0 => w.push(format!("P{dwell}")),
            _ => {}
        }
        match p.edge {
            Some(Edge::PeckBeyond) => w.push("Q-1.".into()),
            _ if p.peck != Peck::Standard => w.push(format!("Q{}", mm(p.peck_nm()))),
            _ => {}
        }
        let lead = p.lead_nm();
        let f = if p.per_revolution { lead } else { lead * s as i64 };
        match p.edge {
            Some(Edge::LeadZero) => w.push("F0".into()),
            _ => w.push(format!("F{}", mm(f))),
        }
        match p.edge {
            Some(Edge::RepeatMin) => w.push("K1".into()),
            Some(Edge::RepeatBeyond) => w.push("K10000".into()),
            _ if p.repeats() > 1 => w.push(format!("K{}", p.repeats())),
            _ => {}
        }
        if p.m29_in_block {
            w.push(format!("M29 S{s}"));
        }
        b.line(&w.join(" "));
        match p.edge {
            Some(Edge::DwellBeyond | Edge::PeckBeyond | Edge::RepeatBeyond) => {
                b.alarm(AlarmKind::WordOutOfRange)
            }
            Some(Edge::LeadZero) => b.alarm(AlarmKind::FeedZero),
            Some(Edge::SpeedBeyond) => b.alarm(AlarmKind::IllegalSCode),
            _ => {}
        }
        if p.second_hole {
            b.line("X20. Y10.");
        }
        b.line(match p.cancel {
            Cancel::G80 => "G80",
            Cancel::Rapid => "G0 Z20.",
            Cancel::Feed => {
                if p.per_revolution {
                    "G1 Z20. F0.2"
                } else {
                    "G1 Z20. F500"
                }
            }
            Cancel::ProgramEnd => "",
        });
        b.line("M30");
    }
}

/// Program text being built: lines, and the alarm of the last invalid word with its line.
#[derive(Default)]
struct Blocks {
    text: String,
    lines: u32,
    alarm: Option<RangeAlarm>,
}

impl Blocks {
    fn line(&mut self, s: &str) {
        if s.is_empty() {
            return;
        }
        self.text.push_str(s);
        self.text.push('\n');
        self.lines += 1;
    }

    /// The block just written holds a word out of range.
    fn alarm(&mut self, kind: AlarmKind) {
        self.alarm.get_or_insert(RangeAlarm { kind, line: self.lines });
    }
}
