//! The `linuxcnc` dialect against LinuxCNC itself: the moves the interpreter plans for LinuxCNC's
//! own interpreter tests are compared, point by point, with the canonical traces LinuxCNC keeps
//! next to them (`tests/interp/g84/g17/g98/expected`, `tests/interp/g84/g18/g99/expected`,
//! `tests/interp/g76/expected`, LinuxCNC/linuxcnc @5c41560; the move endpoints below are read
//! from those files, inch). Rules LCNC-CYC-02..05, LCNC-TAP-01, LCNC-G76-01..02.

use nc_engine::plan::{expand_all, Step};
use nc_engine::Machine;

const IN: f64 = 25_400_000.0;

fn corpus(name: &str) -> String {
    let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../corpus").join(name);
    std::fs::read_to_string(p).unwrap()
}

/// The end point (inch) of every rapid, feed, arc and synchronised stroke the program plans, with
/// `T` for a traverse and `F` for a feed; moves that go nowhere are left out.
fn moves(text: &str) -> Vec<(char, [f64; 3])> {
    moves_with(text, &[])
}

/// [`moves`] with parameters set.
fn moves_with(text: &str, params: &[(&str, f64)]) -> Vec<(char, [f64; 3])> {
    let mut m = Machine::new("linuxcnc").unwrap();
    for (id, v) in params {
        m.params.set(id, None, *v).unwrap();
    }
    let p = m.parse(text).unwrap();
    let mut interp = m.dialect.interpreter(&m.params);
    let mut steps = Vec::new();
    for b in &p.blocks {
        interp.block(b, &mut steps).unwrap_or_else(|a| panic!("line {}: {}", b.line, a.message()));
        if steps.contains(&Step::End) {
            break;
        }
    }
    let mut out: Vec<(char, [f64; 3])> = Vec::new();
    let mut last = [0.0; 3];
    for s in expand_all(steps) {
        let targets = match s {
            Step::Rapid { target } => vec![('T', target)],
            Step::Feed { target, .. } | Step::Arc { target, .. } => vec![('F', target)],
            // A synchronised pass: LinuxCNC's STRAIGHT_FEEDs end at its knots.
            Step::Thread(p) => p.knots[1..p.n]
                .iter()
                .map(|&(a, c)| {
                    let mut t = p.target;
                    t[p.along] = a.round() as i64;
                    t[p.across] = c.round() as i64;
                    ('F', t)
                })
                .collect(),
            _ => continue,
        };
        for (kind, t) in targets {
            let p = [t[0] as f64 / IN, t[1] as f64 / IN, t[2] as f64 / IN];
            if p != last {
                out.push((kind, p));
            }
            last = p;
        }
    }
    out
}

fn close(a: [f64; 3], b: [f64; 3]) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() < 0.00006)
}

/// `tests/interp/g84/g17/g98/expected`: STRAIGHT_TRAVERSE (T) and STRAIGHT_FEED (F) end points.
const G17_G98: &[(char, [f64; 3])] = &[
    ('T', [0., 0., 2.]),
    ('T', [1., 1., 2.]),
    ('T', [1., 1., 1.]),
    ('F', [1., 1., -1.]),
    ('F', [1., 1., 2.]),
    ('T', [1., 1., 3.]),
    ('T', [1., 2., 3.]),
    ('F', [1., 2., 0.5]),
    ('F', [1., 2., 3.]),
    ('T', [1., 2., 5.]),
    ('T', [1., 3., 5.]),
    ('F', [1., 3., 4.]),
    ('F', [1., 3., 5.]),
    ('T', [10., 0., 2.]),
    ('T', [11., 1., 2.]),
    ('T', [11., 1., 1.]),
    ('F', [11., 1., -1.]),
    ('F', [11., 1., 2.]),
    ('T', [12., 2., 2.]),
    ('T', [12., 2., 1.]),
    ('F', [12., 2., -1.]),
    ('F', [12., 2., 2.]),
    ('T', [20., 0., 2.]),
    ('T', [20., 0., 3.]),
    ('T', [21., 1., 3.]),
    ('F', [21., 1., 0.5]),
    ('F', [21., 1., 3.]),
    ('T', [22., 2., 3.]),
    ('F', [22., 2., 0.5]),
    ('F', [22., 2., 3.]),
    ('T', [30., 0., 2.]),
    ('T', [30., 0., 5.]),
    ('T', [31., 1., 5.]),
    ('F', [31., 1., 4.]),
    ('F', [31., 1., 5.]),
    ('T', [32., 2., 5.]),
    ('F', [32., 2., 4.]),
    ('F', [32., 2., 5.]),
];

/// LCNC-CYC-02..04, LCNC-TAP-01: the six orderings of Z, old Z and R under G98, G90 and G91 L2,
/// every move where LinuxCNC puts it (feeding back to the old Z).
#[test]
fn g17_g98_g84_matches_linuxcnc_expected_trace() {
    let got = moves(&corpus("LinuxCNC__linuxcnc__g17-g98-g84.ngc"));
    assert_eq!(got.len(), G17_G98.len(), "{got:?}");
    for (i, ((k, p), (wk, wp))) in got.iter().zip(G17_G98).enumerate() {
        assert!(k == wk && close(*p, *wp), "move {i}: {k} {p:?}, LinuxCNC {wk} {wp:?}");
    }
}

/// `tests/interp/g84/g18/g99/expected`; `P` marks LinuxCNC's permuted G84 feed points
/// (`cycle_feed(block, plane, y, bottom_z, x)` in the XZ plane, DEC-166).
const G18_G99: &[(char, [f64; 3])] = &[
    ('T', [0., 2., 0.]),
    ('T', [1., 2., 1.]),
    ('T', [1., 1., 1.]),
    ('F', [1., -1., 1.]),
    ('T', [1., 1., 1.]),
    ('T', [1., 3., 1.]),
    ('T', [1., 3., 2.]),
    ('P', [0.5, 2., 1.]),
    ('P', [3., 2., 1.]),
    ('T', [1., 5., 2.]),
    ('T', [1., 5., 3.]),
    ('P', [4., 3., 1.]),
    ('P', [5., 3., 1.]),
    ('T', [10., 2., 0.]),
    ('T', [11., 2., 1.]),
    ('T', [11., 1., 1.]),
    ('P', [-1., 1., 11.]),
    ('P', [1., 1., 11.]),
    ('T', [12., 1., 2.]),
    ('P', [-1., 2., 12.]),
    ('P', [1., 2., 12.]),
    ('T', [20., 2., 0.]),
    ('T', [20., 3., 0.]),
    ('T', [21., 3., 1.]),
    ('P', [0.5, 1., 21.]),
    ('P', [3., 1., 21.]),
    ('T', [22., 3., 2.]),
    ('P', [0.5, 2., 22.]),
    ('P', [3., 2., 22.]),
    ('T', [30., 2., 0.]),
    ('T', [30., 5., 0.]),
    ('T', [31., 5., 1.]),
    ('P', [4., 1., 31.]),
    ('P', [5., 1., 31.]),
    ('T', [32., 5., 2.]),
    ('P', [4., 2., 32.]),
    ('P', [5., 2., 32.]),
];

/// LCNC-CYC-05, DEC-166: in the XZ plane under G99 every move is where LinuxCNC puts it, its
/// permuted G84 feed points too (`nc.g74_g84_plane_points` 1, the default).
#[test]
fn g18_g99_g84_matches_linuxcnc_expected_trace() {
    let got = moves(&corpus("LinuxCNC__linuxcnc__g18-g99-g84.ngc"));
    assert_eq!(got.len(), G18_G99.len(), "{got:?}");
    for (i, ((k, p), (wk, wp))) in got.iter().zip(G18_G99).enumerate() {
        let wk = if *wk == 'P' { 'F' } else { *wk };
        assert!(*k == wk && close(*p, *wp), "move {i}: {k} {p:?}, LinuxCNC {wk} {wp:?}");
    }
}

/// LCNC-CYC-05, DEC-84: with `nc.g74_g84_plane_points` 0 each G84 feed goes to the point the
/// manual means: LinuxCNC's printed (x, y, z) is the intended (y, z, x), so the intended point is
/// (z, x, y) of the printed one; every other move is LinuxCNC's.
#[test]
fn g18_g99_g84_along_the_tool_axis_when_the_manual_is_asked_for() {
    let got = moves_with(&corpus("LinuxCNC__linuxcnc__g18-g99-g84.ngc"), &[("nc.g74_g84_plane_points", 0.0)]);
    assert_eq!(got.len(), G18_G99.len(), "{got:?}");
    for (i, ((k, p), (wk, wp))) in got.iter().zip(G18_G99).enumerate() {
        let (wk, wp) = match wk {
            'P' => ('F', [wp[2], wp[0], wp[1]]),
            k => (*k, *wp),
        };
        assert!(*k == wk && close(*p, wp), "move {i}: {k} {p:?}, the manual's {wk} {wp:?}");
    }
}

/// LCNC-G76-01..02: `tests/interp/g76/g76only.ngc` cuts 31 degression passes, one at full depth and
/// three spring passes (two synchronised feeds each with the exit taper), from X.2 Z.2, and ends at
/// (X.2, Z-.5); the first, second and last passes are where LinuxCNC puts them.
#[test]
fn g76only_matches_linuxcnc_expected_trace() {
    let got = moves(&corpus("LinuxCNC__linuxcnc__g76only.ngc"));
    assert_eq!(got.iter().filter(|(k, _)| *k == 'F').count(), 35 * 2);
    let xz = |p: [f64; 3]| [p[0], 0.0, p[2]];
    let pass1 = [
        [0.2370, 0., 0.1955],
        [0.1170, 0., 0.1955],
        [0.1170, 0., -0.4291],
        [0.1620, 0., -0.4791],
        [0.2370, 0., -0.4791],
    ];
    let pass2 = [
        [0.2337, 0., 0.1936],
        [0.1137, 0., 0.1936],
        [0.1137, 0., -0.4309],
        [0.1587, 0., -0.4809],
        [0.2337, 0., -0.4809],
    ];
    let last = [[0.2, 0., 0.1745], [0.08, 0., 0.1745], [0.08, 0., -0.45], [0.125, 0., -0.5], [0.2, 0., -0.5]];
    assert!(close(xz(got[0].1), [0.2, 0., 0.2]));
    for (k, want) in pass1.iter().chain(&pass2).enumerate() {
        assert!(close(xz(got[1 + k].1), *want), "point {k}: {:?} vs {want:?}", got[1 + k].1);
    }
    let n = got.len();
    // The last pass, then g0 x.5 and g0 z0 (the cycle's own final move to (X.2, Z-.5) goes nowhere).
    for (k, want) in last.iter().enumerate() {
        assert!(close(xz(got[n - 7 + k].1), *want), "last pass point {k}: {:?}", got[n - 7 + k].1);
    }
    assert!(close(got[n - 2].1, [0.5, 0., -0.5]) && close(got[n - 1].1, [0.5, 0., 0.]));
}
