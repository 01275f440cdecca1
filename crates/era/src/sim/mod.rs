//! Simulators: the thesis's truth model (docs/src/design.md §2, thesis §4.2 and Table 5.2),
//! seeded synthetic lightly damped structures (§3), and FRF measurement noise.
//!
//! All random numbers come from [`Minstd`], the Park–Miller generator with Box–Muller
//! normals. It is a few lines, and it is portable: the Octave peer (the thesis's own
//! routines run in GNU Octave by `scripts/octave_peer.sh`; they are not shipped with the
//! repository) draws the same stream in the same order, so a seed gives bit-identical
//! noise and structures in both.

pub mod experiment;
pub mod fleet;
pub mod shaker;

use crate::data::frf::{uniform_lines, FrfData, Quantity};
use crate::data::statespace::{StateSpace, TimeDomain};
use crate::error::{EraError, Result};
use crate::pipeline::fit::frequency_response;
use faer::Mat;
use num_complex::Complex64;
use std::f64::consts::PI;

use crate::linalg::rng::Minstd;

/// The largest noise fraction [`add_noise`] takes: noise a thousand times the signal
/// already buries it; beyond, the noisy values head for overflow.
pub const MAX_NOISE_FRACTION: f64 = 1000.0;

/// Checks a noise fraction a front end was given: `{noise} {value}: must be a fraction
/// from 0 to 1000 (0.15 for 15 %)`, naming it as `naming` does.
///
/// # Errors
/// [`EraError::Invalid`] for a negative or non-finite fraction, or one above
/// [`MAX_NOISE_FRACTION`].
pub fn check_noise(naming: crate::params::Naming, noise: f64) -> Result<()> {
    let max = MAX_NOISE_FRACTION;
    if !(noise.is_finite() && (0.0..=max).contains(&noise)) {
        return crate::params::invalid(format!(
            "{} {noise}: must be a fraction from 0 to {max} (0.15 for 15 %)",
            naming.name("noise")
        ));
    }
    Ok(())
}

/// What `era simulate modal` (and Python's `simulate_modal`) is asked for: a
/// [`ModalSpec`] and the lines to evaluate it on.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct ModalRequest {
    /// The structure.
    pub spec: ModalSpec,
    /// Lines from 0 Hz.
    pub lines: usize,
    /// Line spacing, Hz.
    pub df_hz: f64,
}

impl ModalRequest {
    /// `spec` on `lines` lines from 0 Hz, `df_hz` apart.
    pub fn new(spec: ModalSpec, lines: usize, df_hz: f64) -> Self {
        ModalRequest { spec, lines, df_hz }
    }

    /// Checks sizes against [`crate::params::limits`] before anything is allocated, and the
    /// frequencies: positive spacing and band, `fmax` below the last line, a
    /// collocated set square. Messages name each parameter as `naming` does.
    ///
    /// # Errors
    /// [`EraError::Invalid`] or [`EraError::Limit`].
    pub fn check(&self, naming: crate::params::Naming) -> Result<()> {
        use crate::params::check_positive;
        use crate::params::limits::{CHANNELS, LINES, STATES, VALUES};
        let name = |key: &str| naming.name(key);
        let s = &self.spec;
        CHANNELS.check(name("outputs"), s.outputs as u64)?;
        CHANNELS.check(name("inputs"), s.inputs as u64)?;
        STATES.check_product(
            format!("{} (2 states each)", name("modes")),
            &[s.modes as u64, 2],
        )?;
        LINES.check(name("lines"), self.lines as u64)?;
        VALUES.check_product(
            format!(
                "{} x {} x {}",
                name("outputs"),
                name("inputs"),
                name("lines")
            ),
            &[s.outputs as u64, s.inputs as u64, self.lines as u64],
        )?;
        VALUES.check_product(
            format!(
                "{} x {} x {} x {} (modal FRF terms)",
                name("outputs"),
                name("inputs"),
                name("lines"),
                name("modes")
            ),
            &[
                s.outputs as u64,
                s.inputs as u64,
                self.lines as u64,
                s.modes as u64,
            ],
        )?;
        check_positive(naming, "df", self.df_hz, "line spacing in Hz")?;
        check_positive(naming, "fmin", s.fmin_hz, "frequency in Hz")?;
        check_positive(naming, "fmax", s.fmax_hz, "frequency in Hz")?;
        if s.collocated && s.outputs != s.inputs {
            return crate::params::invalid(format!(
                "{} needs as many outputs as inputs, got {} x {}",
                name("collocated"),
                s.outputs,
                s.inputs
            ));
        }
        let last = self.df_hz * (self.lines.saturating_sub(1)) as f64;
        if s.fmax_hz >= last {
            return crate::params::invalid(format!(
                "{} {} Hz is not below the last line, {last} Hz ({} {} at {} {})",
                name("fmax"),
                s.fmax_hz,
                name("lines"),
                self.lines,
                name("df"),
                self.df_hz
            ));
        }
        Ok(())
    }
}

/// Adds complex Gaussian noise to every FRF: the noise on each pair has an RMS of exactly
/// `fraction` times that pair's RMS magnitude (docs/src/design.md §2; thesis "15 % noise").
///
/// Draw order, for bit-for-bit agreement with the peer's `addnoise.m`: pairs input-major
/// (input 1: outputs 1…q, then input 2, …), and within a pair every line in order.
///
/// # Errors
/// [`EraError::InvalidParameter`] for a negative or non-finite fraction, or one above
/// [`MAX_NOISE_FRACTION`].
pub fn add_noise(frf: &FrfData, fraction: f64, seed: u64) -> Result<FrfData> {
    if !(fraction.is_finite() && (0.0..=MAX_NOISE_FRACTION).contains(&fraction)) {
        return Err(EraError::InvalidParameter {
            name: "noise",
            value: fraction.to_string(),
            reason: format!("the noise fraction must be a number from 0 to {MAX_NOISE_FRACTION} (0.15 for 15 %)").into(),
        });
    }
    let (q, p, lines) = (frf.outputs(), frf.inputs(), frf.lines());
    let mut rng = Minstd::new(seed);
    let mut values = frf.values().to_vec();
    for j in 0..p {
        for i in 0..q {
            let draws: Vec<Complex64> = (0..lines).map(|_| rng.complex_normal()).collect();
            let start = (i * p + j) * lines;
            let pair = &mut values[start..start + lines];
            let rms = |v: &[Complex64]| {
                (v.iter().map(|x| x.norm_sqr()).sum::<f64>() / v.len() as f64).sqrt()
            };
            let scale = fraction * rms(pair) / rms(&draws);
            for (v, g) in pair.iter_mut().zip(&draws) {
                *v += g * scale;
            }
        }
    }
    frf.with_values(values)
}

/// Table 5.2 of the thesis as printed, truth column: natural frequency (Hz) and
/// damping ratio (%) of the four truth-model modes, to 0.01.
pub const TABLE_5_2_TRUTH: [(f64, f64); 4] = [
    (1748.64, 5.02),
    (5031.80, 4.22),
    (7709.75, 5.22),
    (9458.39, 6.03),
];

/// Table 5.2 as printed, "ERA fit with noise" column (the thesis's own noise draw, which
/// is not recorded): frequency (Hz) and damping ratio (%).
pub const TABLE_5_2_ERA_NOISY: [(f64, f64); 4] = [
    (1747.70, 4.98),
    (5031.66, 4.28),
    (7708.31, 5.31),
    (9457.83, 6.03),
];

/// Sample rate of the truth-model FRFs, Hz (docs/src/design.md §2).
pub const TRUTH_SAMPLE_RATE_HZ: f64 = 25_600.0;
/// Number of truth-model FRF lines (0 … 12 800 Hz).
pub const TRUTH_LINES: usize = 1025;

/// The thesis's truth model (§4.2, Fig. 4.1) in continuous time: four masses
/// `m = 1e-3`, springs `k = 1e6` ground–m1–m2–m3–m4, dampers `c = 2` on the same links
/// plus m4–ground; forces F1–F3 on masses 1–3, displacements Y1–Y3 of masses 1–3.
/// State `[q1…q4, q̇1…q̇4]`.
pub fn truth_model() -> StateSpace {
    let (m, k, c) = (1e-3, 1e6, 2.0);
    // Chain stiffness (fixed–free) and damping (an extra damper from m4 to ground).
    let stiffness = |i: usize, j: usize| -> f64 {
        match (i, j) {
            (3, 3) => k,
            _ if i == j => 2.0 * k,
            _ if i.abs_diff(j) == 1 => -k,
            _ => 0.0,
        }
    };
    let damping = |i: usize, j: usize| -> f64 {
        if i == j {
            2.0 * c
        } else if i.abs_diff(j) == 1 {
            -c
        } else {
            0.0
        }
    };
    let a = Mat::from_fn(8, 8, |i, j| match (i < 4, j < 4) {
        (true, true) => 0.0,
        (true, false) => f64::from(u8::from(j - 4 == i)),
        (false, true) => -stiffness(i - 4, j) / m,
        (false, false) => -damping(i - 4, j - 4) / m,
    });
    let b = Mat::from_fn(
        8,
        3,
        |i, j| if i >= 4 && i - 4 == j { 1.0 / m } else { 0.0 },
    );
    let cm = Mat::from_fn(3, 8, |i, j| f64::from(u8::from(i == j)));
    StateSpace::new(a, b, cm, Mat::zeros(3, 3), TimeDomain::Continuous)
}

/// Truth-model displacement FRFs: the model discretised by zero-order hold at
/// [`TRUTH_SAMPLE_RATE_HZ`] and its discrete FRF at [`TRUTH_LINES`] lines from 0 to
/// 12 800 Hz, with optional noise `(fraction, seed)` from [`add_noise`].
///
/// # Errors
/// From [`add_noise`].
pub fn truth_model_frf(noise: Option<(f64, u64)>) -> Result<FrfData> {
    let ts = 1.0 / TRUTH_SAMPLE_RATE_HZ;
    let discrete = truth_model().c2d(ts)?;
    let lines = uniform_lines(
        TRUTH_LINES,
        TRUTH_SAMPLE_RATE_HZ / 2.0 / (TRUTH_LINES - 1) as f64,
    );
    let values = frequency_response(&discrete, &lines)?;
    let clean = FrfData::new(lines, 3, 3, values, Quantity::Displacement)?;
    match noise {
        Some((fraction, seed)) => add_noise(&clean, fraction, seed),
        None => Ok(clean),
    }
}

/// How to draw a synthetic structure (docs/src/design.md §3).
#[derive(Debug, Clone, PartialEq)]
pub struct ModalSpec {
    /// Outputs `q`.
    pub outputs: usize,
    /// Inputs `p`.
    pub inputs: usize,
    /// Number of modes `r`.
    pub modes: usize,
    /// Lowest natural frequency, Hz.
    pub fmin_hz: f64,
    /// Highest natural frequency, Hz.
    pub fmax_hz: f64,
    /// Smallest damping ratio (fraction).
    pub damping_min: f64,
    /// Largest damping ratio (fraction).
    pub damping_max: f64,
    /// Input shapes equal output shapes (`b_r = φ_r`; needs `q = p`).
    pub collocated: bool,
    /// Seed of the [`Minstd`] stream.
    pub seed: u64,
}

impl Default for ModalSpec {
    /// The DTA-like set of the peer's `mkdta.m`: 8×8, 40 modes in 0.5 … 14 Hz, ζ from
    /// 0.5 to 2 %, collocated, seed 987654321.
    fn default() -> Self {
        ModalSpec {
            outputs: 8,
            inputs: 8,
            modes: 40,
            fmin_hz: 0.5,
            fmax_hz: 14.0,
            damping_min: 0.005,
            damping_max: 0.02,
            collocated: true,
            seed: 987_654_321,
        }
    }
}

impl ModalSpec {
    /// A spec with the DTA-like defaults and the given size.
    pub fn new(outputs: usize, inputs: usize, modes: usize) -> Self {
        ModalSpec {
            outputs,
            inputs,
            modes,
            collocated: outputs == inputs,
            ..Self::default()
        }
    }
}

/// A structure with real normal modes and proportional damping:
/// `G_disp(ω) = Σ_r φ_r b_rᵀ / (ω_r² − ω² + 2jζ_r ω_r ω)`.
#[derive(Debug, Clone, PartialEq)]
pub struct ModalStructure {
    /// Natural frequencies, Hz, ascending.
    pub frequencies_hz: Vec<f64>,
    /// Damping ratios (fractions), paired with the frequencies.
    pub damping_ratios: Vec<f64>,
    /// Output shapes `φ_r` (q entries each), one per mode.
    pub output_shapes: Vec<Vec<f64>>,
    /// Input shapes `b_r` (p entries each), one per mode.
    pub input_shapes: Vec<Vec<f64>>,
}

impl ModalStructure {
    /// Draws a structure: `r` uniforms give the sorted frequencies, `r` more the damping
    /// ratios (paired in order), then `q·r` normals the output shapes (mode-major) and,
    /// unless collocated, `p·r` normals the input shapes. With the defaults this is the
    /// peer's `mkdta.m` set.
    ///
    /// # Errors
    /// [`EraError::InvalidParameter`] for empty sizes, a bad band or damping range, or
    /// `collocated` with `q ≠ p`.
    pub fn random(spec: &ModalSpec) -> Result<Self> {
        let bad = |name: &'static str, value: String, reason: &str| {
            Err(EraError::InvalidParameter {
                name,
                value,
                reason: reason.into(),
            })
        };
        if spec.outputs == 0 || spec.inputs == 0 {
            return bad(
                "outputs/inputs",
                format!("{}x{}", spec.outputs, spec.inputs),
                "need at least 1 each",
            );
        }
        if spec.modes == 0 {
            return bad("modes", "0".into(), "need at least one mode");
        }
        crate::params::limits::CHANNELS.check("outputs", spec.outputs as u64)?;
        crate::params::limits::CHANNELS.check("inputs", spec.inputs as u64)?;
        crate::params::limits::STATES
            .check_product("modes (2 states each)", &[spec.modes as u64, 2])?;
        crate::params::limits::VALUES.check_product(
            "mode shapes ((outputs + inputs) x modes)",
            &[
                (spec.outputs as u64).saturating_add(spec.inputs as u64),
                spec.modes as u64,
            ],
        )?;
        if !(spec.fmin_hz > 0.0 && spec.fmax_hz >= spec.fmin_hz && spec.fmax_hz.is_finite()) {
            return bad(
                "fmin/fmax",
                format!("{}..{}", spec.fmin_hz, spec.fmax_hz),
                "need 0 < fmin <= fmax",
            );
        }
        if !(spec.damping_min > 0.0
            && spec.damping_max >= spec.damping_min
            && spec.damping_max < 1.0)
        {
            return bad(
                "damping",
                format!("{}..{}", spec.damping_min, spec.damping_max),
                "need 0 < min <= max < 1 (fractions, not percent)",
            );
        }
        if spec.collocated && spec.outputs != spec.inputs {
            return bad(
                "collocated",
                format!("{}x{}", spec.outputs, spec.inputs),
                "a collocated set must be square",
            );
        }
        let mut rng = Minstd::new(spec.seed);
        let r = spec.modes;
        let mut frequencies_hz: Vec<f64> = (0..r)
            .map(|_| spec.fmin_hz + (spec.fmax_hz - spec.fmin_hz) * rng.uniform())
            .collect();
        frequencies_hz.sort_by(f64::total_cmp);
        let damping_ratios = (0..r)
            .map(|_| spec.damping_min + (spec.damping_max - spec.damping_min) * rng.uniform())
            .collect();
        let output_shapes: Vec<Vec<f64>> = (0..r)
            .map(|_| (0..spec.outputs).map(|_| rng.normal()).collect())
            .collect();
        let input_shapes = if spec.collocated {
            output_shapes.clone()
        } else {
            (0..r)
                .map(|_| (0..spec.inputs).map(|_| rng.normal()).collect())
                .collect()
        };
        Ok(ModalStructure {
            frequencies_hz,
            damping_ratios,
            output_shapes,
            input_shapes,
        })
    }

    /// Outputs `q`.
    pub fn outputs(&self) -> usize {
        self.output_shapes.first().map_or(0, Vec::len)
    }
    /// Inputs `p`.
    pub fn inputs(&self) -> usize {
        self.input_shapes.first().map_or(0, Vec::len)
    }

    /// Continuous poles with positive imaginary part, `−ζω + jω√(1−ζ²)`, one per mode.
    pub fn poles(&self) -> Vec<Complex64> {
        self.frequencies_hz
            .iter()
            .zip(&self.damping_ratios)
            .map(|(f, z)| {
                let w = 2.0 * PI * f;
                Complex64::new(-z * w, w * (1.0 - z * z).sqrt())
            })
            .collect()
    }

    /// Analytic FRFs of `quantity` at `lines` lines `spacing_hz` apart (velocity `jω·G`,
    /// acceleration `−ω²·G`).
    ///
    /// # Errors
    /// [`EraError::InvalidParameter`] for fewer than 2 lines or a non-positive spacing;
    /// [`EraError::Limit`] when the lines, the values or the terms (values × modes) are
    /// above [`crate::params::limits::LINES`] or [`crate::params::limits::VALUES`].
    pub fn frf(&self, lines: usize, spacing_hz: f64, quantity: Quantity) -> Result<FrfData> {
        if lines < 2 || !(spacing_hz > 0.0 && spacing_hz.is_finite()) {
            return Err(EraError::InvalidParameter {
                name: "lines/df",
                value: format!("{lines} lines at {spacing_hz} Hz"),
                reason: "need at least 2 lines and a positive spacing".into(),
            });
        }
        crate::params::limits::LINES.check("lines", lines as u64)?;
        let (q, p) = (self.outputs(), self.inputs());
        crate::params::limits::VALUES.check_product(
            "FRF values (outputs x inputs x lines)",
            &[q as u64, p as u64, lines as u64],
        )?;
        // The work: one term per mode and value.
        crate::params::limits::VALUES.check_product(
            "modal FRF terms (outputs x inputs x lines x modes)",
            &[
                q as u64,
                p as u64,
                lines as u64,
                self.frequencies_hz.len() as u64,
            ],
        )?;
        let freq = uniform_lines(lines, spacing_hz);
        let mut values = vec![Complex64::new(0.0, 0.0); q * p * lines];
        for (r, (fr, zr)) in self
            .frequencies_hz
            .iter()
            .zip(&self.damping_ratios)
            .enumerate()
        {
            let wr = 2.0 * PI * fr;
            for (k, f) in freq.iter().enumerate() {
                let w = 2.0 * PI * f;
                let receptance = 1.0 / Complex64::new(wr * wr - w * w, 2.0 * zr * wr * w);
                let factor = match quantity {
                    Quantity::Displacement => receptance,
                    Quantity::Velocity => Complex64::new(0.0, w) * receptance,
                    Quantity::Acceleration => -w * w * receptance,
                };
                for i in 0..q {
                    for j in 0..p {
                        values[(i * p + j) * lines + k] +=
                            factor * self.output_shapes[r][i] * self.input_shapes[r][j];
                    }
                }
            }
        }
        if values
            .iter()
            .any(|v| !(v.re.is_finite() && v.im.is_finite()))
        {
            return Err(EraError::InvalidParameter {
                name: "lines/df",
                value: format!("{lines} lines at {spacing_hz} Hz"),
                reason: crate::params::names::Prose::from(format!(
                    "the {quantity} FRFs overflow at these frequencies (up to {} Hz): lower ",
                    spacing_hz * (lines - 1) as f64
                ))
                .param(crate::params::names::Param::Df)
                .text(" or ")
                .param(crate::params::names::Param::Lines),
            });
        }
        FrfData::new(freq, q, p, values, quantity)
    }

    /// Continuous state-space model whose outputs are `quantity` (2 states per mode:
    /// modal displacement and velocity). Acceleration outputs have `D = Σ φ_r b_rᵀ`.
    pub fn state_space(&self, quantity: Quantity) -> StateSpace {
        let r = self.frequencies_hz.len();
        let (q, p) = (self.outputs(), self.inputs());
        let mut a = Mat::<f64>::zeros(2 * r, 2 * r);
        let mut b = Mat::<f64>::zeros(2 * r, p);
        let mut c = Mat::<f64>::zeros(q, 2 * r);
        let mut d = Mat::<f64>::zeros(q, p);
        for m in 0..r {
            let w = 2.0 * PI * self.frequencies_hz[m];
            let z = self.damping_ratios[m];
            a[(2 * m, 2 * m + 1)] = 1.0;
            a[(2 * m + 1, 2 * m)] = -w * w;
            a[(2 * m + 1, 2 * m + 1)] = -2.0 * z * w;
            for j in 0..p {
                b[(2 * m + 1, j)] = self.input_shapes[m][j];
            }
            for i in 0..q {
                let phi = self.output_shapes[m][i];
                match quantity {
                    Quantity::Displacement => c[(i, 2 * m)] = phi,
                    Quantity::Velocity => c[(i, 2 * m + 1)] = phi,
                    Quantity::Acceleration => {
                        c[(i, 2 * m)] = -w * w * phi;
                        c[(i, 2 * m + 1)] = -2.0 * z * w * phi;
                        for j in 0..p {
                            d[(i, j)] += phi * self.input_shapes[m][j];
                        }
                    }
                }
            }
        }
        StateSpace::new(a, b, c, d, TimeDomain::Continuous)
    }
}

/// Markov blocks of a lightly damped discrete structure, for scale tests and benchmarks:
/// `Y_k = Σ_r φ_r b_rᵀ e^(−ζ_r ω_r k) sin(ω_r √(1−ζ_r²) k)` for `k ≥ 1` (`Y_0 = 0`), with
/// `modes` frequencies uniform in 0.01 … 0.45 cycles per sample, ζ in 0.5 … 2 %, and
/// normal shapes, all drawn from [`Minstd`] with `seed`. The sequence has rank `2·modes`.
pub fn lightly_damped_markov(
    outputs: usize,
    inputs: usize,
    modes: usize,
    samples: usize,
    seed: u64,
) -> crate::sources::frf::MarkovSequence {
    let mut rng = Minstd::new(seed);
    let freq: Vec<f64> = (0..modes).map(|_| 0.01 + 0.44 * rng.uniform()).collect();
    let zeta: Vec<f64> = (0..modes).map(|_| 0.005 + 0.015 * rng.uniform()).collect();
    let phi: Vec<Vec<f64>> = (0..modes)
        .map(|_| (0..outputs).map(|_| rng.normal()).collect())
        .collect();
    let b: Vec<Vec<f64>> = (0..modes)
        .map(|_| (0..inputs).map(|_| rng.normal()).collect())
        .collect();
    let mut markov = crate::sources::frf::MarkovSequence::zeros(outputs, inputs, samples);
    for r in 0..modes {
        let w = 2.0 * PI * freq[r];
        let wd = w * (1.0 - zeta[r] * zeta[r]).sqrt();
        for k in 1..samples {
            let h = (-zeta[r] * w * k as f64).exp() * (wd * k as f64).sin();
            for (i, phi_i) in phi[r].iter().enumerate() {
                for (j, b_j) in b[r].iter().enumerate() {
                    let v = markov.get(k, i, j) + phi_i * b_j * h;
                    markov.set(k, i, j, v);
                }
            }
        }
    }
    markov
}

/// Time response of a discrete model from rest: `x_{k+1} = A x_k + B u_k`,
/// `y_k = C x_k + D u_k`. `inputs[j]` is input `j`'s samples (all of one length); the
/// result is `outputs[i]`, of the same length. For testing FRF estimation and for
/// synthetic time histories.
///
/// # Errors
/// [`EraError::InvalidParameter`] for a continuous model; [`EraError::ShapeMismatch`]
/// when the number of input channels differs from the model's or they differ in length.
pub fn time_response(model: &StateSpace, inputs: &[Vec<f64>]) -> Result<Vec<Vec<f64>>> {
    if model.sample_time_s().is_none() {
        return Err(EraError::InvalidParameter {
            name: "model",
            value: "continuous".into(),
            reason: "time_response needs a discrete model (StateSpace::c2d)".into(),
        });
    }
    let (n, p, q) = (model.states(), model.inputs(), model.outputs());
    if inputs.len() != p {
        return Err(EraError::ShapeMismatch {
            what: "input channels of the model".into(),
            expected: p,
            got: inputs.len(),
        });
    }
    let samples = inputs.first().map_or(0, Vec::len);
    if let Some(bad) = inputs.iter().find(|u| u.len() != samples) {
        return Err(EraError::ShapeMismatch {
            what: "samples per input channel".into(),
            expected: samples,
            got: bad.len(),
        });
    }
    let mut x = vec![0.0; n];
    let mut next = vec![0.0; n];
    let mut out = vec![vec![0.0; samples]; q];
    for k in 0..samples {
        for (i, channel) in out.iter_mut().enumerate() {
            let mut v = 0.0;
            for (s, xs) in x.iter().enumerate() {
                v += model.c[(i, s)] * xs;
            }
            for (j, u) in inputs.iter().enumerate() {
                v += model.d[(i, j)] * u[k];
            }
            channel[k] = v;
        }
        for (r, nr) in next.iter_mut().enumerate() {
            let mut v = 0.0;
            for (s, xs) in x.iter().enumerate() {
                v += model.a[(r, s)] * xs;
            }
            for (j, u) in inputs.iter().enumerate() {
                v += model.b[(r, j)] * u[k];
            }
            *nr = v;
        }
        std::mem::swap(&mut x, &mut next);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn minstd_matches_park_miller_check_value() {
        // Park & Miller (1988): from seed 1, the 10 000th value is 1043618065.
        let mut g = Minstd::new(1);
        for _ in 0..10_000 {
            g.uniform();
        }
        assert_eq!(g.state, 1_043_618_065);
    }

    #[test]
    fn noise_has_the_requested_rms() {
        let clean = truth_model_frf(None).unwrap();
        let noisy = add_noise(&clean, 0.15, 7).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let a = clean.pair(i, j);
                let b = noisy.pair(i, j);
                let rms = |f: &dyn Fn(usize) -> f64| {
                    ((0..a.len()).map(f).sum::<f64>() / a.len() as f64).sqrt()
                };
                let signal = rms(&|k| a[k].norm_sqr());
                let noise = rms(&|k| (b[k] - a[k]).norm_sqr());
                assert!((noise / signal - 0.15).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn modal_frf_agrees_with_its_state_space() {
        let spec = ModalSpec {
            collocated: false,
            ..ModalSpec::new(3, 2, 4)
        };
        let s = ModalStructure::random(&spec).unwrap();
        for quantity in [
            Quantity::Displacement,
            Quantity::Velocity,
            Quantity::Acceleration,
        ] {
            let frf = s.frf(50, 0.3, quantity).unwrap();
            let ss = s.state_space(quantity);
            let g = frequency_response(&ss, frf.frequency_hz()).unwrap();
            for (x, y) in frf.values().iter().zip(&g) {
                assert!(
                    (x - y).norm() <= 1e-9 * (1.0 + x.norm()),
                    "{quantity}: {x} vs {y}"
                );
            }
        }
    }
}
