//! LinuxCNC canned cycles G73, G74, G81..G89 in the three planes (rules LCNC-CYC-*, LCNC-TAP-*):
//! the words and their memory (sticky R, bottom, P, Q, I/J/K), L repeats, G90/G91, the initial
//! level, the climb to R, G98 (back to the higher of the initial level and R) / G99 (to R), and
//! each cycle's body as `interp_cycles.cc` emits it. G73/G83 pecks reuse [`crate::plan::drill`].

use super::machine::{alarm, secs, Eb, FeedMode, Machine};
use crate::alarm::{Alarm, AlarmKind};
use crate::plan::drill::{drill, spindle_m, DrillCycle, DrillKind};
use crate::plan::{Plane, Pos, Step};
use crate::trace::Phase;
use crate::units::Nm;

/// G83/G73 clearance: 0.010 inch (LinuxCNC `G83_RAPID_DELTA`).
const RAPID_DELTA_INCH: f64 = 0.010;

/// Whether a motion code (× 10) is a canned cycle.
pub fn is_cycle(g: u32) -> bool {
    matches!(g, 730 | 740 | 810..=890)
}

/// The plane's axes: (first, second, normal), as slots and letters.
fn letters(plane: Plane) -> [char; 3] {
    let (a, b, c) = plane.axes();
    let l = ['X', 'Y', 'Z'];
    [l[a], l[b], l[c]]
}

fn plane_texts(plane: Plane) -> (&'static str, &'static str) {
    match plane {
        Plane::Xy => ("R less than z in cycle in xy plane", "Z value unspecified in xy plane canned cycle"),
        Plane::Zx => ("R less than y in cycle in xz plane", "Y value unspecified in xz plane canned cycle"),
        Plane::Yz => ("R less than x in cycle in yz plane", "X value unspecified in yz plane canned cycle"),
    }
}

/// One canned cycle line.
pub fn canned(m: &mut Machine, g: u32, b: &Eb, out: &mut Vec<Step>) -> Result<(), Alarm> {
    let line = b.line;
    let err = |kind, text: &str, col| alarm(kind, text, line, col);
    if m.feed == 0.0 {
        return Err(err(AlarmKind::LcncFeedZero, "Cannot feed with zero feed rate", None));
    }
    if m.feed_mode == FeedMode::InverseTime {
        return Err(err(AlarmKind::LcncInterpreter, "Cannot use inverse time feed with canned cycles", None));
    }
    if m.comp {
        return Err(err(
            AlarmKind::LcncInterpreter,
            "Cannot use canned cycles with cutter compensation on",
            None,
        ));
    }
    let same = m.motion == Some(g);
    let r_word = match b.get('R') {
        Some(r) => r,
        None if same => m.cyc.r,
        None => return Err(err(AlarmKind::LcncRUnspecified, "R clearance plane unspecified in cycle", None)),
    };
    if g == 740 && b.get('L').is_some() {
        // LinuxCNC counts G74 out of the cycles that take L (interp_check.cc, G81..G89 and G73).
        return Err(err(
            AlarmKind::LcncInterpreter,
            "L word with no G10, cutter compensation, canned cycle, digital/analog input, M98 or NURBS code",
            b.col('L'),
        ));
    }
    let repeats = match b.get('L') {
        Some(l) if l < 0.0 => {
            return Err(err(AlarmKind::LcncInterpreter, "Negative l word used", b.col('L')))
        }
        Some(l) if l.round() == 0.0 => {
            return Err(err(AlarmKind::LcncZeroRepeats, "Cannot do zero repeats of cycle", b.col('L')))
        }
        Some(l) => l.round().min(100_000.0) as u32,
        None => 1,
    };
    let (ia, ib, ic) = m.plane.axes();
    let [la, lb, lc] = letters(m.plane);
    let (r_below, bottom_missing) = plane_texts(m.plane);
    if !same && b.get(lc).is_none() {
        return Err(err(AlarmKind::LcncWordMissing, bottom_missing, None));
    }
    let cc_word = b.get(lc).unwrap_or(m.cyc.cc);
    let current_cc = m.work(ic);
    let mut old_cc = *m.cyc.il.get_or_insert(current_cc);
    let (mut aa, mut bb, r, bottom, inc) = if m.absolute {
        let aa = b.get(la).map(|v| m.len(v, ia, b, la)).transpose()?.unwrap_or(m.work(ia));
        let bb = b.get(lb).map(|v| m.len(v, ib, b, lb)).transpose()?.unwrap_or(m.work(ib));
        (aa, bb, m.len(r_word, ic, b, 'R')?, m.len(cc_word, ic, b, lc)?, [0, 0])
    } else {
        let ai = b.get(la).map(|v| m.len(v, ia, b, la)).transpose()?.unwrap_or(0);
        let bi = b.get(lb).map(|v| m.len(v, ib, b, lb)).transpose()?.unwrap_or(0);
        let r = m.len(r_word, ic, b, 'R')?.saturating_add(old_cc);
        (m.work(ia), m.work(ib), r, r.saturating_add(m.len(cc_word, ic, b, lc)?), [ai, bi])
    };
    if r < bottom {
        return Err(err(AlarmKind::LcncRBelowBottom, r_below, None));
    }
    let body = Body::of(m, g, b, same)?;
    let at = |m: &Machine, a: Nm, bv: Nm, c: Nm| -> Pos {
        let mut w = [m.work(0), m.work(1), m.work(2)];
        w[ia] = a;
        w[ib] = bv;
        w[ic] = c;
        m.machine(w)
    };
    out.push(Step::Phase(Phase::Positioning));
    let mut current_cc = current_cc;
    if old_cc < r {
        let t = at(m, m.work(ia), m.work(ib), r);
        m.rapid(t, out);
        old_cc = r;
        current_cc = r;
    }
    let clear = if m.old_z { old_cc } else { r };
    // rs274 runs the cycle's moves in G61 (interp_cycles.cc convert_cycle: after the rapid up to
    // R, SET_MOTION_CONTROL_MODE(CANON_EXACT_PATH), the mode in force restored at its end).
    m.path_mode(false, out);
    for n in 0..repeats {
        aa = aa.saturating_add(inc[0]);
        bb = bb.saturating_add(inc[1]);
        out.push(Step::Phase(Phase::Positioning));
        // LCNC-CYC-03: the first hole is reached at the present level when above R; every
        // other positioning move runs at the clearance level (CYCLE_MACRO).
        let level = if n == 0 && current_cc > r { current_cc } else { clear };
        let t = at(m, aa, bb, level);
        m.rapid(t, out);
        if level > r {
            let t = at(m, aa, bb, r);
            m.rapid(t, out);
        }
        body.emit(m, ic, at(m, aa, bb, r), bottom, clear, out);
    }
    // Restored with canon's tolerance (GET_EXTERNAL_MOTION_CONTROL_TOLERANCE): 0.001 inch until
    // a G64 gives one, though the planner had none before (L-124, DEC-164).
    if m.continuous {
        m.tolerance = m.canon_tolerance;
    }
    m.path_mode(m.continuous, out);
    out.push(Step::Phase(Phase::Idle));
    m.cyc.cc = cc_word;
    m.cyc.r = r_word;
    Ok(())
}

/// LinuxCNC's G84/G74 feed point in the XZ or YZ plane at `w` (work nm) on the tool axis, for the
/// hole at `at_r` (machine nm): `convert_cycle_g74_g84` passes `cycle_feed` its arguments out of
/// order, so in G18 X takes the tool axis' value, Y the hole's Z and Z the hole's X; in G19 X the
/// hole's Z, Y the tool axis' value and Z the hole's Y (DEC-166; the rs274 oracle's
/// `g18-g99-g84`, `g19-g98-g84`; `testdata/linuxcnc` g84_g18 in real motion).
fn permuted(m: &Machine, plane: Plane, at_r: Pos, w: Nm) -> Pos {
    let hole = |a: usize| at_r[a].saturating_sub(m.off[a]);
    let work = match plane {
        Plane::Zx => [w, hole(2), hole(0)],
        Plane::Yz => [hole(2), w, hole(1)],
        Plane::Xy => [hole(0), hole(1), w],
    };
    let mut p = at_r;
    for (a, v) in work.into_iter().enumerate() {
        p[a] = v.saturating_add(m.off[a]);
    }
    p
}

/// What one hole does, with the words it needs checked.
struct Body {
    g: u32,
    dwell_us: u64,
    q: Nm,
    delta: Nm,
    /// G87: offset in the plane and the top of the back bore (work nm on the tool axis).
    g87: Option<([Nm; 2], Nm)>,
    /// Spindle direction before the cycle: 1 M3, -1 M4.
    dir: i8,
}

impl Body {
    fn of(m: &mut Machine, g: u32, b: &Eb, same: bool) -> Result<Body, Alarm> {
        let line = b.line;
        let err = |kind, text: String| alarm(kind, text, line, None);
        let p = b.get('P');
        let needs_p = matches!(g, 820 | 860 | 880 | 890);
        if needs_p && !same && p.is_none() {
            return Err(err(
                AlarmKind::LcncWordMissing,
                format!("Dwell time p word missing with g{}", g / 10),
            ));
        }
        let dwell = p.unwrap_or(m.cyc.p);
        if needs_p || matches!(g, 740 | 840) {
            m.cyc.p = dwell;
        }
        let mut q = 0;
        if matches!(g, 730 | 830) {
            let qv = match b.get('Q') {
                Some(q) => q,
                None if same => m.cyc.q,
                None => {
                    return Err(err(AlarmKind::LcncWordMissing, format!("Q word missing with g{}", g / 10)))
                }
            };
            if qv <= 0.0 {
                return Err(err(AlarmKind::LcncInterpreter, "Negative or zero q value used".into()));
            }
            m.cyc.q = qv;
            q = m.len(qv, 2, b, 'Q')?;
        }
        let dir = m.spindle;
        let stopped = dir == 0 || m.s <= 0.0;
        match g {
            840 | 740 => {
                let name = if g == 840 { "G84" } else { "G74" };
                if stopped {
                    return Err(err(AlarmKind::LcncSpindle, format!("Spindle not turning in {name}")));
                }
                if g == 740 && dir > 0 {
                    return Err(err(AlarmKind::LcncSpindle, "Spindle turning clockwise in G74".into()));
                }
                if g == 840 && dir < 0 {
                    return Err(err(
                        AlarmKind::LcncSpindle,
                        "Spindle turning counterclockwise in G84".into(),
                    ));
                }
            }
            860 | 870 | 880 if stopped => {
                return Err(err(AlarmKind::LcncSpindle, format!("Spindle not turning in g{}", g / 10)));
            }
            _ => {}
        }
        let mut g87 = None;
        if g == 870 {
            let mut ijk = m.cyc.ijk;
            for (n, l) in ['I', 'J', 'K'].into_iter().enumerate() {
                match b.get(l) {
                    Some(v) => ijk[n] = v,
                    None if !same => {
                        return Err(err(AlarmKind::LcncWordMissing, format!("{l} word missing with g87")))
                    }
                    None => {}
                }
            }
            m.cyc.ijk = ijk;
            // The offset is given by the plane's own letters (I J in G17, K I in G18, J K in G19).
            let (ia, ib, ic) = m.plane.axes();
            let by_axis = |a: usize| ijk[a];
            let off = [m.len(by_axis(ia), ia, b, 'I')?, m.len(by_axis(ib), ib, b, 'J')?];
            let top = m.len(by_axis(ic), ic, b, 'K')?;
            g87 = Some((off, top));
        }
        let unit_inch = if m.inch { 1.0 } else { 25.4 };
        let delta = m.len(RAPID_DELTA_INCH * unit_inch, 2, b, 'Q')?;
        Ok(Body {
            g,
            dwell_us: if needs_p || matches!(g, 740 | 840) { secs(dwell) } else { 0 },
            q,
            delta,
            g87,
            dir,
        })
    }

    /// Appends the hole at `at_r` (over the hole at R) down to `bottom` and back to `clear`.
    fn emit(&self, m: &mut Machine, ic: usize, at_r: Pos, bottom: Nm, clear: Nm, out: &mut Vec<Step>) {
        let off = m.off[ic];
        let level = |p: Pos, w: Nm| {
            let mut p = p;
            p[ic] = w.saturating_add(off);
            p
        };
        let dwell = |out: &mut Vec<Step>| {
            if self.dwell_us > 0 {
                out.push(Step::Phase(Phase::Dwell));
                out.push(Step::Dwell { us: self.dwell_us });
            }
        };
        let fwd = if self.dir >= 0 { 3 } else { 4 };
        out.push(Step::Phase(Phase::Cutting));
        match self.g {
            730 | 830 => {
                let kind = if self.g == 830 { DrillKind::DeepPeck } else { DrillKind::HighSpeedPeck };
                let cycle = DrillCycle {
                    kind,
                    axis: ic,
                    at_r,
                    bottom: bottom.saturating_add(off),
                    feed: m.feed_rate(),
                    dwell_us: 0,
                    q: self.q,
                    d: self.delta,
                    spindle_forward: self.dir >= 0,
                };
                drill(&cycle, out);
                // The builder ends at R; LinuxCNC rapids from the bottom straight to the
                // clearance level (convert_cycle_g73 / g83).
                if matches!(out.last(), Some(Step::Rapid { target }) if *target == at_r) {
                    out.pop();
                }
                // From the bottom, where the builder's steps left the tool (under G99 the
                // clearance level is R itself: not a move of no length).
                let up = level(at_r, clear);
                out.push(Step::Rapid { target: up });
                m.pos = up;
            }
            740 | 840 => {
                // LCNC-TAP-01: overrides off, feed in, reverse, dwell, feed out to the clearance.
                let (cut, back) = if self.g == 840 { (3, 4) } else { (4, 3) };
                // In G18 and G19 LinuxCNC feeds to its permuted point (DEC-166) unless the
                // manual's tool axis is asked for (DEC-84).
                let point = |m: &Machine, w: Nm| match m.plane {
                    Plane::Xy => level(at_r, w),
                    _ if !m.cfg.tap_permuted => level(at_r, w),
                    plane => permuted(m, plane, at_r, w),
                };
                out.push(Step::OverrideLock(true));
                m.feed_to(point(m, bottom), out);
                out.push(spindle_m(5));
                out.push(spindle_m(back));
                dwell(out);
                out.push(Step::Phase(Phase::Retract));
                m.feed_to(point(m, clear), out);
                out.push(spindle_m(5));
                out.push(spindle_m(cut));
                out.push(Step::OverrideLock(false));
                // The interpreter takes the tool to be over the hole at the clearance level, as
                // LinuxCNC's does (its next move starts from there in rs274, from the permuted
                // point on the machine).
                let over = level(at_r, clear);
                m.astray = m.pos != over;
                m.pos = over;
            }
            870 => {
                let Some((o, top)) = self.g87 else { return };
                let (ia, ib, _) = m.plane.axes();
                let mut shifted = at_r;
                shifted[ia] = shifted[ia].saturating_add(o[0]);
                shifted[ib] = shifted[ib].saturating_add(o[1]);
                m.rapid(shifted, out);
                out.push(spindle_m(5));
                out.push(spindle_m(19));
                m.rapid(level(shifted, bottom), out);
                m.rapid(level(at_r, bottom), out);
                out.push(spindle_m(fwd));
                m.feed_to(level(at_r, top), out);
                m.feed_to(level(at_r, bottom), out);
                out.push(spindle_m(5));
                out.push(spindle_m(19));
                out.push(Step::Phase(Phase::Retract));
                m.rapid(level(shifted, bottom), out);
                m.rapid(level(shifted, clear), out);
                m.rapid(level(at_r, clear), out);
                out.push(spindle_m(fwd));
            }
            _ => {
                m.feed_to(level(at_r, bottom), out);
                match self.g {
                    820 | 860 | 880 | 890 => dwell(out),
                    _ => {}
                }
                out.push(Step::Phase(Phase::Retract));
                match self.g {
                    850 => {
                        m.feed_to(at_r, out);
                        m.rapid(level(at_r, clear), out);
                    }
                    860 => {
                        out.push(spindle_m(5));
                        m.rapid(level(at_r, clear), out);
                        out.push(spindle_m(fwd));
                    }
                    880 => {
                        // LCNC-CYC-06: spindle stop and program stop, the spindle again after
                        // cycle start; the retract is the operator's (a jog, not modelled): no
                        // move. The interpreter takes the tool to be at the clearance level as
                        // LinuxCNC's does (rs274: the next move starts from there), while it
                        // stands at the bottom, where the next move really starts (DEC-151).
                        out.push(spindle_m(5));
                        out.push(Step::Stop { optional: false });
                        m.pos = level(at_r, clear);
                        m.astray = true;
                        out.push(spindle_m(fwd));
                    }
                    890 => m.feed_to(level(at_r, clear), out),
                    _ => m.rapid(level(at_r, clear), out),
                }
            }
        }
    }
}
