//! End-to-end tests of the `era` binary.

use crate::common;
use common::assert_success;

use common::{era, expect_input_error, s, simulated_truth, truth_identify, write, TRUTH_SETTINGS};
use era::sim::TABLE_5_2_TRUTH;
use serde_json::Value;
use std::path::Path;

fn json_of(output: &std::process::Output) -> Value {
    serde_json::from_slice(&output.stdout).expect("stdout is JSON")
}

#[test]
fn demo_prints_table_5_2_and_json_agrees() {
    let out = era().arg("demo").output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("Table 5.2") && text.contains("1748.64") && text.contains("9458.39"),
        "{text}"
    );

    let out = era()
        .args(["demo", "--json", "--timings"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let v = json_of(&out);
    for key in ["truth", "no_noise", "noisy"] {
        assert_eq!(v[key].as_array().unwrap().len(), 4, "{key}");
    }
    for (mode, (f, z)) in v["no_noise"]
        .as_array()
        .unwrap()
        .iter()
        .zip(TABLE_5_2_TRUTH)
    {
        assert!((mode["frequency_hz"].as_f64().unwrap() - f).abs() < 0.01);
        assert!((mode["damping_ratio"].as_f64().unwrap() - z / 100.0).abs() < 1e-4);
    }
    assert!(
        v["errors"]["no_noise"]["max_frequency_error_hz"]
            .as_f64()
            .unwrap()
            < 0.01
    );
    assert!(
        v["errors"]["noisy"]["max_frequency_error_hz"]
            .as_f64()
            .unwrap()
            > 0.0
    );
    assert_eq!(v["noise"]["seed"], 1);
    assert!(v["timings_s"]["noisy"]["hankel_svd"].as_f64().is_some());
    // Human text went to stderr, stdout is JSON only.
    assert!(String::from_utf8_lossy(&out.stderr).contains("Table 5.2"));
}

#[test]
fn demo_seed_changes_only_the_noisy_column() {
    let a = json_of(
        &era()
            .args(["demo", "--json", "--seed", "7"])
            .output()
            .unwrap(),
    );
    let b = json_of(
        &era()
            .args(["demo", "--json", "--seed", "8"])
            .output()
            .unwrap(),
    );
    assert_eq!(a["no_noise"], b["no_noise"]);
    assert_ne!(a["noisy"], b["noisy"]);
}

#[test]
fn demo_out_writes_frfs_models_and_fits() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    era()
        .args(["demo", "-q", "--out"])
        .arg(&out)
        .assert()
        .success();
    for f in [
        "truth_frf.csv",
        "truth_frf_noisy.csv",
        "no_noise/model.json",
        "no_noise/fit.json",
        "noisy/model.json",
        "noisy/fit.json",
        "noisy/model.mat",
        "no_noise/model.mat",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
}

#[test]
fn simulate_then_identify_the_truth_model() {
    let dir = tempfile::tempdir().unwrap();
    let frf = simulated_truth(dir.path());
    let out_dir = dir.path().join("out");
    let out = era()
        .arg("identify")
        .arg(&frf)
        .args(["--preset", "thesis", "--states", "8"])
        .args(TRUTH_SETTINGS)
        .args(["--json", "--timings", "--out"])
        .arg(&out_dir)
        .output()
        .unwrap();
    assert_success(&out);
    let v = json_of(&out);
    assert_eq!(v["states"], 8);
    assert_eq!(v["time_domain"], "discrete");
    assert_eq!(v["singular_values"].as_array().unwrap().len(), 45);
    assert_eq!(v["parameters"]["hankel_factor"], 4);
    assert_eq!(v["hankel"]["path"], "dense");
    for (mode, (f, z)) in v["modes"].as_array().unwrap().iter().zip(TABLE_5_2_TRUTH) {
        assert!((mode["frequency_hz"].as_f64().unwrap() - f).abs() < 0.01);
        assert!((mode["damping_ratio"].as_f64().unwrap() - z / 100.0).abs() < 1e-4);
    }
    for stage in [
        "read",
        "preprocess",
        "markov",
        "hankel_svd",
        "realize",
        "modes",
        "fit",
        "write",
    ] {
        assert!(v["timings_s"][stage].as_f64().is_some(), "{stage}");
    }
    // No scan at a fixed order: no scan stages. The process's wall time is beside the
    // stages, not among them.
    assert!(v["timings_s"].get("scan").is_none());
    let stages: f64 = v["timings_s"]
        .as_object()
        .unwrap()
        .iter()
        .filter(|(k, _)| *k != "wall")
        .map(|(_, t)| t.as_f64().unwrap())
        .sum();
    assert!(stages <= v["timings_s"]["wall"].as_f64().unwrap());
    let model: Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("model.json")).unwrap())
            .unwrap();
    assert_eq!(model["modes"], v["modes"]);
    let fit: Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("fit.json")).unwrap()).unwrap();
    assert_eq!(fit["pairs"].as_array().unwrap().len(), 9);
    assert!(fit["collocated_mean_relative_error"].as_f64().unwrap() < 1e-9);
}

#[test]
fn continuous_model_from_a_noisy_modal_set() {
    let dir = tempfile::tempdir().unwrap();
    let frf = crate::common::simulate_modal(
        dir.path(),
        "modal.csv",
        &[
            "--outputs",
            "3",
            "--inputs",
            "2",
            "--modes",
            "4",
            "--fmin",
            "2",
            "--fmax",
            "8",
            "--lines",
            "401",
            "--df",
            "0.05",
            "--quantity",
            "velocity",
            "--noise",
            "0.01",
            "--seed",
            "3",
        ],
    );
    let out = era()
        .arg("identify")
        .arg(&frf)
        .args([
            "--states",
            "8",
            "--hankel-factor",
            "10",
            "--time-domain",
            "continuous",
            "--json",
        ])
        .output()
        .unwrap();
    assert_success(&out);
    let v = json_of(&out);
    assert_eq!(v["time_domain"], "continuous");
    assert!(v["sample_time_s"].is_null());
    let modes = v["modes"].as_array().unwrap();
    assert!(modes
        .iter()
        .all(|m| (1.5..8.5).contains(&m["frequency_hz"].as_f64().unwrap())));
}

#[test]
fn bad_csv_files_exit_2_naming_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases = [
        (
            "missing.csv",
            "frequency_hz,H1_1_re,H1_1_im,H2_1_re\n0,1,1,1\n1,1,1,1\n",
            "missing column(s) for a 2x1 set: H2_1_im",
        ),
        (
            "text.csv",
            "frequency_hz,H1_1_re,H1_1_im\n0,1,1\n1,x1,1\n",
            "line 3, column H1_1_re: 'x1' is not a number",
        ),
        (
            "nan.csv",
            "frequency_hz,H1_1_re,H1_1_im\n0,1,1\n1,NaN,1\n",
            "line 3, column H1_1_re: NaN is not a finite number",
        ),
        (
            "uneven.csv",
            "frequency_hz,H1_1_re,H1_1_im\n0,1,1\n1,1,1\n3,1,1\n",
            "line 4, column frequency_hz: frequencies are not uniformly spaced",
        ),
        (
            "offset.csv",
            "frequency_hz,H1_1_re,H1_1_im\n5.5,1,1\n6.5,1,1\n",
            "line 2, column frequency_hz: the first line is 5.5 Hz, 5.5000 increments",
        ),
    ];
    for (name, text, needle) in cases {
        let p = write(d, name, text);
        expect_input_error(&["identify", p.to_str().unwrap(), "--states", "2"], needle);
        expect_input_error(&["identify", p.to_str().unwrap(), "--states", "2"], name);
    }
}

#[test]
fn impossible_requests_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let frf = simulated_truth(dir.path());
    let f = frf.to_str().unwrap();
    expect_input_error(
        &["identify", f, "--states", "12", "--hankel-factor", "4"],
        "the data supports only 8 states",
    );
    expect_input_error(
        &["identify", f, "--states", "8", "--hankel-factor", "300"],
        "Markov samples",
    );
    expect_input_error(
        &["identify", f, "--states", "8", "--integrations", "1"],
        "cannot be integrated",
    );
    expect_input_error(
        &["identify", f, "--states", "8", "--lowpass-hz", "-3"],
        "--lowpass-hz -3",
    );
    expect_input_error(&["identify", f, "--states", "0"], "--states 0");
    expect_input_error(
        &["identify", f, "--states", "eight"],
        "invalid value 'eight'",
    );
    expect_input_error(&["identify", f, "--sates", "8"], "unexpected argument");

    let zeros = write(
        dir.path(),
        "zeros.csv",
        "frequency_hz,H1_1_re,H1_1_im\n0,0,0\n1,0,0\n2,0,0\n3,0,0\n",
    );
    expect_input_error(
        &[
            "identify",
            zeros.to_str().unwrap(),
            "--states",
            "2",
            "--hankel-factor",
            "1",
        ],
        "every FRF value is zero",
    );

    expect_input_error(
        &["identify", "/no/such/frf.csv", "--states", "2"],
        "/no/such/frf.csv",
    );

    // --out below a regular file cannot be created, whoever runs the test.
    let blocker = write(dir.path(), "blocker", "");
    let out = blocker.join("sub");
    expect_input_error(
        &[
            "identify",
            f,
            "--states",
            "8",
            "--hankel-factor",
            "4",
            "--out",
            out.to_str().unwrap(),
        ],
        "--out",
    );
    expect_input_error(&["demo", "--out", out.to_str().unwrap()], "--out");
    expect_input_error(
        &[
            "simulate",
            "truth-model",
            "--out",
            out.join("x.csv").to_str().unwrap(),
        ],
        "x.csv",
    );
    expect_input_error(&["demo", "--noise", "-1"], "--noise -1");
    expect_input_error(
        &[
            "simulate",
            "modal",
            "--collocated",
            "--outputs",
            "3",
            "--inputs",
            "2",
            "--out",
            "x.csv",
        ],
        "--collocated",
    );
    expect_input_error(
        &[
            "simulate",
            "modal",
            "--damping",
            "0.01-0.02",
            "--out",
            "x.csv",
        ],
        "--damping",
    );
}

#[test]
fn a_failed_run_leaves_no_file_behind() {
    let dir = tempfile::tempdir().unwrap();
    let frf = simulated_truth(dir.path());
    let out_dir = dir.path().join("out");
    let out = era()
        .arg("identify")
        .arg(&frf)
        .args(["--states", "12", "--out"])
        .arg(&out_dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        std::fs::read_dir(&out_dir).unwrap().count(),
        0,
        "no model.json from a failed run"
    );
}

#[test]
fn simulate_reports_timings_and_the_true_modes() {
    let dir = tempfile::tempdir().unwrap();
    let frf = dir.path().join("m.csv");
    let out = era()
        .args([
            "simulate",
            "modal",
            "--outputs",
            "2",
            "--inputs",
            "2",
            "--modes",
            "3",
            "--collocated",
            "--timings",
            "--json",
            "--out",
        ])
        .arg(&frf)
        .output()
        .unwrap();
    assert!(out.status.success());
    let v = json_of(&out);
    assert!(
        v["timings_s"]["simulate"].as_f64().is_some() && v["timings_s"]["write"].as_f64().is_some()
    );
    assert_eq!(v["modes"].as_array().unwrap().len(), 3);
    let text = std::fs::read_to_string(&frf).unwrap();
    assert!(text.starts_with("# quantity: acceleration\n"));
}

#[test]
fn identify_reports_the_svd_path() {
    let dir = tempfile::tempdir().unwrap();
    let frf = simulated_truth(dir.path());
    let base = [&["--states", "8"][..], &TRUTH_SETTINGS, &["--timings"]].concat();
    // auto: a 45 x 45 Hankel stays dense.
    let out = era()
        .arg("identify")
        .arg(&frf)
        .args(&base)
        .arg("--json")
        .output()
        .unwrap();
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["hankel"]["path"], "dense");
    assert_eq!(v["parameters"]["svd"], "auto");
    assert!(String::from_utf8_lossy(&out.stderr).contains("hankel_svd path: dense"));
    // forced matrix-free: same modes, reported as such.
    let out = era()
        .arg("identify")
        .arg(&frf)
        .args(&base)
        .args(["--svd", "matrix-free", "--json"])
        .output()
        .unwrap();
    assert_success(&out);
    let w: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(w["hankel"]["path"], "matrix-free");
    assert!(w["hankel"]["svd_iterations"].as_u64().unwrap() >= 1);
    assert_eq!(w["singular_values"].as_array().unwrap().len(), 8);
    assert!(String::from_utf8_lossy(&out.stderr).contains("hankel_svd path: matrix-free"));
    for (a, b) in v["modes"]
        .as_array()
        .unwrap()
        .iter()
        .zip(w["modes"].as_array().unwrap())
    {
        let (fa, fb) = (
            a["frequency_hz"].as_f64().unwrap(),
            b["frequency_hz"].as_f64().unwrap(),
        );
        assert!((fa - fb).abs() < 1e-8 * fa);
    }
}

#[test]
fn identify_out_writes_every_figure_and_the_report() {
    let dir = tempfile::tempdir().unwrap();
    let frf = crate::common::simulate_modal(
        dir.path(),
        "dta.csv",
        &["--collocated", "--seed", "987654321"],
    );
    let out = dir.path().join("out");
    let run = era()
        .arg("identify")
        .arg(&frf)
        .args([
            "--states",
            "80",
            "--integrations",
            "1",
            "--zero-lines",
            "3",
            "--pad-to",
            "1024",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(run.status.success());
    // stderr is not a terminal here: no spinner or bar is drawn into it.
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        !stderr.contains('\u{1b}') && !stderr.contains("[0s]"),
        "{stderr}"
    );
    let count = |ext: &str| {
        std::fs::read_dir(out.join("pairs"))
            .unwrap()
            .filter(|e| {
                e.as_ref()
                    .unwrap()
                    .path()
                    .extension()
                    .is_some_and(|x| x == ext)
            })
            .count()
    };
    assert_eq!(count("svg"), 64);
    assert_eq!(count("png"), 64);
    for f in [
        "grid.svg",
        "grid.png",
        "singular_values.svg",
        "singular_values.png",
        "report.html",
        "model.json",
        "fit.json",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert_eq!(html.matches("class=\"plot overlay\"").count(), 64);
    for id in [
        "id=\"parameters\"",
        "id=\"fig-singular-values\"",
        "id=\"modal-table\"",
        "id=\"fit-table\"",
        "id=\"fig-grid\"",
    ] {
        assert!(html.contains(id), "{id}");
    }
    assert!(html.contains("output 8 / input 8 (collocated)"));
    // Self-contained: the only URLs are the SVG namespace names, and nothing is loaded.
    assert_eq!(
        html.matches("http").count(),
        html.matches("http://www.w3.org/2000/svg").count()
    );
    // The one script is inline (the pair picker): nothing is fetched.
    assert_eq!(html.matches("<script>").count(), 1);
    assert!(!html.contains("<script src") && !html.contains("<link") && !html.contains("src="));
    // 64 overlays, the grid, the singular values, the AutoMAC and the complexity.
    assert_eq!(html.matches("<svg").count(), 68);
    for f in [
        "automac.svg",
        "automac.png",
        "complexity.svg",
        "complexity.png",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
}

#[test]
fn plot_overlays_a_file_with_a_model_or_alone() {
    let dir = tempfile::tempdir().unwrap();
    let frf = simulated_truth(dir.path());
    let model_dir = dir.path().join("model");
    era()
        .args(truth_identify(&frf, "8", &model_dir))
        .assert()
        .success();
    let with = dir.path().join("with");
    era()
        .arg("plot")
        .arg(&frf)
        .arg("--model")
        .arg(model_dir.join("model.json"))
        .arg("--out")
        .arg(&with)
        .arg("-q")
        .assert()
        .success();
    assert_eq!(std::fs::read_dir(with.join("pairs")).unwrap().count(), 18);
    assert!(with.join("singular_values.svg").is_file());
    let svg = std::fs::read_to_string(with.join("pairs/pair_2_2.svg")).unwrap();
    // The legend names the model: refined when model.json says a refinement ran.
    let model: Value =
        serde_json::from_str(&std::fs::read_to_string(model_dir.join("model.json")).unwrap())
            .unwrap();
    let refined = !model["refinement"].is_null();
    let name = if refined {
        "refined model"
    } else {
        "ERA model"
    };
    assert!(svg.contains(name) && svg.contains("(collocated)"), "{name}");

    let alone = dir.path().join("alone");
    era()
        .arg("plot")
        .arg(&frf)
        .arg("--out")
        .arg(&alone)
        .arg("-q")
        .assert()
        .success();
    let svg = std::fs::read_to_string(alone.join("pairs/pair_1_2.svg")).unwrap();
    assert!(svg.contains("measured") && !svg.contains("ERA model"));
    assert!(!alone.join("singular_values.svg").exists());

    // A model of another shape is refused.
    let other = crate::common::simulate_modal(
        dir.path(),
        "m.csv",
        &["--outputs", "2", "--inputs", "2", "--modes", "2"],
    );
    expect_input_error(
        &[
            "plot",
            other.to_str().unwrap(),
            "--model",
            model_dir.join("model.json").to_str().unwrap(),
            "--out",
            dir.path().join("x").to_str().unwrap(),
        ],
        "the model has 3 outputs x 3 inputs",
    );
}

#[test]
fn quantity_flag_overrides_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let frf = simulated_truth(dir.path()); // "# quantity: displacement"
    let base = [
        &["--states", "8"][..],
        &TRUTH_SETTINGS,
        &["--integrations", "1", "-q"],
    ]
    .concat();
    expect_input_error(
        &[
            "identify",
            frf.to_str().unwrap(),
            "--states",
            "8",
            "--integrations",
            "1",
        ],
        "displacement FRFs cannot be integrated",
    );
    let out = era()
        .arg("identify")
        .arg(&frf)
        .args(&base)
        .args(["--quantity", "velocity", "--json"])
        .output()
        .unwrap();
    assert_success(&out);
}

#[test]
fn identify_reads_mat_files_by_content() {
    let dir = tempfile::tempdir().unwrap();
    let csv = simulated_truth(dir.path());
    // The same FRFs as a MAT file in the thesis's FRF + FreqV layout, under a
    // misleading extension: detection goes by content.
    let frf = era::sim::truth_model_frf(None).unwrap();
    let mat = dir.path().join("truth.dat");
    era_io::mat::write_frf_mat(&mat, &frf).unwrap();
    let args = [
        &["--states", "8"][..],
        &TRUTH_SETTINGS,
        &["--quantity", "displacement", "--json", "-q"],
    ]
    .concat();
    let from_csv: Value = serde_json::from_slice(
        &era()
            .arg("identify")
            .arg(&csv)
            .args(&args)
            .output()
            .unwrap()
            .stdout,
    )
    .unwrap();
    let out = era()
        .arg("identify")
        .arg(&mat)
        .args(&args)
        .output()
        .unwrap();
    assert_success(&out);
    let from_mat: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(from_mat["modes"], from_csv["modes"]);
    // A MAT file with no FRF layout is refused, naming what it holds.
    let model_dir = dir.path().join("m");
    era()
        .args(truth_identify(&csv, "8", &model_dir))
        .assert()
        .success();
    expect_input_error(
        &[
            "identify",
            model_dir.join("model.mat").to_str().unwrap(),
            "--states",
            "2",
        ],
        "holds a state-space model",
    );
}

#[test]
fn suspect_results_are_warned_of_in_the_summary_and_the_json() {
    let dir = tempfile::tempdir().unwrap();
    let frf = simulated_truth(dir.path());
    // Padded four times with a short Hankel, the truth model's realization has a
    // growing mode: the run succeeds, but says so, naming the flags to change.
    let args = [
        "--preset",
        "thesis",
        "--states",
        "8",
        "--hankel-factor",
        "2",
        "--pad-to",
        "4096",
    ];
    let out = era().arg("identify").arg(&frf).args(args).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("warning: 1 mode(s) with negative damping") && text.contains("--states auto"),
        "{text}"
    );
    let out = era()
        .arg("identify")
        .arg(&frf)
        .args(args)
        .args(["--json", "-q"])
        .output()
        .unwrap();
    let model = json_of(&out);
    let warnings: Vec<&str> = model["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w.as_str().unwrap())
        .collect();
    assert!(
        warnings.iter().any(|w| w.contains("negative damping")),
        "{warnings:?}"
    );
    assert!(model["modes"]
        .as_array()
        .unwrap()
        .iter()
        .any(|m| m["damping_ratio"].as_f64().unwrap() < 0.0));
    // The report says so before anything else of the run.
    let bundle = dir.path().join("suspect");
    era()
        .arg("identify")
        .arg(&frf)
        .args(args)
        .args(["-q", "--out"])
        .arg(&bundle)
        .assert()
        .success();
    let html = std::fs::read_to_string(bundle.join("report.html")).unwrap();
    let at = html
        .find("id=\"warning-list\"")
        .expect("a warnings section");
    assert!(at < html.find("id=\"parameters\"").unwrap());
    assert!(html[at..].contains("negative damping"));
    let clean = dir.path().join("clean");
    era()
        .arg("identify")
        .arg(&frf)
        .args(["--states", "8"])
        .args(TRUTH_SETTINGS)
        .args(["-q", "--out"])
        .arg(&clean)
        .assert()
        .success();
    let html = std::fs::read_to_string(clean.join("report.html")).unwrap();
    assert!(!html.contains("id=\"warning-list\""));
    // The thesis settings give a stable model and no warning.
    let out = era()
        .arg("identify")
        .arg(&frf)
        .args(["--states", "8"])
        .args(TRUTH_SETTINGS)
        .args(["--json", "-q"])
        .output()
        .unwrap();
    assert_eq!(json_of(&out)["warnings"], serde_json::json!([]));
}

/// `--states auto --timings`: the scan and the selection are stages of their own, and
/// the table says how much of the process's wall time no stage holds.
#[test]
fn the_automatic_order_times_its_scan_and_selection() {
    let dir = tempfile::tempdir().unwrap();
    let frf = simulated_truth(dir.path());
    let out = era()
        .args([
            "identify",
            s(&frf),
            "--states",
            "auto",
            "--timings",
            "--no-figures",
        ])
        .args(["--out", s(&dir.path().join("o"))])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    // The zero-start check identifies the model's own FRF twice: a stage of its own.
    for stage in [
        "scan ",
        "selection ",
        "hankel_svd ",
        "zero_start ",
        "total ",
        "wall ",
    ] {
        assert!(text.contains(&format!("  {stage}")), "{stage}: {text}");
    }
    assert!(text.contains("% of it in no stage above"), "{text}");
    let model: Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("o/model.json")).unwrap()).unwrap();
    let t = model["timings_s"].as_object().unwrap();
    assert!(t["scan"].as_f64().unwrap() > 0.0 && t["selection"].as_f64().unwrap() > 0.0);
    assert!(t["zero_start"].as_f64().unwrap() > 0.0, "{t:?}");
    // The refinement's rounds are parts of its stage: under it in the table, within it
    // in the JSON, and not counted twice.
    assert!(text.contains("\n    round 1 "), "{text}");
    let rounds: f64 = t
        .iter()
        .filter(|(k, _)| k.starts_with("refine.round "))
        .map(|(_, v)| v.as_f64().unwrap())
        .sum();
    assert!(
        rounds > 0.0 && rounds <= t["refine"].as_f64().unwrap(),
        "{t:?}"
    );
    let stages: f64 = t
        .iter()
        .filter(|(k, _)| *k != "wall" && !k.contains('.'))
        .map(|(_, v)| v.as_f64().unwrap())
        .sum();
    assert!(stages <= t["wall"].as_f64().unwrap(), "{t:?}");
}

#[test]
fn threads_sets_the_run_and_refuses_absurd_counts() {
    let dir = tempfile::tempdir().unwrap();
    let frf = crate::common::dta_like_set(dir.path(), "dta.csv");
    let run = |threads: &[&str]| {
        let out = era()
            .args(threads)
            .arg("identify")
            .arg(&frf)
            .args([
                "--preset",
                "thesis",
                "--states",
                "80",
                "--hankel-factor",
                "5",
                "--integrations",
                "1",
            ])
            .args(["--zero-lines", "3", "--pad-to", "1024", "--json", "-q"])
            .output()
            .unwrap();
        assert_success(&out);
        json_of(&out)
    };
    let all = run(&[]);
    let one = run(&["--threads", "1"]);
    let freqs = |m: &Value| -> Vec<f64> {
        m["modes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x["frequency_hz"].as_f64().unwrap())
            .collect()
    };
    let (a, b) = (freqs(&all), freqs(&one));
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() <= 1e-9 * x.abs(), "{x} vs {y}");
    }
    for bad in ["0", "100000"] {
        expect_input_error(
            &["identify", "--threads", bad, "x.csv", "--states", "2"],
            &format!("--threads {bad}: must be between 1 and 1024"),
        );
    }
}

/// `--no-figures` (identify and refine) writes the model files and nothing else, and
/// needs `--out`.
#[test]
fn no_figures_writes_the_model_files_only() {
    let dir = tempfile::tempdir().unwrap();
    let frf = simulated_truth(dir.path());
    let frf = s(&frf);
    // Runs era, expects success, returns what it printed (stdout and stderr).
    let ok = |args: &[&str]| {
        let out = era().args(args).output().unwrap();
        let said = String::from_utf8_lossy(&out.stderr).into_owned()
            + &String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{args:?}: {said}");
        said
    };
    let model_files = [
        "model.json",
        "fit.json",
        "model.mat",
        "modes.uff",
        "model_frf.uff",
    ];
    let out = dir.path().join("bare");
    ok(&[
        "identify",
        frf,
        "--states",
        "8",
        "-q",
        "--no-figures",
        "--out",
        s(&out),
    ]);
    let mut written: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    written.sort();
    let mut expected: Vec<String> = model_files.iter().map(|f| f.to_string()).collect();
    expected.sort();
    assert_eq!(written, expected);
    // The same run with figures adds the report and the figures, nothing else changes.
    let full = dir.path().join("full");
    ok(&["identify", frf, "--states", "8", "-q", "--out", s(&full)]);
    assert!(full.join("report.html").is_file() && full.join("grid.png").is_file());
    let a: Value = serde_json::from_slice(&std::fs::read(out.join("model.json")).unwrap()).unwrap();
    let b: Value =
        serde_json::from_slice(&std::fs::read(full.join("model.json")).unwrap()).unwrap();
    assert_eq!(a["a"], b["a"]);
    // refine as well
    let refined = dir.path().join("refined");
    let model = out.join("model.json");
    ok(&[
        "refine",
        s(&model),
        frf,
        "-q",
        "--no-figures",
        "--out",
        s(&refined),
    ]);
    assert!(refined.join("model.json").is_file());
    assert!(!refined.join("report.html").exists());
    // Into the folder with figures: the earlier report stays, and the run says whose it is.
    let said = ok(&[
        "identify",
        frf,
        "--states",
        "8",
        "--no-figures",
        "--out",
        s(&full),
    ]);
    assert!(said.contains("earlier run"), "{said}");
    // Without --out there is nothing to leave figures out of.
    expect_input_error(&["identify", frf, "--states", "8", "--no-figures"], "--out");
}

/// `era identify` with `args` on `frf`: its JSON and its human text.
fn identify_json(frf: &Path, args: &[&str]) -> (Value, String) {
    let out = era()
        .arg("identify")
        .arg(frf)
        .args(args)
        .arg("--json")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    (
        json_of(&out),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn the_default_route_is_echoed_and_the_thesis_preset_is_plain_era() {
    let dir = tempfile::tempdir().unwrap();
    let frf = simulated_truth(dir.path());
    // No flag at all: the measured route, each choice echoed with its reason.
    let (v, text) = identify_json(&frf, &[]);
    for line in [
        "route (--preset measured)\n",
        "order: automatic (from the stabilization diagram",
        "refinement: on (the measured preset",
        "time domain: continuous (the measured preset: measured FRFs are continuous-time data",
        "direct term: D = 0 (the measured preset: a displacement FRF has no direct term)",
    ] {
        assert!(text.contains(line), "{line}: {text}");
    }
    assert_eq!(v["time_domain"], "continuous");
    assert_eq!(v["parameters"]["preset"], "measured");
    let physical: Vec<f64> = v["modes"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["physical"] == true)
        .map(|m| m["frequency_hz"].as_f64().unwrap())
        .collect();
    assert_eq!(physical.len(), 4, "{physical:?}");
    for (f, (t, _)) in physical.iter().zip(TABLE_5_2_TRUTH) {
        assert!((f - t).abs() < 0.01, "{f} vs {t}");
    }
    // --preset thesis is plain ERA: the same model, bit for bit, as every thesis
    // choice spelled out.
    let thesis = [&["--states", "8"][..], &TRUTH_SETTINGS].concat();
    let mut preset = vec!["--preset", "thesis"];
    preset.extend(&thesis);
    let (a, text) = identify_json(&frf, &preset);
    assert!(
        text.contains("refinement: off (the thesis preset: plain ERA)"),
        "{text}"
    );
    let mut spelled = vec![
        "--no-refine",
        "--time-domain",
        "discrete",
        "--direct-term",
        "zero",
        "--band",
        "all",
        "--no-window-correction",
    ];
    spelled.extend(&thesis);
    let (b, _) = identify_json(&frf, &spelled);
    assert_eq!(a["time_domain"], "discrete");
    assert!(a["refinement"].is_null(), "{}", a["refinement"]);
    for key in ["a", "b", "c", "d", "singular_values"] {
        assert_eq!(a[key], b[key], "{key}");
    }
    // An explicit flag overrides the preset.
    let mut refined = preset.clone();
    refined.push("--refine");
    let (r, _) = identify_json(&frf, &refined);
    assert!(r["refinement"].is_object());
    assert_eq!(r["time_domain"], "discrete");
}

#[test]
fn a_late_start_warns_of_its_cost_and_the_refinement_is_free_of_it() {
    // Receptance of modes at 6 and 13 Hz, lines from 5 Hz: padded with zeros below.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("late.csv");
    let mut text = String::from("# quantity: displacement\nfrequency_hz,H1_1_re,H1_1_im\n");
    for k in 50..=400 {
        let f = k as f64 * 0.1;
        let w = 2.0 * std::f64::consts::PI * f;
        let mut h = num_complex::Complex64::new(0.0, 0.0);
        for (fn_hz, zeta) in [(6.0, 0.02), (13.0, 0.01)] {
            let wn = 2.0 * std::f64::consts::PI * fn_hz;
            h += 1.0 / num_complex::Complex64::new(wn * wn - w * w, 2.0 * zeta * wn * w);
        }
        text.push_str(&format!("{f},{:e},{:e}\n", h.re, h.im));
    }
    std::fs::write(&path, text).unwrap();
    let base = ["--states", "4", "--hankel-factor", "20"];
    let mut plain = vec!["--preset", "thesis"];
    plain.extend(base);
    let (v, _) = identify_json(&path, &plain);
    let warnings: Vec<String> = v["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w.as_str().unwrap().to_string())
        .collect();
    let late = warnings
        .iter()
        .find(|w| w.contains("the lines below 5 Hz are zero"))
        .unwrap_or_else(|| panic!("{warnings:?}"));
    assert!(
        late.contains("--zero-lines") && late.contains("% in damping"),
        "{late}"
    );
    // A band that starts inside the lowest mode's half-power band says so.
    let mut edge = base.to_vec();
    edge.extend(["--band", "5.8..40"]);
    let (v, _) = identify_json(&path, &edge);
    assert!(
        v["warnings"]
            .to_string()
            .contains("the band is too short for the lowest mode"),
        "{}",
        v["warnings"]
    );
    let (v, _) = identify_json(&path, &base);
    let first = &v["modes"][0];
    assert!(
        (first["frequency_hz"].as_f64().unwrap() - 6.0).abs() < 1e-6,
        "{first}"
    );
    assert!(
        (first["damping_ratio"].as_f64().unwrap() - 0.02).abs() < 1e-6,
        "{first}"
    );
    assert!(
        v["warnings"].to_string().contains("free of it"),
        "{}",
        v["warnings"]
    );
}
