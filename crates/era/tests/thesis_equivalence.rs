//! The fast pipeline equals the naive reference of the thesis steps on a DTA-like set,
//! and recovers the structure's modes.

mod common;

use common::worst_match;
use era::identify::{identify, identify_naive, EraOptions};
use era::sim::{ModalSpec, ModalStructure};
use era::Quantity;

#[test]
fn dta_like_set_fast_equals_naive_reference() {
    // 8×8, 40 modes, acceleration, 801 lines at 0.025 Hz: the DTA analyzer's grid.
    let structure = ModalStructure::random(&ModalSpec::default()).unwrap();
    let frf = structure.frf(801, 0.025, Quantity::Acceleration).unwrap();
    let options = EraOptions::thesis_dta();
    let fast = identify(&frf, &options).unwrap();
    let naive = identify_naive(&frf, &options).unwrap();
    assert_eq!(fast.realization.hankel_size, (1592, 1592));
    let err = worst_match(&naive.model.poles().unwrap(), &fast.model.poles().unwrap());
    assert!(err <= 1e-8, "eigenvalues differ from the naive reference by {err:e}");
    let s1 = naive.realization.singular_values[0];
    for (a, b) in fast.realization.singular_values.iter().zip(&naive.realization.singular_values) {
        assert!((a - b).abs() <= 1e-12 * s1);
    }
    // The model is the structure: every true mode within 0.5 % in frequency (the peer's
    // README reports the same for the Octave routines).
    let mut matched = 0;
    for f_true in &structure.frequencies_hz {
        let nearest = fast
            .modal
            .modes
            .iter()
            .map(|m| (m.frequency_hz - f_true).abs() / f_true)
            .fold(f64::INFINITY, f64::min);
        matched += usize::from(nearest < 0.005);
    }
    assert_eq!(matched, 40, "true modes found within 0.5 %");
}
