//! The records of a UFF file as read: ordinate storage, axes, 58 headers and values.

use super::*;
use era::{Complex64, Quantity};
use std::collections::BTreeMap;

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
    pub(super) fn from_code(code: i64) -> Option<Self> {
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

pub(super) fn trim_bytes(line: &[u8]) -> &[u8] {
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

pub(super) fn quantity_code(q: Quantity) -> i64 {
    match q {
        Quantity::Displacement => 8,
        Quantity::Velocity => 11,
        Quantity::Acceleration => 12,
    }
}
