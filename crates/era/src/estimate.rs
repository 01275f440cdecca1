//! FRF estimation from time histories: the analyzer in front of ERA.
//!
//! The thesis's FRFs came out of a Tektronix 2642A (§4.5): random excitation, 2048-sample
//! Hanning frames, averaged auto- and cross-spectra, and the ratio of the two. This module
//! does the same job for any number of inputs and outputs.
//!
//! # Spectra (Welch)
//! The record is cut into frames of `frame` samples that start `frame − overlap` samples
//! apart (frames that would run past the end are dropped, as in scipy's `csd`). Each frame
//! is detrended ([`Detrend`]), multiplied by the window `w` ([`Window`]) and transformed
//! with a real FFT, `X_k = Σ_n w_n x_n e^{−2πi kn/N}`, lines `k = 0 … N/2` at `k·fs/N` Hz.
//! Averaged over the `K` frames, the one-sided spectral *densities* are
//!
//! ```text
//!   G_ab(f_k) = c_k / (fs · Σ w_n²) · (1/K) Σ_frames A_k · conj(B_k)
//! ```
//!
//! with `c_k = 2` except at 0 Hz and (for even `N`) at the Nyquist line, where `c_k = 1`.
//! This is scipy's `csd(b, a, scaling="density")`; note the order: `G_yx = E[Y X*]`, which
//! scipy calls `csd(x, y)`. Units are signal²/Hz. The scale cancels in the FRF and
//! coherence estimates, so the window's normalisation only matters for the spectra
//! themselves.
//!
//! # Estimators (p inputs, q outputs, per line)
//! With `Gxx` the p × p input cross-spectral matrix (`[Gxx]_jk = E[X_j X_k*]`), `Gyx` the
//! q × p output/input matrix and `Gyy` the q × q output matrix:
//! - **H1** `= Gyx Gxx⁻¹`: unbiased by noise on the outputs (least squares on the outputs);
//! - **H2** `= Gyy Gyx (Gyx^H Gyx)⁻¹`: unbiased by noise on the inputs; for one input it
//!   is the textbook `Gyy / Gxy`. It needs at least as many outputs as inputs, and every
//!   output's noise enters every row, so it is meant for SISO and for `q = p`;
//! - **Hv** (total least squares): for each output `i`, the eigenvector `v` of the
//!   smallest eigenvalue of the (p+1) × (p+1) matrix of `[x; y_i]`, and
//!   `h_i = −conj(v_{1…p}) / conj(v_{p+1})`; it lies between H1 and H2.
//!
//! Coherence: ordinary `γ²_ij = |G_{y_i x_j}|² / (G_{x_j x_j} G_{y_i y_i})`, multiple
//! `γ²_i = Re(Σ_j H1_ij G_{x_j y_i}) / G_{y_i y_i}`, the share of output `i`'s power that
//! the inputs explain linearly. Both need `Gxx` to be invertible: when two inputs are
//! coherent, or there are fewer frames than inputs, estimation stops with
//! [`EraError::SingularInputSpectrum`], naming the inputs.
//!
//! Memory: frames are transformed in batches of [`BATCH_FRAMES`], so the working set is
//! `(p + q) · BATCH_FRAMES · (N/2 + 1)` complex values plus the accumulated spectra,
//! whatever the record length. Channels are transformed and pairs accumulated in parallel
//! (`rayon`).

use crate::data::frf::{FrfData, Quantity};
use crate::error::{EraError, Result};
use faer::linalg::solvers::Solve;
use faer::{Mat, Side};
use num_complex::Complex64;
use rayon::prelude::*;

/// Frames transformed at once (bounds the working memory on long records).
pub const BATCH_FRAMES: usize = 64;

/// Smallest eigenvalue of the coherence-normalised input matrix below which it is taken
/// as singular (1 − |γ| for two inputs).
pub(crate) const SINGULAR_TOLERANCE: f64 = 1e-10;

/// Lines where an input's autospectrum is below this fraction of its largest value are
/// *unexcited*: zero in exact arithmetic (0 Hz after removing the mean with a
/// rectangular window), rounding noise in practice. Their FRF and coherence are set to 0
/// and they are listed in [`FrfEstimate::unexcited_lines`]. 1e-20 is 200 dB, far below
/// any analyzer's dynamic range.
pub const UNEXCITED_FRACTION: f64 = 1e-20;

/// Window applied to each frame. All are the periodic (DFT-even) forms, as an analyzer
/// and scipy's `get_window` use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Window {
    /// No window (`w = 1`): for transients and periodic signals that fit the frame.
    Rectangular,
    /// Hann (`0.5 − 0.5 cos 2πn/N`): the analyzer default for random excitation, and
    /// era's.
    #[default]
    Hann,
    /// Five-term flat-top (scipy's `flattop` coefficients): accurate amplitudes of sines.
    FlatTop,
}

impl Window {
    /// The `n` window values.
    pub fn values(self, n: usize) -> Vec<f64> {
        const FLAT_TOP: [f64; 5] = [
            0.215_578_95,
            0.416_631_58,
            0.277_263_158,
            0.083_578_947,
            0.006_947_368,
        ];
        let step = 2.0 * std::f64::consts::PI / n as f64;
        (0..n)
            .map(|k| {
                let phase = step * k as f64;
                match self {
                    Window::Rectangular => 1.0,
                    Window::Hann => 0.5 - 0.5 * phase.cos(),
                    Window::FlatTop => FLAT_TOP
                        .iter()
                        .enumerate()
                        .map(|(m, a)| {
                            let sign = if m % 2 == 0 { 1.0 } else { -1.0 };
                            sign * a * (m as f64 * phase).cos()
                        })
                        .sum(),
                }
            })
            .collect()
    }

    /// Name as the CLI spells it.
    pub fn name(self) -> &'static str {
        crate::params::names::Named::name_of(&self)
    }
}

/// Trend removed from each frame before windowing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Detrend {
    /// Nothing removed.
    None,
    /// The frame's mean (scipy's `detrend="constant"`, its default, and era's).
    #[default]
    Mean,
    /// The frame's least-squares straight line (scipy's `"linear"`).
    Linear,
}

impl Detrend {
    /// Name as the CLI spells it.
    pub fn name(self) -> &'static str {
        crate::params::names::Named::name_of(&self)
    }

    fn apply(self, frame: &mut [f64]) {
        let n = frame.len() as f64;
        match self {
            Detrend::None => {}
            Detrend::Mean => {
                let mean = frame.iter().sum::<f64>() / n;
                frame.iter_mut().for_each(|v| *v -= mean);
            }
            Detrend::Linear => {
                let t_mean = (n - 1.0) / 2.0;
                let mean = frame.iter().sum::<f64>() / n;
                let (mut sxy, mut sxx) = (0.0, 0.0);
                for (k, v) in frame.iter().enumerate() {
                    let t = k as f64 - t_mean;
                    sxy += t * (v - mean);
                    sxx += t * t;
                }
                let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
                for (k, v) in frame.iter_mut().enumerate() {
                    *v -= mean + slope * (k as f64 - t_mean);
                }
            }
        }
    }
}

/// FRF estimator (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Estimator {
    /// `Gyx Gxx⁻¹`: noise on the outputs (the default).
    #[default]
    H1,
    /// `Gyy Gyx (Gyx^H Gyx)⁻¹`: noise on the inputs.
    H2,
    /// Total least squares per output.
    Hv,
}

impl Estimator {
    /// Name as the CLI spells it.
    pub fn name(self) -> &'static str {
        crate::params::names::Named::name_of(&self)
    }
}

/// Samples per frame when the caller does not say.
pub const DEFAULT_FRAME: usize = 2048;

/// Fewest averages of an estimate that judges modes: fewer give FRFs too noisy to vouch
/// for (or against) a mode.
pub const JUDGING_AVERAGES: usize = 8;

/// The frame for FRFs that only judge and refine a model whose Markov parameters come
/// from elsewhere (OKID's): the largest power of two up to [`DEFAULT_FRAME`], and at
/// least 256, that gives `records` records of `samples` samples at least
/// [`JUDGING_AVERAGES`] averages at `overlap`. On a simulated 60 s record at 64 Hz the
/// default frame gives 2 averages, and the noise test then rejected 6 of 10 true modes.
pub fn judging_frame(samples: usize, records: usize, overlap: f64) -> usize {
    let mut frame = DEFAULT_FRAME;
    loop {
        let mut o = WelchOptions::new(1.0, frame);
        o.overlap = overlap.clamp(0.0, 0.99);
        if frame <= 256 || records.saturating_mul(o.frames(samples)) >= JUDGING_AVERAGES {
            return frame;
        }
        frame /= 2;
    }
}

/// Welch parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct WelchOptions {
    /// Sampling rate of the time histories, Hz.
    pub sample_rate_hz: f64,
    /// Samples per frame (the FFT length); lines are `frame/2 + 1`, spaced `fs/frame`.
    pub frame: usize,
    /// Overlap of consecutive frames as a fraction of the frame, in `[0, 1)`; the
    /// overlap in samples is `round(overlap · frame)`.
    pub overlap: f64,
    /// Window of each frame.
    pub window: Window,
    /// Trend removed from each frame.
    pub detrend: Detrend,
}

impl WelchOptions {
    /// The overlap of `WelchOptions::new`: half a frame.
    pub const DEFAULT_OVERLAP: f64 = 0.5;

    /// `frame`-sample frames of time histories sampled at `sample_rate_hz`, with the
    /// usual choices: half overlap, a Hann window, each frame's mean removed.
    pub fn new(sample_rate_hz: f64, frame: usize) -> Self {
        WelchOptions {
            sample_rate_hz,
            frame,
            overlap: Self::DEFAULT_OVERLAP,
            window: Window::default(),
            detrend: Detrend::default(),
        }
    }

    /// Overlap in samples.
    pub fn overlap_samples(&self) -> usize {
        (self.overlap * self.frame as f64).round() as usize
    }

    /// Frames that fit in `samples`.
    pub fn frames(&self, samples: usize) -> usize {
        let step = self.frame - self.overlap_samples();
        if samples < self.frame {
            0
        } else {
            (samples - self.frame) / step + 1
        }
    }

    /// Lines of the one-sided spectrum.
    pub fn lines(&self) -> usize {
        self.frame / 2 + 1
    }

    fn validate(&self, samples: usize) -> Result<()> {
        if !(self.sample_rate_hz.is_finite() && self.sample_rate_hz > 0.0) {
            return Err(EraError::InvalidParameter {
                name: "sample_rate",
                value: self.sample_rate_hz.to_string(),
                reason: "must be a positive number of samples per second".into(),
            });
        }
        if self.frame < 2 {
            return Err(EraError::InvalidParameter {
                name: "frame",
                value: self.frame.to_string(),
                reason: "a frame needs at least 2 samples".into(),
            });
        }
        if !(self.overlap.is_finite() && (0.0..1.0).contains(&self.overlap)) {
            return Err(EraError::InvalidParameter {
                name: "overlap",
                value: self.overlap.to_string(),
                reason: "must be a fraction in [0, 1), e.g. 0.5 for 50 %".into(),
            });
        }
        if self.overlap_samples() >= self.frame {
            return Err(EraError::InvalidParameter {
                name: "overlap",
                value: self.overlap.to_string(),
                reason: format!(
                    "rounds to {} of the {} samples of a frame: frames would not advance",
                    self.overlap_samples(),
                    self.frame
                )
                .into(),
            });
        }
        if samples < self.frame {
            return Err(EraError::InvalidParameter {
                name: "frame",
                value: self.frame.to_string(),
                reason: crate::params::names::Prose::from(format!(
                    "the time histories have only {samples} samples, fewer than one frame: use a shorter "
                ))
                .param(crate::params::names::Param::Frame),
            });
        }
        Ok(())
    }
}

/// Averaged one-sided spectral densities of p inputs and q outputs.
#[derive(Debug, Clone, PartialEq)]
pub struct Spectra {
    frequency_hz: Vec<f64>,
    inputs: usize,
    outputs: usize,
    frames: usize,
    /// `[j][k][line]`: `E[X_j X_k*]`.
    gxx: Vec<Complex64>,
    /// `[i][j][line]`: `E[Y_i X_j*]`.
    gyx: Vec<Complex64>,
    /// `[i][k][line]` when full, `[i][line]` (autospectra only) otherwise.
    gyy: Vec<Complex64>,
    gyy_full: bool,
}

impl Spectra {
    /// Frequencies of the lines, Hz (`k · fs / frame`).
    pub fn frequency_hz(&self) -> &[f64] {
        &self.frequency_hz
    }
    /// Number of lines.
    pub fn lines(&self) -> usize {
        self.frequency_hz.len()
    }
    /// Number of inputs p.
    pub fn inputs(&self) -> usize {
        self.inputs
    }
    /// Number of outputs q.
    pub fn outputs(&self) -> usize {
        self.outputs
    }
    /// Frames averaged.
    pub fn frames(&self) -> usize {
        self.frames
    }
    /// `G_{x_j x_k} = E[X_j X_k*]` over the lines (0-based j, k).
    pub fn gxx(&self, j: usize, k: usize) -> &[Complex64] {
        let l = self.lines();
        let at = (j * self.inputs + k) * l;
        &self.gxx[at..at + l]
    }
    /// `G_{y_i x_j} = E[Y_i X_j*]` over the lines.
    pub fn gyx(&self, i: usize, j: usize) -> &[Complex64] {
        let l = self.lines();
        let at = (i * self.inputs + j) * l;
        &self.gyx[at..at + l]
    }
    /// `G_{y_i y_i}` over the lines (real, stored as complex).
    pub fn gyy_auto(&self, i: usize) -> Vec<f64> {
        (0..self.lines()).map(|k| self.gyy_at(i, i, k).re).collect()
    }
    /// `G_{y_i y_k}` over the lines, when the full output matrix was computed.
    pub fn gyy(&self, i: usize, k: usize) -> Option<&[Complex64]> {
        if !self.gyy_full {
            return None;
        }
        let l = self.lines();
        let at = (i * self.outputs + k) * l;
        Some(&self.gyy[at..at + l])
    }
    fn gyy_at(&self, i: usize, k: usize, line: usize) -> Complex64 {
        let l = self.lines();
        if self.gyy_full {
            self.gyy[(i * self.outputs + k) * l + line]
        } else {
            debug_assert_eq!(i, k);
            self.gyy[i * l + line]
        }
    }
}

impl Spectra {
    /// Pools the spectra of several records taken with the same settings: the
    /// frame-weighted mean, which is exactly Welch's average over all their frames.
    ///
    /// # Errors
    /// [`EraError::ShapeMismatch`] when the records differ in lines, channels or
    /// frequencies, or there are none.
    pub fn pool(records: &[Spectra]) -> Result<Spectra> {
        let Some(first) = records.first() else {
            return Err(EraError::ShapeMismatch {
                what: "records to pool".into(),
                expected: 1,
                got: 0,
            });
        };
        for (r, other) in records.iter().enumerate().skip(1) {
            let same = other.frequency_hz == first.frequency_hz
                && other.inputs == first.inputs
                && other.outputs == first.outputs
                && other.gyy_full == first.gyy_full;
            if !same {
                return Err(EraError::ShapeMismatch {
                    what: format!(
                        "record {} (lines, channels or sample rate differ from record 1)",
                        r + 1
                    ),
                    expected: first.lines(),
                    got: other.lines(),
                });
            }
        }
        let frames: usize = records.iter().map(|r| r.frames).sum();
        let mut pooled = first.clone();
        pooled.frames = frames;
        let mix = |get: fn(&Spectra) -> &Vec<Complex64>| -> Vec<Complex64> {
            (0..get(first).len())
                .map(|t| {
                    records
                        .iter()
                        .map(|r| get(r)[t] * r.frames as f64)
                        .sum::<Complex64>()
                        / frames as f64
                })
                .collect()
        };
        pooled.gxx = mix(|r| &r.gxx);
        pooled.gyx = mix(|r| &r.gyx);
        pooled.gyy = mix(|r| &r.gyy);
        Ok(pooled)
    }
}

fn check_channels(inputs: &[&[f64]], outputs: &[&[f64]]) -> Result<usize> {
    if inputs.is_empty() || outputs.is_empty() {
        return Err(EraError::ShapeMismatch {
            what: "number of input and output channels (at least 1 each)".into(),
            expected: 1,
            got: inputs.len().min(outputs.len()),
        });
    }
    check_record(inputs, outputs, None)
}

/// One record's channels (at least one input): every channel as long as input 1 and
/// every sample finite. Returns the samples per channel. `record` (1-based) is named in
/// the message when the caller has several.
pub(crate) fn check_record(
    inputs: &[&[f64]],
    outputs: &[&[f64]],
    record: Option<usize>,
) -> Result<usize> {
    let samples = inputs[0].len();
    let of_record = record
        .map(|n| format!(" of record {n}"))
        .unwrap_or_default();
    for (role, set) in [("input", inputs), ("output", outputs)] {
        for (c, channel) in set.iter().enumerate() {
            if channel.len() != samples {
                return Err(EraError::ShapeMismatch {
                    what: format!(
                        "samples in {role} {}{of_record} (input 1 has {samples})",
                        c + 1
                    ),
                    expected: samples,
                    got: channel.len(),
                });
            }
            if let Some(sample) = channel.iter().position(|v| !v.is_finite()) {
                return Err(EraError::NonFiniteSample {
                    role,
                    channel: c + 1,
                    sample,
                });
            }
        }
    }
    Ok(samples)
}

/// Welch-averaged spectra of the inputs and outputs (module documentation for the
/// definitions). `full_output_matrix` computes every `G_{y_i y_k}` (H2 needs it);
/// otherwise only the output autospectra.
///
/// # Errors
/// [`EraError::ShapeMismatch`] for no channels or channels of unequal length,
/// [`EraError::NonFiniteSample`], [`EraError::InvalidParameter`] for the options or a
/// record shorter than one frame.
pub fn spectra(
    inputs: &[&[f64]],
    outputs: &[&[f64]],
    options: &WelchOptions,
    full_output_matrix: bool,
) -> Result<Spectra> {
    let samples = check_channels(inputs, outputs)?;
    options.validate(samples)?;
    let (p, q) = (inputs.len(), outputs.len());
    let n = options.frame;
    let lines = options.lines();
    let step = n - options.overlap_samples();
    let frames = options.frames(samples);
    let window = options.window.values(n);
    let (fft, _) = crate::linalg::fft::real_fft_plans(n);

    let channels: Vec<&[f64]> = inputs.iter().chain(outputs.iter()).copied().collect();
    let mut gxx = vec![Complex64::new(0.0, 0.0); p * p * lines];
    let mut gyx = vec![Complex64::new(0.0, 0.0); q * p * lines];
    let gyy_pairs = if full_output_matrix { q * q } else { q };
    let mut gyy = vec![Complex64::new(0.0, 0.0); gyy_pairs * lines];

    let mut first = 0;
    while first < frames {
        crate::cancel::check()?;
        let batch = BATCH_FRAMES.min(frames - first);
        // spectra[c][b][line] for this batch.
        let transformed: Vec<Vec<Complex64>> = channels
            .par_iter()
            .map(|signal| {
                let mut out = vec![Complex64::new(0.0, 0.0); batch * lines];
                let mut buf = vec![0.0; n];
                let mut scratch = fft.make_scratch_vec();
                for b in 0..batch {
                    let start = (first + b) * step;
                    buf.copy_from_slice(&signal[start..start + n]);
                    options.detrend.apply(&mut buf);
                    buf.iter_mut().zip(&window).for_each(|(v, w)| *v *= w);
                    fft.process_with_scratch(
                        &mut buf,
                        &mut out[b * lines..(b + 1) * lines],
                        &mut scratch,
                    )
                    .expect("buffer lengths match the plan");
                }
                out
            })
            .collect();
        let accumulate = |target: &mut [Complex64], a: usize, b: usize| {
            let (sa, sb) = (&transformed[a], &transformed[b]);
            for f in 0..batch {
                let (ra, rb) = (
                    &sa[f * lines..(f + 1) * lines],
                    &sb[f * lines..(f + 1) * lines],
                );
                for ((t, x), y) in target.iter_mut().zip(ra).zip(rb) {
                    *t += x * y.conj();
                }
            }
        };
        gxx.par_chunks_mut(lines)
            .enumerate()
            .for_each(|(pair, t)| accumulate(t, pair / p, pair % p));
        gyx.par_chunks_mut(lines)
            .enumerate()
            .for_each(|(pair, t)| accumulate(t, p + pair / p, pair % p));
        gyy.par_chunks_mut(lines).enumerate().for_each(|(pair, t)| {
            if full_output_matrix {
                accumulate(t, p + pair / q, p + pair % q)
            } else {
                accumulate(t, p + pair, p + pair)
            }
        });
        first += batch;
    }

    let power: f64 = window.iter().map(|w| w * w).sum();
    let scale = 1.0 / (options.sample_rate_hz * power * frames as f64);
    let nyquist = if n.is_multiple_of(2) {
        Some(n / 2)
    } else {
        None
    };
    for set in [&mut gxx, &mut gyx, &mut gyy] {
        set.par_chunks_mut(lines).for_each(|pair| {
            for (k, v) in pair.iter_mut().enumerate() {
                let c = if k == 0 || Some(k) == nyquist {
                    1.0
                } else {
                    2.0
                };
                *v *= c * scale;
            }
        });
    }
    let frequency_hz = (0..lines)
        .map(|k| k as f64 * options.sample_rate_hz / n as f64)
        .collect();
    Ok(Spectra {
        frequency_hz,
        inputs: p,
        outputs: q,
        frames,
        gxx,
        gyx,
        gyy,
        gyy_full: full_output_matrix,
    })
}

/// FRFs estimated from time histories, with their coherence.
#[derive(Debug, Clone)]
pub struct FrfEstimate {
    /// The FRFs, `[output][input][line]`.
    pub frf: FrfData,
    /// Ordinary coherence `[output][input][line]`, `q · p · lines` values in `[0, 1]`.
    pub ordinary_coherence: Vec<f64>,
    /// Multiple coherence `[output][line]`, `q · lines` values in `[0, 1]`.
    pub multiple_coherence: Vec<f64>,
    /// The spectra the estimate came from.
    pub spectra: Spectra,
    /// The estimator used.
    pub estimator: Estimator,
    /// Lines (0-based) where some input has no power (see [`UNEXCITED_FRACTION`]):
    /// FRF and coherence are 0 there.
    pub unexcited_lines: Vec<usize>,
}

impl FrfEstimate {
    /// Keeps the first `lines` lines (an analyzer's span: `era frf --max-hz`). The
    /// sample time ERA infers from the FRF grows accordingly, as after decimation.
    ///
    /// # Errors
    /// [`EraError::InvalidParameter`] for fewer than 2 lines or more than there are.
    pub fn truncate(&mut self, lines: usize) -> Result<()> {
        let total = self.spectra.lines();
        if lines < 2 || lines > total {
            return Err(EraError::InvalidParameter {
                name: "max_hz",
                value: format!("{lines} lines"),
                reason: format!("keeps fewer than 2 or more than the {total} lines").into(),
            });
        }
        let cut_c = |v: &[Complex64], pairs: usize| -> Vec<Complex64> {
            (0..pairs)
                .flat_map(|a| v[a * total..a * total + lines].iter().copied())
                .collect()
        };
        let cut_r = |v: &[f64], pairs: usize| -> Vec<f64> {
            (0..pairs)
                .flat_map(|a| v[a * total..a * total + lines].iter().copied())
                .collect()
        };
        let (p, q) = (self.spectra.inputs, self.spectra.outputs);
        let s = &mut self.spectra;
        s.gxx = cut_c(&s.gxx, p * p);
        s.gyx = cut_c(&s.gyx, q * p);
        s.gyy = cut_c(&s.gyy, if s.gyy_full { q * q } else { q });
        s.frequency_hz.truncate(lines);
        self.frf = FrfData::new(
            s.frequency_hz.clone(),
            q,
            p,
            cut_c(self.frf.values(), q * p),
            self.frf.quantity(),
        )?;
        self.ordinary_coherence = cut_r(&self.ordinary_coherence, q * p);
        self.multiple_coherence = cut_r(&self.multiple_coherence, q);
        self.unexcited_lines.retain(|&k| k < lines);
        Ok(())
    }

    /// Ordinary coherence of one pair over the lines (0-based).
    pub fn coherence(&self, output: usize, input: usize) -> &[f64] {
        let l = self.spectra.lines();
        let at = (output * self.spectra.inputs + input) * l;
        &self.ordinary_coherence[at..at + l]
    }
    /// Multiple coherence of one output over the lines (0-based).
    pub fn multiple(&self, output: usize) -> &[f64] {
        let l = self.spectra.lines();
        &self.multiple_coherence[output * l..(output + 1) * l]
    }
}

/// Estimates FRFs (and coherence) from input and output time histories.
///
/// `inputs[j]` and `outputs[i]` are the sampled channels, all of one length. The FRFs are
/// tagged with `quantity` (what the outputs measure).
///
/// # Errors
/// Those of [`spectra`]; [`EraError::SingularInputSpectrum`] when the inputs are linearly
/// dependent at some line (or there are fewer frames than inputs);
/// [`EraError::InvalidParameter`] for H2 with fewer outputs than inputs;
/// [`EraError::Numerical`] when H2's or Hv's solve fails.
pub fn estimate(
    inputs: &[&[f64]],
    outputs: &[&[f64]],
    options: &WelchOptions,
    estimator: Estimator,
    quantity: Quantity,
) -> Result<FrfEstimate> {
    if estimator == Estimator::H2 && outputs.len() < inputs.len() {
        return Err(EraError::InvalidParameter {
            name: "estimator",
            value: "h2".into(),
            reason: format!(
                "H2 needs at least as many outputs as inputs ({} outputs, {} inputs): use h1 or hv",
                outputs.len(),
                inputs.len()
            )
            .into(),
        });
    }
    let s = spectra(inputs, outputs, options, estimator == Estimator::H2)?;
    estimate_from_spectra(s, estimator, quantity)
}

/// Estimates FRFs (and coherence) from spectra already averaged, e.g. pooled over
/// several records with [`Spectra::pool`]. H2 needs spectra computed with the full
/// output matrix.
///
/// # Errors
/// As [`estimate`], and [`EraError::InvalidParameter`] for H2 on spectra without the
/// full output matrix.
pub fn estimate_from_spectra(
    s: Spectra,
    estimator: Estimator,
    quantity: Quantity,
) -> Result<FrfEstimate> {
    if estimator == Estimator::H2 && (!s.gyy_full || s.outputs < s.inputs) {
        return Err(EraError::InvalidParameter {
            name: "estimator",
            value: "h2".into(),
            reason: format!(
                "H2 needs the full output cross-spectral matrix and at least as many outputs as inputs ({} outputs, {} inputs)",
                s.outputs, s.inputs
            ).into(),
        });
    }
    let unexcited = check_input_matrix(&s)?;
    let (p, q, lines) = (s.inputs, s.outputs, s.lines());
    let mut skip = vec![false; lines];
    unexcited.iter().for_each(|&k| skip[k] = true);

    // Per line: H1 (always: multiple coherence needs it) and the chosen estimate.
    let per_line: Vec<Result<(Vec<Complex64>, Vec<Complex64>)>> = (0..lines)
        .into_par_iter()
        .map(|k| {
            if skip[k] {
                let zero = vec![Complex64::new(0.0, 0.0); q * p];
                return Ok((zero.clone(), zero));
            }
            let gxx = Mat::<Complex64>::from_fn(p, p, |a, b| s.gxx(a, b)[k]);
            // Gxx X = Gyx^H, H1 = X^H.
            let rhs = Mat::<Complex64>::from_fn(p, q, |j, i| s.gyx(i, j)[k].conj());
            let x = gxx.partial_piv_lu().solve(&rhs);
            let h1: Vec<Complex64> = (0..q * p).map(|t| x[(t % p, t / p)].conj()).collect();
            let chosen = match estimator {
                Estimator::H1 => h1.clone(),
                Estimator::H2 => h2_line(&s, k)?,
                Estimator::Hv => hv_line(&s, k)?,
            };
            Ok((h1, chosen))
        })
        .collect();
    let mut values = vec![Complex64::new(0.0, 0.0); q * p * lines];
    let mut multiple = vec![0.0; q * lines];
    let mut ordinary = vec![0.0; q * p * lines];
    for (k, line) in per_line.into_iter().enumerate() {
        let (h1, chosen) = line?;
        if skip[k] {
            continue;
        }
        for i in 0..q {
            let gyy = s.gyy_at(i, i, k).re;
            let mut explained = 0.0;
            for j in 0..p {
                let gyx = s.gyx(i, j)[k];
                values[(i * p + j) * lines + k] = chosen[i * p + j];
                explained += (h1[i * p + j] * gyx.conj()).re;
                let gxx = s.gxx(j, j)[k].re;
                ordinary[(i * p + j) * lines + k] = ratio(gyx.norm_sqr(), gxx * gyy);
            }
            multiple[i * lines + k] = ratio(explained, gyy);
        }
    }
    let frf = FrfData::new(s.frequency_hz.clone(), q, p, values, quantity)?;
    Ok(FrfEstimate {
        frf,
        ordinary_coherence: ordinary,
        multiple_coherence: multiple,
        spectra: s,
        estimator,
        unexcited_lines: unexcited,
    })
}

/// `a > b`, false for NaN: negated, it catches NaN as well as small values.
fn exceeds(a: f64, b: f64) -> bool {
    a > b
}

/// `a / b`, 0 when `b` is 0 (an output with no power at that line).
fn ratio(a: f64, b: f64) -> f64 {
    if b > 0.0 {
        a / b
    } else {
        0.0
    }
}

/// H2 at one line: `Gyy Gyx (Gyx^H Gyx)⁻¹`, row-major `q · p`. Computed as
/// `Gyy U S⁻¹ V^H` from the thin SVD `Gyx = U S V^H`, which never forms the normal
/// matrix `Gyx^H Gyx` (whose condition number is the square of `Gyx`'s).
fn h2_line(s: &Spectra, k: usize) -> Result<Vec<Complex64>> {
    let (p, q) = (s.inputs, s.outputs);
    let gyx = Mat::<Complex64>::from_fn(q, p, |i, j| s.gyx(i, j)[k]);
    let gyy = Mat::<Complex64>::from_fn(q, q, |i, m| s.gyy_at(i, m, k));
    let svd = gyx.thin_svd().map_err(|e| {
        EraError::Numerical(format!("H2 at {} Hz: SVD failed: {e:?}", s.frequency_hz[k]))
    })?;
    let sv = svd.S().column_vector();
    let largest = (0..p).map(|j| sv[j].re).fold(0.0, f64::max);
    if (0..p).any(|j| !exceeds(sv[j].re, 1e-13 * largest)) {
        return Err(EraError::Numerical(format!(
            "H2 at {} Hz: the output/input cross-spectra have rank below {p} (an output set that does not see every input): use h1 or hv",
            s.frequency_hz[k]
        )));
    }
    let u_scaled = Mat::<Complex64>::from_fn(q, p, |i, j| svd.U()[(i, j)] / sv[j].re);
    let h = &gyy * &u_scaled * svd.V().adjoint();
    Ok((0..q * p).map(|t| h[(t / p, t % p)]).collect())
}

/// Hv at one line: per output, the eigenvector of the smallest eigenvalue of the
/// spectral matrix of `[x; y_i]`.
fn hv_line(s: &Spectra, k: usize) -> Result<Vec<Complex64>> {
    let (p, q) = (s.inputs, s.outputs);
    let mut h = Vec::with_capacity(q * p);
    for i in 0..q {
        // z = [x_1..x_p, y_i]; G_zz[a][b] = E[z_a z_b*].
        let g = Mat::<Complex64>::from_fn(p + 1, p + 1, |a, b| match (a < p, b < p) {
            (true, true) => s.gxx(a, b)[k],
            (false, true) => s.gyx(i, b)[k],
            (true, false) => s.gyx(i, a)[k].conj(),
            (false, false) => s.gyy_at(i, i, k),
        });
        let eig = g
            .self_adjoint_eigen(Side::Lower)
            .map_err(|e| EraError::Numerical(format!("Hv at {} Hz: {e:?}", s.frequency_hz[k])))?;
        let v = eig.U().col(0);
        let last = v[p].conj();
        for j in 0..p {
            let value = -v[j].conj() / last;
            if !(value.re.is_finite() && value.im.is_finite()) {
                return Err(EraError::Numerical(format!(
                    "Hv at {} Hz, output {}: the noise eigenvector has no output component",
                    s.frequency_hz[k],
                    i + 1
                )));
            }
            h.push(value);
        }
    }
    Ok(h)
}

/// Finds the unexcited lines and refuses an input matrix that is singular at any other
/// line; the message names the most coherent pair of inputs at the first such line.
fn check_input_matrix(s: &Spectra) -> Result<Vec<usize>> {
    let (p, lines) = (s.inputs, s.lines());
    let floor: Vec<f64> = (0..p)
        .map(|j| {
            let largest = s.gxx(j, j).iter().map(|v| v.re).fold(0.0, f64::max);
            UNEXCITED_FRACTION * largest
        })
        .collect();
    if let Some(j) = (0..p).find(|&j| !exceeds(floor[j], 0.0)) {
        return Err(EraError::SingularInputSpectrum {
            singular_lines: lines,
            lines,
            first_hz: 0.0,
            min_eigenvalue: 0.0,
            reason: format!(
                "input {} has no power at any line (a constant or silent channel)",
                j + 1
            )
            .into(),
        });
    }
    let unexcited: Vec<usize> = (0..lines)
        .filter(|&k| (0..p).any(|j| s.gxx(j, j)[k].re <= floor[j]))
        .collect();
    let smallest: Vec<f64> = (0..lines)
        .into_par_iter()
        .map(|k| {
            if p == 1 || unexcited.binary_search(&k).is_ok() {
                return 1.0;
            }
            let d: Vec<f64> = (0..p).map(|j| s.gxx(j, j)[k].re).collect();
            let c = Mat::<Complex64>::from_fn(p, p, |a, b| s.gxx(a, b)[k] / (d[a] * d[b]).sqrt());
            c.self_adjoint_eigenvalues(Side::Lower)
                .map(|e| e[0])
                .unwrap_or(0.0)
        })
        .collect();
    let bad: Vec<usize> = (0..lines)
        .filter(|&k| !exceeds(smallest[k], SINGULAR_TOLERANCE))
        .collect();
    let Some(&first) = bad.first() else {
        return Ok(unexcited);
    };
    let reason = if s.frames < p {
        crate::params::names::Prose::from(format!(
            "{} frames were averaged, fewer than the {p} inputs: the matrix has rank {} at most; use a shorter ",
            s.frames, s.frames
        ))
        .param(crate::params::names::Param::Frame)
        .text(" or more ")
        .param(crate::params::names::Param::Overlap)
    } else {
        let mut worst = (0, 1, -1.0);
        for a in 0..p {
            for b in a + 1..p {
                let g =
                    s.gxx(a, b)[first].norm_sqr() / (s.gxx(a, a)[first].re * s.gxx(b, b)[first].re);
                if g > worst.2 {
                    worst = (a, b, g);
                }
            }
        }
        crate::params::names::Prose::from(format!(
            "inputs {} and {} are fully coherent (coherence {:.9}): two identical or proportional inputs cannot be told apart, drop one",
            worst.0 + 1,
            worst.1 + 1,
            worst.2
        ))
    };
    Err(EraError::SingularInputSpectrum {
        singular_lines: bad.len(),
        lines,
        first_hz: s.frequency_hz[first],
        min_eigenvalue: smallest[first],
        reason,
    })
}

crate::params::names::named!(display Window, "window", [
    Window::Hann => "hann" | "hanning",
    Window::Rectangular => "rectangular" | "boxcar",
    Window::FlatTop => "flat-top" | "flattop",
]);

crate::params::names::named!(display Estimator, "estimator", [
    Estimator::H1 => "h1",
    Estimator::H2 => "h2",
    Estimator::Hv => "hv",
]);

crate::params::names::named!(display Detrend, "detrend", [
    Detrend::None => "none",
    Detrend::Mean => "mean",
    Detrend::Linear => "linear",
]);
