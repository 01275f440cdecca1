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

pub mod hostile;
