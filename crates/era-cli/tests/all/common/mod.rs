//! Helpers shared by the CLI tests.
#![allow(dead_code)]

use assert_cmd::Command;
use std::path::{Path, PathBuf};

/// The `era` binary under test.
pub fn era() -> Command {
    Command::cargo_bin("era").unwrap()
}

/// A path as the `&str` an argument list takes (the tests' paths are UTF-8).
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Writes the truth model's FRFs into `dir/truth.csv` with `era simulate truth-model`.
pub fn simulated_truth(dir: &Path) -> PathBuf {
    let frf = dir.join("truth.csv");
    era()
        .args(["simulate", "truth-model", "-q", "--out"])
        .arg(&frf)
        .assert()
        .success();
    frf
}

/// A thesis-size set written to `dir/name` (8 x 8, 40 modes, collocated, 5 % noise),
/// whose `--states auto --refine` takes seconds.
pub fn dta_like_set(dir: &Path, name: &str) -> PathBuf {
    let path = dir.join(name);
    era()
        .args([
            "simulate",
            "modal",
            "--collocated",
            "--noise",
            "0.05",
            "-q",
            "--out",
        ])
        .arg(&path)
        .assert()
        .success();
    path
}

/// Runs `era`, expects success, and parses its stdout as JSON (`--json` runs).
#[track_caller]
pub fn json_of(args: &[&str]) -> serde_json::Value {
    let out = era().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// Runs `era` and expects exit code 2 with `needle` in stderr, and no panic.
pub fn expect_input_error(args: &[&str], needle: &str) {
    let out = era().args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(
        stderr.contains(needle),
        "{args:?}: expected '{needle}' in: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
}

/// A file under the workspace's `data/` folder (the real data sets shipped with the repo,
/// see data/README.md). A missing file fails the test with its path: the data tests never
/// skip silently.
#[track_caller]
pub fn data_file(rel: &str) -> PathBuf {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data")
        .join(rel);
    assert!(
        p.is_file(),
        "data file {} is missing: the repository's data/ folder should hold it (see data/README.md)",
        p.display()
    );
    p
}

/// One-to-one matching of `found` frequencies to `truth` within `tolerance` (relative),
/// nearest pairs first: the matched (truth index, found index) pairs and the found
/// indices left over (spurious).
pub fn match_frequencies(
    truth: &[f64],
    found: &[f64],
    tolerance: f64,
) -> (Vec<(usize, usize)>, Vec<usize>) {
    let mut pairs = Vec::new();
    for (i, t) in truth.iter().enumerate() {
        for (j, f) in found.iter().enumerate() {
            let rel = (f - t).abs() / t;
            if rel <= tolerance {
                pairs.push((rel, i, j));
            }
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut ti, mut fj) = (vec![false; truth.len()], vec![false; found.len()]);
    let mut out = Vec::new();
    for (_, i, j) in pairs {
        if !ti[i] && !fj[j] {
            ti[i] = true;
            fj[j] = true;
            out.push((i, j));
        }
    }
    let left = (0..found.len()).filter(|&j| !fj[j]).collect();
    (out, left)
}

/// The DaISy subframe's 14 indicative frequencies, Hz (its PROVENANCE: spectral peaks,
/// about ±0.1 Hz).
pub const DAISY_REFERENCE_HZ: [f64; 14] = [
    62.1, 119.0, 154.7, 192.5, 215.0, 229.5, 239.3, 286.8, 321.2, 334.1, 352.2, 398.1, 417.5, 467.2,
];

/// How many of [`DAISY_REFERENCE_HZ`] lie within 0.5 Hz of one of `found`, and the
/// frequencies of `found` that match none.
pub fn daisy_hits(found: &[f64]) -> (usize, Vec<f64>) {
    let near = |a: f64, b: f64| (a - b).abs() < 0.5;
    let hits = DAISY_REFERENCE_HZ
        .iter()
        .filter(|r| found.iter().any(|f| near(*f, **r)))
        .count();
    let extra = found
        .iter()
        .copied()
        .filter(|f| !DAISY_REFERENCE_HZ.iter().any(|r| near(*f, *r)))
        .collect();
    (hits, extra)
}

/// `era identify --from-time` on the DaISy subframe (inputs 1–2, outputs 3–30, 1024 Hz),
/// then `extra`, as JSON (the run must succeed).
#[track_caller]
pub fn daisy_json(extra: &[&str]) -> serde_json::Value {
    let mat = data_file("daisy-steel-subframe/flexible_structure_dat.mat");
    let mut args = vec![
        "identify",
        "--from-time",
        s(&mat),
        "--inputs",
        "1,2",
        "--outputs",
        "3-30",
        "--sample-rate",
        "1024",
    ];
    args.extend_from_slice(extra);
    json_of(&args)
}

/// (frequency Hz, damping ratio) of the modes of a JSON (`model.json`, or the truth
/// `era simulate ... --json` prints), all of them or the physical ones.
pub fn modes_of(v: &serde_json::Value, only_physical: bool) -> Vec<(f64, f64)> {
    v["modes"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| !only_physical || m["physical"].as_bool().unwrap())
        .map(|m| {
            (
                m["frequency_hz"].as_f64().unwrap(),
                m["damping_ratio"].as_f64().unwrap(),
            )
        })
        .collect()
}

pub mod hostile;

/// The arguments of `era identify` of the truth model `frf` at `states` into `out`, at the
/// thesis's truth-model settings: a run of a tenth of a second with a full set of outputs.
pub fn truth_identify(frf: &Path, states: &str, out: &Path) -> Vec<String> {
    [
        "identify",
        s(frf),
        "--states",
        states,
        "--hankel-factor",
        "4",
        "--pad-to",
        "1024",
        "-q",
        "--out",
        s(out),
    ]
    .map(String::from)
    .to_vec()
}
