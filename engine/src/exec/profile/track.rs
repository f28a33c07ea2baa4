//! A synchronised segment that starts from rest behind its spindle and catches it up the way
//! LinuxCNC's position synchronisation does (tp.c `tpSyncPositionMode`, "tracking" once the first
//! segment of a run of synchronised moves has matched the spindle): each servo cycle the
//! segment's speed command is the spindle's speed plus `√(|error| × a)`, followed within the
//! segment's acceleration `a`. From rest with an error `e0` behind a law moving at `v`, the axis
//! accelerates at `a` until its speed is `v + √(e·a)`; from there the error closes as
//! `√e` falls linearly, i.e. the axis decelerates at `a/2` onto `v` exactly as the error reaches
//! 0, then cruises on the law; before the end it decelerates at `a` to rest at the end point
//! (the segment ends at rest: exact stop, DEC-147).

use super::{Piece, Profile, MAX_PIECES, NO_PIECE};
use crate::units::{ceil_to, Micros};

impl Profile {
    /// A segment of `dist` nm (> 0) that starts at rest `e0` nm behind a law moving at `v` nm/µs
    /// (> 0) and tracks it with the acceleration `a` nm/µs², ending at rest at `dist`; the motion
    /// starts `t0` µs after a tick of `period` and its end is held to the next tick. An error of
    /// 0 or less (not behind) is an ordinary thread ramp ([`Profile::thread`]).
    pub fn tracking(dist: f64, v: f64, e0: f64, a: f64, period: Micros, t0: Micros) -> Profile {
        let period = period.max(1);
        if !(dist > 0.0 && v > 0.0 && v.is_finite() && e0 > 0.0 && e0.is_finite() && a > 0.0 && a.is_finite())
        {
            return Profile::thread(dist, v, a, period, t0);
        }
        // Accelerate at a until the speed is v + √(e·a): u = that excess, u² = (2·a·e0 + v²)/3.
        let u = ((2.0 * a * e0 + v * v) / 3.0).sqrt();
        let v1 = v + u;
        let t1 = v1 / a;
        let s1 = 0.5 * a * t1 * t1;
        // Then the excess falls at a/2 to 0 while the error closes.
        let t2 = 2.0 * u / a;
        let s2 = s1 + 0.5 * (v1 + v) * t2;
        let free = [
            Piece { t0: 0.0, s0: 0.0, v0: 0.0, a },
            Piece { t0: t1, s0: s1, v0: v1, a: -0.5 * a },
            Piece { t0: t1 + t2, s0: s2, v0: v, a: 0.0 },
        ];
        // Where the distance to stop at a reaches the end: the first piece in which s + v²/2a
        // (increasing while the axis moves forward) passes `dist`.
        let reach = |p: &Piece, dt: f64| {
            let s = p.s0 + p.v0 * dt + 0.5 * p.a * dt * dt;
            let w = p.v0 + p.a * dt;
            s + w * w / (2.0 * a)
        };
        let mut pieces = [NO_PIECE; MAX_PIECES];
        let mut n = 0;
        let mut brake = None;
        for (i, p) in free.iter().enumerate() {
            let len = free.get(i + 1).map_or(f64::INFINITY, |q| q.t0 - p.t0);
            pieces[n] = *p;
            n += 1;
            let end = if len.is_finite() { len } else { (dist / v).max(1.0) + t1 + t2 };
            if reach(p, end) >= dist {
                // reach() increases within the piece.
                let (lo, _) = super::bisect(|t| reach(p, t), dist, end, 64);
                let s = p.s0 + p.v0 * lo + 0.5 * p.a * lo * lo;
                let w = (p.v0 + p.a * lo).max(0.0);
                brake = Some((p.t0 + lo, s, w));
                break;
            }
        }
        let Some((tb, sb, vb)) = brake else { return Profile::thread(dist, v, a, period, t0) };
        let decel = if vb > 0.0 { vb * vb / (2.0 * (dist - sb).max(1e-9)) } else { a };
        pieces[n] = Piece { t0: tb, s0: sb, v0: vb, a: -decel };
        n += 1;
        let t_end = tb + if decel > 0.0 { vb / decel } else { 0.0 };
        pieces[n] = Piece { t0: t_end, s0: dist, v0: 0.0, a: 0.0 };
        n += 1;
        let total = ceil_to(t0 + (t_end.ceil() as Micros).max(1), period) - t0;
        Profile { pieces, n, dist, total }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_rest_behind_the_law_it_overshoots_the_spindle_speed_then_settles_on_the_law() {
        // LinuxCNC through the adapter (g76/passes, S600, 1.5 mm lead, Z at 1000 mm/s²): the
        // exit taper starts at rest 0.1125 mm behind; the recorded Z speed peaks at 27.45 mm/s
        // 29 ms later and is back at 15 mm/s about 52 ms after the start.
        // nm/µs = mm/s; nm/µs² × 1e6 = mm/s².
        let (v, a, e0, dist) = (15.0, 1e-3, 0.1125e6, 2.0e6);
        let p = Profile::tracking(dist, v, e0, a, 1000, 0);
        assert_eq!(p.total % 1000, 0);
        assert_eq!(p.eval(p.total), (dist, 0.0));
        let peak = (0..p.total).step_by(100).map(|t| p.eval(t).1).fold(0.0, f64::max);
        assert!((peak - 27.25).abs() < 0.05, "peak {peak} mm/s");
        // On the law (e0 + v·t) once the error has closed, until the braking.
        let (_, v60) = p.eval(60_000);
        assert!((v60 - v).abs() < 1e-9, "{v60}");
        let s60 = p.eval(60_000).0;
        assert!((s60 - (e0 + v * 60_000.0)).abs() < 1.0, "{s60}");
        let mut last = (0.0, 0.0);
        for t in (0..=p.total).step_by(50) {
            let (s, w) = p.eval(t);
            assert!(s >= last.0 && (w - last.1).abs() <= a * 50.0 * (1.0 + 1e-9) + 1e-12, "{t}");
            last = (s, w);
        }
    }

    #[test]
    fn a_short_segment_brakes_before_it_has_caught_up() {
        let (v, a, e0) = (15.0, 1e-3, 0.1125e6);
        let p = Profile::tracking(0.3e6, v, e0, a, 1000, 0);
        assert_eq!(p.eval(p.total), (0.3e6, 0.0));
        let peak = (0..p.total).step_by(100).map(|t| p.eval(t).1).fold(0.0, f64::max);
        assert!(peak < 27.2 && peak > 0.0, "{peak}");
        // Not behind: an ordinary ramp to v.
        let q = Profile::tracking(1e6, v, 0.0, a, 1000, 0);
        assert_eq!(q, Profile::thread(1e6, v, a, 1000, 0));
    }
}
