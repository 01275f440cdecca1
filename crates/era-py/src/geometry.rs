//! `read_geometry`: a test geometry (UFF 15/2411, 82, 18/2420 or era's geometry CSV)
//! as numpy arrays, read and checked by [`era_io::geometry::read_geometry`], the
//! reader behind the CLI's `--geometry`.

use crate::{guarded, io_error, vector};
use numpy::PyArrayMethods;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// Reads a geometry file and returns a dict:
///
/// - `ids`: int64 (n,), the node ids;
/// - `xyz`: float64 (n, 3), their global positions (coordinate systems applied);
/// - `lines`: int64 (m, 2), every trace-line segment as a pair of node ids;
/// - `line_rows`: int64 (m, 2), the same segments as rows of `xyz`;
/// - `displacement_systems`: int64 (n,), the coordinate system of each node's
///   measured directions (0: global);
/// - `notes`: what the reader skipped or assumed.
///
/// A malformed file, duplicate node ids, a non-finite coordinate or a trace line naming
/// a missing node raise `ValueError` naming the file and line; a missing file
/// `FileNotFoundError`.
#[pyfunction]
pub fn read_geometry(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyDict>> {
    let g = guarded(py, || {
        era_io::geometry::read_geometry(&path).map_err(io_error)
    })?;
    let index = g.node_index();
    let segments = g.segments();
    let n = g.nodes.len();
    let m = segments.len();
    let ids: Vec<i64> = g.nodes.iter().map(|node| node.id).collect();
    let xyz: Vec<f64> = g.nodes.iter().flat_map(|node| node.xyz).collect();
    let systems: Vec<i64> = g
        .nodes
        .iter()
        .map(|node| node.displacement_system)
        .collect();
    let lines: Vec<i64> = segments.iter().flat_map(|&(a, b)| [a, b]).collect();
    // Every segment names existing nodes: the reader checked it.
    let rows: Vec<i64> = lines.iter().map(|id| index[id] as i64).collect();
    let d = PyDict::new(py);
    d.set_item("ids", vector(py, ids))?;
    d.set_item("xyz", vector(py, xyz).reshape([n, 3])?)?;
    d.set_item("lines", vector(py, lines).reshape([m, 2])?)?;
    d.set_item("line_rows", vector(py, rows).reshape([m, 2])?)?;
    d.set_item("displacement_systems", vector(py, systems))?;
    d.set_item("notes", g.notes)?;
    Ok(d)
}
