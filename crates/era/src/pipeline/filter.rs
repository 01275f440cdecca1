//! Zero-phase Butterworth low-pass on the impulse responses (docs/src/design.md §1.6; thesis
//! `butter` + `filtfilt` in `frffilt`).
//!
//! The design and the forward–backward filtering come from `sci-rs`, a port of
//! `scipy.signal`: `butter(order, 2·fc·Ts, output='sos')` and `sosfiltfilt`. Working in
//! second-order sections is better conditioned than the thesis's `[b, a]` form at high
//! orders and low cut-offs.
//!
//! **Edge handling** (scipy's `sosfiltfilt` default): the signal is extended at both
//! ends by odd reflection about its end values, `3·(2·sections + 1)` samples each side
//! (fewer when sections have zero trailing coefficients), and each pass starts from the
//! steady-state initial conditions of `sosfilt_zi` scaled by the first sample. The
//! extension is removed afterwards. Golden values in `tests/golden/` were made by
//! `scripts/make_filter_golden.py` with scipy.

use crate::error::{EraError, Result};
use sci_rs::signal::filter::design::{
    butter_dyn, DigitalFilter, FilterBandType, FilterOutputType, Sos,
};
use sci_rs::signal::filter::sosfiltfilt_dyn;

/// The normalised cut-off (`2·fc·Ts`, 1 = Nyquist) must lie in
/// `[MIN_NORMALISED_CUTOFF, 1 − MIN_NORMALISED_CUTOFF]`. Closer to 0 or to Nyquist the
/// bilinear transform puts the poles so near `z = ±1` that sci-rs's pairing of poles
/// into sections fails an internal assertion (a panic at `1e-300`) or the sections lose
/// every digit (NaN impulse responses at `1e-10`). 10⁻⁴ of Nyquist is far below any
/// useful low-pass of an impulse response.
pub const MIN_NORMALISED_CUTOFF: f64 = 1e-4;

/// A zero-phase low-pass Butterworth filter.
#[derive(Debug, Clone)]
pub struct LowPass {
    sections: Vec<Sos<f64>>,
    order: usize,
    cutoff_hz: f64,
}

impl LowPass {
    /// Designs an order-`order` digital Butterworth low-pass with cut-off `cutoff_hz` for
    /// samples `sample_time_s` apart (normalised cut-off `2·fc·Ts`, 1 = Nyquist).
    ///
    /// # Errors
    /// [`EraError::InvalidParameter`] when the order is 0 or above 20, the sample time is
    /// not positive, or the cut-off is not between 0 and the Nyquist frequency `1/(2·Ts)`
    /// with the margin [`MIN_NORMALISED_CUTOFF`] (checked before sci-rs sees it).
    pub fn design(order: usize, cutoff_hz: f64, sample_time_s: f64) -> Result<Self> {
        if order == 0 || order > 20 {
            return Err(EraError::InvalidParameter {
                name: "lowpass_order",
                value: order.to_string(),
                reason: "the Butterworth order must be 1 to 20".into(),
            });
        }
        if !(sample_time_s.is_finite() && sample_time_s > 0.0) {
            return Err(EraError::InvalidParameter {
                name: "sample_time",
                value: sample_time_s.to_string(),
                reason: "the impulse responses need a positive, finite sample time".into(),
            });
        }
        let normalised = 2.0 * cutoff_hz * sample_time_s;
        let nyquist = 0.5 / sample_time_s;
        if !(MIN_NORMALISED_CUTOFF..=1.0 - MIN_NORMALISED_CUTOFF).contains(&normalised) {
            return Err(EraError::InvalidParameter {
                name: "lowpass_hz",
                value: cutoff_hz.to_string(),
                reason: format!(
                    "the cut-off must lie between {} Hz and {} Hz ({MIN_NORMALISED_CUTOFF} to {} of the Nyquist frequency {nyquist} Hz)",
                    six_digits(MIN_NORMALISED_CUTOFF * nyquist),
                    six_digits((1.0 - MIN_NORMALISED_CUTOFF) * nyquist),
                    1.0 - MIN_NORMALISED_CUTOFF,
                ).into(),
            });
        }
        let filter = butter_dyn(
            order,
            vec![normalised],
            Some(FilterBandType::Lowpass),
            Some(false),
            Some(FilterOutputType::Sos),
            None,
        );
        let DigitalFilter::Sos(sos) = filter else {
            return Err(EraError::Numerical(
                "Butterworth design did not return sections".into(),
            ));
        };
        let finite = sos
            .sos
            .iter()
            .all(|s| s.b.iter().chain(s.a.iter()).all(|c| c.is_finite()));
        if !finite {
            return Err(EraError::InvalidParameter {
                name: "lowpass_hz",
                value: cutoff_hz.to_string(),
                reason: crate::params::names::Prose::from(format!("the order-{order} Butterworth design at this cut-off is not finite: raise the cut-off or lower "))
                    .param(crate::params::names::Param::LowpassOrder),
            });
        }
        Ok(LowPass {
            sections: sos.sos,
            order,
            cutoff_hz,
        })
    }

    /// Filter order.
    pub fn order(&self) -> usize {
        self.order
    }
    /// Cut-off, Hz.
    pub fn cutoff_hz(&self) -> f64 {
        self.cutoff_hz
    }

    /// Samples of odd extension added at each end by [`LowPass::apply`].
    pub fn edge_samples(&self) -> usize {
        let n = self.sections.len();
        let bzeros = self.sections.iter().filter(|s| s.b[2] == 0.0).count();
        let azeros = self.sections.iter().filter(|s| s.a[2] == 0.0).count();
        3 * (2 * n + 1 - bzeros.min(azeros))
    }

    /// Filters forward and backward (zero phase), like scipy's `sosfiltfilt`.
    ///
    /// # Errors
    /// [`EraError::InvalidParameter`] when the signal is not longer than the edge
    /// extension ([`LowPass::edge_samples`]).
    pub fn apply(&self, signal: &[f64]) -> Result<Vec<f64>> {
        let edge = self.edge_samples();
        if signal.len() <= edge {
            return Err(EraError::InvalidParameter {
                name: "lowpass_order",
                value: self.order.to_string(),
                reason: format!(
                    "zero-phase filtering needs more than {edge} samples, the impulse response has {}",
                    signal.len()
                ).into(),
            });
        }
        let out = sosfiltfilt_dyn(signal.iter(), &self.sections);
        if out.iter().any(|x| !x.is_finite()) {
            return Err(EraError::InvalidParameter {
                name: "lowpass_hz",
                value: self.cutoff_hz.to_string(),
                reason: crate::params::names::Prose::from(format!(
                    "the order-{} filter turned the impulse response into non-finite values: raise the cut-off or lower ",
                    self.order
                ))
                .param(crate::params::names::Param::LowpassOrder),
            });
        }
        Ok(out)
    }
}

/// `x` to 6 significant digits, without trailing zeros (`1.28`, `12798.7`), or in
/// exponent form outside 1e-3 … 1e6.
fn six_digits(x: f64) -> String {
    if x == 0.0 || !(1e-3..1e6).contains(&x.abs()) {
        return format!("{x:.5e}");
    }
    let decimals = (5 - x.abs().log10().floor() as i32).clamp(0, 8) as usize;
    let text = format!("{x:.decimals$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cutoffs_outside_the_margin_are_refused_before_sci_rs() {
        // 1e-300 Hz made sci-rs panic; 1e-10 Hz gave NaN impulse responses.
        for hz in [
            1e-300,
            1e-10,
            0.0,
            -1.0,
            f64::NAN,
            f64::INFINITY,
            0.5,
            1e300,
        ] {
            let e = LowPass::design(4, hz, 1.0).unwrap_err();
            assert!(e.to_string().contains("lowpass_hz"), "{hz}: {e}");
        }
        assert!(LowPass::design(4, 0.1, f64::NAN).is_err());
        assert!(LowPass::design(4, 0.1, 0.0).is_err());
        // The band's edges read as numbers a person writes.
        let e = LowPass::design(4, 1e9, 1.0 / 25600.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("between 1.28 Hz and 12798.7 Hz"), "{e}");
        assert_eq!(six_digits(0.00123456789), "0.00123457");
        assert_eq!(six_digits(0.000123456789), "1.23457e-4");
        assert_eq!(six_digits(2.5e-7), "2.50000e-7");
        assert_eq!(six_digits(100.0), "100");
    }

    #[test]
    fn every_order_is_finite_across_the_allowed_band() {
        // The edges of the allowed band and a few decades between, at every order: no
        // panic inside sci-rs, finite sections, a finite filtered impulse.
        let mut impulse = vec![0.0; 4000];
        impulse[10] = 1.0;
        let lo = MIN_NORMALISED_CUTOFF;
        for order in 1..=20 {
            for normalised in [lo, 1e-3, 1e-2, 0.1, 0.5, 0.9, 1.0 - lo] {
                let f = LowPass::design(order, normalised / 2.0, 1.0)
                    .unwrap_or_else(|e| panic!("order {order} at {normalised}: {e}"));
                let out = f.apply(&impulse).unwrap();
                assert!(
                    out.iter().all(|x| x.is_finite()),
                    "order {order} at {normalised}"
                );
            }
        }
    }
}
