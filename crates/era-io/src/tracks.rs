//! The table of `era track`: one row per tracked mode of a record, in Apache Parquet
//! like the modes table of [`crate::fleet`], so that pandas, polars and DuckDB read it
//! as it is.
//!
//! [`write_tracks`] writes a `tracks.parquet` (staged, synced and renamed),
//! [`read_tracks`] reads one back with every column checked by name and type. The
//! columns:
//!
//! | column | type | |
//! |---|---|---|
//! | `record_id` | string | the record's id |
//! | `time` | timestamp (µs, UTC), nullable | the record's start |
//! | `track` | uint32 | 1-based, by mean frequency |
//! | `mode` | uint32 | the mode's number in its record's table |
//! | `frequency_hz`, `damping_ratio` | float64 | |
//! | `frequency_std_hz`, `damping_ratio_std` | float64, nullable | null when not estimated |
//! | `mac_to_track` | float64, nullable | MAC with the track's recent shape when the mode joined; null for a track's first mode or no shared channels |
//! | `physical` | bool | the identification's verdict |
//! | `sparse` | bool | the track is seen in fewer than the minimum records |
//! | `x` | float64 | days since the first record, or the record's position in time order when the records have no times |

use crate::table::{cell, column};
use crate::IoError;
use arrow_array::builder::{
    BooleanBuilder, Float64Builder, StringBuilder, TimestampMicrosecondBuilder, UInt32Builder,
};
use arrow_array::{
    Array, ArrayRef, BooleanArray, Float64Array, RecordBatch, StringArray,
    TimestampMicrosecondArray, UInt32Array,
};
use arrow_schema::{DataType, Field, Schema, TimeUnit};
use std::path::Path;
use std::sync::Arc;

/// One tracked mode of one record.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackRow {
    /// The record's id.
    pub record_id: String,
    /// The record's start, microseconds since 1970-01-01 UTC.
    pub time_us: Option<i64>,
    /// The track, 1-based.
    pub track: u32,
    /// The mode's number in its record (1-based).
    pub mode: u32,
    /// Natural frequency, Hz.
    pub frequency_hz: f64,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// Standard deviation of the frequency, Hz.
    pub frequency_std_hz: Option<f64>,
    /// Standard deviation of the damping ratio.
    pub damping_ratio_std: Option<f64>,
    /// MAC with the track's recent shape.
    pub mac_to_track: Option<f64>,
    /// Whether the identification called the mode physical.
    pub physical: bool,
    /// Whether the track is sparse.
    pub sparse: bool,
    /// Days since the first record, or the record's position.
    pub x: f64,
}

fn schema() -> Arc<Schema> {
    let f = |name: &str, nullable| Field::new(name, DataType::Float64, nullable);
    Arc::new(Schema::new(vec![
        Field::new("record_id", DataType::Utf8, false),
        Field::new(
            "time",
            DataType::Timestamp(TimeUnit::Microsecond, Some("UTC".into())),
            true,
        ),
        Field::new("track", DataType::UInt32, false),
        Field::new("mode", DataType::UInt32, false),
        f("frequency_hz", false),
        f("damping_ratio", false),
        f("frequency_std_hz", true),
        f("damping_ratio_std", true),
        f("mac_to_track", true),
        Field::new("physical", DataType::Boolean, false),
        Field::new("sparse", DataType::Boolean, false),
        f("x", false),
    ]))
}

fn batch(rows: &[TrackRow]) -> Result<RecordBatch, arrow_schema::ArrowError> {
    let mut id = StringBuilder::new();
    let mut time = TimestampMicrosecondBuilder::new().with_timezone("UTC");
    let (mut track, mut mode) = (UInt32Builder::new(), UInt32Builder::new());
    let mut f: Vec<Float64Builder> = (0..6).map(|_| Float64Builder::new()).collect();
    let (mut physical, mut sparse) = (BooleanBuilder::new(), BooleanBuilder::new());
    for r in rows {
        id.append_value(&r.record_id);
        time.append_option(r.time_us);
        track.append_value(r.track);
        mode.append_value(r.mode);
        f[0].append_value(r.frequency_hz);
        f[1].append_value(r.damping_ratio);
        f[2].append_option(r.frequency_std_hz);
        f[3].append_option(r.damping_ratio_std);
        f[4].append_option(r.mac_to_track);
        f[5].append_value(r.x);
        physical.append_value(r.physical);
        sparse.append_value(r.sparse);
    }
    let f: Vec<ArrayRef> = f
        .into_iter()
        .map(|mut b| Arc::new(b.finish()) as ArrayRef)
        .collect();
    RecordBatch::try_new(
        schema(),
        vec![
            Arc::new(id.finish()),
            Arc::new(time.finish()),
            Arc::new(track.finish()),
            Arc::new(mode.finish()),
            f[0].clone(),
            f[1].clone(),
            f[2].clone(),
            f[3].clone(),
            f[4].clone(),
            Arc::new(physical.finish()),
            Arc::new(sparse.finish()),
            f[5].clone(),
        ],
    )
}

/// Writes `rows` to `path` as Parquet (snappy-compressed), atomically.
///
/// # Errors
/// [`IoError`] naming `path` when it cannot be written.
pub fn write_tracks(path: &Path, rows: &[TrackRow]) -> Result<(), IoError> {
    crate::table::write(path, schema(), rows, batch)
}

/// Reads a tracks table written by [`write_tracks`].
///
/// # Errors
/// [`IoError`] naming `path` when it cannot be read, is not Parquet, lacks a column or
/// has one of another type, or holds a null where a value is required.
pub fn read_tracks(path: &Path) -> Result<Vec<TrackRow>, IoError> {
    let mut rows = Vec::new();
    for b in crate::table::read(path, &schema(), "a tracks table of era track")? {
        let id = column::<StringArray>(path, &b, "record_id", "string")?;
        let time = column::<TimestampMicrosecondArray>(path, &b, "time", "timestamp[us]")?;
        let track = column::<UInt32Array>(path, &b, "track", "uint32")?;
        let mode = column::<UInt32Array>(path, &b, "mode", "uint32")?;
        let f = |name| column::<Float64Array>(path, &b, name, "float64");
        let (freq, damp, x) = (f("frequency_hz")?, f("damping_ratio")?, f("x")?);
        let (fstd, dstd, mac) = (
            f("frequency_std_hz")?,
            f("damping_ratio_std")?,
            f("mac_to_track")?,
        );
        let physical = column::<BooleanArray>(path, &b, "physical", "bool")?;
        let sparse = column::<BooleanArray>(path, &b, "sparse", "bool")?;
        for i in 0..b.num_rows() {
            let required: [&dyn Array; 8] = [id, track, mode, freq, damp, physical, sparse, x];
            if required.iter().any(|a| a.is_null(i)) {
                return Err(IoError::format(
                    path,
                    format!("row {}: ", rows.len() + 1),
                    "a required column is null",
                ));
            }
            rows.push(TrackRow {
                record_id: id.value(i).to_string(),
                time_us: (!time.is_null(i)).then(|| time.value(i)),
                track: track.value(i),
                mode: mode.value(i),
                frequency_hz: freq.value(i),
                damping_ratio: damp.value(i),
                frequency_std_hz: cell(fstd, i),
                damping_ratio_std: cell(dstd, i),
                mac_to_track: cell(mac, i),
                physical: physical.value(i),
                sparse: sparse.value(i),
                x: x.value(i),
            });
        }
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_a_foreign_table_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("tracks.parquet");
        let rows: Vec<TrackRow> = (0..5)
            .map(|k| TrackRow {
                record_id: format!("r{k}"),
                time_us: (k != 2).then_some(1_777_000_000_000_000 + k),
                track: 1 + (k % 2) as u32,
                mode: 1 + k as u32,
                frequency_hz: 2.0 + k as f64,
                damping_ratio: 0.01,
                frequency_std_hz: (k != 1).then_some(0.002),
                damping_ratio_std: None,
                mac_to_track: (k > 0).then_some(0.98),
                physical: k != 3,
                sparse: k == 4,
                x: k as f64 / 24.0,
            })
            .collect();
        write_tracks(&path, &rows).unwrap();
        assert_eq!(read_tracks(&path).unwrap(), rows);
        write_tracks(&path, &[]).unwrap();
        assert!(read_tracks(&path).unwrap().is_empty());
        let modes = dir.path().join("modes.parquet");
        crate::fleet::write_modes(&modes, &[]).unwrap();
        let e = read_tracks(&modes).unwrap_err().to_string();
        assert!(
            e.contains("modes.parquet") && e.contains("no column track"),
            "{e}"
        );
    }
}
