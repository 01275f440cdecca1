//! Universal File Format: dataset 58 (a function at a nodal DOF, ASCII and binary
//! "58b") read and written, dataset 55 (data at nodes: mode shapes) written.
//!
//! Written by hand: no maintained Rust crate reads or writes UFF (crates.io has none
//! that handles 58b), and the format is a set of fixed-width Fortran records that a
//! few hundred lines describe completely. The layout follows the SDRC/UC-SDRL
//! definition of datasets 58, 58b and 55.
//!
//! # Reading
//! A file is a sequence of records, each between two lines holding `-1` in columns
//! 1–6. The second line of a record gives its dataset number; `58b` marks binary data
//! and carries the byte order, the floating-point format, the number of ASCII header
//! lines (11) and the number of data bytes. Records of other datasets (151, 164,
//! 2411, …) are skipped and counted.
//!
//! Each dataset-58 record holds one function: a response DOF (node, direction) over a
//! reference DOF, its ordinate type (real or complex, single or double), its abscissa
//! (even: minimum and increment; uneven: stored beside each value) and its axes. Field
//! widths are checked: a value that does not parse at its columns is an error naming
//! the line and the columns.
//!
//! In binary records the values follow the 11th header line directly. Their length
//! is computed from the header (points × values per point × bytes per value) and
//! must be followed by the closing `-1`. Two writers in use depart from the
//! definition, and both are read:
//! - pyuff 2.x writes the header's byte count as points × 8 even for complex data
//!   (half the real length), and writes 8-byte values under a single-precision
//!   ordinate type. The values and the closing `-1` agree with each other, so the
//!   reader trusts them over the byte count and says so in a note;
//! - Simcenter Testlab ends the binary data with a line break before the `-1`.
//!
//! When neither the header's byte count nor the layout lands on a closing `-1`, the
//! record is refused, naming both lengths.
//!
//! [`frf_from_uff`] builds one FRF matrix from the records of function type 4 (FRF):
//! inputs are the distinct reference DOFs and outputs the distinct response DOFs, in
//! the order they first appear. Missing or duplicate pairs, records whose abscissas
//! disagree, and unknown function types are refused with a list. Records of other
//! known function types (coherence, auto-spectra, …) are skipped with a note.
//!
//! # Writing
//! [`write_uff58`] writes one record per output/input pair: ASCII by default with the
//! widths of the definition (13 significant digits in the 20-wide double fields), or
//! binary 58b (little-endian IEEE, exact). [`write_uff55`] writes the mode shapes of
//! an identified model as complex-eigenvalue records (analysis type 3).

use crate::atomic::write_via;
use crate::csv::FrfFile;
use crate::IoError;
use era::modal::ModalParameters;
use era::{Complex64, FrfData, Quantity};
use std::collections::{BTreeMap, HashMap};
use std::io::Write;
use std::path::Path;

/// How the ordinates of a function are stored (record 7, field 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ordinate {
    /// Code 2.
    RealSingle,
    /// Code 4.
    RealDouble,
    /// Code 5.
    ComplexSingle,
    /// Code 6.
    ComplexDouble,
}

impl Ordinate {
    fn from_code(code: i64) -> Option<Self> {
        Some(match code {
            2 => Ordinate::RealSingle,
            4 => Ordinate::RealDouble,
            5 => Ordinate::ComplexSingle,
            6 => Ordinate::ComplexDouble,
            _ => return None,
        })
    }
    /// The code of record 7.
    pub fn code(self) -> i64 {
        match self {
            Ordinate::RealSingle => 2,
            Ordinate::RealDouble => 4,
            Ordinate::ComplexSingle => 5,
            Ordinate::ComplexDouble => 6,
        }
    }
    /// Real and imaginary parts stored.
    pub fn is_complex(self) -> bool {
        matches!(self, Ordinate::ComplexSingle | Ordinate::ComplexDouble)
    }
    /// Double precision.
    pub fn is_double(self) -> bool {
        matches!(self, Ordinate::RealDouble | Ordinate::ComplexDouble)
    }
    /// A short name for messages and `era info`.
    pub fn name(self) -> &'static str {
        match self {
            Ordinate::RealSingle => "real single",
            Ordinate::RealDouble => "real double",
            Ordinate::ComplexSingle => "complex single",
            Ordinate::ComplexDouble => "complex double",
        }
    }
}

/// A node and direction (records 6): the place a function was measured.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Dof {
    /// Node number.
    pub node: i64,
    /// 0 scalar, ±1..±3 translation X, Y, Z, ±4..±6 rotation about X, Y, Z.
    pub direction: i64,
}

impl std::fmt::Display for Dof {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}", self.node, direction_name(self.direction))
    }
}

/// `+X`, `-Z`, `+RY`, `S` (scalar) or the number itself when out of range.
pub fn direction_name(direction: i64) -> String {
    let sign = if direction < 0 { "-" } else { "+" };
    match direction.abs() {
        0 => "S".into(),
        1 => format!("{sign}X"),
        2 => format!("{sign}Y"),
        3 => format!("{sign}Z"),
        4 => format!("{sign}RX"),
        5 => format!("{sign}RY"),
        6 => format!("{sign}RZ"),
        _ => direction.to_string(),
    }
}

/// An axis description (records 8–11).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Axis {
    /// Specific data type: 8 displacement, 11 velocity, 12 acceleration,
    /// 13 excitation force, 17 time, 18 frequency, …
    pub data_type: i64,
    /// Length units exponent.
    pub length_exp: i64,
    /// Force units exponent.
    pub force_exp: i64,
    /// Temperature units exponent.
    pub temperature_exp: i64,
    /// Axis label (`NONE` when unused).
    pub label: String,
    /// Units label (`NONE` when unused).
    pub units: String,
}

/// Binary storage of a 58b record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Binary {
    /// Byte order 1 (little-endian) rather than 2.
    pub little_endian: bool,
    /// The byte count the header gives.
    pub header_bytes: usize,
}

/// The header of one dataset-58 record.
#[derive(Debug, Clone, PartialEq)]
pub struct Function58 {
    /// 1-based position of the record among all records of the file.
    pub record: usize,
    /// Byte offset of its opening `-1`.
    pub offset: usize,
    /// `Some` for 58b.
    pub binary: Option<Binary>,
    /// The five ID lines, trailing blanks removed.
    pub ids: [String; 5],
    /// 4 is a frequency response function; see [`function_type_name`].
    pub function_type: i64,
    /// Function identification number.
    pub function_id: i64,
    /// Version or sequence number.
    pub version: i64,
    /// Load case.
    pub load_case: i64,
    /// Response entity name.
    pub response_entity: String,
    /// Response DOF (an output).
    pub response: Dof,
    /// Reference entity name.
    pub reference_entity: String,
    /// Reference DOF (an input).
    pub reference: Dof,
    /// Ordinate storage.
    pub ordinate: Ordinate,
    /// Number of points.
    pub points: usize,
    /// Even abscissa (minimum and increment only) rather than stored per point.
    pub even: bool,
    /// First abscissa value (even spacing).
    pub abscissa_min: f64,
    /// Abscissa increment (even spacing).
    pub abscissa_inc: f64,
    /// Z-axis value.
    pub z_value: f64,
    /// Abscissa, ordinate numerator, ordinate denominator and Z axes.
    pub axes: [Axis; 4],
}

/// The values of one dataset-58 record.
#[derive(Debug, Clone, PartialEq)]
pub struct Data58 {
    /// Abscissa of each point (computed for even spacing).
    pub abscissa: Vec<f64>,
    /// Ordinates (imaginary part 0 for real types).
    pub values: Vec<Complex64>,
}

/// What a UFF file holds.
#[derive(Debug, Clone, Default)]
pub struct UffContents {
    /// The dataset-58 records, with their values when they were read.
    pub functions: Vec<(Function58, Option<Data58>)>,
    /// Records of other datasets: dataset number → count.
    pub skipped: BTreeMap<i64, usize>,
    /// Remarks on what was tolerated (writer quirks).
    pub notes: Vec<String>,
}

/// Name of a dataset-58 function type (record 6, field 1); `None` when undefined.
pub fn function_type_name(code: i64) -> Option<&'static str> {
    const NAMES: [&str; 29] = [
        "general",
        "time response",
        "auto spectrum",
        "cross spectrum",
        "frequency response function",
        "transmissibility",
        "coherence",
        "auto correlation",
        "cross correlation",
        "power spectral density",
        "energy spectral density",
        "probability density function",
        "spectrum",
        "cumulative frequency distribution",
        "peaks valley",
        "stress/cycles",
        "strain/cycles",
        "orbit",
        "mode indicator function",
        "force pattern",
        "partial power",
        "partial coherence",
        "eigenvalue",
        "eigenvector",
        "shock response spectrum",
        "finite impulse response filter",
        "multiple coherence",
        "order function",
        "phase compensation",
    ];
    usize::try_from(code)
        .ok()
        .and_then(|c| NAMES.get(c).copied())
}

/// The FRF function type.
pub const FUNCTION_FRF: i64 = 4;

/// True when the first non-blank line of `head` is a UFF record start (`-1`).
pub fn looks_like_uff(head: &[u8]) -> bool {
    let text = head
        .split(|b| *b == b'\n')
        .map(trim_bytes)
        .find(|l| !l.is_empty());
    text == Some(b"-1".as_slice())
}

fn trim_bytes(line: &[u8]) -> &[u8] {
    let start = line.iter().position(|b| !b.is_ascii_whitespace());
    match start {
        None => &[],
        Some(s) => {
            let end = line
                .iter()
                .rposition(|b| !b.is_ascii_whitespace())
                .unwrap_or(s);
            &line[s..=end]
        }
    }
}

/// Parsing state over the bytes of a file.
struct Parser<'a> {
    bytes: &'a [u8],
    path: &'a Path,
    pos: usize,
}

/// A line: its text (without the line break) and its start offset.
struct Line<'a> {
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

fn is_delimiter(text: &[u8]) -> bool {
    trim_bytes(text) == b"-1"
}

/// Columns `start..start+width` of a line (shorter when the line is), as text.
fn columns(text: &[u8], start: usize, width: usize) -> &[u8] {
    let end = (start + width).min(text.len());
    if start >= end {
        &[]
    } else {
        &text[start..end]
    }
}

/// A Fortran real: `1.5e-3`, `1.5E-03`, `1.5D-03`.
fn parse_real(field: &[u8]) -> Option<f64> {
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

fn parse_int(field: &[u8]) -> Option<i64> {
    let t = trim_bytes(field);
    if t.is_empty() || t.contains(&b' ') {
        return None;
    }
    std::str::from_utf8(t).ok()?.parse::<i64>().ok()
}

fn text_field(field: &[u8]) -> String {
    String::from_utf8_lossy(trim_bytes(field)).into_owned()
}

/// The fixed-width fields of a header line.
struct Fields<'p, 'a> {
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
    let file = std::fs::File::open(path).map_err(|e| IoError::io(path, e))?;
    let len = file.metadata().map_err(|e| IoError::io(path, e))?.len();
    if len == 0 {
        return Err(IoError::format(path, "", "the file is empty"));
    }
    // SAFETY: the map is read-only and lives only during the parse; a file shrunk by
    // another process meanwhile would fault, as reading any changing file can fail.
    let map = unsafe { memmap2::Mmap::map(&file) }.map_err(|e| IoError::io(path, e))?;
    parse_uff(&map, path, with_data)
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
type Quirks = BTreeMap<String, (usize, String)>;

fn finish(p: &Parser, mut out: UffContents, quirks: Quirks) -> Result<UffContents, IoError> {
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

fn shorten(text: &[u8]) -> String {
    let s = String::from_utf8_lossy(text);
    let s = s.trim_end();
    if s.chars().count() > 40 {
        format!("{}…", s.chars().take(40).collect::<String>())
    } else {
        s.to_string()
    }
}

/// The 58b fields of the ID line: `(I6,1A1,I6,I6,I12,I12,I6,I6,I12,I12)`.
fn binary_id(p: &Parser, id: &Line, record: usize) -> Result<Binary, IoError> {
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

fn header_line<'a>(
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

fn axis(fields: &Fields) -> Result<Axis, IoError> {
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
fn header58(
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
fn values_per_point(f: &Function58) -> usize {
    usize::from(!f.even) + if f.ordinate.is_complex() { 2 } else { 1 }
}

/// Field widths of the ASCII data, by position within a point.
fn ascii_widths(f: &Function58) -> &'static [usize] {
    match (f.ordinate, f.even) {
        (Ordinate::RealSingle | Ordinate::ComplexSingle, true) => &[13],
        (Ordinate::RealSingle, false) => &[13, 13],
        (Ordinate::ComplexSingle, false) => &[13, 13, 13],
        (Ordinate::RealDouble | Ordinate::ComplexDouble, true) => &[20],
        (Ordinate::RealDouble, false) => &[13, 20],
        (Ordinate::ComplexDouble, false) => &[13, 20, 20],
    }
}

fn total_values(p: &Parser, f: &Function58) -> Result<usize, IoError> {
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
fn ascii_data(p: &mut Parser, f: &Function58, with_data: bool) -> Result<Option<Data58>, IoError> {
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
fn skip_ascii_fast(p: &mut Parser, f: &Function58, total: usize) -> Option<()> {
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
fn binary_data(
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
fn closing_after(bytes: &[u8], at: usize) -> Option<usize> {
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

fn assemble(f: &Function58, numbers: &[f64]) -> Data58 {
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
fn skip_record(
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

/// A channel of an FRF matrix: the DOF and entity name it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    /// Node and direction.
    pub dof: Dof,
    /// Entity name (`NONE` when unused).
    pub entity: String,
}

impl Channel {
    /// The entity name, unless blank or `NONE`.
    pub fn entity_name(&self) -> Option<&str> {
        (!self.entity.is_empty() && self.entity != "NONE").then_some(self.entity.as_str())
    }
}

/// Which DOF each output and input of an FRF matrix is.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ChannelTable {
    /// Outputs (response DOFs), in matrix order.
    pub outputs: Vec<Channel>,
    /// Inputs (reference DOFs), in matrix order.
    pub inputs: Vec<Channel>,
}

impl ChannelTable {
    /// Outputs at nodes 1..q and inputs at nodes 1001..1000+p, all `+Z`: the
    /// numbering `era` uses when a file does not say.
    pub fn numbered(outputs: usize, inputs: usize) -> Self {
        let ch = |node: usize| Channel {
            dof: Dof {
                node: node as i64,
                direction: 3,
            },
            entity: "NONE".into(),
        };
        ChannelTable {
            outputs: (1..=outputs).map(ch).collect(),
            inputs: (1001..1001 + inputs).map(ch).collect(),
        }
    }

    /// The table as text lines: `output 1 = node 12 +Z (entity)`.
    pub fn describe(&self) -> Vec<String> {
        let row = |kind: &str, k: usize, c: &Channel| {
            let entity = c
                .entity_name()
                .map(|e| format!(" ({e})"))
                .unwrap_or_default();
            format!(
                "{kind} {} = node {} {}{entity}",
                k + 1,
                c.dof.node,
                direction_name(c.dof.direction)
            )
        };
        self.outputs
            .iter()
            .enumerate()
            .map(|(k, c)| row("output", k, c))
            .chain(
                self.inputs
                    .iter()
                    .enumerate()
                    .map(|(k, c)| row("input", k, c)),
            )
            .collect()
    }
}

/// The quantity an axis's specific data type names (8, 11, 12), if any.
pub fn quantity_of(data_type: i64) -> Option<Quantity> {
    match data_type {
        8 => Some(Quantity::Displacement),
        11 => Some(Quantity::Velocity),
        12 => Some(Quantity::Acceleration),
        _ => None,
    }
}

fn quantity_code(q: Quantity) -> i64 {
    match q {
        Quantity::Displacement => 8,
        Quantity::Velocity => 11,
        Quantity::Acceleration => 12,
    }
}

/// The first few items joined with "; ", then how many more.
pub fn listed(items: &[String]) -> String {
    const SHOWN: usize = 8;
    let mut s = items
        .iter()
        .take(SHOWN)
        .cloned()
        .collect::<Vec<_>>()
        .join("; ");
    if items.len() > SHOWN {
        s.push_str(&format!("; … and {} more", items.len() - SHOWN));
    }
    s
}

/// How FRF records fill a matrix: the channel table (DOFs in order of first
/// appearance), the record of each output/input pair, and what is missing or repeated.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FrfLayout {
    /// Outputs (response DOFs) and inputs (reference DOFs).
    pub table: ChannelTable,
    /// For pair `i·p + j`, the index (among the records given) of its record.
    pub slot: Vec<Option<usize>>,
    /// "output 2 (12:+Z) from input 1 (101:+Z)" for each pair without a record.
    pub missing: Vec<String>,
    /// One line per pair given more than once, with the record numbers.
    pub duplicates: Vec<String>,
}

impl FrfLayout {
    /// The layout of the given FRF records.
    pub fn of<'a>(records: impl Iterator<Item = &'a Function58>) -> Self {
        let records: Vec<&Function58> = records.collect();
        let mut table = ChannelTable::default();
        let mut out_index: HashMap<&Dof, usize> = HashMap::new();
        let mut in_index: HashMap<&Dof, usize> = HashMap::new();
        for f in &records {
            out_index.entry(&f.response).or_insert_with(|| {
                table.outputs.push(Channel {
                    dof: f.response.clone(),
                    entity: f.response_entity.clone(),
                });
                table.outputs.len() - 1
            });
            in_index.entry(&f.reference).or_insert_with(|| {
                table.inputs.push(Channel {
                    dof: f.reference.clone(),
                    entity: f.reference_entity.clone(),
                });
                table.inputs.len() - 1
            });
        }
        let (q, p) = (table.outputs.len(), table.inputs.len());
        let mut slot: Vec<Option<usize>> = vec![None; q * p];
        let mut duplicates = Vec::new();
        for (n, f) in records.iter().enumerate() {
            let s = out_index[&f.response] * p + in_index[&f.reference];
            match slot[s] {
                Some(first) => duplicates.push(format!(
                    "{} from {} in records {} and {}",
                    f.response, f.reference, records[first].record, f.record
                )),
                None => slot[s] = Some(n),
            }
        }
        let missing = slot
            .iter()
            .enumerate()
            .filter(|(_, s)| s.is_none())
            .map(|(s, _)| {
                format!(
                    "output {} ({}) from input {} ({})",
                    s / p + 1,
                    table.outputs[s / p].dof,
                    s % p + 1,
                    table.inputs[s % p].dof
                )
            })
            .collect();
        FrfLayout {
            table,
            slot,
            missing,
            duplicates,
        }
    }
}

/// Builds one FRF matrix from the FRF records of a file read with its data (see the
/// module doc), with its channel table. FRFs are tagged with the quantity of the
/// ordinate axis (8, 11, 12) when the records say, else `default_quantity`.
///
/// When the lines start above 0 Hz at a whole number of increments, the missing low
/// lines are added as zeros (ERA needs lines from 0 Hz) and a note says so.
///
/// # Errors
/// [`IoError`] naming the file and the records: no FRF records, unknown function
/// types, missing or duplicate pairs, abscissas that disagree, an uneven or
/// non-uniform abscissa, disagreeing quantities.
pub fn frf_from_uff(
    path: &Path,
    contents: &UffContents,
    default_quantity: Quantity,
) -> Result<FrfFile, IoError> {
    let fail = |m: String| IoError::format(path, "", m);
    let unknown: Vec<String> = contents
        .functions
        .iter()
        .filter(|(f, _)| function_type_name(f.function_type).is_none())
        .map(|(f, _)| format!("record {} has function type {}", f.record, f.function_type))
        .collect();
    if !unknown.is_empty() {
        return Err(fail(format!(
            "unknown function types (0-28 are defined): {}",
            listed(&unknown)
        )));
    }
    let frfs: Vec<&(Function58, Option<Data58>)> = contents
        .functions
        .iter()
        .filter(|(f, _)| f.function_type == FUNCTION_FRF)
        .collect();
    let mut metadata = BTreeMap::new();
    let mut notes: Vec<String> = contents.notes.clone();
    let others: BTreeMap<&str, usize> = contents
        .functions
        .iter()
        .filter(|(f, _)| f.function_type != FUNCTION_FRF)
        .fold(BTreeMap::new(), |mut m, (f, _)| {
            *m.entry(function_type_name(f.function_type).unwrap_or("?"))
                .or_insert(0) += 1;
            m
        });
    if frfs.is_empty() {
        let found = if others.is_empty() {
            "none of dataset 58".to_string()
        } else {
            others
                .iter()
                .map(|(k, n)| format!("{n} {k}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        return Err(fail(format!(
            "no FRF records (dataset 58, function type 4); the file has: {found}"
        )));
    }
    if !others.is_empty() {
        notes.push(format!(
            "skipped records that are not FRFs: {}",
            others
                .iter()
                .map(|(k, n)| format!("{n} {k}"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    if !contents.skipped.is_empty() {
        notes.push(format!(
            "skipped records of other datasets: {}",
            contents
                .skipped
                .iter()
                .map(|(d, n)| format!("{n} of dataset {d}"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    let layout = FrfLayout::of(frfs.iter().map(|r| &r.0));
    if !layout.duplicates.is_empty() {
        return Err(fail(format!(
            "duplicate FRF pairs: {}",
            listed(&layout.duplicates)
        )));
    }
    if !layout.missing.is_empty() {
        return Err(fail(format!(
            "missing FRF pairs ({} of {}): {}",
            layout.missing.len(),
            layout.table.outputs.len() * layout.table.inputs.len(),
            listed(&layout.missing)
        )));
    }
    let FrfLayout { table, slot, .. } = layout;
    let (q, p) = (table.outputs.len(), table.inputs.len());
    // One abscissa for all.
    let (first, first_data) = frfs[0];
    let describe = |f: &Function58| {
        if f.even {
            format!(
                "{} points from {} step {}",
                f.points, f.abscissa_min, f.abscissa_inc
            )
        } else {
            format!("{} points, uneven abscissa", f.points)
        }
    };
    let data_of = |f: &Function58, d: &Option<Data58>| -> Result<Vec<f64>, IoError> {
        d.as_ref().map(|d| d.abscissa.clone()).ok_or_else(|| {
            fail(format!(
                "record {}: values were not read (header-only read)",
                f.record
            ))
        })
    };
    let abscissa = data_of(first, first_data)?;
    let scale = abscissa
        .iter()
        .fold(0.0f64, |m, x| m.max(x.abs()))
        .max(f64::MIN_POSITIVE);
    let mut mismatched = Vec::new();
    for (f, d) in frfs.iter().skip(1).map(|r| (&r.0, &r.1)) {
        let x = data_of(f, d)?;
        let same = x.len() == abscissa.len()
            && x.iter()
                .zip(&abscissa)
                .all(|(a, b)| (a - b).abs() <= 1e-9 * scale);
        if !same {
            mismatched.push(format!(
                "record {} ({} from {}): {}",
                f.record,
                f.response,
                f.reference,
                describe(f)
            ));
        }
    }
    if !mismatched.is_empty() {
        return Err(fail(format!(
            "abscissas disagree with record {} ({}): {}",
            first.record,
            describe(first),
            listed(&mismatched)
        )));
    }
    if let Some(f) = frfs
        .iter()
        .map(|r| &r.0)
        .find(|f| f.axes[0].data_type == 17)
    {
        return Err(fail(format!(
            "record {}: the abscissa is time (data type 17): FRFs need frequency",
            f.record
        )));
    }
    // Quantity.
    let tagged: Vec<(usize, Quantity)> = frfs
        .iter()
        .filter_map(|r| quantity_of(r.0.axes[1].data_type).map(|q| (r.0.record, q)))
        .collect();
    let quantity = match tagged.first() {
        Some(&(_, q0)) => {
            let differ: Vec<String> = tagged
                .iter()
                .filter(|(_, q)| *q != q0)
                .map(|(r, q)| format!("record {r} is {q}"))
                .collect();
            if !differ.is_empty() {
                return Err(fail(format!(
                    "records disagree on the response quantity: record {} is {q0}; {}",
                    tagged[0].0,
                    listed(&differ)
                )));
            }
            q0
        }
        None => default_quantity,
    };
    // Lines from 0 Hz.
    let mut frequency_hz = abscissa;
    let mut pad = 0usize;
    if first.even && first.abscissa_min != 0.0 && first.abscissa_inc > 0.0 {
        let n0 = first.abscissa_min / first.abscissa_inc;
        if n0 > 0.0 && (n0 - n0.round()).abs() < 1e-6 && n0.round() <= 1e7 {
            pad = n0.round() as usize;
            let inc = first.abscissa_inc;
            frequency_hz = (0..pad + frequency_hz.len())
                .map(|k| k as f64 * inc)
                .collect();
            notes.push(format!(
                "the lines start at {} Hz; the {pad} lines below were added as zeros (ERA needs lines from 0 Hz)",
                first.abscissa_min
            ));
        }
    }
    let lines = frequency_hz.len();
    let mut values = vec![Complex64::new(0.0, 0.0); q * p * lines];
    for (s, n) in slot.iter().enumerate() {
        let d = frfs[n.expect("every pair present")]
            .1
            .as_ref()
            .expect("read with data");
        values[s * lines + pad..(s + 1) * lines].copy_from_slice(&d.values);
    }
    let frf = FrfData::new(frequency_hz, q, p, values, quantity).map_err(|e| {
        let uneven = if first.even {
            ""
        } else {
            " (the records have an uneven abscissa)"
        };
        fail(format!(
            "records {}…: ERA needs uniformly spaced lines from 0 Hz{uneven}: {e}",
            first.record
        ))
    })?;
    let units = |a: &Axis| (!a.units.is_empty() && a.units != "NONE").then(|| a.units.clone());
    if let Some(u) = units(&first.axes[1]) {
        metadata.insert("response_unit".to_string(), u);
    }
    if let Some(u) = units(&first.axes[2]) {
        metadata.insert("force_unit".to_string(), u);
    }
    metadata.insert(
        "layout".to_string(),
        format!(
            "UFF 58{}, {} FRF records, {q} x {p}",
            if first.binary.is_some() { "b" } else { "" },
            frfs.len()
        ),
    );
    if !notes.is_empty() {
        metadata.insert("notes".to_string(), notes.join(" | "));
    }
    Ok(FrfFile {
        frf,
        quantity_given: !tagged.is_empty(),
        metadata,
        channels: Some(table),
    })
}

/// Reads FRFs from a UFF file: [`read_uff`] then [`frf_from_uff`].
///
/// # Errors
/// As those two.
pub fn read_frf_uff(path: &Path, default_quantity: Quantity) -> Result<FrfFile, IoError> {
    let contents = read_uff(path, true)?;
    frf_from_uff(path, &contents, default_quantity)
}

/// How [`write_uff58`] stores values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct UffWriteOptions {
    /// Binary 58b (little-endian IEEE) rather than ASCII.
    pub binary: bool,
    /// Single precision rather than double.
    pub single: bool,
}

/// Fortran-style `E` format: `width` columns, `digits` after the point, an exponent
/// of at least two digits (`-1.234567890123e+00`).
fn fortran_e(x: f64, width: usize, digits: usize) -> String {
    let s = format!("{x:.digits$e}");
    let (mantissa, exponent) = s.split_once('e').expect("exponent form");
    let e: i32 = exponent.parse().expect("integer exponent");
    let sign = if e < 0 { '-' } else { '+' };
    format!(
        "{:>width$}",
        format!("{mantissa}e{sign}{:02}", e.unsigned_abs())
    )
}

fn header_text(s: &str, width: usize) -> String {
    let t: String = s.chars().filter(|c| !c.is_control()).take(width).collect();
    let t = if t.trim().is_empty() {
        "NONE".into()
    } else {
        t
    };
    format!("{t:<width$}")
}

/// The ASCII part of one dataset-58 record (opening `-1` to record 11).
#[allow(clippy::too_many_arguments)]
fn write_header58(
    w: &mut impl Write,
    opts: UffWriteOptions,
    data_bytes: usize,
    ids: [&str; 5],
    response: &Channel,
    reference: &Channel,
    points: usize,
    spacing: f64,
    axes: [(i64, i64, i64, &str); 4],
) -> std::io::Result<()> {
    writeln!(w, "{:>6}", -1)?;
    if opts.binary {
        writeln!(
            w,
            "{:>6}b{:>6}{:>6}{:>12}{:>12}{:>6}{:>6}{:>12}{:>12}",
            58, 1, 2, 11, data_bytes, 0, 0, 0, 0
        )?;
    } else {
        writeln!(w, "{:>6}{:74}", 58, "")?;
    }
    for id in ids {
        writeln!(w, "{}", header_text(id, 80).trim_end())?;
    }
    writeln!(
        w,
        "{:>5}{:>10}{:>5}{:>10} {}{:>10}{:>4} {}{:>10}{:>4}",
        FUNCTION_FRF,
        0,
        0,
        0,
        header_text(&response.entity, 10),
        response.dof.node,
        response.dof.direction,
        header_text(&reference.entity, 10),
        reference.dof.node,
        reference.dof.direction
    )?;
    let ordinate = if opts.single {
        Ordinate::ComplexSingle
    } else {
        Ordinate::ComplexDouble
    };
    writeln!(
        w,
        "{:>10}{:>10}{:>10}{}{}{}",
        ordinate.code(),
        points,
        1,
        fortran_e(0.0, 13, 6),
        fortran_e(spacing, 13, 6),
        fortran_e(0.0, 13, 5)
    )?;
    for (data_type, length, force, units) in axes {
        writeln!(
            w,
            "{:>10}{:>5}{:>5}{:>5} {} {}",
            data_type,
            length,
            force,
            0,
            header_text("NONE", 20),
            header_text(units, 20)
        )?;
    }
    Ok(())
}

/// Writes FRFs as UFF dataset 58, one record per pair (output-major), through a
/// temporary file and a rename. `channels` gives the node and direction of each output
/// and input (else [`ChannelTable::numbered`]); `units` (response, force) go in the
/// axis labels.
///
/// # Errors
/// [`IoError`] naming the file; a channel table whose size differs from the FRFs.
pub fn write_uff58(
    path: &Path,
    frf: &FrfData,
    channels: Option<&ChannelTable>,
    units: (Option<&str>, Option<&str>),
    opts: UffWriteOptions,
) -> Result<(), IoError> {
    let (q, p, lines) = (frf.outputs(), frf.inputs(), frf.lines());
    let numbered = ChannelTable::numbered(q, p);
    let table = channels.unwrap_or(&numbered);
    if table.outputs.len() != q || table.inputs.len() != p {
        return Err(IoError::format(
            path,
            "",
            format!(
                "the channel table has {} outputs and {} inputs, the FRFs {q} and {p}",
                table.outputs.len(),
                table.inputs.len()
            ),
        ));
    }
    let quantity = frf.quantity();
    let (response_unit, force_unit) = (units.0.unwrap_or("NONE"), units.1.unwrap_or("NONE"));
    write_streamed(path, |w| {
        for i in 0..q {
            for j in 0..p {
                let size = if opts.single { 4 } else { 8 };
                let title = format!("era: H{}_{} ({quantity} / force)", i + 1, j + 1);
                write_header58(
                    w,
                    opts,
                    lines * 2 * size,
                    [&title, "NONE", "NONE", "NONE", "NONE"],
                    &table.outputs[i],
                    &table.inputs[j],
                    lines,
                    frf.spacing_hz(),
                    [
                        (18, 0, 0, "Hz"),
                        (quantity_code(quantity), 1, 0, response_unit),
                        (13, 0, 1, force_unit),
                        (0, 0, 0, "NONE"),
                    ],
                )?;
                let values = frf.pair(i, j);
                if opts.binary {
                    let mut buf = Vec::with_capacity(lines * 2 * size);
                    for v in values {
                        if opts.single {
                            buf.extend_from_slice(&(v.re as f32).to_le_bytes());
                            buf.extend_from_slice(&(v.im as f32).to_le_bytes());
                        } else {
                            buf.extend_from_slice(&v.re.to_le_bytes());
                            buf.extend_from_slice(&v.im.to_le_bytes());
                        }
                    }
                    w.write_all(&buf)?;
                } else {
                    let (width, digits, per_line) =
                        if opts.single { (13, 5, 6) } else { (20, 12, 4) };
                    let mut line = String::with_capacity(80);
                    let parts = values.iter().flat_map(|v| [v.re, v.im]);
                    for (k, x) in parts.enumerate() {
                        let digits = if x != 0.0 && x.abs().log10().abs() >= 99.0 {
                            digits - 1
                        } else {
                            digits
                        };
                        line.push_str(&fortran_e(x, width, digits));
                        if (k + 1) % per_line == 0 {
                            line.push('\n');
                            w.write_all(line.as_bytes())?;
                            line.clear();
                        }
                    }
                    if !line.is_empty() {
                        line.push('\n');
                        w.write_all(line.as_bytes())?;
                    }
                }
                // In 58b the closing -1 follows the data directly.
                writeln!(w, "{:>6}", -1)?;
            }
        }
        Ok(())
    })
}

/// Runs `body` on a buffered temporary file, then flushes, syncs and renames it.
fn write_streamed(
    path: &Path,
    body: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
) -> Result<(), IoError> {
    write_via(path, |tmp| {
        (|| {
            let file = std::fs::File::create(tmp)?;
            let mut w = std::io::BufWriter::with_capacity(1 << 20, file);
            body(&mut w)?;
            w.flush()?;
            w.get_ref().sync_all()
        })()
        .map_err(|e| IoError::io(path, e))
    })
}

/// Writes the mode shapes of an identified model as UFF dataset 55, one record per
/// mode: complex eigenvalue analysis (type 3), the continuous pole `s` (rad/s) as the
/// eigenvalue, modal A and B written as 0, and at each output node the complex shape
/// `Cφ` in its direction (a negative direction flips the sign). Translations only give
/// 3 values per node; any rotation gives 6.
///
/// # Errors
/// [`IoError`] naming the file; a channel table whose size differs from the shapes.
pub fn write_uff55(
    path: &Path,
    modal: &ModalParameters,
    channels: Option<&ChannelTable>,
    quantity: Quantity,
) -> Result<(), IoError> {
    let q = modal.modes.first().map_or(0, |m| m.shape.len());
    let numbered = ChannelTable::numbered(q, 0);
    let outputs = channels.map_or(&numbered.outputs, |t| &t.outputs);
    if modal.modes.iter().any(|m| m.shape.len() != outputs.len()) {
        return Err(IoError::format(
            path,
            "",
            format!(
                "the channel table has {} outputs, the mode shapes {q}",
                outputs.len()
            ),
        ));
    }
    let rotations = outputs.iter().any(|c| c.dof.direction.abs() > 3);
    let per_node = if rotations { 6 } else { 3 };
    // Nodes in order of first appearance; each output lands in one slot.
    let mut nodes: Vec<i64> = Vec::new();
    let mut slots = Vec::with_capacity(outputs.len());
    for c in outputs {
        let n = match nodes.iter().position(|&x| x == c.dof.node) {
            Some(n) => n,
            None => {
                nodes.push(c.dof.node);
                nodes.len() - 1
            }
        };
        let d = c.dof.direction;
        let component = if d == 0 {
            2
        } else {
            (d.unsigned_abs() - 1) as usize
        };
        let sign = if d < 0 { -1.0 } else { 1.0 };
        slots.push((n, component.min(per_node - 1), sign));
    }
    write_streamed(path, |w| {
        for (number, mode) in modal.modes.iter().enumerate() {
            writeln!(w, "{:>6}", -1)?;
            writeln!(w, "{:>6}{:74}", 55, "")?;
            let title = format!(
                "era: mode {} at {:.6} Hz, damping ratio {:.6}",
                number + 1,
                mode.frequency_hz,
                mode.damping_ratio
            );
            for id in [title.as_str(), "NONE", "NONE", "NONE", "NONE"] {
                writeln!(w, "{}", header_text(id, 80).trim_end())?;
            }
            writeln!(
                w,
                "{:>10}{:>10}{:>10}{:>10}{:>10}{:>10}",
                1,
                3,
                if rotations { 3 } else { 2 },
                quantity_code(quantity),
                5,
                per_node
            )?;
            writeln!(w, "{:>10}{:>10}{:>10}{:>10}", 2, 6, 0, number + 1)?;
            let s = mode.continuous_pole;
            let mut r8 = String::new();
            for x in [s.re, s.im, 0.0, 0.0, 0.0, 0.0] {
                r8.push_str(&fortran_e(x, 13, 5));
            }
            writeln!(w, "{r8}")?;
            let mut values = vec![Complex64::new(0.0, 0.0); nodes.len() * per_node];
            for (k, &(n, component, sign)) in slots.iter().enumerate() {
                values[n * per_node + component] = mode.shape[k] * sign;
            }
            for (n, node) in nodes.iter().enumerate() {
                writeln!(w, "{node:>10}")?;
                let mut line = String::new();
                for (k, v) in values[n * per_node..(n + 1) * per_node]
                    .iter()
                    .flat_map(|v| [v.re, v.im])
                    .enumerate()
                {
                    line.push_str(&fortran_e(v, 13, 5));
                    if (k + 1) % 6 == 0 {
                        line.push('\n');
                    }
                }
                w.write_all(line.as_bytes())?;
            }
            writeln!(w, "{:>6}", -1)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use era::frf::uniform_lines;

    fn sample(q: usize, p: usize, lines: usize) -> FrfData {
        FrfData::from_fn(
            uniform_lines(lines, 0.25),
            q,
            p,
            Quantity::Acceleration,
            |i, j, k| {
                Complex64::new(
                    (i + 1) as f64 * 1.234_567_890_123_4 - k as f64 / 7.0,
                    -((j + 1) as f64) * 1e-7 / 3.0 + k as f64,
                )
            },
        )
        .unwrap()
    }

    #[test]
    fn fortran_e_matches_the_fortran_layout() {
        assert_eq!(fortran_e(0.0, 13, 5), "  0.00000e+00");
        assert_eq!(fortran_e(-1.5e-3, 20, 12), " -1.500000000000e-03");
        assert_eq!(fortran_e(2.5e120, 20, 11), "  2.50000000000e+120");
        assert_eq!(fortran_e(0.25, 13, 6), " 2.500000e-01");
    }

    fn round_trip(opts: UffWriteOptions) -> (FrfData, FrfData) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.uff");
        let frf = sample(3, 2, 11);
        write_uff58(&path, &frf, None, (Some("m/s^2"), Some("N")), opts).unwrap();
        let back = read_frf_uff(&path, Quantity::Velocity).unwrap();
        assert_eq!(back.channels, Some(ChannelTable::numbered(3, 2)));
        assert!(back.quantity_given);
        assert_eq!(back.metadata["response_unit"], "m/s^2");
        assert_eq!(back.metadata["force_unit"], "N");
        (frf, back.frf)
    }

    #[test]
    fn binary_double_round_trip_is_exact() {
        let (a, b) = round_trip(UffWriteOptions {
            binary: true,
            single: false,
        });
        assert_eq!(a, b);
    }

    #[test]
    fn ascii_and_single_round_trips_keep_their_digits() {
        for (opts, tol) in [
            (UffWriteOptions::default(), 1e-12),
            (
                UffWriteOptions {
                    binary: true,
                    single: true,
                },
                1e-7,
            ),
            (
                UffWriteOptions {
                    binary: false,
                    single: true,
                },
                1e-5,
            ),
        ] {
            let (a, b) = round_trip(opts);
            assert_eq!(a.frequency_hz(), b.frequency_hz());
            for (x, y) in a.values().iter().zip(b.values()) {
                assert!(
                    (x - y).norm() <= tol * x.norm().max(1e-300),
                    "{opts:?}: {x} vs {y}"
                );
            }
        }
    }

    #[test]
    fn header_only_read_skips_the_data() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.uff");
        write_uff58(
            &path,
            &sample(2, 2, 37),
            None,
            (None, None),
            UffWriteOptions::default(),
        )
        .unwrap();
        let c = read_uff(&path, false).unwrap();
        assert_eq!(c.functions.len(), 4);
        assert!(c
            .functions
            .iter()
            .all(|(f, d)| d.is_none() && f.points == 37));
    }

    #[test]
    fn delimiters_and_closings() {
        assert_eq!(closing_after(b"    -1\n", 0), Some(7));
        assert_eq!(closing_after(b"\r\n    -1", 0), Some(8));
        assert_eq!(closing_after(b"    -12\n", 0), None);
        assert!(looks_like_uff(b"\n    -1\n    58\n"));
        assert!(!looks_like_uff(b"frequency_hz,H1_1_re\n"));
    }
}
