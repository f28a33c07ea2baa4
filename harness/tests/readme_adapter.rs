//! The adapter line of the README and of `examples/python-adapter/README.md` works as written:
//! `nc-conform conform --adapter "python3 examples/python-adapter/toy_adapter.py"`, with no
//! `--nc-conform PATH` and no `nc-conform` on the PATH (the toy finds the binary that started it).

use std::path::PathBuf;
use std::process::Command;

use nc_conform::conform::process::split_command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The first line of `file` that starts with `prefix`, inside a code block.
fn line_of(file: &str, prefix: &str) -> String {
    let text = std::fs::read_to_string(root().join(file)).unwrap();
    text.lines()
        .map(str::trim)
        .find(|l| l.starts_with(prefix))
        .unwrap_or_else(|| panic!("{file} has no line starting with {prefix}"))
        .to_string()
}

#[test]
fn the_example_adapter_line_runs_as_written() {
    let line = line_of("examples/python-adapter/README.md", "target/debug/nc-conform conform --adapter");
    let words = split_command(&line).unwrap();
    assert_eq!(words[1..], ["conform", "--adapter", "python3 examples/python-adapter/toy_adapter.py"]);
    // The README of the repository shows the same adapter line.
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    assert!(readme.contains("--adapter \"python3 examples/python-adapter/toy_adapter.py\""));
    let out = Command::new(env!("CARGO_BIN_EXE_nc-conform"))
        .current_dir(root())
        .args(&words[1..])
        .args(["--filter", "fanuc/repeat/l_is_k", "--filter", "gsk/peck/high_speed_seed_example"])
        .env_remove("NC_CONFORM")
        .env("PATH", "/usr/local/bin:/usr/bin:/bin")
        .output()
        .expect("nc-conform runs");
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(text.contains("toy-python"), "{text}");
    assert!(text.contains("2 passed") || text.contains("passed: 2") || text.contains("passed 2"), "{text}");
}
