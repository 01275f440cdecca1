//! The pole–residue model and its linear basis: which real columns the residues and
//! residual terms multiply, their derivatives with respect to the poles, and the data of
//! the fit arranged in blocks that share one basis.

use super::{RefineOptions, Residuals, Weighting};
use crate::data::frf::{FrfData, Quantity};
use crate::error::{EraError, Result};
use faer::Mat;
use num_complex::Complex64;
use std::f64::consts::PI;

/// `κ`: the data is `(jω)^κ` times displacement.
pub(crate) fn order(quantity: Quantity) -> i32 {
    match quantity {
        Quantity::Displacement => 0,
        Quantity::Velocity => 1,
        Quantity::Acceleration => 2,
    }
}

/// `z^n` for a small integer `n ≥ 0` by repeated products (exact for `n ≤ 2`).
pub(crate) fn power(z: Complex64, n: i32) -> Complex64 {
    (0..n).fold(Complex64::new(1.0, 0.0), |acc, _| acc * z)
}

/// `(jω)^e` for `e ∈ {−2, −1, 0}` (the residual terms), also at other small `e`.
pub(crate) fn jw_power(omega: f64, e: i32) -> Complex64 {
    Complex64::new(0.0, omega).powi(e)
}

/// The residual term `(jω)^e`, or in the z-domain its zero-order-hold image: `1`,
/// `Ts/(z − 1)` for `1/s`, `Ts²(z + 1)/(2(z − 1)²)` for `1/s²`.
pub(crate) fn residual_factor(omega: f64, e: i32, sample_time_s: Option<f64>) -> Complex64 {
    match sample_time_s {
        None => jw_power(omega, e),
        Some(ts) => {
            let z = Complex64::from_polar(1.0, omega * ts);
            match e {
                -1 => ts / (z - 1.0),
                -2 => ts * ts * (z + 1.0) / (2.0 * (z - 1.0) * (z - 1.0)),
                _ => Complex64::new(1.0, 0.0),
            }
        }
    }
}

/// Which residual term a basis column carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ResidualKind {
    Lower,
    Upper,
}

/// The columns of the linear problem: per mode `per_mode` real columns (2: `Re R`,
/// `Im R`; 1 with real modes: `Im R`), then one column per residual term.
#[derive(Debug, Clone)]
pub(crate) struct Layout {
    pub kappa: i32,
    /// `Some(Ts)`: the zero-order-hold (z-domain) model, `z = e^(jωTs)`.
    pub sample_time_s: Option<f64>,
    pub per_mode: usize,
    /// `(kind, exponent e of (jω)^e in the data's quantity)`.
    pub residuals: Vec<(ResidualKind, i32)>,
}

impl Layout {
    pub(crate) fn new(quantity: Quantity, options: &RefineOptions) -> Self {
        let kappa = order(quantity);
        let lower = (ResidualKind::Lower, kappa - 2);
        let upper = (ResidualKind::Upper, 0);
        let residuals = match options.residuals {
            Residuals::None => vec![],
            Residuals::Lower => vec![lower],
            Residuals::Upper => vec![upper],
            // For acceleration data both terms are a constant: fitted once, as `upper`.
            Residuals::Both if kappa == 2 => vec![upper],
            Residuals::Both => vec![lower, upper],
        };
        Layout {
            kappa,
            sample_time_s: options.sample_time_s,
            per_mode: if options.real_modes { 1 } else { 2 },
            residuals,
        }
    }
    pub(crate) fn columns(&self, modes: usize) -> usize {
        modes * self.per_mode + self.residuals.len()
    }
}

/// `g(s) = s^κ/(jω − s)` and `g'(s) = κ s^(κ−1)/(jω − s) + s^κ/(jω − s)²`; in the
/// z-domain `g = 1/(z − e^(sTs))`, `g' = Ts e^(sTs)/(z − e^(sTs))²`.
pub(crate) fn partial_fraction(
    s: Complex64,
    omega: f64,
    kappa: i32,
    sample_time_s: Option<f64>,
) -> (Complex64, Complex64) {
    if let Some(ts) = sample_time_s {
        let z = Complex64::from_polar(1.0, omega * ts);
        let lambda = (s * ts).exp();
        let inv = 1.0 / (z - lambda);
        return (inv, ts * lambda * inv * inv);
    }
    let inv = 1.0 / (Complex64::new(0.0, omega) - s);
    let sk = power(s, kappa);
    let g = sk * inv;
    let dg = if kappa == 0 {
        g * inv
    } else {
        f64::from(kappa) * power(s, kappa - 1) * inv + g * inv
    };
    (g, dg)
}

/// The mode's columns at one line: `Re R` multiplies `g(s) + g(s̄)`, `Im R` multiplies
/// `j(g(s) − g(s̄))`, so that `R g(s) + R̄ g(s̄) = Re R·(…) + Im R·(…)`.
pub(crate) fn mode_columns(
    s: Complex64,
    omega: f64,
    kappa: i32,
    sample_time_s: Option<f64>,
) -> [Complex64; 2] {
    let (g1, _) = partial_fraction(s, omega, kappa, sample_time_s);
    let (g2, _) = partial_fraction(s.conj(), omega, kappa, sample_time_s);
    conjugate_columns(g1, g2)
}

/// A mode's two real columns from a function of its pole at `s` (`at_s`) and at `s̄`
/// (`at_conj`): `Re R` multiplies `at_s + at_conj` and `Im R` multiplies
/// `j(at_s − at_conj)`. The basis, its derivatives and its second derivatives all take
/// this form.
fn conjugate_columns(at_s: Complex64, at_conj: Complex64) -> [Complex64; 2] {
    let j = Complex64::new(0.0, 1.0);
    [at_s + at_conj, j * (at_s - at_conj)]
}

/// Derivatives of the two mode columns for `ds/dθ = delta` (and `ds̄/dθ = conj(delta)`).
fn mode_column_derivatives(
    s: Complex64,
    omega: f64,
    layout: &Layout,
    delta: Complex64,
) -> [Complex64; 2] {
    let (_, d1) = partial_fraction(s, omega, layout.kappa, layout.sample_time_s);
    let (_, d2) = partial_fraction(s.conj(), omega, layout.kappa, layout.sample_time_s);
    conjugate_columns(d1 * delta, d2 * delta.conj())
}

/// The nonlinear parameters of one mode: `s = −σ + jω_d` with `x = ln σ` (stability
/// enforced) or `x = σ`, and `ω_d`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PoleParameters {
    pub log_damping: bool,
}

impl PoleParameters {
    pub(crate) fn pole(&self, theta: &[f64], r: usize) -> Complex64 {
        let x = theta[2 * r];
        let sigma = if self.log_damping { x.exp() } else { x };
        Complex64::new(-sigma, theta[2 * r + 1])
    }
    pub(crate) fn poles(&self, theta: &[f64]) -> Vec<Complex64> {
        (0..theta.len() / 2).map(|r| self.pole(theta, r)).collect()
    }
    /// `θ` of poles (which must have `Re s < 0` when the damping is logarithmic).
    pub(crate) fn theta(&self, poles: &[Complex64]) -> Vec<f64> {
        poles
            .iter()
            .flat_map(|s| {
                let sigma = -s.re;
                [if self.log_damping { sigma.ln() } else { sigma }, s.im]
            })
            .collect()
    }
    /// `ds/dθ` for the damping parameter and the frequency parameter of pole `s`.
    pub(crate) fn deltas(&self, s: Complex64) -> [Complex64; 2] {
        let d_sigma = if self.log_damping { s.re } else { -1.0 };
        [Complex64::new(d_sigma, 0.0), Complex64::new(0.0, 1.0)]
    }
    /// `∂²s/∂θ_t∂θ_t'` for the couples [`PARAMETER_COUPLES`] of pole `s`: only the
    /// logarithmic damping's own, `∂²(−e^x)/∂x² = Re s`.
    pub(crate) fn second_deltas(&self, s: Complex64) -> [Complex64; 3] {
        let zero = Complex64::new(0.0, 0.0);
        let own = if self.log_damping {
            Complex64::new(s.re, 0.0)
        } else {
            zero
        };
        [own, zero, zero]
    }
}

/// Writes a mode's columns at line `k` (the last `pm` of `columns`: both, or the real
/// mode's one) into `out` from column `first` on: real parts in row `k`, imaginary parts
/// in row `L + k`.
fn put_mode_columns(
    out: &mut Mat<f64>,
    k: usize,
    columns: [Complex64; 2],
    pm: usize,
    first: usize,
) {
    let lines = out.nrows() / 2;
    for local in 0..pm {
        let v = columns[local + 2 - pm];
        out[(k, first + local)] = v.re;
        out[(lines + k, first + local)] = v.im;
    }
}

/// Real basis, `2L × columns`: rows `0..L` the real parts, `L..2L` the imaginary parts.
pub(crate) fn basis(layout: &Layout, omega: &[f64], poles: &[Complex64]) -> Mat<f64> {
    let lines = omega.len();
    let cols = layout.columns(poles.len());
    let mut out = Mat::<f64>::zeros(2 * lines, cols);
    let pm = layout.per_mode;
    for (r, &s) in poles.iter().enumerate() {
        for (k, &w) in omega.iter().enumerate() {
            let c = mode_columns(s, w, layout.kappa, layout.sample_time_s);
            put_mode_columns(&mut out, k, c, pm, r * pm);
        }
    }
    for (m, &(_, e)) in layout.residuals.iter().enumerate() {
        let col = poles.len() * pm + m;
        for (k, &w) in omega.iter().enumerate() {
            let v = residual_factor(w, e, layout.sample_time_s);
            out[(k, col)] = v.re;
            out[(lines + k, col)] = v.im;
        }
    }
    out
}

/// Derivative columns, `2L × (2N·per_mode)`: column `(2r + t)·per_mode + c` is the
/// derivative of mode `r`'s column `c` with respect to its parameter `t` (0: damping,
/// 1: frequency).
pub(crate) fn basis_derivatives(
    layout: &Layout,
    parameters: PoleParameters,
    omega: &[f64],
    poles: &[Complex64],
) -> Mat<f64> {
    let lines = omega.len();
    let pm = layout.per_mode;
    let mut out = Mat::<f64>::zeros(2 * lines, 2 * poles.len() * pm);
    for (r, &s) in poles.iter().enumerate() {
        for (t, delta) in parameters.deltas(s).into_iter().enumerate() {
            for (k, &w) in omega.iter().enumerate() {
                let c = mode_column_derivatives(s, w, layout, delta);
                put_mode_columns(&mut out, k, c, pm, (2 * r + t) * pm);
            }
        }
    }
    out
}

/// `g''(s)` of [`partial_fraction`]: `κ(κ−1) s^(κ−2)/(jω − s) + 2κ s^(κ−1)/(jω − s)² +
/// 2 s^κ/(jω − s)³`; in the z-domain `Ts² λ (z − λ + 2λ)/(z − λ)³` with `λ = e^(sTs)`.
fn partial_fraction_second(
    s: Complex64,
    omega: f64,
    kappa: i32,
    sample_time_s: Option<f64>,
) -> Complex64 {
    if let Some(ts) = sample_time_s {
        let z = Complex64::from_polar(1.0, omega * ts);
        let lambda = (s * ts).exp();
        let inv = 1.0 / (z - lambda);
        return ts * ts * lambda * inv * inv * (1.0 + 2.0 * lambda * inv);
    }
    let inv = 1.0 / (Complex64::new(0.0, omega) - s);
    let k = f64::from(kappa);
    let mut out = 2.0 * power(s, kappa) * inv * inv * inv;
    if kappa != 0 {
        out += 2.0 * k * power(s, kappa - 1) * inv * inv;
        if kappa != 1 {
            out += k * (k - 1.0) * power(s, kappa - 2) * inv;
        }
    }
    out
}

/// The couples `(t, t')` of a mode's two parameters whose second derivatives
/// [`basis_second_derivatives`] holds, in its column order.
pub(crate) const PARAMETER_COUPLES: [(usize, usize); 3] = [(0, 0), (0, 1), (1, 1)];

/// Second derivative columns, `2L × (3N·per_mode)`: column `(3r + c)·per_mode + l` is
/// the second derivative of mode `r`'s column `l` with respect to its parameters
/// [`PARAMETER_COUPLES`]`[c]` (a mode's columns depend on its own pole only, so no
/// other second derivative is nonzero). With `ds/dθ_t = δ_t` and
/// `∂²s/∂θ_t∂θ_t' = κ_tt'`, `∂²g(s)/∂θ_t∂θ_t' = g''(s) δ_t δ_t' + g'(s) κ_tt'`.
pub(crate) fn basis_second_derivatives(
    layout: &Layout,
    parameters: PoleParameters,
    omega: &[f64],
    poles: &[Complex64],
) -> Mat<f64> {
    let lines = omega.len();
    let pm = layout.per_mode;
    let (kappa, ts) = (layout.kappa, layout.sample_time_s);
    let mut out = Mat::<f64>::zeros(2 * lines, 3 * poles.len() * pm);
    for (r, &s) in poles.iter().enumerate() {
        let delta = parameters.deltas(s);
        let curvature = parameters.second_deltas(s);
        let couples = PARAMETER_COUPLES.map(|(t, t2)| delta[t] * delta[t2]);
        for (k, &w) in omega.iter().enumerate() {
            // g' and g'' at s and at s̄, once per line for the three couples.
            let (_, d1) = partial_fraction(s, w, kappa, ts);
            let (_, d2) = partial_fraction(s.conj(), w, kappa, ts);
            let (e1, e2) = (
                partial_fraction_second(s, w, kappa, ts),
                partial_fraction_second(s.conj(), w, kappa, ts),
            );
            for (c, (&dd, &kk)) in couples.iter().zip(&curvature).enumerate() {
                let a = e1 * dd + d1 * kk;
                let b = e2 * dd.conj() + d2 * kk.conj();
                put_mode_columns(&mut out, k, conjugate_columns(a, b), pm, (3 * r + c) * pm);
            }
        }
    }
    out
}

/// Pairs that share one coefficient vector (one pair, or `(i, j)` and `(j, i)` when
/// reciprocal), fitted against one stacked basis.
#[derive(Debug, Clone)]
pub(crate) struct Block {
    /// Square-root weights of each stacked segment per band line (`None`: 1).
    pub segment_weights: Vec<Option<Vec<f64>>>,
    /// For each unit, the pair indices (`i·p + j`) sharing its coefficients: one per
    /// segment, or all fitted through their weighted mean (`scales`).
    pub units: Vec<Vec<usize>>,
    /// Per unit, what its coefficients come out scaled by: 1, or `√W` when the weights
    /// are constant over the band (uniform, or one per pair such as
    /// [`Weighting::PairNoise`]'s). Then the pairs `k` of a unit, with square-root
    /// weights `w_k`, are fitted through `√W·ȳ`, `W = Σ w_k²`, `ȳ = Σ w_k² y_k / W`:
    /// the same minimiser, Jacobian and gradient as fitting each pair with its weight
    /// (`Σ w_k²‖y_k − Φc‖² = W‖ȳ − Φc‖² + Σ w_k²‖y_k − ȳ‖²`), with one basis and one
    /// QR for every pair. The cost misses the last sum, which is `cost_offset`.
    pub scales: Vec<f64>,
    /// The part of the cost that no parameter changes.
    pub cost_offset: f64,
    /// Weighted data, `segments·2L × units`.
    pub rhs: Mat<f64>,
}

impl Block {
    /// `√W` for a unit fitted through its weighted mean, 1 otherwise: its coefficients
    /// are divided by this.
    pub(crate) fn unit_scale(&self, u: usize) -> f64 {
        self.scales[u]
    }

    /// The basis (or its derivative columns) stacked and weighted per segment.
    pub(crate) fn stack(&self, unweighted: &Mat<f64>) -> Mat<f64> {
        let rows = unweighted.nrows();
        let lines = rows / 2;
        let segments = self.segment_weights.len();
        Mat::from_fn(segments * rows, unweighted.ncols(), |i, c| {
            let (seg, row) = (i / rows, i % rows);
            let w = self.segment_weights[seg]
                .as_ref()
                .map_or(1.0, |w| w[row % lines]);
            w * unweighted[(row, c)]
        })
    }
}

/// Everything fixed during the fit: the band, the layout, the data in blocks.
#[derive(Debug, Clone)]
pub(crate) struct Problem {
    pub layout: Layout,
    pub parameters: PoleParameters,
    pub outputs: usize,
    pub inputs: usize,
    pub quantity: Quantity,
    pub band: (usize, usize),
    /// `ω_k = 2π f_k` over the band, rad/s.
    pub omega: Vec<f64>,
    pub blocks: Vec<Block>,
    /// Data over the band, `[pair][line]`.
    pub data: Vec<Vec<Complex64>>,
    /// `Σ |G|²` over the band, unweighted.
    pub data_norm2: f64,
    /// Real observations `2·L·q·p` (each pair counted once).
    pub observations: usize,
    /// Square-root weight of each pair when the weights are constant over the band
    /// (uniform: all 1), `None` when they vary from line to line.
    pub pair_weights: Option<Vec<f64>>,
    /// [`RefineOptions::rank_one`].
    pub rank_one: bool,
    /// [`RefineOptions::reciprocal`].
    pub reciprocal: bool,
}

fn invalid(name: &'static str, value: String, reason: impl Into<String>) -> EraError {
    EraError::InvalidParameter {
        name,
        value,
        reason: reason.into().into(),
    }
}

/// The fitted band as line indices `first..end`: the options' band, checked, or every
/// line above 0 Hz; with a sample time, every line of it below the Nyquist frequency.
fn fit_band(freq: &[f64], options: &RefineOptions) -> Result<(usize, usize)> {
    let lines = freq.len();
    let band = match options.band {
        Some((a, b)) => {
            if !(a < b && b <= lines) {
                return Err(invalid(
                    "band",
                    format!("{a}..{b}"),
                    format!("need first < end <= {lines} (the lines of the data)"),
                ));
            }
            if freq[a] <= 0.0 {
                return Err(invalid(
                    "band",
                    format!("{a}..{b}"),
                    "the band must leave out the 0 Hz line",
                ));
            }
            (a, b)
        }
        None => {
            let first = freq.iter().position(|&f| f > 0.0).unwrap_or(lines);
            (first, lines)
        }
    };
    if let Some(ts) = options.sample_time_s {
        if !(ts.is_finite() && ts > 0.0) {
            return Err(invalid(
                "sample time",
                ts.to_string(),
                "must be positive and finite",
            ));
        }
        if options.real_modes {
            return Err(invalid(
                "real_modes",
                "true".into(),
                "the residues of a sampled (z-domain) model are not imaginary: real modes need the continuous model",
            ));
        }
        if let Some(&f) = freq[band.0..band.1]
            .iter()
            .find(|&&f| f * ts > 0.5 * (1.0 + 1e-9))
        {
            return Err(invalid(
                "band",
                format!("{}..{}", band.0, band.1),
                format!(
                    "{f} Hz is above the Nyquist frequency {} Hz of the sample time {ts} s",
                    0.5 / ts
                ),
            ));
        }
    }
    Ok(band)
}

/// The options that do not depend on the data's values: reciprocity on a square set, the
/// tolerance, the iteration limit.
fn check_options(options: &RefineOptions, q: usize, p: usize) -> Result<()> {
    if options.reciprocal && q != p {
        return Err(invalid(
            "reciprocal",
            format!("{q}x{p}"),
            "reciprocity needs a square (collocated) set",
        ));
    }
    if !(options.tolerance.is_finite() && options.tolerance >= 0.0) {
        return Err(invalid(
            "tolerance",
            options.tolerance.to_string(),
            "must be a finite number >= 0",
        ));
    }
    crate::params::limits::ITERATIONS.check("max_iterations", options.max_iterations as u64)?;
    Ok(())
}

/// Units: pairs (`i·p + j`) sharing a coefficient vector, `(i, j)` with `(j, i)` when
/// reciprocal.
fn units_of(q: usize, p: usize, reciprocal: bool) -> Vec<Vec<usize>> {
    if reciprocal {
        let mut u = Vec::new();
        for i in 0..q {
            u.push(vec![i * p + i]);
            for j in i + 1..p {
                u.push(vec![i * p + j, j * p + i]);
            }
        }
        u
    } else {
        (0..q * p).map(|pair| vec![pair]).collect()
    }
}

/// Refuses a pair whose every weight in the band is zero.
fn check_pair_weights(weights: &[Vec<f64>], p: usize) -> Result<()> {
    for (pair, wp) in weights.iter().enumerate() {
        if wp.iter().all(|&x| x == 0.0) {
            return Err(invalid(
                "weighting",
                format!("output {}, input {}", pair / p + 1, pair % p + 1),
                "every weight of this pair in the band is zero",
            ));
        }
    }
    Ok(())
}

/// One block for every unit when each pair has one weight `pw` over the band: each unit
/// fitted through its weighted mean ([`Block::scales`]).
fn shared_block(units: &[Vec<usize>], pw: &[f64], data: &[Vec<Complex64>], nl: usize) -> Block {
    let mut block = Block {
        segment_weights: vec![None],
        units: units.to_vec(),
        scales: Vec::with_capacity(units.len()),
        cost_offset: 0.0,
        rhs: Mat::zeros(2 * nl, units.len()),
    };
    for (u, unit) in units.iter().enumerate() {
        let total: f64 = unit.iter().map(|&pair| pw[pair] * pw[pair]).sum();
        let root = total.sqrt();
        block.scales.push(root);
        // `k` indexes the line of every pair of the unit, not one slice.
        #[allow(clippy::needless_range_loop)]
        for k in 0..nl {
            let mean = unit
                .iter()
                .map(|&pair| pw[pair] * pw[pair] * data[pair][k])
                .sum::<Complex64>()
                / total;
            block.rhs[(k, u)] = root * mean.re;
            block.rhs[(nl + k, u)] = root * mean.im;
            block.cost_offset += unit
                .iter()
                .map(|&pair| pw[pair] * pw[pair] * (data[pair][k] - mean).norm_sqr())
                .sum::<f64>();
        }
    }
    block
}

/// The block of one unit whose weights `w` vary over the band: its pairs stacked, each
/// segment weighted line by line.
fn weighted_block(unit: &[usize], w: &[Vec<f64>], data: &[Vec<Complex64>], nl: usize) -> Block {
    let segments = unit.len();
    let mut rhs = Mat::<f64>::zeros(segments * 2 * nl, 1);
    for (seg, &pair) in unit.iter().enumerate() {
        for k in 0..nl {
            rhs[(seg * 2 * nl + k, 0)] = w[pair][k] * data[pair][k].re;
            rhs[(seg * 2 * nl + nl + k, 0)] = w[pair][k] * data[pair][k].im;
        }
    }
    Block {
        segment_weights: unit.iter().map(|&pair| Some(w[pair].clone())).collect(),
        units: vec![unit.to_vec()],
        scales: vec![1.0],
        cost_offset: 0.0,
        rhs,
    }
}

impl Problem {
    /// Validates the options against the data and arranges the blocks.
    pub(crate) fn new(frf: &FrfData, options: &RefineOptions) -> Result<Self> {
        let (q, p, lines) = (frf.outputs(), frf.inputs(), frf.lines());
        let freq = frf.frequency_hz();
        let band = fit_band(freq, options)?;
        check_options(options, q, p)?;
        let omega: Vec<f64> = freq[band.0..band.1].iter().map(|f| 2.0 * PI * f).collect();
        let nl = omega.len();
        let pair_count = q * p;
        let data: Vec<Vec<Complex64>> = (0..pair_count)
            .map(|pair| frf.pair(pair / p, pair % p)[band.0..band.1].to_vec())
            .collect();
        let data_norm2: f64 = data.iter().flatten().map(|v| v.norm_sqr()).sum();
        if data_norm2 == 0.0 {
            return Err(EraError::AllZero);
        }
        let weights = square_root_weights(&options.weighting, q * p * lines, lines, band)?;
        let layout = Layout::new(frf.quantity(), options);
        let units = units_of(q, p, options.reciprocal);
        if let Some(w) = &weights {
            check_pair_weights(w, p)?;
        }
        // One weight per pair over the whole band (uniform included): every unit shares
        // one basis (`Block::scales`).
        let pair_weight: Option<Vec<f64>> = match &weights {
            None => Some(vec![1.0; pair_count]),
            Some(w) => w
                .iter()
                .map(|wp| wp.iter().all(|&x| x == wp[0]).then_some(wp[0]))
                .collect(),
        };
        let blocks = match (&pair_weight, &weights) {
            (Some(pw), _) => vec![shared_block(&units, pw, &data, nl)],
            (None, Some(w)) => units
                .iter()
                .map(|unit| weighted_block(unit, w, &data, nl))
                .collect(),
            (None, None) => unreachable!("uniform weights are one per pair"),
        };
        Ok(Problem {
            layout,
            parameters: PoleParameters {
                log_damping: options.enforce_stability,
            },
            outputs: q,
            inputs: p,
            quantity: frf.quantity(),
            band,
            omega,
            blocks,
            data,
            data_norm2,
            observations: 2 * nl * pair_count,
            pair_weights: pair_weight,
            rank_one: options.rank_one,
            reciprocal: options.reciprocal,
        })
    }

    /// Real observations less unknowns (`parameters` pole parameters and every unit's
    /// linear coefficients), or `None` when there are not more observations.
    pub(crate) fn degrees_of_freedom(&self, parameters: usize) -> Option<usize> {
        let units: usize = self.blocks.iter().map(|b| b.units.len()).sum();
        let unknowns = parameters + self.layout.columns(parameters / 2) * units;
        self.observations.checked_sub(unknowns).filter(|&d| d > 0)
    }

    /// Whether the rank-one stage will follow the free fit: asked for, weights
    /// constant per pair, complex modes.
    pub(crate) fn rank_one_follows(&self) -> bool {
        self.rank_one && self.pair_weights.is_some() && self.layout.per_mode == 2
    }

    /// Checks that there are more real observations per unit than linear unknowns.
    pub(crate) fn check_size(&self, modes: usize) -> Result<()> {
        let cols = self.layout.columns(modes);
        let rows = 2 * self.omega.len();
        if rows <= cols {
            return Err(invalid(
                "band",
                format!("{}..{}", self.band.0, self.band.1),
                format!(
                    "{} lines give {rows} real values per FRF, not more than the {cols} unknowns of {modes} modes and the residual terms: widen the band or start from fewer poles",
                    self.omega.len()
                ),
            ));
        }
        crate::params::limits::STATES
            .check_product("refined modes (2 states each)", &[modes as u64, 2])?;
        crate::params::limits::VALUES.check_product(
            "refinement basis (2 x lines x columns)",
            &[rows as u64, (3 * cols) as u64],
        )?;
        Ok(())
    }
}

/// Square roots of the per-line weights over the band, per pair, or `None` (uniform).
fn square_root_weights(
    weighting: &Weighting,
    expected: usize,
    lines: usize,
    band: (usize, usize),
) -> Result<Option<Vec<Vec<f64>>>> {
    let (values, coherence) = match weighting {
        // PairNoise is resolved into InverseVariance before a problem is built.
        Weighting::Uniform | Weighting::PairNoise => return Ok(None),
        Weighting::Coherence(v) => (v, true),
        Weighting::InverseVariance(v) => (v, false),
    };
    if values.len() != expected {
        return Err(EraError::ShapeMismatch {
            what: "weights ([output][input][line], like the FRF values)".into(),
            expected,
            got: values.len(),
        });
    }
    let pairs = expected / lines;
    let mut out = Vec::with_capacity(pairs);
    for pair in 0..pairs {
        let mut w = Vec::with_capacity(band.1 - band.0);
        for k in band.0..band.1 {
            let v = values[pair * lines + k];
            let ok = if coherence {
                (0.0..=1.0).contains(&v)
            } else {
                v.is_finite() && v > 0.0
            };
            if !ok {
                return Err(invalid(
                    if coherence { "coherence" } else { "variance" },
                    v.to_string(),
                    format!(
                        "at line {k} of pair {pair}: {}",
                        if coherence {
                            "a coherence must be in [0, 1]"
                        } else {
                            "a variance must be positive and finite"
                        }
                    ),
                ));
            }
            w.push(if coherence { v.sqrt() } else { 1.0 / v.sqrt() });
        }
        out.push(w);
    }
    Ok(Some(out))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The second derivative columns against central differences of the first ones, in
    /// both time domains, for each quantity's `κ` and both damping parameters.
    #[test]
    fn second_derivatives_match_differences_of_the_first() {
        let omega: Vec<f64> = (0..40).map(|k| 2.0 * PI * (0.5 + 0.3 * k as f64)).collect();
        let poles = [
            Complex64::new(-0.3, 2.0 * PI * 4.1),
            Complex64::new(-0.05, 2.0 * PI * 9.7),
        ];
        for (kappa, ts) in [(0, None), (1, None), (2, None), (0, Some(0.01))] {
            for log_damping in [true, false] {
                let layout = Layout {
                    kappa,
                    sample_time_s: ts,
                    per_mode: 2,
                    residuals: Vec::new(),
                };
                let parameters = PoleParameters { log_damping };
                let theta = parameters.theta(&poles);
                let second = basis_second_derivatives(&layout, parameters, &omega, &poles);
                for r in 0..poles.len() {
                    for (c, &(t, t2)) in PARAMETER_COUPLES.iter().enumerate() {
                        // Differences of ∂/∂θ_t along θ_t2.
                        let h = 1e-6 * theta[2 * r + t2].abs().max(1.0);
                        let at = |sign: f64| {
                            let mut moved = theta.clone();
                            moved[2 * r + t2] += sign * h;
                            basis_derivatives(
                                &layout,
                                parameters,
                                &omega,
                                &parameters.poles(&moved),
                            )
                        };
                        let (up, down) = (at(1.0), at(-1.0));
                        let mut worst: f64 = 0.0;
                        let mut scale: f64 = 0.0;
                        for local in 0..2 {
                            let col = (3 * r + c) * 2 + local;
                            let first = (2 * r + t) * 2 + local;
                            for row in 0..second.nrows() {
                                let fd = (up[(row, first)] - down[(row, first)]) / (2.0 * h);
                                worst = worst.max((fd - second[(row, col)]).abs());
                                scale = scale.max(second[(row, col)].abs());
                            }
                        }
                        assert!(
                            worst <= 1e-5 * scale,
                            "κ {kappa}, Ts {ts:?}, log {log_damping}, mode {r}, couple {c}: {worst:e} of {scale:e}"
                        );
                    }
                }
            }
        }
    }
}
