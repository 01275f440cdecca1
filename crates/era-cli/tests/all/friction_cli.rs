//! End-to-end tests of `era friction`.

use crate::common;
use common::assert_success;

use common::{era, expect_input_error};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Simulates a free decay into `dir/name` (k = 1 lbf/in, f_n = 1.5 Hz, 200 Hz).
fn decay(dir: &Path, name: &str, coulomb_force: f64, extra: &[&str]) -> PathBuf {
    let path = dir.join(name);
    era()
        .args([
            "friction",
            "simulate",
            "-q",
            "--stiffness",
            "1",
            "--natural-frequency-hz",
            "1.5",
            "--coulomb-force",
        ])
        .arg(coulomb_force.to_string())
        .args(extra)
        .arg("--out")
        .arg(&path)
        .assert()
        .success();
    path
}

#[test]
fn estimate_reads_simulated_records_and_reports_the_schema() {
    let dir = tempfile::tempdir().unwrap();
    let files: Vec<PathBuf> = (1..=4)
        .map(|s| {
            decay(
                dir.path(),
                &format!("d{s}.csv"),
                0.0591,
                &["--noise", "0.02", "--seed", &s.to_string()],
            )
        })
        .collect();
    let out = era()
        .args(["friction", "estimate", "--stiffness", "1", "--json"])
        .args(&files)
        .output()
        .unwrap();
    assert_success(&out);
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let records = v["records"].as_array().unwrap();
    assert_eq!(records.len(), 4);
    for r in records {
        for key in [
            "file",
            "natural_frequency_hz",
            "cycles",
            "velocity_drop_per_cycle",
            "coulomb_force",
            "viscous_damping_ratio",
        ] {
            assert!(!r[key].is_null(), "{key}");
        }
        assert_eq!(r["better_model"], "coulomb");
    }
    let mean = v["coulomb_force_mean"].as_f64().unwrap();
    assert!((mean - 0.0591).abs() / 0.0591 < 0.03, "{mean}");
    assert!(v["coulomb_force_std"].as_f64().unwrap() > 0.0);
    assert!((v["natural_frequency_hz_mean"].as_f64().unwrap() - 1.5).abs() < 0.02);
}

#[test]
fn viscous_record_is_called_viscous() {
    let dir = tempfile::tempdir().unwrap();
    let f = decay(
        dir.path(),
        "v.csv",
        0.0,
        &["--viscous-damping-ratio", "0.02", "--duration", "12"],
    );
    let out = era()
        .args(["friction", "estimate", "--stiffness", "1", "--json"])
        .arg(&f)
        .output()
        .unwrap();
    assert_success(&out);
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["records"][0]["better_model"], "viscous");
}

#[test]
fn tune_from_a_model_and_from_records() {
    let out = era()
        .args([
            "friction",
            "tune",
            "--coulomb-force",
            "0.0591",
            "--stiffness",
            "1",
            "--json",
            "-q",
        ])
        .output()
        .unwrap();
    assert!(out.status.success());
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let neutral = v["neutral_coefficient"].as_f64().unwrap();
    assert!((neutral - 0.0591).abs() / 0.0591 < 0.02, "{neutral}");
    assert!((v["stability_margin"].as_f64().unwrap() - 0.15).abs() < 1e-12);

    let dir = tempfile::tempdir().unwrap();
    let f = decay(dir.path(), "d.csv", 0.0353, &[]);
    let out = era()
        .args(["friction", "tune", "--stiffness", "1", "--json", "-q"])
        .arg(&f)
        .output()
        .unwrap();
    assert_success(&out);
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!((v["neutral_coefficient"].as_f64().unwrap() - 0.0353).abs() / 0.0353 < 0.02);
    assert!(v["free_decay_estimate_margin"].as_f64().is_some());
}

#[test]
fn bad_records_exit_2_naming_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let write = |name: &str, text: String| {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    // Too few cycles: four half-cycles from a small release.
    let few = decay(d, "few.csv", 0.0591, &["--x0", "0.45"]);
    expect_input_error(
        &[
            "friction",
            "estimate",
            "--stiffness",
            "1",
            few.to_str().unwrap(),
        ],
        "too few cycles to fit",
    );
    // Never oscillates: actuator 9 of Table 5.1 (0.2824 lbf) from a small release.
    let stuck = decay(d, "stuck.csv", 0.2824, &["--x0", "0.9"]);
    expect_input_error(
        &[
            "friction",
            "estimate",
            "--stiffness",
            "1",
            stuck.to_str().unwrap(),
        ],
        "never oscillates",
    );
    expect_input_error(
        &[
            "friction",
            "estimate",
            "--stiffness",
            "1",
            stuck.to_str().unwrap(),
        ],
        "stuck.csv",
    );
    // Non-monotonic time and NaN, with the line.
    let good = std::fs::read_to_string(decay(d, "good.csv", 0.0591, &[])).unwrap();
    let mut lines: Vec<String> = good.lines().map(str::to_string).collect();
    let header = lines.iter().position(|l| l.starts_with("time_s")).unwrap();
    let mut back = lines.clone();
    back[header + 20] = back[header + 18].clone();
    let back = write("back.csv", back.join("\n"));
    expect_input_error(
        &["friction", "estimate", "--stiffness", "1", &back],
        "column time_s: time does not increase",
    );
    let cells: Vec<&str> = lines[header + 30].split(',').collect();
    lines[header + 30] = format!("{},NaN,{}", cells[0], cells[2]);
    let nan = write("nan.csv", lines.join("\n"));
    expect_input_error(
        &["friction", "estimate", "--stiffness", "1", &nan],
        &format!(
            "line {}, column velocity: NaN is not a finite number",
            header + 31
        ),
    );
    let missing = write("missing.csv", "time_s,force\n0,1\n".into());
    expect_input_error(
        &["friction", "estimate", "--stiffness", "1", &missing],
        "missing column",
    );
    expect_input_error(
        &["friction", "estimate", "--stiffness", "0", &missing],
        "--stiffness 0",
    );
    expect_input_error(
        &[
            "friction",
            "estimate",
            "--stiffness",
            "1",
            "/no/such/decay.csv",
        ],
        "/no/such/decay.csv",
    );
    expect_input_error(
        &[
            "friction",
            "simulate",
            "--coulomb-force",
            "-1",
            "--stiffness",
            "1",
            "--out",
            "x.csv",
        ],
        "coulomb-force",
    );
    expect_input_error(&["friction", "tune", "--stiffness", "1"], "--coulomb-force");
    expect_input_error(
        &[
            "friction",
            "tune",
            "--stiffness",
            "1",
            "--coulomb-force",
            "0.05",
            "--fraction",
            "1.5",
        ],
        "fraction",
    );
}

#[test]
fn a_closed_pipe_is_not_a_panic() {
    use std::process::{Command as Std, Stdio};
    let mut child = Std::new(assert_cmd::cargo::cargo_bin("era"))
        .args(["demo", "--json", "-q"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take()); // the reader goes away before anything is written
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(out.status.code(), Some(0), "{stderr}");
}

#[test]
fn timings_name_the_friction_stages() {
    for (args, stage) in [
        (
            vec![
                "friction",
                "tune",
                "--coulomb-force",
                "0.05",
                "--stiffness",
                "1",
            ],
            "tune",
        ),
        (
            vec![
                "friction",
                "simulate",
                "--coulomb-force",
                "0.05",
                "--stiffness",
                "1",
            ],
            "simulate",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out_file = dir.path().join("d.csv");
        let mut cmd = era();
        cmd.args(&args).args(["--timings", "--json"]);
        if stage == "simulate" {
            cmd.arg("--out").arg(&out_file);
        }
        let out = cmd.output().unwrap();
        assert_success(&out);
        let v: Value = serde_json::from_slice(&out.stdout).unwrap();
        assert!(v["timings_s"][stage].as_f64().is_some(), "{stage}");
        // The table on stderr lists the stage itself, not only the total.
        assert!(
            String::from_utf8_lossy(&out.stderr).contains(&format!("  {stage} ")),
            "{stage}"
        );
    }
}
