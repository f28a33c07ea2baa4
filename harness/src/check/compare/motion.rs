//! The sampled part of the comparison: the synchronisation error in the reference's
//! synchronised moves (`CHK-SYNC-01`) and the position envelope (`CHK-ENV-01`), runs of
//! out-of-tolerance samples reported as one divergence each.

use nc_engine::trace::Sample;

use super::super::tolerance::{attribute, mm_nm, ms_us, Topic};
use super::{Comparator, Divergence, Run};
use crate::scenario::timeline::{fixed, ms};

impl Comparator<'_, '_> {
    pub(super) fn sync(&mut self, t: i64, s: &Sample) {
        let r = self.r;
        let Some(k) = r.sync_index(t) else {
            self.close_sync();
            self.sync_win = None;
            self.cur_sync = None;
            return;
        };
        let w = r.sync_window(k);
        if !self.carried.angle || !self.carried.axis(w.slot) {
            return;
        }
        if self.sync_win.map(|x| x.0) != Some(k) {
            self.close_sync();
            self.sync_win = Some((k, None));
            self.sync_cut_us = self.interruption_cut(&w);
            self.cur_sync = None;
        }
        if t >= self.sync_cut_us {
            return;
        }
        let slack = self.floor_us - 1;
        let still = (mm_nm(self.tol.sync_mm) / 2).max(2000);
        let Some(e) = super::super::sync::error_at(r, &w, t, s.axes[w.slot], s.spindle_mdeg, slack, still)
        else {
            return;
        };
        self.sync_samples += 1;
        let e0 = match &mut self.sync_win {
            Some((_, e0)) => *e0.get_or_insert(e),
            None => e,
        };
        let err = if w.locked { e } else { e - e0 };
        self.cur_sync = Some(err);
        self.max_sync_nm = self.max_sync_nm.max(err.abs());
        let tol = mm_nm(self.tol.sync_mm) as f64;
        if err.abs() > tol {
            let excess = err.abs() - tol;
            let run = self.sync_run.get_or_insert_with(|| Run::starting(t));
            run.samples += 1;
            if excess > run.excess {
                let letter = r.axes().iter().find(|a| a.index == w.slot).map_or('?', |a| a.letter);
                let what = if w.locked { "start angle and lead" } else { "lead" };
                run.what =
                    format!("{letter} synchronisation with the spindle, {} {} ({what})", w.kind.name(), w.n);
                run.excess = excess;
                run.t_worst = t;
                run.expected = format!(
                    "|{letter} − the reference's {letter} at the recorded spindle angle{}| <= {} mm",
                    if w.locked { "" } else { ", drift since the move's start" },
                    fixed(mm_nm(self.tol.sync_mm), 6)
                );
                run.actual = format!("{} mm at {}", fixed(err.round() as i64, 6), ms(t.max(0) as u64));
            }
        } else {
            self.close_sync();
        }
    }

    /// `event_ms` before the reference's reset or emergency stop that ends its synchronised move
    /// `w` (`i64::MAX` when none does): the recorded input is held to `event_ms` of the
    /// reference's, and a control whose abort reaches motion earlier brakes the axis off the
    /// spindle there (LinuxCNC 2.9 stamps the reset when its task reports it done, after the axis
    /// has stopped, 16 ms after it began to brake). Both sides let go of the spindle on purpose:
    /// the samples from there are not judged.
    fn interruption_cut(&self, w: &super::super::sync::Window) -> i64 {
        let ev = ms_us(self.tol.event_ms);
        self.r
            .inputs
            .iter()
            .filter(|(ti, name, _)| {
                matches!(name.as_str(), "reset" | "emergency_stop") && *ti >= w.t0 && *ti <= w.t1
            })
            .map(|(ti, _, _)| ti - ev)
            .min()
            .unwrap_or(i64::MAX)
    }

    pub(super) fn close_sync(&mut self) {
        if let Some(run) = self.sync_run.take() {
            self.diverge(
                Topic::Sync,
                "CHK-SYNC-01",
                format!("{} ({} samples)", run.what, run.samples),
                run.t_first,
                run.expected,
                run.actual,
                format!("{} mm", fixed(run.excess.round() as i64, 6)),
            );
        }
    }

    pub(super) fn envelope(&mut self, t: i64, s: &Sample) {
        if t < 0 {
            return;
        }
        let w = self.env_w;
        let tol = self.env_tol;
        // `r` outlives `self`'s borrow: no copy of the axes per recorded sample.
        let r = self.r;
        let Some((los, his, at)) = r.envelope(t, w, &self.env_slots, t <= r.end_us) else { return };
        for (k, a) in r.axes().iter().enumerate() {
            if !self.carried.axis(a.index) {
                continue;
            }
            let (lo, hi) = (los[a.index], his[a.index]);
            let v = s.axes[a.index] as f64;
            if let (Some(p), false) = (at, a.rotary) {
                let p = p[a.index];
                self.fit.0 += (v - p) * (v - p);
                self.fit.1 += 1;
            }
            let excess = (lo - tol - v).max(v - hi - tol);
            if excess > 0.0 {
                self.max_env_nm = self.max_env_nm.max(excess);
                let run = self.env_runs[k].get_or_insert_with(|| Run::starting(t));
                run.samples += 1;
                if excess > run.excess {
                    run.excess = excess;
                    run.t_worst = t;
                    let unit = if a.rotary { "deg" } else { "mm" };
                    run.expected = format!(
                        "{} in [{}, {}] {unit} (reference ± {} ms ± {} mm)",
                        a.letter,
                        fixed(lo.round() as i64, 6),
                        fixed(hi.round() as i64, 6),
                        self.tol.envelope_ms,
                        self.tol.position_mm
                    );
                    run.actual = format!("{} = {} {unit} at {}", a.letter, fixed(v as i64, 6), ms(t as u64));
                }
            } else {
                self.close_env(k);
            }
        }
    }

    pub(super) fn close_env(&mut self, k: usize) {
        if let Some(run) = self.env_runs[k].take() {
            let letter = self.r.axes()[k].letter;
            // Attributed where the run starts, but an overload retract begun by its worst point
            // counts: a late retract strays before the reference's retract phase begins.
            // (A run that began before the moves and phases held is attributed at the end.)
            let overload = self.r.overload_by(run.t_worst);
            let rule = self.r.holds_context_at(run.t_first).then(|| {
                let mut ctx = self.context(run.t_first);
                ctx.overload |= overload;
                attribute(Topic::Envelope, &ctx)
            });
            let d = Divergence {
                rule: String::new(),
                check: "CHK-ENV-01".into(),
                what: format!("{letter} position envelope ({} samples)", run.samples),
                t_us: Some(run.t_first),
                expected: run.expected,
                actual: run.actual,
                margin: format!("{} mm", fixed(run.excess.round() as i64, 6)),
            };
            self.push_attributed(d, rule, Topic::Envelope, overload);
        }
    }
}
