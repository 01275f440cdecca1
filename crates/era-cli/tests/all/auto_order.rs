//! `era identify --states auto` and the stabilization diagram (docs/src/design.md §10), on
//! DTA-like sets the tuning never saw (seeds 11 and 12), on the real DaISy subframe, and
//! on bad input.

use crate::common;
use common::assert_success;
use common::{era, expect_input_error, json_of, s, DTA_SETTINGS as THESIS};
use std::path::Path;

/// A DTA-like 8 x 8 set with the recipe; returns the true frequencies.
fn dta_like(dir: &Path, seed: u64, noise: f64) -> (std::path::PathBuf, Vec<f64>) {
    let file = dir.join(format!("dta{seed}.csv"));
    let (seed, noise) = (seed.to_string(), noise.to_string());
    let v = json_of(&[
        "simulate",
        "modal",
        "--outputs",
        "8",
        "--inputs",
        "8",
        "--modes",
        "40",
        "--fmin",
        "0.5",
        "--fmax",
        "14",
        "--damping",
        "0.005..0.02",
        "--lines",
        "801",
        "--df",
        "0.025",
        "--quantity",
        "acceleration",
        "--collocated",
        "--seed",
        &seed,
        "--noise",
        &noise,
        "--out",
        s(&file),
        "--json",
    ]);
    let truth = v["modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["frequency_hz"].as_f64().unwrap())
        .collect();
    (file, truth)
}

/// Physical modes of a model.json, Hz.
fn physical(v: &serde_json::Value) -> Vec<f64> {
    v["modes"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["physical"].as_bool().unwrap())
        .map(|m| m["frequency_hz"].as_f64().unwrap())
        .collect()
}

/// One-to-one matching within `tolerance` (relative), nearest first: (found, spurious).
fn score(truth: &[f64], found: &[f64], tolerance: f64) -> (usize, Vec<f64>) {
    let (pairs, left) = common::match_frequencies(truth, found, tolerance);
    (pairs.len(), left.iter().map(|&j| found[j]).collect())
}

#[test]
fn noise_free_dta_like_set_finds_every_mode_and_writes_the_diagram() {
    let dir = tempfile::tempdir().unwrap();
    let (file, truth) = dta_like(dir.path(), 11, 0.0);
    let out = dir.path().join("out");
    let mut args = vec![
        "identify",
        s(&file),
        "--states",
        "auto",
        "--out",
        s(&out),
        "--json",
    ];
    args.extend(THESIS);
    let v = json_of(&args);
    let (found, spurious) = score(&truth, &physical(&v), 0.005);
    assert_eq!(found, 40, "found {found} of 40");
    assert!(spurious.is_empty(), "spurious physical modes {spurious:?}");
    // Every mode says whether to trust it, with indicators; the scan's data is in the JSON.
    for m in v["modes"].as_array().unwrap() {
        let i = &m["indicators"];
        assert!(i["mpc"].as_f64().unwrap() > 0.9, "{m}");
        assert!(i["emac"].as_f64().is_some() && i["contribution"].as_f64().is_some());
    }
    let st = &v["stabilization"];
    assert_eq!(st["physical_modes"].as_u64(), Some(40));
    assert!(st["poles"].as_array().unwrap().len() > 1000);
    assert!(st["rule"].as_str().unwrap().contains("physical"));
    assert_eq!(v["parameters"]["states"], "auto");
    for name in [
        "stabilization.svg",
        "stabilization.png",
        "singular_values.png",
    ] {
        assert!(out.join(name).is_file(), "{name}");
    }
    let report = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(report.contains("id=\"fig-stabilization\"") && report.contains("<th>CMI</th>"));
    let saved: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("model.json")).unwrap()).unwrap();
    assert_eq!(saved["modes"], v["modes"]);
}

#[test]
fn noisy_dta_like_set_finds_at_least_37_modes_and_no_spurious_one() {
    let dir = tempfile::tempdir().unwrap();
    let (file, truth) = dta_like(dir.path(), 12, 0.05);
    let mut args = vec!["identify", s(&file), "--states", "auto", "--json", "-q"];
    args.extend(THESIS);
    let v = json_of(&args);
    let (found, spurious) = score(&truth, &physical(&v), 0.005);
    assert!(found >= 37, "found {found} of 40");
    assert!(spurious.is_empty(), "spurious physical modes {spurious:?}");
}

#[test]
fn daisy_subframe_auto_finds_the_reference_modes() {
    let v = common::daisy_json(&["--frame", "2048", "--states", "auto", "--json", "-q"]);
    let phys = physical(&v);
    let (hits, _) = common::daisy_hits(&phys);
    assert!(hits >= 12, "{hits} of 14 within 0.5 Hz among {phys:?}");
}

#[test]
fn a_fixed_order_is_judged_against_the_scan_and_flags_suspect_modes() {
    let dir = tempfile::tempdir().unwrap();
    let (file, _) = dta_like(dir.path(), 11, 0.05);
    let mut args = vec![
        "identify",
        s(&file),
        "--states",
        "80",
        "--orders",
        "40..120:8",
        "--preset",
        "thesis",
    ];
    args.extend(THESIS);
    let out = era().args(&args).output().unwrap();
    assert_success(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("stabilization: 11 orders (40..120:8)"),
        "{text}"
    );
    assert!(text.contains("trust") && text.contains("MPC"), "{text}");
    let mut json_args = args.clone();
    json_args.push("--json");
    let v = json_of(&json_args);
    let modes = v["modes"].as_array().unwrap();
    assert_eq!(
        v["states"].as_u64(),
        Some(80),
        "the model is the thesis's at 80 states"
    );
    // At 80 states on noisy data, some modes are computational: they are flagged, with a
    // reason, and negative damping is never called physical.
    let suspect: Vec<&serde_json::Value> = modes
        .iter()
        .filter(|m| !m["physical"].as_bool().unwrap())
        .collect();
    assert!(!suspect.is_empty());
    assert!(suspect
        .iter()
        .all(|m| m["reason"].as_str().is_some_and(|r| !r.is_empty())));
    for m in modes {
        if m["damping_ratio"].as_f64().unwrap() <= 0.0 {
            assert!(!m["physical"].as_bool().unwrap());
        }
    }
}

#[test]
fn bad_orders_and_impossible_scans_exit_2_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("small.csv");
    era()
        .args(["simulate", "truth-model", "--out", s(&file), "-q"])
        .assert()
        .success();
    let f = s(&file);
    for (orders, needle) in [
        ("10..5", "--orders 10..5"),
        ("abc", "--orders abc"),
        ("4..8:0", "--orders 4..8:0"),
        ("0..8", "--orders 0..8"),
        ("4..9000", "--orders 4..9000"),
    ] {
        expect_input_error(
            &["identify", f, "--states", "8", "--orders", orders],
            needle,
        );
    }
    expect_input_error(&["identify", f, "--states", "sideways"], "--states");
    // Twelve lines are too short for any scan.
    let short = dir.path().join("short.csv");
    let mut text = String::from("# quantity: acceleration\nfrequency_hz,H1_1_re,H1_1_im\n");
    for k in 0..12 {
        text.push_str(&format!(
            "{},{},{}\n",
            k as f64,
            1.0 / (1.0 + k as f64),
            0.1
        ));
    }
    std::fs::write(&short, text).unwrap();
    expect_input_error(
        &["identify", s(&short), "--states", "auto"],
        "--states auto",
    );
}
