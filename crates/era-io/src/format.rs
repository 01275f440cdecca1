//! One door for FRF files in every format: detection by content (the extension is a
//! hint), and a small [`FrfReader`]/[`FrfWriter`] pair that each format implements.
//!
//! | format | detected by | read | written |
//! |---|---|---|---|
//! | [`FrfFormat::Csv`] | anything else; `.csv` | [`crate::csv`] | full precision |
//! | [`FrfFormat::Uff`] | first non-blank line `-1`; `.uff`, `.unv`, `.uf` | [`crate::uff`] | 58 ASCII, or 58b with `binary` |
//! | [`FrfFormat::Mat`] | `MATLAB 5.0 MAT-file` header; `.mat` | [`crate::mat`] | `FRF` + `FreqV` |
//!
//! A CSV carries the channel table of a UFF file as metadata lines
//! (`# output_1: node 12 +Z`), so UFF → CSV → UFF keeps the nodes.

use crate::csv::{format_frf_csv, read_frf_csv};
use crate::frf_file::FrfFile;
pub use crate::frf_file::{channel_metadata, channels_from_metadata, time_hint, ReadOptions};
use crate::uff::UffWriteOptions;
use crate::IoError;
use std::path::Path;

/// A file format for FRFs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrfFormat {
    /// Our CSV (docs/design.md §4).
    Csv,
    /// Universal File Format dataset 58 (ASCII or binary 58b).
    Uff,
    /// MATLAB MAT v5 (compressed or not).
    Mat,
}

/// Reads FRFs from a file.
pub trait FrfReader {
    /// Reads `path`.
    ///
    /// # Errors
    /// [`IoError`] naming the file and where in it the problem is.
    fn read_frf(&self, path: &Path, opts: &ReadOptions) -> Result<FrfFile, IoError>;
}

/// Writes FRFs to a file, through a temporary file and a rename.
pub trait FrfWriter {
    /// Writes `file` to `path`.
    ///
    /// # Errors
    /// [`IoError`] naming the file.
    fn write_frf(&self, path: &Path, file: &FrfFile, uff: UffWriteOptions) -> Result<(), IoError>;
}

impl FrfFormat {
    /// Lower-case name for messages.
    pub fn name(self) -> &'static str {
        match self {
            FrfFormat::Csv => "CSV",
            FrfFormat::Uff => "UFF",
            FrfFormat::Mat => "MAT",
        }
    }

    /// The format an extension names, if any.
    pub fn from_extension(path: &Path) -> Option<FrfFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "csv" | "txt" => Some(FrfFormat::Csv),
            "uff" | "unv" | "uf" => Some(FrfFormat::Uff),
            "mat" => Some(FrfFormat::Mat),
            _ => None,
        }
    }

    /// The format of a file from its first bytes; the extension only breaks ties and
    /// catches a file that is not what its name says. The file is opened through
    /// [`crate::input::read_input`] like every input (mapped when regular, so nothing past
    /// the head is read; refused when a folder; a FIFO cannot block the open).
    ///
    /// # Errors
    /// [`IoError`] when the file cannot be read, is empty, is a MAT v7.3 (HDF5) file, or
    /// is named `.uff`/`.mat` but does not start like one.
    pub fn detect(path: &Path) -> Result<FrfFormat, IoError> {
        FrfFormat::detect_bytes(&crate::input::read_input(path)?, path)
    }

    /// [`FrfFormat::detect`] on the bytes of a file already read (only the first 4 kB
    /// are looked at); `path` names it and gives the extension.
    ///
    /// # Errors
    /// As [`FrfFormat::detect`].
    pub fn detect_bytes(bytes: &[u8], path: &Path) -> Result<FrfFormat, IoError> {
        let head = &bytes[..bytes.len().min(4096)];
        if head.is_empty() {
            return Err(IoError::format(path, "", "the file is empty"));
        }
        let by_content = if head.starts_with(b"MATLAB 5.0 MAT-file") {
            Some(FrfFormat::Mat)
        } else if head.starts_with(b"MATLAB 7.3 MAT-file") {
            return Err(IoError::format(
                path,
                "",
                "MAT v7.3 (HDF5) files are not read: save with -v7 (the default) or -v6",
            ));
        } else if crate::time::hdf5_offset(bytes).is_some() {
            return Err(IoError::format(
                path,
                "",
                format!(
                    "is an HDF5 file, which holds time histories for era, not FRFs: {}",
                    time_hint(path)
                ),
            ));
        } else if crate::uff::looks_like_uff(head) {
            Some(FrfFormat::Uff)
        } else {
            None
        };
        match (by_content, FrfFormat::from_extension(path)) {
            (Some(f), _) => Ok(f),
            (None, Some(named @ (FrfFormat::Uff | FrfFormat::Mat))) => Err(IoError::format(
                path,
                "line 1: ",
                format!(
                    "the name says {} but the content does not start like one ('{}')",
                    named.name(),
                    first_line(head)
                ),
            )),
            (None, _) => Ok(FrfFormat::Csv),
        }
    }
}

fn first_line(head: &[u8]) -> String {
    let line = head.split(|b| *b == b'\n').next().unwrap_or(&[]);
    let s: String = String::from_utf8_lossy(line).chars().take(40).collect();
    s.trim_end().to_string()
}

impl FrfReader for FrfFormat {
    fn read_frf(&self, path: &Path, opts: &ReadOptions) -> Result<FrfFile, IoError> {
        match self {
            FrfFormat::Csv => read_frf_csv(path, opts.default_quantity),
            FrfFormat::Uff => crate::uff::read_frf_uff(path, opts.default_quantity),
            FrfFormat::Mat => {
                crate::mat::parse_frf_mat_with(&crate::input::read_input(path)?, path, opts)
            }
        }
    }
}

impl FrfWriter for FrfFormat {
    fn write_frf(&self, path: &Path, file: &FrfFile, uff: UffWriteOptions) -> Result<(), IoError> {
        let unit = |key: &str| file.metadata.get(key).map(String::as_str);
        match self {
            FrfFormat::Csv => write_frf_csv_keeping(path, file, |key| {
                key == "force_unit" || key == "response_unit"
            }),
            FrfFormat::Uff => crate::uff::write_uff58(
                path,
                &file.frf,
                file.channels.as_ref(),
                (unit("response_unit"), unit("force_unit")),
                uff,
            ),
            FrfFormat::Mat => crate::mat::write_frf_mat_file(path, file),
        }
    }
}

/// Writes an FRF CSV with the channel table and the metadata entries whose key `keep`
/// accepts, as `# key: value` lines.
///
/// # Errors
/// [`IoError`] naming the file.
pub fn write_frf_csv_keeping(
    path: &Path,
    file: &FrfFile,
    keep: impl Fn(&str) -> bool,
) -> Result<(), IoError> {
    let mut extra: Vec<(String, String)> = file
        .metadata
        .iter()
        .filter(|(k, _)| keep(k))
        .map(|(k, v)| (k.clone(), v.clone()))
        .collect();
    if let Some(t) = &file.channels {
        extra.extend(channel_metadata(t));
    }
    let extra: Vec<(&str, &str)> = extra
        .iter()
        .map(|(k, v)| (k.as_str(), v.as_str()))
        .collect();
    crate::atomic::write_atomic(path, format_frf_csv(&file.frf, &extra).as_bytes())
}

/// Detects the format of `path` and reads it.
///
/// # Errors
/// As [`FrfFormat::detect`] and the format's reader.
pub fn read_frf_file(path: &Path, opts: &ReadOptions) -> Result<(FrfFile, FrfFormat), IoError> {
    let bytes = crate::input::read_input(path)?;
    parse_frf_bytes(&bytes, path, opts)
}

/// Detects the format of bytes already read (see [`crate::input::read_input`]) and parses
/// them; `path` names them in messages.
///
/// # Errors
/// As [`FrfFormat::detect_bytes`] and the format's parser.
pub fn parse_frf_bytes(
    bytes: &[u8],
    path: &Path,
    opts: &ReadOptions,
) -> Result<(FrfFile, FrfFormat), IoError> {
    let format = FrfFormat::detect_bytes(bytes, path)?;
    let file = match format {
        FrfFormat::Csv => crate::csv::parse_frf_csv(
            crate::input::utf8(bytes, path)?,
            path,
            opts.default_quantity,
        )?,
        FrfFormat::Uff => {
            let contents = crate::uff::parse_uff(bytes, path, true)?;
            crate::uff::frf_from_uff(path, &contents, opts.default_quantity)?
        }
        FrfFormat::Mat => crate::mat::parse_frf_mat_with(bytes, path, opts)?,
    };
    Ok((file, format))
}

/// Writes in the format the extension names.
///
/// # Errors
/// [`IoError`] for an extension that names no FRF format, and the writer's errors.
pub fn write_frf_file(path: &Path, file: &FrfFile, uff: UffWriteOptions) -> Result<(), IoError> {
    let format = FrfFormat::from_extension(path).ok_or_else(|| {
        IoError::format(
            path,
            "",
            "cannot tell the output format from the extension: use .csv, .uff (or .unv) or .mat",
        )
    })?;
    format.write_frf(path, file, uff)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frf_file::ChannelTable;
    use std::collections::BTreeMap;

    #[test]
    fn channel_lines_round_trip() {
        let mut t = ChannelTable::numbered(2, 1);
        t.outputs[1].dof.direction = -5;
        t.inputs[0].entity = "shaker A".into();
        let meta: BTreeMap<String, String> = channel_metadata(&t).into_iter().collect();
        assert_eq!(meta["output_2"], "node 2 -RY");
        assert_eq!(channels_from_metadata(&meta, 2, 1), Some(t));
        assert_eq!(channels_from_metadata(&meta, 3, 1), None);
    }

    #[test]
    fn an_hdf5_file_is_sent_to_era_frf() {
        let mut bytes = b"\x89HDF\r\n\x1a\n".to_vec();
        bytes.resize(2048, 0);
        for name in ["view_0.hdf5", "frf.csv"] {
            let e = FrfFormat::detect_bytes(&bytes, Path::new(name))
                .unwrap_err()
                .to_string();
            assert!(
                e.contains(name)
                    && e.contains("HDF5")
                    && e.contains("era frf")
                    && e.contains("--from-time"),
                "{e}"
            );
            assert!(!e.contains("UTF-8"), "{e}");
        }
    }

    #[test]
    fn detection_by_content_with_the_extension_as_a_hint() {
        let dir = tempfile::tempdir().unwrap();
        let uff_named_csv = dir.path().join("a.csv");
        std::fs::write(&uff_named_csv, "    -1\n    58\n").unwrap();
        assert_eq!(FrfFormat::detect(&uff_named_csv).unwrap(), FrfFormat::Uff);
        let csv_named_uff = dir.path().join("b.uff");
        std::fs::write(&csv_named_uff, "frequency_hz,H1_1_re,H1_1_im\n").unwrap();
        let e = FrfFormat::detect(&csv_named_uff).unwrap_err().to_string();
        assert!(e.contains("b.uff") && e.contains("UFF"), "{e}");
        let empty = dir.path().join("c.uff");
        std::fs::write(&empty, "").unwrap();
        assert!(FrfFormat::detect(&empty)
            .unwrap_err()
            .to_string()
            .contains("empty"));
    }
}
