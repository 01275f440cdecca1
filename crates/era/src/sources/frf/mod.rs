//! FRF → impulse response → Markov parameters (docs/src/design.md §1.5).
//!
//! Each FRF of `N` lines (0 … Nyquist) is extended to a Hermitian spectrum of
//! `n = 2(N − 1)` points and inverse-transformed *with* the `1/n` factor, exactly as
//! MATLAB's `h = real(ifft(mirror(G)))` of the thesis. Taking the real part there discards
//! the imaginary parts of the DC and Nyquist lines (which a mirror cannot make
//! Hermitian); here those are set to zero before a real inverse FFT (`realfft`), which
//! is the same thing. The plan comes from `crate::linalg::fft::real_fft_plans`, made once
//! per length per process. Sample `h[k]` is the Markov block `Y_k`: `Y_0` is the direct
//! term and `Y_k = C A^(k-1) B` for `k ≥ 1`.

pub mod preprocess;

use crate::data::frf::FrfData;
use crate::error::{EraError, Result};
use num_complex::Complex64;

/// What the blocks of a [`MarkovSequence`] are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum MarkovKind {
    /// Impulse-response blocks `Y_0 = D`, `Y_k = C A^(k−1) B` of a system whose inputs
    /// were measured (the FRFs' inverse transform, OKID).
    #[default]
    Impulse,
    /// Output correlation blocks `R_k = E[y_(t+k) y_refᵀ]` against reference outputs
    /// (output-only data: they decay as `C A^(k−1) G`, with `G` in place of `B`).
    Correlation,
}

/// A sequence of q×p Markov blocks `Y_0, Y_1, …, Y_(K-1)`, `sample_time_s` apart, and
/// what they are ([`MarkovKind`]): what every source hands the pipeline.
///
/// Storage is "woven" per input: for input `j`, the values `Y_k[i][j]` run output-fastest,
/// then sample (`data[j·K·q + k·q + i]`). One block-Hankel column is then one contiguous
/// slice, which is what makes [`crate::pipeline::hankel`] a sequence of copies.
///
/// A sequence is built with a sample time of 1 s and of [`MarkovKind::Impulse`]; a source
/// says its own with [`MarkovSequence::with_sample_time`] and [`MarkovSequence::with_kind`].
#[derive(Debug, Clone, PartialEq)]
pub struct MarkovSequence {
    outputs: usize,
    inputs: usize,
    samples: usize,
    data: Vec<f64>,
    sample_time_s: f64,
    kind: MarkovKind,
}

impl MarkovSequence {
    /// All-zero sequence.
    pub fn zeros(outputs: usize, inputs: usize, samples: usize) -> Self {
        MarkovSequence {
            outputs,
            inputs,
            samples,
            data: vec![0.0; outputs * inputs * samples],
            sample_time_s: 1.0,
            kind: MarkovKind::Impulse,
        }
    }

    /// The same blocks, `sample_time_s` seconds apart.
    #[must_use]
    pub fn with_sample_time(mut self, sample_time_s: f64) -> Self {
        self.sample_time_s = sample_time_s;
        self
    }

    /// The same blocks, of `kind`.
    #[must_use]
    pub fn with_kind(mut self, kind: MarkovKind) -> Self {
        self.kind = kind;
        self
    }

    /// Seconds between blocks.
    pub fn sample_time_s(&self) -> f64 {
        self.sample_time_s
    }

    /// What the blocks are.
    pub fn kind(&self) -> MarkovKind {
        self.kind
    }

    /// Builds from one time series per output/input pair, pairs in `[output][input]`
    /// order, each of the same length.
    ///
    /// # Panics
    /// If the number of series is not `outputs·inputs` or their lengths differ.
    #[track_caller]
    pub fn from_pair_series(outputs: usize, inputs: usize, series: &[Vec<f64>]) -> Self {
        assert_eq!(series.len(), outputs * inputs, "one series per pair");
        let samples = series.first().map_or(0, Vec::len);
        let mut m = Self::zeros(outputs, inputs, samples);
        for i in 0..outputs {
            for j in 0..inputs {
                let s = &series[i * inputs + j];
                assert_eq!(s.len(), samples, "series lengths differ");
                for (k, v) in s.iter().enumerate() {
                    m.set(k, i, j, *v);
                }
            }
        }
        m
    }

    /// Builds from a function of (sample, output, input).
    pub fn from_fn(
        outputs: usize,
        inputs: usize,
        samples: usize,
        mut value: impl FnMut(usize, usize, usize) -> f64,
    ) -> Self {
        let mut m = Self::zeros(outputs, inputs, samples);
        for k in 0..samples {
            for i in 0..outputs {
                for j in 0..inputs {
                    m.set(k, i, j, value(k, i, j));
                }
            }
        }
        m
    }

    /// Outputs `q`.
    pub fn outputs(&self) -> usize {
        self.outputs
    }
    /// Inputs `p`.
    pub fn inputs(&self) -> usize {
        self.inputs
    }
    /// Number of samples `K` (blocks `Y_0 … Y_(K-1)`).
    pub fn samples(&self) -> usize {
        self.samples
    }
    /// `Y_k[i][j]`.
    #[inline]
    pub fn get(&self, sample: usize, output: usize, input: usize) -> f64 {
        self.data[(input * self.samples + sample) * self.outputs + output]
    }
    /// Sets `Y_k[i][j]`.
    #[inline]
    pub fn set(&mut self, sample: usize, output: usize, input: usize, value: f64) {
        self.data[(input * self.samples + sample) * self.outputs + output] = value;
    }
    /// For input `j`, the samples `first .. first+count` of all outputs, output-fastest:
    /// one block-Hankel column.
    #[inline]
    pub(crate) fn input_run(&self, input: usize, first: usize, count: usize) -> &[f64] {
        let start = (input * self.samples + first) * self.outputs;
        &self.data[start..start + count * self.outputs]
    }
    /// Time series of one pair.
    pub fn pair_series(&self, output: usize, input: usize) -> Vec<f64> {
        (0..self.samples)
            .map(|k| self.get(k, output, input))
            .collect()
    }
    /// The q×p block `Y_k` as row-major nested vectors.
    pub fn block(&self, sample: usize) -> Vec<Vec<f64>> {
        (0..self.outputs)
            .map(|i| (0..self.inputs).map(|j| self.get(sample, i, j)).collect())
            .collect()
    }
}

/// Impulse responses of every pair, `[output][input]` order, each of `2(N−1)` samples,
/// by a real inverse FFT with the `1/n` factor (MATLAB `real(ifft(mirror(G)))`).
///
/// # Errors
/// [`EraError::TooFewLines`] for fewer than 2 lines (cannot happen for a valid
/// [`FrfData`]).
pub(crate) fn impulse_responses(frf: &FrfData) -> Result<Vec<Vec<f64>>> {
    let lines = frf.lines();
    if lines < 2 {
        return Err(EraError::TooFewLines { lines });
    }
    let n = 2 * (lines - 1);
    let (_, c2r) = crate::linalg::fft::real_fft_plans(n);
    let mut spectrum = c2r.make_input_vec();
    let mut scratch = c2r.make_scratch_vec();
    let scale = 1.0 / n as f64;
    let mut out = Vec::with_capacity(frf.outputs() * frf.inputs());
    for i in 0..frf.outputs() {
        for j in 0..frf.inputs() {
            spectrum.copy_from_slice(frf.pair(i, j));
            spectrum[0].im = 0.0;
            spectrum[lines - 1].im = 0.0;
            let mut h = c2r.make_output_vec();
            c2r.process_with_scratch(&mut spectrum, &mut h, &mut scratch)
                .map_err(|e| EraError::Numerical(format!("inverse FFT: {e}")))?;
            h.iter_mut().for_each(|v| *v *= scale);
            out.push(h);
        }
    }
    Ok(out)
}

/// Naive O(n²) reference of `impulse_responses`: builds the mirrored spectrum
/// `X = [G_0 … G_(N-1), conj(G_(N-2)) … conj(G_1)]` and evaluates
/// `h[t] = Re( (1/n) Σ_k X[k] e^(+2πi·kt/n) )` directly.
pub fn impulse_responses_naive(frf: &FrfData) -> Vec<Vec<f64>> {
    let lines = frf.lines();
    let n = 2 * (lines - 1);
    let twiddle: Vec<Complex64> = (0..n)
        .map(|m| Complex64::from_polar(1.0, 2.0 * std::f64::consts::PI * m as f64 / n as f64))
        .collect();
    let mut out = Vec::new();
    for i in 0..frf.outputs() {
        for j in 0..frf.inputs() {
            let g = frf.pair(i, j);
            let mut x = g.to_vec();
            for k in (1..lines - 1).rev() {
                x.push(g[k].conj());
            }
            let h = (0..n)
                .map(|t| {
                    let mut acc = Complex64::new(0.0, 0.0);
                    for (k, xk) in x.iter().enumerate() {
                        acc += xk * twiddle[(k * t) % n];
                    }
                    acc.re / n as f64
                })
                .collect();
            out.push(h);
        }
    }
    out
}

/// The FRFs of a Markov sequence sampled `sample_time_s` apart: the discrete transfer
/// function `Y_0 + Σ_k Y_k e^(−jωk·Ts)` at the `K/2 + 1` lines `0 … 1/(2Ts)` spaced
/// `1/(K·Ts)` (a real forward FFT of each pair's `K` samples, with no window: the
/// sequence ends where its blocks end), tagged `quantity`. The inverse of
/// `impulse_responses` for an even `K`.
///
/// # Errors
/// [`EraError::TooFewLines`] for fewer than 2 samples, and `FrfData::new`'s.
pub(crate) fn frf_of_markov(
    markov: &MarkovSequence,
    sample_time_s: f64,
    quantity: crate::data::frf::Quantity,
) -> Result<FrfData> {
    let n = markov.samples();
    if n < 2 {
        return Err(EraError::TooFewLines { lines: n });
    }
    let lines = n / 2 + 1;
    let (q, p) = (markov.outputs(), markov.inputs());
    let (r2c, _) = crate::linalg::fft::real_fft_plans(n);
    let mut values = Vec::with_capacity(q * p * lines);
    let mut spectrum = r2c.make_output_vec();
    for i in 0..q {
        for j in 0..p {
            let mut series = markov.pair_series(i, j);
            r2c.process(&mut series, &mut spectrum)
                .map_err(|e| EraError::Numerical(format!("forward FFT: {e}")))?;
            values.extend_from_slice(&spectrum[..lines]);
        }
    }
    let df = 1.0 / (n as f64 * sample_time_s);
    let frequency_hz = (0..lines).map(|k| k as f64 * df).collect();
    FrfData::new(frequency_hz, q, p, values, quantity)
}

/// Markov parameters of the FRFs: `impulse_responses` woven into a [`MarkovSequence`],
/// at the sample time of the FRFs' lines ([`preprocess::sample_time_s`]).
pub fn markov_from_frf(frf: &FrfData) -> Result<MarkovSequence> {
    let series = impulse_responses(frf)?;
    Ok(
        MarkovSequence::from_pair_series(frf.outputs(), frf.inputs(), &series)
            .with_sample_time(preprocess::sample_time_s(frf.spacing_hz(), frf.lines())),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::frf::{uniform_lines, Quantity};

    #[test]
    fn fft_path_equals_naive_mirror_ifft() {
        // Arbitrary complex data, including non-real DC and Nyquist lines.
        let d = FrfData::from_fn(
            uniform_lines(17, 0.5),
            2,
            3,
            Quantity::Velocity,
            |i, j, k| {
                let x = (i * 31 + j * 7 + k * 13) as f64;
                Complex64::new(x.sin(), (1.7 * x).cos())
            },
        )
        .unwrap();
        let fast = impulse_responses(&d).unwrap();
        let slow = impulse_responses_naive(&d);
        assert!(fast.iter().all(|a| a.len() == 32));
        era_testkit::assert_matches_naive(
            "impulse responses",
            &fast,
            &slow,
            era_testkit::Scale::Absolute,
            era_testkit::tol(1.0, 32, 1.0),
        );
    }

    /// `frf_of_markov` is the forward transform whose inverse `impulse_responses` is:
    /// a Markov sequence round-trips to rounding, at the sequence's lines.
    #[test]
    fn markov_to_frf_and_back_is_the_identity() {
        let (q, p, k) = (3, 2, 64);
        let markov = MarkovSequence::from_fn(q, p, k, |n, i, j| {
            (0.9f64).powi(n as i32) * ((n * (i + 1) + j) as f64 * 0.37).cos()
        });
        let frf = frf_of_markov(&markov, 0.01, Quantity::Displacement).unwrap();
        assert_eq!(frf.lines(), k / 2 + 1);
        assert!((frf.spacing_hz() - 1.0 / (k as f64 * 0.01)).abs() < 1e-12);
        let back = impulse_responses(&frf).unwrap();
        for i in 0..q {
            for j in 0..p {
                for (n, v) in back[i * p + j].iter().enumerate() {
                    assert!((v - markov.get(n, i, j)).abs() < 1e-13, "{i} {j} {n}");
                }
            }
        }
        assert!(
            frf_of_markov(&MarkovSequence::zeros(1, 1, 1), 1.0, Quantity::Displacement).is_err()
        );
    }

    #[test]
    fn constant_spectrum_is_a_unit_impulse() {
        let d = FrfData::from_fn(
            uniform_lines(5, 1.0),
            1,
            1,
            Quantity::Velocity,
            |_, _, _| Complex64::new(1.0, 0.0),
        )
        .unwrap();
        let h = impulse_responses(&d).unwrap().remove(0);
        assert!((h[0] - 1.0).abs() < 1e-15);
        assert!(h[1..].iter().all(|v| v.abs() < 1e-15));
    }
}

/// The lag window of a Welch-averaged FRF estimate, and its correction.
///
/// Under stationary random excitation, the expected H1 of frames tapered by a window
/// `w` of `N` samples is the true FRF convolved with `|W|²` (Bendat & Piersol, §11.5):
/// in the lag domain, the impulse response the inverse FFT returns is the true one
/// multiplied by the window's normalised autocorrelation
///
/// ```text
/// c(τ) = Σ_n w(n) w(n + τ) / Σ_n w(n)²,   0 ≤ τ < N
/// ```
///
/// A damped exponential times `c(τ)` is not a sum of damped exponentials: ERA fits the
/// product with extra poles beside each mode (doublets, 1–3 % away) and damping biased
/// upwards, the more so the shorter the frame is against the modes' decay. Dividing the
/// Markov samples by `c(τ)` undoes it in expectation. The samples are those of a
/// period `N/fs` of the frame (with or without a kept span: the inverse FFT of
/// lines `df` apart always spans `1/df`); lags past [`LAG_CORRECTION_FLOOR`] of `c(0)`
/// are left as they are (their noise would be amplified more than the bias is removed).
///
/// A transient that lies whole inside a frame (impact, burst that decays, a sweep with
/// quiet ends) has no such bias, and the derivation is H1's: the correction is for H1
/// estimates under random excitation, and `era identify` applies it only to those made
/// with tapered windows ([`LagWindow::correct_frf`], before any other step).
#[derive(Debug, Clone, PartialEq)]
pub struct LagWindow {
    /// `c(τ)` at the frame's sample lags `τ = 0 … N − 1`, `c(0) = 1`.
    pub c: Vec<f64>,
    /// The frame's sample rate, Hz.
    pub sample_rate_hz: f64,
}

/// Lags whose `c(τ)` is below this are not corrected.
pub const LAG_CORRECTION_FLOOR: f64 = 0.2;

impl LagWindow {
    /// The lag window to divide out of an estimate made by `estimator` with `window` over
    /// frames of `frame` samples at `sample_rate_hz`: H1's with a tapered window, `None`
    /// for a rectangular window (transients need no correction) or another estimator
    /// (the lag window is H1's bias, an output-noise estimator's).
    ///
    /// # Errors
    /// As [`LagWindow::new`].
    pub fn of_estimate(
        estimator: crate::estimate::Estimator,
        window: crate::estimate::Window,
        frame: usize,
        sample_rate_hz: f64,
    ) -> Result<Option<Self>> {
        use crate::estimate::{Estimator, Window};
        if estimator != Estimator::H1 || window == Window::Rectangular {
            return Ok(None);
        }
        Self::new(window, frame, sample_rate_hz).map(Some)
    }

    /// The lag window of `window` over frames of `frame` samples at `sample_rate_hz`
    /// (the autocorrelation by FFT, zero-padded to `2N`).
    ///
    /// # Errors
    /// [`EraError::InvalidParameter`] for a frame below 2 samples or a bad rate.
    pub fn new(window: crate::estimate::Window, frame: usize, sample_rate_hz: f64) -> Result<Self> {
        if frame < 2 || !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
            return Err(EraError::InvalidParameter {
                name: "frame",
                value: format!("{frame} samples at {sample_rate_hz} Hz"),
                reason: "the lag window needs a frame of 2 samples or more and a positive rate"
                    .into(),
            });
        }
        crate::params::limits::SAMPLES.check("frame", frame as u64)?;
        let w = window.values(frame);
        let n2 = 2 * frame;
        let (r2c, c2r) = crate::linalg::fft::real_fft_plans(n2);
        let mut padded = vec![0.0; n2];
        padded[..frame].copy_from_slice(&w);
        let mut spectrum = r2c.make_output_vec();
        r2c.process(&mut padded, &mut spectrum)
            .map_err(|e| EraError::Numerical(format!("FFT: {e}")))?;
        for v in spectrum.iter_mut() {
            *v = crate::Complex64::new(v.norm_sqr(), 0.0);
        }
        let mut r = c2r.make_output_vec();
        c2r.process(&mut spectrum, &mut r)
            .map_err(|e| EraError::Numerical(format!("inverse FFT: {e}")))?;
        let r0 = r[0];
        let c = r[..frame].iter().map(|v| v / r0).collect();
        Ok(LagWindow { c, sample_rate_hz })
    }

    /// `c(t)` at `t` seconds (linear between the frame's lags; 0 past the frame).
    pub fn at(&self, t: f64) -> f64 {
        let x = t.abs() * self.sample_rate_hz;
        let k = x.floor() as usize;
        if k + 1 >= self.c.len() {
            return if k < self.c.len() { self.c[k] } else { 0.0 };
        }
        let frac = x - k as f64;
        self.c[k] * (1.0 - frac) + self.c[k + 1] * frac
    }
}

impl LagWindow {
    /// `frf` with the lag window divided out: each pair's impulse response (the inverse
    /// FFT of its lines, which spans one frame, `1/df`) divided by `c(t)` where
    /// `c(t) ≥` [`LAG_CORRECTION_FLOOR`], and transformed back. In expectation this
    /// is the FRF without the window's smoothing, so that every stage (ERA, the
    /// refinement, the fit and the figures) sees the same debiased data. Lines
    /// `0 … L−1` must start at 0 Hz (as an analyzer's do); leading lines that are zero
    /// in every pair (a late start) stay zero.
    ///
    /// # Errors
    /// As `impulse_responses`, and [`EraError::InvalidParameter`] when the lines do
    /// not start at 0 Hz.
    pub fn correct_frf(&self, frf: &FrfData) -> Result<FrfData> {
        let corrected = self.correct_lines(frf)?;
        // A late start stays zero (its lines were never measured).
        let padded = crate::data::frf::leading_zero_lines(frf);
        Ok(preprocess::zero_leading_lines(&corrected, padded))
    }

    fn correct_lines(&self, frf: &FrfData) -> Result<FrfData> {
        let lines = frf.lines();
        if frf.frequency_hz().first().copied() != Some(0.0) {
            return Err(EraError::InvalidParameter {
                name: "frf",
                value: format!("first line {} Hz", frf.frequency_hz()[0]),
                reason: "the window correction needs lines from 0 Hz".into(),
            });
        }
        let mut series = impulse_responses(frf)?;
        let n = 2 * (lines - 1);
        let sample_time_s = 1.0 / (n as f64 * frf.spacing_hz());
        for k in 1..n {
            let c = self.at(k as f64 * sample_time_s);
            if c < LAG_CORRECTION_FLOOR {
                break;
            }
            for s in series.iter_mut() {
                s[k] /= c;
            }
        }
        let (r2c, _) = crate::linalg::fft::real_fft_plans(n);
        let mut values = Vec::with_capacity(frf.values().len());
        let mut spectrum = r2c.make_output_vec();
        for mut h in series {
            r2c.process(&mut h, &mut spectrum)
                .map_err(|e| EraError::Numerical(format!("FFT: {e}")))?;
            values.extend_from_slice(&spectrum[..lines]);
        }
        frf.with_values(values)
    }
}

#[cfg(test)]
mod lag_window_tests {
    use super::*;
    use crate::estimate::Window;

    /// Against the definition, summed directly.
    #[test]
    fn the_lag_window_is_the_normalised_autocorrelation_of_the_window() {
        for window in [Window::Hann, Window::Rectangular, Window::FlatTop] {
            let n = 64;
            let lw = LagWindow::new(window, n, 10.0).unwrap();
            let w = window.values(n);
            let r0: f64 = w.iter().map(|v| v * v).sum();
            for tau in 0..n {
                let r: f64 = (0..n - tau).map(|k| w[k] * w[k + tau]).sum();
                assert!((lw.c[tau] - r / r0).abs() < 1e-12, "{window:?} {tau}");
            }
            // Rectangular: the triangle 1 − τ/N.
            if window == Window::Rectangular {
                assert!((lw.at(1.6) - (1.0 - 16.0 / 64.0)).abs() < 1e-12);
            }
        }
    }
}
