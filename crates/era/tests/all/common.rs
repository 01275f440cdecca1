//! Helpers shared by the integration tests.
#![allow(dead_code)]

use era::Complex64;
use era_testkit::{assert_matches_naive, difference, Difference, Scale};
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

/// `found` reordered to pair with `expected` one to one, each expected value taking the
/// nearest value left, after checking both lists have the same length.
pub fn paired(expected: &[Complex64], found: &[Complex64]) -> Vec<Complex64> {
    assert_eq!(expected.len(), found.len(), "eigenvalue counts differ");
    let mut left: Vec<Complex64> = found.to_vec();
    expected
        .iter()
        .map(|e| {
            let (k, _) = left
                .iter()
                .enumerate()
                .map(|(k, f)| (k, (f - e).norm()))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap();
            left.swap_remove(k)
        })
        .collect()
}

/// Eigenvalues `found` against the `expected` ones, paired nearest first ([`paired`]):
/// the distances relative to `max(1, |expected|)`.
pub fn eigenvalue_difference(expected: &[Complex64], found: &[Complex64]) -> Difference {
    difference(&paired(expected, found), expected, Scale::Mixed(1.0))
}

/// Asserts that the eigenvalues `found` by a fast path match its reference's `expected`
/// ones within `tol` (see [`eigenvalue_difference`]).
#[track_caller]
pub fn assert_eigenvalues_match(what: &str, found: &[Complex64], expected: &[Complex64], tol: f64) {
    assert_matches_naive(
        what,
        &paired(expected, found),
        expected,
        Scale::Mixed(1.0),
        tol,
    );
}

/// Largest distance from each expected value to its nearest found value, relative to
/// `max(1, |expected|)`, after checking both lists have the same length.
pub fn worst_match(expected: &[Complex64], found: &[Complex64]) -> f64 {
    eigenvalue_difference(expected, found).worst
}
