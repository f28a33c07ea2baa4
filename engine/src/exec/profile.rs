//! Velocity profiles: closed-form distance and speed over time for one motion (constant
//! acceleration ramps, cruise, deceleration), stretched to whole interpolation periods.

use crate::units::{ceil_to, Micros};

mod between;
mod catch_up;
mod follow;
mod track;
pub use catch_up::catch_up_lag;
pub use follow::Ramp;

/// Most pieces a profile has (a feed following an accelerating spindle has the most).
const MAX_PIECES: usize = 16;

const NO_PIECE: Piece = Piece { t0: 0.0, s0: 0.0, v0: 0.0, a: 0.0 };

#[derive(Debug, Clone, Copy, PartialEq)]
struct Piece {
    t0: f64,
    s0: f64,
    v0: f64,
    a: f64,
}

/// Where the increasing `f` reaches `target` within `[0, hi]`, by `steps` halvings: the last
/// point below and the first at or above it.
fn bisect(f: impl Fn(f64) -> f64, target: f64, hi: f64, steps: u32) -> (f64, f64) {
    let (mut lo, mut hi) = (0.0, hi);
    for _ in 0..steps {
        let mid = 0.5 * (lo + hi);
        if f(mid) >= target {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    (lo, hi)
}

/// Distance travelled (nm, ≥ 0) against time since the motion started (µs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Profile {
    pieces: [Piece; MAX_PIECES],
    n: usize,
    /// Total distance, nm.
    pub dist: f64,
    /// Duration, µs (a whole number of interpolation periods).
    pub total: Micros,
}

impl Profile {
    /// A motion of `dist` nm at up to `v` nm/µs with acceleration `a` nm/µs² (`a` infinite or
    /// 0: no ramp), duration rounded up to whole `period`s by slowing the whole profile evenly.
    pub fn trapezoid(dist: f64, v: f64, a: f64, period: Micros) -> Profile {
        if dist <= 0.0 || v <= 0.0 || !v.is_finite() {
            return Profile::still();
        }
        let a = if a > 0.0 && a.is_finite() { a } else { f64::INFINITY };
        let vmax = v.max(1e-12);
        let (mut v, mut ta, mut tc) = (vmax, 0.0, dist / vmax);
        if a.is_finite() {
            ta = vmax / a;
            let d_acc = 0.5 * vmax * ta;
            if 2.0 * d_acc >= dist {
                v = (dist * a).sqrt();
                ta = v / a;
                tc = 0.0;
            } else {
                tc = (dist - 2.0 * d_acc) / vmax;
            }
        }
        let ideal = 2.0 * ta + tc;
        let total = ceil_to((ideal.ceil() as Micros).max(1), period.max(1));
        let k = total as f64 / ideal;
        ta *= k;
        tc *= k;
        v /= k;
        let acc = if ta > 0.0 { v / ta } else { 0.0 };
        let d1 = 0.5 * v * ta;
        let d2 = d1 + v * tc;
        let mut pieces = [NO_PIECE; MAX_PIECES];
        pieces[0] = Piece { t0: 0.0, s0: 0.0, v0: 0.0, a: acc };
        pieces[1] = Piece { t0: ta, s0: d1, v0: v, a: 0.0 };
        pieces[2] = Piece { t0: ta + tc, s0: d2, v0: v, a: -acc };
        Profile { pieces, n: 3, dist, total }
    }

    /// A thread pass of `dist` nm (HDH-C832-05): accelerate at `a` nm/µs² to exactly `v` nm/µs,
    /// cruise at exactly `v` (the pitch stays exact: no stretching), decelerate; the motion
    /// starts `t0` µs after a tick and ends on a tick of `period`: the cruise gives up half the
    /// rounding and the deceleration takes it, so the distance is kept. A move too short to
    /// cruise that long is an ordinary [`Profile::trapezoid`].
    pub fn thread(dist: f64, v: f64, a: f64, period: Micros, t0: Micros) -> Profile {
        let period = period.max(1);
        if dist <= 0.0 || v <= 0.0 || !v.is_finite() || !(a > 0.0 && a.is_finite()) {
            return Profile::trapezoid(dist, v, a, period);
        }
        let ta = v / a;
        let tc = (dist - v * ta) / v;
        let ideal = 2.0 * ta + tc;
        let end = ceil_to(t0 + (ideal.ceil() as Micros).max(1), period);
        let total = end - t0;
        let extra = total as f64 - ideal;
        if tc < extra || tc < 0.0 {
            return Profile::trapezoid(dist, v, a, period);
        }
        let (tc, td) = (tc - extra, ta + 2.0 * extra);
        let mut pieces = [NO_PIECE; MAX_PIECES];
        pieces[0] = Piece { t0: 0.0, s0: 0.0, v0: 0.0, a };
        pieces[1] = Piece { t0: ta, s0: 0.5 * v * ta, v0: v, a: 0.0 };
        pieces[2] = Piece { t0: ta + tc, s0: 0.5 * v * ta + v * tc, v0: v, a: -v / td };
        Profile { pieces, n: 3, dist, total }
    }

    /// A motion that does not move.
    pub fn still() -> Profile {
        Profile { pieces: [NO_PIECE; MAX_PIECES], n: 1, dist: 0.0, total: 0 }
    }

    /// Distance and speed (nm, nm/µs) at `t` µs after the start.
    pub fn eval(&self, t: Micros) -> (f64, f64) {
        if t >= self.total {
            return (self.dist, 0.0);
        }
        let t = t as f64;
        let mut p = &self.pieces[0];
        for q in &self.pieces[1..self.n] {
            if q.t0 <= t {
                p = q;
            }
        }
        let dt = t - p.t0;
        let s = (p.s0 + p.v0 * dt + 0.5 * p.a * dt * dt).clamp(0.0, self.dist);
        (s, (p.v0 + p.a * dt).max(0.0))
    }

    /// The profile of stopping as soon as possible from `t`: decelerate at `a` nm/µs² (infinite:
    /// at once), in whole periods. Distances are measured from the original start.
    pub fn stop_from(&self, t: Micros, a: f64, period: Micros) -> Profile {
        let (s0, v0) = self.eval(t);
        if v0 <= 0.0 || !a.is_finite() || a <= 0.0 {
            return Profile { dist: s0, total: 0, ..Profile::still() }.offset(s0);
        }
        let total = ceil_to(((v0 / a).ceil() as Micros).max(1), period.max(1));
        let a = v0 / total as f64;
        if s0 + 0.5 * v0 * total as f64 >= self.dist && self.end_speed() < 1e-9 {
            // It would stop past the end: the motion's own deceleration to its end is sooner
            // (it used to run at speed into the end and stop there at once: INV-11, INV-13).
            return self.rest_from(t);
        }
        // (A motion that ends at speed, a tap following its spindle through its end point, stops
        // past its end.)
        let dist = s0 + 0.5 * v0 * total as f64;
        let mut pieces = [NO_PIECE; MAX_PIECES];
        pieces[0] = Piece { t0: 0.0, s0, v0, a: -a };
        Profile { pieces, n: 1, dist, total }
    }

    /// The speed at the very end of the profile, nm/µs (0 unless it ends at speed).
    pub fn end_speed(&self) -> f64 {
        let p = &self.pieces[self.n.max(1) - 1];
        (p.v0 + p.a * (self.total as f64 - p.t0)).max(0.0)
    }

    /// The rest of this profile from `t` µs, as a profile starting at 0 (distances still from
    /// the original start).
    fn rest_from(&self, t: Micros) -> Profile {
        let tf = t as f64;
        let mut pieces = [NO_PIECE; MAX_PIECES];
        let mut n = 0;
        for (k, p) in self.pieces[..self.n].iter().enumerate() {
            let end = self.pieces[..self.n].get(k + 1).map_or(f64::INFINITY, |q| q.t0);
            if end <= tf {
                continue;
            }
            pieces[n] = if p.t0 <= tf {
                let dt = tf - p.t0;
                Piece { t0: 0.0, s0: p.s0 + p.v0 * dt + 0.5 * p.a * dt * dt, v0: p.v0 + p.a * dt, a: p.a }
            } else {
                Piece { t0: p.t0 - tf, ..*p }
            };
            n += 1;
        }
        if n == 0 {
            return Profile { dist: self.dist, total: 0, ..Profile::still() }.offset(self.dist);
        }
        Profile { pieces, n, dist: self.dist, total: self.total.saturating_sub(t) }
    }

    /// A tap braking behind its spindle from `v0` nm/µs: it follows the spindle's deceleration
    /// `a_follow` nm/µs² where its own limit `a_axis` allows (else decelerates at `a_axis`), and
    /// when that would carry it past `room` nm it leaves the spindle just in time to stop at
    /// `room` at `a_axis` (past `room` only when even that cannot stop it in time). Returns the
    /// profile (ending on the µs it stops) and whether it was cut short.
    pub fn brake_behind(v0: f64, a_follow: f64, a_axis: f64, room: f64) -> (Profile, bool) {
        let a_ax = if a_axis > 0.0 && a_axis.is_finite() { a_axis } else { 1e12 };
        let a_b = if a_follow > 0.0 && a_follow.is_finite() { a_follow.min(a_ax) } else { a_ax };
        let mut pieces = [NO_PIECE; MAX_PIECES];
        if v0 <= 0.0 {
            return (Profile::still(), false);
        }
        let coast = v0 * v0 / (2.0 * a_b);
        pieces[0] = Piece { t0: 0.0, s0: 0.0, v0, a: -a_b };
        if coast <= room {
            let total = ((v0 / a_b).ceil() as Micros).max(1);
            return (Profile { pieces, n: 1, dist: coast, total }, false);
        }
        // g(t) = s(t) + v(t)²/(2·a_ax), non-decreasing: the latest t with g(t) ≤ room.
        let g = |t: f64| {
            let v = v0 - a_b * t;
            v0 * t - 0.5 * a_b * t * t + v * v / (2.0 * a_ax)
        };
        let (mut lo, mut hi) = (0.0, v0 / a_b);
        if g(0.0) < room {
            for _ in 0..100 {
                let mid = 0.5 * (lo + hi);
                if g(mid) <= room {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
        }
        let t1 = lo;
        let v1 = v0 - a_b * t1;
        let s1 = v0 * t1 - 0.5 * a_b * t1 * t1;
        pieces[1] = Piece { t0: t1, s0: s1, v0: v1, a: -a_ax };
        let dist = s1 + v1 * v1 / (2.0 * a_ax);
        let total = ((t1 + v1 / a_ax).ceil() as Micros).max(1);
        (Profile { pieces, n: 2, dist, total }, true)
    }

    /// The same motion standing still at its end until `end` µs (the tick on which the control
    /// sees it stopped).
    pub fn still_until(mut self, end: Micros) -> Profile {
        if end <= self.total || self.n >= MAX_PIECES {
            return self;
        }
        let t = self.total as f64;
        let (s, v) = {
            let p = &self.pieces[self.n - 1];
            let dt = t - p.t0;
            (p.s0 + p.v0 * dt + 0.5 * p.a * dt * dt, (p.v0 + p.a * dt).max(0.0))
        };
        if v > 1e-9 {
            return self;
        }
        self.pieces[self.n] = Piece { t0: t, s0: s.min(self.dist), v0: 0.0, a: 0.0 };
        self.n += 1;
        self.total = end;
        self
    }

    fn offset(mut self, s0: f64) -> Profile {
        self.pieces[0].s0 = s0;
        self.dist = s0;
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trapezoid_reaches_its_distance_in_whole_periods() {
        // 10 mm at 1000 mm/min with a 100 ms ramp.
        let v = 1e9 / 60e6;
        let p = Profile::trapezoid(10e6, v, v / 100_000.0, 1000);
        assert_eq!(p.total % 1000, 0);
        assert!(p.total >= 600_000 && p.total <= 702_000, "{}", p.total);
        assert_eq!(p.eval(p.total).0, 10e6);
        assert_eq!(p.eval(0).0, 0.0);
        let (mid, vmid) = p.eval(p.total / 2);
        assert!((mid - 5e6).abs() < 1.0, "{mid}");
        assert!(vmid > 0.0);
    }

    #[test]
    fn short_moves_become_triangles_and_stay_monotonic() {
        let p = Profile::trapezoid(1000.0, 1.0, 1e-5, 2000);
        let mut last = 0.0;
        for t in (0..=p.total).step_by(100) {
            let s = p.eval(t).0;
            assert!(s >= last);
            last = s;
        }
        assert_eq!(last, 1000.0);
    }

    #[test]
    fn stop_from_decelerates_past_the_point_but_not_past_the_end() {
        let p = Profile::trapezoid(10e6, 0.1, 1e-5, 1000);
        let t = p.total / 2;
        let (s, v) = p.eval(t);
        let q = p.stop_from(t, 1e-5, 1000);
        assert!(q.dist > s && q.dist <= p.dist);
        assert!((q.total as f64) >= v / 1e-5);
        assert_eq!(q.eval(0).0, s);
    }

    #[test]
    fn a_thread_pass_cruises_at_exactly_its_speed_and_ends_on_a_tick() {
        // 40 mm at 1000 mm/min (1/60 nm/µs... in nm/µs: 16.67) with 1000 mm/s² (1e-3 nm/µs²).
        let v = 1e9 / 60e6;
        for t0 in [0, 1, 333, 999] {
            let p = Profile::thread(40e6, v, 1e-3, 1000, t0);
            assert_eq!((t0 + p.total) % 1000, 0, "{t0}");
            assert_eq!(p.eval(p.total).0, 40e6);
            // Cruise: s = v·t − v²/(2a), exactly.
            let t = 1_000_000;
            let (s, sp) = p.eval(t);
            assert_eq!(sp, v);
            assert!((s - (v * t as f64 - v * v / 2e-3)).abs() < 1e-6, "{s}");
        }
    }

    #[test]
    fn zero_distance_takes_no_time() {
        assert_eq!(Profile::trapezoid(0.0, 1.0, 1.0, 1000).total, 0);
    }
}
