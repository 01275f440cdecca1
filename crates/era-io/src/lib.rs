//! File formats of `era`: one module per format.
//!
//! - [`csv`]: our self-describing FRF CSV (DESIGN.md §4), read and written;
//! - [`decay_csv`]: free-decay records (time, velocity, displacement) for `era friction`;
//! - [`model_json`]: `model.json` and `fit.json`;
//! - [`mat`]: MATLAB MAT files (model and FRFs) for MATLAB, Octave and scipy;
//! - [`uff`]: Universal File Format datasets 58/58b (FRFs, read and written) and 55
//!   (mode shapes, written);
//! - [`mod@format`]: detection by content and one reader/writer trait over CSV, UFF and MAT;
//! - [`atomic`]: every write goes to a temporary file in the destination folder and is
//!   renamed into place, so a failed run never leaves a half-written file.
//!
//! Errors name the file, and where it applies the line and column.

pub mod atomic;
pub mod csv;
pub mod decay_csv;
pub mod format;
pub mod mat;
mod mat_check;
pub mod model_json;
pub mod time;
pub mod uff;

use std::collections::BTreeMap;
use std::path::PathBuf;
use thiserror::Error;

/// A problem with a file.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum IoError {
    /// The file could not be opened, read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The content is malformed.
    #[error("{path}: {location}{message}")]
    Format {
        /// The file.
        path: PathBuf,
        /// "line 12, column H2_1_re: " or empty.
        location: String,
        /// What is wrong.
        message: String,
    },
}

impl IoError {
    pub(crate) fn format(
        path: impl Into<PathBuf>,
        location: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        IoError::Format {
            path: path.into(),
            location: location.into(),
            message: message.into(),
        }
    }
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        IoError::Io {
            path: path.into(),
            source,
        }
    }
}

impl IoError {
    /// A format error at a 1-based line and, when not empty, a named column.
    pub(crate) fn at(path: &std::path::Path, line: usize, column: &str, message: String) -> Self {
        let location = if column.is_empty() {
            format!("line {line}: ")
        } else {
            format!("line {line}, column {column}: ")
        };
        IoError::format(path, location, message)
    }
}

/// A `# key: value` metadata line as (lower-case key, value); `None` for other lines
/// (a `#` line without a colon is a plain comment).
/// The `# key: value` lines before a CSV header (keys lower-case; blank lines skipped)
/// and the header itself as (1-based line number, trimmed text), if there is one.
pub(crate) fn metadata_and_header(text: &str) -> (BTreeMap<String, String>, Option<(usize, &str)>) {
    let mut metadata = BTreeMap::new();
    for (index, line) in text.lines().enumerate() {
        let trimmed = line.trim();
        if trimmed.is_empty() {
            continue;
        }
        if trimmed.starts_with('#') {
            if let Some((key, value)) = metadata_line(trimmed) {
                metadata.insert(key, value);
            }
            continue;
        }
        return (metadata, Some((index + 1, trimmed)));
    }
    (metadata, None)
}

pub(crate) fn metadata_line(trimmed: &str) -> Option<(String, String)> {
    let (key, value) = trimmed.strip_prefix('#')?.split_once(':')?;
    Some((key.trim().to_ascii_lowercase(), value.trim().to_string()))
}
