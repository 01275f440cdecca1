//! The shapes of a run drawn for a test report: the simulated sets' own geometries
//! (the DTA-like ring of `era simulate modal`, the demo's shear frame), each mode in
//! three views (`shapes/mode_NN`), the AutoMAC and complexity figures, and
//! `--geometry` on `oma` and `plot`.

use crate::common;
use common::{era, expect_input_error, json_of, s};
use std::path::Path;

/// `era simulate modal` of `q` outputs into `dir/NAME.csv`: the FRF file and the
/// geometry written beside it.
fn simulated(dir: &Path, name: &str, q: usize) -> (std::path::PathBuf, std::path::PathBuf) {
    let frf = dir.join(format!("{name}.csv"));
    let q = q.to_string();
    let v = json_of(&[
        "simulate",
        "modal",
        "--outputs",
        &q,
        "--inputs",
        "2",
        "--modes",
        "6",
        "--seed",
        "5",
        "--out",
        s(&frf),
        "--json",
        "-q",
    ]);
    let geometry = dir.join(format!("{name}_geometry.csv"));
    assert_eq!(v["geometry"].as_str().unwrap(), s(&geometry));
    (frf, geometry)
}

#[test]
fn simulate_modal_writes_a_ring_geometry_carrying_every_output() {
    let dir = tempfile::tempdir().unwrap();
    for q in [3, 8, 20] {
        let (_, geometry) = simulated(dir.path(), &format!("set{q}"), q);
        let g = era_io::geometry::read_geometry(&geometry).unwrap();
        let numbered = era_io::frf_file::ChannelTable::numbered(q, 0);
        let map = era_io::geometry::map_channels(&g, &numbered.outputs);
        assert_eq!(map.placed.len(), q, "every output on a node");
        // More nodes than channels: the tripod, masts and simulators carry none.
        assert!(g.nodes.len() > 2 * q);
        let text = std::fs::read_to_string(&geometry).unwrap();
        assert!(text.contains("not a finite-element model"));
    }
}

/// The `MPC 0.123` of each panel title of complexity.svg, in order.
fn panel_mpcs(svg: &str) -> Vec<String> {
    svg.match_indices(", MPC ")
        .map(|(k, _)| svg[k + 6..k + 11].to_string())
        .collect()
}

#[test]
fn identify_on_the_ring_draws_three_views_automac_and_complexity() {
    let dir = tempfile::tempdir().unwrap();
    let (frf, geometry) = simulated(dir.path(), "dta", 6);
    let out = dir.path().join("run");
    era()
        .args([
            "identify",
            s(&frf),
            "--states",
            "12",
            "--preset",
            "thesis",
            "-q",
        ])
        .args(["--geometry", s(&geometry), "--out", s(&out)])
        .assert()
        .success();
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("model.json")).unwrap()).unwrap();
    let modes = model["modes"].as_array().unwrap();
    assert!(!modes.is_empty());
    for k in 1..=modes.len() {
        let svg = std::fs::read_to_string(out.join(format!("shapes/mode_{k:02}.svg"))).unwrap();
        for panel in ["front (x–z)", "side (y–z)", "top (x–y)"] {
            assert!(svg.contains(panel), "mode {k}: no {panel}");
        }
        assert!(out.join(format!("shapes/mode_{k:02}.png")).is_file());
    }
    assert!(!out
        .join(format!("shapes/mode_{:02}.svg", modes.len() + 1))
        .exists());
    // The complexity panels are the physical modes', their MPC the indicator's.
    let physical: Vec<&serde_json::Value> = modes
        .iter()
        .filter(|m| m["physical"].as_bool() == Some(true))
        .collect();
    let shown: Vec<&serde_json::Value> = if physical.is_empty() {
        modes.iter().collect()
    } else {
        physical
    };
    let complexity = std::fs::read_to_string(out.join("complexity.svg")).unwrap();
    let expected: Vec<String> = shown
        .iter()
        .map(|m| format!("{:.3}", m["indicators"]["mpc"].as_f64().unwrap()))
        .collect();
    assert_eq!(panel_mpcs(&complexity), expected);
    assert!(out.join("complexity.png").is_file());
    if shown.len() >= 2 {
        assert!(out.join("automac.svg").is_file() && out.join("automac.png").is_file());
    }
    let report = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(report.contains("id=\"fig-complexity\""));
    assert!(report.contains("data-shape-view=\"three\""));
    // The pictures are files beside the report, not inlined in it.
    assert!(!report.contains("shapes/mode_01.svg\""));
}

#[test]
fn the_demo_draws_its_chain_as_a_shear_frame() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    era()
        .args(["demo", "-q", "--out", s(&out)])
        .assert()
        .success();
    for run in ["no_noise", "noisy"] {
        let report = std::fs::read_to_string(out.join(run).join("report.html")).unwrap();
        assert!(
            report.contains("<canvas id=\"shape-canvas\""),
            "{run}: no viewer"
        );
        assert!(report.contains("4-storey shear frame"));
        assert!(report.contains("Every output channel is drawn."));
        assert!(out.join(run).join("shapes/mode_01.png").is_file());
        assert!(out.join(run).join("automac.svg").is_file());
        // modes.uff keeps era's numbering: no geometry datasets in it.
        let uff = std::fs::read_to_string(out.join(run).join("modes.uff")).unwrap();
        assert!(!uff.contains("\n    15\n") && !uff.contains("\n    82\n"));
    }
}

/// A short simulated shaker test (8 accelerometers in columns 3-10).
fn shaker(dir: &Path) -> std::path::PathBuf {
    let file = dir.join("shaker.csv");
    era()
        .args([
            "simulate",
            "shaker",
            "--seed",
            "3",
            "--duration",
            "200",
            "-q",
        ])
        .args(["--out", s(&file)])
        .assert()
        .success();
    file
}

#[test]
fn oma_takes_a_geometry_and_refuses_a_bad_one_before_reading() {
    let dir = tempfile::tempdir().unwrap();
    let file = shaker(dir.path());
    let geometry = dir.path().join("ring.csv");
    std::fs::write(
        &geometry,
        era_io::geometry::csv::geometry_csv_text(&era_io::geometry::layouts::dta_like(8), &[]),
    )
    .unwrap();
    let out = dir.path().join("run");
    era()
        .args(["oma", s(&file), "--outputs", "3-10", "-q"])
        .args(["--geometry", s(&geometry), "--out", s(&out)])
        .assert()
        .success();
    let report = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(report.contains("<canvas id=\"shape-canvas\""));
    assert!(report.contains("8 of 8 output channels on its nodes"));
    assert!(out.join("shapes/mode_01.svg").is_file());
    assert!(out.join("complexity.svg").is_file());
    // The geometry goes into modes.uff ahead of the shapes.
    let back = era_io::geometry::read_geometry(&out.join("modes.uff")).unwrap();
    assert_eq!(
        back.nodes.len(),
        era_io::geometry::layouts::dta_like(8).nodes.len()
    );

    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, "node,x,y,z\n1,0,0,0\nfrom,to\n1,9\n").unwrap();
    let never = dir.path().join("never");
    expect_input_error(
        &[
            "oma",
            s(&file),
            "--outputs",
            "3-10",
            "--geometry",
            s(&bad),
            "--out",
            s(&never),
        ],
        "bad.csv: trace line 1 (line 4) names node 9",
    );
    assert!(!never.join("model.json").exists());
}

#[test]
fn plot_draws_the_models_modes_on_a_geometry() {
    let dir = tempfile::tempdir().unwrap();
    let (frf, geometry) = simulated(dir.path(), "dta", 4);
    let run = dir.path().join("run");
    era()
        .args(["identify", s(&frf), "--states", "8", "--no-figures", "-q"])
        .args(["--out", s(&run)])
        .assert()
        .success();
    let out = dir.path().join("plots");
    let model = run.join("model.json");
    let v = json_of(&[
        "plot",
        s(&frf),
        "--model",
        s(&model),
        "--geometry",
        s(&geometry),
        "--out",
        s(&out),
        "--json",
        "-q",
    ]);
    let drawn = v["shapes_drawn"].as_u64().unwrap() as usize;
    let modes: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    assert_eq!(drawn, modes["modes"].as_array().unwrap().len());
    assert!(drawn >= 1);
    let svg = std::fs::read_to_string(out.join("shapes/mode_01.svg")).unwrap();
    assert!(svg.contains("top (x–y)") && svg.contains("Mode 1: "));
    // A bad geometry: exit 2 naming the file and line, before anything is written.
    let bad = dir.path().join("nan.csv");
    std::fs::write(&bad, "node,x,y,z\n1,0,0,0\n2,NaN,0,0\n").unwrap();
    let never = dir.path().join("never");
    expect_input_error(
        &[
            "plot",
            s(&frf),
            "--model",
            s(&model),
            "--geometry",
            s(&bad),
            "--out",
            s(&never),
        ],
        "nan.csv: node 2 (line 3): coordinate x is NaN",
    );
    assert!(!never.exists());
    expect_input_error(
        &[
            "plot",
            s(&frf),
            "--geometry",
            s(&geometry),
            "--out",
            s(&never),
        ],
        "--geometry draws the model's mode shapes: give --model",
    );
}
