//! Running the `era` binary in the CLI's tests, and the argument lists they repeat.
//!
//! The binary is the one Cargo builds for the calling test (`CARGO_BIN_EXE_era`, or the
//! target folder beside the test), so these helpers serve the tests of `era-cli`.

use assert_cmd::Command;
use std::path::{Path, PathBuf};

/// The thesis's settings for the 8-state truth model: Hankel factor 4 and the FRFs padded
/// to 1024 lines (a tenth of a second of response with a full set of outputs).
pub const TRUTH_SETTINGS: [&str; 4] = ["--hankel-factor", "4", "--pad-to", "1024"];

/// The thesis's settings for the DTA-like set at 80 states: Hankel factor 5, one
/// integration (accelerance to mobility), three zeroed lines, padded to 1024 lines.
pub const DTA_SETTINGS: [&str; 8] = [
    "--hankel-factor",
    "5",
    "--integrations",
    "1",
    "--zero-lines",
    "3",
    "--pad-to",
    "1024",
];

/// The `era` binary under test.
pub fn era() -> Command {
    Command::cargo_bin("era").expect("the era binary (run from era-cli's tests)")
}

/// A path as the `&str` an argument list takes (the tests' paths are UTF-8).
pub fn s(p: &Path) -> &str {
    p.to_str().expect("a UTF-8 path")
}

/// Asserts that a run succeeded, failing with its stderr.
#[track_caller]
pub fn assert_success(out: &std::process::Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Runs `era ARGS`, expects success (else fails with its stderr), and returns stdout.
#[track_caller]
pub fn stdout_of(args: &[&str]) -> String {
    let out = era().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("UTF-8 stdout")
}

/// Runs `era ARGS`, expects success, and parses its stdout as JSON (`--json` runs).
#[track_caller]
pub fn json_of(args: &[&str]) -> serde_json::Value {
    serde_json::from_str(&stdout_of(args)).expect("stdout is JSON")
}

/// Runs `era ARGS` and expects exit code 2 with `needle` in stderr, and no panic;
/// returns the stderr, for further checks.
#[track_caller]
pub fn expect_input_error(args: &[&str], needle: &str) -> String {
    let out = era().args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(
        stderr.contains(needle),
        "{args:?}: expected '{needle}' in: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    stderr
}

/// Writes the truth model's FRFs into `dir/truth.csv` with `era simulate truth-model`.
#[track_caller]
pub fn simulated_truth(dir: &Path) -> PathBuf {
    let frf = dir.join("truth.csv");
    era()
        .args(["simulate", "truth-model", "-q", "--out"])
        .arg(&frf)
        .assert()
        .success();
    frf
}

/// Writes `dir/name` with `era simulate modal -q ARGS --out dir/name` (`args`: the
/// structure, lines, noise and seed), expecting success.
#[track_caller]
pub fn simulate_modal(dir: &Path, name: &str, args: &[&str]) -> PathBuf {
    let path = dir.join(name);
    era()
        .args(["simulate", "modal", "-q"])
        .args(args)
        .arg("--out")
        .arg(&path)
        .assert()
        .success();
    path
}

/// A thesis-size set written to `dir/name` (8 x 8, 40 modes, collocated, 5 % noise),
/// whose `--states auto --refine` takes seconds.
#[track_caller]
pub fn dta_like_set(dir: &Path, name: &str) -> PathBuf {
    simulate_modal(dir, name, &["--collocated", "--noise", "0.05"])
}

/// The arguments of `era identify` of the truth model `frf` at `states` into `out`, at
/// [`TRUTH_SETTINGS`], quietly.
pub fn truth_identify(frf: &Path, states: &str, out: &Path) -> Vec<String> {
    let mut args = vec!["identify", s(frf), "--states", states];
    args.extend(TRUTH_SETTINGS);
    args.extend(["-q", "--out", s(out)]);
    args.into_iter().map(String::from).collect()
}
