//! The geometry readers on a real file: the ARTeMIS export shipped in
//! data/pyuff-artemis-geometry (see its PROVENANCE.md for the figures checked by hand).

use crate::common::data_file;
use era_io::frf_file::{Channel, Dof};
use era_io::geometry::{map_channels, read_geometry};

#[test]
fn the_artemis_geometry_is_read_as_the_file_says() {
    let path = data_file("pyuff-artemis-geometry/artemis_geometry_rpbc.uff");
    let g = read_geometry(&path).unwrap();
    assert_eq!(g.nodes.len(), 74);
    assert_eq!(g.trace_lines.len(), 2);
    assert!(g.trace_lines.iter().all(|t| t.name == "Global Trace Lines"));
    let segments = g.segments();
    assert_eq!(segments.len(), 83 + 25);
    assert_eq!(&segments[..3], &[(16, 17), (16, 20), (16, 18)]);
    assert_eq!(segments.last(), Some(&(139, 140)));
    let at = |id: i64| g.nodes.iter().find(|n| n.id == id).unwrap().xyz;
    assert_eq!(at(16), [0.0, 0.0, 0.0]);
    assert_eq!(at(93), [-4.24, 0.875, 0.365]);
    assert_eq!(at(142), [0.0, 0.1, 1.665]);
    assert!(g.coordinate_systems.is_empty());
    // The 2412 elements are skipped, and said so.
    assert_eq!(g.notes, vec!["skipped: 1 × dataset 2412".to_string()]);
    // A channel table over these nodes: two drawn, one (node 5) not in the geometry.
    let ch = |node, direction| Channel {
        dof: Dof { node, direction },
        entity: String::new(),
    };
    let map = map_channels(&g, &[ch(16, 3), ch(5, 1), ch(142, -2)]);
    assert_eq!(map.placed.len(), 2);
    assert_eq!(map.placed[1].direction, [0.0, -1.0, 0.0]);
    assert_eq!(map.not_drawn.len(), 1);
    assert_eq!(map.not_drawn[0].channel, 1);
}

#[test]
fn the_artemis_geometry_survives_our_uff_and_csv_writers() {
    let g = read_geometry(&data_file(
        "pyuff-artemis-geometry/artemis_geometry_rpbc.uff",
    ))
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("g.csv");
    era_io::geometry::csv::write_geometry_csv(&csv, &g).unwrap();
    let back = read_geometry(&csv).unwrap();
    assert_eq!(back.nodes, g.nodes);
    assert_eq!(back.segments(), g.segments());
    let mut uff = Vec::new();
    era_io::uff::write_geometry_records(&mut uff, &g).unwrap();
    let back = era_io::geometry::parse_geometry(&uff, std::path::Path::new("w.uff")).unwrap();
    assert_eq!(back.nodes, g.nodes);
    assert_eq!(back.segments(), g.segments());
}
