//! Files the tool reads: one place that opens and reads them, for the command line and the
//! library modules alike, each read bounded by a size cap (`docs/input-limits.md`).
//!
//! A file larger than its cap is refused with an error that names the file and the cap, before
//! it is read whole: a regular file by its size, anything else (`/dev/zero`, a pipe) by reading
//! at most one byte past the cap. Recorded traces are not read here: [`crate::import`] streams
//! them line by line with its own bound on a line's length.

use std::io::Read;
use std::path::Path;

use crate::check::Tolerances;
use crate::diag::InputError;

/// How large a file of one kind may be.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Cap {
    /// What the file is, as the error says it ("a program").
    pub what: &'static str,
    /// The default cap in MiB.
    pub default_mib: u64,
    /// The environment variable that raises (or lowers) it, when a user could need more.
    pub env: Option<&'static str>,
    /// The most lines, with the environment variable that changes it: what a program costs in
    /// memory follows its blocks more than its bytes (about 220 bytes a block).
    pub lines: Option<(u64, &'static str)>,
    /// The longest line, bytes (a 60 MB line of words took more than 512 MiB to parse).
    pub line_bytes: Option<usize>,
}

/// G-code programs (`run PROGRAM`, `check PROGRAM`, a scenario's `program_file`): 64 MiB and
/// 1 000 000 lines, each about 220 MB of memory when run; `NC_CONFORM_MAX_PROGRAM_MIB` and
/// `NC_CONFORM_MAX_PROGRAM_LINES` raise them.
pub const PROGRAM: Cap = Cap {
    what: "a program",
    default_mib: 64,
    env: Some("NC_CONFORM_MAX_PROGRAM_MIB"),
    lines: Some((1_000_000, "NC_CONFORM_MAX_PROGRAM_LINES")),
    line_bytes: Some(MAX_PROGRAM_LINE),
};

/// The longest program line read, bytes: far beyond any control's block (LinuxCNC's is 252).
pub const MAX_PROGRAM_LINE: usize = 64 * 1024;

/// YAML files (scenarios, `--params`, `--map`, `--tolerances`): 4 MiB.
pub const YAML: Cap = Cap { what: "a YAML file", default_mib: 4, env: None, lines: None, line_bytes: None };

/// A whole number read from the environment variable `var`, else `default`.
fn env_or(var: &str, default: u64) -> u64 {
    std::env::var(var).ok().and_then(|v| v.trim().parse::<u64>().ok()).filter(|n| *n > 0).unwrap_or(default)
}

impl Cap {
    /// The cap in bytes, after the environment override (a whole number of MiB, at least 1).
    pub fn bytes(self) -> u64 {
        let mib = match self.env {
            Some(v) => env_or(v, self.default_mib),
            None => self.default_mib,
        };
        mib.saturating_mul(1024 * 1024)
    }

    /// The refusal of a file with a line longer than the cap, if it has one.
    fn too_long_line(self, bytes: &[u8]) -> Option<String> {
        let max = self.line_bytes?;
        let mut start = 0;
        for (no, end) in memchr::memchr_iter(b'\n', bytes).chain(std::iter::once(bytes.len())).enumerate() {
            if end - start > max {
                return Some(format!(
                    "line {} is {} bytes long, more than the {max} bytes allowed for a line of {}",
                    no + 1,
                    end - start,
                    self.what
                ));
            }
            start = end + 1;
        }
        None
    }

    /// The refusal of a file of more lines than the cap, if it has more.
    fn too_many_lines(self, bytes: &[u8]) -> Option<String> {
        let (default, var) = self.lines?;
        let most = env_or(var, default);
        let lines = memchr::memchr_iter(b'\n', bytes).count() as u64 + u64::from(!bytes.ends_with(b"\n"));
        (lines > most).then(|| {
            format!(
                "{lines} lines, more than the {most} lines allowed for {}; set {var} to raise it",
                self.what
            )
        })
    }

    /// The refusal of a file larger than the cap (without the file's name).
    fn refusal(self) -> String {
        let mib = self.bytes() / (1024 * 1024);
        let raise = match self.env {
            Some(v) => format!("; set {v} to raise it"),
            None => String::new(),
        };
        format!("larger than the {mib} MiB limit for {}{raise}", self.what)
    }
}

/// A path as the user wrote it.
pub fn display_name(path: &Path) -> String {
    path.display().to_string()
}

/// Reads a whole file of at most `cap`; the error message does not name the file (the caller
/// does, as it names it to the user).
///
/// # Errors
///
/// The file cannot be opened or read, or it is larger than the cap.
pub fn read_capped(path: &Path, cap: Cap) -> Result<Vec<u8>, String> {
    let limit = cap.bytes();
    // A named pipe with no writer blocks `open` for ever (a scenario's `program_file` naming one
    // hung the run): refused, except the standard streams a user names on purpose (/dev/stdin).
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let device = path.starts_with("/dev") || path.starts_with("/proc");
        if !device && std::fs::metadata(path).is_ok_and(|m| m.file_type().is_fifo()) {
            return Err(
                "cannot read: it is a named pipe (FIFO), which may never end; give a file, or /dev/stdin"
                    .into(),
            );
        }
    }
    let f = std::fs::File::open(path).map_err(|e| format!("cannot read: {e}"))?;
    let meta = f.metadata().map_err(|e| format!("cannot read: {e}"))?;
    if meta.is_dir() {
        return Err("cannot read: it is a directory".into());
    }
    if meta.is_file() && meta.len() > limit {
        return Err(cap.refusal());
    }
    let mut bytes =
        Vec::with_capacity(if meta.is_file() { usize::try_from(meta.len()).unwrap_or(0) } else { 0 });
    f.take(limit.saturating_add(1)).read_to_end(&mut bytes).map_err(|e| format!("cannot read: {e}"))?;
    if bytes.len() as u64 > limit {
        return Err(cap.refusal());
    }
    if let Some(refusal) = cap.too_many_lines(&bytes).or_else(|| cap.too_long_line(&bytes)) {
        return Err(refusal);
    }
    Ok(bytes)
}

/// Reads a text file of at most `cap` (invalid UTF-8 is replaced, a leading byte-order mark
/// dropped), as programs are read.
///
/// # Errors
///
/// As [`read_capped`], with the file named.
pub fn read_text(path: &Path, cap: Cap) -> Result<String, InputError> {
    let bytes = read_capped(path, cap).map_err(|m| InputError::new(display_name(path), m))?;
    Ok(lossy_text(bytes))
}

/// Bytes as text: invalid UTF-8 replaced, a leading byte-order mark dropped.
pub fn lossy_text(bytes: Vec<u8>) -> String {
    let text = match String::from_utf8(bytes) {
        Ok(t) => t,
        Err(e) => String::from_utf8_lossy(e.as_bytes()).into_owned(),
    };
    match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    }
}

/// Reads a UTF-8 text file of at most `cap`.
///
/// # Errors
///
/// As [`read_capped`], or the file is not UTF-8; the file is named.
pub fn read_utf8(path: &Path, cap: Cap) -> Result<String, InputError> {
    let name = display_name(path);
    let bytes = read_capped(path, cap).map_err(|m| InputError::new(&name, m))?;
    String::from_utf8(bytes)
        .map_err(|_| InputError::new(name, "cannot read: stream did not contain valid UTF-8"))
}

/// Reads a tolerance file (`docs/checking.md`).
///
/// # Errors
///
/// Unreadable file, bad YAML, unknown keys (located).
pub fn load_tolerances(path: &Path) -> Result<Tolerances, InputError> {
    let text = read_utf8(path, YAML)?;
    serde_saphyr::from_str::<Tolerances>(&text).map_err(|e| {
        let pe = crate::params_yaml::yaml_error(&text, &e);
        let message = pe.message.replacen("invalid parameter file", "bad tolerance file", 1);
        InputError::at(display_name(path), &text, pe.span, message, pe.expected)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn special_files_are_read_bounded() {
        if Path::new("/dev/zero").exists() {
            let e = read_capped(Path::new("/dev/zero"), YAML).unwrap_err();
            assert_eq!(e, "larger than the 4 MiB limit for a YAML file");
        }
    }

    #[test]
    fn programs_are_capped_in_lines_too() {
        let cap = Cap { lines: Some((3, "NC_CONFORM_TEST_UNSET_VARIABLE")), line_bytes: Some(4), ..PROGRAM };
        assert_eq!(cap.too_long_line(b"G0\nG123\nM30"), None);
        assert_eq!(
            cap.too_long_line(b"G0\nG1234\nM30").as_deref(),
            Some("line 2 is 5 bytes long, more than the 4 bytes allowed for a line of a program")
        );
        assert_eq!(cap.too_many_lines(b"G0\nG1\nM30\n"), None);
        assert_eq!(cap.too_many_lines(b"G0\nG1\nM30"), None);
        assert_eq!(
            cap.too_many_lines(b"G0\nG1\nG2\nM30").as_deref(),
            Some("4 lines, more than the 3 lines allowed for a program; set NC_CONFORM_TEST_UNSET_VARIABLE to raise it")
        );
    }

    #[test]
    fn directories_and_missing_files_are_refused() {
        assert!(read_capped(Path::new("."), YAML).unwrap_err().contains("directory"));
        assert!(read_capped(Path::new("no/such/file"), YAML).unwrap_err().starts_with("cannot read"));
    }

    #[test]
    fn byte_order_mark_dropped_and_bad_utf8_replaced() {
        assert_eq!(lossy_text(b"\xef\xbb\xbfG0\xff".to_vec()), "G0\u{fffd}");
    }
}
