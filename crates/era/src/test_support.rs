//! Data the unit tests of several modules build alike.

use crate::{Complex64, FrfData, Quantity};

/// Receptance of modes `(f Hz, ζ)` with unit residues, one output and one input, on
/// `lines` lines at `df` Hz from 0 Hz.
pub(crate) fn receptance(modes: &[(f64, f64)], df: f64, lines: usize) -> FrfData {
    let f: Vec<f64> = (0..lines).map(|k| k as f64 * df).collect();
    let v = f
        .iter()
        .map(|&h| {
            let w = 2.0 * std::f64::consts::PI * h;
            modes
                .iter()
                .map(|&(fn_hz, zeta)| {
                    let wn = 2.0 * std::f64::consts::PI * fn_hz;
                    Complex64::new(1.0, 0.0) / Complex64::new(wn * wn - w * w, 2.0 * zeta * wn * w)
                })
                .sum()
        })
        .collect();
    FrfData::new(f, 1, 1, v, Quantity::Displacement).unwrap()
}
