//! Files the tool reads: one place that opens and reads them, for the command line and the
//! library modules alike.

use std::path::Path;

use crate::check::Tolerances;
use crate::diag::InputError;

/// A path as the user wrote it.
pub fn display_name(path: &Path) -> String {
    path.display().to_string()
}

/// Reads a UTF-8 text file.
///
/// # Errors
///
/// An unreadable file or one that is not UTF-8, named in the error.
pub fn read_utf8(path: &Path) -> Result<String, InputError> {
    std::fs::read_to_string(path)
        .map_err(|e| InputError::new(display_name(path), format!("cannot read: {e}")))
}

/// Reads a tolerance file (`docs/checking.md`).
///
/// # Errors
///
/// Unreadable file, bad YAML, unknown keys (located).
pub fn load_tolerances(path: &Path) -> Result<Tolerances, InputError> {
    let text = read_utf8(path)?;
    serde_saphyr::from_str::<Tolerances>(&text)
        .map_err(|e| InputError::new(display_name(path), format!("bad tolerance file: {e}")))
}
