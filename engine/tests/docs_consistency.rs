//! The docs are part of the contract: every parameter and alarm is documented, and every rule id
//! that a test cites is defined in `docs/rules/`.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn read_dir_text(dir: &Path, ext: &str) -> Vec<(PathBuf, String)> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(read_dir_text(&p, ext));
        } else if p.extension().is_some_and(|x| x == ext) {
            out.push((p.clone(), std::fs::read_to_string(&p).unwrap()));
        }
    }
    out
}

/// Rule ids like `GSK-RT-07` in a text (families COM, GSK, FAN, KND, LCNC, HDH).
fn rule_ids(text: &str) -> BTreeSet<String> {
    let mut ids = BTreeSet::new();
    let b = text.as_bytes();
    for fam in ["COM-", "GSK-", "FAN-", "KND-", "LCNC-", "HDH-"] {
        let mut from = 0;
        while let Some(i) = text[from..].find(fam) {
            let start = from + i;
            let mut end = start + fam.len();
            while end < b.len() && (b[end].is_ascii_uppercase() || b[end].is_ascii_digit()) {
                end += 1;
            }
            if end > start + fam.len() && end < b.len() && b[end] == b'-' {
                let mut d = end + 1;
                while d < b.len() && b[d].is_ascii_digit() {
                    d += 1;
                }
                if d - end - 1 == 2 {
                    ids.insert(text[start..d].to_string());
                }
            }
            from = start + fam.len();
        }
    }
    ids
}

#[test]
fn every_rule_id_cited_by_a_test_is_defined() {
    let defined: BTreeSet<String> = read_dir_text(&root().join("docs/rules"), "md")
        .iter()
        .flat_map(|(_, t)| t.lines().filter(|l| l.starts_with("**")).flat_map(rule_ids).collect::<Vec<_>>())
        .collect();
    assert!(defined.len() > 100, "{} rules", defined.len());
    let mut missing = Vec::new();
    for dir in ["engine/tests", "engine/src", "harness"] {
        for (p, text) in read_dir_text(&root().join(dir), "rs") {
            for id in rule_ids(&text) {
                // The scenario parser's own test of the id syntax cites a made-up id.
                if !defined.contains(&id) && id != "HDH-ABC-99" {
                    missing.push(format!("{} cites {id}", p.display()));
                }
            }
        }
    }
    assert!(missing.is_empty(), "undefined rule ids:\n{}", missing.join("\n"));
}

#[test]
fn every_parameter_is_documented() {
    let doc = std::fs::read_to_string(root().join("docs/parameters.md")).unwrap();
    for d in nc_engine::dialect::ALL {
        for p in d.param_table() {
            assert!(
                doc.contains(&format!("`{}`", p.id)),
                "{} parameter {} is not in docs/parameters.md",
                d.name(),
                p.id
            );
        }
    }
}

#[test]
fn every_alarm_is_documented() {
    let doc = std::fs::read_to_string(root().join("docs/alarms.md")).unwrap();
    for k in nc_engine::AlarmKind::ALL {
        assert!(
            doc.contains(k.code()) && doc.contains(k.title()),
            "{} {} missing from docs/alarms.md",
            k.code(),
            k.title()
        );
    }
    // And the other way: every alarm row of the table is a kind of `AlarmKind::ALL`, so the list
    // that scenarios resolve alarm codes through misses none.
    let rows: Vec<&str> =
        doc.lines().filter_map(|l| l.strip_prefix("| `")).filter_map(|l| l.split('`').next()).collect();
    assert!(rows.len() >= nc_engine::AlarmKind::ALL.len(), "{} alarm rows", rows.len());
    for code in rows {
        assert!(
            nc_engine::AlarmKind::ALL.iter().any(|k| k.code() == code),
            "docs/alarms.md lists {code}, which is not in AlarmKind::ALL"
        );
    }
}
