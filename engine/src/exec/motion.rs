//! The axes' motions: rapid (each axis on its own), linear and circular interpolation, the
//! synchronised tapping stroke where the tap axis follows the spindle, and the thread pass. Positions are evaluated in
//! closed form at any time.

use super::profile::Profile;
use crate::plan::{Plane, Pos};
use crate::trace::AXES;
use crate::units::{Micros, Nm};

/// The geometry of a motion.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq)]
pub enum Path {
    /// Each axis its own profile; `backlash` nm of motor travel precede the table's motion.
    Rapid {
        /// Per-axis distance profiles.
        profiles: [Profile; AXES],
        /// Backlash taken up first, per axis, nm.
        backlash: [f64; AXES],
    },
    /// Straight line, one profile along the path.
    Line {
        /// Path profile.
        profile: Profile,
        /// Path length, nm.
        len: f64,
    },
    /// Circle or helix in a plane; other axes move linearly with the angle.
    Arc {
        /// Path profile.
        profile: Profile,
        /// Path length, nm.
        len: f64,
        /// Centre (first, second axis of the plane).
        center: [f64; 2],
        /// Radius at the start, nm.
        radius: f64,
        /// Radius at the end, nm (differs from `radius` on a spiral).
        radius_end: f64,
        /// Start angle, rad.
        a0: f64,
        /// Signed sweep, rad.
        sweep: f64,
        /// Plane.
        plane: Plane,
    },
    /// Rigid tapping stroke: the profile is the motor travel of the tap axis (backlash included);
    /// the spindle turns travel / lead revolutions.
    Tap {
        /// Motor travel profile, nm.
        profile: Profile,
        /// Tap axis slot.
        axis: usize,
        /// Backlash taken up first, nm.
        backlash: f64,
        /// Lead, nm/rev.
        lead: f64,
        /// Spindle direction, +1 forward.
        spin: f64,
    },
    /// A spindle-synchronised thread pass: the drive axis travels as `law` gives; the infeed
    /// axis is a function of that travel through the knots; other axes move linearly with it.
    Thread {
        /// The drive axis' travel against time.
        law: Law,
        /// Drive axis slot.
        along: usize,
        /// Infeed axis slot.
        across: usize,
        /// (travel from the start, infeed position) of each knot, nm.
        knots: [(f64, f64); 4],
        /// Knots used.
        n: usize,
        /// Direction of the travel on the drive axis, ±1.
        dir: f64,
        /// Travel of the drive axis, nm (> 0).
        len: f64,
    },
}

/// How a thread pass' drive axis travels with time.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Law {
    /// Locked to a spindle turning at a steady speed: `lead·n + dlead·n²/2` after `n`
    /// revolutions since the start angle.
    Locked {
        /// Revolutions per µs (> 0).
        rev_us: f64,
        /// Revolutions since the start angle when the motion started (within a µs of 0).
        n0: f64,
        /// Lead at the start, nm/rev.
        lead: f64,
        /// Lead change, nm/rev².
        dlead: f64,
        /// Duration, µs (ends on an interpolation tick).
        total: Micros,
    },
    /// A profile accelerating to exactly lead × speed, cruising at it, decelerating to the end.
    Ramped(Profile),
}

impl Law {
    /// Travel (nm, clamped to `len`) and speed (nm/µs) `dt` µs after the start.
    pub fn eval(&self, dt: Micros, len: f64) -> (f64, f64) {
        match self {
            Law::Locked { rev_us, n0, lead, dlead, total } => {
                let n = n0 + rev_us * dt.min(*total) as f64;
                ((lead * n + 0.5 * dlead * n * n).clamp(0.0, len), rev_us * (lead + dlead * n))
            }
            Law::Ramped(p) => p.eval(dt),
        }
    }

    fn total(&self) -> Micros {
        match self {
            Law::Locked { total, .. } => *total,
            Law::Ramped(p) => p.total,
        }
    }
}

/// A rapid as one coordinated straight line over `delta` (nm per axis): the path's speed and
/// acceleration are the largest that keep every axis within its own rapid rate (nm/min) and
/// acceleration (rate over its time constant, µs) for its share of the path, so the slowest axis
/// for its share sets them and every axis starts and ends together (LinuxCNC's G0).
pub fn coordinated_rapid(
    delta: [f64; AXES],
    rate_nm_min: [f64; AXES],
    ramp_us: [Micros; AXES],
    period: Micros,
) -> Path {
    let len = delta.iter().map(|d| d * d).sum::<f64>().sqrt();
    let (mut v, mut a) = (f64::INFINITY, f64::INFINITY);
    for i in 0..AXES {
        if delta[i] != 0.0 {
            let share = len / delta[i].abs();
            let vi = rate_nm_min[i] / 60e6;
            v = v.min(vi * share);
            a = a.min(vi / ramp_us[i].max(1) as f64 * share);
        }
    }
    if !v.is_finite() {
        return Path::Line { profile: Profile::still(), len: 0.0 };
    }
    Path::Line { profile: Profile::trapezoid(len, v, a, period), len }
}

/// One motion in progress.
#[derive(Debug, Clone, PartialEq)]
pub struct Motion {
    /// Start time.
    pub t0: Micros,
    /// Command positions at the start.
    pub start: Pos,
    /// Command positions at the end (where a stopped motion comes to rest).
    pub target: Pos,
    /// The end of the path as planned: lines and arcs are interpolated towards it, also after a
    /// stop has made `target` a point on the way.
    pub path_end: Pos,
    /// Geometry and timing.
    pub path: Path,
    /// Machine lock was on when the motion started: the machine stays still for the whole motion
    /// (COM-MOT-04). A lock switched during a motion acts from the next one (COM-INP-10).
    pub locked: bool,
    /// Under that lock the spindle stands too: a rigid tapping stroke, whose spindle is an axis in
    /// position mode (COM-MOT-04). A speed-mode spindle that the axis follows (KND G93) turns.
    pub lock_spindle: bool,
}

impl Motion {
    /// Duration, µs.
    pub fn duration(&self) -> Micros {
        match &self.path {
            Path::Rapid { profiles, .. } => profiles.iter().map(|p| p.total).max().unwrap_or(0),
            Path::Line { profile, .. } | Path::Arc { profile, .. } | Path::Tap { profile, .. } => {
                profile.total
            }
            Path::Thread { law, .. } => law.total(),
        }
    }

    /// End time.
    pub fn end(&self) -> Micros {
        self.t0 + self.duration()
    }

    /// Command positions at `t` (the target once the motion has ended).
    pub fn pos(&self, t: Micros) -> Pos {
        if t.saturating_sub(self.t0) >= self.duration() {
            self.target
        } else {
            self.pos_unclamped(t)
        }
    }

    /// For a tapping stroke: the spindle's turned angle (deg, signed) and speed (rpm, signed) at `t`.
    pub fn spindle(&self, t: Micros) -> Option<(f64, f64)> {
        match &self.path {
            Path::Tap { profile, lead, spin, .. } => {
                let (s, v) = profile.eval(t.saturating_sub(self.t0));
                Some((spin * s / lead * 360.0, spin * v / lead * 60e6))
            }
            _ => None,
        }
    }

    /// The tap axis' travel speed (nm/µs) at `t`, for stopping.
    pub fn speed(&self, t: Micros) -> f64 {
        let dt = t.saturating_sub(self.t0);
        match &self.path {
            Path::Rapid { profiles, .. } => profiles.iter().map(|p| p.eval(dt).1).fold(0.0, f64::max),
            Path::Line { profile, .. } | Path::Arc { profile, .. } | Path::Tap { profile, .. } => {
                profile.eval(dt).1
            }
            Path::Thread { law, len, .. } => law.eval(dt, *len).1,
        }
    }

    /// Replaces the profile(s) by a stop as soon as possible from `t`, decelerating at `a`
    /// nm/µs² (per-axis rates for rapids use `a` too). The target becomes the stopping point.
    pub fn stop_at(&mut self, t: Micros, a: f64, period: Micros) {
        let dt = t.saturating_sub(self.t0);
        let elapsed = dt;
        if let Path::Thread { law: Law::Locked { .. }, .. } = self.path {
            // A thread is locked to the spindle: it cannot run on along a braking profile; the
            // axes stop where they are (a thread retract pulls out from there).
            let here = self.pos_unclamped(t);
            // Under machine lock the machine stayed at the start: keep it there (the lock offset
            // takes the travel at the end; found by the physics census, INV-07).
            if !self.locked {
                self.start = here;
            }
            self.target = here;
            self.path_end = here;
            self.t0 = t;
            self.path = Path::Rapid { profiles: [Profile::still(); AXES], backlash: [0.0; AXES] };
            return;
        }
        match &mut self.path {
            Path::Rapid { profiles, .. } => {
                for p in profiles.iter_mut() {
                    *p = p.stop_from(dt, a, period);
                }
            }
            Path::Line { profile, .. }
            | Path::Arc { profile, .. }
            | Path::Tap { profile, .. }
            | Path::Thread { law: Law::Ramped(profile), .. } => *profile = profile.stop_from(dt, a, period),
            Path::Thread { law: Law::Locked { .. }, .. } => {}
        }
        // Re-anchor: the new profiles start at `t` and measure from the old start.
        self.t0 += elapsed;
        let end = self.t0 + self.duration();
        let stop = self.pos_unclamped(end);
        self.target = stop;
    }

    /// Positions from the profile alone (also past its end: where a stopped motion comes to rest).
    fn pos_unclamped(&self, t: Micros) -> Pos {
        let m = self;
        let dt = t.saturating_sub(m.t0);
        let mut p = m.start;
        match &m.path {
            Path::Rapid { profiles, backlash } => {
                for i in 0..AXES {
                    let d = m.target[i] - m.start[i];
                    if d != 0 {
                        let s = (profiles[i].eval(dt).0 - backlash[i]).max(0.0);
                        p[i] = m.start[i] + (d.signum() as f64 * s).round() as Nm;
                    }
                }
            }
            Path::Line { profile, len } => {
                let f = if *len > 0.0 { profile.eval(dt).0 / len } else { 1.0 };
                for i in 0..AXES {
                    p[i] = m.start[i] + ((m.path_end[i] - m.start[i]) as f64 * f).round() as Nm;
                }
            }
            Path::Arc { profile, len, center, radius, radius_end, a0, sweep, plane } => {
                let f = profile.eval(dt).0 / len.max(1.0);
                let (i0, i1, _) = plane.axes();
                for i in 0..AXES {
                    p[i] = m.start[i] + ((m.path_end[i] - m.start[i]) as f64 * f).round() as Nm;
                }
                let a = a0 + sweep * f;
                let r = radius + (radius_end - radius) * f;
                p[i0] = (center[0] + r * libm::cos(a)).round() as Nm;
                p[i1] = (center[1] + r * libm::sin(a)).round() as Nm;
            }
            Path::Tap { profile, axis, backlash, .. } => {
                let d = m.target[*axis] - m.start[*axis];
                let s = (profile.eval(dt).0 - backlash).max(0.0);
                p[*axis] = m.start[*axis] + (d.signum() as f64 * s).round() as Nm;
            }
            Path::Thread { law, along, across, knots, n, dir, len } => {
                let s = law.eval(dt, *len).0;
                for i in 0..AXES {
                    p[i] = m.start[i] + ((m.path_end[i] - m.start[i]) as f64 * s / len).round() as Nm;
                }
                p[*along] = m.start[*along] + (dir * s).round() as Nm;
                p[*across] = across_at(&knots[..*n], s).round() as Nm;
            }
        }
        p
    }
}

/// The infeed position at `s` along a thread pass: linear between knots, constant beyond.
fn across_at(knots: &[(f64, f64)], s: f64) -> f64 {
    let Some(&(_, mut c)) = knots.first() else { return 0.0 };
    for w in knots.windows(2) {
        let ((s0, c0), (s1, c1)) = (w[0], w[1]);
        if s >= s1 {
            c = c1;
        } else if s > s0 && s1 > s0 {
            return c0 + (c1 - c0) * (s - s0) / (s1 - s0);
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stopped_line_decelerates_along_its_path_and_rests_on_it() {
        // COM-INP-02: 20 mm along Z at 20 mm/s (20 nm/µs) with 1000 mm/s² (1e-3 nm/µs²).
        let (v, a) = (20.0, 1e-3);
        let len = 20e6;
        let mut target = [0; AXES];
        target[2] = -20_000_000;
        let path = Path::Line { profile: Profile::trapezoid(len, v, a, 1000), len };
        let mut m = Motion {
            t0: 0,
            start: [0; AXES],
            target,
            path_end: target,
            path,
            locked: false,
            lock_spindle: false,
        };
        let before = m.pos(300_000)[2];
        m.stop_at(300_000, a, 1000);
        // From 20 mm/s at 1000 mm/s² the stop takes 20 ms and 0.2 mm.
        assert_eq!(m.end(), 320_000);
        assert_eq!(m.pos(300_000)[2], before);
        let mut last = before;
        for t in (300_000..=320_000).step_by(1000) {
            let z = m.pos(t)[2];
            assert!(z <= last && z >= m.target[2], "{t}: {z}");
            last = z;
        }
        assert_eq!(m.target[2], last);
        assert!((m.target[2] - (before - 200_000)).abs() <= 1, "{}", m.target[2]);
    }
}
