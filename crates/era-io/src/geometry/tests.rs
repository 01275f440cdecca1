use super::*;
use crate::frf_file::{Channel, Dof};
use std::path::Path;

fn uff(text: &str) -> Result<Geometry, String> {
    parse_geometry(text.as_bytes(), Path::new("g.uff")).map_err(|e| e.to_string())
}

fn close(a: [f64; 3], b: [f64; 3]) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9)
}

/// A square of four nodes (dataset 15) and its outline as one trace line with a pen lift.
const SQUARE: &str = "    -1
    15
         1         0         0         0  0.00000E+00  0.00000E+00  0.00000E+00
         2         0         0         0  1.00000E+00  0.00000E+00  0.00000E+00
         3         0         0         0  1.00000E+00  2.00000E+00  0.00000E+00
         4         0         0         0  0.00000E+00  2.00000E+00 -5.00000E-01
    -1
    -1
    82
         1         7         0
outline
         1         2         3         4         0         4         1
    -1
";

#[test]
fn nodes_and_a_trace_line_with_a_pen_lift_are_read() {
    let g = uff(SQUARE).unwrap();
    assert_eq!(g.nodes.len(), 4);
    assert!(close(g.nodes[3].xyz, [0.0, 2.0, -0.5]));
    assert_eq!(g.trace_lines.len(), 1);
    assert_eq!(g.trace_lines[0].name, "outline");
    assert_eq!(g.trace_lines[0].strokes, vec![vec![1, 2, 3, 4], vec![4, 1]]);
    assert_eq!(g.segments(), vec![(1, 2), (2, 3), (3, 4), (4, 1)]);
    assert_eq!(g.summary(), "4 nodes, 4 segments in 1 trace lines");
    // Zeros past the count (Simcenter Testlab pads the last line) are pen lifts: read.
    let padded = SQUARE.replace(
        "         0         4         1\n",
        "         0         4         1         0\n",
    );
    assert_eq!(uff(&padded).unwrap().segments(), g.segments());
}

#[test]
fn dataset_2411_with_d_exponents_and_free_format_lines_are_read() {
    let text = "    -1
  2411
         7         1         1        11
   2.0940900802612305D+01   1.3069399833679199D+01  -3.9683275171308864D+01
 8 0 0 0
 1.5 -2.5 3.5
    -1
    -1
    15
 9 0 0 0 1.0e0 2.0 3.0
    -1
";
    let g = uff(text).unwrap();
    assert_eq!(g.nodes.len(), 3);
    assert!(close(
        g.nodes[0].xyz,
        [20.940900802612305, 13.0693998336792, -39.683275171308864]
    ));
    // 2411 positions are in the part frame: its export system is not applied.
    assert_eq!(g.nodes[0].displacement_system, 1);
    assert!(close(g.nodes[1].xyz, [1.5, -2.5, 3.5]));
    assert!(close(g.nodes[2].xyz, [1.0, 2.0, 3.0]));
    // System 1 is not defined: a note, and its directions are taken as global.
    assert!(g
        .notes
        .iter()
        .any(|n| n.contains("displacement coordinate systems 1")));
}

/// Dataset 18 as Simcenter Testlab writes it: system 1 has its x axis along global −X
/// and its z axis along global −Z (a sensor mounted upside down).
const TESTLAB18: &str = "    -1
    18
         1         0         0         8         1
SYS1
 -2.40000e+00 -9.50000e-01  0.00000e+00 -3.40000e+00 -9.50000e-01 -8.74228e-08
 -3.40000e+00 -9.50000e-01 -1.00000e+00
         2         1         1         8         1
CYL
  1.00000e+00  0.00000e+00  0.00000e+00  2.00000e+00  0.00000e+00  0.00000e+00
  2.00000e+00  0.00000e+00  1.00000e+00
    -1
";

#[test]
fn dataset_18_systems_place_nodes_and_turn_directions() {
    let text = format!(
        "{TESTLAB18}    -1
    15
         1         0         1         8 -2.40000e+00 -9.50000e-01  0.00000e+00
         2         1         0         8  1.00000e+00  2.00000e+00  3.00000e+00
         3         2         2         8  2.00000e+00  9.00000e+01  1.00000e+00
    -1
"
    );
    let g = uff(&text).unwrap();
    let s1 = g.system(1).unwrap();
    assert!(close(s1.origin, [-2.4, -0.95, 0.0]));
    assert!((s1.axes[0][0] + 1.0).abs() < 1e-7 && (s1.axes[1][1] - 1.0).abs() < 1e-7);
    assert!((s1.axes[2][2] + 1.0).abs() < 1e-7);
    // Node 2 at (1, 2, 3) in system 1: origin − 1 X + 2 Y − 3 Z.
    let n2 = g.nodes[1].xyz;
    assert!((n2[0] - (-3.4)).abs() < 1e-6 && (n2[1] - 1.05).abs() < 1e-6);
    assert!((n2[2] - (-3.0)).abs() < 1e-6, "{n2:?}");
    // System 2 is cylindrical, defined in system 1: origin 1 along system 1's x
    // (global −X), its axes those of system 1. Node 3 at r = 2, θ = 90°, z = 1 in it:
    // 2 along system 1's y (global +Y) and 1 along its z (global −Z).
    let n3 = g.nodes[2].xyz;
    assert!(
        close(n3.map(|v| (v * 1e6).round() / 1e6), [-3.4, 1.05, -1.0]),
        "{n3:?}"
    );
    // Channels: node 1 +X is global −X; node 3 +X (radial) points along global +Y;
    // node 2 (global system) +Z is +Z; node 9 is not in the geometry; node 1 +RX is a
    // rotation.
    let ch = |node, direction| Channel {
        dof: Dof { node, direction },
        entity: "NONE".into(),
    };
    let map = map_channels(
        &g,
        &[ch(1, 1), ch(3, 1), ch(2, -3), ch(9, 3), ch(1, 4), ch(2, 0)],
    );
    assert_eq!(map.placed.len(), 3);
    assert!(close(
        map.placed[0].direction.map(f64::round),
        [-1.0, 0.0, 0.0]
    ));
    let radial = map.placed[1].direction;
    assert!((radial[1] - 1.0).abs() < 1e-6, "{radial:?}");
    assert!(close(map.placed[2].direction, [0.0, 0.0, -1.0]));
    let reasons: Vec<(usize, &str)> = map
        .not_drawn
        .iter()
        .map(|u| (u.channel, u.reason.as_str()))
        .collect();
    assert_eq!(reasons.len(), 3);
    assert_eq!(reasons[0], (3, "node 9 is not in the geometry"));
    assert!(reasons[1].1.contains("+RX is not a translation"));
    assert!(reasons[2].1.contains("scalar"));
}

#[test]
fn dataset_2420_rows_are_the_axes_and_the_fourth_the_origin() {
    let text = "    -1
  2420
         1
Part1
         5         0         2
CS5
   0.0000000000000000D+00   1.0000000000000000D+00   0.0000000000000000D+00
  -1.0000000000000000D+00   0.0000000000000000D+00   0.0000000000000000D+00
   0.0000000000000000D+00   0.0000000000000000D+00   1.0000000000000000D+00
   1.0000000000000000D+01   0.0000000000000000D+00   0.0000000000000000D+00
    -1
    -1
    15
         1         5         5         0  1.00000E+00  0.00000E+00  0.00000E+00
    -1
";
    let g = uff(text).unwrap();
    // x of system 5 is global +Y: local (1, 0, 0) is (10, 1, 0).
    assert!(close(g.nodes[0].xyz, [10.0, 1.0, 0.0]));
    let c = Channel {
        dof: Dof {
            node: 1,
            direction: 2,
        },
        entity: String::new(),
    };
    let map = map_channels(&g, &[c]);
    assert!(close(map.placed[0].direction, [-1.0, 0.0, 0.0]));
}

#[test]
fn bad_geometry_is_refused_naming_the_line() {
    let dup = SQUARE.replace(
        "         2         0         0         0  1",
        "         1         0         0         0  1",
    );
    let e = uff(&dup).unwrap_err();
    assert!(e.contains("node 1 is defined twice (lines 3 and 4)"), "{e}");
    let missing = SQUARE.replace(
        "         0         4         1",
        "         0         4        77",
    );
    let e = uff(&missing).unwrap_err();
    assert!(e.contains("trace line 1 (line 10) names node 77"), "{e}");
    let nan = SQUARE.replace("2.00000E+00 -5.00000E-01", "2.00000E+00          NaN");
    let e = uff(&nan).unwrap_err();
    assert!(e.contains("node 4 (line 6): coordinate z is NaN"), "{e}");
    let field = SQUARE.replace("1.00000E+00  2.00000E+00", "1.0000xE+00  2.00000E+00");
    let e = uff(&field).unwrap_err();
    assert!(
        e.contains("g.uff: line 5: dataset 15 node (x), columns 41-53: expected a real number"),
        "{e}"
    );
    let count = SQUARE.replace(
        "         1         7         0",
        "         1 900000000         0",
    );
    let e = uff(&count).unwrap_err();
    assert!(
        e.contains("announces 900000000 nodes; the record holds at most 8"),
        "{e}"
    );
    let short = SQUARE.replace(
        "         1         7         0",
        "         1         9         0",
    );
    let e = uff(&short).unwrap_err();
    assert!(
        e.contains("trace line 1 announces 9 nodes; the record holds at most 8"),
        "{e}"
    );
    let few = SQUARE.replace(
        "         1         7         0",
        "         1         6         0",
    );
    let e = uff(&few).unwrap_err();
    assert!(
        e.contains("line 12: dataset 82: trace line 1 has more nodes than the 6 it announces"),
        "{e}"
    );
    let undefined = SQUARE.replace(
        "         3         0         0         0",
        "         3         4         0         0",
    );
    let e = uff(&undefined).unwrap_err();
    assert!(
        e.contains("line 5: node 3: its definition coordinate system 4 is not defined"),
        "{e}"
    );
    let open = SQUARE.trim_end().trim_end_matches("-1");
    let e = uff(open).unwrap_err();
    assert!(
        e.contains("line 8: the record of dataset 82 has no closing -1"),
        "{e}"
    );
    let e = uff("    -1\n    82\n         1         2         0\nx\n 1 2\n    -1\n").unwrap_err();
    assert!(e.contains("no nodes"), "{e}");
}

#[test]
fn cyclic_and_degenerate_systems_are_refused() {
    let cyclic = TESTLAB18.replacen(
        "         1         0         0         8         1",
        "         1         0         2         8         1",
        1,
    );
    let text = format!(
        "{cyclic}{}",
        &SQUARE[..SQUARE.find("    -1\n    82").unwrap()]
    );
    let e = uff(&text).unwrap_err();
    assert!(e.contains("refers to itself through its references"), "{e}");
    let flat = TESTLAB18.replace(
        " -3.40000e+00 -9.50000e-01 -1.00000e+00",
        " -4.40000e+00 -9.50000e-01  0.00000e+00",
    );
    let text = format!(
        "{flat}{}",
        &SQUARE[..SQUARE.find("    -1\n    82").unwrap()]
    );
    let e = uff(&text).unwrap_err();
    assert!(e.contains("line 3: dataset 18: coordinate system 1: its origin, +x point and +xz point do not span a plane"), "{e}");
}

#[test]
fn other_datasets_and_binary_records_are_skipped() {
    let mut bytes = b"    -1\n    58b     1     2          11          16     0     0           0           0\n".to_vec();
    for k in 0..11 {
        bytes.extend_from_slice(format!("header {k}\n").as_bytes());
    }
    bytes.extend_from_slice(&[0xff; 16]);
    bytes.extend_from_slice(b"\n    -1\n    -1\n   164\nunits\n    -1\n");
    bytes.extend_from_slice(SQUARE.as_bytes());
    let g = parse_geometry(&bytes, Path::new("g.uff")).unwrap();
    assert_eq!(g.nodes.len(), 4);
    assert!(
        g.notes
            .iter()
            .any(|n| n == "skipped: 1 × dataset 58; 1 × dataset 164"),
        "{:?}",
        g.notes
    );
}

#[test]
fn the_uff_writer_round_trips_nodes_lines_and_systems() {
    let text = format!(
        "{TESTLAB18}    -1
    15
         1         0         1         8 -2.40000e+00 -9.50000e-01  0.00000e+00
         2         1         2         8  1.00000e+00  2.00000e+00  3.00000e+00
    -1
"
    );
    let mut g = uff(&text).unwrap();
    // A stroke of 600 nodes back and forth between nodes 1 and 2: split at 250 entries.
    let long: Vec<i64> = (0..600).map(|k| 1 + k % 2).collect();
    g.trace_lines.push(TraceLine {
        id: 4,
        name: String::new(),
        strokes: vec![long, vec![2, 1]],
    });
    let mut out = Vec::new();
    crate::uff::write_geometry_records(&mut out, &g).unwrap();
    let again = parse_geometry(&out, Path::new("w.uff")).unwrap();
    assert_eq!(again.nodes.len(), 2);
    for (a, b) in g.nodes.iter().zip(&again.nodes) {
        assert_eq!(a.id, b.id);
        assert_eq!(a.displacement_system, b.displacement_system);
        assert!(a.xyz.iter().zip(b.xyz).all(|(x, y)| (x - y).abs() < 1e-4));
    }
    assert_eq!(again.segments(), g.segments());
    assert!(again.trace_lines.len() >= 3);
    let text = String::from_utf8(out).unwrap();
    for block in text.split("    82").skip(1) {
        let count: usize = block.lines().nth(1).unwrap()[10..20]
            .trim()
            .parse()
            .unwrap();
        assert!(count <= 250, "{count}");
    }
    for (a, b) in g.coordinate_systems.iter().zip(&again.coordinate_systems) {
        assert_eq!((a.id, a.kind), (b.id, b.kind));
        let d = a.axes.iter().flatten().zip(b.axes.iter().flatten());
        assert!(d.map(|(x, y)| (x - y).abs()).fold(0.0, f64::max) < 1e-4);
    }
}

#[test]
fn the_csv_is_read_and_its_errors_name_line_and_column() {
    let csv = |t: &str| parse_geometry(t.as_bytes(), Path::new("g.csv")).map_err(|e| e.to_string());
    let good =
        "# a triangle\nfrom,to\n1,2\n2,3\n\nNode, X, Y, Z\n1,0,0,0\n2,1,0,0\n3, 0.5, 0.8, 1e-1\n";
    let g = csv(good).unwrap();
    assert_eq!(g.nodes.len(), 3);
    assert!(close(g.nodes[2].xyz, [0.5, 0.8, 0.1]));
    assert_eq!(g.segments(), vec![(1, 2), (2, 3)]);
    let e = csv("node,x,y,z\n1,0,0,0\n2,0,zero,0\n").unwrap_err();
    assert_eq!(e, "g.csv: line 3, column y: 'zero' is not a number");
    let e = csv("node,x,y,z\n1,0,0,0\n1,0,0,1\n").unwrap_err();
    assert!(e.contains("node 1 is defined twice (lines 2 and 3)"), "{e}");
    let e = csv("node,x,y,z\n1,0,0,0\n2,0,inf,1\n").unwrap_err();
    assert!(e.contains("node 2 (line 3): coordinate y is inf"), "{e}");
    let e = csv("node,x,y,z\n1,0,0,0\nfrom,to\n1,5\n").unwrap_err();
    assert!(e.contains("trace line 1 (line 4) names node 5"), "{e}");
    let e = csv("1,0,0,0\n").unwrap_err();
    assert!(
        e.contains("line 1: expected the header 'node,x,y,z'"),
        "{e}"
    );
    let e = csv("from,to\n1,2\n").unwrap_err();
    assert!(e.contains("no 'node,x,y,z' section"), "{e}");
    let e = csv("node,x,y,z\n1,0,0\n").unwrap_err();
    assert!(e.contains("line 2: a node row has 4 cells"), "{e}");
    let e = csv("   \n").unwrap_err();
    assert!(e.contains("empty"), "{e}");
}

#[test]
fn the_csv_writer_round_trips() {
    let g = uff(SQUARE).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.csv");
    csv::write_geometry_csv(&path, &g).unwrap();
    let again = read_geometry(&path).unwrap();
    assert_eq!(again.nodes, g.nodes);
    assert_eq!(again.segments(), g.segments());
}

#[test]
fn a_geometry_round_trips_through_json() {
    let g = uff(&format!("{TESTLAB18}{SQUARE}")).unwrap();
    let text = serde_json::to_string(&g).unwrap();
    assert!(text.contains("\"kind\":\"cylindrical\""), "{text}");
    let back: Geometry = serde_json::from_str(&text).unwrap();
    assert_eq!(back, g);
}

#[test]
fn validate_refuses_what_the_readers_refuse() {
    let mut g = uff(SQUARE).unwrap();
    assert!(g.validate().is_ok());
    g.nodes[0].xyz[1] = f64::NAN;
    assert_eq!(
        g.validate().unwrap_err(),
        "node 1: coordinate y is NaN (not a finite number)"
    );
    assert_eq!(
        Geometry::default().validate().unwrap_err(),
        "the geometry has no nodes"
    );
}

mod no_panic {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]
        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
            let _ = parse_geometry(&bytes, Path::new("p"));
            let mut uff = b"    -1\n".to_vec();
            uff.extend_from_slice(&bytes);
            let _ = parse_geometry(&uff, Path::new("p"));
        }

        #[test]
        fn edited_files_never_panic(at in 0usize..2000, byte in any::<u8>(), cut in 0usize..2000) {
            let base = format!("{TESTLAB18}{SQUARE}");
            let mut bytes = base.into_bytes();
            let at = at % bytes.len();
            bytes[at] = byte;
            let _ = parse_geometry(&bytes, Path::new("p"));
            bytes.truncate(cut % bytes.len());
            let _ = parse_geometry(&bytes, Path::new("p"));
        }
    }
}
