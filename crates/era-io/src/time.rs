//! Time histories for FRF estimation (`era frf`): CSV, MAT v5 and HDF5.
//!
//! The format is told by content: a MAT v5 header, the HDF5 signature (at byte 0, or at
//! 512, 1024, … as in MATLAB v7.3 files and files with a user block), CSV otherwise.
//!
//! - **CSV**: optional `# key: value` lines, then a header `time_s,name1,name2,…` and one
//!   row per sample. The sample rate is `(n − 1) / (t_last − t_0)`; every time stamp must
//!   lie within 1 % of a sample interval of the uniform grid (printed time stamps are
//!   rounded; a missing or doubled sample is not).
//! - **MAT v5**: a numeric matrix (`--variable NAME` when the file holds several, or
//!   several names whose columns are placed side by side). Channels have no names; the
//!   sample rate comes from the command line.
//! - **HDF5** (read with the pure-Rust `hdf5-reader` crate, so no C library is needed):
//!   one 2-D dataset whose columns are channels, or several 1-D datasets, one channel
//!   each (`--dataset PATH`, repeatable). Without `--dataset`, the file's only 2-D
//!   floating-point dataset is taken. Channel names come from a `channel_names` dataset
//!   beside a 2-D dataset (the LADISK layout), or from the 1-D datasets' names. The sample
//!   rate comes from a `sample_rate`, `sample_rate_hz` or `fs` dataset or attribute beside
//!   the data, or from a `time` dataset.
//!
//! Matrices are read with time along the longer side: rows are samples unless the matrix
//! has more columns than rows (MATLAB writes v7.3 arrays transposed).
//!
//! Samples must be finite: NaN or infinity is refused, naming the file, the channel and
//! the sample (CSV: the line). Channels of unequal length are refused.

use crate::mat::{contain, parse_mat_matrix};
use crate::IoError;
use era::params::limits::Saturated;
use std::collections::BTreeMap;
use std::path::Path;

/// What a time-history file is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimeFormat {
    /// `time_s` plus named channels.
    Csv,
    /// MATLAB v5.
    Mat,
    /// HDF5 (also MATLAB v7.3).
    Hdf5,
}

impl TimeFormat {
    /// Name for messages.
    pub fn name(self) -> &'static str {
        match self {
            TimeFormat::Csv => "CSV",
            TimeFormat::Mat => "MAT v5",
            TimeFormat::Hdf5 => "HDF5",
        }
    }

    /// Tells the format by content.
    ///
    /// # Errors
    /// [`IoError`] when the file cannot be read or is empty.
    pub fn detect(bytes: &[u8], path: &Path) -> Result<TimeFormat, IoError> {
        if bytes.is_empty() {
            return Err(IoError::format(path, "", "the file is empty"));
        }
        if bytes.starts_with(b"MATLAB 5.0 MAT-file") {
            return Ok(TimeFormat::Mat);
        }
        if hdf5_offset(bytes).is_some() {
            return Ok(TimeFormat::Hdf5);
        }
        Ok(TimeFormat::Csv)
    }
}

const HDF5_SIGNATURE: &[u8] = b"\x89HDF\r\n\x1a\n";

/// Where the HDF5 superblock starts: 0, 512, 1024, 2048, …
pub(crate) fn hdf5_offset(bytes: &[u8]) -> Option<usize> {
    let mut at = 0;
    while at + HDF5_SIGNATURE.len() <= bytes.len() {
        if bytes[at..].starts_with(HDF5_SIGNATURE) {
            return Some(at);
        }
        at = if at == 0 { 512 } else { at * 2 };
    }
    None
}

/// Sampled channels read from a file.
#[derive(Debug, Clone, PartialEq)]
pub struct TimeHistory {
    /// The format read.
    pub format: TimeFormat,
    /// One vector per channel, all of one length.
    pub columns: Vec<Vec<f64>>,
    /// Channel names, when the file has them.
    pub names: Option<Vec<String>>,
    /// Sample rate from the file, Hz, and where it came from.
    pub sample_rate: Option<(f64, String)>,
    /// What was read, for messages ("variable flexible_structure_dat, 8523 × 30").
    pub description: String,
    /// `# key: value` lines of a CSV file (keys lower-case).
    pub metadata: BTreeMap<String, String>,
}

impl TimeHistory {
    /// Samples per channel.
    pub fn samples(&self) -> usize {
        self.columns.first().map_or(0, Vec::len)
    }
    /// Number of channels.
    pub fn channels(&self) -> usize {
        self.columns.len()
    }
    /// Name of channel `c` (0-based): its name, or its 1-based number.
    pub fn label(&self, c: usize) -> String {
        match &self.names {
            Some(n) => n[c].clone(),
            None => format!("column {}", c + 1),
        }
    }
}

/// Which part of a MAT or HDF5 file to read.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TimeSelection {
    /// MAT variables (`--variable`), side by side.
    pub variables: Vec<String>,
    /// HDF5 datasets (`--dataset`): one 2-D dataset, or 1-D datasets, one per channel.
    pub datasets: Vec<String>,
}

/// Reads a time-history file of any of the three formats.
///
/// # Errors
/// [`IoError`] naming the file and what is wrong (with the line for CSV).
pub fn read_time_file(path: &Path, selection: &TimeSelection) -> Result<TimeHistory, IoError> {
    parse_time_input(crate::input::read_input(path)?, path, selection)
}

/// Parses the bytes of a time-history file of any of the three formats, told apart by
/// content; `path` names the file in messages.
///
/// # Errors
/// [`IoError`] naming the file and what is wrong (with the line for CSV).
pub fn parse_time_input(
    bytes: crate::input::InputBytes,
    path: &Path,
    selection: &TimeSelection,
) -> Result<TimeHistory, IoError> {
    let format = TimeFormat::detect(&bytes, path)?;
    let misplaced = |flag: &str, fmt: &str| {
        Err(IoError::format(
            path,
            "",
            format!(
                "{flag} applies to {fmt} files; this is a {} file",
                format.name()
            ),
        ))
    };
    if !selection.variables.is_empty() && format != TimeFormat::Mat {
        return misplaced("--variable", "MAT");
    }
    if !selection.datasets.is_empty() && format != TimeFormat::Hdf5 {
        return misplaced("--dataset", "HDF5");
    }
    match format {
        TimeFormat::Csv => {
            let text = crate::input::utf8(&bytes, path).map_err(|e| match e {
                IoError::Format {
                    path,
                    location,
                    message,
                } => IoError::Format {
                    path,
                    location,
                    message: format!("{message} (neither MAT v5 nor HDF5 either)"),
                },
                other => other,
            })?;
            parse_time_csv(text, path)
        }
        TimeFormat::Mat => read_mat(&bytes, path, &selection.variables),
        TimeFormat::Hdf5 => read_hdf5(bytes.into_vec(), path, &selection.datasets),
    }
}

/// Parses a time-history CSV (module documentation).
///
/// # Errors
/// [`IoError`] naming the line and column.
pub fn parse_time_csv(text: &str, path: &Path) -> Result<TimeHistory, IoError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let (metadata, header) = crate::text::metadata_and_header(text);
    let Some((header_line, header)) = header else {
        return Err(IoError::format(
            path,
            "",
            "no header line (expected time_s,<channel>,…)",
        ));
    };
    let names: Vec<String> = header.split(',').map(|c| c.trim().to_string()).collect();
    if names[0] != "time_s" {
        return Err(IoError::at(
            path,
            header_line,
            "",
            format!(
                "the first column must be time_s (seconds), found '{}'",
                names[0]
            ),
        ));
    }
    era::params::limits::CHANNELS
        .check(
            format!(
                "the header names {} channels",
                names.len().saturating_sub(1)
            ),
            names.len().saturating_sub(1) as u64,
        )
        .map_err(|e| IoError::limit(path, e))?;
    if names.len() < 2 {
        return Err(IoError::at(
            path,
            header_line,
            "",
            "no channels after time_s".into(),
        ));
    }
    if let Some(c) = names.iter().position(String::is_empty) {
        return Err(IoError::at(
            path,
            header_line,
            "",
            format!("column {} has no name", c + 1),
        ));
    }
    for (a, name) in names.iter().enumerate() {
        if names[..a].contains(name) {
            return Err(IoError::at(
                path,
                header_line,
                name,
                "the name appears twice".into(),
            ));
        }
    }
    let width = names.len();
    let mut columns: Vec<Vec<f64>> = vec![Vec::new(); width];
    for (n, line) in text.lines().enumerate().skip(header_line) {
        let trimmed = line.trim();
        if trimmed.is_empty() || trimmed.starts_with('#') {
            continue;
        }
        let mut count = 0;
        for (c, cell) in trimmed.split(',').enumerate() {
            count += 1;
            if c >= width {
                continue;
            }
            let cell = cell.trim();
            let value: f64 = cell.parse().map_err(|_| {
                IoError::at(path, n + 1, &names[c], format!("'{cell}' is not a number"))
            })?;
            if !value.is_finite() {
                return Err(IoError::at(
                    path,
                    n + 1,
                    &names[c],
                    format!("{cell}: samples must be finite"),
                ));
            }
            columns[c].push(value);
        }
        if count != width {
            return Err(IoError::at(
                path,
                n + 1,
                "",
                format!(
                    "{count} fields, the header has {width}: every channel needs a sample on every row"
                ),
            ));
        }
    }
    let time = columns.remove(0);
    let samples = time.len();
    if samples < 2 {
        return Err(IoError::format(
            path,
            "",
            format!("{samples} samples: at least 2 are needed for a sample rate"),
        ));
    }
    let span = time[samples - 1] - time[0];
    let dt = span / (samples - 1) as f64;
    if dt.is_nan() || dt <= 0.0 {
        return Err(IoError::format(
            path,
            "column time_s: ",
            "time does not increase".to_string(),
        ));
    }
    let first_data_line = |k: usize| -> usize {
        // Line number of the k-th sample (for messages): count data lines again.
        text.lines()
            .enumerate()
            .skip(header_line)
            .filter(|(_, l)| !l.trim().is_empty() && !l.trim().starts_with('#'))
            .nth(k)
            .map_or(0, |(n, _)| n + 1)
    };
    for (k, t) in time.iter().enumerate() {
        let expected = time[0] + k as f64 * dt;
        if (t - expected).abs() > 0.01 * dt {
            return Err(IoError::at(
                path,
                first_data_line(k),
                "time_s",
                format!(
                    "{t} s is off the uniform grid of {dt:.6e} s steps (expected {expected}): a missing or repeated sample?"
                ),
            ));
        }
    }
    let description = format!("{} channels x {samples} samples", width - 1);
    Ok(TimeHistory {
        format: TimeFormat::Csv,
        columns,
        names: Some(names[1..].to_vec()),
        sample_rate: Some((1.0 / dt, "the time_s column".into())),
        description,
        metadata,
    })
}

/// Splits a column-major `rows × cols` matrix into channels, time along the longer side.
fn channels_of(values: &[f64], rows: usize, cols: usize) -> Vec<Vec<f64>> {
    if rows >= cols {
        values.chunks(rows.max(1)).map(<[f64]>::to_vec).collect()
    } else {
        (0..rows)
            .map(|r| (0..cols).map(|c| values[c * rows + r]).collect())
            .collect()
    }
}

fn read_mat(bytes: &[u8], path: &Path, variables: &[String]) -> Result<TimeHistory, IoError> {
    let wanted: Vec<Option<&str>> = if variables.is_empty() {
        vec![None]
    } else {
        variables.iter().map(|v| Some(v.as_str())).collect()
    };
    let mut columns: Vec<Vec<f64>> = Vec::new();
    let mut parts = Vec::new();
    let mut first: Option<(String, usize)> = None;
    for v in wanted {
        let m = parse_mat_matrix(bytes, path, v)?;
        let channels = channels_of(&m.values, m.rows, m.cols);
        let samples = channels.first().map_or(0, Vec::len);
        if let Some((name, n)) = &first {
            if *n != samples {
                return Err(IoError::format(
                    path,
                    "",
                    format!(
                        "variable {} has {samples} samples, {name} has {n}: channels must have equal lengths",
                        m.name
                    ),
                ));
            }
        } else {
            first = Some((m.name.clone(), samples));
        }
        parts.push(format!("variable {} ({} x {})", m.name, m.rows, m.cols));
        columns.extend(channels);
    }
    let samples = columns.first().map_or(0, Vec::len);
    Ok(TimeHistory {
        format: TimeFormat::Mat,
        description: format!(
            "{}: {} channels x {samples} samples",
            parts.join(" + "),
            columns.len()
        ),
        columns,
        names: None,
        sample_rate: None,
        metadata: BTreeMap::new(),
    })
}

fn read_hdf5(bytes: Vec<u8>, path: &Path, datasets: &[String]) -> Result<TimeHistory, IoError> {
    let offset = hdf5_offset(&bytes).unwrap_or(0);
    let bytes = if offset > 0 {
        bytes[offset..].to_vec()
    } else {
        bytes
    };
    let fail = |m: String| IoError::format(path, "", m);
    let file_len = bytes.len() as u64;
    let outcome = contain(move || -> Result<TimeHistory, String> {
        let file = hdf5_reader::Hdf5File::from_vec(bytes)
            .map_err(|e| format!("not a readable HDF5 file: {e}"))?;
        let all = list_datasets(&file)?;
        let listing = || {
            all.iter()
                .map(|(p, shape)| format!("{p} {shape:?}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let chosen: Vec<String> = if datasets.is_empty() {
            let candidates: Vec<&(String, Vec<u64>)> = all
                .iter()
                .filter(|(p, shape)| shape.len() == 2 && is_float(&file, p))
                .collect();
            match candidates.as_slice() {
                [one] => vec![one.0.clone()],
                [] => {
                    return Err(format!(
                        "no 2-D floating-point dataset; name the channels with --dataset (the file has: {})",
                        listing()
                    ))
                }
                _ => {
                    return Err(format!(
                        "several 2-D datasets; name one with --dataset (the file has: {})",
                        listing()
                    ))
                }
            }
        } else {
            datasets
                .iter()
                .map(|d| d.trim_start_matches('/').to_string())
                .collect()
        };
        let mut columns = Vec::new();
        let mut names = Vec::new();
        let mut named = true;
        let mut first: Option<(String, usize)> = None;
        for name in &chosen {
            let Some((_, shape)) = all.iter().find(|(p, _)| p == name) else {
                return Err(format!("no dataset {name} (the file has: {})", listing()));
            };
            check_declared_shape(name, shape, file_len)?;
            let ds = file
                .dataset(name)
                .map_err(|e| format!("dataset {name}: {e}"))?;
            let values = read_numeric(&ds).map_err(|e| format!("dataset {name}: {e}"))?;
            let channels = match shape.as_slice() {
                [_] => vec![values],
                [rows, cols] => {
                    let (rows, cols) = (*rows as usize, *cols as usize);
                    // Row-major: transpose into column-major first.
                    let col_major: Vec<f64> = (0..rows * cols)
                        .map(|t| values[(t % rows) * cols + t / rows])
                        .collect();
                    channels_of(&col_major, rows, cols)
                }
                s => {
                    return Err(format!(
                        "dataset {name} has shape {s:?}: 1-D or 2-D is needed"
                    ))
                }
            };
            for (c, ch) in channels.iter().enumerate() {
                if let Some(k) = ch.iter().position(|v| !v.is_finite()) {
                    return Err(format!(
                        "dataset {name}, channel {}, sample {k}: {} (samples must be finite)",
                        c + 1,
                        ch[k]
                    ));
                }
            }
            let samples = channels.first().map_or(0, Vec::len);
            match &first {
                Some((other, n)) if *n != samples => {
                    return Err(format!(
                        "dataset {name} has {samples} samples, {other} has {n}: channels must have equal lengths"
                    ))
                }
                None => first = Some((name.clone(), samples)),
                _ => {}
            }
            if shape.len() == 1 {
                names.push(name.rsplit('/').next().unwrap_or(name).to_string());
            } else {
                match channel_names(&file, name, channels.len()) {
                    Some(n) => names.extend(n),
                    None => named = false,
                }
            }
            columns.extend(channels);
        }
        let sample_rate = sample_rate_near(&file, &chosen[0], first.map_or(0, |f| f.1));
        let samples = columns.first().map_or(0, Vec::len);
        Ok(TimeHistory {
            format: TimeFormat::Hdf5,
            description: format!(
                "dataset {}: {} channels x {samples} samples",
                chosen.join(" + "),
                columns.len()
            ),
            columns,
            names: named.then_some(names),
            sample_rate,
            metadata: BTreeMap::new(),
        })
    });
    match outcome {
        Ok(Ok(history)) => Ok(history),
        Ok(Err(message)) => Err(fail(message)),
        Err(_) => Err(fail(
            "not a readable HDF5 file (its structure is corrupt)".into(),
        )),
    }
}

/// Every dataset's path and shape, depth first.
fn list_datasets(file: &hdf5_reader::Hdf5File) -> Result<Vec<(String, Vec<u64>)>, String> {
    fn walk(
        group: &hdf5_reader::group::Group,
        prefix: &str,
        out: &mut Vec<(String, Vec<u64>)>,
        depth: usize,
    ) -> Result<(), String> {
        if depth > 32 {
            return Err("groups nested deeper than 32 levels".into());
        }
        let (groups, datasets) = group.members().map_err(|e| e.to_string())?;
        for d in datasets {
            out.push((format!("{prefix}{}", d.name()), d.shape().to_vec()));
        }
        for g in groups {
            walk(&g, &format!("{prefix}{}/", g.name()), out, depth + 1)?;
        }
        Ok(())
    }
    let mut out = Vec::new();
    let root = file.root_group().map_err(|e| e.to_string())?;
    walk(&root, "", &mut out, 0)?;
    Ok(out)
}

fn is_float(file: &hdf5_reader::Hdf5File, path: &str) -> bool {
    file.dataset(path)
        .is_ok_and(|d| matches!(d.dtype(), hdf5_reader::Datatype::FloatingPoint { .. }))
}

/// A dataset's values as f64, whatever its numeric type (row-major order).
/// Deflate cannot shrink data more than about 1032 to 1 (LZ4 about 255 to 1).
const MAX_COMPRESSION: u64 = 1032;

/// Checks the shape an HDF5 dataset declares before its values are read: each side
/// against [`era::params::limits::SAMPLES`], and the element count against what the file can
/// hold (its length times the best compression ratio, at one byte per element). A
/// 1.4 kB file declaring an unwritten 1e8×2 dataset would otherwise read gigabytes of
/// fill values.
fn check_declared_shape(name: &str, shape: &[u64], file_len: u64) -> Result<(), String> {
    for &side in shape {
        era::params::limits::SAMPLES
            .check(format!("dataset {name} declares shape {shape:?}"), side)
            .map_err(|e| e.to_string())?;
    }
    let elements = shape.iter().fold(1u64, |a, &d| a.saturating_mul(d));
    let can_hold = file_len.saturating_mul(MAX_COMPRESSION);
    if elements > can_hold {
        return Err(format!(
            "dataset {name} declares shape {shape:?} ({} values) but a file of {file_len} bytes can hold at most {can_hold} even compressed: its data is missing",
            Saturated(usize::try_from(elements).ok())
        ));
    }
    Ok(())
}

fn read_numeric(ds: &hdf5_reader::Dataset) -> Result<Vec<f64>, String> {
    use hdf5_reader::Datatype as D;
    let err = |e: hdf5_reader::error::Error| e.to_string();
    let values = match ds.dtype() {
        D::FloatingPoint { size: 8, .. } => ds
            .read_array::<f64>()
            .map_err(err)?
            .iter()
            .copied()
            .collect(),
        D::FloatingPoint { size: 4, .. } => ds
            .read_array::<f32>()
            .map_err(err)?
            .iter()
            .map(|v| f64::from(*v))
            .collect(),
        D::FixedPoint { size, signed, .. } => match (size, signed) {
            (8, true) => ds
                .read_array::<i64>()
                .map_err(err)?
                .iter()
                .map(|v| *v as f64)
                .collect(),
            (8, false) => ds
                .read_array::<u64>()
                .map_err(err)?
                .iter()
                .map(|v| *v as f64)
                .collect(),
            (4, true) => ds
                .read_array::<i32>()
                .map_err(err)?
                .iter()
                .map(|v| f64::from(*v))
                .collect(),
            (4, false) => ds
                .read_array::<u32>()
                .map_err(err)?
                .iter()
                .map(|v| f64::from(*v))
                .collect(),
            (2, true) => ds
                .read_array::<i16>()
                .map_err(err)?
                .iter()
                .map(|v| f64::from(*v))
                .collect(),
            (2, false) => ds
                .read_array::<u16>()
                .map_err(err)?
                .iter()
                .map(|v| f64::from(*v))
                .collect(),
            (1, true) => ds
                .read_array::<i8>()
                .map_err(err)?
                .iter()
                .map(|v| f64::from(*v))
                .collect(),
            (1, false) => ds
                .read_array::<u8>()
                .map_err(err)?
                .iter()
                .map(|v| f64::from(*v))
                .collect(),
            _ => return Err(format!("{size}-byte integers are not read")),
        },
        other => return Err(format!("type {other:?} is not numeric")),
    };
    Ok(values)
}

/// The parent group's path of a dataset path ("" for the root).
fn parent(path: &str) -> &str {
    path.rsplit_once('/').map_or("", |(p, _)| p)
}

fn sibling(dataset: &str, name: &str) -> String {
    match parent(dataset) {
        "" => name.to_string(),
        p => format!("{p}/{name}"),
    }
}

fn channel_names(file: &hdf5_reader::Hdf5File, dataset: &str, count: usize) -> Option<Vec<String>> {
    let names = file
        .dataset(&sibling(dataset, "channel_names"))
        .ok()?
        .read_strings()
        .ok()?;
    (names.len() == count).then(|| names.into_iter().map(|n| n.trim().to_string()).collect())
}

/// A sample rate stored beside the data: a scalar dataset or an attribute (of the
/// dataset or its group) called `sample_rate`, `sample_rate_hz` or `fs`, or a `time`
/// dataset of the right length.
fn sample_rate_near(
    file: &hdf5_reader::Hdf5File,
    dataset: &str,
    samples: usize,
) -> Option<(f64, String)> {
    const NAMES: [&str; 3] = ["sample_rate", "sample_rate_hz", "fs"];
    let good = |v: f64| (v.is_finite() && v > 0.0).then_some(v);
    for name in NAMES {
        let path = sibling(dataset, name);
        if let Ok(ds) = file.dataset(&path) {
            if let Ok(v) = read_numeric(&ds) {
                if let [one] = v.as_slice() {
                    if let Some(rate) = good(*one) {
                        return Some((rate, format!("dataset {path}")));
                    }
                }
            }
        }
        if let Ok(ds) = file.dataset(dataset) {
            if let Some(rate) = ds
                .attribute(name)
                .ok()
                .and_then(|a| a.read_as_f64().ok())
                .and_then(good)
            {
                return Some((rate, format!("attribute {name} of {dataset}")));
            }
        }
        let group = parent(dataset);
        let g = if group.is_empty() {
            file.root_group().ok()
        } else {
            file.group(group).ok()
        };
        if let Some(rate) = g
            .and_then(|g| g.attribute(name).ok())
            .and_then(|a| a.read_as_f64().ok())
            .and_then(good)
        {
            return Some((rate, format!("attribute {name} of /{group}")));
        }
    }
    let path = sibling(dataset, "time");
    let t = read_numeric(&file.dataset(&path).ok()?).ok()?;
    if t.len() == samples && samples >= 2 {
        let dt = (t[samples - 1] - t[0]) / (samples - 1) as f64;
        if let Some(rate) = good(1.0 / dt) {
            return Some((rate, format!("dataset {path}")));
        }
    }
    None
}

/// Parses a channel list: 1-based numbers, ranges `a-b`, and names (where the file has
/// them), separated by commas: `1,2`, `3-30`, `force`, `acc,3`.
///
/// # Errors
/// A message naming the item: a number out of range, a reversed range, or an unknown
/// name (with the names the file has).
pub fn parse_channels(spec: &str, history: &TimeHistory) -> Result<Vec<usize>, String> {
    let count = history.channels();
    let mut out = Vec::new();
    let number = |s: &str| -> Result<usize, String> {
        let n: usize = s
            .trim()
            .parse()
            .map_err(|_| format!("'{s}' is not a channel number"))?;
        if n == 0 || n > count {
            return Err(format!(
                "channel {n} is out of range: the file has {count} channels, numbered 1 to {count}"
            ));
        }
        Ok(n - 1)
    };
    for item in spec.split(',') {
        let item = item.trim();
        if item.is_empty() {
            return Err(format!("empty item in '{spec}'"));
        }
        if let Some(names) = &history.names {
            if let Some(c) = names.iter().position(|n| n == item) {
                out.push(c);
                continue;
            }
        }
        let looks_numeric = item
            .chars()
            .all(|c| c.is_ascii_digit() || c == '-' || c.is_whitespace());
        if looks_numeric {
            if let Some((a, b)) = item.split_once('-') {
                let (a, b) = (number(a)?, number(b)?);
                if a > b {
                    return Err(format!("range {item} runs backwards"));
                }
                out.extend(a..=b);
            } else {
                out.push(number(item)?);
            }
            continue;
        }
        return Err(match &history.names {
            Some(names) => format!(
                "no channel named '{item}' (the file has: {})",
                names.join(", ")
            ),
            None => format!(
                "no channel named '{item}': this {} file has no channel names; use column numbers 1 to {count}",
                history.format.name()
            ),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn csv(text: &str) -> Result<TimeHistory, IoError> {
        parse_time_csv(text, Path::new("t.csv"))
    }

    #[test]
    fn csv_reads_channels_and_sample_rate() {
        let h = csv("# note: x\ntime_s,f,a\n0,1,2\n0.001,3,4\n0.002,5,6\n").unwrap();
        assert_eq!(h.columns, vec![vec![1.0, 3.0, 5.0], vec![2.0, 4.0, 6.0]]);
        assert_eq!(
            h.names.as_deref(),
            Some(&["f".to_string(), "a".to_string()][..])
        );
        assert!((h.sample_rate.unwrap().0 - 1000.0).abs() < 1e-9);
        assert_eq!(h.metadata["note"], "x");
    }

    #[test]
    fn csv_errors_name_line_and_column() {
        let e = csv("time_s,f,a\n0,1,2\n0.001,3\n").unwrap_err().to_string();
        assert!(
            e.contains("line 3") && e.contains("2 fields, the header has 3"),
            "{e}"
        );
        let e = csv("time_s,f,a\n0,1,2\n0.001,NaN,4\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("line 3, column f") && e.contains("finite"),
            "{e}"
        );
        let e = csv("t,f\n0,1\n").unwrap_err().to_string();
        assert!(e.contains("first column must be time_s"), "{e}");
        let e = csv("time_s,f\n0,1\n0.001,2\n0.003,3\n0.004,4\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("off the uniform grid"), "{e}");
        let e = csv("time_s,f,f\n0,1,2\n").unwrap_err().to_string();
        assert!(e.contains("appears twice"), "{e}");
    }

    #[test]
    fn channel_lists() {
        let h = csv("time_s,force,acc,x\n0,1,2,3\n1,1,2,3\n").unwrap();
        assert_eq!(parse_channels("1,3", &h).unwrap(), vec![0, 2]);
        assert_eq!(parse_channels("2-3", &h).unwrap(), vec![1, 2]);
        assert_eq!(parse_channels("acc,force", &h).unwrap(), vec![1, 0]);
        let e = parse_channels("accel", &h).unwrap_err();
        assert!(
            e.contains("no channel named 'accel'") && e.contains("force, acc, x"),
            "{e}"
        );
        assert!(parse_channels("4", &h)
            .unwrap_err()
            .contains("out of range"));
        assert!(parse_channels("3-1", &h).unwrap_err().contains("backwards"));
        assert!(parse_channels("0", &h)
            .unwrap_err()
            .contains("out of range"));
    }

    #[test]
    fn matrices_are_read_with_time_along_the_longer_side() {
        // 3 x 2 column-major: rows are samples.
        assert_eq!(
            channels_of(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0], 3, 2),
            vec![vec![1.0, 2.0, 3.0], vec![4.0, 5.0, 6.0]]
        );
        // 2 x 3: columns are samples.
        assert_eq!(
            channels_of(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0], 2, 3),
            vec![vec![1.0, 3.0, 5.0], vec![2.0, 4.0, 6.0]]
        );
    }
}
