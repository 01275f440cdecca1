//! Geometries drawn by `era` itself for its simulated sets, so that their mode shapes
//! can be shown: the DTA-like ring truss with its tripod of `era simulate modal`, and
//! the thesis's 4-mass chain of `era demo` drawn as a shear frame.
//!
//! These are *layouts*, not finite-element models: the simulated shapes are random
//! vectors (or the chain's exact shapes) placed on their nodes, one channel per node,
//! and the nodes without a channel are drawn where they are.
//!
//! The DTA-like layout follows thesis chapter II (section 2.1): a circular ring truss
//! (two chords of joints tied by verticals and diagonals) as the backbone; an equipment
//! tripod of three legs from the ring up to a secondary plate; two solar-array masts
//! out from the ring, each with its panel; three mass simulators beneath the ring. The
//! proportions are indicative (metres), chosen for the picture. Without a channel
//! table the outputs are nodes `1..q` in +Z (era's numbering): here they are joints
//! of the upper chord, spread evenly round the ring.

use super::{Geometry, Node, TraceLine};
use std::f64::consts::PI;

/// Radius of the ring truss (m).
const RING_RADIUS: f64 = 1.8;
/// Depth between its upper and lower chords (m).
const RING_DEPTH: f64 = 0.35;
/// Height of the tripod's secondary plate above the upper chord (m).
const TRIPOD_HEIGHT: f64 = 2.2;
/// Radius of the secondary plate (m).
const PLATE_RADIUS: f64 = 0.3;
/// Length of a solar-array mast beyond the ring (m).
const MAST_LENGTH: f64 = 2.6;
/// How far below the lower chord the mass simulators hang (m).
const SIMULATOR_DROP: f64 = 0.5;

fn node(id: i64, xyz: [f64; 3]) -> Node {
    Node {
        id,
        xyz,
        displacement_system: 0,
    }
}

fn trace(id: i64, name: &str, strokes: Vec<Vec<i64>>) -> TraceLine {
    TraceLine {
        id,
        name: name.to_string(),
        strokes,
    }
}

/// The number of ring joints for `outputs` channels: a multiple of 12 (so that the
/// tripod's legs, the masts and the mass simulators fall on joints), at least 12 and
/// at least `outputs`.
pub fn ring_joints(outputs: usize) -> usize {
    outputs.max(12).div_ceil(12) * 12
}

/// The DTA-like structure of `era simulate modal` with `outputs` channels: the output
/// channels (nodes `1..=outputs`, +Z) on joints of the ring's upper chord, spread
/// evenly; the other joints `101..`, the lower chord `201..`, the tripod's plate
/// `300..303`, the masts and panels `510..`, `520..` and the mass simulators `401..403`
/// carry no channel.
pub fn dta_like(outputs: usize) -> Geometry {
    let n = ring_joints(outputs);
    // Upper-chord joint j carries output k + 1 when j is the k-th evenly spread joint.
    let mut upper_id: Vec<i64> = (0..n).map(|j| 101 + j as i64).collect();
    for k in 0..outputs {
        upper_id[k * n / outputs] = 1 + k as i64;
    }
    let lower_id = |j: usize| 201 + (j % n) as i64;
    let angle = |j: usize| 2.0 * PI * j as f64 / n as f64;
    let on_ring = |j: usize, r: f64, z: f64| [r * angle(j).cos(), r * angle(j).sin(), z];
    let mut nodes = Vec::with_capacity(2 * n + 20);
    for (j, &id) in upper_id.iter().enumerate() {
        nodes.push(node(id, on_ring(j, RING_RADIUS, 0.0)));
    }
    for j in 0..n {
        nodes.push(node(lower_id(j), on_ring(j, RING_RADIUS, -RING_DEPTH)));
    }
    let up = |j: usize| upper_id[j % n];
    let mut lines = Vec::new();
    // The ring truss: both chords closed, verticals, one diagonal per bay.
    let mut upper: Vec<i64> = (0..=n).map(up).collect();
    let lower: Vec<i64> = (0..=n).map(lower_id).collect();
    let mut ties = Vec::with_capacity(2 * n);
    for j in 0..n {
        ties.push(vec![up(j), lower_id(j)]);
        ties.push(vec![lower_id(j), up(j + 1)]);
    }
    let mut strokes = vec![std::mem::take(&mut upper), lower];
    strokes.extend(ties);
    lines.push(trace(1, "ring truss", strokes));
    // The tripod: three legs from the upper chord to the plate, the plate a triangle
    // about its centre (node 300).
    nodes.push(node(300, [0.0, 0.0, TRIPOD_HEIGHT]));
    let mut legs = Vec::new();
    for leg in 0..3 {
        let j = leg * n / 3;
        let id = 301 + leg as i64;
        nodes.push(node(id, on_ring(j, PLATE_RADIUS, TRIPOD_HEIGHT)));
        legs.push(vec![up(j), id]);
        legs.push(vec![id, 300]);
    }
    legs.push(vec![301, 302, 303, 301]);
    lines.push(trace(2, "tripod", legs));
    // Two solar-array masts, out from the ring at a quarter and three quarters of a
    // turn, each with a panel (a rectangle along the mast's outer part).
    let mut masts = Vec::new();
    for (m, j) in [(0, n / 4), (1, 3 * n / 4)] {
        let base = 510 + 10 * m;
        let (c, s) = (angle(j).cos(), angle(j).sin());
        let at = |r: f64, t: f64| [r * c - t * s, r * s + t * c, 0.0];
        let tip = RING_RADIUS + MAST_LENGTH;
        let inner = RING_RADIUS + 0.35 * MAST_LENGTH;
        nodes.push(node(base, at(tip, 0.0)));
        nodes.push(node(base + 1, at(inner, -0.7)));
        nodes.push(node(base + 2, at(tip, -0.7)));
        nodes.push(node(base + 3, at(tip, 0.7)));
        nodes.push(node(base + 4, at(inner, 0.7)));
        masts.push(vec![up(j), base]);
        masts.push(vec![base + 1, base + 2, base + 3, base + 4, base + 1]);
    }
    lines.push(trace(3, "solar arrays", masts));
    // Three mass simulators beneath the ring, between the tripod's legs.
    let mut hung = Vec::new();
    for s in 0..3 {
        let j = s * n / 3 + n / 6;
        let id = 401 + s as i64;
        nodes.push(node(
            id,
            on_ring(j, RING_RADIUS, -RING_DEPTH - SIMULATOR_DROP),
        ));
        hung.push(vec![lower_id(j), id]);
    }
    lines.push(trace(4, "mass simulators", hung));
    Geometry {
        nodes,
        trace_lines: lines,
        coordinate_systems: Vec::new(),
        notes: Vec::new(),
    }
}

/// The thesis's truth model (four masses in a fixed–free chain) drawn as a shear frame
/// of `storeys` storeys: ground (nodes 100–102), then mass `k` at node `k`, one storey
/// above the other, a column between them. The masses move along x, the direction of
/// the chain: the demo's output `i` is node `i` in +X.
pub fn shear_frame(storeys: usize) -> Geometry {
    let mut nodes = vec![
        node(100, [-0.6, 0.0, 0.0]),
        node(101, [0.6, 0.0, 0.0]),
        node(102, [0.0, 0.0, 0.0]),
    ];
    let mut column = vec![102];
    for k in 1..=storeys {
        nodes.push(node(k as i64, [0.0, 0.0, k as f64]));
        column.push(k as i64);
    }
    Geometry {
        nodes,
        trace_lines: vec![
            trace(1, "ground", vec![vec![100, 102, 101]]),
            trace(2, "storeys", vec![column]),
        ],
        coordinate_systems: Vec::new(),
        notes: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frf_file::ChannelTable;
    use crate::geometry::map_channels;

    #[test]
    fn the_ring_carries_every_output_and_reads_back() {
        for q in [1, 3, 8, 12, 13, 30] {
            let g = dta_like(q);
            g.validate().unwrap();
            let map = map_channels(&g, &ChannelTable::numbered(q, 0).outputs);
            assert_eq!(map.placed.len(), q, "q = {q}");
            assert!(map.not_drawn.is_empty());
            // Each output is on the upper chord (z = 0, on the ring's radius).
            for p in &map.placed {
                let xyz = g.nodes[p.node].xyz;
                assert!(xyz[2].abs() < 1e-12);
                assert!((xyz[0].hypot(xyz[1]) - RING_RADIUS).abs() < 1e-9);
            }
            // Through the CSV writer and reader: the same geometry.
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join("g.csv");
            crate::geometry::csv::write_geometry_csv(&path, &g).unwrap();
            let back = crate::geometry::read_geometry(&path).unwrap();
            assert_eq!(back.nodes, g.nodes);
            assert_eq!(back.segments(), g.segments());
        }
    }

    #[test]
    fn the_tripod_stands_above_the_ring_and_the_simulators_hang_below() {
        let g = dta_like(8);
        let z = |id: i64| g.nodes.iter().find(|n| n.id == id).unwrap().xyz[2];
        assert!(z(300) > 1.0 && z(301) > 1.0);
        assert!(z(401) < -RING_DEPTH);
        assert_eq!(ring_joints(8), 12);
        assert_eq!(ring_joints(13), 24);
    }

    #[test]
    fn the_frame_stacks_its_masses_on_the_ground() {
        let g = shear_frame(4);
        g.validate().unwrap();
        let map = map_channels(&g, &ChannelTable::numbered(3, 0).outputs);
        assert_eq!(map.placed.len(), 3);
        assert_eq!(g.segments().len(), 2 + 4);
    }
}
