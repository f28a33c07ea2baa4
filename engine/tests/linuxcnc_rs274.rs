//! LinuxCNC's own interpreter as an oracle (issue 13): every program of
//! `oracle/linuxcnc-rs274/programs/` is run on the `linuxcnc` dialect and compared with the
//! canonical commands LinuxCNC's `rs274` printed for it (`canon/NAME.canon`): the end point of
//! every STRAIGHT_TRAVERSE, STRAIGHT_FEED, ARC_FEED and RIGID_TAP (in mm; inch programs × 25.4), and
//! the refusal (the same line, LinuxCNC's message in the engine's alarm). A difference passes only
//! when `differences.tsv` lists it (program, line, decision id, reason) and the decision is in
//! `docs/decisions.md`; an entry that no longer matches a difference fails too. A program dropped
//! in the folder with its canon file (`scripts/linuxcnc-canon`) is picked up with no code change.
//!
//! `installed_rs274_agrees_with_the_stored_canon` runs the `rs274` of Debian's `linuxcnc-uspace`
//! when it is installed (skipped, saying so, when it is not).

#[path = "linuxcnc_rs274/canon.rs"]
mod canon;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use canon::{parse_canon, run_engine, Move, Outcome};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../oracle/linuxcnc-rs274")
}

/// Every program that has a canon file: (name, program text, canon text).
fn cases() -> Vec<(String, String, String)> {
    let mut v = Vec::new();
    let dir = root().join("canon");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok())
        .filter_map(|e| e.file_name().to_str()?.strip_suffix(".canon").map(str::to_string))
        .collect();
    names.sort();
    for n in names {
        let prog = root().join("programs").join(format!("{n}.ngc"));
        let text = std::fs::read_to_string(&prog).unwrap_or_else(|e| panic!("{}: {e}", prog.display()));
        let canon = std::fs::read_to_string(dir.join(format!("{n}.canon"))).unwrap();
        v.push((n, text, canon));
    }
    v
}

/// One allowed difference: program, line, decision, reason.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
struct Allowed {
    program: String,
    line: u32,
    decision: String,
}

fn allowances() -> BTreeSet<Allowed> {
    let path = root().join("differences.tsv");
    let text = std::fs::read_to_string(&path).unwrap_or_default();
    let decisions = std::fs::read_to_string(root().join("../../docs/decisions.md")).unwrap();
    let mut out = BTreeSet::new();
    for (i, l) in text.lines().enumerate().filter(|(_, l)| !l.starts_with('#') && !l.trim().is_empty()) {
        let f: Vec<&str> = l.split('\t').collect();
        assert!(
            f.len() >= 4 && !f[3].trim().is_empty(),
            "differences.tsv:{}: program, line, decision, reason",
            i + 1
        );
        let line = f[1].parse().unwrap_or_else(|_| panic!("differences.tsv:{}: line `{}`", i + 1, f[1]));
        let anchor = format!("<a id=\"{}\"></a>", f[2].to_lowercase());
        assert!(
            f[2].starts_with("DEC-") && decisions.contains(&anchor),
            "differences.tsv:{}: `{}` is not a decision of docs/decisions.md",
            i + 1,
            f[2]
        );
        out.insert(Allowed { program: f[0].to_string(), line, decision: f[2].to_string() });
    }
    out
}

fn same(a: &Move, b: &Move) -> bool {
    let tol = a.tol.max(b.tol);
    a.kind == b.kind && a.p.iter().zip(b.p).all(|(x, y)| (x - y).abs() <= tol)
}

/// The differences between rs274's moves and the engine's, each at a program line: hunks of a
/// longest-common-subsequence alignment, each described.
fn move_differences(want: &[Move], got: &[Move], refused_at: Option<u32>) -> Vec<(u32, String)> {
    let (n, m) = (want.len(), got.len());
    let mut lcs = vec![vec![0u32; m + 1]; n + 1];
    for i in (0..n).rev() {
        for j in (0..m).rev() {
            lcs[i][j] = if same(&want[i], &got[j]) {
                lcs[i + 1][j + 1] + 1
            } else {
                lcs[i + 1][j].max(lcs[i][j + 1])
            };
        }
    }
    let (mut i, mut j) = (0, 0);
    let mut out = Vec::new();
    let mut last_line = 0;
    let fmt = |m: &Move| format!("{} ({:.4}, {:.4}, {:.4})", m.kind, m.p[0], m.p[1], m.p[2]);
    while i < n || j < m {
        if i < n && j < m && same(&want[i], &got[j]) {
            last_line = got[j].line.unwrap_or(last_line);
            i += 1;
            j += 1;
            continue;
        }
        // A hunk: everything up to the next common move.
        let (i0, j0) = (i, j);
        while (i < n || j < m) && !(i < n && j < m && same(&want[i], &got[j])) {
            if j < m && (i >= n || lcs[i][j + 1] >= lcs[i + 1][j]) {
                j += 1;
            } else {
                i += 1;
            }
        }
        // The hunk's line: its first engine move's, else the next one's, else the refused line's.
        let line = got[j0..j]
            .iter()
            .find_map(|m| m.line)
            .or(got.get(j).and_then(|m| m.line))
            .or(refused_at)
            .unwrap_or(last_line);
        let w: Vec<String> = want[i0..i].iter().map(fmt).collect();
        let g: Vec<String> = got[j0..j].iter().map(fmt).collect();
        out.push((line, format!("moves {}..{}: rs274 [{}], engine [{}]", i0, i, w.join(", "), g.join(", "))));
    }
    out
}

/// The line of the program whose text rs274 printed with its error (first match).
fn line_of(program: &str, text: &str) -> u32 {
    program.lines().position(|l| l.trim().eq_ignore_ascii_case(text.trim())).map_or(0, |i| i as u32 + 1)
}

fn refusal_difference(program: &str, want: &Outcome, got: &Outcome) -> Option<(u32, String)> {
    match (&want.refusal, &got.refusal) {
        (None, None) => None,
        (Some(w), None) => Some((
            line_of(program, &w.text),
            format!("rs274 refuses `{}`: {}; the engine runs", w.text, w.message),
        )),
        (None, Some(g)) => Some((
            g.line,
            format!("the engine refuses line {} `{}`: {}; rs274 runs", g.line, g.text, g.message),
        )),
        (Some(w), Some(g)) => {
            let same_line = w.text.eq_ignore_ascii_case(&g.text);
            // LinuxCNC's message, or its head when it adds particulars after a colon.
            // (o-word errors start with the line number: `2: not in a subroutine definition: …`).
            let m = w
                .message
                .split_once(": ")
                .filter(|(n, _)| n.parse::<u32>().is_ok())
                .map_or(&*w.message, |(_, m)| m);
            let (msg, head) = (m.to_lowercase(), m.split(": ").next().unwrap_or("").to_lowercase());
            let engine = g.message.to_lowercase();
            let same_text = engine.contains(&msg) || (!head.is_empty() && engine.contains(&head));
            (!same_line || !same_text).then(|| {
                (
                    g.line,
                    format!(
                        "rs274 refuses `{}`: {}; the engine refuses line {} `{}`: {}",
                        w.text, w.message, g.line, g.text, g.message
                    ),
                )
            })
        }
    }
}

/// Every program against its canon file: K of N agree, the others differ only where
/// `differences.tsv` allows it.
#[test]
fn every_program_agrees_with_rs274_or_differs_under_a_decision() {
    let allowed = allowances();
    let mut used = BTreeSet::new();
    let mut failures = Vec::new();
    let cases = cases();
    assert!(cases.len() >= 25, "the oracle folder holds {} programs", cases.len());
    let (mut agree, mut agree_own) = (0, 0);
    let own = cases.iter().filter(|(n, _, _)| n.starts_with("project__")).count();
    for (name, program, canon) in &cases {
        let want = parse_canon(canon);
        let got = match run_engine(program) {
            Ok(o) => o,
            Err(e) => {
                failures.push(format!("{name}: the engine does not parse it: {e}"));
                continue;
            }
        };
        let mut diffs = move_differences(&want.moves, &got.moves, got.refusal.as_ref().map(|r| r.line));
        diffs.extend(refusal_difference(program, &want, &got));
        if diffs.is_empty() {
            agree += 1;
            agree_own += usize::from(name.starts_with("project__"));
        }
        for (line, what) in diffs {
            let key = allowed.iter().find(|a| &a.program == name && a.line == line);
            match key {
                Some(a) => {
                    used.insert(a.clone());
                }
                None => failures.push(format!("{name}:{line}: {what}")),
            }
        }
    }
    for a in allowed.difference(&used) {
        failures.push(format!(
            "differences.tsv: {} line {} ({}) matches no difference any more",
            a.program, a.line, a.decision
        ));
    }
    println!(
        "rs274 oracle: {agree}/{} programs agree exactly (LinuxCNC's and the corpus' {}/{}, the project's {agree_own}/{own}); the others differ only at the {} lines of differences.tsv",
        cases.len(),
        agree - agree_own,
        cases.len() - own,
        used.len()
    );
    assert!(failures.is_empty(), "{} undocumented differences:\n{}", failures.len(), failures.join("\n"));
}

/// The oracle's own reading: a canon file's moves and refusal as the README says.
#[test]
fn canon_reading() {
    let o = parse_canon(
        "executing\n    1 N..... USE_LENGTH_UNITS(CANON_UNITS_INCHES)\n    2 N..... STRAIGHT_TRAVERSE(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n    3 N..... SELECT_PLANE(CANON_PLANE_XZ)\n    4 N..... ARC_FEED(2.0000, 1.0000, 0.0000, 1.0000, -1, 0.5000, 0.0000, 0.0000, 0.0000)\nCannot put an a in canned cycle\na90\n    5 N..... ON_RESET()\n",
    );
    assert_eq!(o.moves.len(), 2);
    assert_eq!(o.moves[1].kind, 'A');
    assert_eq!(o.moves[1].p, [25.4, 12.7, 50.8]);
    let r = o.refusal.unwrap();
    assert_eq!((r.message.as_str(), r.text.as_str()), ("Cannot put an a in canned cycle", "a90"));
}

fn rs274() -> Option<PathBuf> {
    let p = std::env::var_os("RS274").map(PathBuf::from).unwrap_or_else(|| PathBuf::from("/usr/bin/rs274"));
    p.is_file().then_some(p)
}

/// Runs rs274 on a copy of the program (and its tool table) in a scratch folder.
fn run_rs274(rs274: &Path, name: &str) -> String {
    let dir = std::env::temp_dir().join(format!("nc-rs274-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let progs = root().join("programs");
    let mut args = vec![];
    let tbl = progs.join(format!("{name}.tbl"));
    if tbl.is_file() {
        std::fs::copy(&tbl, dir.join(format!("{name}.tbl"))).unwrap();
        args.extend(["-t".to_string(), format!("{name}.tbl")]);
    }
    std::fs::copy(progs.join(format!("{name}.ngc")), dir.join(format!("{name}.ngc"))).unwrap();
    args.extend(["-g".to_string(), format!("{name}.ngc")]);
    let out = std::process::Command::new(rs274)
        .args(&args)
        .current_dir(&dir)
        .stdin(std::process::Stdio::null())
        .output()
        .unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let mut s = String::from_utf8_lossy(&out.stdout).into_owned();
    s.push_str(&String::from_utf8_lossy(&out.stderr));
    s
}

/// The stored canon files are what the installed rs274 prints today (moves and refusals; the
/// 2.9 and 2.10 series differ in commands that carry no position).
#[test]
fn installed_rs274_agrees_with_the_stored_canon() {
    let Some(rs274) = rs274() else {
        eprintln!("SKIPPED: no rs274 (apt-get install linuxcnc-uspace, or set RS274=path)");
        return;
    };
    let mut bad = BTreeMap::new();
    for (name, program, canon) in cases() {
        let stored = parse_canon(&canon);
        let now = parse_canon(&run_rs274(&rs274, &name));
        let mut d = move_differences(&stored.moves, &now.moves, None);
        if stored.refusal.as_ref().map(|r| (&r.text, &r.message))
            != now.refusal.as_ref().map(|r| (&r.text, &r.message))
        {
            d.push((0, format!("refusal {:?} now {:?}", stored.refusal, now.refusal)));
        }
        let _ = program;
        if !d.is_empty() {
            bad.insert(name, d);
        }
    }
    assert!(bad.is_empty(), "stored canon differs from {}: {bad:#?}", rs274.display());
}
