//! Canned cycles of `fanuc-mill` (group 09: G73, G74, G76, G81..G89, G84.2 / G84.3): the cycle
//! data kept from block to block, the holes a block makes, and rigid tapping mode.
//!
//! Per hole (Fanuc semantics, seed 003): positioning phase; rapid to the hole in the plane; rapid
//! to R on the tool axis; the body ([`crate::plan::drill`] or [`crate::plan::rigid_tap`], both end
//! at R); under G98 a rapid back to the initial level. In G91, R is the distance from the initial
//! level, the hole bottom the distance from R, and the plane words move each of the K holes by
//! the same amount (a row of holes); in G90, K repeats the same hole.
//!
//! Decisions where the Fanuc documents are silent (listed in `docs/`):
//! - K (Haas: L) counts only in its block (Fanuc: K is not retained); K0 stores the data and
//!   makes no hole;
//! - a block in cycle mode makes a hole when it has a plane axis word, the tool-axis word or R;
//!   other axis words alone (A B C) are a rapid move without hole; G04 / G28 / G30 / G53 in cycle
//!   mode do their own move and make no hole;
//! - a group-01 code cancels the cycle but keeps the retained data (only G80 clears it);
//! - a plane change in cycle mode (outside rigid tapping) takes the new tool axis's current
//!   position as the initial level;
//! - a hole needs R and the bottom (given in this block or retained): else NC-1002; G73 / G83
//!   need Q > 0 (NC-1002 when missing, NC-1001 when Q ≤ 0); Q < 0 is refused in every cycle;
//! - rigid tapping: Q0 is no peck; the lead in G94 is F / S rounded to 1 nm, a lead under 1 nm
//!   raises 0207; an F retained from earlier blocks counts (0201 only when no F is active);
//! - G84.2 / G84.3 (Fanuc 15 format) are always rigid: without M29 the interpreter emits the M29
//!   handshake itself, as with parameter 5200.0 = 1;
//! - switching between G84 and G74 keeps rigid tapping mode (both are tapping cycles);
//! - conventional tapping needs the spindle commanded in the cutting direction (M03 for G84, M04
//!   for G74) with S > 0, else NC-1017; Q is ignored there;
//! - G73 / G83 dwell P at the bottom when P is given (Haas); G73 retracts and G83 clearances are
//!   1 mm;
//! - the RGTAP check (0205) comes before each hole's tap, after positioning to R.

use super::{locate, CycleData, FanucInterp, Spindle};
use crate::alarm::{Alarm, AlarmKind};
use crate::dialect::common::{dwell_p, g_name, Words, MAX_COORD_NM};
use crate::parse::Word;
use crate::plan::drill::{drill, DrillCycle, DrillKind};
use crate::plan::rigid_tap::{rigid_tap, Peck, RigidTap};
use crate::plan::{Feed, Step};
use crate::trace::{Phase, AXIS_LETTERS};
use crate::units::{Nm, NM_PER_MM};

/// G73 retract and G83 clearance, nm.
const PECK_CLEARANCE_NM: Nm = NM_PER_MM;

/// Whether G×10 `code` is a canned cycle (G80 is not).
pub(super) fn is_cycle(code: u32) -> bool {
    matches!(code, 730 | 740 | 760 | 810 | 820 | 830 | 840 | 842 | 843 | 850 | 860 | 870 | 880 | 890)
}

/// Whether G×10 `code` is a tapping cycle.
pub(super) fn is_tap(code: u32) -> bool {
    matches!(code, 740 | 840 | 842 | 843)
}

/// Whether G×10 `code` is a drilling peck cycle (Q is the depth of cut and required).
fn is_peck(code: u32) -> bool {
    matches!(code, 730 | 830)
}

/// The body of a non-rigid cycle.
fn drill_kind(code: u32) -> DrillKind {
    match code {
        730 => DrillKind::HighSpeedPeck,
        740 => DrillKind::Tap { right_hand: false },
        760 => DrillKind::FineBore,
        820 => DrillKind::SpotFace,
        830 => DrillKind::DeepPeck,
        840 => DrillKind::Tap { right_hand: true },
        850 => DrillKind::Bore,
        860 => DrillKind::BoreStop,
        870 => DrillKind::BackBore,
        880 => DrillKind::BoreManual,
        890 => DrillKind::BoreDwell,
        _ => DrillKind::Drill,
    }
}

/// How a hole's body is cut.
enum Body {
    /// Rigid tapping at this lead, speed and peck.
    Rigid { lead_nm: i64, rpm: u32, peck: Peck },
    /// A drilling, boring or conventional tapping body at this feed.
    Drill { feed: Feed, q: Nm },
}

impl FanucInterp {
    /// A block in canned-cycle mode (`code` is the cycle that is active after the block; `gword`
    /// its G word when the block writes one).
    pub(super) fn cycle_block(
        &mut self,
        w: &Words,
        code: u32,
        gword: Option<Word>,
        out: &mut Vec<Step>,
    ) -> Result<(), Alarm> {
        let (a, b, n) = self.plane.axes();
        if self.cycle.is_none() {
            self.initial = self.pos[n];
        }
        self.cycle = Some(code);
        self.read_cycle_data(w, code, n)?;
        let repeats = match w.get('L') {
            Some(_) => w.int_in('L', 0, 9999, "repeat count L")?,
            None => w.int_in('K', 0, 9999, "repeat count K")?,
        };

        let tap = is_tap(code);
        if tap && self.rigid.is_none() && (self.set.g84_rigid || matches!(code, 842 | 843)) {
            let Some(rpm) = self.s.filter(|&s| s > 0) else {
                return Err(locate(
                    w,
                    gword,
                    AlarmKind::IllegalSCode,
                    format!("{}: rigid tapping needs a spindle speed S > 0", g_name(code)),
                ));
            };
            out.push(Step::RigidEnter { code: self.set.rigid_code, rpm });
            self.rigid = Some(rpm);
        }
        let rigid = if tap { self.rigid } else { None };
        if let Some(rpm) = rigid {
            if rpm > self.set.rigid_max_rpm {
                return Err(locate(
                    w,
                    gword.or(w.get('S')),
                    AlarmKind::IllegalSCode,
                    format!("S{rpm}: above the rigid tapping maximum {} rpm (5241)", self.set.rigid_max_rpm),
                ));
            }
        }

        let words = self.axis_words(w)?;
        let makes_hole = words[a].is_some() || words[b].is_some() || words[n].is_some() || w.has('R');
        if !makes_hole {
            if words.iter().any(Option::is_some) {
                let target = self.target(&words);
                out.push(Step::Rapid { target });
                self.pos = target;
            }
            return Ok(());
        }
        let repeats = repeats.unwrap_or(1);
        if repeats == 0 {
            return Ok(());
        }

        let at = gword;
        let missing = |what: &str| {
            locate(w, at, AlarmKind::WordMissing, format!("{}: {what} is not given", g_name(code)))
        };
        let r = match self.data.r {
            Some((v, true)) => self.initial.saturating_add(v),
            Some((v, false)) => v,
            None => return Err(missing("R (the R level)")),
        };
        let bottom = match self.data.z {
            Some((v, true)) => r.saturating_add(v),
            Some((v, false)) => v,
            None => return Err(missing(&format!("{} (the hole bottom)", AXIS_LETTERS[n]))),
        };
        let body = match rigid {
            Some(rpm) => self.rigid_body(w, at, rpm)?,
            None => {
                if tap {
                    let (want, m) =
                        if code == 840 { (Spindle::Forward, "M03") } else { (Spindle::Reverse, "M04") };
                    if self.set.tap_spindle_check && (self.spindle != want || self.s.unwrap_or(0) == 0) {
                        return Err(locate(
                            w,
                            at,
                            AlarmKind::SpindleNotTurning,
                            format!(
                                "{}: the spindle must turn ({m} with S > 0) before tapping",
                                g_name(code)
                            ),
                        ));
                    }
                }
                let q = match self.data.q {
                    // G73 / G83: the depth of cut must be > 0 (FAN-CYC-13, FAN-CYC-14).
                    Some(q) if q <= 0 && is_peck(code) => {
                        return Err(locate(
                            w,
                            w.get('Q').or(at),
                            AlarmKind::WordOutOfRange,
                            format!("{}: the depth of cut Q must be > 0", g_name(code)),
                        ))
                    }
                    Some(q) => q,
                    None if is_peck(code) => return Err(missing("Q (the depth of cut)")),
                    _ => 0,
                };
                Body::Drill { feed: self.feed(w, at, &g_name(code))?, q }
            }
        };

        for hole in 0..repeats {
            let mut p = self.pos;
            for (i, v) in words.iter().enumerate() {
                if let (Some(v), true) = (v, i != n) {
                    p[i] = if self.abs { *v } else { p[i].saturating_add(*v) };
                }
            }
            out.push(Step::Phase(Phase::Positioning));
            out.push(Step::Rapid { target: p });
            p[n] = r;
            out.push(Step::Rapid { target: p });
            match body {
                Body::Rigid { lead_nm, rpm, peck } => {
                    out.push(Step::RigidCheck { alarm: AlarmKind::RigidModeDiOff });
                    let c = RigidTap {
                        axis: n,
                        start: r,
                        bottom,
                        lead_nm,
                        rpm,
                        right_hand: matches!(code, 840 | 842),
                        dwell_us: self.data.p,
                        peck,
                        extraction_pct: self.set.extraction_pct,
                        overload: None,
                    };
                    rigid_tap(&c, out);
                }
                Body::Drill { feed, q } => {
                    let c = DrillCycle {
                        kind: drill_kind(code),
                        axis: n,
                        at_r: p,
                        bottom,
                        feed,
                        dwell_us: self.data.p,
                        q,
                        d: PECK_CLEARANCE_NM,
                        spindle_forward: self.spindle != Spindle::Reverse,
                    };
                    drill(&c, out);
                }
            }
            let tapping =
                matches!(body, Body::Rigid { .. }) || matches!(drill_kind(code), DrillKind::Tap { .. });
            if tapping && hole + 1 < repeats {
                // Single block stops where a held-over feed hold does: back at R after each
                // hole of a K repeat (FAN-CYC-09, FAN-RT-15).
                out.push(Step::SingleBlockStop);
            }
            if self.ret_initial && p[n] != self.initial {
                p[n] = self.initial;
                out.push(Step::Rapid { target: p });
            }
            self.pos = p;
        }
        out.push(Step::Phase(Phase::Idle));
        if rigid.is_some() {
            self.m29_pending = false;
        }
        Ok(())
    }

    /// Keeps R, the bottom, P and Q of a cycle block.
    fn read_cycle_data(&mut self, w: &Words, _code: u32, n: usize) -> Result<(), Alarm> {
        let inc = !self.abs;
        let mut d: CycleData = self.data;
        if let Some(r) = self.lu().coord(w, 'R')? {
            d.r = Some((r, inc));
        }
        if let Some(z) = self.units(n).coord(w, AXIS_LETTERS[n])? {
            d.z = Some((z, inc));
        }
        if let Some(p) = dwell_p(w, true)? {
            d.p = p;
        }
        if let Some(qw) = w.get('Q') {
            let q = self.lu().len(qw.value);
            if !(0..=MAX_COORD_NM).contains(&q) {
                return Err(w.alarm(
                    AlarmKind::WordOutOfRange,
                    &qw,
                    format!("Q{}: the depth of cut must be 0..99999.999 mm (0: no peck)", qw.value.display()),
                ));
            }
            d.q = Some(q);
        }
        self.data = d;
        Ok(())
    }

    /// Lead, speed and peck of a rigid tapping hole (alarms 0201, 0011, 0207).
    fn rigid_body(&self, w: &Words, at: Option<Word>, rpm: u32) -> Result<Body, Alarm> {
        let f = match self.feed_nm {
            None => {
                return Err(locate(
                    w,
                    at,
                    AlarmKind::FeedNotFoundRigid,
                    "rigid tapping needs F (the feed, mm/min in G94 or the lead in G95)".into(),
                ))
            }
            Some(0) => {
                return Err(locate(w, w.get('F').or(at), AlarmKind::FeedZero, "rigid tapping with F0".into()))
            }
            Some(f) => f,
        };
        let lead_nm = if self.per_rev { f } else { (f + i64::from(rpm) / 2) / i64::from(rpm) };
        if lead_nm < 1 {
            return Err(locate(
                w,
                w.get('F').or(at),
                AlarmKind::RigidDataMismatch,
                format!("the lead F / S = {f} nm/min / {rpm} rpm is below 1 nm"),
            ));
        }
        let peck = match self.data.q {
            Some(q) if q > 0 && self.set.pcp => Peck::Deep { q },
            Some(q) if q > 0 => Peck::HighSpeed { q, d: self.set.peck_return_nm },
            _ => Peck::None,
        };
        Ok(Body::Rigid { lead_nm, rpm, peck })
    }
}
