//! Automatic free-decay analysis: what the thesis's `FC.M` did with mouse clicks.
//!
//! For one record of relative velocity against time:
//!
//! 1. **Checks**: strictly increasing, uniform time; finite values; enough samples.
//! 2. **Noise and offset**: the sensor noise from the median absolute deviation of the
//!    second differences (`σ = 1.4826·MAD/√6`, blind to a smooth signal); the offset is
//!    the record's median (the rest before the release and after sticking).
//! 3. **Rough frequency**: the peak of the record's spectrum (`realfft`, zero-padded,
//!    parabolic interpolation).
//! 4. **Half-cycles**: a zero-phase Butterworth low-pass at 3 f_n ([`crate::pipeline::filter`])
//!    for segmentation only; the lobes between zero crossings whose peak stands above
//!    the noise (4σ after the filter, and 2 % of the largest) and last at least a
//!    quarter period. The longest run of consecutive lobes is the oscillation.
//! 5. **Usable stretch**: the first lobe (the release transient) and the last (the
//!    stuck tail, where static friction and noise take over) are dropped.
//! 6. **Amplitudes**: each usable lobe's amplitude is the least-squares fit of a half
//!    sine between its zero crossings to the *unfiltered* samples, so neither the filter
//!    nor a single noisy sample biases it.
//! 7. **Natural frequency** from the spacing of the zero crossings and, separately, of
//!    the lobe centres (linear regressions on the index).
//! 8. **Models**: a straight line `A = a + b t` (Coulomb, Eq. 3.10) and an exponential
//!    `A = A₀ e^(−σt)` (viscous; weighted log-linear start, Gauss–Newton refinement);
//!    the RMS residuals say which explains the record better.
//! 9. **Friction**: Eq. 3.12 with the fitted drop per cycle `−b/f_n`.
//! 10. **Both at once**: Eq. 3.12 reads the whole decay as friction, so any viscous
//!     damping in the actuator (back-EMF, air) inflates it. The combined law separates
//!     them. Within one half-cycle of `m ẍ + c ẋ + k x = −F_C sgn ẋ` the motion is a
//!     damped oscillation about the shifted rest point `±δ`, `δ = F_C/k`, so the
//!     displacement extremes obey `X₊ − δ = d (X − δ) − 2δ` with the half-cycle ratio
//!     `d = e^(−σπ/ω_d)`, `σ = ζω`. The lobe amplitudes `A = K (X − δ)`,
//!     `K = (ω²/ω_d)·e^(−σπ/2ω_d)` (the envelope at the lobe centre), therefore follow
//!     `A₊ = d A − 2Kδ`, whose continuous form is
//!     `A(t) = A₀ e^(−σt) − r (1 − e^(−σt))/σ`. It is linear in `(A₀, r)` for a given
//!     `σ`, so `σ ≥ 0` is found by a one-dimensional search on the least-squares residual
//!     (a log-spaced grid, then golden-section refinement) with `r ≥ 0`, and
//!     `F_C = k (r/σ)(1 − d) / (2K)`. At `σ = 0` it is the straight line and Eq. 3.12
//!     exactly; at `r = 0` it is the exponential.

use super::{coulomb_force_from_decay, FrictionError, Result};
use crate::pipeline::filter::LowPass;

/// Which damping law explains a decay better.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DampingModel {
    /// Linear decrement of the amplitude (dry friction).
    Coulomb,
    /// Exponential decrement (viscous damping).
    Viscous,
}

impl DampingModel {
    /// `"coulomb"` or `"viscous"`.
    pub fn name(self) -> &'static str {
        match self {
            DampingModel::Coulomb => "coulomb",
            DampingModel::Viscous => "viscous",
        }
    }
}

/// One lobe's fitted amplitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfCycle {
    /// Start (zero crossing), s.
    pub start_s: f64,
    /// End (zero crossing), s.
    pub end_s: f64,
    /// Fitted velocity amplitude (positive).
    pub amplitude: f64,
}

/// What [`estimate_velocity`] found.
#[derive(Debug, Clone, PartialEq)]
pub struct DecayEstimate {
    /// From the zero crossings, Hz.
    pub natural_frequency_hz: f64,
    /// From the lobe centres, Hz.
    pub natural_frequency_hz_from_peaks: f64,
    /// Cycles spanned by the fitted amplitudes.
    pub cycles: f64,
    /// Fitted velocity drop per cycle (Coulomb line).
    pub velocity_drop_per_cycle: f64,
    /// Eq. 3.12 with that drop.
    pub coulomb_force: f64,
    /// From the exponential fit.
    pub viscous_damping_ratio: f64,
    /// RMS residual of the straight line.
    pub coulomb_residual: f64,
    /// RMS residual of the exponential.
    pub viscous_residual: f64,
    /// The model with the smaller residual.
    pub better_model: DampingModel,
    /// The combined Coulomb + viscous law (module docs, step 10).
    pub combined: CombinedFit,
    /// The half-cycles fitted.
    pub half_cycles: Vec<HalfCycle>,
    /// Estimated sensor noise RMS.
    pub noise_rms: f64,
    /// Velocity offset removed.
    pub offset: f64,
}

/// Friction and viscous damping fitted together to the lobe amplitudes (module docs,
/// step 10).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CombinedFit {
    /// Coulomb force with the viscous share taken out.
    pub coulomb_force: f64,
    /// Viscous damping ratio with the friction share taken out.
    pub viscous_damping_ratio: f64,
    /// RMS residual of the combined law.
    pub residual: f64,
}

/// Minimum usable half-cycles for the fits.
pub(crate) const MIN_USABLE_HALF_CYCLES: usize = 3;

fn check_record(time_s: &[f64], values: &[f64], column: &'static str) -> Result<f64> {
    if time_s.len() != values.len() {
        return Err(FrictionError::InvalidParameter {
            name: "record",
            value: format!("{} times, {} values", time_s.len(), values.len()),
            reason: "time and values must have the same length".into(),
        });
    }
    const NEEDED: usize = 32;
    if time_s.len() < NEEDED {
        return Err(FrictionError::TooFewSamples {
            samples: time_s.len(),
            needed: NEEDED,
        });
    }
    for (index, (t, v)) in time_s.iter().zip(values).enumerate() {
        if !t.is_finite() {
            return Err(FrictionError::NonFinite {
                column: "time_s",
                index,
            });
        }
        if !v.is_finite() {
            return Err(FrictionError::NonFinite { column, index });
        }
        if index > 0 && *t <= time_s[index - 1] {
            return Err(FrictionError::NonMonotonicTime {
                index,
                previous: time_s[index - 1],
                time: *t,
            });
        }
    }
    let dt = (time_s[time_s.len() - 1] - time_s[0]) / (time_s.len() - 1) as f64;
    for (index, w) in time_s.windows(2).enumerate() {
        if ((w[1] - w[0]) - dt).abs() > 0.01 * dt {
            return Err(FrictionError::InvalidParameter {
                name: "time_s",
                value: format!("{} s step at sample {}", w[1] - w[0], index + 1),
                reason: format!("sampling must be uniform (mean step {dt} s)"),
            });
        }
    }
    Ok(dt)
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

/// Noise RMS from the second differences: robust to a smooth signal and to outliers.
fn noise_rms(values: &[f64]) -> f64 {
    let mut d2: Vec<f64> = values
        .windows(3)
        .map(|w| (w[2] - 2.0 * w[1] + w[0]).abs())
        .collect();
    1.4826 * median(&mut d2) / 6f64.sqrt()
}

/// Frequency of the spectral peak (excluding DC), Hz.
fn dominant_frequency(values: &[f64], dt: f64) -> f64 {
    let n = (4 * values.len()).next_power_of_two();
    let (fft, _) = crate::linalg::fft::real_fft_plans(n);
    let mut input = fft.make_input_vec();
    input[..values.len()].copy_from_slice(values);
    let mut spectrum = fft.make_output_vec();
    fft.process(&mut input, &mut spectrum)
        .expect("buffer lengths from the plan");
    let mag: Vec<f64> = spectrum.iter().map(|c| c.norm()).collect();
    let k = (1..mag.len() - 1)
        .max_by(|a, b| mag[*a].total_cmp(&mag[*b]))
        .unwrap_or(1);
    let (a, b, c) = (mag[k - 1], mag[k], mag[k + 1]);
    let denom = a - 2.0 * b + c;
    let shift = if denom != 0.0 {
        0.5 * (a - c) / denom
    } else {
        0.0
    };
    (k as f64 + shift.clamp(-0.5, 0.5)) / (n as f64 * dt)
}

/// Least squares `y = a + b x`; returns (a, b, RMS residual).
fn line_fit(x: &[f64], y: &[f64]) -> (f64, f64, f64) {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxx: f64 = x.iter().map(|v| (v - mx) * (v - mx)).sum();
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let b = sxy / sxx;
    let a = my - b * mx;
    let rms = (x
        .iter()
        .zip(y)
        .map(|(xi, yi)| (yi - a - b * xi).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    (a, b, rms)
}

/// `(1 − e^(−σt))/σ`, continuous at σ = 0 (where it is `t`).
fn friction_basis(sigma: f64, t: f64) -> f64 {
    if sigma * t < 1e-12 {
        t
    } else {
        -(-sigma * t).exp_m1() / sigma
    }
}

/// For a given σ: least squares `y = A₀ e^(−σt) − r (1 − e^(−σt))/σ` with `r ≥ 0`;
/// returns (A₀, r, RMS residual).
fn combined_at(sigma: f64, t: &[f64], y: &[f64]) -> (f64, f64, f64) {
    let rms = |a0: f64, r: f64| {
        (t.iter()
            .zip(y)
            .map(|(ti, yi)| {
                (yi - a0 * (-sigma * ti).exp() + r * friction_basis(sigma, *ti)).powi(2)
            })
            .sum::<f64>()
            / t.len() as f64)
            .sqrt()
    };
    let (mut s11, mut s12, mut s22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (ti, yi) in t.iter().zip(y) {
        let (e, g) = ((-sigma * ti).exp(), -friction_basis(sigma, *ti));
        s11 += e * e;
        s12 += e * g;
        s22 += g * g;
        b1 += e * yi;
        b2 += g * yi;
    }
    let det = s11 * s22 - s12 * s12;
    if det > 1e-12 * s11 * s22 {
        let (a0, r) = ((s22 * b1 - s12 * b2) / det, (s11 * b2 - s12 * b1) / det);
        if r >= 0.0 {
            return (a0, r, rms(a0, r));
        }
    }
    // Friction would be negative (or the two laws are indistinguishable): the
    // exponential alone.
    let a0 = b1 / s11;
    (a0, 0.0, rms(a0, 0.0))
}

/// The combined Coulomb + viscous law (module docs, step 10) for amplitudes `y` at lobe
/// centres `t` (from the first), damped angular frequency `omega_d`.
fn combined_fit(t: &[f64], y: &[f64], omega_d: f64, stiffness: f64) -> CombinedFit {
    let cost = |sigma: f64| combined_at(sigma, t, y).2;
    // σ up to the decay of one cycle in e^-2π (ζ ≈ 0.7): beyond it there is no
    // oscillation to fit. A log grid, σ = 0 included, then golden section around the
    // best point.
    let top = omega_d;
    let floor = 1e-6 * omega_d;
    let grid: Vec<f64> = std::iter::once(0.0)
        .chain((0..=120).map(|i| floor * (top / floor).powf(i as f64 / 120.0)))
        .collect();
    let costs: Vec<f64> = grid.iter().map(|&sigma| cost(sigma)).collect();
    let best = (0..grid.len())
        .min_by(|a, b| costs[*a].total_cmp(&costs[*b]))
        .unwrap_or(0);
    let (mut lo, mut hi) = (
        grid[best.saturating_sub(1)],
        grid[(best + 1).min(grid.len() - 1)],
    );
    let phi = 0.5 * (5f64.sqrt() - 1.0);
    let (mut x1, mut x2) = (hi - phi * (hi - lo), lo + phi * (hi - lo));
    let (mut f1, mut f2) = (cost(x1), cost(x2));
    for _ in 0..80 {
        if f1 <= f2 {
            hi = x2;
            (x2, f2) = (x1, f1);
            x1 = hi - phi * (hi - lo);
            f1 = cost(x1);
        } else {
            lo = x1;
            (x1, f1) = (x2, f2);
            x2 = lo + phi * (hi - lo);
            f2 = cost(x2);
        }
    }
    let mut sigma = if f1 <= f2 { x1 } else { x2 };
    if costs[best] < f1.min(f2) {
        sigma = grid[best];
    }
    let (_, r, residual) = combined_at(sigma, t, y);
    let half = std::f64::consts::PI / omega_d;
    let omega2 = omega_d * omega_d + sigma * sigma;
    let gain = omega2 / omega_d * (-0.5 * sigma * half).exp();
    // (r/σ)(1 − d), continuous at σ = 0 where it is r·half.
    let drop = r * friction_basis(sigma, half);
    CombinedFit {
        coulomb_force: stiffness * drop / (2.0 * gain),
        viscous_damping_ratio: sigma / omega2.sqrt(),
        residual,
    }
}

/// Least squares `y = A₀ exp(−σ x)` for positive `y`; returns (A₀, σ, RMS residual).
fn exponential_fit(x: &[f64], y: &[f64]) -> (f64, f64, f64) {
    // Start: log-linear fit weighted by y² (the weights that make it approximate the
    // unweighted fit in y).
    let w: Vec<f64> = y.iter().map(|v| v * v).collect();
    let sw: f64 = w.iter().sum();
    let logs: Vec<f64> = y.iter().map(|v| v.max(f64::MIN_POSITIVE).ln()).collect();
    let mx = x.iter().zip(&w).map(|(a, b)| a * b).sum::<f64>() / sw;
    let my = logs.iter().zip(&w).map(|(a, b)| a * b).sum::<f64>() / sw;
    let sxx: f64 = x.iter().zip(&w).map(|(a, b)| b * (a - mx).powi(2)).sum();
    let sxy: f64 = x
        .iter()
        .zip(&logs)
        .zip(&w)
        .map(|((a, l), b)| b * (a - mx) * (l - my))
        .sum();
    let mut sigma = -sxy / sxx;
    let mut a0 = (my + sigma * mx).exp();
    // Gauss–Newton on (A₀, σ).
    for _ in 0..20 {
        let (mut j11, mut j12, mut j22, mut g1, mut g2) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (xi, yi) in x.iter().zip(y) {
            let e = (-sigma * xi).exp();
            let r = yi - a0 * e;
            let (da, ds) = (e, -a0 * xi * e);
            j11 += da * da;
            j12 += da * ds;
            j22 += ds * ds;
            g1 += da * r;
            g2 += ds * r;
        }
        let det = j11 * j22 - j12 * j12;
        if det.abs() < f64::MIN_POSITIVE {
            break;
        }
        let (step_a, step_s) = ((j22 * g1 - j12 * g2) / det, (j11 * g2 - j12 * g1) / det);
        a0 += step_a;
        sigma += step_s;
        if step_a.abs() <= 1e-14 * a0.abs() && step_s.abs() <= 1e-14 * sigma.abs().max(1e-300) {
            break;
        }
    }
    let rms = (x
        .iter()
        .zip(y)
        .map(|(xi, yi)| (yi - a0 * (-sigma * xi).exp()).powi(2))
        .sum::<f64>()
        / x.len() as f64)
        .sqrt();
    (a0, sigma, rms)
}

/// Analyses a free-decay velocity record; `stiffness` is `k` for Eq. 3.12.
///
/// # Errors
/// [`FrictionError::TooFewSamples`], [`FrictionError::NonMonotonicTime`],
/// [`FrictionError::NonFinite`], [`FrictionError::InvalidParameter`] (non-uniform
/// sampling, bad stiffness), [`FrictionError::NeverOscillates`] and
/// [`FrictionError::TooFewCycles`].
pub fn estimate_velocity(
    time_s: &[f64],
    velocity: &[f64],
    stiffness: f64,
) -> Result<DecayEstimate> {
    if !(stiffness > 0.0 && super::physical(stiffness)) {
        return Err(FrictionError::InvalidParameter {
            name: "stiffness",
            value: super::show(stiffness),
            reason: super::range_reason("positive"),
        });
    }
    let dt = check_record(time_s, velocity, "velocity")?;
    let noise = noise_rms(velocity);
    let offset = median(&mut velocity.to_vec());
    let centred: Vec<f64> = velocity.iter().map(|v| v - offset).collect();
    let f_rough = dominant_frequency(&centred, dt);
    let (smooth, threshold) = segmentation_signal(&centred, noise, f_rough, dt)?;
    let lobes = Lobes::find(time_s, &smooth, threshold, f_rough)?;
    let half_cycles = lobes.half_cycles(time_s, &smooth, &centred);
    let mut estimate = fit_decay(&lobes, half_cycles, stiffness);
    estimate.noise_rms = noise;
    estimate.offset = offset;
    Ok(estimate)
}

/// The record low-passed at `3 f_n` where the sampling allows it (for the segmentation)
/// and the threshold a lobe's height must pass: four times the noise left after the
/// filter, and 2 % of the largest value.
fn segmentation_signal(
    centred: &[f64],
    noise: f64,
    f_rough: f64,
    dt: f64,
) -> Result<(Vec<f64>, f64)> {
    let nyquist = 0.5 / dt;
    let cutoff = 3.0 * f_rough;
    let (smooth, noise_after) = if f_rough > 0.0 && cutoff < 0.9 * nyquist {
        let filter =
            LowPass::design(4, cutoff, dt).map_err(|e| FrictionError::InvalidParameter {
                name: "record",
                value: format!("{f_rough} Hz"),
                reason: e.to_string(),
            })?;
        match filter.apply(centred) {
            Ok(s) => (s, noise * (cutoff / nyquist).sqrt()),
            Err(_) => (centred.to_vec(), noise),
        }
    } else {
        (centred.to_vec(), noise)
    };
    let peak = smooth.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    Ok((smooth, (4.0 * noise_after).max(0.02 * peak)))
}

/// The zero crossings of the segmentation signal (linear interpolation, with the
/// record's ends) and the usable lobes between them.
struct Lobes {
    crossings: Vec<f64>,
    crossing_index: Vec<usize>,
    /// Lobe `l` lies between crossings `l` and `l + 1`.
    usable: Vec<usize>,
}

impl Lobes {
    /// The longest run of consecutive lobes higher than `threshold` and at least a
    /// quarter period long, less its first (the release transient) and last (the stuck
    /// tail).
    fn find(time_s: &[f64], smooth: &[f64], threshold: f64, f_rough: f64) -> Result<Self> {
        let mut crossings = vec![time_s[0]];
        let mut crossing_index = vec![0usize];
        for k in 1..smooth.len() {
            let (a, b) = (smooth[k - 1], smooth[k]);
            if (a < 0.0 && b >= 0.0) || (a > 0.0 && b <= 0.0) {
                let frac = if a != b { a / (a - b) } else { 0.0 };
                crossings.push(time_s[k - 1] + frac * (time_s[k] - time_s[k - 1]));
                crossing_index.push(k);
            }
        }
        crossings.push(time_s[time_s.len() - 1]);
        crossing_index.push(time_s.len());
        let quarter = 0.25 / f_rough.max(f64::MIN_POSITIVE);
        let valid: Vec<bool> = (0..crossings.len() - 1)
            .map(|l| {
                let lobe = &smooth[crossing_index[l]..crossing_index[l + 1]];
                let height = lobe.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                height > threshold && crossings[l + 1] - crossings[l] >= quarter
            })
            .collect();
        // The longest run of consecutive valid lobes.
        let (mut best_start, mut best_len, mut start) = (0usize, 0usize, 0usize);
        for l in 0..=valid.len() {
            if l == valid.len() || !valid[l] {
                if l - start > best_len {
                    best_len = l - start;
                    best_start = start;
                }
                start = l + 1;
            }
        }
        if best_len < 3 {
            return Err(FrictionError::NeverOscillates {
                half_cycles: best_len,
            });
        }
        // Drop the release transient and the stuck tail.
        let usable: Vec<usize> = (best_start + 1..best_start + best_len - 1).collect();
        if usable.len() < MIN_USABLE_HALF_CYCLES {
            return Err(FrictionError::TooFewCycles {
                usable: usable.len(),
                needed: MIN_USABLE_HALF_CYCLES,
            });
        }
        Ok(Lobes {
            crossings,
            crossing_index,
            usable,
        })
    }

    /// Half-sine amplitude of each usable lobe, from the unfiltered samples.
    fn half_cycles(&self, time_s: &[f64], smooth: &[f64], centred: &[f64]) -> Vec<HalfCycle> {
        let (crossings, crossing_index) = (&self.crossings, &self.crossing_index);
        let mut half_cycles = Vec::with_capacity(self.usable.len());
        for &l in &self.usable {
            let (ta, tb) = (crossings[l], crossings[l + 1]);
            let sign = smooth[(crossing_index[l] + crossing_index[l + 1]) / 2].signum();
            let (mut num, mut den) = (0.0, 0.0);
            for k in crossing_index[l]..crossing_index[l + 1] {
                let s = (std::f64::consts::PI * (time_s[k] - ta) / (tb - ta)).sin();
                num += sign * centred[k] * s;
                den += s * s;
            }
            half_cycles.push(HalfCycle {
                start_s: ta,
                end_s: tb,
                amplitude: num / den,
            });
        }
        half_cycles
    }
}

/// The frequencies (from the zero crossings and from the lobes' centres) and the decay
/// models fitted to the half-cycle amplitudes; the noise and the offset are left at 0
/// for the caller.
fn fit_decay(lobes: &Lobes, half_cycles: Vec<HalfCycle>, stiffness: f64) -> DecayEstimate {
    let usable = &lobes.usable;
    // Frequencies.
    let index: Vec<f64> = (0..=usable.len()).map(|i| i as f64).collect();
    let zero_times: Vec<f64> = (usable[0]..=usable[usable.len() - 1] + 1)
        .map(|l| lobes.crossings[l])
        .collect();
    let (_, half_period, _) = line_fit(&index, &zero_times);
    let natural_frequency_hz = 0.5 / half_period;
    let centres: Vec<f64> = half_cycles
        .iter()
        .map(|h| 0.5 * (h.start_s + h.end_s))
        .collect();
    let (_, half_from_peaks, _) = line_fit(&index[..centres.len()], &centres);
    let natural_frequency_hz_from_peaks = 0.5 / half_from_peaks;

    // Models.
    let amplitudes: Vec<f64> = half_cycles.iter().map(|h| h.amplitude).collect();
    let t0 = centres[0];
    let rel: Vec<f64> = centres.iter().map(|t| t - t0).collect();
    let (_, slope, coulomb_residual) = line_fit(&rel, &amplitudes);
    let (_, sigma, viscous_residual) = if amplitudes.iter().all(|a| *a > 0.0) {
        exponential_fit(&rel, &amplitudes)
    } else {
        (0.0, f64::NAN, f64::INFINITY)
    };
    let omega_d = 2.0 * std::f64::consts::PI * natural_frequency_hz;
    let viscous_damping_ratio = sigma / (sigma * sigma + omega_d * omega_d).sqrt();
    let velocity_drop_per_cycle = -slope / natural_frequency_hz;
    let cycles = rel[rel.len() - 1] * natural_frequency_hz;
    let coulomb_force = coulomb_force_from_decay(
        velocity_drop_per_cycle * cycles,
        stiffness,
        natural_frequency_hz,
        cycles,
    );
    let combined = combined_fit(&rel, &amplitudes, omega_d, stiffness);
    let better_model = if coulomb_residual <= viscous_residual {
        DampingModel::Coulomb
    } else {
        DampingModel::Viscous
    };
    DecayEstimate {
        natural_frequency_hz,
        natural_frequency_hz_from_peaks,
        cycles,
        velocity_drop_per_cycle,
        coulomb_force,
        viscous_damping_ratio,
        coulomb_residual,
        viscous_residual,
        better_model,
        combined,
        half_cycles,
        noise_rms: 0.0,
        offset: 0.0,
    }
}

/// Analyses a displacement record: the displacement is low-passed at 3 f_n (zero
/// phase), differentiated by central differences, and analysed as a velocity record.
///
/// # Errors
/// As [`estimate_velocity`].
pub fn estimate_displacement(
    time_s: &[f64],
    displacement: &[f64],
    stiffness: f64,
) -> Result<DecayEstimate> {
    let dt = check_record(time_s, displacement, "displacement")?;
    let offset = median(&mut displacement.to_vec());
    let centred: Vec<f64> = displacement.iter().map(|x| x - offset).collect();
    let f_rough = dominant_frequency(&centred, dt);
    let cutoff = 3.0 * f_rough;
    let smooth = if f_rough > 0.0 && cutoff < 0.45 / dt {
        LowPass::design(4, cutoff, dt)
            .and_then(|f| f.apply(&centred))
            .unwrap_or(centred)
    } else {
        centred
    };
    let n = smooth.len();
    let velocity: Vec<f64> = (0..n)
        .map(|k| {
            let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
            (smooth[b] - smooth[a]) / (time_s[b] - time_s[a])
        })
        .collect();
    estimate_velocity(time_s, &velocity, stiffness)
}

/// Mean and spread over several records (the thesis averaged four per actuator).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DecaySummary {
    /// Mean Coulomb force.
    pub coulomb_force_mean: f64,
    /// Sample standard deviation (0 for one record).
    pub coulomb_force_std: f64,
    /// Mean natural frequency, Hz.
    pub natural_frequency_hz_mean: f64,
    /// Mean Coulomb force of the combined law (viscous share taken out).
    pub combined_coulomb_force_mean: f64,
    /// Mean viscous damping ratio of the combined law.
    pub combined_viscous_damping_ratio_mean: f64,
}

/// Summary of several estimates.
///
/// # Panics
/// If `estimates` is empty.
#[track_caller]
pub fn summarize(estimates: &[DecayEstimate]) -> DecaySummary {
    assert!(!estimates.is_empty(), "at least one estimate");
    let n = estimates.len() as f64;
    let mean_of = |field: fn(&DecayEstimate) -> f64| estimates.iter().map(field).sum::<f64>() / n;
    let mean = mean_of(|e| e.coulomb_force);
    let var = if estimates.len() > 1 {
        estimates
            .iter()
            .map(|e| (e.coulomb_force - mean).powi(2))
            .sum::<f64>()
            / (n - 1.0)
    } else {
        0.0
    };
    DecaySummary {
        coulomb_force_mean: mean,
        coulomb_force_std: var.sqrt(),
        natural_frequency_hz_mean: mean_of(|e| e.natural_frequency_hz),
        combined_coulomb_force_mean: mean_of(|e| e.combined.coulomb_force),
        combined_viscous_damping_ratio_mean: mean_of(|e| e.combined.viscous_damping_ratio),
    }
}
