//! Test geometry: the nodes of a structure, the trace lines drawn between them and the
//! coordinate systems of both, read from a UFF file (datasets 15/2411, 82, 18/2420) or
//! from our geometry CSV ([`csv`]); with [`map_channels`], which places each channel of
//! an FRF or time file (node and direction) on a node.
//!
//! A [`Geometry`] is plain data: every position is in the global frame (the coordinate
//! systems have been applied when it was read), every coordinate is finite, node ids are
//! unique, and every trace line names nodes that exist ([`Geometry::validate`]).
//!
//! Coordinate systems follow the I-DEAS definitions: a system is an origin and three
//! orthonormal axes in the global frame, Cartesian `(x, y, z)`, cylindrical
//! `(r, θ°, z)` or spherical `(r, θ°, φ°)` with θ from the z axis and φ in the xy plane
//! from x. A node's *definition* system places it (dataset 15; dataset 2411 gives
//! positions in the part frame already); its *displacement* system gives the meaning of
//! the directions measured there (+X of a node in a system whose x axis points down is
//! global −Z).

pub mod csv;
mod frames;
pub mod layouts;

pub use frames::{CoordinateSystem, SystemKind};

use crate::frf_file::Channel;
use crate::IoError;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// A node: its id, its place in the global frame, and the coordinate system its
/// measured directions refer to (0: the global frame).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Node {
    /// Node label, as channels name it.
    pub id: i64,
    /// Global x, y, z.
    pub xyz: [f64; 3],
    /// Displacement coordinate system (0 = global).
    #[serde(default)]
    pub displacement_system: i64,
}

/// A trace line: strokes of connected nodes (a polyline each). A stroke of two nodes
/// is one segment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TraceLine {
    /// Trace line number.
    pub id: i64,
    /// Its name (the identification line of dataset 82), possibly empty.
    #[serde(default)]
    pub name: String,
    /// Polylines, each a list of node ids drawn in turn.
    pub strokes: Vec<Vec<i64>>,
}

/// Nodes, trace lines and coordinate systems, in the global frame.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Geometry {
    /// The nodes, in the file's order.
    pub nodes: Vec<Node>,
    /// The trace lines, in the file's order.
    pub trace_lines: Vec<TraceLine>,
    /// The coordinate systems other than the global one (id 0).
    #[serde(default)]
    pub coordinate_systems: Vec<CoordinateSystem>,
    /// What the reader tolerated or left out (other datasets, a missing displacement
    /// system), for the run's notes.
    #[serde(default)]
    pub notes: Vec<String>,
}

/// Where the parts of a geometry came from in its file, for messages: 1-based line
/// numbers of each node and each trace line.
#[derive(Debug, Clone, Default)]
pub(crate) struct Origins {
    pub nodes: Vec<usize>,
    pub trace_lines: Vec<usize>,
}

impl Origins {
    fn node(&self, k: usize) -> String {
        self.nodes
            .get(k)
            .map(|l| format!(" (line {l})"))
            .unwrap_or_default()
    }
    fn trace(&self, k: usize) -> String {
        self.trace_lines
            .get(k)
            .map(|l| format!(" (line {l})"))
            .unwrap_or_default()
    }
}

impl Geometry {
    /// Every segment drawn, as node pairs, in order.
    pub fn segments(&self) -> Vec<(i64, i64)> {
        self.trace_lines
            .iter()
            .flat_map(|t| t.strokes.iter())
            .flat_map(|s| s.windows(2).map(|w| (w[0], w[1])))
            .collect()
    }

    /// The index of each node id.
    pub fn node_index(&self) -> HashMap<i64, usize> {
        self.nodes
            .iter()
            .enumerate()
            .map(|(k, n)| (n.id, k))
            .collect()
    }

    /// The coordinate system `id`; `None` for 0 (global) or an unknown id.
    pub fn system(&self, id: i64) -> Option<&CoordinateSystem> {
        self.coordinate_systems.iter().find(|c| c.id == id)
    }

    /// A one-line description: `72 nodes, 108 segments in 2 trace lines`.
    pub fn summary(&self) -> String {
        let mut s = format!(
            "{} nodes, {} segments in {} trace lines",
            self.nodes.len(),
            self.segments().len(),
            self.trace_lines.len()
        );
        if !self.coordinate_systems.is_empty() {
            s.push_str(&format!(
                ", {} coordinate systems",
                self.coordinate_systems.len()
            ));
        }
        s
    }

    /// Checks what every geometry must satisfy: at least one node, unique node ids
    /// and coordinate system ids, finite coordinates, orthonormal axes, trace lines
    /// naming existing nodes.
    ///
    /// # Errors
    /// The first problem, naming the node, trace line or system.
    pub fn validate(&self) -> Result<(), String> {
        self.check(&Origins::default())
    }

    pub(crate) fn check(&self, at: &Origins) -> Result<(), String> {
        if self.nodes.is_empty() {
            return Err("the geometry has no nodes".into());
        }
        let mut first: HashMap<i64, usize> = HashMap::with_capacity(self.nodes.len());
        for (k, n) in self.nodes.iter().enumerate() {
            if let Some(c) = n.xyz.iter().position(|v| !v.is_finite()) {
                return Err(format!(
                    "node {}{}: coordinate {} is {} (not a finite number)",
                    n.id,
                    at.node(k),
                    ["x", "y", "z"][c],
                    n.xyz[c]
                ));
            }
            if let Some(&j) = first.get(&n.id) {
                let lines = match (at.nodes.get(j), at.nodes.get(k)) {
                    (Some(a), Some(b)) => format!(" (lines {a} and {b})"),
                    _ => String::new(),
                };
                return Err(format!(
                    "node {} is defined twice{lines}; node ids must be unique",
                    n.id
                ));
            }
            first.insert(n.id, k);
        }
        let mut systems = BTreeMap::new();
        for c in &self.coordinate_systems {
            if c.id == 0 {
                return Err(
                    "coordinate system 0 is the global frame and cannot be redefined".into(),
                );
            }
            if systems.insert(c.id, ()).is_some() {
                return Err(format!("coordinate system {} is defined twice", c.id));
            }
            c.check()?;
        }
        for (k, t) in self.trace_lines.iter().enumerate() {
            for s in &t.strokes {
                for id in s {
                    if !first.contains_key(id) {
                        return Err(format!(
                            "trace line {}{} names node {id}, which is not among the {} nodes",
                            t.id,
                            at.trace(k),
                            self.nodes.len()
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

/// A channel placed on a node: which channel, which node, and its measuring direction
/// as a global unit vector (its sign included).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlacedChannel {
    /// Index of the channel in the list given.
    pub channel: usize,
    /// Index of its node in [`Geometry::nodes`].
    pub node: usize,
    /// Global direction of a positive value.
    pub direction: [f64; 3],
}

/// A channel that cannot be drawn, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UndrawnChannel {
    /// Index of the channel in the list given.
    pub channel: usize,
    /// Why: no such node, a scalar or rotational direction.
    pub reason: String,
}

/// Where the channels of a measurement sit on a geometry.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ChannelMap {
    /// Channels on a node, with a translational direction.
    pub placed: Vec<PlacedChannel>,
    /// Channels not drawn: not an error, the report lists them.
    pub not_drawn: Vec<UndrawnChannel>,
}

impl ChannelMap {
    /// One sentence per channel not drawn, `channels` the list that was mapped:
    /// `output 3 (node 3 +Z): why`.
    pub fn not_drawn_sentences(&self, channels: &[Channel]) -> Vec<String> {
        self.not_drawn
            .iter()
            .map(|u| {
                let c = &channels[u.channel];
                format!(
                    "output {} (node {} {}): {}",
                    u.channel + 1,
                    c.dof.node,
                    crate::frf_file::direction_name(c.dof.direction),
                    u.reason
                )
            })
            .collect()
    }
}

/// Places each channel (node and direction, as [`crate::frf_file::ChannelTable`] gives
/// them) on the geometry. A channel whose node is not in the geometry, or whose
/// direction is a scalar (0) or a rotation (±4..±6), is not drawn and listed with the
/// reason; nothing is guessed.
pub fn map_channels(geometry: &Geometry, channels: &[Channel]) -> ChannelMap {
    let index = geometry.node_index();
    let mut map = ChannelMap::default();
    for (k, c) in channels.iter().enumerate() {
        let d = c.dof.direction;
        let reason = match index.get(&c.dof.node) {
            None => Some(format!("node {} is not in the geometry", c.dof.node)),
            Some(_) if d == 0 => Some(format!(
                "node {}: a scalar channel has no direction",
                c.dof.node
            )),
            Some(_) if !(1..=3).contains(&d.abs()) => Some(format!(
                "node {}: direction {} is not a translation",
                c.dof.node,
                crate::frf_file::direction_name(d)
            )),
            Some(&n) => {
                let node = &geometry.nodes[n];
                let axis = (d.unsigned_abs() - 1) as usize;
                let local = match geometry.system(node.displacement_system) {
                    Some(s) => s.direction_at(node.xyz, axis),
                    None => {
                        let mut e = [0.0; 3];
                        e[axis] = 1.0;
                        e
                    }
                };
                let sign = d.signum() as f64;
                map.placed.push(PlacedChannel {
                    channel: k,
                    node: n,
                    direction: local.map(|v| v * sign),
                });
                None
            }
        };
        if let Some(reason) = reason {
            map.not_drawn.push(UndrawnChannel { channel: k, reason });
        }
    }
    map
}

/// Reads a geometry file: UFF (datasets 15, 2411, 82, 18, 2420; told by its first
/// line, `-1`) or our geometry CSV ([`csv`]).
///
/// # Errors
/// [`IoError`] naming the file and the line: a malformed record or row, duplicate node
/// ids, a non-finite coordinate, a trace line naming a missing node, an undefined or
/// degenerate coordinate system, or a file without nodes.
pub fn read_geometry(path: &Path) -> Result<Geometry, IoError> {
    let bytes = crate::input::read_input(path)?;
    parse_geometry(&bytes, path)
}

/// Parses the bytes of a geometry file (see [`read_geometry`]); `path` names it in
/// messages.
///
/// # Errors
/// As [`read_geometry`].
pub fn parse_geometry(bytes: &[u8], path: &Path) -> Result<Geometry, IoError> {
    if bytes.iter().all(|b| b.is_ascii_whitespace()) {
        return Err(IoError::format(path, "", "the file is empty"));
    }
    if crate::uff::looks_like_uff(bytes) {
        crate::uff::parse_uff_geometry(bytes, path)
    } else {
        csv::parse_geometry_csv(bytes, path)
    }
}

/// At most 40 characters of `text`, control characters escaped, for a message.
fn shortened(text: &str) -> String {
    let s: String = text.chars().take(40).collect();
    let more = if text.chars().count() > 40 { "…" } else { "" };
    format!("{}{more}", crate::text::escaped(&s))
}

#[cfg(test)]
mod tests;
