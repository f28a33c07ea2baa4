//! The spindle's speed as it streams by: each start from rest (its slope from 10 % to 90 % of
//! the speed it reaches), told apart as a rigid tapping stroke (RGSPP/RGSPM rose around it) or a
//! speed-mode start; and each coming to rest (the time its deceleration reaches zero), paired
//! with the zero-speed answer (ZSP ↑) that follows.

use super::Bounded;

/// Above this |speed| the spindle turns (1 rpm, in milli-rpm).
const TURNING: i64 = 1000;
/// Samples of one start kept at most.
const KEEP: usize = 65_536;

/// One start from rest.
#[derive(Debug, Clone, Copy)]
pub struct Start {
    /// Slope from 10 % to 90 % of `top`, rpm/s.
    pub slope: f64,
    /// The speed it reached, rpm.
    pub top: f64,
}

/// The spindle followed through the recording.
#[derive(Default)]
pub struct SpindleTrack {
    /// Speed-mode starts from rest.
    pub starts: Bounded<Start>,
    /// Rigid tapping strokes' starts from rest.
    pub rigid: Bounded<Start>,
    /// Spindle at rest → ZSP ↑, µs.
    pub zsp: Bounded<f64>,
    ramp: Vec<(i64, i64)>,
    last: Option<(i64, i64)>,
    before: Option<(i64, i64)>,
    /// When the spindle came to rest (its deceleration extrapolated to zero), waiting for ZSP.
    rest_at: Option<f64>,
    /// The last time RGSPP or RGSPM rose, and whether one is high.
    rigid_rise: Option<i64>,
    rigid_high: bool,
}

impl SpindleTrack {
    /// A new track.
    pub fn new() -> Self {
        SpindleTrack {
            starts: Bounded::new(4096),
            rigid: Bounded::new(4096),
            zsp: Bounded::new(65_536),
            ..Default::default()
        }
    }

    /// RGSPP or RGSPM changed: `high` is whether either is high now.
    pub fn stroke(&mut self, t: i64, rose: bool, high: bool) {
        if rose {
            self.rigid_rise = Some(t);
        }
        self.rigid_high = high;
    }

    /// ZSP rose.
    pub fn zsp_rose(&mut self, t: i64) {
        if let Some(r) = self.rest_at.take() {
            let d = t as f64 - r;
            if (0.0..=10e6).contains(&d) {
                self.zsp.push(d);
            }
        }
    }

    /// One recorded sample of the speed (milli-rpm).
    pub fn sample(&mut self, t: i64, mrpm: i64) {
        let speed = mrpm.abs();
        let prev = self.last.replace((t, speed));
        if !self.ramp.is_empty() {
            let &(_, top) = self.ramp.last().expect("ramp");
            if speed > top && self.ramp.len() < KEEP {
                self.ramp.push((t, speed));
                return;
            }
            self.finish_ramp(t);
        }
        let Some((tp, sp)) = prev else { return };
        if sp <= TURNING && speed > TURNING {
            // A start from rest: from the last sample at rest.
            self.rest_at = None;
            self.ramp = vec![(tp, sp), (t, speed)];
        } else if sp > TURNING && speed <= TURNING {
            // Come to rest: the deceleration through the last two samples turning, to zero.
            if let Some((tb, sb)) = self.before.filter(|b| b.1 > sp) {
                let rate = (sb - sp) as f64 / (tp - tb).max(1) as f64;
                self.rest_at = Some(tp as f64 + sp as f64 / rate);
            } else {
                self.rest_at = Some(t as f64);
            }
        }
        self.before = prev;
    }

    fn finish_ramp(&mut self, now: i64) {
        let ramp = std::mem::take(&mut self.ramp);
        let top = ramp.last().expect("ramp").1 as f64;
        let at = |level: f64| {
            ramp.windows(2).find_map(|w| {
                let (a, b) = (w[0].1 as f64, w[1].1 as f64);
                (a < level && b >= level)
                    .then(|| w[0].0 as f64 + (level - a) / (b - a) * (w[1].0 - w[0].0) as f64)
            })
        };
        let (Some(t1), Some(t2)) = (at(0.1 * top), at(0.9 * top)) else { return };
        if t2 <= t1 {
            return;
        }
        let start = Start { slope: 0.8 * top / 1000.0 / ((t2 - t1) / 1e6), top: top / 1000.0 };
        // A stroke signal rose within 20 ms before the start, or during the ramp (edges of a
        // PLC-scan recorder come late), or is high: a rigid stroke.
        let t0 = ramp[0].0;
        let rigid = self.rigid_high || self.rigid_rise.is_some_and(|r| r >= t0 - 20_000 && r <= now);
        if rigid {
            self.rigid.push(start);
        } else {
            self.starts.push(start);
        }
    }
}
