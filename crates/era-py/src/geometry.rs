//! `read_geometry`: a test geometry (UFF 15/2411, 82, 18/2420 or era's geometry CSV)
//! as numpy arrays, read and checked by [`era_io::geometry::read_geometry`], the
//! reader behind the CLI's `--geometry`; and `Identification.shapes_on`, each mode's
//! displacement at the nodes of a geometry.

use crate::{guarded, io_error, value_error, vector};
use era::data::identification::Identification;
use era::Complex64;
use era_io::frf_file::{parse_direction, Channel, ChannelTable, Dof};
use era_io::geometry::{
    map_channels, read_geometry as read_geometry_file, Geometry, Node, TraceLine,
};
use numpy::PyArrayMethods;
use pyo3::exceptions::{PyTypeError, PyValueError};
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
    let g = guarded(py, || read_geometry_file(&path).map_err(io_error))?;
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

/// A geometry given to `shapes_on`: a path (read as `read_geometry` reads it) or the
/// dict `read_geometry` returns (`ids`, `xyz`, and `lines` when there are any),
/// checked as a file is.
fn geometry_of(geometry: &Bound<'_, PyAny>) -> PyResult<Geometry> {
    let Ok(d) = geometry.downcast::<PyDict>() else {
        let path: PathBuf = geometry.extract().map_err(|_| {
            PyTypeError::new_err("geometry: give a path or the dict era.read_geometry returns")
        })?;
        return read_geometry_file(&path).map_err(io_error);
    };
    let listed = |key: &str| -> PyResult<Option<Bound<'_, PyAny>>> {
        match d.get_item(key)? {
            None => Ok(None),
            Some(v) if v.hasattr("tolist")? => Ok(Some(v.call_method0("tolist")?)),
            Some(v) => Ok(Some(v)),
        }
    };
    let (Some(ids), Some(xyz)) = (listed("ids")?, listed("xyz")?) else {
        return value_error(
            "geometry: the dict needs 'ids' and 'xyz' (as era.read_geometry returns)",
        );
    };
    let ids: Vec<i64> = ids
        .extract()
        .map_err(|_| PyValueError::new_err("geometry['ids']: integers expected"))?;
    let xyz: Vec<[f64; 3]> = xyz
        .extract()
        .map_err(|_| PyValueError::new_err("geometry['xyz']: rows of three numbers expected"))?;
    if ids.len() != xyz.len() {
        return value_error(format!(
            "geometry: {} ids and {} rows of xyz; one row per node",
            ids.len(),
            xyz.len()
        ));
    }
    let lines: Vec<[i64; 2]> = match listed("lines")? {
        None => Vec::new(),
        Some(l) => l
            .extract()
            .map_err(|_| PyValueError::new_err("geometry['lines']: pairs of node ids expected"))?,
    };
    let g = Geometry {
        nodes: ids
            .iter()
            .zip(&xyz)
            .map(|(&id, &xyz)| Node {
                id,
                xyz,
                displacement_system: 0,
            })
            .collect(),
        trace_lines: vec![TraceLine {
            id: 1,
            name: String::new(),
            strokes: lines.iter().map(|l| l.to_vec()).collect(),
        }],
        coordinate_systems: Vec::new(),
        notes: Vec::new(),
    };
    g.validate()
        .map_err(|m| PyValueError::new_err(format!("geometry: {m}")))?;
    Ok(g)
}

/// The channel table of `q` outputs: era's numbering (nodes `1..q`, +Z) without
/// `channels`, else one `(node, direction)` per output, the direction a UFF number
/// (±1..±3 translations) or its name (`"+X"`, `"-Z"`).
fn outputs_of(channels: Option<&Bound<'_, PyAny>>, q: usize) -> PyResult<Vec<Channel>> {
    let Some(channels) = channels else {
        return Ok(ChannelTable::numbered(q, 0).outputs);
    };
    let rows: Vec<(i64, Bound<'_, PyAny>)> = channels.extract().map_err(|_| {
        PyValueError::new_err("channels: one (node, direction) pair per output expected")
    })?;
    if rows.len() != q {
        return value_error(format!(
            "channels: {} given, the model has {q} outputs; one (node, direction) per output",
            rows.len()
        ));
    }
    rows.iter()
        .enumerate()
        .map(|(k, (node, d))| {
            let direction = match d.extract::<i64>() {
                Ok(n) => Some(n),
                Err(_) => d
                    .extract::<String>()
                    .ok()
                    .and_then(|t| parse_direction(t.trim())),
            };
            let direction = direction.ok_or_else(|| {
                PyValueError::new_err(format!(
                    "channels[{k}]: direction {d}: expected +X, -Y, Z ... or a number ±1..±6"
                ))
            })?;
            Ok(Channel {
                dof: Dof {
                    node: *node,
                    direction,
                },
                entity: "NONE".into(),
            })
        })
        .collect()
}

/// `Identification.shapes_on`: each mode's displacement at each node of `geometry`
/// (module doc of the method in model.rs).
pub(crate) fn shapes_on<'py>(
    py: Python<'py>,
    found: &Identification,
    geometry: &Bound<'py, PyAny>,
    channels: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let g = geometry_of(geometry)?;
    let q = found.measured.outputs();
    let outputs = outputs_of(channels, q)?;
    let map = map_channels(&g, &outputs);
    if map.placed.is_empty() {
        return value_error(format!(
            "the geometry ({}) carries none of the {q} outputs: {}{}",
            g.summary(),
            map.not_drawn
                .first()
                .map_or(String::new(), |u| u.reason.clone()),
            if channels.is_none() {
                " (without channels= the outputs are nodes 1..q in +Z)"
            } else {
                ""
            }
        ));
    }
    let n = g.nodes.len();
    let modes = &found.modal.modes;
    let nan = Complex64::new(f64::NAN, f64::NAN);
    let mut measured = vec![false; n];
    for p in &map.placed {
        measured[p.node] = true;
    }
    let mut u = vec![nan; modes.len() * n * 3];
    for (m, mode) in modes.iter().enumerate() {
        for (k, _) in measured.iter().enumerate().filter(|(_, &on)| on) {
            for a in 0..3 {
                u[(m * n + k) * 3 + a] = Complex64::new(0.0, 0.0);
            }
        }
        for p in &map.placed {
            let v = mode.shape[p.channel];
            for (a, e) in p.direction.iter().enumerate() {
                u[(m * n + p.node) * 3 + a] += v * e;
            }
        }
    }
    let not_drawn = map.not_drawn_sentences(&outputs);
    let d = PyDict::new(py);
    d.set_item("ids", vector(py, g.nodes.iter().map(|x| x.id).collect()))?;
    d.set_item(
        "xyz",
        vector(py, g.nodes.iter().flat_map(|x| x.xyz).collect()).reshape([n, 3])?,
    )?;
    d.set_item("displacement", vector(py, u).reshape([modes.len(), n, 3])?)?;
    d.set_item("measured", vector(py, measured))?;
    d.set_item(
        "not_drawn_outputs",
        vector(py, map.not_drawn.iter().map(|x| x.channel as i64).collect()),
    )?;
    d.set_item("not_drawn", not_drawn)?;
    Ok(d)
}
