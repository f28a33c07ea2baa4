//! The moves of one axis, found in the recorded samples as they stream by (bounded memory): the
//! velocity over an 8 ms window, each move's peak, its plateau and its acceleration and
//! deceleration fitted on the raw positions. Each finished move leaves a [`MoveSummary`]; the
//! samples are not kept.

use std::collections::VecDeque;

use super::Bounded;

/// Velocity window, µs.
const WINDOW_US: i64 = 8_000;
/// Below this |v| (nm/s) an axis is at rest (0.5 mm/s: twice what ± 1 µm of encoder noise
/// gives over the window).
const FLOOR: f64 = 5e5;
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
    /// A rigid tapping stroke (RGSPP or RGSPM high at the middle of most of its windows: the
    /// stroke that begins as a move ends, within the window's reach, does not count).
    pub rigid: bool,
    /// No other axis moved (the others' positions at its first and its last moving window within
    /// 50 µm, or 1 % of its travel).
    pub single: bool,
    /// Its acceleration, its deceleration followed the spindle's speed (a rigid stroke, a G33.1
    /// reversal): neither a rapid's nor a cutting feed's.
    pub follows: [bool; 2],
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
    /// Its moving windows, and those with a stroke signal high.
    windows: (u32, u32),
    others: [i64; nc_engine::trace::AXES],
    /// Every axis at its last moving window.
    others_end: [i64; nc_engine::trace::AXES],
    /// |Spindle speed| (rpm) at each window of `head_v` and `tail_v`.
    head_r: Vec<f64>,
    tail_r: VecDeque<f64>,
}

/// One axis followed through the recording.
pub struct AxisTrack {
    /// Slot in the samples.
    pub index: usize,
    /// Axis letter.
    pub letter: char,
    /// Reported as a diameter (positions halved).
    pub diameter: bool,
    pending: VecDeque<(i64, f64, i64, bool)>,
    recent: VecDeque<(i64, f64)>,
    open: Option<Open>,
    last_axes: [i64; nc_engine::trace::AXES],
    /// Finished moves (an even subsample of them all).
    pub moves: Bounded<MoveSummary>,
    /// The fastest finished moves that may be rapids (no stroke, not following the spindle),
    /// at most 4096: a long recording's few long rapids are not lost in the subsample.
    pub fastest: Vec<MoveSummary>,
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
            fastest: Vec::new(),
        }
    }

    /// One recorded sample; `rigid`: a rigid tapping stroke signal is high (or rose since the
    /// last sample); `mrpm`: the spindle's speed.
    pub fn sample(&mut self, t: i64, axes: &[i64; nc_engine::trace::AXES], rigid: bool, mrpm: i64) {
        let p = axes[self.index] as f64 / if self.diameter { 2.0 } else { 1.0 };
        self.last_axes = *axes;
        if let Some(o) = &mut self.open {
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
        self.pending.push_back((t, p, mrpm, rigid));
        while let Some(&(t0, p0, r0, _)) = self.pending.front() {
            if t - t0 < WINDOW_US {
                break;
            }
            let mid = self.pending[(self.pending.len() - 1) / 2].3;
            self.pending.pop_front();
            let v = (p - p0) / ((t - t0) as f64 / 1e6);
            let rpm = (r0 + mrpm).abs() as f64 / 2000.0;
            // A stroke at the window's middle: the one that ends as the move begins, or begins
            // as it ends, is not in it.
            self.window((t0 + t) / 2, v, rpm, mid);
        }
        if self.pending.len() > KEEP {
            self.pending.pop_front();
        }
    }

    fn window(&mut self, tm: i64, v: f64, rpm: f64, rigid: bool) {
        let moving = v.abs() > FLOOR;
        // A reversal ends a move and starts the next (the two ramps of a V, which the window
        // may not bring below the floor when their accelerations differ).
        if moving && self.open.as_ref().is_some_and(|o| o.tail_v.back().is_some_and(|w| w.1 * v < 0.0)) {
            let o = self.open.take().expect("open");
            self.finish(o);
        }
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
                    windows: (1, u32::from(rigid)),
                    others: self.last_axes,
                    others_end: self.last_axes,
                    head_r: vec![rpm],
                    tail_r: VecDeque::from([rpm]),
                });
            }
            (Some(o), true) => {
                o.windows.0 += 1;
                o.windows.1 += u32::from(rigid);
                o.peak = o.peak.max(v.abs());
                o.others_end = self.last_axes;
                if o.head_v.len() < KEEP {
                    o.head_v.push((tm, v));
                    o.head_r.push(rpm);
                }
                push_ring(&mut o.tail_v, (tm, v));
                push_ring(&mut o.tail_r, rpm);
            }
            (Some(_), false) => {
                let o = self.open.take().expect("open");
                self.finish(o);
            }
            (None, false) => {}
        }
    }

    /// Keeps the summary of a finished move that shows something (a plateau, a ramp).
    fn finish(&mut self, o: Open) {
        let s = self.summary(o);
        if s.plateau.is_some() || s.accel.iter().any(Option::is_some) {
            if !s.rigid && !s.follows[0] && !s.follows[1] {
                self.fastest.push(s);
                if self.fastest.len() >= 2 * MOVES {
                    self.fastest.sort_by(|a, b| b.peak.total_cmp(&a.peak));
                    self.fastest.truncate(MOVES);
                }
            }
            self.moves.push(s);
        }
    }

    fn summary(&self, o: Open) -> MoveSummary {
        let peak = o.peak;
        let single = (0..nc_engine::trace::AXES).filter(|&i| i != self.index).all(|i| {
            let travel = (o.others_end[self.index] - o.others[self.index]).abs();
            (o.others_end[i] - o.others[i]).abs() <= (travel / 100).max(50_000)
        });
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
        // Following the spindle: on a ramp (20 %–80 % of the peak) the axis' speed stays in
        // proportion to the spindle's (within a quarter: the axis may trail it), as in a rigid
        // stroke or a G33.1 reversal, where a rapid or a feed changes speed with the spindle
        // steady, at rest, or changing otherwise.
        let up = o.head_v.iter().position(|w| w.1.abs() >= 0.95 * peak).unwrap_or(o.head_v.len());
        let down = o.tail_v.iter().rposition(|w| w.1.abs() >= 0.95 * peak).map_or(0, |k| k + 1);
        // The spindle steady over the plateau (its speed at the plateau's two ends within 10 %),
        // and the axis' speed on the ramp (50 %–95 % of the peak) in the plateau's proportion to
        // it, within a quarter (the axis may trail the spindle a little).
        let r_up = o.head_r.get(up).copied();
        let r_down = down.checked_sub(1).and_then(|k| o.tail_r.get(k)).copied();
        let steady = match (r_up, r_down) {
            (Some(a), Some(b)) => a > 1.0 && (a - b).abs() <= 0.1 * a.max(b),
            _ => false,
        };
        let follows_on = |ws: &mut dyn Iterator<Item = (&(i64, f64), &f64)>, r_plateau: Option<f64>| {
            let Some(rp) = r_plateau.filter(|_| steady && flat) else { return false };
            let k = peak / rp;
            let ratios: Vec<f64> = ws
                .filter(|(w, _)| (0.5 * peak..=0.95 * peak).contains(&w.1.abs()))
                .map(|(w, &r)| if r > 1.0 { w.1.abs() / r } else { f64::INFINITY })
                .collect();
            ratios.len() >= 3 && ratios.iter().all(|r| (r - k).abs() <= 0.25 * k)
        };
        let follows = [
            follows_on(&mut o.head_v[..up].iter().zip(&o.head_r[..up]), r_up),
            follows_on(&mut o.tail_v.iter().zip(&o.tail_r).skip(down), r_down),
        ];
        // A plateau is one: its mean speed near the peak (not a rapid blended into a feed).
        let plateau = plateau.filter(|&(d, t)| d / t >= 0.93 * peak);
        MoveSummary { peak, plateau, flat, accel, rigid: 2 * o.windows.1 > o.windows.0, single, follows }
    }
}
