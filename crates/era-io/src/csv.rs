//! The FRF CSV of docs/design.md §4.
//!
//! ```text
//! # quantity: acceleration
//! # force_unit: lbf
//! # response_unit: in/s^2
//! frequency_hz,H1_1_re,H1_1_im,H2_1_re,H2_1_im,...
//! 0,0.0,0.0,...
//! ```
//!
//! `Hi_j` is output `i` from input `j`, 1-based; columns may come in any order, and every
//! pair of `1..q × 1..p` must be present with both parts. Rows are parsed with the `csv`
//! crate; everything else (metadata, column map, checks) is here so that each error can
//! name the file, the line and the column.

use crate::atomic::write_atomic;
pub use crate::frf_file::FrfFile;
use crate::IoError;
use era::{Complex64, EraError, FrfData, Quantity};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// Which part of a complex value a column holds.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Part {
    Re,
    Im,
}

fn parse_column(name: &str) -> Option<(usize, usize, Part)> {
    let rest = name.strip_prefix('H').or_else(|| name.strip_prefix('h'))?;
    let (pair, part) = rest.rsplit_once('_')?;
    let part = match part.to_ascii_lowercase().as_str() {
        "re" => Part::Re,
        "im" => Part::Im,
        _ => return None,
    };
    let (i, j) = pair.split_once('_')?;
    let (i, j) = (i.parse::<usize>().ok()?, j.parse::<usize>().ok()?);
    (i >= 1 && j >= 1).then_some((i, j, part))
}

/// A cell trimmed, without the quotes around it if it has them.
fn unquoted(raw: &str) -> &str {
    let t = raw.trim_ascii();
    t.strip_prefix('"')
        .and_then(|u| u.strip_suffix('"'))
        .map_or(t, str::trim)
}

/// One data line as its numbers, `None` for a comment or a blank line (every cell
/// empty); cells are trimmed and may be quoted. Errors name the line and the column.
fn parse_row(
    text: &str,
    line: usize,
    names: &[String],
    fail: &(dyn Fn(usize, &str, String) -> IoError + Sync),
) -> Result<Option<Vec<f64>>, IoError> {
    if text.trim_start().starts_with('#') {
        return Ok(None);
    }
    // One vectorised search over the line for its commas (memchr), rather than a
    // searcher started again for each short cell.
    let mut cells: Vec<&str> = Vec::with_capacity(names.len());
    let mut start = 0;
    for i in memchr::memchr_iter(b',', text.as_bytes()) {
        cells.push(unquoted(&text[start..i]));
        start = i + 1;
    }
    cells.push(unquoted(&text[start..]));
    if cells.iter().all(|c| c.is_empty()) {
        return Ok(None);
    }
    if cells.len() != names.len() {
        return Err(fail(
            line,
            "",
            format!("{} cells, the header has {}", cells.len(), names.len()),
        ));
    }
    let mut values = Vec::with_capacity(cells.len());
    for (c, t) in cells.into_iter().enumerate() {
        let v: f64 = t
            .parse()
            .map_err(|_| fail(line, &names[c], format!("'{t}' is not a number")))?;
        if !v.is_finite() {
            return Err(fail(line, &names[c], format!("{t} is not a finite number")));
        }
        values.push(v);
    }
    Ok(Some(values))
}

/// Reads an FRF CSV. Without a `# quantity:` line the FRFs are tagged
/// `default_quantity`.
///
/// # Errors
/// [`IoError::Io`] when the file cannot be read; [`IoError::Format`] naming the line and
/// column for a missing or unknown column, a non-numeric cell, NaN or infinity, a short
/// row, non-uniform frequencies or a first line other than 0 Hz.
pub fn read_frf_csv(path: &Path, default_quantity: Quantity) -> Result<FrfFile, IoError> {
    let bytes = crate::input::read_input(path)?;
    let text = crate::input::utf8(&bytes, path)?;
    parse_frf_csv(text, path, default_quantity)
}

/// [`read_frf_csv`] on text already read; `path` names it in messages.
///
/// # Errors
/// As [`read_frf_csv`].
pub fn parse_frf_csv(
    text: &str,
    path: &Path,
    default_quantity: Quantity,
) -> Result<FrfFile, IoError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let fail =
        |line: usize, column: &str, message: String| IoError::at(path, line, column, message);

    // Metadata lines, then the header.
    let (metadata, header) = crate::text::metadata_and_header(text);
    let Some((header_line, _)) = header else {
        return Err(IoError::format(
            path,
            "",
            "no header line (expected frequency_hz,H1_1_re,H1_1_im,...)",
        ));
    };
    let quantity = match metadata.get("quantity") {
        Some(q) => Quantity::parse(q).ok_or_else(|| {
            IoError::format(
                path,
                "",
                format!("unknown quantity '{q}' (acceleration, velocity or displacement)"),
            )
        })?,
        None => default_quantity,
    };
    let names = header_names(text, path, header_line)?;
    let columns = column_map(path, header_line, &names)?;
    let (q, p) = (columns.q, columns.p);
    let rows = data_rows(text, path, header_line, &names, columns.frequency)?;

    // Lines from 0 Hz: a start a whole number of increments above is padded with zero
    // lines (as in every format), another start is refused with the remedy.
    let DataRows {
        mut frequency_hz,
        rows,
        line_of_row,
    } = rows;
    let mut metadata = metadata;
    let start = crate::frf_file::zero_start(
        path,
        &format!("line {}, column frequency_hz: ", line_of_row[0]),
        &frequency_hz,
        q * p,
    )?;
    let added = start.as_ref().map_or(0, |z| z.added);
    if let Some(z) = &start {
        crate::frf_file::add_note(&mut metadata, z.note());
        frequency_hz = z.frequency_hz.clone();
    }
    let lines = rows.len() + added;
    let mut values = vec![Complex64::new(0.0, 0.0); q * p * lines];
    for i in 1..=q {
        for j in 1..=p {
            let (re, im) = (columns.pairs[&(i, j, 0)], columns.pairs[&(i, j, 1)]);
            for (k, row) in rows.iter().enumerate() {
                values[((i - 1) * p + (j - 1)) * lines + added + k] =
                    Complex64::new(row[re], row[im]);
            }
        }
    }
    // A line index of the padded set is row `line − added` of the file.
    let row_line = |line: usize| line_of_row[line.saturating_sub(added).min(rows.len() - 1)];
    let frf = FrfData::new(frequency_hz, q, p, values, quantity).map_err(|e| match e {
        EraError::NonUniformFrequencies { line, .. } | EraError::NonFinite { line, .. } => {
            fail(row_line(line), "frequency_hz", e.to_string())
        }
        EraError::FirstLineNotZero { .. } => fail(line_of_row[0], "frequency_hz", e.to_string()),
        other => IoError::format(path, "", other.to_string()),
    })?;
    Ok(FrfFile {
        channels: crate::frf_file::channels_from_metadata(&metadata, frf.outputs(), frf.inputs()),
        frf,
        quantity_given: metadata.contains_key("quantity"),
        metadata,
    })
}

/// The header's column names, read with the `csv` crate (which knows quoting) from the
/// first non-blank record; a header of one column split by another separator, or one
/// with a time column, is refused with what to do instead.
fn header_names(text: &str, path: &Path, header_line: usize) -> Result<Vec<String>, IoError> {
    let fail =
        |line: usize, column: &str, message: String| IoError::at(path, line, column, message);
    let mut reader = ::csv::ReaderBuilder::new()
        .has_headers(false)
        .comment(Some(b'#'))
        .flexible(true)
        .trim(::csv::Trim::All)
        .from_reader(text.as_bytes());
    let mut records = reader.records();
    let header = loop {
        match records.next() {
            Some(Ok(r)) if r.iter().all(str::is_empty) => continue,
            Some(Ok(r)) => break r,
            Some(Err(e)) => {
                return Err(fail(
                    header_line,
                    "",
                    format!("cannot read the header: {e}"),
                ))
            }
            None => return Err(IoError::format(path, "", "no header line")),
        }
    };
    let names: Vec<String> = header.iter().map(str::to_string).collect();
    if let [only] = names.as_slice() {
        let separators = [(';', "semicolons"), ('\t', "tabs"), ('|', "bars")];
        if let Some((sep, what)) = separators.iter().find(|(c, _)| only.contains(*c)) {
            return Err(fail(
                header_line,
                "",
                format!(
                    "the header is one column: its names are separated by {what} ('{}'), and era reads comma-separated files with '.' decimals; save the file with ',' as the separator (frequency_hz,H1_1_re,H1_1_im,...)",
                    sep.escape_default()
                ),
            ));
        }
    }
    if let Some(time) = names.iter().find(|n| {
        ["time_s", "time", "t", "time_ms", "seconds"]
            .iter()
            .any(|t| n.eq_ignore_ascii_case(t))
    }) {
        return Err(fail(
            header_line,
            time,
            format!(
                "a time column: this file holds time histories, not FRFs; {}",
                crate::frf_file::time_hint(path)
            ),
        ));
    }
    Ok(names)
}

/// Where each column of the header is: the frequencies, and each pair's parts.
struct ColumnMap {
    /// The `frequency_hz` column.
    frequency: usize,
    /// `(i, j, 0 re | 1 im)` → column, 1-based `i`, `j`.
    pairs: BTreeMap<(usize, usize, u8), usize>,
    /// Outputs and inputs: the largest `i` and `j` named.
    q: usize,
    p: usize,
}

/// The column map of the header, refusing unknown, duplicate or missing columns and a
/// channel count over [`era::params::limits::CHANNELS`].
fn column_map(path: &Path, header_line: usize, names: &[String]) -> Result<ColumnMap, IoError> {
    let fail =
        |line: usize, column: &str, message: String| IoError::at(path, line, column, message);
    let mut frequency_col = None;
    let mut columns: BTreeMap<(usize, usize, u8), usize> = BTreeMap::new();
    let (mut q, mut p) = (0, 0);
    for (c, name) in names.iter().enumerate() {
        if name.eq_ignore_ascii_case("frequency_hz") {
            if frequency_col.replace(c).is_some() {
                return Err(fail(header_line, name, "duplicate column".into()));
            }
            continue;
        }
        let Some((i, j, part)) = parse_column(name) else {
            return Err(fail(
                header_line,
                name,
                "unknown column (expected frequency_hz or Hi_j_re / Hi_j_im)".into(),
            ));
        };
        if columns
            .insert((i, j, u8::from(part == Part::Im)), c)
            .is_some()
        {
            return Err(fail(header_line, name, "duplicate column".into()));
        }
        q = q.max(i);
        p = p.max(j);
    }
    let Some(frequency_col) = frequency_col else {
        return Err(fail(header_line, "frequency_hz", "missing column".into()));
    };
    // A column named H99999_99999_re asks for 10^10 pairs: count the missing ones and
    // name only the first few (fuzzing found the enumeration exhausting memory).
    const NAMED: usize = 10;
    let expected = (q as u128) * (p as u128) * 2;
    let absent = expected.saturating_sub(columns.len() as u128);
    let mut missing = Vec::new();
    'scan: for i in 1..=q {
        for j in 1..=p {
            for (part, suffix) in [(0u8, "re"), (1u8, "im")] {
                if missing.len() == NAMED || missing.len() as u128 == absent {
                    break 'scan;
                }
                if !columns.contains_key(&(i, j, part)) {
                    missing.push(format!("H{i}_{j}_{suffix}"));
                }
            }
        }
    }
    if absent > NAMED as u128 {
        missing.push(format!("… {} columns in all", absent));
    }
    if q == 0 {
        return Err(fail(
            header_line,
            "",
            "no FRF columns (expected H1_1_re, H1_1_im, ...)".into(),
        ));
    }
    if !missing.is_empty() {
        return Err(fail(
            header_line,
            "",
            format!(
                "missing column(s) for a {q}x{p} set: {}",
                missing.join(", ")
            ),
        ));
    }
    for (count, side) in [(q, "outputs"), (p, "inputs")] {
        era::params::limits::CHANNELS
            .check(format!("the header names {count} {side}"), count as u64)
            .map_err(|e| IoError::limit(path, e))?;
    }
    Ok(ColumnMap {
        frequency: frequency_col,
        pairs: columns,
        q,
        p,
    })
}

/// The data rows of the file: each row's numbers, its frequency and its line number.
struct DataRows {
    frequency_hz: Vec<f64>,
    rows: Vec<Vec<f64>>,
    line_of_row: Vec<usize>,
}

/// Every line after the header as numbers (comments and blank lines skipped), at least
/// one row.
fn data_rows(
    text: &str,
    path: &Path,
    header_line: usize,
    names: &[String],
    frequency_col: usize,
) -> Result<DataRows, IoError> {
    let fail =
        |line: usize, column: &str, message: String| IoError::at(path, line, column, message);
    // Rows: every line after the header, parsed in parallel (docs/design.md §7: a 2 MB
    // file is about 100 000 numbers, and parsing them is the whole cost of reading).
    // The header went through the csv crate, which knows quoting; a number has no
    // comma, so a row splits on commas, and a cell may be quoted.
    let data: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .skip(header_line)
        .map(|(index, line)| (index + 1, line))
        .collect();
    let parsed: Vec<Result<Option<Vec<f64>>, IoError>> = data
        .par_iter()
        .map(|&(line, text)| parse_row(text, line, names, &fail))
        .collect();
    let mut frequency_hz = Vec::new();
    let mut rows: Vec<Vec<f64>> = Vec::new();
    let mut line_of_row = Vec::new();
    for (row, (line, _)) in parsed.into_iter().zip(&data) {
        if let Some(values) = row? {
            frequency_hz.push(values[frequency_col]);
            rows.push(values);
            line_of_row.push(*line);
        }
    }
    if rows.is_empty() {
        return Err(IoError::format(path, "", "no data rows"));
    }
    Ok(DataRows {
        frequency_hz,
        rows,
        line_of_row,
    })
}

/// Formats FRFs as CSV text: metadata lines (`quantity` first, then `extra`), the header
/// with pairs output-fastest (`H1_1, H2_1, …, H1_2, …`), full-precision values.
pub fn format_frf_csv(frf: &FrfData, extra: &[(&str, &str)]) -> String {
    let (q, p, lines) = (frf.outputs(), frf.inputs(), frf.lines());
    let mut out = String::with_capacity(lines * q * p * 48);
    let _ = writeln!(out, "# quantity: {}", frf.quantity());
    for (k, v) in extra {
        let _ = writeln!(out, "# {k}: {v}");
    }
    out.push_str("frequency_hz");
    for j in 1..=p {
        for i in 1..=q {
            let _ = write!(out, ",H{i}_{j}_re,H{i}_{j}_im");
        }
    }
    out.push('\n');
    for k in 0..lines {
        let _ = write!(out, "{}", frf.frequency_hz()[k]);
        for j in 0..p {
            for i in 0..q {
                let v = frf.pair(i, j)[k];
                let _ = write!(out, ",{:e},{:e}", v.re, v.im);
            }
        }
        out.push('\n');
    }
    out
}

/// Writes FRFs as CSV, atomically.
///
/// # Errors
/// [`IoError::Io`] naming the file when it cannot be written.
pub fn write_frf_csv(path: &Path, frf: &FrfData, extra: &[(&str, &str)]) -> Result<(), IoError> {
    write_atomic(path, format_frf_csv(frf, extra).as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use era::data::frf::uniform_lines;

    fn sample() -> FrfData {
        FrfData::from_fn(
            uniform_lines(4, 0.025),
            2,
            3,
            Quantity::Velocity,
            |i, j, k| {
                Complex64::new(
                    0.1 * (i + 1) as f64 + k as f64 / 3.0,
                    -(j as f64) * 1e-7 / 7.0,
                )
            },
        )
        .unwrap()
    }

    fn write(dir: &tempfile::TempDir, name: &str, text: &str) -> std::path::PathBuf {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn round_trip_is_exact() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f.csv");
        write_frf_csv(&p, &sample(), &[("force_unit", "lbf")]).unwrap();
        let back = read_frf_csv(&p, Quantity::Acceleration).unwrap();
        assert_eq!(back.frf, sample());
        assert!(back.quantity_given);
        assert_eq!(back.metadata["force_unit"], "lbf");
    }

    #[test]
    fn any_column_order() {
        let dir = tempfile::tempdir().unwrap();
        let p = write(
            &dir,
            "a.csv",
            "H1_1_im,frequency_hz,H1_1_re\n2,0,1\n4,1,3\n",
        );
        let f = read_frf_csv(&p, Quantity::Displacement).unwrap();
        assert_eq!(f.frf.pair(0, 0)[1], Complex64::new(3.0, 4.0));
        assert!(!f.quantity_given);
    }

    #[test]
    fn rows_parsed_in_parallel_read_as_one_pass_would() {
        let dir = tempfile::tempdir().unwrap();
        // Quoted cells, padding, a comment and a blank row between the data rows.
        let p = write(
            &dir,
            "mixed.csv",
            "frequency_hz,H1_1_re,H1_1_im\r\n\"0\", 1.5 ,\" -2 \"\n# note\n,,\n\n1,3,4\n",
        );
        let file = read_frf_csv(&p, Quantity::Velocity).unwrap();
        assert_eq!(file.frf.frequency_hz(), &[0.0, 1.0]);
        assert_eq!(
            file.frf.values(),
            &[Complex64::new(1.5, -2.0), Complex64::new(3.0, 4.0)]
        );
        // Many bad rows: the first one in the file is named, whatever thread saw it.
        let mut text = String::from("frequency_hz,H1_1_re,H1_1_im\n");
        for k in 0..5000 {
            let bad = if k >= 1234 { "x" } else { "1" };
            text.push_str(&format!("{k},{bad},1\n"));
        }
        let p = write(&dir, "bad.csv", &text);
        let err = read_frf_csv(&p, Quantity::Velocity)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("line 1236, column H1_1_re: 'x' is not a number"),
            "{err}"
        );
    }

    #[test]
    fn a_late_start_on_the_grid_is_padded_with_zero_lines() {
        let dir = tempfile::tempdir().unwrap();
        let p = write(
            &dir,
            "late.csv",
            "frequency_hz,H1_1_re,H1_1_im,H2_1_re,H2_1_im\n0.5,1,2,5,6\n0.75,3,4,7,8\n",
        );
        let f = read_frf_csv(&p, Quantity::Velocity).unwrap();
        assert_eq!(f.frf.frequency_hz(), &[0.0, 0.25, 0.5, 0.75]);
        let zero = Complex64::new(0.0, 0.0);
        assert_eq!(
            f.frf.pair(0, 0),
            &[
                zero,
                zero,
                Complex64::new(1.0, 2.0),
                Complex64::new(3.0, 4.0)
            ]
        );
        assert_eq!(f.frf.pair(1, 0)[3], Complex64::new(7.0, 8.0));
        let note = &f.metadata["notes"];
        assert!(
            note.contains("start at 0.5 Hz") && note.contains("2 lines"),
            "{note}"
        );
        // An uneven line after the padding is named by its line in the file.
        let p = write(
            &dir,
            "late_uneven.csv",
            "frequency_hz,H1_1_re,H1_1_im\n2,1,1\n3,1,1\n4.5,1,1\n",
        );
        let e = read_frf_csv(&p, Quantity::Velocity)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("line 4, column frequency_hz: frequencies are not uniformly spaced"),
            "{e}"
        );
    }

    #[test]
    fn a_semicolon_header_is_not_echoed_as_one_column_name() {
        let dir = tempfile::tempdir().unwrap();
        let p = write(&dir, "semi.csv", "frequency_hz;H1_1_re;H1_1_im\n0;1;1\n");
        let e = read_frf_csv(&p, Quantity::Velocity)
            .unwrap_err()
            .to_string();
        assert!(!e.contains("frequency_hz;H1_1_re"), "{e}");
        assert!(e.contains("save the file with ','"), "{e}");
    }

    #[test]
    fn errors_name_file_line_and_column() {
        let dir = tempfile::tempdir().unwrap();
        let cases = [
            (
                "missing.csv",
                "frequency_hz,H1_1_re,H1_1_im,H1_2_re\n0,1,1,1\n",
                "missing column(s) for a 1x2 set: H1_2_im",
            ),
            (
                "text.csv",
                "frequency_hz,H1_1_re,H1_1_im\n0,1,1\n1,abc,1\n",
                "line 3, column H1_1_re: 'abc' is not a number",
            ),
            (
                "nan.csv",
                "frequency_hz,H1_1_re,H1_1_im\n0,1,NaN\n",
                "line 2, column H1_1_im: NaN is not a finite number",
            ),
            (
                "uneven.csv",
                "# quantity: velocity\nfrequency_hz,H1_1_re,H1_1_im\n0,1,1\n1,1,1\n2.5,1,1\n",
                "line 5, column frequency_hz: frequencies are not uniformly spaced",
            ),
            (
                "start.csv",
                "frequency_hz,H1_1_re,H1_1_im\n1.5,1,1\n2.5,1,1\n",
                "line 2, column frequency_hz: the first line is 1.5 Hz, 1.5000 increments",
            ),
            (
                "semicolons.csv",
                "frequency_hz;H1_1_re;H1_1_im\n0;1;1\n",
                "line 1: the header is one column: its names are separated by semicolons (';')",
            ),
            (
                "time.csv",
                "time_s,force,accel\n0,1,1\n0.001,1,1\n",
                "line 1, column time_s: a time column: this file holds time histories, not FRFs; estimate the FRFs with `era frf",
            ),
            (
                "short.csv",
                "frequency_hz,H1_1_re,H1_1_im\n0,1\n",
                "line 2: 2 cells, the header has 3",
            ),
            (
                "nofreq.csv",
                "H1_1_re,H1_1_im\n0,1\n",
                "column frequency_hz: missing column",
            ),
            (
                "quantity.csv",
                "# quantity: jerk\nfrequency_hz,H1_1_re,H1_1_im\n0,1,1\n",
                "unknown quantity 'jerk'",
            ),
        ];
        for (name, text, expected) in cases {
            let p = write(&dir, name, text);
            let err = read_frf_csv(&p, Quantity::Velocity)
                .unwrap_err()
                .to_string();
            assert!(
                err.contains(name) && err.contains(expected),
                "{name}: {err}"
            );
        }
    }
}
