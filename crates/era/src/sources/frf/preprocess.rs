//! FRF preprocessing before the inverse FFT: docs/src/design.md §1 steps 1–4 (the thesis's
//! `frffilt`, Appendix J.1.1, and `frfinter`, J.1.4).

use crate::data::frf::{uniform_lines, FrfData};
use crate::error::{EraError, Result};
use num_complex::Complex64;

/// Integrates every FRF `times` times: `G(f_k) ← G(f_k) / (j·2πf_k)` for `k ≥ 1` and
/// `G(f_0) ← 0` (docs/src/design.md §1.1). Acceleration becomes velocity, velocity displacement.
///
/// Because [`FrfData`] guarantees `f_0 = 0`, the thesis's `frfinter` first-line bug
/// (it divides by the last ω when `f_0 ≠ 0`) cannot arise.
///
/// # Errors
/// [`EraError::InvalidParameter`] when integrating past displacement.
pub fn integrate(frf: &FrfData, times: usize) -> Result<FrfData> {
    let mut quantity = frf.quantity();
    for _ in 0..times {
        quantity = quantity
            .integrated()
            .ok_or_else(|| EraError::InvalidParameter {
                name: "integrations",
                value: times.to_string(),
                reason: format!("{} FRFs cannot be integrated {times} times", frf.quantity())
                    .into(),
            })?;
    }
    if times == 0 {
        return Ok(frf.clone());
    }
    let lines = frf.lines();
    let freq = frf.frequency_hz();
    let mut values = frf.values().to_vec();
    for pair in values.chunks_mut(lines) {
        pair[0] = Complex64::new(0.0, 0.0);
        for k in 1..lines {
            let jw = Complex64::new(0.0, 2.0 * std::f64::consts::PI * freq[k]);
            let mut g = pair[k];
            for _ in 0..times {
                g /= jw;
            }
            pair[k] = g;
        }
    }
    FrfData::new(freq.to_vec(), frf.outputs(), frf.inputs(), values, quantity)
}

/// Pads with zero lines up to `pad_to + 1` lines (docs/src/design.md §1.2; thesis `ndpts`).
/// `pad_to = 0`, or `pad_to + 1 ≤ L`, leaves the data as it is.
pub(crate) fn pad(frf: &FrfData, pad_to: usize) -> FrfData {
    let lines = frf.lines();
    if pad_to == 0 || pad_to < lines {
        return frf.clone();
    }
    let new_lines = pad_to + 1;
    let zero = Complex64::new(0.0, 0.0);
    let mut values = Vec::with_capacity(frf.outputs() * frf.inputs() * new_lines);
    for pair in frf.values().chunks(lines) {
        values.extend_from_slice(pair);
        values.resize(values.len() + new_lines - lines, zero);
    }
    let freq = uniform_lines(new_lines, frf.spacing_hz());
    FrfData::new(freq, frf.outputs(), frf.inputs(), values, frf.quantity())
        .expect("padding a valid FrfData keeps it valid")
}

/// Sample time of the impulse responses, `Ts = 1 / (2·Δf·(N − 1))` (docs/src/design.md §1.3):
/// `N` lines span 0 … Nyquist.
pub fn sample_time_s(spacing_hz: f64, lines: usize) -> f64 {
    1.0 / (2.0 * spacing_hz * (lines as f64 - 1.0))
}

/// Sets the first `count` lines of every FRF to zero (docs/src/design.md §1.4; thesis `nz`, used
/// to drop the large low-frequency accelerations of the DTA).
pub fn zero_leading_lines(frf: &FrfData, count: usize) -> FrfData {
    if count == 0 {
        return frf.clone();
    }
    let lines = frf.lines();
    let mut values = frf.values().to_vec();
    for pair in values.chunks_mut(lines) {
        for v in pair.iter_mut().take(count) {
            *v = Complex64::new(0.0, 0.0);
        }
    }
    frf.with_values(values)
        .expect("zeroing lines keeps the data valid")
}

/// The FRFs as the inverse FFT sees them, with the sample time they imply.
#[derive(Debug, Clone)]
pub struct Preprocessed {
    /// Integrated, padded and zeroed FRFs (`N` lines).
    pub frf: FrfData,
    /// `Ts` of §1.3, seconds.
    pub sample_time_s: f64,
    /// Lines of the measurement before padding, `L`.
    pub measured_lines: usize,
}

/// Steps 1–4 of docs/src/design.md §1 in the thesis's order: integrate, pad, sample time, zero.
///
/// # Errors
/// From [`integrate`]; [`EraError::InvalidParameter`] when `zero_lines` removes every
/// measured line; [`EraError::Limit`] when `pad_to + 1` lines exceed
/// [`crate::params::limits::LINES`] or the padded set exceeds [`crate::params::limits::VALUES`] (checked
/// before anything is allocated).
pub fn preprocess(
    frf: &FrfData,
    integrations: usize,
    pad_to: usize,
    zero_lines: usize,
) -> Result<Preprocessed> {
    if zero_lines >= frf.lines() {
        return Err(EraError::InvalidParameter {
            name: "zero_lines",
            value: zero_lines.to_string(),
            reason: format!("the data has only {} lines", frf.lines()).into(),
        });
    }
    if pad_to != 0 && pad_to.saturating_add(1) < frf.lines() {
        return Err(EraError::InvalidParameter {
            name: "pad_to",
            value: pad_to.to_string(),
            reason: format!(
                "padding to {} lines would truncate the {} measured lines (use 0 for no padding)",
                pad_to + 1,
                frf.lines()
            )
            .into(),
        });
    }
    if pad_to != 0 {
        // pad_to + 1 lines per pair, without wrapping at usize::MAX.
        let lines = (pad_to as u64).saturating_add(1);
        crate::params::limits::LINES.check("pad_to", lines)?;
        crate::params::limits::VALUES.check_product(
            "pad-to (outputs x inputs x lines)",
            &[frf.outputs() as u64, frf.inputs() as u64, lines],
        )?;
    }
    let integrated = integrate(frf, integrations)?;
    let padded = pad(&integrated, pad_to);
    let ts = sample_time_s(padded.spacing_hz(), padded.lines());
    let zeroed = zero_leading_lines(&padded, zero_lines);
    Ok(Preprocessed {
        frf: zeroed,
        sample_time_s: ts,
        measured_lines: frf.lines(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::frf::Quantity;

    #[test]
    fn integration_divides_by_j_omega_and_zeros_dc() {
        let f = uniform_lines(3, 1.0);
        let d = FrfData::from_fn(f, 1, 1, Quantity::Acceleration, |_, _, _| {
            Complex64::new(1.0, 0.0)
        })
        .unwrap();
        let v = integrate(&d, 1).unwrap();
        assert_eq!(v.quantity(), Quantity::Velocity);
        assert_eq!(v.pair(0, 0)[0], Complex64::new(0.0, 0.0));
        let expected = Complex64::new(0.0, -1.0 / (2.0 * std::f64::consts::PI * 2.0));
        assert!((v.pair(0, 0)[2] - expected).norm() < 1e-15);
        assert!(integrate(&d, 3).is_err());
    }

    #[test]
    fn huge_padding_is_refused_before_allocating() {
        let d = FrfData::from_fn(
            uniform_lines(9, 1.0),
            2,
            2,
            Quantity::Acceleration,
            |_, _, _| Complex64::new(1.0, 0.0),
        )
        .unwrap();
        for pad_to in [usize::MAX - 1, usize::MAX, 100_000_000] {
            match preprocess(&d, 0, pad_to, 0) {
                Err(EraError::Limit(e)) => {
                    assert_eq!(e.context.to_string(), "pad_to");
                    assert!(e.asked > e.allowed, "{e}");
                }
                other => panic!("pad-to {pad_to}: {other:?}"),
            }
        }
        assert!(preprocess(&d, 0, 16, 0).is_ok());
    }

    #[test]
    fn dta_settings_give_thesis_sample_time() {
        // 801 lines at 0.025 Hz padded to 1025 lines: Ts = 1/51.2 s (thesis §4.5).
        let d = FrfData::from_fn(
            uniform_lines(801, 0.025),
            1,
            1,
            Quantity::Acceleration,
            |_, _, _| Complex64::new(1.0, 1.0),
        )
        .unwrap();
        let p = preprocess(&d, 1, 1024, 3).unwrap();
        assert_eq!(p.frf.lines(), 1025);
        assert!((p.sample_time_s - 1.0 / 51.2).abs() < 1e-15);
        assert_eq!(p.frf.pair(0, 0)[2], Complex64::new(0.0, 0.0));
        assert_ne!(p.frf.pair(0, 0)[3], Complex64::new(0.0, 0.0));
        assert_eq!(p.frf.pair(0, 0)[900], Complex64::new(0.0, 0.0));
    }
}
