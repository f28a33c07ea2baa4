//! A thread pass locked to its spindle, reached with a catch-up ramp (DEC-146): the lock law
//! `s(τ) = v0·τ + acc·τ²/2` (τ µs since the spindle's angle passed the pass' start angle: lead ×
//! speed and its change through a variable lead) cannot be joined at speed from rest, so the axis
//! starts earlier, at a start angle shifted by a constant lag, accelerates with its own
//! acceleration and meets the law tangentially: from then on it is exactly where the spindle's
//! angle puts it, the same groove on every pass. Before the end it leaves the law and decelerates
//! to rest at the end point, on an interpolation tick.

use super::{Piece, Profile, MAX_PIECES, NO_PIECE};
use crate::units::{ceil_to, Micros};

/// The lag (µs) by which a catch-up ramp at `a` nm/µs² starts before the lock law's origin, for a
/// law of speed `v0` nm/µs at its origin and acceleration `acc` nm/µs² (`acc < a`): the root of
/// `a·acc·τ² + 2·a·v0·τ + v0² = 0` in its stable form (`v0 / 2a` for a constant lead).
pub fn catch_up_lag(v0: f64, acc: f64, a: f64) -> f64 {
    v0 / (a + (a * (a - acc)).max(0.0).sqrt())
}

impl Profile {
    /// A pass of `dist` nm (> 0) whose lock law has speed `v0` nm/µs (> 0) and acceleration `acc`
    /// nm/µs² at its origin `t_s` µs after the motion's start (`t_s > 0`, about
    /// [`catch_up_lag`]); the motion starts `t0` µs after a tick of `period`. The ramp's
    /// acceleration is the one that meets the law tangentially from rest at 0 (the design
    /// acceleration `a`, to the µs the start was rounded to); the deceleration at `a` takes the
    /// rounding of the end to a tick by leaving the law that much earlier (the distance is kept).
    /// A pass too short to reach the law is a trapezoid at up to the law's speed at its end.
    pub fn catch_up(dist: f64, v0: f64, acc: f64, t_s: f64, a: f64, period: Micros, t0: Micros) -> Profile {
        let period = period.max(1);
        let lock_s = |t: f64| v0 * (t - t_s) + 0.5 * acc * (t - t_s) * (t - t_s);
        let lock_v = |t: f64| v0 + acc * (t - t_s);
        let fallback = || {
            let v_end = (v0 * v0 + 2.0 * acc * dist).max(0.0).sqrt().max(v0);
            Profile::trapezoid(dist, v_end, a, period)
        };
        if !(dist > 0.0 && v0 > 0.0 && t_s > 0.0 && a > acc && a.is_finite()) {
            return fallback();
        }
        // The ramp: tangency from rest at 0 with the law (a·acc·t_s² − 2·a·v0·t_s + v0² = 0).
        let denom = t_s * (2.0 * v0 - acc * t_s);
        if denom <= 0.0 {
            return fallback();
        }
        let a1 = v0 * v0 / denom;
        if a1.is_nan() || a1 <= acc || lock_v(0.0) <= 0.0 {
            return fallback();
        }
        let t1 = lock_v(0.0) / (a1 - acc);
        // Leaving the law: the latest x with lock_s(x) + v(x)²/2a ≤ dist, then the stop.
        let reach = |x: f64| lock_s(x) + lock_v(x) * lock_v(x) / (2.0 * a) - dist;
        if reach(t1) > 0.0 {
            return fallback();
        }
        let mut hi = t1 + 1.0;
        while reach(hi) < 0.0 && lock_v(hi) > 0.0 {
            hi = t1 + 2.0 * (hi - t1);
            if hi > 1e13 {
                return fallback();
            }
        }
        let x_ideal = bisect(t1, hi, reach);
        let end_ideal = x_ideal + lock_v(x_ideal) / a;
        let end = (ceil_to(t0 + (end_ideal.ceil() as Micros).max(1), period) - t0) as f64;
        // With the end on the tick: a uniform deceleration from (lock_s(x), lock_v(x)) over
        // end − x covers the rest exactly.
        let cover = |x: f64| lock_s(x) + 0.5 * lock_v(x) * (end - x) - dist;
        if cover(t1) > 0.0 {
            return fallback();
        }
        let x = bisect(t1, x_ideal, cover);
        let (sx, vx) = (lock_s(x), lock_v(x));
        let mut pieces = [NO_PIECE; MAX_PIECES];
        pieces[0] = Piece { t0: 0.0, s0: 0.0, v0: 0.0, a: a1 };
        pieces[1] = Piece { t0: t1, s0: lock_s(t1), v0: lock_v(t1), a: acc };
        pieces[2] = Piece { t0: x, s0: sx, v0: vx, a: -vx / (end - x) };
        Profile { pieces, n: 3, dist, total: end as Micros }
    }
}

/// The x in [lo, hi] where the non-decreasing `f` crosses 0 (f(lo) ≤ 0 ≤ f(hi)), to 1e-6 µs.
fn bisect(mut lo: f64, mut hi: f64, f: impl Fn(f64) -> f64) -> f64 {
    for _ in 0..200 {
        if hi - lo < 1e-6 {
            break;
        }
        let mid = 0.5 * (lo + hi);
        if f(mid) <= 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples of a profile every `step` µs: (t, s, v).
    fn samples(p: &Profile, step: Micros) -> Vec<(f64, f64, f64)> {
        (0..=p.total / step).map(|k| k * step).map(|t| (t as f64, p.eval(t).0, p.eval(t).1)).collect()
    }

    #[test]
    fn a_constant_lead_is_caught_up_at_the_axis_acceleration_and_then_followed_exactly() {
        // 2 mm lead at 1000 rpm: 33.3 nm/µs; a = 1333 mm/s² = 1.333e-3 nm/µs²; 30 mm.
        let (v0, a, dist) = (2e6 * 1000.0 / 60e6, 1.333e-3, 30e6);
        let t_s = catch_up_lag(v0, 0.0, a);
        assert!((t_s - v0 / (2.0 * a)).abs() < 1e-9);
        let p = Profile::catch_up(dist, v0, 0.0, t_s, a, 1000, 300);
        assert_eq!((p.total + 300) % 1000, 0, "ends on a tick");
        assert_eq!(p.eval(p.total), (dist, 0.0));
        let mut on_law = 0;
        let mut last_v = 0.0;
        for (t, s, v) in samples(&p, 100) {
            assert!((v - last_v).abs() <= a * 100.0 * (1.0 + 1e-6) + 1e-9, "{t}: {last_v} → {v}");
            last_v = v;
            // Once caught up (2·t_s) and before the deceleration, exactly on v0·(t − t_s).
            if t >= 2.0 * t_s && s < dist - v0 * v0 / (2.0 * a) - v0 * 1000.0 {
                assert!((s - v0 * (t - t_s)).abs() < 1e-3, "{t}: {s}");
                on_law += 1;
            }
        }
        assert!(on_law > 5000, "{on_law}");
    }

    #[test]
    fn a_variable_lead_is_met_tangentially_and_followed_to_the_end() {
        // Lead 4 mm growing 0.1 mm per turn at 500 rpm (seed 002's example).
        let r = 500.0 / 60e6;
        let (v0, acc, a, dist) = (4e6 * r, 0.1e6 * r * r, 1.333e-3, 25e6);
        let t_s = catch_up_lag(v0, acc, a);
        let p = Profile::catch_up(dist, v0, acc, t_s + 0.3, a, 1000, 0);
        assert_eq!(p.total % 1000, 0);
        let law = |t: f64| v0 * (t - t_s - 0.3) + 0.5 * acc * (t - t_s - 0.3).powi(2);
        let mut prev = (0.0, 0.0);
        let mut on_law = 0;
        for (t, s, v) in samples(&p, 50) {
            assert!((v - prev.1).abs() <= a * 50.0 * (1.0 + 1e-4) + 1e-9, "{t}");
            assert!(s >= prev.0, "never backwards");
            prev = (s, v);
            if (s - law(t)).abs() < 1e-3 {
                on_law += 1;
            }
        }
        // About 0.75 s of pass: all but its ramps on the law.
        assert!(on_law * 50 > p.total * 4 / 5, "{on_law} of {}", p.total);
        // A lead change faster than the axis can follow, or no room to lock: an ordinary ramp.
        let q = Profile::catch_up(1e5, v0, 0.0, catch_up_lag(v0, 0.0, a), a, 1000, 0);
        assert_eq!(q.eval(q.total).0, 1e5);
    }
}
