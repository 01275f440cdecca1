//! Table 5.2 of the thesis: the 4-mass truth model, identified with the thesis settings,
//! against the thesis's truth column, the exact model, and the Octave peer.

use crate::common;

use common::{read_csv, worst_match};
use era::identify::{identify, EraOptions};
use era::sim::{truth_model, truth_model_frf, TABLE_5_2_TRUTH};
use era::Complex64;

#[test]
fn no_noise_recovers_table_5_2_truth() {
    let frf = truth_model_frf(None).unwrap();
    let found = identify(&frf, &EraOptions::thesis_truth_model()).unwrap();
    assert_eq!(found.modal.modes.len(), 4);
    assert!(found.modal.real_poles.is_empty());
    for (mode, (f, z)) in found.modal.modes.iter().zip(TABLE_5_2_TRUTH) {
        assert!(
            (mode.frequency_hz - f).abs() < 0.01,
            "{} vs {f}",
            mode.frequency_hz
        );
        // The table prints ζ to 0.01 %, i.e. ±5e-5 as a fraction.
        assert!(
            (mode.damping_ratio - z / 100.0).abs() < 1e-4,
            "{} vs {z}",
            mode.damping_ratio
        );
    }
    // And to round-off against the exact continuous poles.
    let exact: Vec<Complex64> = truth_model()
        .poles()
        .unwrap()
        .into_iter()
        .filter(|s| s.im > 0.0)
        .collect();
    let ident: Vec<Complex64> = found
        .modal
        .modes
        .iter()
        .map(|m| m.continuous_pole)
        .collect();
    let err = worst_match(&exact, &ident);
    assert!(err < 1e-9, "relative pole error {err:e}");
    assert!(found.fit.collocated_mean_relative_error.unwrap() < 1e-9);
    assert!(found.fit.noncollocated_mean_relative_error.unwrap() < 1e-9);
}

fn octave_eigs(case: &str) -> Vec<Complex64> {
    let (_, rows) = read_csv("octave_truth_eigs_seed123456789.csv");
    rows.iter()
        .filter(|r| r[0] == case)
        .map(|r| Complex64::new(r[1].parse().unwrap(), r[2].parse().unwrap()))
        .collect()
}

#[test]
fn clean_and_noisy_runs_match_the_octave_peer() {
    // The peer's addnoise.m draws the same MINSTD stream, so the noisy FRFs are the
    // same to round-off and so must be the identified poles.
    let (_, sv_rows) = read_csv("octave_truth_sv_seed123456789.csv");
    for (case, noise) in [("clean", None), ("noise", Some((0.15, 123_456_789)))] {
        let frf = truth_model_frf(noise).unwrap();
        let found = identify(&frf, &EraOptions::thesis_truth_model()).unwrap();
        let poles = found.model.poles().unwrap();
        let err = worst_match(&octave_eigs(case), &poles);
        assert!(
            err < 1e-9,
            "{case}: eigenvalues differ from the peer by {err:e}"
        );
        let col = if case == "clean" { 1 } else { 2 };
        let sv = &found.realization.singular_values;
        assert_eq!(sv.len(), sv_rows.len());
        let s1 = sv[0];
        for (k, row) in sv_rows.iter().enumerate() {
            let peer: f64 = row[col].parse().unwrap();
            assert!(
                (sv[k] - peer).abs() <= 1e-10 * s1,
                "{case} sv {k}: {} vs {peer}",
                sv[k]
            );
        }
    }
}

#[test]
fn noisy_modes_match_the_peer_modal_table() {
    let (_, rows) = read_csv("octave_truth_modes_seed123456789.csv");
    let frf = truth_model_frf(Some((0.15, 123_456_789))).unwrap();
    let found = identify(&frf, &EraOptions::thesis_truth_model()).unwrap();
    for (mode, row) in found.modal.modes.iter().zip(&rows) {
        let f: f64 = row[5].parse().unwrap();
        let z: f64 = row[6].parse().unwrap();
        assert!((mode.frequency_hz - f).abs() < 1e-6 * f);
        assert!((100.0 * mode.damping_ratio - z).abs() < 1e-6);
    }
}

#[test]
fn the_kept_model_response_is_the_model_frf_on_the_measured_lines() {
    let frf = truth_model_frf(Some((0.15, 5))).unwrap();
    let found = identify(&frf, &EraOptions::thesis_truth_model()).unwrap();
    let again = era::pipeline::fit::model_frf(&found.model, &found.processed).unwrap();
    assert_eq!(again.values(), &found.model_response[..]);
}
