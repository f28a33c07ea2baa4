//! A spindle override that acts on the turning spindle at once (`PlantConfig::
//! spindle_override_at_once`, LinuxCNC: motion's `spindle.N.speed-out` is the commanded speed ×
//! the override's scale in every servo period, LCNC-G331-04, LCNC-G76-04), and the moves that
//! follow the spindle re-planned from where they are: an axis following the spindle's encoder
//! (`Step::Follow`, G33.1) and a thread pass on its ramped law (`Step::Thread`, G33, G76).
//!
//! Knows no G code: it acts on the spindle's command and on the motion in progress.

use super::motion::{Motion, Path};
use super::profile::{Profile, Ramp};
use super::Exec;
use crate::plan::{FollowKind, Step};
use crate::trace::AXES;

impl Exec<'_> {
    /// The spindle override in force for speed-mode rotation: 100 % while the program holds the
    /// overrides (`Step::OverrideLock`).
    pub(super) fn spindle_ovr(&self) -> u32 {
        if self.override_locked {
            100
        } else {
            self.spindle_override
        }
    }

    /// The override in force may have changed (an input, the program's lock taken or released):
    /// with `spindle_override_at_once` a spindle turning in speed mode is commanded S × it now
    /// (ramping there), and a move following the spindle goes on from where it is at the new
    /// speed. Otherwise the override acts from the next speed command (COM-MOT-06).
    pub(super) fn spindle_override_changed(&mut self) {
        if !self.cfg.spindle_override_at_once
            || self.spindle.position_mode
            || self.spindle.stalled
            || self.css.is_some()
            || self.spindle.target == 0.0
        {
            return;
        }
        let max = self.cfg.spindle_max_rpm as f64;
        let rpm = (self.s_cmd as f64 * self.spindle_ovr() as f64 / 100.0).min(max);
        let target = rpm * self.spindle.target.signum();
        if rpm <= 0.0 || target == self.spindle.target {
            return;
        }
        self.spindle.command(self.now, target);
        self.spindle_changed();
        self.refollow();
    }

    /// The spindle's speed changed under a move that follows it: the rest of the move follows the
    /// new speed from the position and speed it has now. A move that could no longer end (the
    /// spindle brought to rest first) keeps its plan.
    fn refollow(&mut self) {
        let now = self.now;
        let Some(m) = &self.motion else { return };
        let dt = now.saturating_sub(m.t0);
        if dt >= m.duration() || m.locked {
            return;
        }
        let (_, rpm) = self.spindle.at(now);
        let ramp = self.spindle.ramp(now).unwrap_or(Ramp { rpm0: rpm, slope: 0.0, dur: 0.0 });
        let vmax = self.cfg.feed_max_nm_min / 60e6;
        let accel = vmax / self.cfg.feed_ramp_us.max(1) as f64;
        let here = m.pos(now);
        let follow = self
            .follow_step
            .filter(|(t0, f)| *t0 == m.t0 && matches!(f.kind, FollowKind::Cut | FollowKind::Through { .. }))
            .map(|(_, f)| f);
        let path = match (&m.path, follow, &self.motion_step) {
            (Path::Rapid { profiles, backlash }, Some(f), _) => {
                let p = &profiles[f.axis];
                let (s, v) = p.eval(dt);
                let per_rpm = f.lead_nm.max(1) as f64 / 60e6;
                let Some((q, v_end)) =
                    Profile::following_through_from(p.dist - s, v, per_rpm, ramp, vmax, accel)
                else {
                    return;
                };
                self.follow_v = Some((v_end, false));
                let mut profiles = [Profile::still(); AXES];
                let mut b = [0.0; AXES];
                profiles[f.axis] = q;
                b[f.axis] = (backlash[f.axis] - s).max(0.0);
                Path::Rapid { profiles, backlash: b }
            }
            (
                Path::Thread { profile: p, along, across, knots, n, dir, len, blend },
                None,
                Some(Step::Thread(t)),
            ) => {
                let (s, v) = p.eval(dt);
                let per_rpm = t.lead_nm.max(1.0) / 60e6;
                let period = self.cfg.period_us;
                let Some(q) = Profile::following_from(len - s, v, per_rpm, ramp, vmax, accel, period) else {
                    return;
                };
                // The knots measured from here, each with its blend.
                let mut k = [(0.0, here[*across] as f64); 4];
                let mut w = [0.0; 4];
                let mut used = 1;
                for (&(a, c), &bw) in knots[..*n].iter().zip(blend.iter()) {
                    if a > s && used < k.len() {
                        k[used] = (a - s, c);
                        w[used] = bw;
                        used += 1;
                    }
                }
                Path::Thread {
                    profile: q,
                    blend: w,
                    along: *along,
                    across: *across,
                    knots: k,
                    n: used,
                    dir: *dir,
                    len: len - s,
                }
            }
            _ => return,
        };
        let Some(old) = self.motion.take() else { return };
        if let Some((t0, _)) = &mut self.follow_step {
            *t0 = now;
        }
        self.cmd = here;
        self.motion = Some(Motion {
            t0: now,
            start: here,
            target: old.target,
            path_end: old.path_end,
            path,
            locked: false,
            lock_spindle: old.lock_spindle,
        });
    }
}
