//! LinuxCNC 2.9's blend arc between two G64 rapids (DEC-164): the geometry and speed its planner
//! gives the arc that joins two straight moves (tp.c `tpCreateLineLineBlend` with blendmath.c
//! `blendInit3FromLineLine`, `blendParamKinematics`, `blendComputeParameters`,
//! `blendFindPoints3`), computed here from those rules, not copied:
//!
//! - the half angle θ between the moves (half of π minus the turn); none for a reversal, a
//!   straight continuation, or a kink small enough for the planner's tangent join;
//! - the tolerance: with G64 without P, a quarter of the shorter move's nominal length
//!   (tc.c `tcFindBlendTolerance`); the arc may take at most half of either move;
//! - the acceleration `a` the plane of the two moves allows (the largest circle inscribed in the
//!   axes' acceleration box cut by that plane), of which √¾ may be normal (centripetal);
//! - the speed: the lower of the normal acceleration's limit on the largest radius and the moves'
//!   own (the planar speed box, or the altitude of the triangle of their speeds);
//! - the radius: what a parabolic blend at a/2 reaching that speed would take, spread over the
//!   arc's angle, at least v²/a_normal, at most the geometric limit.
//!
//! The arc then runs at that speed; the move before it ends at that speed at the arc's start, the
//! move after it starts at that speed at the arc's end.

use crate::trace::AXES;

/// The kink below which 2.9 joins two moves tangentially instead of with an arc
/// (`arcBlendTangentKinkRatio`, 0.1 unless the INI sets it).
const KINK_RATIO: f64 = 0.1;

/// A blend arc (nm, nm/µs).
#[derive(Debug, Clone, PartialEq)]
pub struct Arc3 {
    /// Where it leaves the first move.
    pub start: [f64; 3],
    /// Where it joins the second move.
    pub end: [f64; 3],
    /// Centre.
    pub center: [f64; 3],
    /// Unit vector from the centre to the start.
    pub u: [f64; 3],
    /// Unit vector along the first move (the travel at the start).
    pub w: [f64; 3],
    /// Radius.
    pub radius: f64,
    /// Angle swept, rad.
    pub sweep: f64,
    /// Speed along the arc, nm/µs.
    pub v: f64,
    /// The arc's own speed limit, nm/µs (its planned speed: the segment's maximum).
    pub v_plan: f64,
    /// Distance from the corner to the start and to the end, nm.
    pub trim: f64,
    /// The acceleration the plane of the two moves allows, nm/µs² (the arc's tangential
    /// acceleration is half of it: tc.c `tcGetTangentialMaxAccel`, BLEND_ACC_RATIO_TANGENTIAL).
    pub a_max: f64,
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
fn scale(a: [f64; 3], k: f64) -> [f64; 3] {
    [a[0] * k, a[1] * k, a[2] * k]
}
fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// The largest speed (or acceleration) along unit `u` that keeps every axis within `bound`.
pub fn along(u: [f64; 3], bound: [f64; 3]) -> f64 {
    (0..3).filter(|&i| u[i].abs() > 1e-12).map(|i| bound[i] / u[i].abs()).fold(f64::INFINITY, f64::min)
}

/// The diameter of the largest circle of the plane with unit normal `n` inside the box
/// `±bound` (blendmath.c `calculateInscribedDiameter`): for each axis, its bound over the length
/// of the axis' unit vector projected onto the plane; the least of them.
fn inscribed(n: [f64; 3], bound: [f64; 3]) -> f64 {
    (0..3)
        .map(|i| {
            let mut e = [0.0; 3];
            e[i] = 1.0;
            let proj = sub(e, scale(n, n[i]));
            bound[i] / norm(proj).max(1e-12)
        })
        .fold(f64::INFINITY, f64::min)
}

/// The blend arc LinuxCNC 2.9 puts at the corner `p1` between the rapid `p0 → p1` (`[p0, p1, p2]`) (of nominal
/// length `nominal1`: its length before an earlier arc took its start) and the rapid `p1 → p2`,
/// with the axes' rapid rates `rate` (nm/µs) and accelerations `acc` (nm/µs²); the first move
/// enters at `v0`; `tolerance` the moves' blend tolerances (G64 P, 0: none); `req` the speeds the
/// two moves ask for (infinite for a rapid: its maximum) with the top of the feed override. None where 2.9 makes no arc (a reversal, a straight or nearly straight
/// continuation, a move of no length).
pub fn blend_arc(
    [p0, p1, p2]: [[f64; 3]; 3],
    nominal1: f64,
    v0: f64,
    rate: [f64; AXES],
    acc: [f64; AXES],
    tolerance: [f64; 2],
    (req, feed_scale): ([f64; 2], f64),
) -> Option<Arc3> {
    let (rate, acc) = ([rate[0], rate[1], rate[2]], [acc[0], acc[1], acc[2]]);
    let (d1, d2) = (sub(p1, p0), sub(p2, p1));
    let (len1, len2) = (norm(d1), norm(d2));
    if !(len1 > 1.0 && len2 > 1.0) {
        return None;
    }
    let (u1, u2) = (scale(d1, 1.0 / len1), scale(d2, 1.0 / len2));
    let theta = 0.5 * libm::acos((-dot(u1, u2)).clamp(-1.0, 1.0));
    // A reversal within 2° stops (tp.c tpSetupTangent); a straight line has no arc.
    if norm(add(u1, u2)) < std::f64::consts::PI * 2.0 / 180.0 || std::f64::consts::FRAC_PI_2 - theta < 1e-6 {
        return None;
    }
    let (v1max, v2max) = (along(u1, rate), along(u2, rate));
    // The speeds the moves ask for (a rapid: its maximum), and the fastest the planner may see
    // them asked with the feed override at its top (tc.c `tcGetMaxTargetVel`).
    let goal1 = (req[0] * feed_scale).min(v1max);
    let goal2 = (req[1] * feed_scale).min(v2max);
    let (a1, a2) = (along(u1, acc), along(u2, acc));
    // A kink small enough: joined tangentially (the speed change taken in one servo period).
    let a_inst = goal1.min(goal2) / 1000.0 + a2;
    let kink = (0..3).map(|i| (a_inst * (u2[i] - u1[i])).abs() / acc[i].max(1e-30)).fold(0.0, f64::max);
    if kink < KINK_RATIO {
        return None;
    }
    // Each move's tolerance, or a quarter of its nominal length where it has none.
    let t1 = if tolerance[0] > 0.0 { tolerance[0] } else { 0.25 * nominal1 };
    let t2 = if tolerance[1] > 0.0 { tolerance[1] } else { 0.25 * len2 };
    let tolerance = t1.min(t2).min(0.25 * nominal1).min(0.25 * len2);
    let (l1, l2) = (len1.min(0.5 * nominal1), 0.5 * len2);
    let d_tol = libm::cos(theta) * tolerance / (1.0 - libm::sin(theta));
    let d_geom = l1.min(l2).min(d_tol);
    let r_geom = libm::tan(theta) * d_geom;
    let n = cross(u1, u2);
    let n = scale(n, 1.0 / norm(n).max(1e-30));
    let a_max = inscribed(n, acc);
    let a_n = a_max * 0.75f64.sqrt();
    let phi = std::f64::consts::PI - 2.0 * theta;
    // The speed the moves allow at the corner.
    let phi_eff = phi.min(std::f64::consts::PI * 0.49);
    let vm1 = v1max.min(v2max / libm::cos(phi_eff));
    let vm2 = v2max.min(v1max / libm::cos(phi_eff));
    let base = norm(sub(scale(u2, vm2), scale(u1, vm1)));
    let v_alt = if base > 0.0 { vm1 * vm2 * libm::sin(phi) / base } else { 0.0 };
    let v_goal = goal1.max(goal2).min(v_alt.max(inscribed(n, rate)));
    let v_plan = (a_n * r_geom).sqrt().min(v_goal);
    // The radius a parabolic blend at a/2 reaching v_plan would take, over the arc's angle.
    let a_par = 0.5 * a_max;
    let t_blend = (2.0 * a_par * d_geom).sqrt().min(v_plan) / a_par;
    let r_blend = (t_blend * v_plan / phi).min(r_geom);
    let radius = (v_plan * v_plan / a_n).max(r_blend);
    if !(radius > 1.0 && v_plan > 0.0) {
        return None;
    }
    let trim = radius / libm::tan(theta);
    // The speed the arc runs at: what the first move reaches by its start and what lets the
    // second move stop by its end.
    let reach = (v0 * v0 + 2.0 * a1 * (len1 - trim).max(0.0)).sqrt();
    let stop = (2.0 * a2 * (len2 - trim).max(0.0)).sqrt();
    // Run at one speed, the arc is no faster than either move may go (the planner's final speed
    // of a segment is the lower of its own and the next one's target speed).
    let v = v_plan.min(v1max.min(v2max)).min(req[0].min(req[1])).min(reach).min(stop);
    if v.is_nan() || v <= 0.0 {
        return None;
    }
    let normal = sub(u2, u1);
    let normal = scale(normal, 1.0 / norm(normal).max(1e-30));
    let center = add(p1, scale(normal, radius / libm::sin(theta)));
    let start = sub(p1, scale(u1, trim));
    let end = add(p1, scale(u2, trim));
    let u = scale(sub(start, center), 1.0 / radius);
    Some(Arc3 { start, end, center, u, w: u1, radius, sweep: phi, v, v_plan, trim, a_max })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Debian 2.9 recording g81: `G0 X0 Y0 Z5` (from the origin) then the cycle's rapid to
    /// X10 Y10, at 30.48 mm/s and 508 mm/s² per axis. LinuxCNC turned on an arc of about 2.33 mm
    /// at 30.48 mm/s: X and Y leave at Z 2.62 (222 ms), Z arrives at 5 with X and Y at 1.6.
    #[test]
    fn the_g81_corner_is_the_arc_linuxcnc_2_9_ran() {
        let mm = 1e6;
        let rate = [30.48; AXES];
        let acc = [508e-6; AXES];
        let a = blend_arc(
            [[0.0; 3], [0.0, 0.0, 5.0 * mm], [10.0 * mm, 10.0 * mm, 5.0 * mm]],
            5.0 * mm,
            0.0,
            rate,
            acc,
            [0.0, 0.0],
            ([f64::INFINITY; 2], 1.0),
        )
        .expect("an arc");
        assert!((a.radius / mm - 2.329).abs() < 0.01, "R {}", a.radius / mm);
        assert!((a.v - 30.48).abs() < 1e-6, "v {}", a.v);
        assert!((a.start[2] / mm - 2.671).abs() < 0.01 && a.start[0] == 0.0, "{:?}", a.start);
        assert!((a.end[0] / mm - 1.647).abs() < 0.01 && (a.end[2] / mm - 5.0).abs() < 1e-9, "{:?}", a.end);
        assert!((a.sweep - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        // On the arc: its centre is R from both ends.
        for p in [a.start, a.end] {
            assert!((norm(sub(p, a.center)) - a.radius).abs() < 1.0);
        }
    }

    /// The Debian 2.9 recording g84_g18, made after g81 and g84 in one LinuxCNC session: the
    /// first corner (the rapid to X10 Y6 Z5, then down Y to R) under the 0.001 inch the earlier
    /// programs' canned cycles left: a tiny arc, X still at 2.85 mm/s when Y starts (~4 mm/s
    /// along the path, 490 ms); with no tolerance the arc would be 1.05 mm at 21.5 mm/s.
    #[test]
    fn a_blend_tolerance_makes_the_arc_small_and_slow() {
        let mm = 1e6;
        let rate = [30.48; AXES];
        let acc = [508e-6; AXES];
        let (p0, p1, p2) = ([0.0; 3], [10.0 * mm, 6.0 * mm, 5.0 * mm], [10.0 * mm, 2.0 * mm, 5.0 * mm]);
        let nominal = norm(p1);
        let tight =
            blend_arc([p0, p1, p2], nominal, 0.0, rate, acc, [25_400.0, 0.0], ([f64::INFINITY; 2], 1.0))
                .expect("an arc");
        assert!(tight.v > 3.0 && tight.v < 4.0, "{} mm/s", tight.v);
        assert!(tight.radius < 0.03 * mm, "R {}", tight.radius / mm);
        let free = blend_arc([p0, p1, p2], nominal, 0.0, rate, acc, [0.0, 0.0], ([f64::INFINITY; 2], 1.0))
            .expect("an arc");
        assert!((free.v - 21.5).abs() < 0.2 && (free.radius / mm - 1.05).abs() < 0.01, "{free:?}");
    }

    #[test]
    fn no_arc_for_a_reversal_or_a_straight_line() {
        let rate = [30.48; AXES];
        let acc = [508e-6; AXES];
        let z = |v: f64| [0.0, 0.0, v * 1e6];
        assert_eq!(
            blend_arc([z(0.0), z(5.0), z(1.0)], 5e6, 0.0, rate, acc, [0.0; 2], ([f64::INFINITY; 2], 1.0)),
            None
        );
        assert_eq!(
            blend_arc([z(0.0), z(5.0), z(9.0)], 5e6, 0.0, rate, acc, [0.0; 2], ([f64::INFINITY; 2], 1.0)),
            None
        );
        assert_eq!(
            blend_arc([z(0.0), z(5.0), z(5.0)], 5e6, 0.0, rate, acc, [0.0; 2], ([f64::INFINITY; 2], 1.0)),
            None
        );
    }
}
