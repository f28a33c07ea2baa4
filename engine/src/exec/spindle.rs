//! The spindle: speed ramps in velocity mode (constant acceleration), position mode for rigid
//! tapping (the tapping stroke drives the angle), a stall fault, and the angle in closed form.

use crate::units::Micros;

/// Degrees per µs at 1 rpm.
pub const DEG_PER_US_PER_RPM: f64 = 360.0 / 60e6;

/// The spindle's state from `t0` on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spindle {
    /// When this segment started.
    pub t0: Micros,
    /// Angle at `t0`, degrees (not wrapped).
    pub angle0: f64,
    /// Speed at `t0`, rpm (signed).
    pub rpm0: f64,
    /// Speed being ramped to, rpm (signed).
    pub target: f64,
    /// Acceleration, rpm/µs (> 0; infinite: no ramp).
    pub accel: f64,
    /// Position (rigid tapping) mode.
    pub position_mode: bool,
    /// Stalled: does not turn whatever is commanded.
    pub stalled: bool,
}

impl Spindle {
    /// Stopped at angle 0.
    pub fn new(accel: f64) -> Spindle {
        Spindle { t0: 0, angle0: 0.0, rpm0: 0.0, target: 0.0, accel, position_mode: false, stalled: false }
    }

    /// Angle (deg, unwrapped) and speed (rpm) at `t` in velocity mode.
    pub fn at(&self, t: Micros) -> (f64, f64) {
        if self.stalled {
            return (self.angle0, 0.0);
        }
        let dt = t.saturating_sub(self.t0) as f64;
        let dv = self.target - self.rpm0;
        let ramp = if self.accel.is_finite() && self.accel > 0.0 { dv.abs() / self.accel } else { 0.0 };
        if dt >= ramp {
            let a_ramp = 0.5 * (self.rpm0 + self.target) * ramp;
            let angle = self.angle0 + (a_ramp + self.target * (dt - ramp)) * DEG_PER_US_PER_RPM;
            (angle, self.target)
        } else {
            let a = dv.signum() * self.accel;
            let rpm = self.rpm0 + a * dt;
            let angle = self.angle0 + (self.rpm0 * dt + 0.5 * a * dt * dt) * DEG_PER_US_PER_RPM;
            (angle, rpm)
        }
    }

    /// Commands a new speed from `t` (ramping from the present speed).
    pub fn command(&mut self, t: Micros, rpm: f64) {
        let (angle, now) = self.at(t);
        self.t0 = t;
        self.angle0 = angle;
        self.rpm0 = now;
        self.target = rpm;
    }

    /// Puts the spindle at rest at `angle` from `t` (end of a tapping stroke, orientation).
    pub fn hold(&mut self, t: Micros, angle: f64) {
        self.t0 = t;
        self.angle0 = angle;
        self.rpm0 = 0.0;
        self.target = 0.0;
    }

    /// When the present ramp ends (the speed is steady from then on).
    pub fn ramp_end(&self) -> Micros {
        let dv = (self.target - self.rpm0).abs();
        if dv == 0.0 || !self.accel.is_finite() || self.accel <= 0.0 {
            self.t0
        } else {
            self.t0 + (dv / self.accel).ceil() as Micros
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramps_at_constant_acceleration_and_integrates_the_angle() {
        // 0 → 1000 rpm in 1 s (accel 1000 rpm/s = 0.001 rpm/µs).
        let mut s = Spindle::new(0.001);
        s.command(0, 1000.0);
        assert_eq!(s.at(500_000).1, 500.0);
        // Ramp: 1 s at an average 500 rpm = 8.333 rev, then 1 s at 1000 rpm = 16.667 rev: 25 rev.
        let (angle, rpm) = s.at(2_000_000);
        assert_eq!(rpm, 1000.0);
        assert!((angle / 360.0 - 25.0).abs() < 1e-9, "{angle}");
        assert_eq!(s.ramp_end(), 1_000_000);
    }

    #[test]
    fn a_stalled_spindle_does_not_turn() {
        let mut s = Spindle::new(0.001);
        s.command(0, 1000.0);
        let (a, _) = s.at(100_000);
        s.hold(100_000, a);
        s.stalled = true;
        s.command(100_000, 1000.0);
        assert_eq!(s.at(900_000).1, 0.0);
    }
}
