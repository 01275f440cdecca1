//! Helpers shared by the integration tests.
#![allow(dead_code)]

use era::Complex64;
use std::path::PathBuf;

/// Path of a golden file.
pub fn golden(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("golden")
        .join(name)
}

/// Reads a golden CSV of this crate: skips `#` lines, returns the header and the rows as
/// strings.
pub fn read_csv(name: &str) -> (Vec<String>, Vec<Vec<String>>) {
    era_testkit::files::read_golden_csv(golden(name))
}

/// Largest distance from each expected value to its nearest found value, relative to
/// `max(1, |expected|)`, after checking both lists have the same length.
pub fn worst_match(expected: &[Complex64], found: &[Complex64]) -> f64 {
    assert_eq!(expected.len(), found.len(), "eigenvalue counts differ");
    let mut left: Vec<Complex64> = found.to_vec();
    let mut worst: f64 = 0.0;
    for e in expected {
        let (k, d) = left
            .iter()
            .enumerate()
            .map(|(k, f)| (k, (f - e).norm()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        left.swap_remove(k);
        worst = worst.max(d / e.norm().max(1.0));
    }
    worst
}
