//! Constant surface speed (KND G96, rules KND-CSS-*): the spindle's commanded speed follows the
//! X diameter of the command position — at every interpolation period of a cutting move (G01,
//! G02, G03), for the end point as a rapid starts (DEC-66), and not during a thread or a G93
//! cycle, which turn at the speed they started with (DEC-67).

use super::motion::Path;
use super::{Active, Exec};
use crate::plan::Css;
use crate::units::{Micros, Nm};

impl Exec<'_> {
    /// The speed constant surface speed asks for at machine X `x` (radius), rpm, unsigned: the
    /// surface-speed rpm times the spindle override, clamped by the G50 S limit and the machine.
    pub(super) fn css_speed(&self, css: &Css, x: Nm) -> f64 {
        let max = self.cfg.spindle_max_rpm;
        let limit = if css.limit_rpm > 0 { css.limit_rpm.min(max) } else { max } as f64;
        let ovr = self.spindle_ovr();
        (css.rpm(x, max) * ovr as f64 / 100.0).min(limit)
    }

    /// Commands the spindle (when it is turning, in speed mode) to the speed for machine X `x`.
    pub(super) fn css_follow(&mut self, x: Nm) {
        let Some(css) = self.css else { return };
        let dir = self.spindle.target.signum();
        if dir == 0.0 || self.spindle.position_mode || self.spindle.stalled {
            return;
        }
        let rpm = self.css_speed(&css, x) * dir;
        if rpm != self.spindle.target {
            self.spindle.command(self.now, rpm);
            self.spindle_changed();
        }
    }

    /// `Step::Css`: G96 on (or its S, limit or zero changed) or off. Off, the last speed stays
    /// commanded and becomes S (seed 001 CSS note 3).
    pub(super) fn css_set(&mut self, css: Option<Css>) {
        if let (Some(old), None) = (self.css, css) {
            self.s_cmd = old.rpm(self.cmd[0], self.cfg.spindle_max_rpm).round() as u32;
        }
        self.css = css;
        self.css_follow(self.cmd[0]);
    }

    /// Whether the speed is being followed along the present motion (a cutting move outside a
    /// thread or tapping cycle).
    pub(super) fn css_tracking(&self) -> bool {
        self.css.is_some()
            && !self.hold_suppressed
            && self.active == Active::Moving
            && self.motion.as_ref().is_some_and(|m| matches!(m.path, Path::Line { .. } | Path::Arc { .. }))
    }

    /// The next interpolation period after now at which the speed is updated, if any.
    pub(super) fn css_next(&self) -> Option<Micros> {
        self.css_tracking().then(|| (self.now / self.cfg.period_us + 1) * self.cfg.period_us)
    }

    /// At a period boundary during a cutting move: the speed for the X reached.
    pub(super) fn css_tick(&mut self, t: Micros) {
        if self.css_tracking() && t.is_multiple_of(self.cfg.period_us) {
            let x = self.command_pos(t)[0];
            self.css_follow(x);
        }
    }
}
