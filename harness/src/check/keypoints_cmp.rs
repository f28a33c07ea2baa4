//! Key points of the recorded trace against the reference's: number of pecks, each peck depth
//! and retract height, the hole bottom, the pause at the bottom of each cut (the dwell), the
//! return level, the number of spindle reversals.

use nc_engine::trace::Signal;

use super::compare::Comparator;
use super::keypoints::KeyPoints;
use super::tolerance::{mm_nm, ms_us, Topic};
use crate::scenario::timeline::{fixed, ms};

fn mm(nm: i64) -> String {
    format!("{} mm", fixed(nm, 6))
}

fn depth(d: Option<i64>) -> String {
    d.map_or("no sample".into(), mm)
}

/// Compares `rec` with the reference's key points, adding divergences to `c`.
pub fn compare(c: &mut Comparator, rec: &KeyPoints) {
    let Some(tap) = c.r.tap else { return };
    let refk = c.r.keys.clone();
    let tol = mm_nm(c.tol.keypoint_mm);
    let letter = c.r.axes().iter().find(|a| a.index == tap.slot).map_or('?', |a| a.letter);
    // Depths are along the direction into the hole; shown as positions.
    let pos = |d: Option<i64>| d.map(|d| d * tap.into_sign);
    let t0 = refk.segments.first().map_or(0, |s| s.t_start);
    let (rp, qp) = (refk.pecks(), rec.pecks());
    if rp.len() != qp.len() {
        let t = rp.get(qp.len().min(rp.len().saturating_sub(1))).map_or(t0, |p| p.0);
        c.diverge(
            Topic::Pecks,
            "CHK-KEY-01",
            "number of pecks".into(),
            t,
            format!("{} cuts", rp.len()),
            format!("{} cuts", qp.len()),
            format!("{}", (rp.len() as i64 - qp.len() as i64).abs()),
        );
    }
    let points = |c: &mut Comparator,
                  check: &'static str,
                  what: &str,
                  topic: Topic,
                  a: &[(i64, Option<i64>, i64)],
                  b: &[(i64, Option<i64>, i64)]| {
        for (k, (x, y)) in a.iter().zip(b).enumerate() {
            let (Some(dx), Some(dy)) = (x.1, y.1) else { continue };
            let tol = tol + x.2 + y.2;
            if (dx - dy).abs() > tol {
                c.diverge(
                    topic,
                    check,
                    format!("{what} #{}", k + 1),
                    x.0,
                    format!("{letter} = {} ± {}", depth(pos(x.1)), mm(tol)),
                    format!("{letter} = {}", depth(pos(y.1))),
                    mm((dx - dy).abs() - tol),
                );
            }
        }
    };
    points(c, "CHK-KEY-02", "peck depth", Topic::Pecks, &rp, &qp);
    points(c, "CHK-KEY-03", "retract height", Topic::Pecks, &refk.retracts(), &rec.retracts());
    // The return level and the reversals need F76.3 (else noted as not comparable).
    let rtap = c.carries_signal(Signal::Rtap);
    let returns = |k: &KeyPoints| if rtap { k.returns.clone() } else { Vec::new() };
    points(c, "CHK-KEY-05", "return level", Topic::Bottom, &returns(&refk), &returns(rec));
    if let (Some(a), Some(b)) = (refk.bottom(), rec.bottom()) {
        let unc = |k: &KeyPoints| k.pecks().iter().find(|p| p.1 == k.bottom()).map_or(0, |p| p.2);
        let tol = tol + unc(&refk) + unc(rec);
        if (a - b).abs() > tol {
            let t = rp.iter().find(|p| p.1 == Some(a)).map_or(t0, |p| p.0);
            c.diverge(
                Topic::Bottom,
                "CHK-KEY-04",
                "hole bottom".into(),
                t,
                format!("{letter} = {} ± {}", mm(a * tap.into_sign), mm(tol)),
                format!("{letter} = {}", mm(b * tap.into_sign)),
                mm((a - b).abs() - tol),
            );
        }
    }
    let dtol = ms_us(c.tol.dwell_ms);
    for (k, (x, y)) in refk.pauses().iter().zip(rec.pauses()).enumerate() {
        if (x.1 - y.1).abs() > dtol {
            c.diverge(
                Topic::Dwell,
                "CHK-KEY-06",
                format!("pause at the bottom of cut #{} (dwell and reversal)", k + 1),
                x.0,
                format!("{} ± {}", ms(x.1.max(0) as u64), ms(dtol as u64)),
                ms(y.1.max(0) as u64),
                ms(((x.1 - y.1).abs() - dtol) as u64),
            );
        }
    }
    if !rtap {
        return;
    }
    if refk.returns.len() != rec.returns.len() {
        let t = refk.returns.last().map_or(t0, |r| r.0);
        c.diverge(
            Topic::Bottom,
            "CHK-KEY-05",
            "number of returns (F76.3 falls)".into(),
            t,
            format!("{}", refk.returns.len()),
            format!("{}", rec.returns.len()),
            format!("{}", (refk.returns.len() as i64 - rec.returns.len() as i64).abs()),
        );
    }
    if refk.reversals != rec.reversals {
        c.diverge(
            Topic::Reversals,
            "CHK-KEY-07",
            "spindle reversals in rigid tapping".into(),
            t0,
            format!("{}", refk.reversals),
            format!("{}", rec.reversals),
            format!("{}", (refk.reversals as i64 - rec.reversals as i64).abs()),
        );
    }
}
