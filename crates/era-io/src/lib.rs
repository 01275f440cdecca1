//! File formats of `era`: one module per format.
//!
//! - [`csv`]: our self-describing FRF CSV (docs/design.md §4), read and written;
//! - [`decay_csv`]: free-decay records (time, velocity, displacement) for `era friction`;
//! - [`model_json`]: `model.json` and `fit.json`;
//! - [`mat`]: MATLAB MAT files (model and FRFs) for MATLAB, Octave and scipy;
//! - [`uff`]: Universal File Format datasets 58/58b (FRFs, read and written) and 55
//!   (mode shapes, written);
//! - [`geometry`]: test geometry (nodes, trace lines, coordinate systems) from UFF
//!   15/2411/82/18/2420 or our geometry CSV, and where a file's channels sit on it;
//! - [`frf_file`]: the types every FRF format shares ([`frf_file::FrfFile`],
//!   [`frf_file::ChannelTable`]);
//! - [`text`]: CSV metadata lines, shared by the CSV readers;
//! - [`input`]: every input is read once, into memory, with a cap on streams;
//! - [`mod@format`]: detection by content and one reader/writer trait over CSV, UFF and MAT;
//! - [`atomic`]: every write goes to a temporary file in the destination folder and is
//!   renamed into place, so a failed run never leaves a half-written file.
//!
//! Errors name the file, and where it applies the line and column.

pub mod atomic;
pub mod csv;
pub mod decay_csv;
pub mod fleet;
pub mod format;
pub mod frf_file;
pub mod geometry;
pub mod input;
pub mod mat;
mod mat_check;
pub mod model_json;
mod table;
pub mod text;
pub mod time;
pub mod tracks;
pub mod uff;

use std::path::PathBuf;
use thiserror::Error;

/// A problem with a file.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum IoError {
    /// The file could not be opened, read or written. The OS error is part of the
    /// message and not a separate cause, so that a chain of causes prints it once.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        error: std::io::Error,
    },
    /// A size in the file, or the file itself, is above one of `era::params::limits`.
    #[error("{path}: {limit}")]
    Limit {
        /// The file.
        path: PathBuf,
        /// What was asked and what is allowed.
        limit: era::params::limits::LimitError,
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
        // Every format error passes here: text quoted from the file (names, headers,
        // cells) is shown with its control characters escaped, never sent raw to a
        // terminal.
        IoError::Format {
            path: path.into(),
            location: text::escaped_message(&location.into()),
            message: text::escaped_message(&message.into()),
        }
    }
    pub(crate) fn limit(path: impl Into<PathBuf>, limit: era::params::limits::LimitError) -> Self {
        IoError::Limit {
            path: path.into(),
            limit,
        }
    }
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        IoError::Io {
            path: path.into(),
            error: source,
        }
    }
}

/// A file that cannot be read, written or parsed is the caller's to mend.
impl era::error::InputError for IoError {
    fn is_input_error(&self) -> bool {
        true
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
