//! Cycle 832 THREAD EXTENDED (seed 004): the range of every parameter (checked when the
//! `CYCL DEF` block runs) and the thread the parameters describe (worked out when `CYCL CALL`
//! runs, with the seed's cautions as checks). Rules HDH-C832-* in `docs/rules/heidenhain.md`.

use crate::alarm::{Alarm, AlarmKind};
use crate::parse::klartext::{KValue, QParam, Q832};
use crate::plan::thread_832::ThreadCycle;
use crate::plan::Pos;
use crate::units::{Nm, NM_PER_MM};

const X: usize = 0;
const Z: usize = 2;

/// The input range of each parameter (seed 004 "输入"): number, lowest, highest (in millionths),
/// whole numbers only.
const RANGES: [(u16, i64, i64, bool); 20] = [
    (471, 0, 1_000_000, true),
    (461, 0, 1_000_000, true),
    (460, 0, 999_999_000, false),
    (472, 0, 99_999_999_000, false),
    (473, 0, 999_999_000, false),
    (464, 0, 4_000_000, true),
    (491, -99_999_999_000, 99_999_999_000, false),
    (492, -99_999_999_000, 99_999_999_000, false),
    (493, -99_999_999_000, 99_999_999_000, false),
    (494, -99_999_999_000, 99_999_999_000, false),
    (469, -180_000_000, 180_000_000, false),
    (474, 0, 999_999_000, false),
    (465, 100_000, 99_900_000, false),
    (466, 100_000, 99_900_000, false),
    (463, 1_000, 999_999_000, false),
    (467, 0, 60_000_000, false),
    (468, 0, 1_000_000, true),
    (470, 0, 359_999_000_000, false),
    (475, 1_000_000, 500_000_000, true),
    (476, 0, 255_000_000, true),
];

/// Standard thread depth per unit of pitch (ISO 68-1 / DIN 13: h3 = 0.61343 P outside,
/// H1 = 0.54127 P inside), used when Q473 = 0 (HDH-C832-06).
pub const STANDARD_DEPTH: [f64; 2] = [0.61343, 0.54127];

/// A checked cycle 832 definition: the values in the order of [`Q832`].
#[derive(Debug, Clone, PartialEq)]
pub struct Def832 {
    values: Vec<KValue>,
}

fn micro(v: KValue) -> i64 {
    v.value.scaled(1_000_000)
}

fn show(m: i64) -> String {
    crate::units::fixed_string(m, 6).trim_end_matches('0').trim_end_matches('.').to_string()
}

impl Def832 {
    /// Checks every parameter against its range (HDH-C832-01): NC-1070 at the first one out of it.
    pub fn new(params: &[QParam]) -> Result<Def832, Alarm> {
        let mut values = Vec::with_capacity(Q832.len());
        for (q, lo, hi, whole) in RANGES {
            let Some(p) = params.iter().find(|p| p.number == q) else {
                // The parser guarantees each parameter once; keep the engine total anyway.
                return Err(Alarm::new(AlarmKind::WordMissing, format!("cycle 832 lacks Q{q}")));
            };
            let m = micro(p.v);
            if m < lo || m > hi || (whole && !p.v.value.is_integral()) {
                let kind = if whole { "a whole number " } else { "" };
                return Err(Alarm::new(
                    AlarmKind::QParamOutOfRange,
                    format!("Q{q}={}: must be {kind}{}..{}", p.v.value.display(), show(lo), show(hi)),
                )
                .at(p.v.line, Some(p.v.col)));
            }
            values.push(p.v);
        }
        Ok(Def832 { values })
    }

    fn v(&self, q: u16) -> KValue {
        let i = Q832.iter().position(|&n| n == q).unwrap_or(0);
        self.values[i]
    }

    fn nm(&self, q: u16) -> Nm {
        self.v(q).value.scaled(NM_PER_MM)
    }

    fn int(&self, q: u16) -> i64 {
        self.v(q).value.as_int().unwrap_or(0)
    }

    fn deg(&self, q: u16) -> f64 {
        self.v(q).value.to_f64()
    }

    fn alarm(&self, kind: AlarmKind, q: u16, detail: String) -> Alarm {
        let v = self.v(q);
        Alarm::new(kind, detail).at(v.line, Some(v.col))
    }
}

/// What the machine brings to the call.
#[derive(Debug, Clone, Copy)]
pub struct CallContext {
    /// Where the tool stands (X as radius).
    pub pos: Pos,
    /// The flank angle, degrees.
    pub flank_deg: f64,
    /// A negative-diameter pre-position is an alarm (else the cycle runs with Q471 reversed).
    pub neg_diameter_alarm: bool,
}

/// The contour start and end [(radius, Z); 2] from the taper dimension type Q464 (HDH-C832-03).
fn contour(d: &Def832) -> Result<[(Nm, Nm); 2], Alarm> {
    let (mut rs, mut zs) = (d.nm(491) / 2, d.nm(492));
    let (mut re, mut ze) = (d.nm(493) / 2, d.nm(494));
    let t = libm::tan(d.deg(469).to_radians());
    let undefined = |q: u16, why: &str| d.alarm(AlarmKind::ThreadContourUndefined, q, why.to_string());
    let need_tan = |t: f64| -> Result<f64, Alarm> {
        if t.abs() < 1e-9 || !t.is_finite() {
            Err(undefined(469, "Q469: a taper angle of 0 (or 180) fixes no Z coordinate"))
        } else {
            Ok(t)
        }
    };
    // tan(Q469) = (radius at the end − radius at the start) / (Z start − Z end).
    match d.int(464) {
        1 => zs = ze + ((re - rs) as f64 / need_tan(t)?).round() as Nm,
        2 => rs = re - ((zs - ze) as f64 * t).round() as Nm,
        3 => ze = zs - ((re - rs) as f64 / need_tan(t)?).round() as Nm,
        4 => re = rs + ((zs - ze) as f64 * t).round() as Nm,
        _ => {}
    }
    let limit = 99_999_999_000_000 / 1000;
    if [rs * 2, zs, re * 2, ze].iter().any(|v| v.abs() > limit) || !t.is_finite() {
        return Err(undefined(469, "the taper angle puts a contour point beyond ±99999.999 mm"));
    }
    Ok([(rs, zs), (re, ze)])
}

/// The thread of a `CYCL CALL`, after the seed's cautions (HDH-C832-12, HDH-C832-13).
pub fn thread(d: &Def832, ctx: &CallContext) -> Result<ThreadCycle, Alarm> {
    let inside = d.int(471) == 1;
    let face = d.int(461) == 1;
    let infeed_deg = d.deg(467);
    if infeed_deg > ctx.flank_deg {
        return Err(d.alarm(
            AlarmKind::InfeedAboveFlank,
            467,
            format!(
                "Q467={infeed_deg}: the infeed angle is above the flank angle {}° (hei.flank_angle_deg)",
                ctx.flank_deg
            ),
        ));
    }
    if ctx.pos[X] < 0 && ctx.neg_diameter_alarm {
        return Err(Alarm::new(
            AlarmKind::NegativeDiameterPreposition,
            format!(
                "the tool stands at X{} (a negative diameter): Q471 would act reversed",
                crate::units::nm_to_mm_string(ctx.pos[X] * 2)
            ),
        ));
    }
    let constant_chip = d.int(468) == 0;
    if constant_chip && infeed_deg == 0.0 {
        return Err(d.alarm(
            AlarmKind::ChipSectionNeedsAngle,
            467,
            "Q468=0 (constant chip section) needs an infeed angle Q467 > 0".into(),
        ));
    }
    let lead = d.nm(472);
    if lead <= 0 {
        return Err(d.alarm(AlarmKind::FeedZero, 472, "Q472=0: a thread needs a pitch".into()));
    }
    let [(rs, zs), (re, ze)] = contour(d)?;
    let (from, to, along, across) =
        if face { ((rs, zs), (re, ze), X, Z) } else { ((zs, rs), (ze, re), Z, X) };
    if from.0 == to.0 {
        return Err(d.alarm(
            AlarmKind::ThreadContourUndefined,
            464,
            "the thread has no length along its pitch direction".into(),
        ));
    }
    let depth = match d.nm(473) {
        0 => (lead as f64 * STANDARD_DEPTH[usize::from(inside)]).round() as Nm,
        h => h,
    };
    let max_cut = d.nm(463).max(1);
    let ratio = depth as f64 / max_cut as f64;
    let passes = if constant_chip { (ratio * ratio - 1e-9).ceil() } else { (ratio - 1e-9).ceil() };
    Ok(ThreadCycle {
        along,
        across,
        start: ctx.pos,
        from,
        to,
        outward: if inside { -1 } else { 1 },
        clearance: d.nm(460),
        depth,
        passes: passes.clamp(1.0, 1e15) as u64,
        constant_chip,
        infeed_tan: libm::tan(infeed_deg.to_radians()),
        run_out: d.nm(474),
        approach: d.nm(465),
        overrun: d.nm(466),
        lead_nm: lead,
        angle_mdeg: (d.v(470).value.scaled(1000)).rem_euclid(360_000),
        starts: d.int(475).max(1) as u64,
        air_cuts: d.int(476).max(0) as u64,
    })
}
