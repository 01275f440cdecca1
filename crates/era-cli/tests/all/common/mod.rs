//! Helpers shared by the CLI tests: what only these tests use. The ones every crate's
//! tests share (the binary, data files, argument lists, JSON readers) are in era-testkit.
#![allow(dead_code)]

pub use era_testkit::cli::{
    assert_success, dta_like_set, era, expect_input_error, json_of, s, simulate_modal,
    simulated_truth, stdout_of, truth_identify, DTA_SETTINGS, TRUTH_SETTINGS,
};
pub use era_testkit::data_file;
pub use era_testkit::files::{modes_of, read, write};

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

pub mod hostile;
