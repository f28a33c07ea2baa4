//! LinuxCNC 2.9's G64 thread pass with an exit taper (DEC-164): its planner joins the two
//! synchronised segments with a blend arc as it joins two rapids (`blend::blend_arc`), and the
//! arc and the taper follow the spindle along their path at the taper's lead per revolution of
//! path (rs274 gives the taper `START_SPEED_FEED_SYNC` with the lead over the taper's Z share,
//! and the arc, made when the taper is queued, takes the planner's lead then).
//!
//! So the pass runs at its lead to the arc's start without stopping, and from there the arc and
//! the taper track the law period by period as tp.c `tpSyncPositionMode` does: the path's target
//! is the taper's lead × the revolutions since the main segment's law reached the arc's start
//! (tp.c `tpCompleteSegment` moves the synchronisation's offset on by the segment's length over
//! its lead); each period the speed asked is the law's speed plus √(|error| × a), reached within
//! a (the arc's tangential acceleration, half the plane's; the taper's own), and the taper stops
//! at its end (the rapid after it stops exactly). The exact-stop pass (DEC-147) is unchanged.

use super::blend::{self, Arc3};
use super::motion::Path;
use super::Exec;
use crate::plan::{PassLaw, Pos, Step, ThreadPass};
use crate::units::{Micros, Nm};

/// Most servo periods a blended taper may take (a safety bound; a few hundred in practice).
const MAX_POINTS: usize = 200_000;

/// A pass's blend arc, planned when the pass is split into its segments.
#[derive(Debug, Clone)]
pub(super) struct PassBlend {
    arc: Arc3,
    /// The taper's end (X, Y, Z), nm.
    end: [f64; 3],
    /// Unit direction of the taper.
    u2: [f64; 3],
    /// The taper's lead per revolution of path over the drive axis' lead.
    path_ratio: f64,
    /// The drive axis' travel from the pass' start to the arc's start, nm.
    trim_travel: f64,
    /// The taper's acceleration along its line, nm/µs².
    a_taper: f64,
}

fn f3(p: &[Nm]) -> [f64; 3] {
    [p[0] as f64, p[1] as f64, p[2] as f64]
}

impl Exec<'_> {
    /// For LinuxCNC 2.9's planner under G64, a pass whose thread is followed by one exit taper:
    /// the pass split so that the thread ends at the blend arc's start at speed, the taper
    /// step then running the arc and the taper (`start_pass_blend`); returns the arc's start,
    /// where the thread ends. None: split as DEC-147.
    pub(super) fn plan_pass_blend(&mut self, p: &ThreadPass) -> Option<Pos> {
        if !self.cfg.parabolic_half_accel || !self.path_continuous || p.n != 3 || p.along > 2 || p.across > 2
        {
            return None;
        }
        // The thread proper first (no infeed along it from where the tool stands), then the taper.
        if (p.knots[1].1 - self.cmd[p.across] as f64).abs() > 1.0 {
            return None;
        }
        let p0 = f3(&self.cmd);
        let mut joint = p0;
        joint[p.along] = p.knots[1].0;
        joint[p.across] = p.knots[1].1;
        let end = f3(&p.target);
        let rate = self.cfg.rapid_nm_min.map(|r| r / 60e6);
        let acc: [f64; crate::trace::AXES] =
            std::array::from_fn(|i| rate[i] / self.cfg.rapid_ramp_us[i].max(1) as f64);
        let nominal =
            ((joint[0] - p0[0]).powi(2) + (joint[1] - p0[1]).powi(2) + (joint[2] - p0[2]).powi(2)).sqrt();
        let tol = self.path_tolerance;
        let arc = blend::blend_arc(
            [p0, joint, end],
            nominal,
            0.0,
            rate,
            acc,
            [tol, tol],
            ([f64::INFINITY; 2], 1.0),
        )?;
        let d2 = [end[0] - joint[0], end[1] - joint[1], end[2] - joint[2]];
        let len2 = (d2[0] * d2[0] + d2[1] * d2[1] + d2[2] * d2[2]).sqrt();
        let along2 = d2[p.along].abs();
        if along2 <= 0.0 || len2 <= arc.trim {
            return None;
        }
        let u2 = [d2[0] / len2, d2[1] / len2, d2[2] / len2];
        let a_taper = blend::along(u2, [acc[0], acc[1], acc[2]]);
        let trim_travel = (arc.start[p.along] - p0[p.along]).abs();
        let mut trim_point = self.cmd;
        for i in 0..3 {
            trim_point[i] = crate::units::round_i64(arc.start[i]);
        }
        self.pass_blend = Some(PassBlend { arc, end, u2, path_ratio: len2 / along2, trim_travel, a_taper });
        Some(trim_point)
    }

    /// The speed (nm/µs) the thread of a blended pass ends with (the arc's limit), if the pass
    /// about to start is one.
    pub(super) fn pass_blend_entry(&self) -> Option<f64> {
        self.pass_blend.as_ref().map(|b| b.arc.v_plan)
    }

    /// Runs the arc and the taper of a blended pass from the arc's start (the taper step `p`).
    /// False: no blend is pending, the taper runs as DEC-147 has it.
    pub(super) fn start_pass_blend(&mut self, p: &ThreadPass) -> bool {
        if p.law != PassLaw::Tracking {
            return false;
        }
        let Some(b) = self.pass_blend.take() else { return false };
        let Some(lock) = self.sync_lock else { return false };
        let period = self.cfg.period_us.max(1);
        let (_, rpm) = self.spindle_at(self.now);
        // The path's target at `t`: the taper's lead × the revolutions since the thread's law
        // reached the arc's start.
        let target = |ex: &Exec, t: Micros| {
            let (angle, _) = ex.spindle_at(t);
            let law = lock.lead * (angle - lock.angle0) * lock.sign / 360.0 - lock.lag;
            (law - b.trim_travel) * b.path_ratio
        };
        let a = &b.arc;
        let l_arc = a.radius * a.sweep;
        let taper_start = a.end;
        let l_taper = ((b.end[0] - taper_start[0]).powi(2)
            + (b.end[1] - taper_start[1]).powi(2)
            + (b.end[2] - taper_start[2]).powi(2))
        .sqrt();
        let total = l_arc + l_taper;
        let geom = |s: f64| -> [f64; 3] {
            if s <= l_arc {
                let phi = s / a.radius;
                let (c, sn) = (libm::cos(phi), libm::sin(phi));
                std::array::from_fn(|i| a.center[i] + a.radius * (c * a.u[i] + sn * a.w[i]))
            } else {
                let r = (s - l_arc).min(l_taper);
                std::array::from_fn(|i| taper_start[i] + b.u2[i] * r)
            }
        };
        let a_arc = 0.5 * a.a_max;
        let dt = period as f64;
        // The arc's speed is its own maximum at most (tp.c `tpGetMaxTargetVel`: a synchronised
        // segment's maximum is the blend arc's planned speed); the thread ended at it.
        let (mut s, mut v) = (0.0, (rpm.abs() * p.lead_nm / 60e6).min(a.v_plan));
        let mut t = self.now;
        let mut last = target(self, t);
        let mut points = vec![geom(0.0)];
        while points.len() < MAX_POINTS {
            t += period;
            let goal = target(self, t);
            let v_law = (goal - last) / dt;
            last = goal;
            let err = goal - s;
            let acc = if s < l_arc { a_arc } else { b.a_taper };
            let mut want = v_law + (err.abs() * acc).sqrt().copysign(err);
            // Slow enough to stop at the taper's end within the period's steps (tp.c
            // `tpCalculateTrapezoidalAccel`'s discriminant, final speed 0).
            let half = 0.5 * b.a_taper * dt;
            let disc = b.a_taper * (2.0 * (total - s) - v * dt) + half * half;
            let stop = if disc > half * half { disc.sqrt() - half } else { 0.0 };
            want = want.clamp(0.0, stop);
            if s < l_arc {
                // Within the arc's own limit, and slow enough to take the taper's limit at its end.
                want = want.min(a.v_plan);
            }
            let v1 = v + (want - v).clamp(-acc * dt, acc * dt);
            s = (s + 0.5 * (v + v1) * dt).min(total);
            v = v1;
            points.push(geom(s));
            if total - s < 1.0 {
                *points.last_mut().expect("a point") = geom(total);
                break;
            }
        }
        let mut end = p.target;
        for i in 0..3 {
            end[i] = crate::units::round_i64(b.end[i]);
        }
        for axis in [p.along, p.across] {
            let d = end[axis] - self.cmd[axis];
            if d != 0 {
                self.backlash(axis, d.signum() as i8);
            }
        }
        self.start_motion(end, Path::Track { step: period, points });
        if let Some(m) = &mut self.motion {
            m.lock_spindle = false;
        }
        true
    }
}

/// The steps of a blended pass: the thread to the arc's start (accelerated, ending at speed),
/// then the taper step that runs the arc and the taper.
pub(super) fn blended_steps(p: &ThreadPass, trim: Pos) -> [Step; 2] {
    let mut thread = *p;
    thread.target = trim;
    thread.knots = [p.knots[0], (trim[p.along] as f64, p.knots[1].1), (0.0, 0.0), (0.0, 0.0)];
    thread.n = 2;
    thread.thread = 0;
    thread.law = PassLaw::Accelerated { room: None };
    let mut taper = *p;
    taper.knots = [p.knots[1], p.knots[2], (0.0, 0.0), (0.0, 0.0)];
    taper.n = 2;
    taper.thread = 0;
    taper.law = PassLaw::Tracking;
    [Step::Thread(thread), Step::Thread(taper)]
}
