//! Where LinuxCNC 2.9's planner joins a G64 feed per minute to a G2/G3 arc, or the arc to the next
//! feed, with a blend arc (DEC-164, `arc_blend.rs` for the geometry): the feed runs to the blend's
//! start and reaches it at the blend's speed, the blend runs (`start_blend_arc`), the circle starts
//! where the blend touches it at that speed; leaving the circle, it ends where the next blend
//! starts, at its speed, and the next feed starts at the blend's end; from one arc into the next
//! alike (tp.c `tpCreateArcArcBlend`). Only under `nc.trajectory_planner` 209, in G64, with
//! neither single block nor a helix.

use super::arc_blend::{self, Circle, LineCircle};
use super::blend::Arc3;
use super::planner::PendingBlend;
use super::Exec;
use crate::plan::{Feed, Plane, Pos, Step};
use crate::trace::AXES;

fn f3(p: Pos) -> [f64; 3] {
    [p[0] as f64, p[1] as f64, p[2] as f64]
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// A G2/G3 circle from `start` to `target` about `center` (in `plane`): its centre (X, Y, Z), its
/// radius at `start`, the unit normal its travel turns about counterclockwise, and its angle
/// (unsigned, rad). None for a helix (the third axis moves), a spiral or no circle.
fn circle_of(
    start: [f64; 3],
    target: Pos,
    center: [i64; 2],
    plane: Plane,
    cw: bool,
) -> Option<([f64; 3], f64, [f64; 3], f64)> {
    let (i0, i1, i2) = plane.axes();
    let t = f3(target);
    if (t[i2] - start[i2]).abs() > 0.5 {
        return None;
    }
    let mut c = start;
    c[i0] = center[0] as f64;
    c[i1] = center[1] as f64;
    let (sx, sy) = (start[i0] - c[i0], start[i1] - c[i1]);
    let (ex, ey) = (t[i0] - c[i0], t[i1] - c[i1]);
    let radius = libm::hypot(sx, sy);
    // A spiral (the end off the start's circle by more than a µm) is not blended here.
    if (libm::hypot(ex, ey) - radius).abs() > 1000.0 {
        return None;
    }
    let mut sweep = super::steps::arc_sweep(libm::atan2(sy, sx), libm::atan2(ey, ex), cw);
    if dist(start, t) < 0.5 {
        sweep = std::f64::consts::TAU;
    }
    let mut bin = [0.0; 3];
    bin[i2] = if cw { -1.0 } else { 1.0 };
    (radius > 1.0).then_some((c, radius, bin, sweep.abs()))
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn scale(a: [f64; 3], k: f64) -> [f64; 3] {
    a.map(|x| x * k)
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt().max(1e-30);
    scale(a, 1.0 / n)
}

/// The travel direction of a circle at `p`.
fn tangent_at(c: &Circle, p: [f64; 3]) -> [f64; 3] {
    unit(cross(c.binormal, sub(p, c.center)))
}

impl Exec<'_> {
    /// The rapid rates (nm/µs) and accelerations (nm/µs², × `scale`) of X, Y and Z.
    fn axis_bounds(&self, scale: f64) -> ([f64; 3], [f64; 3]) {
        let rate: [f64; AXES] = self.cfg.rapid_nm_min.map(|r| r / 60e6);
        let acc: [f64; AXES] =
            std::array::from_fn(|i| rate[i] / self.cfg.rapid_ramp_us[i].max(1) as f64 * scale);
        ([rate[0], rate[1], rate[2]], [acc[0], acc[1], acc[2]])
    }

    /// The cutting acceleration along the path, nm/µs².
    fn cut_accel(&self) -> f64 {
        self.cfg.feed_max_nm_min / 60e6 / self.cfg.feed_ramp_us.max(1) as f64
    }

    /// A feed per minute's speed (nm/µs) when the feed override acts on it, else None.
    pub(super) fn acting_feed(&self, feed: Feed) -> Option<f64> {
        match feed {
            Feed::PerMin(f)
                if !self.dry_run
                    && !self.hold_suppressed
                    && !self.override_locked
                    && self.feed_override > 0 =>
            {
                Some(f * self.feed_override as f64 / 100.0 / 60e6)
            }
            _ => None,
        }
    }

    /// The blend 2.9 puts between the feed `line` (start, end, length left, nominal length, entry
    /// speed) at `v_feed` and the next move `step`, if that is a G2/G3 arc per minute it joins
    /// with one: the blend arc and the arc's end.
    pub(super) fn line_to_arc_blend(
        &self,
        (p0, p1, len, nominal, v0): ([f64; 3], [f64; 3], f64, f64, f64),
        step: &Step,
        tols: [f64; 2],
        v_feed: f64,
        (rate, acc): ([f64; AXES], [f64; AXES]),
        feed_scale: f64,
    ) -> Option<(Arc3, Pos)> {
        let Step::Arc { target, center, plane, clockwise, feed } = step else { return None };
        if (3..AXES).any(|i| target[i] != self.cmd[i]) {
            return None;
        }
        let v2 = self.acting_feed(*feed)?;
        let (c, radius, binormal, angle) = circle_of(p1, *target, *center, *plane, *clockwise)?;
        let u_line = [(p1[0] - p0[0]) / len, (p1[1] - p0[1]) / len, (p1[2] - p0[2]) / len];
        let g = LineCircle {
            corner: p1,
            u_line,
            line_len: len,
            line_nominal: nominal,
            center: c,
            radius,
            binormal,
            angle,
            angle_share: 1.0 / 3.0,
        };
        let (rate, acc) = ([rate[0], rate[1], rate[2]], [acc[0], acc[1], acc[2]]);
        let v_max = (v_feed.min(v2) * feed_scale).min(super::blend::along(u_line, rate));
        let u_tan2 = unit(cross(binormal, sub(p1, c)));
        let mut b = match arc_blend::line_arc_blend(&g, rate, acc, tols, v_feed.min(v2), feed_scale) {
            Some(b) => b,
            // 2.9's tangent join: on at the lower speed asked, no arc.
            None if arc_blend::tangent_join_of(u_line, u_tan2, v_max, acc, true) => arc_blend::LineArcBlend {
                arc: arc_blend::tangent_arc(p1, u_line, v_feed.min(v2)),
                circle_trim: 0.0,
            },
            None => return None,
        };
        // The line reaches the blend's speed by its start; the circle can stop after it.
        let a = self.cut_accel();
        let reach = (v0 * v0 + 2.0 * a * (len - b.arc.trim).max(0.0)).sqrt();
        let stop = (2.0 * a * (radius * (angle - b.circle_trim)).max(0.0)).sqrt();
        b.arc.v = b.arc.v.min(reach).min(stop);
        Some((b.arc, *target))
    }

    /// Leaving a G2/G3 arc per minute from `start` to `target`, entered at `v0`, at `acc_scale` of
    /// the acceleration:
    /// the blend to the next move if that is a feed per minute or another such arc 2.9 joins to it
    /// with one, with the angle it takes off the circle's end and the next move's target and
    /// length.
    pub(super) fn arc_to_line_blend(
        &mut self,
        start: [f64; 3],
        (target, center, plane, cw, feed): (Pos, [i64; 2], Plane, bool, Feed),
        (acc_scale, v0): (f64, f64),
    ) -> Option<(Arc3, f64, Pos, f64)> {
        if !self.cfg.parabolic_half_accel
            || !self.cfg.coordinated_rapid
            || !self.path_continuous
            || self.single_block
        {
            return None;
        }
        let v1 = self.acting_feed(feed)?;
        let (step, tol2, _) = self.upcoming_moves(1).pop()?;
        if let Step::Arc { target: q, center: cq, plane: pq, clockwise: cwq, feed: f2 } = step {
            // Into another arc of the same plane: 2.9's arc-to-arc blend.
            if pq != plane || (3..AXES).any(|i| q[i] != target[i]) {
                return None;
            }
            let v2 = self.acting_feed(f2)?;
            let circle = |(center, radius, binormal, angle)| Circle { center, radius, binormal, angle };
            let corner = f3(target);
            let mut first = circle(circle_of(start, target, center, plane, cw)?);
            first.radius = dist(corner, first.center);
            let second = circle(circle_of(corner, q, cq, pq, cwq)?);
            let (rate, acc) = self.axis_bounds(acc_scale);
            let feed_scale = self.cfg.overrides.feed_max_pct as f64 / 100.0;
            let tols = [self.path_tolerance, tol2];
            let (t1, t2) = (tangent_at(&first, corner), tangent_at(&second, corner));
            let v_max = (v1.min(v2) * feed_scale).min(super::blend::along(t1, rate));
            let (mut arc, [trim1, trim2]) = match arc_blend::arc_arc_blend(
                corner,
                [first, second],
                (rate, acc),
                tols,
                v1.min(v2),
                feed_scale,
            ) {
                Some(b) => b,
                None if arc_blend::tangent_join_of(t1, t2, v_max, acc, true) => {
                    (arc_blend::tangent_arc(corner, t1, v1.min(v2)), [0.0, 0.0])
                }
                None => return None,
            };
            // The arc reaches the speed by its end.
            let own = first.radius * (first.angle - trim1);
            arc.v = arc.v.min((v0 * v0 + 2.0 * self.cut_accel() * own.max(0.0)).sqrt());
            // The second arc can stop after the blend.
            let rest = second.radius * (second.angle - trim2);
            arc.v = arc.v.min((2.0 * self.cut_accel() * rest.max(0.0)).sqrt());
            let nominal2 = second.radius * second.angle;
            return (arc.v >= super::planner::MIN_ARC_SPEED).then_some((arc, trim1, q, nominal2));
        }
        let Step::Feed { target: q, feed: next_feed } = step else { return None };
        if (3..AXES).any(|i| q[i] != target[i]) {
            return None;
        }
        let v2 = self.acting_feed(next_feed)?;
        let (c, _, binormal, angle) = circle_of(start, target, center, plane, cw)?;
        let (corner, far) = (f3(target), f3(q));
        let line_len = dist(corner, far);
        if line_len <= 1.0 {
            return None;
        }
        let u_line = [
            (corner[0] - far[0]) / line_len,
            (corner[1] - far[1]) / line_len,
            (corner[2] - far[2]) / line_len,
        ];
        // The path run backwards: the next feed towards the corner, then the circle reversed.
        let g = LineCircle {
            corner,
            u_line,
            line_len,
            line_nominal: line_len,
            center: c,
            radius: dist(corner, c),
            binormal: binormal.map(|x| -x),
            angle,
            angle_share: 2.0 / 3.0,
        };
        let (rate, acc) = self.axis_bounds(acc_scale);
        let feed_scale = self.cfg.overrides.feed_max_pct as f64 / 100.0;
        let tols = [self.path_tolerance, tol2];
        let t1 = tangent_at(&Circle { center: c, radius: g.radius, binormal, angle }, corner);
        let u2 = scale(u_line, -1.0);
        let v_max = (v1.min(v2) * feed_scale).min(super::blend::along(t1, rate));
        let mut b = match arc_blend::arc_line_blend(&g, rate, acc, tols, v1.min(v2), feed_scale) {
            Some(b) => b,
            None if arc_blend::tangent_join_of(t1, u2, v_max, acc, true) => arc_blend::LineArcBlend {
                arc: arc_blend::tangent_arc(corner, t1, v1.min(v2)),
                circle_trim: 0.0,
            },
            None => return None,
        };
        let own = g.radius * (angle - b.circle_trim);
        b.arc.v = b.arc.v.min((v0 * v0 + 2.0 * self.cut_accel() * own.max(0.0)).sqrt());
        // The next feed can stop after the blend.
        let stop = (2.0 * self.cut_accel() * (line_len - b.arc.trim).max(0.0)).sqrt();
        b.arc.v = b.arc.v.min(stop);
        (b.arc.v >= super::planner::MIN_ARC_SPEED).then_some((b.arc, b.circle_trim, q, line_len))
    }

    /// Keeps the blend planned at the end of an arc, to run before the feed to `next_target`.
    pub(super) fn pend_blend(&mut self, arc: Arc3, next_target: Pos, nominal2: f64) {
        self.blend = Some(PendingBlend { arc, next_target, nominal2 });
    }
}
