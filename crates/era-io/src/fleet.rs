//! The tables of a fleet of records: one row per record and mode, in Apache Parquet, so
//! that pandas, polars, DuckDB and Spark read them as they are.
//!
//! [`write_modes`] writes a `modes.parquet` (through the safe writer: staged, synced and
//! renamed), [`read_modes`] reads one back with every column checked by name and type.
//! The columns:
//!
//! | column | type | |
//! |---|---|---|
//! | `record_id` | string | the manifest's id |
//! | `time` | timestamp (µs, UTC), nullable | the record's start |
//! | `mode` | uint32 | 1-based, in the record's table order |
//! | `frequency_hz`, `damping_ratio` | float64 | |
//! | `frequency_std_hz`, `damping_ratio_std` | float64, nullable | null when not estimated |
//! | `physical` | bool | the verb's verdict |
//! | `mpc`, `emac` | float64, nullable | null when the verb has none |
//! | `shape_re`, `shape_im` | list of float64 | the mode shape, one entry per channel |
//! | `channels` | list of string | the channel of each shape entry |
//!
//! The shape is two lists (real and imaginary parts) because Parquet has no complex type;
//! the channel names let records with missing channels be compared entry by entry.

use crate::table::{cell, column};
use crate::IoError;
use arrow_array::builder::{
    BooleanBuilder, Float64Builder, ListBuilder, StringBuilder, TimestampMicrosecondBuilder,
    UInt32Builder,
};
use arrow_array::{
    Array, ArrayRef, BooleanArray, Float64Array, ListArray, RecordBatch, StringArray,
    TimestampMicrosecondArray, UInt32Array,
};
use arrow_schema::{DataType, Field, Schema, TimeUnit};
use std::path::Path;
use std::sync::Arc;

/// One mode of one record.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeRow {
    /// The record's id.
    pub record_id: String,
    /// The record's start, microseconds since 1970-01-01 UTC.
    pub time_us: Option<i64>,
    /// 1-based position in the record's table.
    pub mode: u32,
    /// Natural frequency, Hz.
    pub frequency_hz: f64,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// Standard deviation of the frequency, Hz.
    pub frequency_std_hz: Option<f64>,
    /// Standard deviation of the damping ratio.
    pub damping_ratio_std: Option<f64>,
    /// Whether the verb called the mode physical.
    pub physical: bool,
    /// Modal phase collinearity.
    pub mpc: Option<f64>,
    /// Extended modal amplitude coherence.
    pub emac: Option<f64>,
    /// The shape's real parts, one per channel.
    pub shape_re: Vec<f64>,
    /// The shape's imaginary parts.
    pub shape_im: Vec<f64>,
    /// The channel of each shape entry.
    pub channels: Vec<String>,
}

fn schema() -> Arc<Schema> {
    let list_f64 = DataType::List(Arc::new(Field::new("item", DataType::Float64, true)));
    let list_str = DataType::List(Arc::new(Field::new("item", DataType::Utf8, true)));
    Arc::new(Schema::new(vec![
        Field::new("record_id", DataType::Utf8, false),
        Field::new(
            "time",
            DataType::Timestamp(TimeUnit::Microsecond, Some("UTC".into())),
            true,
        ),
        Field::new("mode", DataType::UInt32, false),
        Field::new("frequency_hz", DataType::Float64, false),
        Field::new("damping_ratio", DataType::Float64, false),
        Field::new("frequency_std_hz", DataType::Float64, true),
        Field::new("damping_ratio_std", DataType::Float64, true),
        Field::new("physical", DataType::Boolean, false),
        Field::new("mpc", DataType::Float64, true),
        Field::new("emac", DataType::Float64, true),
        Field::new("shape_re", list_f64.clone(), false),
        Field::new("shape_im", list_f64, false),
        Field::new("channels", list_str, false),
    ]))
}

/// The rows as one Arrow batch.
fn batch(rows: &[ModeRow]) -> Result<RecordBatch, arrow_schema::ArrowError> {
    let mut id = StringBuilder::new();
    let mut time = TimestampMicrosecondBuilder::new().with_timezone("UTC");
    let mut mode = UInt32Builder::new();
    let mut f64s: Vec<Float64Builder> = (0..7).map(|_| Float64Builder::new()).collect();
    let mut physical = BooleanBuilder::new();
    let mut re = ListBuilder::new(Float64Builder::new());
    let mut im = ListBuilder::new(Float64Builder::new());
    let mut channels = ListBuilder::new(StringBuilder::new());
    for r in rows {
        id.append_value(&r.record_id);
        time.append_option(r.time_us);
        mode.append_value(r.mode);
        f64s[0].append_value(r.frequency_hz);
        f64s[1].append_value(r.damping_ratio);
        f64s[2].append_option(r.frequency_std_hz);
        f64s[3].append_option(r.damping_ratio_std);
        f64s[4].append_option(r.mpc);
        f64s[5].append_option(r.emac);
        physical.append_value(r.physical);
        re.values().append_slice(&r.shape_re);
        re.append(true);
        im.values().append_slice(&r.shape_im);
        im.append(true);
        for c in &r.channels {
            channels.values().append_value(c);
        }
        channels.append(true);
    }
    let mut f = f64s
        .into_iter()
        .map(|mut b| Arc::new(b.finish()) as ArrayRef);
    let mut next = || f.next().expect("seven float columns");
    let (freq, damp, fstd, dstd, mpc, emac) = (next(), next(), next(), next(), next(), next());
    RecordBatch::try_new(
        schema(),
        vec![
            Arc::new(id.finish()),
            Arc::new(time.finish()),
            Arc::new(mode.finish()),
            freq,
            damp,
            fstd,
            dstd,
            Arc::new(physical.finish()),
            mpc,
            emac,
            Arc::new(re.finish()),
            Arc::new(im.finish()),
            Arc::new(channels.finish()),
        ],
    )
}

/// Writes `rows` to `path` as Parquet (snappy-compressed), atomically.
///
/// # Errors
/// [`IoError`] naming `path` when it cannot be written, or when a row's shape, its
/// imaginary parts and its channels differ in length.
pub fn write_modes(path: &Path, rows: &[ModeRow]) -> Result<(), IoError> {
    write_modes_stream(path, std::iter::once(Ok(rows.to_vec())))
}

/// [`write_modes`] with the rows coming a record at a time, in bounded memory (a batch
/// of a million records writes its table this way).
///
/// # Errors
/// [`IoError`] naming `path` when it cannot be written, the first error of `records`,
/// or a row whose shape, imaginary parts and channels differ in length.
pub fn write_modes_stream(
    path: &Path,
    records: impl Iterator<Item = Result<Vec<ModeRow>, IoError>>,
) -> Result<(), IoError> {
    let checked = records.map(|rows| {
        let rows = rows?;
        if let Some(r) = rows.iter().find(|r| {
            r.shape_re.len() != r.shape_im.len() || r.shape_re.len() != r.channels.len()
        }) {
            return Err(IoError::format(
                path,
                "",
                format!(
                    "record {} mode {}: the shape has {} real parts, {} imaginary parts and {} channels",
                    r.record_id,
                    r.mode,
                    r.shape_re.len(),
                    r.shape_im.len(),
                    r.channels.len()
                ),
            ));
        }
        Ok(rows)
    });
    crate::table::write_stream(path, schema(), checked, batch)
}

/// The floats of a list cell (nulls in it read as NaN).
fn floats(path: &Path, list: &ListArray, i: usize, name: &str) -> Result<Vec<f64>, IoError> {
    let v = list.value(i);
    let Some(f) = v.as_any().downcast_ref::<Float64Array>() else {
        return Err(IoError::format(
            path,
            format!("column {name}: "),
            "is not a list of float64",
        ));
    };
    Ok((0..f.len())
        .map(|k| cell(f, k).unwrap_or(f64::NAN))
        .collect())
}

/// Reads a modes table written by [`write_modes`] (or by anything with its columns).
///
/// # Errors
/// [`IoError`] naming `path` when it cannot be read, is not Parquet, lacks a column or
/// has one of another type, or holds a null where a value is required.
pub fn read_modes(path: &Path) -> Result<Vec<ModeRow>, IoError> {
    let mut rows = Vec::new();
    for b in crate::table::read(path, &schema(), "a modes table of era batch")? {
        let id = column::<StringArray>(path, &b, "record_id", "string")?;
        let time = column::<TimestampMicrosecondArray>(path, &b, "time", "timestamp[us]")?;
        let mode = column::<UInt32Array>(path, &b, "mode", "uint32")?;
        let f = |name| column::<Float64Array>(path, &b, name, "float64");
        let (freq, damp) = (f("frequency_hz")?, f("damping_ratio")?);
        let (fstd, dstd) = (f("frequency_std_hz")?, f("damping_ratio_std")?);
        let (mpc, emac) = (f("mpc")?, f("emac")?);
        let physical = column::<BooleanArray>(path, &b, "physical", "bool")?;
        let re = column::<ListArray>(path, &b, "shape_re", "list<float64>")?;
        let im = column::<ListArray>(path, &b, "shape_im", "list<float64>")?;
        let ch = column::<ListArray>(path, &b, "channels", "list<string>")?;
        for i in 0..b.num_rows() {
            let required: [&dyn Array; 8] = [id, mode, freq, damp, physical, re, im, ch];
            if required.iter().any(|a| a.is_null(i)) {
                return Err(IoError::format(
                    path,
                    format!("row {}: ", rows.len() + 1),
                    "a required column is null",
                ));
            }
            let names = ch.value(i);
            let Some(names) = names.as_any().downcast_ref::<StringArray>() else {
                return Err(IoError::format(
                    path,
                    "column channels: ",
                    "is not a list of string",
                ));
            };
            rows.push(ModeRow {
                record_id: id.value(i).to_string(),
                time_us: (!time.is_null(i)).then(|| time.value(i)),
                mode: mode.value(i),
                frequency_hz: freq.value(i),
                damping_ratio: damp.value(i),
                frequency_std_hz: cell(fstd, i),
                damping_ratio_std: cell(dstd, i),
                physical: physical.value(i),
                mpc: cell(mpc, i),
                emac: cell(emac, i),
                shape_re: floats(path, re, i, "shape_re")?,
                shape_im: floats(path, im, i, "shape_im")?,
                channels: (0..names.len())
                    .map(|k| names.value(k).to_string())
                    .collect(),
            });
        }
    }
    Ok(rows)
}

/// An RFC 3339 time (`2026-05-01T10:00:00Z`, `2026-05-01T12:00:00+02:00`) as
/// microseconds since 1970-01-01 UTC.
///
/// # Errors
/// What is wrong with `text`, for the caller to place.
pub fn parse_time(text: &str) -> Result<i64, String> {
    let t = chrono::DateTime::parse_from_rfc3339(text.trim()).map_err(|e| {
        format!("time {text:?} is not RFC 3339 (such as 2026-05-01T10:00:00Z): {e}")
    })?;
    Ok(t.timestamp_micros())
}

/// Microseconds since 1970-01-01 UTC as RFC 3339 in UTC (`2026-05-01T10:00:00Z`).
pub fn format_time(us: i64) -> String {
    match chrono::DateTime::from_timestamp_micros(us) {
        Some(t) => t.to_rfc3339_opts(chrono::SecondsFormat::AutoSi, true),
        None => us.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(id: &str, mode: u32, n: usize) -> ModeRow {
        ModeRow {
            record_id: id.into(),
            time_us: (mode == 1).then_some(1_777_000_000_000_000),
            mode,
            frequency_hz: 1.5 * f64::from(mode),
            damping_ratio: 0.01,
            frequency_std_hz: Some(0.001),
            damping_ratio_std: None,
            physical: mode % 2 == 1,
            mpc: Some(0.99),
            emac: None,
            shape_re: (0..n).map(|k| k as f64).collect(),
            shape_im: vec![0.25; n],
            channels: (0..n).map(|k| format!("acc{k}")).collect(),
        }
    }

    #[test]
    fn round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("modes.parquet");
        let rows = vec![row("a", 1, 3), row("a", 2, 3), row("b", 1, 2)];
        write_modes(&path, &rows).unwrap();
        assert_eq!(read_modes(&path).unwrap(), rows);
        write_modes(&path, &[]).unwrap();
        assert!(read_modes(&path).unwrap().is_empty());
        // A record at a time, across row groups: the same rows.
        let many: Vec<ModeRow> = (0..150_000)
            .map(|k| row(&format!("r{}", k / 7), 1 + (k % 7) as u32, 2))
            .collect();
        let pieces = many.chunks(7).map(|c| Ok(c.to_vec()));
        write_modes_stream(&path, pieces).unwrap();
        assert_eq!(read_modes(&path).unwrap(), many);
    }

    #[test]
    fn refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("modes.parquet");
        let mut bad = row("a", 1, 3);
        bad.channels.pop();
        let e = write_modes(&path, &[bad]).unwrap_err().to_string();
        assert!(e.contains("record a mode 1"), "{e}");
        // A table of another kind, even an empty one, is refused by its columns.
        let other = Arc::new(Schema::new(vec![Field::new("x", DataType::Float64, false)]));
        let file = std::fs::File::create(&path).unwrap();
        let w = parquet::arrow::ArrowWriter::try_new(file, other, None).unwrap();
        w.close().unwrap();
        let e = read_modes(&path).unwrap_err().to_string();
        assert!(e.contains("no column record_id"), "{e}");
        std::fs::write(&path, b"not parquet").unwrap();
        let e = read_modes(&path).unwrap_err().to_string();
        assert!(e.contains("modes.parquet") && e.contains("parquet"), "{e}");
    }

    #[test]
    fn times() {
        let us = parse_time("2026-05-01T12:00:00+02:00").unwrap();
        assert_eq!(format_time(us), "2026-05-01T10:00:00Z");
        assert!(parse_time("yesterday").unwrap_err().contains("RFC 3339"));
    }
}
