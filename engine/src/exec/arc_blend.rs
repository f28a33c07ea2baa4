//! LinuxCNC 2.9's blend arc between a G64 line and a G2/G3 arc (DEC-164, L-124): the geometry and
//! speed its planner gives the arc that joins a straight move to a circle or a circle to a
//! straight move (tp.c `tpCreateLineArcBlend`, `tpCreateArcLineBlend`; blendmath.c
//! `blendInit3FromLineArc`, `blendInit3FromArcLine`, `blendComputeParameters`,
//! `blendLineArcPostProcess`, `blendArcLinePostProcess`), computed here from those rules, not
//! copied:
//!
//! - θ, the half angle between the line and the circle's tangent at the corner; the circle is
//!   *convex* at the corner when its centre is not ahead of the corner along the line (it bends
//!   away from the turn: θ is then reduced by a quarter of the angle it may give up);
//! - the circle may give up at most a third of its angle (line to arc) or two thirds (arc to
//!   line), and at most θ (convex) or a quarter turn; the line at most half its length;
//! - radius and speed as between two lines (`blend.rs`: tolerance, normal acceleration √¾ of the
//!   plane's, the parabolic-blend radius), the speed limit of the plane only (no altitude rule
//!   with arcs);
//! - the arc is then put tangent to the line and to the circle itself: its centre R off the line,
//!   r + R (concave) or r − R (convex) from the circle's centre; the line loses the distance to
//!   the arc's start, the circle the angle to the point where the two touch. A blend farther
//!   from the corner than the tolerance, or taking more of the circle than its share, or a line
//!   out of the circle's plane, is no blend (the moves stop: 2.9's parabolic blend is L-124).
//!
//! An arc-to-line corner is the line-to-arc corner of the path run backwards. Two arcs that turn
//! (`arc_arc_blend`, tp.c `tpCreateArcArcBlend`) follow the same rules with a circle on each side.

use super::blend::{along, Arc3};

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn scale(a: [f64; 3], k: f64) -> [f64; 3] {
    [a[0] * k, a[1] * k, a[2] * k]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
fn unit(a: [f64; 3]) -> [f64; 3] {
    scale(a, 1.0 / norm(a).max(1e-30))
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// 2.9's tangent join (tp.c `tpSetupTangent`): a kink small enough that the change of direction
/// at the fastest speed asked, taken in one servo period (1 ms), needs under a tenth of the axes'
/// acceleration (`arcBlendTangentKinkRatio`; with an arc, of its tangential half) gets no blend
/// arc. True for such a kink.
fn tangent_join(u1: [f64; 3], u2: [f64; 3], v_max: f64, acc: [f64; 3]) -> bool {
    tangent_join_of(u1, u2, v_max, acc, true)
}

/// [`tangent_join`] for two moves along `u1` then `u2` at the corner, `circular` when either is
/// an arc (the ratio then against the tangential half of the acceleration).
pub fn tangent_join_of(u1: [f64; 3], u2: [f64; 3], v_max: f64, acc: [f64; 3], circular: bool) -> bool {
    let a_inst = v_max / 1000.0 + along(u2, acc);
    let d = sub(u2, u1);
    let worst = (0..3).map(|i| (a_inst * d[i]).abs() / acc[i].max(1e-30)).fold(0.0, f64::max);
    let worst = if circular { worst / 0.5 } else { worst };
    dot(u1, u2) > 0.0 && worst < 0.1
}

/// A tangent join at `corner` run at `v` (nm/µs): no arc (no sweep), the first move ending at the
/// corner at `v`, the next starting there at `v` (tp.c `TC_TERM_COND_TANGENT`).
pub fn tangent_arc(corner: [f64; 3], dir: [f64; 3], v: f64) -> Arc3 {
    Arc3 {
        start: corner,
        end: corner,
        center: corner,
        u: [0.0; 3],
        w: dir,
        radius: 0.0,
        sweep: 0.0,
        v,
        v_plan: v,
        trim: 0.0,
        a_max: 0.0,
    }
}

/// The diameter of the largest circle of the plane with unit normal `n` in the box `±bound`
/// (blendmath.c `calculateInscribedDiameter`).
fn inscribed(n: [f64; 3], bound: [f64; 3]) -> f64 {
    (0..3)
        .map(|i| {
            let mut e = [0.0; 3];
            e[i] = 1.0;
            bound[i] / norm(sub(e, scale(n, n[i]))).max(1e-12)
        })
        .fold(f64::INFINITY, f64::min)
}

/// The blend's radius, its planned speed and the plane's acceleration (blendmath.c
/// `blendParamKinematics` and `blendComputeParameters` with arcs: no altitude rule): from the half
/// angle `theta`, the lengths each move may give up, the tolerance, the plane's normal `bin`, the
/// axes' bounds and the fastest speed asked (with the feed override at its top). None: too small.
fn radius_and_speed(
    theta: f64,
    [l1, l2]: [f64; 2],
    tol: f64,
    bin: [f64; 3],
    (rate, acc): ([f64; 3], [f64; 3]),
    v_goal: f64,
) -> Option<(f64, f64, f64)> {
    let phi = std::f64::consts::PI - 2.0 * theta;
    let a_max = inscribed(bin, acc);
    let a_n = a_max * 0.75f64.sqrt();
    let v_goal = v_goal.min(inscribed(bin, rate));
    let d_tol = libm::cos(theta) * tol / (1.0 - libm::sin(theta));
    let d_geom = l1.min(l2).min(d_tol);
    let r_geom = libm::tan(theta) * d_geom;
    let v_plan = (a_n * r_geom).sqrt().min(v_goal);
    let a_par = 0.5 * a_max;
    let t_blend = (2.0 * a_par * d_geom).sqrt().min(v_plan) / a_par;
    let r_blend = (t_blend * v_plan / phi).min(r_geom);
    let big_r = (v_plan * v_plan / a_n).max(r_blend);
    (big_r > 1.0 && v_plan > 0.0 && big_r.is_finite()).then_some((big_r, v_plan, a_max))
}

/// A circle of a G2/G3 at the corner (nm): centre, radius, the unit normal its travel turns about
/// counterclockwise, and the angle it has (unsigned, rad).
#[derive(Debug, Clone, Copy)]
pub struct Circle {
    /// Centre.
    pub center: [f64; 3],
    /// Radius.
    pub radius: f64,
    /// Unit normal of its plane, the travel turning about it counterclockwise.
    pub binormal: [f64; 3],
    /// Its angle, rad.
    pub angle: f64,
}

/// The blend 2.9 puts between two G2/G3 circles meeting at `corner` (tp.c `tpCreateArcArcBlend`,
/// blendmath.c `blendInit3FromArcArc`, `blendArcArcPostProcess`): θ from the two tangents, each
/// circle convex or concave there as against a line, the first giving up at most two thirds of its
/// angle, the second a third (and θ when convex, else a quarter turn); no blend below θ = 15°, for
/// circles in different planes, or concentric; the arc tangent to both (its centre r1 ± R from the
/// first centre, r2 ± R from the second, on the side of the turn). The arc's `trim` is 0: the
/// angles taken off the circles are returned, the first's and the second's.
pub fn arc_arc_blend(
    corner: [f64; 3],
    [c1, c2]: [Circle; 2],
    (rate, acc): ([f64; 3], [f64; 3]),
    tolerance: [f64; 2],
    req: f64,
    feed_scale: f64,
) -> Option<(Arc3, [f64; 2])> {
    use std::f64::consts::{FRAC_PI_2, PI};
    let p = corner;
    if !(c1.radius > 1.0 && c2.radius > 1.0 && c1.angle > 0.0 && c2.angle > 0.0) {
        return None;
    }
    if norm(cross(c1.binormal, c2.binormal)) > 1e-6 {
        return None;
    }
    let (rp1, rp2) = (sub(p, c1.center), sub(p, c2.center));
    let u_tan1 = unit(cross(c1.binormal, rp1));
    let u_tan2 = unit(cross(c2.binormal, rp2));
    let theta_tan = 0.5 * libm::acos((-dot(u_tan1, u_tan2)).clamp(-1.0, 1.0));
    if FRAC_PI_2 - theta_tan < 1e-6 || theta_tan < 1e-6 {
        return None;
    }
    if tangent_join(u_tan1, u_tan2, (req * feed_scale).min(along(u_tan1, rate)), acc) {
        return None;
    }
    let bin = unit(cross(u_tan1, u_tan2));
    if norm(cross(bin, c1.binormal)) > 1e-6 {
        return None;
    }
    let normal = unit(sub(u_tan2, u_tan1));
    let convex1 = dot(rp1, u_tan2) < 0.0;
    let convex2 = dot(rp2, u_tan1) >= 0.0;
    let phi1_max = (c1.angle * 2.0 / 3.0).min(if convex1 { theta_tan } else { FRAC_PI_2 });
    let phi2_max = (c2.angle / 3.0).min(if convex2 { theta_tan } else { FRAC_PI_2 });
    let mut theta = theta_tan;
    if convex1 {
        theta = theta.min(theta_tan - phi1_max / 4.0);
    }
    if convex2 {
        theta = theta.min(theta_tan - phi2_max / 4.0);
    }
    if theta < PI / 12.0 {
        return None;
    }
    let l1 = if convex1 { libm::sin(phi1_max / 4.0) * c1.radius } else { phi1_max * c1.radius };
    let l2 = if convex2 { libm::sin(phi2_max / 4.0) * c2.radius } else { phi2_max * c2.radius };
    let (q1, q2) = (0.25 * c1.radius * c1.angle, 0.25 * c2.radius * c2.angle);
    let t1 = if tolerance[0] > 0.0 { tolerance[0] } else { q1 };
    let t2 = if tolerance[1] > 0.0 { tolerance[1] } else { q2 };
    let tol = t1.min(t2).min(q1).min(q2);
    let (big_r, v_plan, a_max) = radius_and_speed(theta, [l1, l2], tol, bin, (rate, acc), req * feed_scale)?;
    // The centre r1 ± R from the first circle's, r2 ± R from the second's, on the turn's side.
    let d1 = if convex1 { c1.radius - big_r } else { c1.radius + big_r };
    let d2 = if convex2 { c2.radius - big_r } else { c2.radius + big_r };
    let c12 = sub(c2.center, c1.center);
    let dc = norm(c12);
    if dc < 1.0 {
        return None;
    }
    let cx = (d1 * d1 - d2 * d2 + dc * dc) / (2.0 * dc);
    let cy2 = d1 * d1 - cx * cx;
    if cy2.is_nan() || cy2 < 0.0 {
        return None;
    }
    let uc = scale(c12, 1.0 / dc);
    let mut nc = unit(cross(bin, uc));
    if dot(normal, nc) < 0.0 {
        nc = scale(nc, -1.0);
    }
    let base = add(c1.center, scale(uc, cx));
    let (ca, cb) = (add(base, scale(nc, cy2.sqrt())), sub(base, scale(nc, cy2.sqrt())));
    let center = if norm(sub(cb, p)) < norm(sub(ca, p)) { cb } else { ca };
    if norm(sub(center, p)) - big_r > tol {
        return None;
    }
    let trim =
        |c: &Circle, rp: [f64; 3]| libm::acos(dot(unit(rp), unit(sub(center, c.center))).clamp(-1.0, 1.0));
    let (trim1, trim2) = (trim(&c1, rp1), trim(&c2, rp2));
    if trim1 > phi1_max || trim2 > phi2_max || trim1 >= c1.angle || trim2 >= c2.angle {
        return None;
    }
    let start = add(c1.center, scale(unit(sub(center, c1.center)), c1.radius));
    let end = add(c2.center, scale(unit(sub(center, c2.center)), c2.radius));
    let u = unit(sub(start, center));
    let w = unit(cross(c1.binormal, sub(start, c1.center)));
    let sweep = libm::acos(dot(u, unit(sub(end, center))).clamp(-1.0, 1.0));
    let v = v_plan.min(req);
    Some((
        Arc3 { start, end, center, u, w, radius: big_r, sweep, v, v_plan, trim: 0.0, a_max },
        [trim1, trim2],
    ))
}

/// A straight move meeting a circle at a corner (nm, nm/µs), as the line-to-arc case sees it.
#[derive(Debug, Clone, Copy)]
pub struct LineCircle {
    /// The corner: where the line ends and the circle starts.
    pub corner: [f64; 3],
    /// Unit vector along the line, towards the corner.
    pub u_line: [f64; 3],
    /// Length of the line left (from where it starts to the corner) and its nominal length.
    pub line_len: f64,
    /// The line's nominal length (before an earlier blend took its start).
    pub line_nominal: f64,
    /// The circle's centre (in the corner's plane) and radius.
    pub center: [f64; 3],
    /// Radius.
    pub radius: f64,
    /// Unit normal of the circle's plane, the travel turning about it counterclockwise.
    pub binormal: [f64; 3],
    /// The circle's angle (unsigned, rad) and the share of it the blend may take (⅓ line to arc,
    /// ⅔ arc to line).
    pub angle: f64,
    /// Share of `angle` the blend may take.
    pub angle_share: f64,
}

/// A blend between a line and a circle: the arc (oriented from the line to the circle) and the
/// angle it takes off the circle at the corner.
#[derive(Debug, Clone, PartialEq)]
pub struct LineArcBlend {
    /// The blend arc; `trim` is the distance it takes off the line.
    pub arc: Arc3,
    /// Angle taken off the circle, rad.
    pub circle_trim: f64,
}

/// The blend 2.9 makes between the line and the circle of `g` (line first), with the axes' speed
/// and acceleration bounds (nm/µs, nm/µs²), the two moves' tolerances (G64 P, 0: none), the speed
/// they ask for (`req`, nm/µs) and the top of the feed override. None where 2.9 makes none.
pub fn line_arc_blend(
    g: &LineCircle,
    rate: [f64; 3],
    acc: [f64; 3],
    tolerance: [f64; 2],
    req: f64,
    feed_scale: f64,
) -> Option<LineArcBlend> {
    use std::f64::consts::FRAC_PI_2;
    let (p, u1, c, r) = (g.corner, g.u_line, g.center, g.radius);
    if !(g.line_len > 1.0 && r > 1.0 && g.angle > 0.0) {
        return None;
    }
    let rp = sub(p, c);
    // The circle's travel direction at the corner.
    let u_tan2 = unit(cross(g.binormal, rp));
    let theta_tan = 0.5 * libm::acos((-dot(u1, u_tan2)).clamp(-1.0, 1.0));
    // No arc for a straight (tangent) continuation or a reversal (blendGeom3Init).
    if FRAC_PI_2 - theta_tan < 1e-6 || theta_tan < 1e-6 {
        return None;
    }
    // Concave when the circle's centre lies ahead of the corner along the line.
    let convex = dot(rp, u1) >= 0.0;
    let phi2_max = (g.angle * g.angle_share).min(if convex { theta_tan } else { FRAC_PI_2 });
    let theta = if convex { theta_tan.min(theta_tan - phi2_max / 4.0) } else { theta_tan };
    if theta <= 0.0 {
        return None;
    }
    let l1 = g.line_len.min(g.line_nominal / 2.0);
    let l2 = if convex { libm::sin(phi2_max / 4.0) * r } else { phi2_max * r };
    // Each move's tolerance, or a quarter of its nominal length where it has none
    // (tc.c `tcFindBlendTolerance`).
    let (arc_len, q1) = (r * g.angle, 0.25 * g.line_nominal);
    let t1 = if tolerance[0] > 0.0 { tolerance[0] } else { q1 };
    let t2 = if tolerance[1] > 0.0 { tolerance[1] } else { 0.25 * arc_len };
    let tol = t1.min(t2).min(q1).min(0.25 * arc_len);
    if tangent_join(u1, u_tan2, (req * feed_scale).min(along(u1, rate)), acc) {
        return None;
    }
    let bin = unit(cross(u1, u_tan2));
    // Only a line in the circle's plane (tp.c: the blend's binormal colinear with the circle's
    // normal); a line out of it (a helix-like entry, a Z move into an XY arc) stops.
    if norm(cross(bin, g.binormal)) > 1e-6 {
        return None;
    }
    let (big_r, v_plan, a_max) = radius_and_speed(theta, [l1, l2], tol, bin, (rate, acc), req * feed_scale)?;
    // Put the arc tangent to the line (its centre R off it, towards the turn) and to the circle.
    let d2 = if convex { r - big_r } else { r + big_r };
    let n1 = unit(cross(bin, u1));
    let (c_u, c_n) = (dot(sub(c, p), u1), dot(sub(c, p), n1));
    let (b, cc) = (2.0 * c_u, c_u * c_u - d2 * d2 + (big_r - c_n).powi(2));
    let disc = b * b - 4.0 * cc;
    if disc < 0.0 {
        return None;
    }
    let (x0, x1) = ((-b + disc.sqrt()) / 2.0, (-b - disc.sqrt()) / 2.0);
    let d_l = x0.abs().min(x1.abs());
    if d_l >= g.line_len {
        return None;
    }
    let center = add(sub(p, scale(u1, d_l)), scale(n1, big_r));
    if norm(sub(center, p)) - big_r > tol {
        return None;
    }
    let circle_trim = libm::acos(dot(unit(rp), unit(sub(center, c))).clamp(-1.0, 1.0));
    // No more of the circle than its share (tp.c: the trim against phi2_max / phi1_max).
    if circle_trim > phi2_max || circle_trim >= g.angle {
        return None;
    }
    let start = sub(p, scale(u1, d_l));
    let end = add(c, scale(unit(sub(center, c)), r));
    let u = unit(sub(start, center));
    let sweep = libm::acos(dot(u, unit(sub(end, center))).clamp(-1.0, 1.0));
    let v = v_plan.min(req).min(along(u1, rate));
    Some(LineArcBlend {
        arc: Arc3 { start, end, center, u, w: u1, radius: big_r, sweep, v, v_plan, trim: d_l, a_max },
        circle_trim,
    })
}

/// The same blend run backwards: the circle of `g` first, then the line, `g` describing the path
/// reversed (its line running from the far end of the next move to the corner, its binormal the
/// reversed circle's). The arc returned runs from the circle to the line.
pub fn arc_line_blend(
    g: &LineCircle,
    rate: [f64; 3],
    acc: [f64; 3],
    tolerance: [f64; 2],
    req: f64,
    feed_scale: f64,
) -> Option<LineArcBlend> {
    let b = line_arc_blend(g, rate, acc, [tolerance[1], tolerance[0]], req, feed_scale)?;
    let a = b.arc;
    // Forwards the arc starts where the reversed one touched the circle, travelling as the
    // circle does there (the reversed circle's travel turned round).
    let w = scale(unit(cross(g.binormal, sub(a.end, g.center))), -1.0);
    let u = unit(sub(a.end, a.center));
    let arc = Arc3 { start: a.end, end: a.start, u, w, ..a };
    Some(LineArcBlend { arc, circle_trim: b.circle_trim })
}

#[cfg(test)]
mod tests {
    use super::*;

    const MM: f64 = 1e6;

    /// g64_arcs' first corner (`G1 X10` from X0, then `G2 X20 Y0 I5 J0`, a half circle of R5
    /// about X15) with the line coming in along `u_line`.
    fn first_corner(u_line: [f64; 3]) -> LineCircle {
        LineCircle {
            corner: [10.0 * MM, 0.0, 0.0],
            u_line,
            line_len: 10.0 * MM,
            line_nominal: 10.0 * MM,
            center: [15.0 * MM, 0.0, 0.0],
            radius: 5.0 * MM,
            binormal: [0.0, 0.0, -1.0],
            angle: std::f64::consts::PI,
            angle_share: 1.0 / 3.0,
        }
    }

    /// g64_arcs' first corner: `G1 X10` (from X0) at F600, then `G2 X20 Y0 I5 J0` (a half circle
    /// of R5 about X15), 508 mm/s² and 30.48 mm/s per axis, the feed override's top 1.2. By
    /// hand from blendmath.c: concave (the centre ahead of the line), θ = 45°, L1 = 5, L2 = π/3·5,
    /// tolerance ¼·10 = 2.5 → d_tol = 6.04, d_geom = 5; a = 508, a_n = 440 mm/s²; v_plan = 12
    /// mm/s (F600 × 1.2); t = 12/254 s, s = 0.567 mm, R = 0.567/(π/2) = 0.361 mm (≥ 12²/440 =
    /// 0.327); tangent to the line and to the circle: d_L = √(25 + 10R) − 5 = 0.349 mm, the
    /// circle's trim atan(R / (5 + d_L)) = 0.0674 rad.
    #[test]
    fn the_g64_arcs_corner_is_what_blendmath_gives() {
        let g = first_corner([1.0, 0.0, 0.0]);
        let (rate, acc) = ([30.48; 3], [508e-6; 3]);
        let b = line_arc_blend(&g, rate, acc, [0.0; 2], 10.0, 1.2).expect("a blend");
        let a = &b.arc;
        let r = 0.567 / std::f64::consts::FRAC_PI_2;
        assert!((a.radius / MM - 0.361).abs() < 0.002, "R {}", a.radius / MM);
        assert!((a.radius / MM - r).abs() < 0.002);
        let d_l = (25.0 + 10.0 * a.radius / MM).sqrt() - 5.0;
        assert!((a.trim / MM - d_l).abs() < 1e-6, "d_L {}", a.trim / MM);
        assert!((b.circle_trim - (a.radius / MM / (5.0 + d_l)).atan()).abs() < 1e-9);
        assert!((a.v - 10.0).abs() < 1e-9 && (a.v_plan - 12.0).abs() < 1e-9);
        // Tangent to both: R from its start and end, its end on the circle, r + R from its centre.
        for q in [a.start, a.end] {
            assert!((norm(sub(q, a.center)) - a.radius).abs() < 1e-3);
        }
        assert!((norm(sub(a.end, g.center)) - g.radius).abs() < 1e-3);
        assert!((norm(sub(a.center, g.center)) - g.radius - a.radius).abs() < 1e-3);
        // Within the tolerance of the corner, and its centripetal acceleration within the normal
        // share of the plane's (v²/R ≤ √¾ · 508 mm/s²).
        assert!(norm(sub(a.center, g.corner)) - a.radius < 2.5 * MM);
        assert!(a.v * a.v / a.radius <= 508e-6 * 0.75f64.sqrt());
        // It turns from the line to the circle's tangent where it touches it.
        let t_end = unit(cross(g.binormal, sub(a.end, g.center)));
        let w_end = add(scale(a.u, -a.sweep.sin()), scale(a.w, a.sweep.cos()));
        assert!(norm(sub(t_end, w_end)) < 1e-9, "{t_end:?} {w_end:?}");
    }

    /// The second corner, `G2` ending at X20 then `G1 X30`, run backwards is the first one
    /// mirrored: the same radius, and the arc starts on the circle going its way.
    #[test]
    fn an_arc_to_line_corner_is_the_mirrored_line_to_arc_one() {
        let g = LineCircle {
            corner: [20.0 * MM, 0.0, 0.0],
            u_line: [-1.0, 0.0, 0.0],
            line_len: 10.0 * MM,
            line_nominal: 10.0 * MM,
            center: [15.0 * MM, 0.0, 0.0],
            radius: 5.0 * MM,
            binormal: [0.0, 0.0, 1.0],
            angle: std::f64::consts::PI,
            angle_share: 2.0 / 3.0,
        };
        let b = arc_line_blend(&g, [30.48; 3], [508e-6; 3], [0.0; 2], 10.0, 1.2).expect("a blend");
        let a = &b.arc;
        assert!((a.radius / MM - 0.361).abs() < 0.002, "R {}", a.radius / MM);
        assert!((a.end[1]).abs() < 1e-6 && a.end[0] > 20.0 * MM, "{:?}", a.end);
        // Forwards (G2 about X15): at its start it travels as the circle does, down and right.
        assert!(a.w[1] < -0.99 && a.w[0] > 0.0, "{:?}", a.w);
        let w_end = add(scale(a.u, -a.sweep.sin()), scale(a.w, a.sweep.cos()));
        assert!(norm(sub(w_end, [1.0, 0.0, 0.0])) < 1e-9, "{w_end:?}");
    }

    /// `G3 X30 Y0 I5 J0` (from X20, about X25) then `G2 X30 Y-10 I0 J-5` at F600: the first
    /// circle concave at the corner, the second convex (it bends away from the turn). By hand from
    /// blendmath.c: φ2max = min(π/3, 45°) = π/4, θ = 45° − φ2max/4 = 0.589 rad, L2 = sin(φ2max/4)·5
    /// = 0.975 mm (the least), R_geom = tan θ · 0.975 = 0.652, v_plan 12 mm/s, the parabolic radius
    /// 0.567/(π − 2θ) = 0.289 < 12²/440 = 0.3273 mm = R; the centre 5 + R from (25, 0) and 5 − R
    /// from (30, −5), the one nearer the corner: (30.3166, −0.3382), the corner passed at 0.1360 mm.
    #[test]
    fn an_arc_to_arc_corner_is_what_blendmath_gives() {
        use std::f64::consts::PI;
        let first =
            Circle { center: [25.0 * MM, 0.0, 0.0], radius: 5.0 * MM, binormal: [0.0, 0.0, 1.0], angle: PI };
        let second = Circle {
            center: [30.0 * MM, -5.0 * MM, 0.0],
            radius: 5.0 * MM,
            binormal: [0.0, 0.0, -1.0],
            angle: PI,
        };
        let corner = [30.0 * MM, 0.0, 0.0];
        let (a, [t1, t2]) =
            arc_arc_blend(corner, [first, second], ([30.48; 3], [508e-6; 3]), [0.0; 2], 10.0, 1.2)
                .expect("a blend");
        assert!((a.radius / MM - 144.0 / (508.0 * 0.75f64.sqrt())).abs() < 1e-6, "R {}", a.radius / MM);
        assert!((a.center[0] / MM - 30.3166).abs() < 2e-4 && (a.center[1] / MM + 0.3382).abs() < 2e-4);
        assert!(((norm(sub(a.center, corner)) - a.radius) / MM - 0.1360).abs() < 2e-4);
        // Tangent to both: outside the first (5 + R), inside the second (5 − R).
        assert!((norm(sub(a.center, first.center)) - first.radius - a.radius).abs() < 1e-3);
        assert!((norm(sub(a.center, second.center)) - second.radius + a.radius).abs() < 1e-3);
        assert!(t1 > 0.0 && t1 < PI / 2.0 && t2 > 0.0 && t2 < PI / 4.0, "{t1} {t2}");
        // It leaves the first circle going its way and joins the second going its way.
        let t_start = unit(cross(first.binormal, sub(a.start, first.center)));
        let t_end = unit(cross(second.binormal, sub(a.end, second.center)));
        let w_end = add(scale(a.u, -a.sweep.sin()), scale(a.w, a.sweep.cos()));
        assert!(norm(sub(t_start, a.w)) < 1e-9 && norm(sub(t_end, w_end)) < 1e-6, "{t_end:?} {w_end:?}");
        assert!((a.v - 10.0).abs() < 1e-9);
        // Two circles continuing tangentially (the same circle's two halves) have none.
        let half =
            Circle { center: [25.0 * MM, 0.0, 0.0], radius: 5.0 * MM, binormal: [0.0, 0.0, 1.0], angle: PI };
        assert_eq!(
            arc_arc_blend(corner, [first, half], ([30.48; 3], [508e-6; 3]), [0.0; 2], 10.0, 1.2),
            None
        );
    }

    /// A line meeting the circle 0.05° off its tangent: 2.9 joins them tangentially (the kink at
    /// 12 mm/s in 1 ms needs 12.5 m/s² × 0.00087 = 11 mm/s², over half of 508 under a tenth),
    /// no arc; 1° off, an arc.
    #[test]
    fn a_small_kink_is_a_tangent_join_not_an_arc() {
        let g = |deg: f64| {
            let a = deg.to_radians();
            first_corner([-a.sin(), a.cos(), 0.0])
        };
        let blend = |deg| line_arc_blend(&g(deg), [30.48; 3], [508e-6; 3], [0.0; 2], 10.0, 1.2);
        assert_eq!(blend(0.05), None);
        assert!(blend(1.0).is_some());
    }

    #[test]
    fn a_line_tangent_to_the_circle_has_no_blend() {
        let g = first_corner([0.0, 1.0, 0.0]);
        assert_eq!(line_arc_blend(&g, [30.48; 3], [508e-6; 3], [0.0; 2], 10.0, 1.2), None);
    }
}
