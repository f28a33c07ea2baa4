//! Thread turning in passes (Heidenhain cycle 832 THREAD EXTENDED, seed 004): from the cycle's
//! start point, rapid to the safety position in front of the thread and infeed; a cutting pass
//! synchronised with the spindle (approach path, thread, run-out, overrun); rapid lift to the
//! safety clearance; rapid back to the start of the cut; the next infeed at the infeed angle;
//! until the thread depth; the air cuts; all of it for every start; rapid back to the start
//! point. Rules HDH-C832-* in `docs/rules/heidenhain.md`.
//!
//! Works in two coordinates: *along* (the pitch direction: Z for a longitudinal thread, X for a
//! face thread) and *across* (the infeed direction, perpendicular to it). Passes are planned
//! [`PASSES_PER_CHUNK`] at a time (a thread may take billions of passes: constant chip section
//! with a tiny maximum cut).

use crate::alarm::AlarmKind;
use crate::plan::{More, PassLaw, Pos, Step, ThreadPass};
use crate::trace::Phase;
use crate::units::Nm;

/// Most passes planned at once (the rest follows in a [`Step::More`]).
pub const PASSES_PER_CHUNK: u64 = 16;

/// One cycle 832 call, in physical nm (X as radius).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThreadCycle {
    /// Axis slot of the pitch direction.
    pub along: usize,
    /// Axis slot of the infeed direction.
    pub across: usize,
    /// The tool's position when the cycle is called (it returns there).
    pub start: Pos,
    /// Contour start (along, across).
    pub from: (Nm, Nm),
    /// Contour end (along, across).
    pub to: (Nm, Nm),
    /// +1: the safety clearance lies towards +across (outside thread), −1: towards −across.
    pub outward: i8,
    /// Safety clearance Q460.
    pub clearance: Nm,
    /// Thread depth (Q473, or the standard depth).
    pub depth: Nm,
    /// Number of infeed passes to the depth.
    pub passes: u64,
    /// Constant chip section (Q468 = 0): pass depths grow as the square root of the pass number.
    pub constant_chip: bool,
    /// tan(Q467): the lateral shift per unit of depth.
    pub infeed_tan: f64,
    /// Run-out Q474.
    pub run_out: Nm,
    /// Approach path Q465.
    pub approach: Nm,
    /// Overrun path Q466.
    pub overrun: Nm,
    /// Lead (Q472), nm per spindle revolution.
    pub lead_nm: i64,
    /// Start angle Q470, milli-degrees 0..360000.
    pub angle_mdeg: i64,
    /// Number of starts Q475.
    pub starts: u64,
    /// Air cuts Q476 (per start).
    pub air_cuts: u64,
}

impl ThreadCycle {
    /// Along direction of the cut, +1 or −1.
    fn dir(&self) -> Nm {
        if self.to.0 >= self.from.0 {
            1
        } else {
            -1
        }
    }

    /// The contour's across coordinate at `a` (the taper line, extended).
    fn line(&self, a: Nm) -> Nm {
        let (a0, c0) = self.from;
        let (a1, c1) = self.to;
        if a1 == a0 {
            return c0;
        }
        c0 + ((c1 - c0) as f64 * (a - a0) as f64 / (a1 - a0) as f64).round() as Nm
    }

    /// Cumulative depth after infeed pass `k` (1-based, up to `passes`), nm (HDH-C832-07).
    pub fn depth_after(&self, k: u64) -> Nm {
        let n = self.passes.max(1);
        let k = k.min(n);
        let f = if self.constant_chip { (k as f64 / n as f64).sqrt() } else { k as f64 / n as f64 };
        (self.depth as f64 * f).round() as Nm
    }

    fn pos(&self, along: Nm, across: Nm) -> Pos {
        let mut p = self.start;
        p[self.along] = along;
        p[self.across] = across;
        p
    }

    /// The pass at cumulative depth `d` for the start at `angle_mdeg`.
    pub fn pass(&self, d: Nm, angle_mdeg: i64) -> ThreadPass {
        let dir = self.dir();
        let shift = -dir * (d as f64 * self.infeed_tan).round() as Nm;
        let out = Nm::from(self.outward);
        let a_start = self.from.0 - dir * self.approach + shift;
        let a_end = self.to.0 + shift;
        let a_over = a_end + dir * self.overrun;
        let at_depth = |a: Nm| self.line(a) - out * d;
        let at_clear = |a: Nm| self.line(a) + out * self.clearance;
        let mut knots = [(a_start, at_depth(a_start)); 4];
        let mut n = 1;
        if self.run_out > 0 {
            let a_c = a_end - dir * self.run_out;
            if (a_c - a_start) * dir > 0 {
                knots[n] = (a_c, at_depth(a_c));
                n += 1;
            }
            knots[n] = (a_end, at_clear(a_end));
            knots[n + 1] = (a_over, at_clear(a_over));
            n += 2;
        } else {
            knots[n] = (a_over, at_depth(a_over));
            n += 1;
        }
        let mut fk = [(0.0, 0.0); 4];
        for (f, (a, c)) in fk.iter_mut().zip(knots) {
            *f = (a as f64, c as f64);
        }
        ThreadPass {
            target: self.pos(knots[n - 1].0, knots[n - 1].1),
            along: self.along,
            across: self.across,
            knots: fk,
            n,
            thread: 0,
            lead_nm: self.lead_nm as f64,
            dlead_nm: 0.0,
            phase_rev: angle_mdeg as f64 / 360_000.0,
            law: PassLaw::Accelerated { room: Some((self.approach, self.overrun)) },
            retract: None,
            alarm: AlarmKind::SpindleNotTurning,
        }
    }

    /// Passes per start: infeeds then air cuts.
    fn per_start(&self) -> u64 {
        self.passes.max(1).saturating_add(self.air_cuts)
    }

    /// Every pass of every start.
    pub fn total_passes(&self) -> u64 {
        self.per_start().saturating_mul(self.starts.max(1))
    }

    /// The start angle of start `j` (0-based), milli-degrees: Q470 + j × 360° / Q475 (HDH-C832-10).
    pub fn start_angle(&self, j: u64) -> i64 {
        let s = self.starts.max(1) as i128;
        let off = (j as i128 * 360_000 + s / 2) / s;
        (self.angle_mdeg as i128 + off).rem_euclid(360_000) as i64
    }

    /// The pass with global index `i` (0-based).
    fn pass_no(&self, i: u64) -> ThreadPass {
        let j = i / self.per_start();
        let k = i % self.per_start() + 1;
        self.pass(self.depth_after(k), self.start_angle(j))
    }
}

/// Appends the steps of the whole cycle, from the start point back to it (the first chunk of
/// passes; a [`Step::More`] carries the rest).
pub fn thread_cycle(c: &ThreadCycle, out: &mut Vec<Step>) {
    out.push(Step::Phase(Phase::Positioning));
    let a0 = c.pass_no(0).knots[0].0 as Nm;
    let out_c = Nm::from(c.outward);
    // Rapid to the safety position in front of the thread (HDH-C832-02).
    out.push(Step::Rapid { target: c.pos(a0, c.line(a0) + out_c * c.clearance) });
    passes(c, 0, out);
}

/// Appends passes from index `next` on, at most [`PASSES_PER_CHUNK`], then either a
/// [`Step::More`] or the return to the start point.
pub fn passes(c: &ThreadCycle, next: u64, out: &mut Vec<Step>) {
    let total = c.total_passes();
    let end = next.saturating_add(PASSES_PER_CHUNK).min(total);
    let out_c = Nm::from(c.outward);
    for i in next..end {
        let p = c.pass_no(i);
        let (a0, c0) = (p.knots[0].0 as Nm, p.knots[0].1 as Nm);
        let (a1, c1) = (p.knots[p.n - 1].0 as Nm, p.knots[p.n - 1].1 as Nm);
        // Infeed to the pass' start (at the infeed angle: the start shifts along, HDH-C832-08).
        out.push(Step::Phase(Phase::Positioning));
        out.push(Step::Rapid { target: c.pos(a0, c0) });
        out.push(Step::Phase(Phase::Cutting));
        out.push(Step::HoldSuppress(true));
        out.push(Step::Thread(p));
        out.push(Step::Phase(Phase::Retract));
        let lifted = c.line(a1) + out_c * c.clearance;
        if lifted != c1 {
            out.push(Step::Rapid { target: c.pos(a1, lifted) });
        }
        out.push(Step::HoldSuppress(false));
        // Back to the start of the next cut at the clearance (HDH-C832-04).
        if i + 1 < total {
            let na = c.pass_no(i + 1).knots[0].0 as Nm;
            out.push(Step::Rapid { target: c.pos(na, c.line(na) + out_c * c.clearance) });
        }
    }
    if end < total {
        out.push(Step::More(Box::new(More::Thread832 { cycle: *c, next: end })));
        return;
    }
    // Rapid back to the cycle's start point (HDH-C832-11).
    out.push(Step::Phase(Phase::Retract));
    out.push(Step::Rapid { target: c.start });
    out.push(Step::Phase(Phase::Idle));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::expand_all;

    fn cycle() -> ThreadCycle {
        ThreadCycle {
            along: 2,
            across: 0,
            start: [40_000_000, 0, 2_000_000, 0, 0, 0],
            from: (0, 50_000_000),
            to: (-35_000_000, 50_000_000),
            outward: 1,
            clearance: 2_000_000,
            depth: 1_226_860,
            passes: 7,
            constant_chip: true,
            infeed_tan: (30f64).to_radians().tan(),
            run_out: 0,
            approach: 4_000_000,
            overrun: 4_000_000,
            lead_nm: 2_000_000,
            angle_mdeg: 0,
            starts: 2,
            air_cuts: 1,
        }
    }

    #[test]
    fn constant_chip_section_cuts_equal_areas() {
        // HDH-C832-07: d_k = h·sqrt(k/n), so d_k² − d_(k−1)² is the same for every pass.
        let c = cycle();
        let areas: Vec<f64> = (1..=7)
            .map(|k| {
                let (a, b) = (c.depth_after(k) as f64, c.depth_after(k - 1) as f64);
                a * a - b * b
            })
            .collect();
        for a in &areas {
            assert!((a / areas[0] - 1.0).abs() < 1e-5, "{areas:?}");
        }
        assert_eq!(c.depth_after(7), 1_226_860);
        let d = ThreadCycle { constant_chip: false, ..c };
        assert_eq!((d.depth_after(1), d.depth_after(4), d.depth_after(7)), (175_266, 701_063, 1_226_860));
    }

    #[test]
    fn every_start_gets_its_passes_and_air_cuts_at_its_angle() {
        let c = cycle();
        let steps = expand_all({
            let mut v = Vec::new();
            thread_cycle(&c, &mut v);
            v
        });
        let passes: Vec<ThreadPass> = steps
            .iter()
            .filter_map(|s| match s {
                Step::Thread(p) => Some(*p),
                _ => None,
            })
            .collect();
        assert_eq!(passes.len(), 2 * 8);
        assert!(passes[..8].iter().all(|p| p.phase_rev == 0.0));
        assert!(passes[8..].iter().all(|p| p.phase_rev == 0.5));
        // The air cut repeats the last depth and shift.
        assert_eq!(passes[7].knots, passes[6].knots);
        // Depth grows and the start shifts back by d·tan(30°) (towards the approach side).
        let (a1, c1) = (passes[0].knots[0].0 as Nm, passes[0].knots[0].1 as Nm);
        let (a7, c7) = (passes[6].knots[0].0 as Nm, passes[6].knots[0].1 as Nm);
        assert!(c7 < c1 && a7 > a1, "{:?} {:?}", passes[0].knots, passes[6].knots);
        assert_eq!(c7, 50_000_000 - 1_226_860);
        assert_eq!(a7, 4_000_000 + (1_226_860.0 * (30f64).to_radians().tan()).round() as i64);
        assert_eq!(steps.last(), Some(&Step::Phase(Phase::Idle)));
        assert!(steps.contains(&Step::Rapid { target: c.start }));
    }
}
