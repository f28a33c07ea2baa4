//! The harness's layering: the command line lives in `src/cli/`, one file per subcommand, and no
//! library module imports it (issue 15, part 5).

use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("readable source directory") {
        let path = entry.expect("directory entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn library_modules_never_import_the_command_line() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let cli = src.join("cli");
    let mut offenders = Vec::new();
    for f in files.iter().filter(|f| !f.starts_with(&cli) && !f.ends_with("main.rs")) {
        let text = std::fs::read_to_string(f).expect("readable source file");
        for (no, line) in text.lines().enumerate() {
            if line.contains("crate::cli") || line.contains("super::cli") || line.contains("nc_conform::cli")
            {
                offenders.push(format!("{}:{}: {}", f.display(), no + 1, line.trim()));
            }
        }
    }
    assert!(offenders.is_empty(), "library modules importing the command line:\n{}", offenders.join("\n"));
}

#[test]
fn the_command_line_is_one_module() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let top: Vec<String> = std::fs::read_dir(&src)
        .expect("src")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("cli"))
        .collect();
    assert_eq!(top, ["cli"], "command-line files outside src/cli/");
    for sub in ["mod.rs", "run.rs", "run_scenario.rs", "campaign.rs", "check.rs", "conform.rs"] {
        assert!(src.join("cli").join(sub).is_file(), "src/cli/{sub} missing");
    }
}
