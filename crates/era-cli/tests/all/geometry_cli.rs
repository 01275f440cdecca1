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

/// The JSON of the report's shape viewer.
fn viewer_data(report: &str) -> serde_json::Value {
    let start = report
        .find("<script type=\"application/json\" id=\"era-shapes\">")
        .expect("the viewer's data in report.html");
    let body = &report[start..];
    let body = &body[body.find('>').unwrap() + 1..body.find("</script>").unwrap()];
    serde_json::from_str(body).expect("the viewer's data is JSON")
}

#[test]
fn the_report_animates_each_mode_on_the_geometry_or_says_there_is_none() {
    let dir = tempfile::tempdir().unwrap();
    let frf = simulated_truth(dir.path());
    // Outputs on nodes 1..3 +Z; node 3 is not in the geometry, node 7 has no channel.
    let geometry = dir.path().join("g.csv");
    std::fs::write(
        &geometry,
        "node,x,y,z\n1,0,0,0\n2,1.5,0,0\n7,2,0,0.25\nfrom,to\n1,2\n2,7\n",
    )
    .unwrap();
    let run = |out: &std::path::Path, with_geometry: bool| {
        let mut cmd = era();
        cmd.args([
            "identify",
            s(&frf),
            "--states",
            "8",
            "--preset",
            "thesis",
            "-q",
        ]);
        if with_geometry {
            cmd.args(["--geometry", s(&geometry)]);
        }
        cmd.args(["--out", s(out)]).assert().success();
        std::fs::read_to_string(out.join("report.html")).unwrap()
    };
    let report = run(&dir.path().join("with"), true);
    let data = viewer_data(&report);
    assert_eq!(data["nodes"].as_array().unwrap().len(), 3);
    assert_eq!(data["segments"], serde_json::json!([[0, 1], [1, 2]]));
    assert_eq!(data["measured"], serde_json::json!([1, 1, 0]));
    let modes = data["modes"].as_array().unwrap();
    // One entry per mode of the table: the truth model's four.
    assert_eq!(modes.len(), 4);
    for (k, m) in modes.iter().enumerate() {
        assert!(m["label"]
            .as_str()
            .unwrap()
            .starts_with(&format!("Mode {}: ", k + 1)));
        // Nodes 1 and 2 move, along z only (their channels are +Z); the largest
        // displacement is 1.
        let u = m["u"].as_array().unwrap();
        assert_eq!(u.len(), 2);
        let mut largest: f64 = 0.0;
        for (row, node) in u.iter().zip([0, 1]) {
            let r: Vec<f64> = row
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            assert_eq!(r[0], node as f64);
            assert_eq!(&r[1..5], &[0.0; 4], "x and y stay still: {r:?}");
            largest = largest.max(r[5].hypot(r[6]));
        }
        assert!((largest - 1.0).abs() < 1e-3, "mode {k}: largest {largest}");
    }
    assert!(report.contains("<canvas id=\"shape-canvas\""));
    assert!(
        report.contains("eraShowPhase"),
        "the viewer's script is inlined"
    );
    assert!(report.contains("<option value=\"3\">Mode 4: "));
    assert!(report.contains("<li>output 3 (node 3 +Z): node 3 is not in the geometry</li>"));
    // No external resource of any kind.
    for needle in [
        "src=\"http",
        "href=\"http",
        "import(",
        "fetch(",
        "XMLHttpRequest",
    ] {
        assert!(!report.contains(needle), "{needle} in report.html");
    }

    // Without a geometry: one line says so, and nothing else of the viewer is there.
    let plain = run(&dir.path().join("without"), false);
    assert_eq!(plain.matches("id=\"shapes-none\"").count(), 1);
    assert!(plain.contains("No test geometry was given"));
    // (The page's one other script is the pair picker's.)
    for needle in ["eraShowPhase", "<canvas", "id=\"shapes\""] {
        assert!(!plain.contains(needle), "{needle} without a geometry");
    }
}
