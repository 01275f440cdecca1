//! `era identify --refine` and `era refine MODEL.json FRF_FILE` (issue 14): the refined
//! model is the model of every output, its modes carry standard deviations, and bad
//! input exits 2 naming the flag or file.

use crate::common;
use common::assert_success;
use common::hostile::run_capped;
use common::{era, json_of, s, DTA_SETTINGS as THESIS, TRUTH_SETTINGS};
use std::path::{Path, PathBuf};

/// A seeded modal set (acceleration): returns the file and the true (frequency, damping).
fn modal_set(dir: &Path, name: &str, extra: &[&str]) -> (PathBuf, Vec<(f64, f64)>) {
    let file = dir.join(name);
    let mut args = vec!["simulate", "modal", "--out", s(&file), "--json"];
    args.extend_from_slice(extra);
    let v = json_of(&args);
    (file, crate::common::modes_of(&v, false))
}

const DTA_LIKE: [&str; 16] = [
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
    "--lines",
    "801",
    "--df",
    "0.025",
    "--collocated",
    "--quiet",
];

/// The nearest refined mode to each true one: (relative frequency error, relative
/// damping error).
fn errors(v: &serde_json::Value, truth: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let modes: Vec<(f64, f64, bool)> = v["modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            (
                m["frequency_hz"].as_f64().unwrap(),
                m["damping_ratio"].as_f64().unwrap(),
                m["physical"].as_bool().unwrap_or(true),
            )
        })
        .collect();
    truth
        .iter()
        .map(|&(f, z)| {
            let m = modes
                .iter()
                .filter(|m| m.2)
                .min_by(|a, b| (a.0 - f).abs().total_cmp(&(b.0 - f).abs()))
                .unwrap();
            ((m.0 - f).abs() / f, (m.1 - z).abs() / z)
        })
        .collect()
}

#[test]
fn refined_auto_model_of_a_noise_free_dta_like_set_is_the_data() {
    let dir = tempfile::tempdir().unwrap();
    let mut sim = DTA_LIKE.to_vec();
    sim.extend(["--seed", "13"]);
    let (file, truth) = modal_set(dir.path(), "dta13.csv", &sim);
    let out = dir.path().join("out");
    let mut args = vec![
        "identify",
        s(&file),
        "--states",
        "auto",
        "--refine",
        "--time-domain",
        "continuous",
        "--out",
        s(&out),
        "--json",
        "-q",
    ];
    args.extend(THESIS);
    let v = json_of(&args);
    let physical = v["modes"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["physical"] == true)
        .count();
    assert_eq!(physical, 40, "every mode found, none spurious");
    for (k, (df, dz)) in errors(&v, &truth).into_iter().enumerate() {
        assert!(df < 1e-9 && dz < 1e-7, "mode {k}: {df:e} {dz:e}");
    }
    let r = &v["refinement"];
    assert_eq!(r["converged"], true, "{r}");
    assert!(r["fit_after"].as_f64().unwrap() < 1e-8, "{r}");
    assert!(r["cost_after"].as_f64().unwrap() < r["cost_before"].as_f64().unwrap());
    assert!(r["iterations"].as_u64().is_some() && r["fit_before"].as_f64().is_some());
    // The fit of the written model, evaluated from its A, B, C, D.
    let fit: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("fit.json")).unwrap()).unwrap();
    for p in fit["pairs"].as_array().unwrap() {
        assert!(p["relative_error"].as_f64().unwrap() < 1e-8, "{p}");
    }
    assert_eq!(v["time_domain"], "continuous");
    // Two states per rank-one term of each residue, and the lower residual of velocity
    // data: one integrator per input, the model's real poles at 0.
    assert!(v["states"].as_u64().unwrap() >= 80 + 8, "{}", v["states"]);
    assert_eq!(v["real_poles"].as_array().unwrap().len(), 8);
    for m in v["modes"].as_array().unwrap() {
        assert!(m["frequency_std_hz"].as_f64().is_some(), "{m}");
        assert!(m["damping_ratio_std"].as_f64().is_some(), "{m}");
    }
    let report = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(report.contains("id=\"refinement\"") && report.contains(" ± "));
    for f in ["model.mat", "modes.uff", "model_frf.uff", "grid.svg"] {
        assert!(out.join(f).is_file(), "{f}");
    }

    // era refine on the written model: the same fit again, at once.
    let again = json_of(&[
        "refine",
        s(&out.join("model.json")),
        s(&file),
        "--json",
        "-q",
    ]);
    assert!(again["refinement"]["fit_after"].as_f64().unwrap() < 1e-8);
    assert_eq!(again["modes"].as_array().unwrap().len(), 40);
}

#[test]
fn refined_truth_model_is_discrete_and_keeps_table_5_2() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("truth.csv");
    era()
        .args(["simulate", "truth-model", "--out", s(&file), "-q"])
        .assert()
        .success();
    let out = era()
        .args(["identify", s(&file), "--states", "8"])
        .args(TRUTH_SETTINGS)
        .args([
            "--refine",
            "--time-domain",
            "discrete",
            "--residuals",
            "none",
            "--reciprocal",
            "--max-iterations",
            "50",
            "--json",
        ])
        .output()
        .unwrap();
    assert_success(&out);
    let human = String::from_utf8_lossy(&out.stderr);
    assert!(human.contains("refinement (z-domain model"), "{human}");
    assert!(human.contains("± (Hz)"), "the mode table shows ±: {human}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["time_domain"], "discrete");
    assert_eq!(v["refinement"]["model"], "z");
    assert_eq!(v["parameters"]["residuals"], "none");
    assert_eq!(v["parameters"]["reciprocal"], true);
    // Reciprocal residues: the model's FRF matrix is symmetric, so B = Cᵀ up to the
    // basis; check it through the modes' shapes against participations instead.
    let truth = [1748.64, 5031.80, 7709.75, 9458.39];
    let modes = v["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 4);
    for (m, t) in modes.iter().zip(truth) {
        let f = m["frequency_hz"].as_f64().unwrap();
        assert!((f - t).abs() < 0.01, "{f} vs {t}");
        assert!(m["damping_ratio"].as_f64().unwrap() > 0.0, "stable");
    }
    assert!(v["refinement"]["fit_after"].as_f64().unwrap() < 1e-8);
}

#[test]
fn modes_the_start_missed_are_added_and_said() {
    // The noisy truth model from four states: ERA has two of the four modes.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("truth.csv");
    era()
        .args([
            "simulate",
            "truth-model",
            "--noise",
            "0.15",
            "--seed",
            "3",
            "--out",
            s(&file),
            "-q",
        ])
        .assert()
        .success();
    let run = |extra: &[&str]| {
        let mut a = vec![
            "identify",
            s(&file),
            "--states",
            "4",
            "--refine",
            "--time-domain",
            "discrete",
            "--json",
        ];
        a.extend_from_slice(extra);
        let out = era().args(&a).output().unwrap();
        assert_success(&out);
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        (v, String::from_utf8_lossy(&out.stderr).into_owned())
    };
    let (v, human) = run(&[]);
    assert!(
        human.contains("the residual showed 2 mode(s) the start missed"),
        "{human}"
    );
    assert_eq!(v["refinement"]["start_modes"], 2);
    assert_eq!(v["refinement"]["added_hz"].as_array().unwrap().len(), 2);
    assert_eq!(v["parameters"]["added_modes"], true);
    let truth = [1748.64, 5031.80, 7709.75, 9458.39];
    let modes = v["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 4);
    for (m, t) in modes.iter().zip(truth) {
        let f = m["frequency_hz"].as_f64().unwrap();
        assert!((f - t).abs() < 0.01 * t, "{f} vs {t}");
        assert_eq!(m["physical"], true, "{m}");
    }
    let (v, human) = run(&["--no-added-modes"]);
    assert!(!human.contains("start missed"), "{human}");
    assert_eq!(v["modes"].as_array().unwrap().len(), 2);
    assert_eq!(v["parameters"]["added_modes"], false);
    assert!(v["refinement"]["added_hz"].as_array().unwrap().is_empty());
}

/// A small model.json and FRF set for the error cases.
fn small_model(dir: &Path) -> (PathBuf, PathBuf) {
    let (file, _) = modal_set(
        dir,
        "small.csv",
        &[
            "--outputs",
            "2",
            "--inputs",
            "2",
            "--modes",
            "3",
            "--fmin",
            "1",
            "--fmax",
            "6",
            "--lines",
            "201",
            "--df",
            "0.05",
            "--collocated",
            "--quiet",
        ],
    );
    let out = dir.join("small-model");
    era()
        .args([
            "identify",
            s(&file),
            "--states",
            "6",
            "--hankel-factor",
            "4",
            "--time-domain",
            "continuous",
            "--out",
            s(&out),
            "-q",
        ])
        .assert()
        .success();
    (file, out.join("model.json"))
}

#[test]
fn bad_refinement_input_exits_2_naming_the_flag_or_file() {
    let dir = tempfile::tempdir().unwrap();
    let (file, model) = small_model(dir.path());
    let f = s(&file);
    let base = ["identify", f, "--states", "6", "--hankel-factor", "4", "-q"];
    let with = |extra: &[&str]| {
        let mut a = base.to_vec();
        a.extend_from_slice(extra);
        run_capped(&a, None, None)
    };
    for (extra, needle) in [
        (
            &["--refine", "--max-iterations", "0"][..],
            "--max-iterations",
        ),
        (
            &["--refine", "--max-iterations", "99999999999999"][..],
            "--max-iterations",
        ),
        (&["--no-refine", "--residuals", "lower"][..], "--refine"),
        (&["--no-refine", "--max-iterations", "5"][..], "--refine"),
        (
            &["--preset", "thesis", "--no-added-modes"][..],
            "--preset thesis",
        ),
    ] {
        let o = with(extra);
        o.assert_input_error();
        assert!(o.stderr.contains(needle), "{extra:?}: {}", o.stderr);
    }
    // Values clap refuses (its own message, exit 2).
    for (extra, needle) in [
        (&["--refine", "--max-iterations=-3"][..], "--max-iterations"),
        (&["--refine", "--residuals", "sideways"][..], "--residuals"),
        (&["--refine", "--no-refine"][..], "--no-refine"),
    ] {
        let mut a = base.to_vec();
        a.extend_from_slice(extra);
        common::expect_input_error(&a, needle);
    }

    // Reciprocity of a non-square set.
    let (rect, _) = modal_set(
        dir.path(),
        "rect.csv",
        &[
            "--outputs",
            "3",
            "--inputs",
            "2",
            "--modes",
            "3",
            "--fmin",
            "1",
            "--fmax",
            "6",
            "--lines",
            "201",
            "--df",
            "0.05",
            "--quiet",
        ],
    );
    let o = run_capped(
        &[
            "identify",
            s(&rect),
            "--states",
            "6",
            "--refine",
            "--reciprocal",
            "-q",
        ],
        None,
        None,
    );
    o.assert_input_error();
    assert!(o.stderr.contains("--reciprocal"), "{}", o.stderr);

    // era refine: a model whose shape is not the file's.
    let o = run_capped(&["refine", s(&model), s(&rect), "-q"], None, None);
    o.assert_input_error();
    assert!(
        o.stderr.contains("model.json") && o.stderr.contains("2 outputs x 2 inputs"),
        "{}",
        o.stderr
    );
    // A file whose lines are not the model's.
    let (other, _) = modal_set(
        dir.path(),
        "other.csv",
        &[
            "--outputs",
            "2",
            "--inputs",
            "2",
            "--modes",
            "3",
            "--fmin",
            "1",
            "--fmax",
            "6",
            "--lines",
            "201",
            "--df",
            "0.04",
            "--collocated",
            "--quiet",
        ],
    );
    let o = run_capped(&["refine", s(&model), s(&other), "-q"], None, None);
    o.assert_input_error();
    assert!(
        o.stderr.contains("other.csv") && o.stderr.contains("lines"),
        "{}",
        o.stderr
    );
    // A malformed model.json, and impossible iterations on era refine.
    let broken = dir.path().join("broken.json");
    std::fs::write(&broken, "{\"outputs\": 2,").unwrap();
    let o = run_capped(&["refine", s(&broken), f, "-q"], None, None);
    o.assert_input_error();
    assert!(o.stderr.contains("broken.json"), "{}", o.stderr);
    let o = run_capped(
        &["refine", s(&model), f, "--max-iterations", "0", "-q"],
        None,
        None,
    );
    o.assert_input_error();
    assert!(o.stderr.contains("--max-iterations"), "{}", o.stderr);

    // The right file refines.
    let o = run_capped(&["refine", s(&model), f, "-q", "--json"], None, None);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    let v: serde_json::Value = serde_json::from_str(&o.stdout).unwrap();
    assert!(
        v["refinement"]["fit_after"].as_f64().unwrap() < 1e-6,
        "{}",
        v["refinement"]
    );
}

#[test]
fn demo_gains_a_refined_column_beside_the_thesis_columns() {
    let out = era().args(["demo", "--json"]).output().unwrap();
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let refined = v["refined"].as_array().unwrap();
    assert_eq!(refined.len(), 4);
    let truth = [1748.64, 5031.80, 7709.75, 9458.39];
    for (m, t) in refined.iter().zip(truth) {
        let f = m["frequency_hz"].as_f64().unwrap();
        let sd = m["frequency_std_hz"].as_f64().unwrap();
        // Within five predicted standard deviations of the truth.
        assert!((f - t).abs() < 5.0 * sd, "{f} ± {sd} vs {t}");
    }
    assert_eq!(v["refinement"]["model"], "z");
    assert!(v["errors"]["refined"]["max_frequency_error_hz"]
        .as_f64()
        .is_some());
    let text = String::from_utf8_lossy(&out.stderr);
    assert!(
        text.contains("ERA + refined") && text.contains("noisy - truth"),
        "{text}"
    );
}
