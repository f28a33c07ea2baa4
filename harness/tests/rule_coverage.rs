//! Every rule id defined in `docs/rules/` is checked by at least one scenario under `scenarios/`
//! (its `rules:` list or the rule of one of its expectations).

use std::path::{Path, PathBuf};

use nc_conform::scenario::load;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn scenario_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    for e in rd {
        let p = e.unwrap().path();
        if p.is_dir() {
            scenario_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "yaml" || e == "yml") {
            out.push(p);
        }
    }
}

/// Rule ids defined in `docs/rules/*.md` (the bold id at the start of each rule paragraph).
fn defined_rules() -> Vec<String> {
    let mut ids = Vec::new();
    let Ok(rd) = std::fs::read_dir(root().join("docs/rules")) else { return ids };
    for e in rd {
        let text = std::fs::read_to_string(e.unwrap().path()).unwrap_or_default();
        for line in text.lines() {
            if let Some(rest) = line.strip_prefix("**") {
                let id: String =
                    rest.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '-').collect();
                if id.matches('-').count() == 2 {
                    ids.push(id);
                }
            }
        }
    }
    ids.sort();
    ids.dedup();
    ids
}

/// Every rule in docs/ is checked by at least one scenario (the `rules:` lists).
#[test]
fn every_rule_has_a_scenario() {
    let mut files = Vec::new();
    scenario_files(&root().join("scenarios"), &mut files);
    let mut cited = std::collections::BTreeSet::new();
    for p in &files {
        let rel = p.to_string_lossy().to_string();
        let s = load::load(p, &rel).unwrap_or_else(|e| panic!("{}", e.render_plain()));
        cited.extend(s.rules.iter().cloned());
        cited.extend(s.expect.rules().into_iter().map(String::from));
    }
    let missing: Vec<String> = defined_rules().into_iter().filter(|r| !cited.contains(r)).collect();
    assert!(missing.is_empty(), "{} rule ids have no scenario:\n{}", missing.len(), missing.join("\n"));
}
