//! Replays the fuzz seed corpora (`fuzz/corpus/<target>/`, importer and entry-point targets included) and every stored crash input
//! (`fuzz/regressions/<target>/`) through the targets' logic in `nc_conform::fuzz`, on stable,
//! so that a crash once found and fixed stays fixed. One test per target; a failure names every
//! input that panicked, with its panic message.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

/// Every input file of `fuzz/<kind>/<target>/` (READMEs and dot files are not inputs).
fn inputs(kind: &str, target: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join("fuzz").join(kind).join(target);
    let Ok(entries) = std::fs::read_dir(&dir) else { return Vec::new() };
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .filter(|p| {
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
            !name.starts_with('.') && !name.eq_ignore_ascii_case("README.md")
        })
        .collect();
    files.sort();
    files
}

/// Runs `f` on every corpus and regression input of `target`; fails naming the inputs that panic.
fn replay(target: &str, f: fn(&[u8])) {
    let corpus = inputs("corpus", target);
    assert!(!corpus.is_empty(), "no seed corpus in fuzz/corpus/{target}/");
    let mut failures = Vec::new();
    for path in corpus.iter().chain(inputs("regressions", target).iter()) {
        let data = std::fs::read(path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
        if let Err(e) = catch_unwind(AssertUnwindSafe(|| f(&data))) {
            let msg = e
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "a panic".into());
            failures.push(format!("{}: {msg}", path.display()));
        }
    }
    assert!(
        failures.is_empty(),
        "{} input(s) of target `{target}` failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn gcode_corpus_and_regressions() {
    replay("gcode", nc_conform::fuzz::gcode);
}

#[test]
fn scenario_yaml_corpus_and_regressions() {
    replay("scenario_yaml", nc_conform::fuzz::scenario_yaml);
}

#[test]
fn engine_case_corpus_and_regressions() {
    replay("engine_case", nc_conform::fuzz::engine_case);
}

#[test]
fn import_csv_corpus_and_regressions() {
    replay("import_csv", nc_conform::import::fuzz::import_csv);
}

#[test]
fn import_jsonl_corpus_and_regressions() {
    replay("import_jsonl", nc_conform::import::fuzz::import_jsonl);
}

#[test]
fn import_vcd_corpus_and_regressions() {
    replay("import_vcd", nc_conform::import::fuzz::import_vcd);
}

#[test]
fn import_shdr_corpus_and_regressions() {
    replay("import_shdr", nc_conform::import::fuzz::import_shdr);
}

#[test]
fn cli_files_corpus_and_regressions() {
    replay("cli_files", nc_conform::cli::fuzz_files::cli_files);
}

#[test]
fn nesting_corpus_and_regressions() {
    replay("nesting", nc_conform::fuzz::nesting);
}

#[test]
fn adapter_lines_corpus_and_regressions() {
    replay("adapter_lines", nc_conform::fuzz::adapter_lines);
}
