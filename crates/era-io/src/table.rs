//! What the Parquet tables of a fleet ([`crate::fleet`], [`crate::tracks`]) share: the
//! atomic writer of record batches, the reader that checks the columns by name before
//! the rows, and typed access to a column.

use crate::IoError;
use arrow_array::{Array, Float64Array, RecordBatch};
use arrow_schema::{ArrowError, Schema};
use std::path::Path;
use std::sync::Arc;

/// Rows per row group and per batch read: a few MB of a typical table, so a reader
/// streams it.
pub(crate) const ROW_GROUP: usize = 65_536;

fn failed(path: &Path, e: &dyn std::fmt::Display) -> IoError {
    IoError::format(path, "", format!("parquet: {e}"))
}

/// Writes `rows` to `path` (snappy-compressed, atomically), one row group per
/// [`ROW_GROUP`] rows made into a batch by `batch`; an empty table keeps its schema.
pub(crate) fn write<T: Clone>(
    path: &Path,
    schema: Arc<Schema>,
    rows: &[T],
    batch: impl Fn(&[T]) -> Result<RecordBatch, ArrowError>,
) -> Result<(), IoError> {
    write_stream(
        path,
        schema,
        rows.chunks(ROW_GROUP).map(|c| Ok(c.to_vec())),
        batch,
    )
}

/// [`write`] with the rows coming in pieces (a record's modes at a time), so that a
/// table of any length is written in bounded memory: the rows are gathered into row
/// groups of [`ROW_GROUP`] and each is written as it fills. A piece that is an error
/// ends the writing with it (the target is untouched).
pub(crate) fn write_stream<T>(
    path: &Path,
    schema: Arc<Schema>,
    pieces: impl Iterator<Item = Result<Vec<T>, IoError>>,
    batch: impl Fn(&[T]) -> Result<RecordBatch, ArrowError>,
) -> Result<(), IoError> {
    crate::atomic::write_via(path, |tmp| {
        let file = std::fs::File::create(tmp).map_err(|e| IoError::io(path, e))?;
        let props = parquet::file::properties::WriterProperties::builder()
            .set_compression(parquet::basic::Compression::SNAPPY)
            .set_created_by(format!("era {}", env!("CARGO_PKG_VERSION")))
            .build();
        let mut writer = parquet::arrow::ArrowWriter::try_new(file, schema, Some(props))
            .map_err(|e| failed(path, &e))?;
        let mut group: Vec<T> = Vec::new();
        let mut written = false;
        let mut flush = |group: &mut Vec<T>, last: bool| -> Result<(), IoError> {
            if group.is_empty() && (written || !last) {
                return Ok(());
            }
            let b = batch(group).map_err(|e| failed(path, &e))?;
            writer.write(&b).map_err(|e| failed(path, &e))?;
            writer.flush().map_err(|e| failed(path, &e))?;
            group.clear();
            written = true;
            Ok(())
        };
        for piece in pieces {
            group.extend(piece?);
            if group.len() >= ROW_GROUP {
                flush(&mut group, false)?;
            }
        }
        flush(&mut group, true)?;
        writer.close().map_err(|e| failed(path, &e))?;
        Ok(())
    })
}

/// The record batches of the table at `path`, read as every input is (a FIFO or a
/// device is bounded, not hung on), after checking that it has every column of
/// `schema` by name, so that an empty table of another kind is refused too. `what`
/// names the table in the error ("a modes table of era batch").
pub(crate) fn read(path: &Path, schema: &Schema, what: &str) -> Result<Vec<RecordBatch>, IoError> {
    let bytes = bytes::Bytes::from(crate::input::read_input(path)?.into_vec());
    let builder = parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder::try_new(bytes)
        .map_err(|e| failed(path, &e))?;
    if let Some(missing) = schema
        .fields()
        .iter()
        .find(|f| builder.schema().field_with_name(f.name()).is_err())
    {
        return Err(IoError::format(
            path,
            "",
            format!("no column {}: not {what}", missing.name()),
        ));
    }
    let reader = builder
        .with_batch_size(ROW_GROUP)
        .build()
        .map_err(|e| failed(path, &e))?;
    reader.map(|b| b.map_err(|e| failed(path, &e))).collect()
}

/// A column of `batch` by name, as `T`; a missing or mistyped column is named.
pub(crate) fn column<'a, T: 'static>(
    path: &Path,
    batch: &'a RecordBatch,
    name: &str,
    kind: &str,
) -> Result<&'a T, IoError> {
    let Some(col) = batch.column_by_name(name) else {
        return Err(IoError::format(path, "", format!("no column {name}")));
    };
    col.as_any().downcast_ref::<T>().ok_or_else(|| {
        IoError::format(
            path,
            format!("column {name}: "),
            format!("is {}, expected {kind}", col.data_type()),
        )
    })
}

/// A nullable float cell.
pub(crate) fn cell(a: &Float64Array, i: usize) -> Option<f64> {
    (!a.is_null(i)).then(|| a.value(i))
}
