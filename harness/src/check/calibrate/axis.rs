//! The moves of one axis, found in the recorded samples as they stream by (bounded memory): the
//! velocity over an 8 ms window, each move's peak, its plateau and its acceleration and
//! deceleration fitted on the raw positions. Each finished move leaves a [`MoveSummary`]; the
//! samples are not kept.

use std::collections::VecDeque;

use super::Bounded;

/// Velocity window, µs.
const WINDOW_US: i64 = 8_000;
/// Below this |v| (nm/s) an axis is at rest (0.2 mm/s).
const FLOOR: f64 = 2e5;
/// Raw samples kept at most of a move's beginning and of its end (a ramp of 4 s at 1 kHz).
const KEEP: usize = 8192;
/// Moves kept (summaries; a longer recording keeps an even subsample).
const MOVES: usize = 4096;

/// What one finished move shows.
#[derive(Debug, Clone, Copy, Default)]
pub struct MoveSummary {
    /// Peak |v|, nm/s.
    pub peak: f64,
    /// Travel (nm) and time (s) on the plateau (≥ 95 % of the peak), if both its ends were seen.
    pub plateau: Option<(f64, f64)>,
    /// The plateau at ≥ 97 % of the peak lasted at least as long as the ramp up (not a
    /// triangle: the move reached its commanded speed).
    pub flat: bool,
    /// Acceleration from rest and deceleration to rest, nm/s², fitted on the positions.
    pub accel: [Option<f64>; 2],
    /// A rigid tapping stroke (RGSPP or RGSPM high) overlapped it.
    pub rigid: bool,
    /// No other axis moved (start and end positions of the others within 5 µm).
    pub single: bool,
}

/// A move being followed.
struct Open {
    /// Raw (t, position) from 8 ms before its first window.
    head: Vec<(i64, f64)>,
    /// Windows (t, v) from its first.
    head_v: Vec<(i64, f64)>,
    /// The last raw samples and windows.
    tail: VecDeque<(i64, f64)>,
    tail_v: VecDeque<(i64, f64)>,
    peak: f64,
    rigid: bool,
    others: [i64; nc_engine::trace::AXES],
}

/// One axis followed through the recording.
pub struct AxisTrack {
    /// Slot in the samples.
    pub index: usize,
    /// Axis letter.
    pub letter: char,
    /// Reported as a diameter (positions halved).
    pub diameter: bool,
    pending: VecDeque<(i64, f64)>,
    recent: VecDeque<(i64, f64)>,
    open: Option<Open>,
    last_axes: [i64; nc_engine::trace::AXES],
    /// Finished moves.
    pub moves: Bounded<MoveSummary>,
}

fn push_ring<T>(q: &mut VecDeque<T>, x: T) {
    if q.len() == KEEP {
        q.pop_front();
    }
    q.push_back(x);
}

impl AxisTrack {
    /// A new track of slot `index`.
    pub fn new(index: usize, letter: char, diameter: bool) -> Self {
        AxisTrack {
            index,
            letter,
            diameter,
            pending: VecDeque::new(),
            recent: VecDeque::new(),
            open: None,
            last_axes: [0; nc_engine::trace::AXES],
            moves: Bounded::new(MOVES),
        }
    }

    /// One recorded sample; `rigid`: a rigid tapping stroke signal is high (or rose since the
    /// last sample).
    pub fn sample(&mut self, t: i64, axes: &[i64; nc_engine::trace::AXES], rigid: bool) {
        let p = axes[self.index] as f64 / if self.diameter { 2.0 } else { 1.0 };
        self.last_axes = *axes;
        if let Some(o) = &mut self.open {
            o.rigid |= rigid;
            if o.head.len() < KEEP {
                o.head.push((t, p));
            }
            push_ring(&mut o.tail, (t, p));
        }
        self.recent.push_back((t, p));
        while self.recent.len() > 4096 || self.recent.front().is_some_and(|s| t - s.0 > 4 * WINDOW_US) {
            self.recent.pop_front();
        }
        // Every pending sample i whose window [i, this] spans 8 ms gives a velocity at its middle.
        self.pending.push_back((t, p));
        while let Some(&(t0, p0)) = self.pending.front() {
            if t - t0 < WINDOW_US {
                break;
            }
            self.pending.pop_front();
            let v = (p - p0) / ((t - t0) as f64 / 1e6);
            self.window((t0 + t) / 2, v, rigid);
        }
        if self.pending.len() > KEEP {
            self.pending.pop_front();
        }
    }

    fn window(&mut self, tm: i64, v: f64, rigid: bool) {
        let moving = v.abs() > FLOOR;
        match (&mut self.open, moving) {
            (None, true) => {
                let head: Vec<(i64, f64)> =
                    self.recent.iter().copied().filter(|s| s.0 >= tm - WINDOW_US).collect();
                let tail = head.iter().copied().collect();
                self.open = Some(Open {
                    head,
                    head_v: vec![(tm, v)],
                    tail,
                    tail_v: VecDeque::from([(tm, v)]),
                    peak: v.abs(),
                    rigid,
                    others: self.last_axes,
                });
            }
            (Some(o), true) => {
                o.peak = o.peak.max(v.abs());
                if o.head_v.len() < KEEP {
                    o.head_v.push((tm, v));
                }
                push_ring(&mut o.tail_v, (tm, v));
            }
            (Some(_), false) => {
                let o = self.open.take().expect("open");
                let s = self.summary(o);
                self.moves.push(s);
            }
            (None, false) => {}
        }
    }

    fn summary(&self, o: Open) -> MoveSummary {
        let peak = o.peak;
        let single = (0..nc_engine::trace::AXES)
            .filter(|&i| i != self.index)
            .all(|i| (self.last_axes[i] - o.others[i]).abs() <= 5_000);
        let first = |vs: &[(i64, f64)], level: f64| vs.iter().find(|w| w.1.abs() >= level).map(|w| w.0);
        let last =
            |vs: &VecDeque<(i64, f64)>, level: f64| vs.iter().rev().find(|w| w.1.abs() >= level).map(|w| w.0);
        // The plateau: first to last window at ≥ 95 % of the peak; travel over time on the raw
        // samples (a long span: jitter and noise of single samples do not bias it).
        let mut plateau = None;
        if let (Some(t0), Some(t1)) = (first(&o.head_v, 0.95 * peak), last(&o.tail_v, 0.95 * peak)) {
            let a = o.head.iter().find(|s| s.0 >= t0);
            let b = o.tail.iter().rev().find(|s| s.0 <= t1);
            if let (Some(a), Some(b)) = (a, b) {
                if b.0 > a.0 {
                    plateau = Some(((b.1 - a.1).abs(), (b.0 - a.0) as f64 / 1e6));
                }
            }
        }
        // The ramp's time from its 10 %–90 % crossing of the windowed velocity (a first guess,
        // biased by the velocity's noise: it only bounds the fit below).
        let cross = |level: f64| {
            o.head_v.windows(2).find_map(|w| {
                let (xa, xb) = (w[0].1.abs(), w[1].1.abs());
                (xa < level && xb >= level)
                    .then(|| w[0].0 as f64 + (level - xa) / (xb - xa) * (w[1].0 - w[0].0) as f64)
            })
        };
        let guess = match (cross(0.1 * peak), cross(0.9 * peak)) {
            (Some(a), Some(b)) if b > a => Some((b - a) / 0.8),
            _ => None,
        };
        let flat = match (guess, first(&o.head_v, 0.97 * peak), last(&o.tail_v, 0.97 * peak)) {
            (Some(g), Some(a), Some(b)) => (b - a) as f64 >= g,
            _ => false,
        };
        let mut accel = [None, None];
        if let Some(g) = guess {
            // In a ramp from rest the axis has gone a·t²/2: √(distance from rest) is a line in
            // time of slope √(a/2), whatever the sample times and their jitter.
            let reach = 0.5 * peak * g / 1e6 * 0.6;
            let fit = |pts: &mut dyn Iterator<Item = (i64, f64)>, rest: f64| -> Option<f64> {
                let pts: Vec<(f64, f64)> = pts
                    .map(|(t, p)| (t as f64 / 1e6, (p - rest).abs()))
                    .filter(|&(_, d)| (50_000.0..=reach).contains(&d))
                    .map(|(t, d)| (t, d.sqrt()))
                    .collect();
                if pts.len() < 4 {
                    return None;
                }
                let n = pts.len() as f64;
                let (mt, my) =
                    (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
                let sxy: f64 = pts.iter().map(|p| (p.0 - mt) * (p.1 - my)).sum();
                let sxx: f64 = pts.iter().map(|p| (p.0 - mt) * (p.0 - mt)).sum();
                let k = (sxy / sxx).abs();
                (sxx > 0.0 && k > 0.0).then_some(2.0 * k * k)
            };
            if let Some(&(_, rest)) = o.head.first() {
                accel[0] = fit(&mut o.head.iter().copied(), rest);
            }
            if let Some(&(_, rest)) = o.tail.back() {
                accel[1] = fit(&mut o.tail.iter().copied(), rest);
            }
        }
        MoveSummary { peak, plateau, flat, accel, rigid: o.rigid, single }
    }
}
