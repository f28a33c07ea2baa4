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
    /// The deceleration of this segment when it is not `accel` (an orientation landing on its
    /// angle), rpm/µs.
    pub seg_accel: Option<f64>,
    /// Position (rigid tapping) mode.
    pub position_mode: bool,
    /// Stalled: does not turn whatever is commanded.
    pub stalled: bool,
    /// An orientation from rest: a turn of this many degrees (signed) from rest to rest in this
    /// many µs, accelerating then decelerating evenly (the spindle's own acceleration at most).
    pub glide: Option<(f64, f64)>,
}

impl Spindle {
    /// Stopped at angle 0.
    pub fn new(accel: f64) -> Spindle {
        Spindle {
            t0: 0,
            angle0: 0.0,
            rpm0: 0.0,
            target: 0.0,
            accel,
            seg_accel: None,
            position_mode: false,
            stalled: false,
            glide: None,
        }
    }

    /// Angle (deg, unwrapped) and speed (rpm) at `t` in velocity mode.
    pub fn at(&self, t: Micros) -> (f64, f64) {
        if self.stalled {
            return (self.angle0, 0.0);
        }
        let dt = t.saturating_sub(self.t0) as f64;
        if let Some((d, total)) = self.glide {
            if dt >= total {
                return (self.angle0 + d, 0.0);
            }
            let u = dt / total;
            let (f, slope) = if u < 0.5 {
                (2.0 * u * u, 4.0 * u)
            } else {
                (1.0 - 2.0 * (1.0 - u) * (1.0 - u), 4.0 * (1.0 - u))
            };
            return (self.angle0 + f * d, slope * d / total / DEG_PER_US_PER_RPM);
        }
        let dv = self.target - self.rpm0;
        let accel = self.seg_accel.unwrap_or(self.accel);
        let ramp = if accel.is_finite() && accel > 0.0 { dv.abs() / accel } else { 0.0 };
        if dt >= ramp {
            let a_ramp = 0.5 * (self.rpm0 + self.target) * ramp;
            let angle = self.angle0 + (a_ramp + self.target * (dt - ramp)) * DEG_PER_US_PER_RPM;
            (angle, self.target)
        } else {
            let a = dv.signum() * accel;
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
        self.seg_accel = None;
        self.glide = None;
    }

    /// Orientation (M19) from `t`: a turning spindle decelerates at its own acceleration, a little
    /// less where needed, so as to come to rest exactly on the next whole turn in its direction
    /// of rotation; a spindle at rest turns forward onto the next whole turn, accelerating then
    /// decelerating at its own acceleration (never a jump: issue 12, INV-13; `orient_us` 0 no
    /// longer makes it instant). Returns when the orientation is complete: `orient_us` after `t`,
    /// or when the spindle has come to rest if that is later.
    pub fn orient(&mut self, t: Micros, orient_us: Micros) -> Micros {
        let (angle, rpm) = self.at(t);
        let whole = |a: f64| (a / 360.0).ceil() * 360.0;
        if rpm == 0.0 {
            // From rest: turn forward onto the next whole turn, accelerating then decelerating at
            // the spindle's own acceleration (never a jump of the angle).
            let d = whole(angle) - angle;
            self.hold(t, angle);
            let a = self.accel * DEG_PER_US_PER_RPM;
            if d > 1e-9 && a.is_finite() && a > 0.0 {
                let total = 2.0 * (d / a).sqrt();
                self.glide = Some((d, total));
                return (t + total.ceil() as Micros).max(t + orient_us);
            }
            self.hold(t, whole(angle));
            return t + orient_us;
        }
        // Speed in deg/µs; the natural stopping distance at the spindle's own acceleration.
        let v = rpm.abs() * DEG_PER_US_PER_RPM;
        let a = self.accel * DEG_PER_US_PER_RPM;
        let natural = if a.is_finite() && a > 0.0 { v * v / (2.0 * a) } else { 0.0 };
        let stop = if rpm > 0.0 { whole(angle + natural) } else { -whole(-(angle - natural)) };
        let d = (stop - angle).abs();
        if d < 1e-9 {
            self.hold(t, stop);
            return t + orient_us;
        }
        self.t0 = t;
        self.angle0 = angle;
        self.rpm0 = rpm;
        self.target = 0.0;
        self.glide = None;
        self.seg_accel = Some(v * v / (2.0 * d) / DEG_PER_US_PER_RPM);
        let rest = t + (2.0 * d / v).ceil() as Micros;
        rest.max(t + orient_us)
    }

    /// Puts the spindle at rest at `angle` from `t` (end of a tapping stroke, orientation).
    pub fn hold(&mut self, t: Micros, angle: f64) {
        self.t0 = t;
        self.angle0 = angle;
        self.rpm0 = 0.0;
        self.target = 0.0;
        self.seg_accel = None;
        self.glide = None;
    }

    /// The speed ramp under way at `t` (signed speed now, signed acceleration rpm/µs, time left
    /// µs), or None when the speed is steady (or the spindle stalled).
    pub fn ramp(&self, t: Micros) -> Option<super::profile::Ramp> {
        let accel = self.seg_accel.unwrap_or(self.accel);
        let (_, rpm) = self.at(t);
        let dv = self.target - rpm;
        if self.glide.is_some_and(|(_, total)| (t.saturating_sub(self.t0) as f64) < total) {
            return None;
        }
        if self.stalled || dv == 0.0 || !accel.is_finite() || accel <= 0.0 {
            return None;
        }
        Some(super::profile::Ramp { rpm0: rpm, slope: dv.signum() * accel, dur: dv.abs() / accel })
    }

    /// When the present ramp ends (the speed is steady from then on).
    pub fn ramp_end(&self) -> Micros {
        if let Some((_, total)) = self.glide {
            return self.t0 + total.ceil() as Micros;
        }
        let dv = (self.target - self.rpm0).abs();
        let accel = self.seg_accel.unwrap_or(self.accel);
        if dv == 0.0 || !accel.is_finite() || accel <= 0.0 {
            self.t0
        } else {
            self.t0 + (dv / accel).ceil() as Micros
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
    fn orientation_decelerates_onto_the_next_whole_turn() {
        // 0 → 1000 rpm in 100 ms (0.01 rpm/µs, 300°); 1.666 ms later at 1000 rpm (6°/ms) the
        // spindle is at 310°. Its natural stop (100 ms, 300°) would end at 610°: it lands on 720°
        // instead, decelerating a little more gently over 410°.
        let mut s = Spindle::new(0.01);
        s.command(0, 1000.0);
        let t = 100_000 + 1_666;
        let (a0, _) = s.at(t);
        let done = s.orient(t, 500_000);
        assert_eq!(done, t + 500_000);
        let (a, rpm) = s.at(t + 2_000);
        assert!(rpm > 0.0 && rpm < 1000.0 && a > a0, "{rpm} {a}");
        let rest = s.ramp_end();
        assert!(rest > t && rest <= done, "{rest}");
        let (a, rpm) = s.at(rest);
        assert_eq!(rpm, 0.0);
        assert!((a - 720.0).abs() < 1e-6, "{a0} -> {a}");
        // Slower than its own acceleration allows, never faster.
        assert!(s.seg_accel.unwrap() <= 0.01);
        // In reverse it lands on the whole turn below; at rest it goes there at once.
        let mut r = Spindle::new(0.01);
        r.command(0, -1000.0);
        r.orient(200_000, 500_000);
        let (a, _) = r.at(r.ramp_end());
        assert!((a / 360.0 - (a / 360.0).round()).abs() < 1e-9 && a < -900.0, "{a}");
        // At rest it turns onto the next whole turn at its own acceleration, never jumping.
        let mut z = Spindle::new(0.01);
        z.hold(0, 10.0);
        assert_eq!(z.orient(0, 500_000), 500_000);
        let (a, rpm) = z.at(z.ramp_end() / 2);
        assert!((a - 185.0).abs() < 0.2 && rpm > 0.0, "{a} {rpm}");
        let (a, rpm) = z.at(z.ramp_end());
        assert!((a - 360.0).abs() < 1e-9 && rpm == 0.0, "{a} {rpm}");
        // 350° at 0.01 rpm/µs (6e-8 °/µs²): 2·√(350/6e-8) µs.
        assert_eq!(z.ramp_end(), (2.0 * (350.0f64 / 6e-8).sqrt()).ceil() as Micros);
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
