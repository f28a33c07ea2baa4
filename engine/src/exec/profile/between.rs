//! A motion that starts and ends at given speeds: a segment of a blended path (LinuxCNC 2.9's
//! blend arc between two moves, DEC-164), entered at the speed the previous segment leaves with
//! and left at the speed the next one takes up.

use super::{Piece, Profile, MAX_PIECES, NO_PIECE};
use crate::units::{ceil_to, Micros};

impl Profile {
    /// `dist` nm from speed `v0` to speed `v1` (nm/µs), at most `v` in between, changing speed at
    /// `a` nm/µs² (accelerate, cruise, decelerate). Where `dist` is too short to go from `v0` to
    /// `v1` at `a`, the speed changes evenly over it (the caller keeps that case small). The
    /// duration is rounded up to the µs (to whole `period`s from rest to rest) by slowing the
    /// whole profile evenly.
    pub fn between(dist: f64, v0: f64, v: f64, v1: f64, a: f64, period: Micros) -> Profile {
        let (v0, v1) = (v0.max(0.0), v1.max(0.0));
        if !(dist > 0.0 && v > 0.0 && v.is_finite() && a > 0.0 && a.is_finite()) {
            return Profile::still();
        }
        if v0 == 0.0 && v1 == 0.0 {
            return Profile::trapezoid(dist, v, a, period);
        }
        let (v0, v1) = (v0.min(v), v1.min(v));
        // The peak: v, or where the ramps from v0 up and down to v1 meet.
        let d_ramps = |p: f64| (2.0 * p * p - v0 * v0 - v1 * v1) / (2.0 * a);
        let (mut peak, mut a_up, mut a_down) = (v, a, a);
        if d_ramps(v) > dist {
            peak = ((2.0 * a * dist + v0 * v0 + v1 * v1) / 2.0).sqrt();
        }
        if peak < v0.max(v1) {
            // Too short even for one ramp from v0 to v1: an even change over the distance.
            peak = v0.max(v1);
            let even = (v1 * v1 - v0 * v0) / (2.0 * dist);
            (a_up, a_down) = if even >= 0.0 { (even, a) } else { (a, -even) };
        }
        let t_up = if a_up > 0.0 { (peak - v0) / a_up } else { 0.0 };
        let t_down = if a_down > 0.0 { (peak - v1) / a_down } else { 0.0 };
        let s_up = 0.5 * (v0 + peak) * t_up;
        let s_down = 0.5 * (v1 + peak) * t_down;
        let t_cruise = ((dist - s_up - s_down) / peak).max(0.0);
        let ideal = t_up + t_cruise + t_down;
        if ideal.is_nan() || ideal <= 0.0 {
            return Profile::still();
        }
        // A segment entered or left at speed is part of a blended path: its ends fall within a
        // period (LinuxCNC's split cycle, tp.c `tpHandleSplitCycle`), so it is rounded to the
        // µs only, its speeds kept; one from rest to rest to whole periods.
        let step = if v0 > 0.0 || v1 > 0.0 { 1 } else { period.max(1) };
        let total = ceil_to((ideal.ceil() as Micros).max(1), step);
        let k = total as f64 / ideal;
        let (t_up, t_cruise) = (t_up * k, t_cruise * k);
        let mut pieces = [NO_PIECE; MAX_PIECES];
        pieces[0] = Piece { t0: 0.0, s0: 0.0, v0: v0 / k, a: a_up / (k * k) };
        pieces[1] = Piece { t0: t_up, s0: s_up, v0: peak / k, a: 0.0 };
        pieces[2] =
            Piece { t0: t_up + t_cruise, s0: s_up + peak * t_cruise / k, v0: peak / k, a: -a_down / (k * k) };
        Profile { pieces, n: 3, dist, total }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_segment_between_two_speeds_keeps_its_distance_and_limits() {
        // 2.67 mm from 30 mm/s at cruise into an arc at 30.48: no ramp at all; from rest to 30.48
        // over 5 mm at 508 mm/s²; from 30.48 down to rest over 10 mm.
        for (dist, v0, v, v1) in
            [(2.67e6, 30.48, 30.48, 30.48), (5e6, 0.0, 30.48, 30.48), (10e6, 30.48, 43.1, 0.0)]
        {
            let a = 508e-6;
            let p = Profile::between(dist, v0, v, v1, a, 1000);
            if v0 == 0.0 && v1 == 0.0 {
                assert!(p.total.is_multiple_of(1000), "{}", p.total);
            }
            assert!((p.eval(0).1 - v0).abs() < 0.02 * v, "{:?}", p.eval(0));
            assert!((p.end_speed() - v1).abs() < 0.02 * v, "{} vs {v1}", p.end_speed());
            let (mut s_last, mut v_last) = (0.0, p.eval(0).1);
            for t in 1..=p.total {
                let (s, vv) = p.eval(t);
                assert!(s >= s_last - 1e-6 && vv <= v * 1.0001, "{t}: {s} {vv}");
                assert!((vv - v_last).abs() <= a * 1.0001 + 1e-12 || t == p.total, "{t}: {v_last} → {vv}");
                (s_last, v_last) = (s, vv);
            }
            assert!((p.eval(p.total - 1).0 - dist).abs() < 0.05 * dist);
        }
    }
}
