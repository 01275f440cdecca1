//! Zero-phase Butterworth low-pass on the impulse responses (DESIGN.md §1.6; thesis
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
    /// [`EraError::InvalidParameter`] when the order is 0 or above 20, or the cut-off is
    /// not strictly between 0 and the Nyquist frequency `1/(2·Ts)`.
    pub fn design(order: usize, cutoff_hz: f64, sample_time_s: f64) -> Result<Self> {
        if order == 0 || order > 20 {
            return Err(EraError::InvalidParameter {
                name: "lowpass-order",
                value: order.to_string(),
                reason: "the Butterworth order must be 1 to 20".into(),
            });
        }
        let normalised = 2.0 * cutoff_hz * sample_time_s;
        if !(normalised > 0.0 && normalised < 1.0) {
            return Err(EraError::InvalidParameter {
                name: "lowpass-hz",
                value: cutoff_hz.to_string(),
                reason: format!(
                    "the cut-off must lie strictly between 0 and the Nyquist frequency {} Hz",
                    0.5 / sample_time_s
                ),
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
                name: "lowpass-order",
                value: self.order.to_string(),
                reason: format!(
                    "zero-phase filtering needs more than {edge} samples, the impulse response has {}",
                    signal.len()
                ),
            });
        }
        Ok(sosfiltfilt_dyn(signal.iter(), &self.sections))
    }
}
