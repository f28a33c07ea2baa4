//! A feed per revolution that follows the spindle while it changes speed (COM-MOT-02): the
//! commanded path speed is F × the actual spindle speed at every instant, capped at the maximum
//! cutting feed; the path follows that command within its own acceleration, and decelerates to
//! rest at the end of the move. The spindle's speed is linear in time while it ramps and constant
//! afterwards, so the command is linear by pieces and the profile stays closed-form.

use super::{Piece, Profile, MAX_PIECES, NO_PIECE};
use crate::units::{ceil_to, Micros};

/// The spindle's speed from the start of the move: `rpm0 + slope·t` for `t < dur`, then constant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ramp {
    /// Signed speed at the start, rpm.
    pub rpm0: f64,
    /// Signed acceleration, rpm/µs.
    pub slope: f64,
    /// Time left in the ramp, µs.
    pub dur: f64,
}

/// A piece of the speed command: from `t` on, `v + slope·(τ − t)` (nm/µs).
#[derive(Debug, Clone, Copy)]
struct Cmd {
    t: f64,
    v: f64,
    slope: f64,
}

impl Profile {
    /// A move of `dist` nm whose speed command is `per_rpm` (nm/µs per rpm) × |the spindle's
    /// speed|, capped at `vmax` nm/µs, followed within the acceleration `a` nm/µs²; stretched to
    /// whole `period`s like [`Profile::trapezoid`]. None when the move cannot end: the spindle
    /// comes to rest before the distance is covered.
    pub fn following(
        dist: f64,
        per_rpm: f64,
        ramp: Ramp,
        vmax: f64,
        a: f64,
        period: Micros,
    ) -> Option<Profile> {
        Profile::following_from(dist, 0.0, per_rpm, ramp, vmax, a, period)
    }

    /// [`Profile::following`] from the speed `v0` (nm/µs) instead of rest: the rest of a move
    /// whose spindle has just been commanded another speed (LinuxCNC's spindle override in a
    /// thread pass, LCNC-G76-04). From a speed it ends on its µs, not stretched to whole periods
    /// (stretching would change the speed it starts with).
    pub fn following_from(
        dist: f64,
        v0: f64,
        per_rpm: f64,
        ramp: Ramp,
        vmax: f64,
        a: f64,
        period: Micros,
    ) -> Option<Profile> {
        if dist <= 0.0 {
            return Some(Profile::still());
        }
        let a = if a > 0.0 && a.is_finite() { a } else { 1e12 };
        let cmd = command(per_rpm, ramp, vmax);
        let mut pieces = follow(&cmd, a, v0);
        // Where the deceleration must begin: the distance run plus the braking distance reaches
        // `dist` (non-decreasing in time, since the path never decelerates faster than `a`).
        let g = |p: &Piece, dt: f64| {
            let v = p.v0 + p.a * dt;
            p.s0 + p.v0 * dt + 0.5 * p.a * dt * dt + v * v / (2.0 * a)
        };
        let mut found = None;
        for (k, p) in pieces.iter().enumerate() {
            let len = pieces.get(k + 1).map_or(f64::INFINITY, |q| q.t0 - p.t0);
            let end_g = if len.is_finite() {
                g(p, len)
            } else if p.v0 > 0.0 {
                f64::INFINITY
            } else {
                g(p, 0.0)
            };
            if end_g >= dist {
                let span = if len.is_finite() { len } else { (dist - g(p, 0.0)) / p.v0 + 1.0 };
                let (_, hi) = super::bisect(|t| g(p, t), dist, span, 100);
                found = Some((k, hi));
                break;
            }
        }
        let (k, dt) = found?;
        let p = pieces[k];
        let td = p.t0 + dt;
        let vd = (p.v0 + p.a * dt).max(0.0);
        let sd = p.s0 + p.v0 * dt + 0.5 * p.a * dt * dt;
        pieces.truncate(k + 1);
        if dt <= 0.0 {
            pieces.pop();
        }
        pieces.push(Piece { t0: td, s0: sd, v0: vd, a: -a });
        let ideal = td + vd / a;
        if ideal <= 0.0 || pieces.len() > MAX_PIECES {
            return None;
        }
        if v0 > 0.0 {
            let mut out = [NO_PIECE; MAX_PIECES];
            out[..pieces.len()].copy_from_slice(&pieces);
            let total = (ideal.ceil() as Micros).max(1);
            return Some(Profile { pieces: out, n: pieces.len(), dist, total });
        }
        // Whole periods: the profile slowed evenly, as a trapezoid is (COM-TIME-02).
        let total = ceil_to((ideal.ceil() as Micros).max(1), period.max(1));
        let f = total as f64 / ideal;
        let mut out = [NO_PIECE; MAX_PIECES];
        for (o, p) in out.iter_mut().zip(&pieces) {
            *o = Piece { t0: p.t0 * f, s0: p.s0, v0: p.v0 / f, a: p.a / (f * f) };
        }
        Some(Profile { pieces: out, n: pieces.len(), dist, total })
    }
}

impl Profile {
    /// A move of `dist` nm locked to the spindle that does not stop at its end: from rest it
    /// catches up with `per_rpm` × |the spindle's speed| (capped at `vmax`) within the
    /// acceleration `a`, then follows it, and ends on the µs where it has covered `dist`, still
    /// at speed (the move after it carries on from there: a following tap braking with its
    /// spindle). Not stretched to whole periods: stretching would unlock it from the spindle.
    /// Returns the profile and its speed at the end (nm/µs); None when the spindle comes to rest
    /// before the distance is covered.
    pub fn following_through(
        dist: f64,
        per_rpm: f64,
        ramp: Ramp,
        vmax: f64,
        a: f64,
    ) -> Option<(Profile, f64)> {
        Profile::following_through_from(dist, 0.0, per_rpm, ramp, vmax, a)
    }

    /// [`Profile::following_through`] from the speed `v0` (nm/µs) instead of rest: the rest of a
    /// following move whose spindle has just been commanded another speed (LinuxCNC's spindle
    /// override, LCNC-G331-04).
    pub fn following_through_from(
        dist: f64,
        v0: f64,
        per_rpm: f64,
        ramp: Ramp,
        vmax: f64,
        a: f64,
    ) -> Option<(Profile, f64)> {
        if dist <= 0.0 {
            return Some((Profile::still(), 0.0));
        }
        let a = if a > 0.0 && a.is_finite() { a } else { 1e12 };
        let pieces = follow(&command(per_rpm, ramp, vmax), a, v0);
        for (k, p) in pieces.iter().enumerate() {
            let len = pieces.get(k + 1).map_or(f64::INFINITY, |q| q.t0 - p.t0);
            let s_at = |dt: f64| p.s0 + p.v0 * dt + 0.5 * p.a * dt * dt;
            let reach = if len.is_finite() { s_at(len) >= dist } else { p.v0 > 0.0 || p.a > 0.0 };
            if !reach {
                continue;
            }
            // s0 + v0·dt + a·dt²/2 = dist: the earlier root.
            let c = dist - p.s0;
            let dt = if p.a.abs() < 1e-18 {
                c / p.v0
            } else {
                let disc = (p.v0 * p.v0 + 2.0 * p.a * c).max(0.0);
                2.0 * c / (p.v0 + disc.sqrt())
            };
            let end = p.t0 + dt.max(0.0);
            let v_end = (p.v0 + p.a * dt).max(0.0);
            if k + 1 > MAX_PIECES || !end.is_finite() {
                return None;
            }
            let mut out = [NO_PIECE; MAX_PIECES];
            out[..=k].copy_from_slice(&pieces[..=k]);
            let total = (end.ceil() as Micros).max(1);
            return Some((Profile { pieces: out, n: k + 1, dist, total }, v_end));
        }
        None
    }
}

/// The speed command `min(per_rpm × |rpm(t)|, vmax)`, linear by pieces; the last piece is constant.
fn command(per_rpm: f64, r: Ramp, vmax: f64) -> Vec<Cmd> {
    let rpm = |t: f64| r.rpm0 + r.slope * t.min(r.dur);
    // Breakpoints of |rpm|: the start, a zero crossing inside the ramp, the end of the ramp.
    let mut ts = vec![0.0];
    if r.slope != 0.0 {
        let tz = -r.rpm0 / r.slope;
        if tz > 0.0 && tz < r.dur {
            ts.push(tz);
        }
    }
    if r.dur > 0.0 {
        ts.push(r.dur);
    }
    let raw = |t: f64| per_rpm * rpm(t).abs();
    let mut out: Vec<Cmd> = Vec::new();
    for (i, &t) in ts.iter().enumerate() {
        let v0 = raw(t);
        let slope = match ts.get(i + 1) {
            Some(&t1) => (raw(t1) - v0) / (t1 - t),
            None => 0.0,
        };
        let end = ts.get(i + 1).copied().unwrap_or(f64::INFINITY);
        if v0 >= vmax {
            out.push(Cmd { t, v: vmax, slope: 0.0 });
            if slope < 0.0 {
                let tx = t + (vmax - v0) / slope;
                if tx < end {
                    out.push(Cmd { t: tx, v: vmax, slope });
                }
            }
        } else {
            out.push(Cmd { t, v: v0, slope });
            if slope > 0.0 {
                let tx = t + (vmax - v0) / slope;
                if tx < end {
                    out.push(Cmd { t: tx, v: vmax, slope: 0.0 });
                }
            }
        }
    }
    out
}

/// The path speed from `u0` following `cmd` within the acceleration `a`: pieces of constant
/// acceleration, the last one of constant speed.
fn follow(cmd: &[Cmd], a: f64, u0: f64) -> Vec<Piece> {
    let mut out: Vec<Piece> = Vec::new();
    let (mut t, mut s, mut u) = (0.0_f64, 0.0_f64, u0.max(0.0));
    for (i, c) in cmd.iter().enumerate() {
        let end = cmd.get(i + 1).map_or(f64::INFINITY, |n| n.t);
        let at = |t: f64| c.v + c.slope * (t - c.t);
        // At most: approach the command, then follow it (or fall behind it) to the piece's end.
        for _ in 0..3 {
            if t >= end {
                break;
            }
            let d = u - at(t);
            let tol = 1e-12 * at(t).abs().max(1e-9);
            let (acc, dur) = if d.abs() <= tol && c.slope.abs() <= a {
                u = at(t);
                (c.slope, end - t)
            } else if d < 0.0 || (d.abs() <= tol && c.slope > a) {
                let meet = if a > c.slope { (at(t) - u) / (a - c.slope) } else { f64::INFINITY };
                (a, meet.max(0.0).min(end - t))
            } else {
                let meet = if a + c.slope > 0.0 { (u - at(t)) / (a + c.slope) } else { f64::INFINITY };
                (-a, meet.max(0.0).min(end - t))
            };
            out.push(Piece { t0: t, s0: s, v0: u, a: acc });
            if !dur.is_finite() {
                return out;
            }
            s += u * dur + 0.5 * acc * dur * dur;
            u = (u + acc * dur).max(0.0);
            if dur >= end - t {
                t = end;
            } else {
                // Met the command: follow it from here.
                t += dur;
                u = at(t);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 0.1 mm/rev in nm/µs per rpm.
    const PER_RPM: f64 = 100_000.0 / 60e6;
    /// A cutting acceleration of 1000 mm/s² in nm/µs².
    const A: f64 = 1e-3;

    fn check_shape(p: &Profile) {
        let mut last = 0.0;
        for t in (0..=p.total).step_by(500) {
            let (s, v) = p.eval(t);
            assert!(s + 1e-6 >= last && v >= 0.0, "{t}: {s} < {last}");
            last = s;
        }
        assert_eq!(p.eval(p.total), (p.dist, 0.0));
        assert_eq!(p.total % 1000, 0);
    }

    #[test]
    fn the_feed_follows_an_accelerating_spindle() {
        // 96 rpm rising at 6 rpm/ms to 600 rpm (84 ms): 1 mm at F0.1.
        let ramp = Ramp { rpm0: 96.0, slope: 0.006, dur: 84_000.0 };
        let p = Profile::following(1e6, PER_RPM, ramp, 1e9, A, 1000).unwrap();
        check_shape(&p);
        // During the ramp the speed is F x the spindle speed: at 42 ms, 348 rpm = 0.58 mm/s.
        let (_, v) = p.eval(42_000);
        assert!((v - 348.0 * PER_RPM).abs() < 1e-3 * v, "{v}");
        // After it, 1 mm/s; the move lasts 84 ms (48.7 µm) + 951 ms: about 1.036 s.
        assert!((p.eval(500_000).1 - 600.0 * PER_RPM).abs() < 1e-3);
        assert!((1_035_000..=1_040_000).contains(&p.total), "{}", p.total);
    }

    #[test]
    fn a_steady_command_is_a_trapezoid() {
        let ramp = Ramp { rpm0: 600.0, slope: 0.0, dur: 0.0 };
        let p = Profile::following(1e6, PER_RPM, ramp, 1e9, A, 1000).unwrap();
        let q = Profile::trapezoid(1e6, 600.0 * PER_RPM, A, 1000);
        assert_eq!(p.total, q.total);
        for t in (0..p.total).step_by(997) {
            assert!((p.eval(t).0 - q.eval(t).0).abs() < 1e-3, "{t}");
        }
    }

    #[test]
    fn the_feed_is_capped_and_a_spindle_reversing_passes_through_zero() {
        // Capped at 0.5 mm/s while the spindle (and the command) would go faster.
        let ramp = Ramp { rpm0: 100.0, slope: 0.01, dur: 200_000.0 };
        let p = Profile::following(1e6, PER_RPM, ramp, 0.5, A, 1000).unwrap();
        check_shape(&p);
        assert!(p.eval(p.total / 2).1 <= 0.5 + 1e-12);
        // From +300 rpm to -300 rpm in 100 ms: the feed slows to 0 at 50 ms and picks up again.
        let ramp = Ramp { rpm0: 300.0, slope: -0.006, dur: 100_000.0 };
        let p = Profile::following(1e6, PER_RPM, ramp, 1e9, A, 1000).unwrap();
        check_shape(&p);
        assert!(p.eval(50_000).1 < 1e-3, "{}", p.eval(50_000).1);
        assert!((p.eval(300_000).1 - 300.0 * PER_RPM).abs() < 1e-3);
    }

    #[test]
    fn a_spindle_coming_to_rest_too_soon_cannot_end_the_move() {
        // 600 rpm down to 0 in 100 ms covers 5 µm at F0.1: 1 mm is never reached.
        let ramp = Ramp { rpm0: 600.0, slope: -0.006, dur: 100_000.0 };
        assert!(Profile::following(1e6, PER_RPM, ramp, 1e9, A, 1000).is_none());
        // 2 µm is reached before it stops.
        let p = Profile::following(2000.0, PER_RPM, ramp, 1e9, A, 1000).unwrap();
        check_shape(&p);
    }
}
