//! `--geometry FILE` on identify and refine: read and checked before the run (a bad
//! file exits 2 naming the file and line), written into modes.uff ahead of the shapes
//! (datasets 15 and 82), and the channels no node carries listed in the report.

use crate::common;
use common::{data_file, era, expect_input_error, s, simulated_truth};

#[test]
fn identify_writes_the_geometry_into_modes_uff_and_lists_what_is_not_drawn() {
    let dir = tempfile::tempdir().unwrap();
    let frf = simulated_truth(dir.path());
    // The truth model's outputs are era's numbering, nodes 1..3 +Z: node 3 is left out.
    let geometry = dir.path().join("g.csv");
    std::fs::write(
        &geometry,
        "node,x,y,z\n1,0,0,0\n2,1.5,0,0\n7,2,0,0.25\nfrom,to\n1,2\n2,7\n",
    )
    .unwrap();
    let out = dir.path().join("run");
    let run = era()
        .args([
            "identify",
            s(&frf),
            "--states",
            "8",
            "--preset",
            "thesis",
            "-q",
        ])
        .args(["--geometry", s(&geometry), "--out", s(&out)])
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let uff = std::fs::read_to_string(out.join("modes.uff")).unwrap();
    // Datasets 15 and 82 come first, then the four mode shapes (55).
    let datasets: Vec<&str> = uff
        .lines()
        .collect::<Vec<_>>()
        .windows(2)
        .filter(|w| w[0].trim() == "-1" && !w[1].trim().is_empty() && w[1].trim() != "-1")
        .map(|w| w[1].trim())
        .collect();
    assert_eq!(datasets, ["15", "82", "55", "55", "55", "55"]);
    assert!(uff.contains(
        "         7         0         0         0  2.00000e+00  0.00000e+00  2.50000e-01"
    ));
    // era reads its own output back as a geometry.
    let back = era_io::geometry::read_geometry(&out.join("modes.uff")).unwrap();
    assert_eq!(back.nodes.len(), 3);
    assert_eq!(back.segments(), [(1, 2), (2, 7)]);
    let report = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(
        report.contains("3 nodes, 2 segments in 1 trace lines"),
        "summary"
    );
    assert!(report.contains("2 of 3 output channels on its nodes"));
    assert!(report.contains("output 3 (node 3 +Z): node 3 is not in the geometry"));
    // Refine keeps it too.
    let refined = dir.path().join("refined");
    era()
        .args([
            "refine",
            s(&out.join("model.json")),
            s(&frf),
            "-q",
            "--no-figures",
        ])
        .args([
            "--geometry",
            s(&data_file(
                "pyuff-artemis-geometry/artemis_geometry_rpbc.uff",
            )),
        ])
        .args(["--out", s(&refined)])
        .assert()
        .success();
    let uff = std::fs::read_to_string(refined.join("modes.uff")).unwrap();
    assert_eq!(uff.matches("Global Trace Lines").count(), 2);
    assert_eq!(
        era_io::geometry::read_geometry(&refined.join("modes.uff"))
            .unwrap()
            .nodes
            .len(),
        74
    );
}

#[test]
fn a_bad_geometry_exits_2_naming_the_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let frf = simulated_truth(dir.path());
    for (name, text, needle) in [
        ("dup.csv", "node,x,y,z\n1,0,0,0\n1,1,0,0\n", "dup.csv: node 1 is defined twice (lines 2 and 3)"),
        ("nan.csv", "node,x,y,z\n1,0,0,0\n2,NaN,0,0\n", "nan.csv: node 2 (line 3): coordinate x is NaN"),
        ("miss.csv", "node,x,y,z\n1,0,0,0\nfrom,to\n1,9\n", "miss.csv: trace line 1 (line 4) names node 9"),
        (
            "bad.uff",
            "    -1\n    15\n         1         0         0         0  0.00000E+00  zero         0.00000E+00\n    -1\n",
            "bad.uff: line 3: dataset 15 node (y), columns 54-66: expected a real number",
        ),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        expect_input_error(&["identify", s(&frf), "--states", "8", "--geometry", s(&path)], needle);
    }
    // Nothing was written: the geometry is checked before the run.
    let out = dir.path().join("never");
    expect_input_error(
        &[
            "identify",
            s(&frf),
            "--geometry",
            s(&dir.path().join("dup.csv")),
            "--out",
            s(&out),
        ],
        "node 1 is defined twice",
    );
    assert!(!out.join("model.json").exists());
}
