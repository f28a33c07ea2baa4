//! Fuzz target `cli_files` (logic here, in the command line, since it drives the command line;
//! the target and `harness/tests/fuzz_corpus.rs` call [`cli_files`]): the bytes as one of the
//! files a user hands to the command line,
//! read by `nc-conform run` or `nc-conform check` exactly as typed at a shell (the arguments go
//! through the same `clap` parser and the same subcommand code as the binary's).
//!
//! An input picks the file's role (a program of one dialect, a scenario, a parameter file, a
//! recorded trace, a CSV column map, a tolerance file) and where the path points: a regular file
//! holding the bytes, the bytes repeated up to a realistic size ([`MAX_FILE_BYTES`]), or a
//! special file (`/dev/zero`, `/dev/null`, a directory, a path that does not exist). The other
//! files of the command line are small valid fixtures written once per process into a scratch
//! directory. The trace and the reports go to `/dev/null`.
//!
//! A bug is a panic, an abort, an exit status other than 0, 1 or 2; libFuzzer's own limits
//! (`-rss_limit_mb`, `-timeout`, set by `scripts/fuzz-nightly` and `.clusterfuzzlite/`) turn
//! unbounded memory or time into crashes too.

use std::path::PathBuf;
use std::sync::OnceLock;

use arbitrary::{Arbitrary, Unstructured};
use clap::Parser;

use super::{Cli, Command};
use crate::fuzz::SCENARIO;

/// The largest file an input writes (its bytes repeated), bytes.
pub const MAX_FILE_BYTES: usize = 8 << 20;

/// A short program per dialect that runs to its end, for the parameter-file role.
const PROGRAMS: [(&str, &str, &str); 5] = [
    ("gsk-lathe", "nc", "G0 X20 Z5\nM03 S500\nG04 X0.1\nM30\n"),
    ("fanuc-mill", "nc", "G0 X0 Y0 Z10\nM03 S500\nG04 P100\nM30\n"),
    ("knd-lathe", "nc", "G0 X20 Z5\nM03 S500\nG04 X0.1\nM30\n"),
    ("linuxcnc", "ngc", "G0 X1 Z5\nM3 S500\nG4 P0.1\nM2\n"),
    ("heidenhain", "h", "0 BEGIN PGM T MM\n1 L Z+10 FMAX\n2 END PGM T MM\n"),
];

/// The CSV trace the map role reads.
const CSV_TRACE: &str = "t,x,z,s\n0,0,10,0\n10,0,10,500\n20,10,2,1000\n";

/// What the fuzzed file is to the command line.
#[derive(Debug, Arbitrary)]
enum Role {
    /// `run FILE --dialect D`
    Program(u8),
    /// `run FILE.yaml --format F`
    Scenario(u8),
    /// `run PROGRAM --dialect D --params FILE`
    Params(u8),
    /// `check SCENARIO --trace FILE [--format F] [--lenient]`
    Trace(u8, bool),
    /// `check SCENARIO --trace TRACE.csv --map FILE`
    Map,
    /// `check SCENARIO --trace TRACE.jsonl --tolerances FILE`
    Tolerances,
}

/// Where the path points.
#[derive(Debug, Arbitrary)]
enum Source {
    /// A regular file holding the bytes.
    File,
    /// A regular file holding the bytes `times` times (up to [`MAX_FILE_BYTES`]).
    Repeated(u32),
    /// `/dev/zero`: endless zero bytes.
    DevZero,
    /// `/dev/null`: an empty special file.
    DevNull,
    /// A directory.
    Directory,
    /// A path that does not exist.
    Missing,
}

/// The scratch directory of this process with its fixtures.
struct Fixtures {
    dir: PathBuf,
}

impl Fixtures {
    fn get() -> &'static Fixtures {
        static F: OnceLock<Fixtures> = OnceLock::new();
        F.get_or_init(|| {
            let dir = std::env::temp_dir().join(format!("nc-conform-fuzz-cli-{}", std::process::id()));
            std::fs::create_dir_all(dir.join("a-directory")).expect("scratch directory");
            let f = Fixtures { dir };
            std::fs::write(f.path("scenario.yaml"), SCENARIO).expect("fixture");
            std::fs::write(f.path("trace.csv"), CSV_TRACE).expect("fixture");
            std::fs::write(f.path("map.yaml"), crate::import::fuzz::FUZZ_MAP).expect("fixture");
            for (dialect, ext, text) in PROGRAMS {
                std::fs::write(f.path(&format!("{dialect}.{ext}")), text).expect("fixture");
            }
            // The recorded trace of `check`: the reference run of the scenario, written by `run`.
            let code =
                cli(&["run", &f.arg("scenario.yaml"), "--format", "jsonl", "--out", &f.arg("trace.jsonl")]);
            assert!(code <= 1, "the fixture scenario does not run: exit {code}");
            f
        })
    }

    fn path(&self, name: &str) -> PathBuf {
        self.dir.join(name)
    }

    fn arg(&self, name: &str) -> String {
        self.path(name).display().to_string()
    }
}

/// Runs the command line `nc-conform ARGS` in this process; returns its exit status.
///
/// # Panics
///
/// When `clap` refuses the arguments (the target only builds valid command lines).
fn cli(args: &[&str]) -> u8 {
    let argv = std::iter::once("nc-conform").chain(args.iter().copied());
    let parsed = Cli::try_parse_from(argv).unwrap_or_else(|e| panic!("bad fuzz command line {args:?}: {e}"));
    match parsed.command {
        Command::Run(a) => super::run::run(&a),
        Command::Check(a) => super::check::run(&a),
        other => panic!("not a file-reading command: {other:?}"),
    }
}

/// Fuzz target `cli_files`: see the module doc.
///
/// # Panics
///
/// On a bug: the command line panics or exits with a status other than 0, 1 or 2.
pub fn cli_files(data: &[u8]) {
    let Some(args) = command_line(data) else { return };
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let code = cli(&refs);
    assert!(code <= 2, "`nc-conform {}` exited {code}", refs.join(" "));
}

/// Writes the input's file and returns the command line that reads it.
fn command_line(data: &[u8]) -> Option<Vec<String>> {
    // The role and the source first (`arbitrary`), then the file's bytes as they are.
    let mut u = Unstructured::new(data);
    let (Ok(role), Ok(source)) = (Role::arbitrary(&mut u), Source::arbitrary(&mut u)) else { return None };
    let bytes = u.take_rest();
    let f = Fixtures::get();
    let dialect = |i: u8| PROGRAMS[i as usize % PROGRAMS.len()];
    let ext = match &role {
        Role::Program(d) => dialect(*d).1,
        Role::Scenario(_) | Role::Params(_) | Role::Map | Role::Tolerances => "yaml",
        Role::Trace(k, _) => ["jsonl", "csv", "vcd", "shdr"][*k as usize % 4],
    };
    let file = fuzzed_file(f, ext, &source, bytes);
    let file = file.display().to_string();
    let scenario = f.arg("scenario.yaml");
    let devnull = "/dev/null";
    let args: Vec<String> = match &role {
        Role::Program(d) => {
            strings(&["run", &file, "--dialect", dialect(*d).0, "--sample-us", "10000", "--out", devnull])
        }
        Role::Scenario(k) => {
            let format = ["jsonl", "vcd", "timing"][*k as usize % 3];
            strings(&["run", &file, "--format", format, "--out", devnull])
        }
        Role::Params(d) => {
            let (name, ext, _) = dialect(*d);
            let program = f.arg(&format!("{name}.{ext}"));
            strings(&["run", &program, "--dialect", name, "--params", &file, "--out", devnull])
        }
        Role::Trace(k, lenient) => {
            let mut a = strings(&["check", &scenario, "--trace", &file, "--report", devnull]);
            if k & 4 != 0 {
                a.extend(strings(&["--format", ["jsonl", "csv", "vcd", "shdr"][*k as usize % 4]]));
            }
            if ext == "csv" || ext == "shdr" {
                a.extend(strings(&["--map", &f.arg("map.yaml")]));
            }
            if *lenient {
                a.push("--lenient".into());
            }
            a
        }
        Role::Map => strings(&["check", &scenario, "--trace", &f.arg("trace.csv"), "--map", &file]),
        Role::Tolerances => {
            strings(&["check", &scenario, "--trace", &f.arg("trace.jsonl"), "--tolerances", &file])
        }
    };
    Some(args)
}

fn strings(a: &[&str]) -> Vec<String> {
    a.iter().map(|s| s.to_string()).collect()
}

/// The path of the fuzzed file: written into the scratch directory, or a special file.
fn fuzzed_file(f: &Fixtures, ext: &str, source: &Source, bytes: &[u8]) -> PathBuf {
    let path = f.path(&format!("fuzzed.{ext}"));
    match source {
        Source::File => std::fs::write(&path, bytes).expect("scratch file"),
        Source::Repeated(times) => {
            let times =
                if bytes.is_empty() { 0 } else { (*times as usize).min(MAX_FILE_BYTES / bytes.len()) };
            std::fs::write(&path, bytes.repeat(times)).expect("scratch file");
        }
        Source::DevZero => return PathBuf::from("/dev/zero"),
        Source::DevNull => return PathBuf::from("/dev/null"),
        Source::Directory => return f.path("a-directory"),
        Source::Missing => return f.path("no-such-file"),
    }
    path
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seed(name: &str) -> Vec<u8> {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus/cli_files");
        std::fs::read(dir.join(name)).unwrap()
    }

    #[test]
    fn seeds_decode_to_the_command_lines_they_are_named_after() {
        let a = command_line(&seed("program_knd_g93.nc")).unwrap();
        assert_eq!(a[..4], ["run".to_string(), a[1].clone(), "--dialect".into(), "knd-lathe".into()]);
        assert!(std::fs::read_to_string(&a[1]).unwrap().contains("G93"));
        let a = command_line(&seed("program_2mb_of_comments.nc")).unwrap();
        assert_eq!(std::fs::metadata(&a[1]).unwrap().len(), 200_000 * 17);
        let a = command_line(&seed("program_dev_null")).unwrap();
        assert_eq!(a[1], "/dev/null");
        let a = command_line(&seed("params_fanuc.yaml")).unwrap();
        assert!(a.contains(&"--params".to_string()) && a.contains(&"fanuc-mill".to_string()));
        let a = command_line(&seed("trace_basic.csv")).unwrap();
        assert_eq!(a[0], "check");
        assert!(a.contains(&"--map".to_string()));
        let a = command_line(&seed("tolerances.yaml")).unwrap();
        assert!(a.contains(&"--tolerances".to_string()));
    }
}
