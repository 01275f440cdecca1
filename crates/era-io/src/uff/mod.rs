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
//! an identified model as complex-eigenvalue records (analysis type 3), after the
//! geometry's datasets 18, 15 and 82 when one is given ([`write_uff55_on`]).
//!
//! # Geometry
//! [`parse_uff_geometry`] reads nodes (15, 2411), trace lines (82) and coordinate
//! systems (18, 2420) into a [`crate::geometry::Geometry`]; see its module.

mod frf;
mod geometry;
mod parse;
#[cfg(test)]
mod tests;
mod types;
mod write55;
mod write58;
mod write_geometry;

pub use crate::frf_file::{direction_name, listed, Channel, ChannelTable, Dof};
pub use frf::{frf_from_uff, quantity_of, read_frf_uff, FrfLayout};
pub use geometry::parse_uff_geometry;
pub use parse::{parse_uff, read_uff};
pub use types::*;
pub use write55::{write_uff55, write_uff55_on};
pub use write58::{write_uff58, UffWriteOptions};
pub use write_geometry::write_geometry_records;
