//! LinuxCNC 2.9's trajectory planner, where it departs from the exact stop the executor models
//! otherwise (`PlantConfig::parabolic_half_accel`, `nc.trajectory_planner` 209, DEC-163).
//!
//! In 2.9 a move added under G64 gets the parabolic end condition (tc.c `tcSetupState`), and
//! every segment whose end condition is parabolic runs at half its acceleration for its whole
//! length (tc.c `tcGetOverallMaxAccel`: "scaled down by 1/2 so that the sum of the two does not
//! exceed the maximum", applied whether a blend follows or not). The end condition changes only
//! when the next move enters the planner's queue (tp.c `tpAddLine`: `handleModeChange`,
//! `tcFlagEarlyStop` and the blend arc or tangent set it to stop or tangent), so a move keeps it
//! when nothing follows it in the queue: the next command is one the task carries out only once
//! the motion has ended (emctaskmain.cc `emcTaskCheckPreconditions`: a rigid tap, a spindle,
//! coolant or tool command, a dwell, a stop, the program end). LinuxCNC fixed it after 2.9
//! (#4220: half acceleration only during an actual blend), which the default follows.
//!
//! Two G64 rapids, or two G64 feeds per minute, that turn are joined by 2.9's blend arc
//! (`blend.rs`, DEC-164; a thread pass and its exit taper: `pass_blend.rs`; a feed and a G2/G3
//! arc or two arcs: `arc_blend.rs`, `arc_join.rs`); two that continue tangentially run on through
//! the join (2.9's tangent join, a blend of no sweep). Not modelled (L-124): 2.9's parabolic
//! blend (`tpDoParabolicBlending`): such a pair stops exactly here, at full acceleration.

use std::collections::VecDeque;

use super::motion::Path;
use super::profile::Profile;
use super::{blend, Exec};
use crate::alarm::Alarm;
use crate::plan::{Feed, Pos, Step};
use crate::trace::AXES;

/// Blocks read ahead at most to find the next move (blocks that queue nothing, such as `G91`
/// or an o-word line, are looked through).
const LOOK_AHEAD_BLOCKS: usize = 16;

/// The slowest blend arc run, nm/µs (1 mm/s): below it the moves stop at the corner instead.
pub(super) const MIN_ARC_SPEED: f64 = 1.0;

/// What a step is to LinuxCNC's planner queue.
#[derive(PartialEq)]
enum Queue {
    /// Enters it as a move that the present move's end condition is decided against.
    Move,
    /// Waits for the motion to end before the task carries it out (a queue buster).
    Buster,
    /// Neither (modal bookkeeping, a phase, the at-speed wait of the next move).
    Quiet,
}

/// Whether a step is bookkeeping only: it neither moves nor waits for the motion (a phase, a
/// modal setting, the at-speed wait of the next move).
pub(super) fn is_bookkeeping(s: &Step) -> bool {
    queue_of(s) == Queue::Quiet
}

fn queue_of(s: &Step) -> Queue {
    match s {
        Step::Rapid { .. } | Step::Feed { .. } | Step::Arc { .. } | Step::Thread(_) | Step::More(_) => {
            Queue::Move
        }
        Step::Phase(_)
        | Step::HoldSuppress(_)
        | Step::OverrideLock(_)
        | Step::PathMode { .. }
        | Step::Css(_)
        | Step::Overload(_)
        | Step::AwaitAtSpeed
        | Step::SingleBlockStop
        | Step::Report(_) => Queue::Quiet,
        // G33.1 (RIGID_TAP), functions, dwells, stops, the end.
        _ => Queue::Buster,
    }
}

/// Blocks interpreted ahead of their turn, with what the interpreter made of each.
pub(super) type Ahead = VecDeque<Result<Vec<Step>, Alarm>>;

impl Exec<'_> {
    /// The acceleration factor of the move about to start: ½ for LinuxCNC 2.9's G64 move that no
    /// move follows in the planner's queue, 1 otherwise. Under single block the task gives
    /// motion one line at a time: nothing follows.
    pub(super) fn planner_accel_scale(&mut self) -> f64 {
        if !self.cfg.parabolic_half_accel || !self.path_continuous {
            return 1.0;
        }
        if !self.single_block && self.next_move().is_some() {
            1.0
        } else {
            0.5
        }
    }

    /// The move that follows the present one in the planner's queue, if one does before any queue
    /// buster, with the blend tolerance it gets (`upcoming_moves`).
    fn next_move(&mut self) -> Option<(Step, f64)> {
        self.upcoming_moves(1).pop().map(|(s, tol, _)| (s, tol))
    }

    /// Up to `n` moves that follow the present one in the planner's queue before any queue
    /// buster, each with the blend tolerance and the path mode (G64) it is queued with: looks
    /// through the steps queued, then reads blocks ahead (kept in `ahead` until their turn).
    pub(super) fn upcoming_moves(&mut self, n: usize) -> Vec<(Step, f64, bool)> {
        let mut out = Vec::new();
        let (mut tol, mut cont) = (self.path_tolerance, self.path_continuous);
        // Each step in order: Some(true) to stop looking.
        let mut take = |s: &Step, out: &mut Vec<(Step, f64, bool)>| match queue_of(s) {
            Queue::Move => {
                out.push((s.clone(), tol, cont));
                out.len() >= n
            }
            Queue::Buster => true,
            Queue::Quiet => {
                if let Step::PathMode { tolerance_nm, continuous } = s {
                    tol = *tolerance_nm as f64;
                    cont = *continuous;
                }
                false
            }
        };
        for s in &self.steps {
            if take(s, &mut out) {
                return out;
            }
        }
        for k in 0..LOOK_AHEAD_BLOCKS {
            if k == self.ahead.len() {
                let Some(block) = self.program.blocks.get(self.pc + k) else { return out };
                let mut read = Vec::new();
                let r = self.interp.block(block, &mut read).map(|()| read);
                self.ahead.push_back(r);
            }
            let Ok(steps) = &self.ahead[k] else { return out };
            for s in steps {
                if take(s, &mut out) {
                    return out;
                }
            }
        }
        out
    }

    /// LinuxCNC 2.9's G64 rapid or feed (DEC-164): when the next move in the queue is of the same
    /// kind (a rapid after a rapid, a feed per minute after one) and turns off this one's line,
    /// the two are joined by a blend arc (`blend::blend_arc`): this move runs to the arc's start
    /// and reaches it at the arc's speed, the arc runs before the next move (`start_blend_arc`),
    /// which starts at its end at that speed. A move entered from an arc starts at the arc's
    /// speed. `feed`: the feed of a feed move (None: a rapid). False: an ordinary move (any other
    /// planner, or nothing to blend and no speed to enter with).
    pub(super) fn start_blended_line(&mut self, target: Pos, scale: f64, feed: Option<Feed>) -> bool {
        let entry = self.entry.take();
        if !self.cfg.parabolic_half_accel || !self.cfg.coordinated_rapid {
            return false;
        }
        // A feed per minute at a feed override that acts (per revolution, dry run, a tapping
        // cycle's locked overrides or 0 % are left to the ordinary feed).
        let v_feed = match feed {
            None => None,
            Some(Feed::PerMin(f))
                if !self.dry_run
                    && !self.hold_suppressed
                    && !self.override_locked
                    && self.feed_override > 0 =>
            {
                Some(f * self.feed_override as f64 / 100.0 / 60e6)
            }
            Some(_) => return false,
        };
        let f = |p: Pos| [p[0] as f64, p[1] as f64, p[2] as f64];
        let (p0, p1) = (f(self.cmd), f(target));
        if (3..AXES).any(|i| target[i] != self.cmd[i]) {
            return false;
        }
        let len = ((p1[0] - p0[0]).powi(2) + (p1[1] - p0[1]).powi(2) + (p1[2] - p0[2]).powi(2)).sqrt();
        if len <= 0.0 {
            return false;
        }
        let (v0, nominal) = entry.unwrap_or((0.0, len));
        let rate = self.cfg.rapid_nm_min.map(|r| r / 60e6);
        let scale = if scale > 0.0 { scale } else { 1.0 };
        let acc: [f64; AXES] =
            std::array::from_fn(|i| rate[i] / self.cfg.rapid_ramp_us[i].max(1) as f64 * scale);
        let ahead =
            if self.path_continuous && !self.single_block { self.upcoming_moves(2) } else { Vec::new() };
        let same_plane = |q: &Pos| (3..AXES).all(|i| q[i] == target[i]);
        // The next move of the same kind, with the speed it asks for (a rapid: its maximum).
        let kin = |s: &Step| match (s, v_feed) {
            (Step::Rapid { target }, None) => Some((*target, f64::INFINITY)),
            (Step::Feed { target, feed: Feed::PerMin(fr) }, Some(_)) => {
                Some((*target, fr * self.feed_override as f64 / 100.0 / 60e6))
            }
            _ => None,
        };
        let next = ahead.first().and_then(|(s, tol2, _)| kin(s).map(|(p2, r2)| (p2, r2, *tol2)));
        let next = next.filter(|n| same_plane(&n.0));
        let req1 = v_feed.unwrap_or(f64::INFINITY);
        let feed_scale = if v_feed.is_some() { self.cfg.overrides.feed_max_pct as f64 / 100.0 } else { 1.0 };
        let tol1 = self.path_tolerance;
        let mut arc = next.and_then(|(p2, r2, tol2)| {
            blend::blend_arc([p0, p1, f(p2)], nominal, v0, rate, acc, [tol1, tol2], ([req1, r2], feed_scale))
                .map(|a| (a, p2))
        });
        // Straight on, or a kink too small for an arc: 2.9's tangent join (tp.c `tpSetupTangent`),
        // on at the lower speed asked, the next move able to stop by its end.
        if let (None, Some((p2, r2, _))) = (&arc, next) {
            let q2 = f(p2);
            let len2 = ((q2[0] - p1[0]).powi(2) + (q2[1] - p1[1]).powi(2) + (q2[2] - p1[2]).powi(2)).sqrt();
            if len2 > 1.0 {
                let u1 = [(p1[0] - p0[0]) / len, (p1[1] - p0[1]) / len, (p1[2] - p0[2]) / len];
                let u2 = [(q2[0] - p1[0]) / len2, (q2[1] - p1[1]) / len2, (q2[2] - p1[2]) / len2];
                let (r3, a3) = ([rate[0], rate[1], rate[2]], [acc[0], acc[1], acc[2]]);
                let (v1max, v2max) = (blend::along(u1, r3), blend::along(u2, r3));
                let v_max = (req1.min(r2) * feed_scale).min(v1max).min(v2max);
                if super::arc_blend::tangent_join_of(u1, u2, v_max, a3, false) {
                    let a1 = self.line_accel(u1, &acc, v_feed.is_some(), scale);
                    let a2 = self.line_accel(u2, &acc, v_feed.is_some(), 1.0);
                    let reach = (v0 * v0 + 2.0 * a1 * len).sqrt();
                    let v = req1.min(r2).min(v1max).min(v2max).min(reach).min((2.0 * a2 * len2).sqrt());
                    arc = Some((super::arc_blend::tangent_arc(p1, u1, v), p2));
                }
            }
        }
        // A feed into a G2/G3 arc: 2.9's line-to-arc blend (`arc_blend.rs`).
        if let (None, Some(v), Some((step, tol2, _))) = (&arc, v_feed, ahead.first()) {
            let line = (p0, p1, len, nominal, v0);
            arc = self.line_to_arc_blend(line, step, [tol1, *tol2], v, (rate, acc), feed_scale);
        }
        // The arc's speed lets the next move slow down to the arc after it, if one follows (the
        // planner's backward pass over its queue, tp.c `tpRunOptimization`), when the next move
        // is queued under G64.
        let next_continuous = ahead.first().is_some_and(|m| m.2);
        let after = ahead.get(1).and_then(|m| kin(&m.0).map(|(p3, r3)| (p3, r3, m.1)));
        if let (Some((a1, p2)), Some(n), Some((p3, r3, tol3)), true) =
            (arc.as_mut(), next, after, next_continuous)
        {
            let (q2, q3) = (f(*p2), f(p3));
            let len2 = ((q2[0] - p1[0]).powi(2) + (q2[1] - p1[1]).powi(2) + (q2[2] - p1[2]).powi(2)).sqrt();
            // As the next move will plan it: from the arc's end at the arc's speed, its nominal
            // length the whole move.
            let tols = [n.2, tol3];
            if let Some(a2) =
                blend::blend_arc([a1.end, q2, q3], len2, a1.v, rate, acc, tols, ([n.1, r3], feed_scale))
            {
                let u2 = [(q2[0] - p1[0]) / len2, (q2[1] - p1[1]) / len2, (q2[2] - p1[2]) / len2];
                let a_2 = self.line_accel(u2, &acc, v_feed.is_some(), 1.0);
                let room = (len2 - a1.trim - a2.trim).max(0.0);
                a1.v = a1.v.min((a2.v * a2.v + 2.0 * a_2 * room).sqrt());
            }
        }
        // An arc that would have to be taken at (almost) no speed is no arc: the moves stop.
        if arc.as_ref().is_some_and(|(a, _)| a.v < MIN_ARC_SPEED) {
            arc = None;
        }
        if arc.is_none() && v0 <= 0.0 {
            return false;
        }
        let u = [(p1[0] - p0[0]) / len, (p1[1] - p0[1]) / len, (p1[2] - p0[2]) / len];
        let mut vmax = blend::along(u, [rate[0], rate[1], rate[2]]);
        if let Some(v) = v_feed {
            vmax = vmax.min(v).min(self.cfg.feed_max_nm_min / 60e6);
        }
        let amax = self.line_accel(u, &acc, v_feed.is_some(), scale);
        let (end, dist, v1) = match &arc {
            Some((a, _)) => {
                let mut end = self.cmd;
                for i in 0..3 {
                    end[i] = crate::units::round_i64(a.start[i]);
                }
                (end, len - a.trim, a.v)
            }
            None => (target, len, 0.0),
        };
        let profile = Profile::between(dist.max(0.0), v0, vmax, v1, amax, self.cfg.period_us);
        if feed.is_none() {
            // Backlash is the joints' business (as `start_rapid`); the directions are kept.
            for i in 0..3 {
                let d = target[i] - self.cmd[i];
                if d != 0 {
                    self.backlash(i, d.signum() as i8);
                }
            }
        }
        self.start_motion(end, Path::Line { profile, len: dist.max(0.0) });
        if let Some((arc, next_target)) = arc {
            let p2 = f(next_target);
            let nominal2 =
                ((p2[0] - p1[0]).powi(2) + (p2[1] - p1[1]).powi(2) + (p2[2] - p1[2]).powi(2)).sqrt();
            self.blend = Some(PendingBlend { arc, next_target, nominal2 });
        }
        true
    }

    /// The acceleration of a straight move along `u`: a rapid's from the axes' (`acc`, already
    /// scaled), a feed's the cutting acceleration × `scale` (as `feed_profile`).
    fn line_accel(&self, u: [f64; 3], acc: &[f64; AXES], feed: bool, scale: f64) -> f64 {
        if feed {
            self.cfg.feed_max_nm_min / 60e6 / self.cfg.feed_ramp_us.max(1) as f64 * scale
        } else {
            blend::along(u, [acc[0], acc[1], acc[2]])
        }
    }

    /// Runs the blend arc planned by the move before (`start_blended_line`) ahead of the move
    /// `step` (a rapid or a feed to `target`), which is put back to start from the arc's end at
    /// its speed. False: no arc is pending for this move.
    pub(super) fn start_blend_arc(&mut self, step: &Step, target: Pos) -> bool {
        let Some(b) = self.blend.take() else { return false };
        if b.next_target != target {
            return false;
        }
        let a = &b.arc;
        // A tangent join (`arc_blend::tangent_arc`): no arc, the move starts at the speed.
        if a.sweep == 0.0 {
            self.entry = Some((a.v, b.nominal2));
            return false;
        }
        let len = a.radius * a.sweep;
        let profile = Profile::between(len, a.v, a.v, a.v, 1.0, self.cfg.period_us);
        let mut end = self.cmd;
        for i in 0..3 {
            end[i] = crate::units::round_i64(a.end[i]);
        }
        let path =
            Path::Bend { profile, len, center: a.center, u: a.u, w: a.w, radius: a.radius, sweep: a.sweep };
        self.start_motion(end, path);
        self.steps.push_front(step.clone());
        self.entry = Some((a.v, b.nominal2));
        true
    }

    /// A hold or a stop drops the blend planned ahead: the rest runs from where the axes stop.
    pub(super) fn drop_blend(&mut self) {
        self.blend = None;
        self.entry = None;
        self.pass_blend = None;
    }
}

/// A blend arc planned at the start of a rapid, to run before the next rapid.
#[derive(Debug, Clone)]
pub(super) struct PendingBlend {
    pub(super) arc: blend::Arc3,
    /// Where the next rapid ends.
    pub(super) next_target: Pos,
    /// The next rapid's nominal length (corner to end), nm.
    pub(super) nominal2: f64,
}
