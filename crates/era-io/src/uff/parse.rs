//! Reading: records between `-1` lines, the fixed-width fields of dataset 58 (ASCII
//! and binary 58b), other datasets skipped.

use super::*;
use crate::IoError;
use era::Complex64;
use std::collections::BTreeMap;
use std::path::Path;

/// Parsing state over the bytes of a file.
pub(super) struct Parser<'a> {
    bytes: &'a [u8],
    path: &'a Path,
    pos: usize,
}

/// A line: its text (without the line break) and its start offset.
pub(super) struct Line<'a> {
    text: &'a [u8],
    start: usize,
}

impl<'a> Parser<'a> {
    /// 1-based line number of a byte offset (counted on demand: only for messages).
    fn line_of(&self, offset: usize) -> usize {
        let end = offset.min(self.bytes.len());
        memchr::memchr_iter(b'\n', &self.bytes[..end]).count() + 1
    }

    fn error_at(&self, offset: usize, message: impl Into<String>) -> IoError {
        IoError::format(
            self.path,
            format!("line {}: ", self.line_of(offset)),
            message.into(),
        )
    }

    fn error_in(&self, f: &Function58, offset: usize, message: impl Into<String>) -> IoError {
        IoError::format(
            self.path,
            format!(
                "record {} (dataset 58 at line {}), line {}: ",
                f.record,
                self.line_of(f.offset),
                self.line_of(offset)
            ),
            message.into(),
        )
    }

    fn next_line(&mut self) -> Option<Line<'a>> {
        if self.pos >= self.bytes.len() {
            return None;
        }
        let start = self.pos;
        let rest = &self.bytes[start..];
        let (text, advance) = match memchr::memchr(b'\n', rest) {
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        self.pos += advance;
        let text = text.strip_suffix(b"\r").unwrap_or(text);
        Some(Line { text, start })
    }
}

pub(super) fn is_delimiter(text: &[u8]) -> bool {
    trim_bytes(text) == b"-1"
}

/// Columns `start..start+width` of a line (shorter when the line is), as text.
pub(super) fn columns(text: &[u8], start: usize, width: usize) -> &[u8] {
    let end = (start + width).min(text.len());
    if start >= end {
        &[]
    } else {
        &text[start..end]
    }
}

/// A Fortran real: `1.5e-3`, `1.5E-03`, `1.5D-03`.
pub(super) fn parse_real(field: &[u8]) -> Option<f64> {
    let t = trim_bytes(field);
    if t.is_empty() || t.contains(&b' ') {
        return None;
    }
    let s = std::str::from_utf8(t).ok()?;
    let value = if s.contains(['D', 'd']) {
        s.replace(['D', 'd'], "E").parse::<f64>().ok()?
    } else {
        s.parse::<f64>().ok()?
    };
    Some(value)
}

pub(super) fn parse_int(field: &[u8]) -> Option<i64> {
    let t = trim_bytes(field);
    if t.is_empty() || t.contains(&b' ') {
        return None;
    }
    std::str::from_utf8(t).ok()?.parse::<i64>().ok()
}

pub(super) fn text_field(field: &[u8]) -> String {
    String::from_utf8_lossy(trim_bytes(field)).into_owned()
}

/// The fixed-width fields of a header line.
pub(super) struct Fields<'p, 'a> {
    parser: &'p Parser<'a>,
    line: Line<'a>,
    what: &'static str,
}

impl Fields<'_, '_> {
    fn int(&self, start: usize, width: usize, name: &str) -> Result<i64, IoError> {
        let field = columns(self.line.text, start, width);
        parse_int(field).ok_or_else(|| self.bad(start, width, name, field, "an integer"))
    }
    fn int_or_zero(&self, start: usize, width: usize, name: &str) -> Result<i64, IoError> {
        let field = columns(self.line.text, start, width);
        if trim_bytes(field).is_empty() {
            return Ok(0);
        }
        self.int(start, width, name)
    }
    fn real_or_zero(&self, start: usize, width: usize, name: &str) -> Result<f64, IoError> {
        let field = columns(self.line.text, start, width);
        if trim_bytes(field).is_empty() {
            return Ok(0.0);
        }
        parse_real(field)
            .filter(|v| v.is_finite())
            .ok_or_else(|| self.bad(start, width, name, field, "a finite real number"))
    }
    fn text(&self, start: usize, width: usize) -> String {
        text_field(columns(self.line.text, start, width))
    }
    fn bad(&self, start: usize, width: usize, name: &str, field: &[u8], want: &str) -> IoError {
        self.parser.error_at(
            self.line.start,
            format!(
                "{} ({}), columns {}-{}: expected {want}, found '{}' (check the field widths)",
                self.what,
                name,
                start + 1,
                start + width,
                String::from_utf8_lossy(field)
            ),
        )
    }
}

/// Reads a UFF file: every dataset-58 record, with its values when `with_data`
/// (otherwise only the headers: fast on large files).
///
/// # Errors
/// [`IoError`] naming the file and the line (and record) of a malformed record.
pub fn read_uff(path: &Path, with_data: bool) -> Result<UffContents, IoError> {
    let bytes = crate::input::read_input(path)?;
    if bytes.is_empty() {
        return Err(IoError::format(path, "", "the file is empty"));
    }
    parse_uff(&bytes, path, with_data)
}

/// Parses the bytes of a UFF file (see [`read_uff`]); `path` names it in messages.
///
/// # Errors
/// As [`read_uff`].
pub fn parse_uff(bytes: &[u8], path: &Path, with_data: bool) -> Result<UffContents, IoError> {
    let mut p = Parser {
        bytes,
        path,
        pos: 0,
    };
    if bytes.iter().all(|b| b.is_ascii_whitespace()) {
        return Err(IoError::format(path, "", "the file is empty"));
    }
    let mut out = UffContents::default();
    let mut quirks = Quirks::new();
    let mut record = 0;
    loop {
        // Blank lines between records are tolerated.
        let open = loop {
            match p.next_line() {
                None => return finish(&p, out, quirks),
                Some(l) if trim_bytes(l.text).is_empty() => continue,
                Some(l) => break l,
            }
        };
        if !is_delimiter(open.text) {
            return Err(p.error_at(
                open.start,
                format!(
                    "expected '    -1' to open a record, found '{}'",
                    shorten(open.text)
                ),
            ));
        }
        record += 1;
        let Some(id) = p.next_line() else {
            return Err(p.error_at(
                open.start,
                format!("record {record}: the file ends after its opening -1"),
            ));
        };
        let dataset = parse_int(columns(id.text, 0, 6)).ok_or_else(|| {
            p.error_at(
                id.start,
                format!(
                    "record {record}: expected a dataset number in columns 1-6, found '{}'",
                    shorten(id.text)
                ),
            )
        })?;
        let binary_flag = matches!(id.text.get(6), Some(b'b' | b'B'));
        let binary = if binary_flag {
            Some(binary_id(&p, &id, record)?)
        } else {
            None
        };
        if dataset == 58 {
            let f = header58(&mut p, record, open.start, binary)?;
            let data = if let Some(b) = binary {
                binary_data(&mut p, &f, b, with_data, &mut quirks)?
            } else {
                ascii_data(&mut p, &f, with_data)?
            };
            out.functions.push((f, data));
        } else {
            skip_record(&mut p, record, dataset, open.start, binary)?;
            *out.skipped.entry(dataset).or_insert(0) += 1;
        }
    }
}

/// Departures from the definition that were read anyway: kind → (records, first).
pub(super) type Quirks = BTreeMap<String, (usize, String)>;

pub(super) fn finish(
    p: &Parser,
    mut out: UffContents,
    quirks: Quirks,
) -> Result<UffContents, IoError> {
    if out.functions.is_empty() && out.skipped.is_empty() {
        return Err(IoError::format(p.path, "", "no UFF records in the file"));
    }
    for (kind, (count, first)) in quirks {
        out.notes.push(format!(
            "{count} binary records have {kind} (first: {first}); read as the closing -1 confirms"
        ));
    }
    Ok(out)
}

pub(super) fn shorten(text: &[u8]) -> String {
    let s = String::from_utf8_lossy(text);
    let s = s.trim_end();
    if s.chars().count() > 40 {
        format!("{}…", s.chars().take(40).collect::<String>())
    } else {
        s.to_string()
    }
}

/// The 58b fields of the ID line: `(I6,1A1,I6,I6,I12,I12,I6,I6,I12,I12)`.
pub(super) fn binary_id(p: &Parser, id: &Line, record: usize) -> Result<Binary, IoError> {
    let f = Fields {
        parser: p,
        line: Line {
            text: id.text,
            start: id.start,
        },
        what: "binary ID line",
    };
    let order = f.int(7, 6, "byte ordering")?;
    let format = f.int(13, 6, "floating-point format")?;
    let ascii = f.int(19, 12, "number of ASCII lines")?;
    let bytes = f.int(31, 12, "number of bytes")?;
    let fail = |m: String| p.error_at(id.start, format!("record {record}: {m}"));
    let little_endian = match order {
        1 => true,
        2 => false,
        o => {
            return Err(fail(format!(
                "byte ordering {o}: expected 1 (little-endian) or 2 (big-endian)"
            )))
        }
    };
    match format {
        2 => {}
        1 | 3 => {
            return Err(fail(format!(
                "floating-point format {format} ({}) is not supported: only 2 (IEEE 754)",
                if format == 1 { "DEC VMS" } else { "IBM 370" }
            )))
        }
        o => {
            return Err(fail(format!(
                "floating-point format {o}: expected 2 (IEEE 754)"
            )))
        }
    }
    if ascii < 0 || bytes < 0 {
        return Err(fail(format!(
            "negative line or byte count ({ascii} lines, {bytes} bytes)"
        )));
    }
    let header_bytes = usize::try_from(bytes).map_err(|_| fail("byte count too large".into()))?;
    Ok(Binary {
        little_endian,
        header_bytes,
    })
}

pub(super) fn header_line<'a>(
    p: &mut Parser<'a>,
    record: usize,
    open: usize,
    which: usize,
) -> Result<Line<'a>, IoError> {
    match p.next_line() {
        Some(l) if !is_delimiter(l.text) => Ok(l),
        Some(l) => Err(p.error_at(
            l.start,
            format!("record {record} (dataset 58): ends at header line {which} of 11 (truncated record)"),
        )),
        None => Err(p.error_at(
            open,
            format!("record {record} (dataset 58): the file ends at header line {which} of 11 (truncated record)"),
        )),
    }
}

pub(super) fn axis(fields: &Fields) -> Result<Axis, IoError> {
    Ok(Axis {
        data_type: fields.int_or_zero(0, 10, "specific data type")?,
        length_exp: fields.int_or_zero(10, 5, "length units exponent")?,
        force_exp: fields.int_or_zero(15, 5, "force units exponent")?,
        temperature_exp: fields.int_or_zero(20, 5, "temperature units exponent")?,
        label: fields.text(26, 20),
        units: fields.text(47, 20),
    })
}

/// Records 1–11 of dataset 58.
pub(super) fn header58(
    p: &mut Parser,
    record: usize,
    open: usize,
    binary: Option<Binary>,
) -> Result<Function58, IoError> {
    let mut ids: [String; 5] = Default::default();
    for (k, id) in ids.iter_mut().enumerate() {
        let line = header_line(p, record, open, k + 1)?;
        *id = String::from_utf8_lossy(line.text).trim_end().to_string();
    }
    let line = header_line(p, record, open, 6)?;
    let r6 = Fields {
        parser: p,
        line,
        what: "record 6 (DOF identification)",
    };
    let function_type = r6.int(0, 5, "function type")?;
    let function_id = r6.int_or_zero(5, 10, "function identification number")?;
    let version = r6.int_or_zero(15, 5, "version number")?;
    let load_case = r6.int_or_zero(20, 10, "load case")?;
    let response_entity = r6.text(31, 10);
    let response = Dof {
        node: r6.int(41, 10, "response node")?,
        direction: r6.int(51, 4, "response direction")?,
    };
    let reference_entity = r6.text(56, 10);
    let reference = Dof {
        node: r6.int(66, 10, "reference node")?,
        direction: r6.int(76, 4, "reference direction")?,
    };
    let line = header_line(p, record, open, 7)?;
    let r7 = Fields {
        parser: p,
        line,
        what: "record 7 (data form)",
    };
    let code = r7.int(0, 10, "ordinate data type")?;
    let ordinate = Ordinate::from_code(code).ok_or_else(|| {
        p.error_at(
            r7.line.start,
            format!(
                "record {record}: ordinate data type {code}: expected 2, 4, 5 or 6 (real/complex, single/double)"
            ),
        )
    })?;
    let points = r7.int(10, 10, "number of points")?;
    let points = usize::try_from(points)
        .ok()
        .filter(|n| *n > 0)
        .ok_or_else(|| {
            p.error_at(
                r7.line.start,
                format!("record {record}: number of points {points}: must be at least 1"),
            )
        })?;
    let spacing = r7.int(20, 10, "abscissa spacing")?;
    let even = match spacing {
        0 => false,
        1 => true,
        s => {
            return Err(p.error_at(
                r7.line.start,
                format!("record {record}: abscissa spacing {s}: expected 0 (uneven) or 1 (even)"),
            ))
        }
    };
    let abscissa_min = r7.real_or_zero(30, 13, "abscissa minimum")?;
    let abscissa_inc = r7.real_or_zero(43, 13, "abscissa increment")?;
    let z_value = r7.real_or_zero(56, 13, "z-axis value")?;
    let mut axes: [Axis; 4] = Default::default();
    for (k, (a, what)) in axes
        .iter_mut()
        .zip([
            "record 8 (abscissa)",
            "record 9 (ordinate numerator)",
            "record 10 (ordinate denominator)",
            "record 11 (z axis)",
        ])
        .enumerate()
    {
        let line = header_line(p, record, open, 8 + k)?;
        *a = axis(&Fields {
            parser: p,
            line,
            what,
        })?;
    }
    Ok(Function58 {
        record,
        offset: open,
        binary,
        ids,
        function_type,
        function_id,
        version,
        load_case,
        response_entity,
        response,
        reference_entity,
        reference,
        ordinate,
        points,
        even,
        abscissa_min,
        abscissa_inc,
        z_value,
        axes,
    })
}

/// Numbers per point (abscissa when uneven, then one or two ordinate parts).
pub(super) fn values_per_point(f: &Function58) -> usize {
    usize::from(!f.even) + if f.ordinate.is_complex() { 2 } else { 1 }
}

/// Field widths of the ASCII data, by position within a point.
pub(super) fn ascii_widths(f: &Function58) -> &'static [usize] {
    match (f.ordinate, f.even) {
        (Ordinate::RealSingle | Ordinate::ComplexSingle, true) => &[13],
        (Ordinate::RealSingle, false) => &[13, 13],
        (Ordinate::ComplexSingle, false) => &[13, 13, 13],
        (Ordinate::RealDouble | Ordinate::ComplexDouble, true) => &[20],
        (Ordinate::RealDouble, false) => &[13, 20],
        (Ordinate::ComplexDouble, false) => &[13, 20, 20],
    }
}

pub(super) fn total_values(p: &Parser, f: &Function58) -> Result<usize, IoError> {
    f.points
        .checked_mul(values_per_point(f))
        .filter(|n| *n <= p.bytes.len())
        .ok_or_else(|| {
            p.error_in(
                f,
                f.offset,
                format!(
                    "{} points cannot fit in a file of {} bytes (truncated record or wrong count)",
                    f.points,
                    p.bytes.len()
                ),
            )
        })
}

/// Record 12 in ASCII.
pub(super) fn ascii_data(
    p: &mut Parser,
    f: &Function58,
    with_data: bool,
) -> Result<Option<Data58>, IoError> {
    let total = total_values(p, f)?;
    if !with_data {
        if let Some(()) = skip_ascii_fast(p, f, total) {
            return Ok(None);
        }
    }
    let widths = ascii_widths(f);
    let mut numbers = Vec::with_capacity(if with_data { total } else { 0 });
    let mut count = 0usize;
    loop {
        let Some(line) = p.next_line() else {
            return Err(p.error_in(
                f,
                p.bytes.len(),
                format!("the file ends after {count} of {total} values (truncated record)"),
            ));
        };
        if is_delimiter(line.text) {
            if count == total {
                break;
            }
            return Err(p.error_in(
                f,
                line.start,
                format!("the record closes after {count} of {total} values (truncated record)"),
            ));
        }
        let mut at = 0;
        let text = line.text;
        while at < text.len() {
            if trim_bytes(&text[at..]).is_empty() {
                break;
            }
            let width = widths[count % widths.len()];
            if count >= total {
                return Err(p.error_in(
                    f,
                    line.start,
                    format!("more than the {total} values the header announces"),
                ));
            }
            if at + width > text.len() {
                return Err(p.error_in(
                    f,
                    line.start,
                    format!(
                        "value {} at columns {}-{} is cut short: {} values need fields {} characters wide (check the field widths)",
                        count + 1,
                        at + 1,
                        text.len(),
                        f.ordinate.name(),
                        width
                    ),
                ));
            }
            let field = &text[at..at + width];
            let Some(v) = parse_real(field) else {
                return Err(p.error_in(
                    f,
                    line.start,
                    format!(
                        "columns {}-{}: '{}' is not a number in a {}-character field (check the field widths)",
                        at + 1,
                        at + width,
                        String::from_utf8_lossy(field),
                        width
                    ),
                ));
            };
            if with_data {
                numbers.push(v);
            }
            count += 1;
            at += width;
        }
    }
    Ok(with_data.then(|| assemble(f, &numbers)))
}

/// Header-only reading of ASCII data: when the lines have equal length, jump to
/// where the last one must start and check that the record closes after it. `None`
/// when that does not hold (the caller then walks the lines).
pub(super) fn skip_ascii_fast(p: &mut Parser, f: &Function58, total: usize) -> Option<()> {
    let start = p.pos;
    let first_end = start + memchr::memchr(b'\n', p.bytes.get(start..)?)? + 1;
    let line_len = first_end - start;
    let widths = ascii_widths(f);
    let text = p.bytes[start..first_end].strip_suffix(b"\n")?;
    let text = text.strip_suffix(b"\r").unwrap_or(text);
    // Values on a full line (a uniform width or whole points of a mixed pattern).
    let per_line = {
        let mut at = 0;
        let mut n = 0;
        while at + widths[n % widths.len()] <= text.len() {
            at += widths[n % widths.len()];
            n += 1;
        }
        if at != text.len() || n == 0 {
            return None;
        }
        n
    };
    let lines = total.div_ceil(per_line);
    let last = start.checked_add((lines - 1).checked_mul(line_len)?)?;
    if last >= p.bytes.len() || p.bytes[last - 1] != b'\n' {
        return None;
    }
    let saved = p.pos;
    p.pos = last;
    let last_line = p.next_line()?;
    let expected = total - per_line * (lines - 1);
    let ok = !is_delimiter(last_line.text)
        && last_line.text.len() >= expected.min(1)
        && p.next_line().is_some_and(|l| is_delimiter(l.text));
    if ok {
        Some(())
    } else {
        p.pos = saved;
        None
    }
}

/// Record 12 in binary (58b).
pub(super) fn binary_data(
    p: &mut Parser,
    f: &Function58,
    b: Binary,
    with_data: bool,
    quirks: &mut Quirks,
) -> Result<Option<Data58>, IoError> {
    let total = total_values(p, f)?;
    let start = p.pos;
    let size = if f.ordinate.is_double() { 8 } else { 4 };
    let layout = total * size;
    // Candidate lengths: the layout the header describes, then 8-byte values under a
    // single-precision type (pyuff), then the header's byte count.
    let mut candidates = vec![(layout, size)];
    if size == 4 {
        candidates.push((total * 8, 8));
    }
    let closes = |len: usize| closing_after(p.bytes, start.checked_add(len)?);
    let found = candidates
        .iter()
        .find_map(|&(len, size)| closes(len).map(|end| (len, size, end)));
    let Some((len, size, end)) = found else {
        let available = p.bytes.len().saturating_sub(start);
        let detail = if available < layout.min(b.header_bytes) {
            format!("only {available} bytes remain (truncated record)")
        } else if closes(b.header_bytes).is_some() {
            format!(
                "the data before the closing -1 is {} bytes, which does not match the layout",
                b.header_bytes
            )
        } else {
            "no closing -1 follows the data".to_string()
        };
        return Err(p.error_in(
            f,
            start,
            format!(
                "binary length disagrees with the header: the header says {} bytes, {} {} values need {layout}; {detail}",
                b.header_bytes,
                total,
                f.ordinate.name()
            ),
        ));
    };
    let declared = if f.ordinate.is_double() { 8 } else { 4 };
    if len != b.header_bytes || size != declared {
        let kind = if size != declared {
            format!(
                "{size}-byte values under the {declared}-byte type {}",
                f.ordinate.name()
            )
        } else {
            format!(
                "a header byte count other than the {} values need",
                f.ordinate.name()
            )
        };
        let entry = quirks.entry(kind).or_insert_with(|| {
            (
                0,
                format!(
                    "record {} (line {}) says {} bytes, holds {len}",
                    f.record,
                    p.line_of(f.offset),
                    b.header_bytes
                ),
            )
        });
        entry.0 += 1;
    }
    p.pos = end;
    if !with_data {
        return Ok(None);
    }
    let raw = &p.bytes[start..start + len];
    let numbers: Vec<f64> = if size == 8 {
        raw.chunks_exact(8)
            .map(|c| {
                let a: [u8; 8] = c.try_into().expect("8 bytes");
                if b.little_endian {
                    f64::from_le_bytes(a)
                } else {
                    f64::from_be_bytes(a)
                }
            })
            .collect()
    } else {
        raw.chunks_exact(4)
            .map(|c| {
                let a: [u8; 4] = c.try_into().expect("4 bytes");
                f64::from(if b.little_endian {
                    f32::from_le_bytes(a)
                } else {
                    f32::from_be_bytes(a)
                })
            })
            .collect()
    };
    if let Some(k) = numbers.iter().position(|v| !v.is_finite()) {
        return Err(p.error_in(
            f,
            start + k * size,
            format!("value {} is not finite ({})", k + 1, numbers[k]),
        ));
    }
    Ok(Some(assemble(f, &numbers)))
}

/// When `at` is followed (after at most one line break) by a `-1` line, the offset
/// after that line.
pub(super) fn closing_after(bytes: &[u8], at: usize) -> Option<usize> {
    let mut i = at;
    if i > bytes.len() {
        return None;
    }
    for _ in 0..2 {
        if matches!(bytes.get(i), Some(b'\r' | b'\n')) {
            i += 1;
        }
    }
    while bytes.get(i) == Some(&b' ') {
        i += 1;
    }
    if bytes.get(i..i + 2) != Some(b"-1".as_slice()) {
        return None;
    }
    i += 2;
    while bytes.get(i) == Some(&b' ') {
        i += 1;
    }
    match bytes.get(i) {
        None => Some(i),
        Some(b'\n') => Some(i + 1),
        Some(b'\r') if bytes.get(i + 1) == Some(&b'\n') => Some(i + 2),
        _ => None,
    }
}

pub(super) fn assemble(f: &Function58, numbers: &[f64]) -> Data58 {
    let per = values_per_point(f);
    let mut abscissa = Vec::with_capacity(f.points);
    let mut values = Vec::with_capacity(f.points);
    for (k, point) in numbers.chunks_exact(per).enumerate() {
        let (x, rest) = if f.even {
            (f.abscissa_min + k as f64 * f.abscissa_inc, point)
        } else {
            (point[0], &point[1..])
        };
        abscissa.push(x);
        values.push(Complex64::new(rest[0], rest.get(1).copied().unwrap_or(0.0)));
    }
    Data58 { abscissa, values }
}

/// Skips a record of another dataset up to its closing `-1`.
pub(super) fn skip_record(
    p: &mut Parser,
    record: usize,
    dataset: i64,
    open: usize,
    binary: Option<Binary>,
) -> Result<(), IoError> {
    if let Some(b) = binary {
        // Binary records of other datasets: skip the ASCII lines the ID line does not
        // count here; find the closing -1 after the announced bytes, else search.
        let mut at = p.pos;
        while at < p.bytes.len() {
            if let Some(end) = closing_after(p.bytes, at.saturating_add(b.header_bytes)) {
                p.pos = end;
                return Ok(());
            }
            match memchr::memchr(b'\n', &p.bytes[at..]) {
                Some(i) => at += i + 1,
                None => break,
            }
        }
    } else {
        while let Some(line) = p.next_line() {
            if is_delimiter(line.text) {
                return Ok(());
            }
        }
    }
    Err(p.error_at(
        open,
        format!("record {record} (dataset {dataset}) has no closing -1 (truncated record)"),
    ))
}
