//! The LinuxCNC G76 threading cycle (rules LCNC-G76-*): passes along a drive line, each one a
//! spindle-synchronised cut (feed per revolution = the pitch along Z), deeper by the degression
//! law `depth(n) = J × n^(1/R)` until the full depth K, then H spring passes at K; compound infeed
//! by the angle Q (each pass starts `depth × tan Q` further along the thread and, so that every
//! pass has the same length, ends `(K - depth) × tan Q` short of Z); tapered entry and/or exit
//! over E along the drive line (L = 1 entry, 2 exit, 3 both). Checked against LinuxCNC's own
//! canonical trace `tests/interp/g76/expected` in `engine/tests/linuxcnc.rs`.
//!
//! The dialect checks the words; this builder takes over at the drive line's start point and
//! leaves the tool at (start X, Z end) as LinuxCNC does.

use crate::alarm::AlarmKind;
use crate::plan::{PassLaw, Pos, Step, ThreadPass};
use crate::trace::Phase;
use crate::units::Nm;

/// Most passes one G76 may plan (a tiny J with a large R would otherwise ask for millions).
pub const MAX_PASSES: u64 = 10_000;

/// One G76 thread, all lengths in nm (X as a radius).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThreadG76 {
    /// Cross (X) axis slot.
    pub x_axis: usize,
    /// Drive (Z) axis slot.
    pub z_axis: usize,
    /// Where the tool stands when the cycle starts: the drive line's start.
    pub start: Pos,
    /// Z at the end of the drive line.
    pub z_end: Nm,
    /// Pitch along Z, nm per revolution (> 0).
    pub pitch: Nm,
    /// I: offset from the drive line to the thread crests (negative: external thread).
    pub i: Nm,
    /// J: depth of the first pass (> 0).
    pub j: Nm,
    /// K: full thread depth (> 0).
    pub k: Nm,
    /// R: depth degression (>= 1).
    pub degression: f64,
    /// Q: compound slide angle, degrees.
    pub compound_deg: f64,
    /// H: spring passes at full depth.
    pub spring: u32,
    /// E: taper length along the drive line.
    pub taper: Nm,
    /// L: 0 none, 1 entry taper, 2 exit taper, 3 both.
    pub taper_ends: u8,
}

impl ThreadG76 {
    /// The depths of the passes before full depth (each < K).
    pub fn depths(&self) -> impl Iterator<Item = Nm> + '_ {
        let (j, k) = (self.j as f64, self.k as f64);
        (1..=MAX_PASSES)
            .map(move |n| (j * libm::pow(n as f64, 1.0 / self.degression)).round() as Nm)
            .take_while(move |&d| (d as f64) < k)
    }

    /// Number of passes the cycle cuts (degression passes, the full-depth one, spring passes).
    pub fn pass_count(&self) -> u64 {
        self.depths().count() as u64 + 1 + self.spring as u64
    }
}

/// Appends the passes of one G76, from the start point to (start X, Z end).
pub fn thread_g76(c: &ThreadG76, out: &mut Vec<Step>) {
    let depths: Vec<Nm> = c.depths().collect();
    for &d in depths.iter().chain(std::iter::repeat_n(&c.k, 1 + c.spring as usize)) {
        pass(c, d, out);
    }
    let mut end = c.start;
    end[c.z_axis] = c.z_end;
    // The last pass's rapid out already ends there (at full depth it ends at the start's X and
    // Z's end): LinuxCNC's planner drops the cycle's final traverse of no length (DEC-167), so
    // the move after the cycle joins the rapid out.
    if !matches!(out.last(), Some(Step::Rapid { target }) if *target == end) {
        out.push(Step::Rapid { target: end });
    }
    out.push(Step::Phase(Phase::Idle));
}

/// One pass at `depth` below the crests.
fn pass(c: &ThreadG76, depth: Nm, out: &mut Vec<Step>) {
    let x0 = c.start[c.x_axis];
    let z0 = c.start[c.z_axis];
    let dir: Nm = if c.i > 0 { 1 } else { -1 };
    let zdir: Nm = if c.z_end > z0 { 1 } else { -1 };
    let tan_q = libm::tan(c.compound_deg.to_radians());
    let shift = |len: Nm| (len as f64 * tan_q).round() as Nm;
    // Saturating: the dialect bounds the words, not their sums (fuzzed: a Q near 90°).
    let start_z = z0.saturating_add(zdir.saturating_mul(shift(depth)));
    let end_z = c.z_end.saturating_sub(zdir.saturating_mul(shift(c.k - depth)));
    let cut_x = x0.saturating_add(c.i).saturating_add(dir * depth);
    let safe_x = cut_x.saturating_sub(c.i).saturating_sub(dir * c.k);
    let taper_x = cut_x.saturating_sub(dir * c.k);
    let at = |x: Nm, z: Nm| {
        let mut p = c.start;
        p[c.x_axis] = x;
        p[c.z_axis] = z;
        p
    };
    // One synchronised pass along Z (one pitch per revolution), X through the tapers' knots:
    // LinuxCNC waits for the index only before the first of a run of synchronised moves.
    let knot = |x: Nm, z: Nm| (z as f64, x as f64);
    let mut knots = [(0.0, 0.0); 4];
    let mut n = 0;
    let mut push = |k: (f64, f64)| {
        if n == 0 || knots[n - 1] != k {
            knots[n] = k;
            n += 1;
        }
    };
    out.push(Step::Phase(Phase::Positioning));
    out.push(Step::Rapid { target: at(safe_x, start_z) });
    let e = c.taper.min(end_z.saturating_sub(start_z).saturating_abs());
    let mut z = start_z;
    // The thread proper follows an entry taper, and the entry taper its infeed: a synchronised
    // move along X at the taper's lead per revolution of path (interp_convert.cc
    // `threading_pass`: START_SPEED_FEED_SYNCH(taper_pitch) then STRAIGHT_FEED "in", where
    // taper_pitch = pitch × √(E² + K²) / E), which waits for the index; the taper and the thread
    // follow it without a new one.
    let entry = c.taper_ends & 1 != 0 && e > 0;
    let thread = usize::from(entry);
    let mut infeed = None;
    if entry {
        if taper_x != safe_x {
            let taper_lead = c.pitch as f64 * (e as f64).hypot(c.k as f64) / e as f64;
            let from = at(safe_x, start_z);
            infeed = ThreadPass::line(from, at(taper_x, start_z), [c.x_axis, c.z_axis], taper_lead, true);
        }
        push(knot(taper_x, start_z));
        z = start_z.saturating_add(zdir * e);
    } else {
        out.push(Step::Rapid { target: at(cut_x, start_z) });
    }
    push(knot(cut_x, z));
    let mut end = at(cut_x, end_z);
    if c.taper_ends & 2 != 0 && e > 0 {
        let straight_end = end_z.saturating_sub(zdir * e);
        if (straight_end as i128 - z as i128) * zdir as i128 > 0 {
            push(knot(cut_x, straight_end));
        }
        end = at(taper_x, end_z);
    }
    push(knot(end[c.x_axis], end_z));
    // Each pass is a synchronised move that is not yet synchronised: LinuxCNC's planner starts
    // it once the spindle is at speed (tp.c `needs_atspeed`, LCNC-MOT-01).
    out.push(Step::AwaitAtSpeed);
    out.push(Step::HoldSuppress(true));
    out.push(Step::Phase(Phase::Cutting));
    if let Some(infeed) = infeed {
        out.push(Step::Thread(ThreadPass { alarm: AlarmKind::LcncSpindle, ..infeed }));
    }
    if n >= 2 && knots[0].0 != knots[n - 1].0 {
        out.push(Step::Thread(ThreadPass {
            target: end,
            along: c.z_axis,
            across: c.x_axis,
            knots,
            n,
            thread,
            lead_nm: c.pitch as f64,
            dlead_nm: 0.0,
            phase_rev: 0.0,
            // Tapers are segments of their own, each ending at rest (DEC-147).
            law: match (n > 2, infeed.is_some()) {
                (true, true) => PassLaw::SegmentsTracking,
                (true, false) => PassLaw::Segments,
                (false, _) => PassLaw::Accelerated { room: None },
            },
            retract: None,
            alarm: AlarmKind::LcncSpindle,
        }));
    }
    out.push(Step::HoldSuppress(false));
    out.push(Step::Phase(Phase::Retract));
    out.push(Step::Rapid { target: at(safe_x, end_z) });
}

#[cfg(test)]
mod tests {
    use super::*;

    const IN: Nm = 25_400_000;

    /// LinuxCNC's `tests/interp/g76/g76only.ngc`: `G76 P.05 Z-.5 I-.075 J.008 K.045 H3 R2 Q29.5
    /// E.05 L2` from X.2 Z.2 (inch).
    fn g76only() -> ThreadG76 {
        ThreadG76 {
            x_axis: 0,
            z_axis: 2,
            start: [IN / 5, 0, IN / 5, 0, 0, 0],
            z_end: -IN / 2,
            pitch: IN / 20,
            i: -75 * IN / 1000,
            j: 8 * IN / 1000,
            k: 45 * IN / 1000,
            degression: 2.0,
            compound_deg: 29.5,
            spring: 3,
            taper: IN / 20,
            taper_ends: 2,
        }
    }

    #[test]
    fn degression_passes_then_full_depth_and_spring_passes() {
        // 0.008 × √n < 0.045 for n = 1..31; then K once and 3 spring passes.
        assert_eq!(g76only().pass_count(), 31 + 1 + 3);
    }

    #[test]
    fn first_pass_matches_linuxcnc_canonical_trace() {
        let mut v = Vec::new();
        pass(&g76only(), 8 * IN / 1000, &mut v);
        let pts: Vec<(Nm, Nm)> = v
            .iter()
            .flat_map(|s| match s {
                Step::Rapid { target } => vec![(target[0], target[2])],
                Step::Thread(p) => p.knots[1..p.n].iter().map(|&(z, x)| (x as Nm, z as Nm)).collect(),
                _ => vec![],
            })
            .collect();
        // expected: (0.2370, 0.1955) (0.1170, 0.1955) (0.1170, -0.4291) (0.1620, -0.4791) (0.2370, -0.4791)
        let want =
            [(0.2370, 0.1955), (0.1170, 0.1955), (0.1170, -0.4291), (0.1620, -0.4791), (0.2370, -0.4791)];
        assert_eq!(pts.len(), want.len());
        for ((x, z), (wx, wz)) in pts.iter().zip(want) {
            assert!((*x as f64 / IN as f64 - wx).abs() < 0.00006, "x {x} vs {wx}");
            assert!((*z as f64 / IN as f64 - wz).abs() < 0.00006, "z {z} vs {wz}");
        }
    }
}
