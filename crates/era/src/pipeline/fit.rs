//! The model's frequency response and its fit to the measurement (docs/src/design.md §1.12).
//!
//! `G(f) = C (zI − A)⁻¹ B + D` with `z = exp(j2πf·Ts)` for a discrete model, or
//! `C (j2πf I − A)⁻¹ B + D` for a continuous one.
//!
//! Two ways to evaluate it, and [`frequency_response`] picks one per model:
//!
//! - **Modal form** (`frequency_response_modal`). With `A = V Λ V⁻¹`,
//!   `G(z) = Σ_k (C φ_k)(ψ_k B)/(z − λ_k) + D`: O(n·q·p) per line, and all lines at once
//!   are one complex matrix product (lines × n by n × q·p). It loses about
//!   `log10 κ(V)` digits to the eigenvector condition (Higham 2002, §14; Golub & Van Loan
//!   §7.2), so it is used only when `κ(V) ≤` [`MODAL_CONDITION_LIMIT`]. ERA's balanced
//!   realizations have well-conditioned eigenvectors (κ ≈ 10–100 at the thesis DTA size),
//!   where this form costs one GEMM of `lines × n` by `n × q·p`.
//! - **Hessenberg form** ([`HessenbergForm`]). `A` is reduced once to upper Hessenberg
//!   form, `A = Q H Qᵀ` with `Q` orthogonal (`faer`), then `(zI − H) X = Qᵀ B` is solved
//!   at each line by Gaussian elimination with adjacent-row pivoting (Laub 1981): O(n²·p)
//!   per line and backward stable, as accurate as a dense solve
//!   (`frequency_response_naive`, the reference). The truth model in physical
//!   coordinates (9 decades, κ(V) ≈ 1e5) takes this path. Lines run in parallel.
//!
//! The solves are written here because `faer` has no shifted Hessenberg solver, and a
//! general complex LU per line (`frequency_response_naive`) costs O(n³).

use crate::data::frf::FrfData;
use crate::data::statespace::{StateSpace, TimeDomain};
use crate::error::{EraError, Result};
use crate::linalg::eigen::balancing_scale;
use crate::pipeline::modes::ModalForm;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::hessenberg;
use faer::linalg::householder;
use faer::linalg::solvers::Solve;
use faer::{Conj, Mat};
use num_complex::Complex64;
use rayon::prelude::*;

/// A model with `A` in upper Hessenberg form: `H = Qᵀ A Q`, `Qᵀ B`, `C Q`.
#[derive(Debug, Clone)]
pub struct HessenbergForm {
    h: Mat<f64>,
    qt_b: Mat<f64>,
    c_q: Mat<f64>,
    d: Mat<f64>,
    domain: TimeDomain,
}

impl HessenbergForm {
    /// Balances the model (`D⁻¹AD`, `D⁻¹B`, `CD` with `D` powers of 2: the same
    /// transfer function, exactly), then reduces `A` to Hessenberg form with `faer` and
    /// transforms `B` and `C`. Without the balancing an orthogonal reduction of a badly
    /// scaled physical model mixes its rows and loses digits.
    pub fn new(model: &StateSpace) -> Self {
        let n = model.states();
        let scale = balancing_scale(&model.a);
        let mut h = Mat::from_fn(n, n, |i, j| model.a[(i, j)] * scale[j] / scale[i]);
        let b = Mat::from_fn(n, model.inputs(), |i, j| model.b[(i, j)] / scale[i]);
        let c = Mat::from_fn(model.outputs(), n, |i, j| model.c[(i, j)] * scale[j]);
        let mut q = Mat::<f64>::identity(n, n);
        if n > 2 {
            let par = faer::get_global_parallelism();
            let bs =
                faer::linalg::qr::no_pivoting::factor::recommended_block_size::<f64>(n - 1, n - 1);
            let mut reflectors = Mat::<f64>::zeros(bs, n - 1);
            let scratch =
                hessenberg::hessenberg_in_place_scratch::<f64>(n, bs, par, Default::default()).or(
                    householder::apply_block_householder_sequence_on_the_right_in_place_scratch::<
                        f64,
                    >(n - 1, bs, n - 1),
                );
            let mut buffer = MemBuffer::new(scratch);
            hessenberg::hessenberg_in_place(
                h.as_mut(),
                reflectors.as_mut(),
                par,
                MemStack::new(&mut buffer),
                Default::default(),
            );
            householder::apply_block_householder_sequence_on_the_right_in_place_with_conj(
                h.as_ref().submatrix(1, 0, n - 1, n - 1),
                reflectors.as_ref(),
                Conj::No,
                q.as_mut().submatrix_mut(1, 1, n - 1, n - 1),
                par,
                MemStack::new(&mut buffer),
            );
            for j in 0..n {
                for i in j + 2..n {
                    h[(i, j)] = 0.0;
                }
            }
        }
        let qt_b = q.transpose() * &b;
        let c_q = &c * &q;
        HessenbergForm {
            h,
            qt_b,
            c_q,
            d: model.d.clone(),
            domain: model.domain,
        }
    }

    /// The Hessenberg matrix `H` (of the balanced `A`).
    #[cfg(test)]
    pub(crate) fn h(&self) -> &Mat<f64> {
        &self.h
    }

    /// Frequency response at `frequency_hz`, `[output][input][line]`. Lines are
    /// independent, so chunks of them run in parallel (`rayon`); each line's arithmetic
    /// is the same whatever the chunking.
    pub fn response(&self, frequency_hz: &[f64]) -> Vec<Complex64> {
        let (q, p, lines) = (self.c_q.nrows(), self.qt_b.ncols(), frequency_hz.len());
        let zero = Complex64::new(0.0, 0.0);
        // Each chunk writes line-major `[line][pair]` rows; scattered afterwards.
        let mut by_line = vec![zero; lines * q * p];
        let chunk = LINES_PER_TASK;
        if lines > chunk {
            by_line
                .par_chunks_mut(chunk * q * p)
                .zip(frequency_hz.par_chunks(chunk))
                .for_each(|(out, f)| self.response_lines(f, out));
        } else {
            self.response_lines(frequency_hz, &mut by_line);
        }
        let mut out = vec![zero; q * p * lines];
        for (k, row) in by_line.chunks_exact(q * p).enumerate() {
            for (pair, v) in row.iter().enumerate() {
                out[pair * lines + k] = *v;
            }
        }
        out
    }

    /// The lines `frequency_hz` into `out`, line-major (`out[k·q·p + i·p + j]`).
    fn response_lines(&self, frequency_hz: &[f64], out: &mut [Complex64]) {
        let n = self.h.nrows();
        let (q, p) = (self.c_q.nrows(), self.qt_b.ncols());
        let zero = Complex64::new(0.0, 0.0);
        // Row-major working copies of zI − H and of the right-hand side.
        let mut m = vec![zero; n * n];
        let mut x = vec![zero; n * p];
        for (k, f) in frequency_hz.iter().enumerate() {
            let z = evaluation_point(self.domain, *f);
            for i in 0..n {
                for j in 0..n {
                    m[i * n + j] = if i == j {
                        z - self.h[(i, j)]
                    } else {
                        Complex64::new(-self.h[(i, j)], 0.0)
                    };
                }
                for j in 0..p {
                    x[i * p + j] = Complex64::new(self.qt_b[(i, j)], 0.0);
                }
            }
            // Eliminate the subdiagonal, pivoting between adjacent rows.
            for c in 0..n.saturating_sub(1) {
                if m[(c + 1) * n + c].norm() > m[c * n + c].norm() {
                    for j in c..n {
                        m.swap(c * n + j, (c + 1) * n + j);
                    }
                    for j in 0..p {
                        x.swap(c * p + j, (c + 1) * p + j);
                    }
                }
                let pivot = m[c * n + c];
                if pivot.norm() == 0.0 {
                    continue;
                }
                let l = m[(c + 1) * n + c] / pivot;
                m[(c + 1) * n + c] = zero;
                for j in c + 1..n {
                    let v = m[c * n + j];
                    m[(c + 1) * n + j] -= l * v;
                }
                for j in 0..p {
                    let v = x[c * p + j];
                    x[(c + 1) * p + j] -= l * v;
                }
            }
            // Back substitution on the upper triangle.
            for i in (0..n).rev() {
                for j in 0..p {
                    let mut acc = x[i * p + j];
                    for c in i + 1..n {
                        acc -= m[i * n + c] * x[c * p + j];
                    }
                    x[i * p + j] = acc / m[i * n + i];
                }
            }
            for i in 0..q {
                for j in 0..p {
                    let mut acc = Complex64::new(self.d[(i, j)], 0.0);
                    for c in 0..n {
                        acc += self.c_q[(i, c)] * x[c * p + j];
                    }
                    out[k * q * p + i * p + j] = acc;
                }
            }
        }
    }
}

/// Lines per parallel task of [`HessenbergForm::response`].
const LINES_PER_TASK: usize = 32;

/// Largest eigenvector condition `κ(V)` ([`ModalForm::eigenvector_condition`], a
/// Frobenius-norm over-estimate) for which [`frequency_response`] takes the modal form.
/// The modal sum loses about `log10 κ(V)` digits against the backward-stable Hessenberg
/// solve; below 1e4 it agrees with it to about 1e-11 relative.
pub const MODAL_CONDITION_LIMIT: f64 = 1e4;

pub(crate) fn evaluation_point(domain: TimeDomain, frequency_hz: f64) -> Complex64 {
    let w = 2.0 * std::f64::consts::PI * frequency_hz;
    match domain {
        TimeDomain::Discrete { sample_time_s } => Complex64::from_polar(1.0, w * sample_time_s),
        TimeDomain::Continuous => Complex64::new(0.0, w),
    }
}

/// The irreducible diagonal blocks of `A`: groups of states that `A` couples (directly
/// or through others), each sorted, the groups by their first state.
pub(crate) fn diagonal_blocks(a: &Mat<f64>) -> Vec<Vec<usize>> {
    let n = a.nrows();
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    for i in 0..n {
        for j in 0..n {
            if i != j && a[(i, j)] != 0.0 {
                let (ri, rj) = (root(&mut parent, i), root(&mut parent, j));
                if ri != rj {
                    parent[ri.max(rj)] = ri.min(rj);
                }
            }
        }
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut index = vec![usize::MAX; n];
    for i in 0..n {
        let r = root(&mut parent, i);
        if index[r] == usize::MAX {
            index[r] = groups.len();
            groups.push(Vec::new());
        }
        groups[index[r]].push(i);
    }
    groups
}

/// Frequency response through the [`HessenbergForm`] of each irreducible diagonal block
/// of `A` (`diagonal_blocks`), summed: `G = Σ_b C_b (zI − A_b)⁻¹ B_b + D`. The same
/// backward-stable solves as one [`HessenbergForm`] of the whole model, at
/// O(Σ n_b²·p) per line instead of O(n²·p): a model in real modal block form (the
/// refinement's, with 2 × 2 blocks and integrator chains) costs O(n·p) per line.
/// Chunks of lines run in parallel, each summing the blocks in their order, so that the
/// sum is the same whatever the chunking and no block's whole response is held.
pub fn frequency_response_blocks(model: &StateSpace, frequency_hz: &[f64]) -> Vec<Complex64> {
    let blocks = diagonal_blocks(&model.a);
    if blocks.len() <= 1 {
        return HessenbergForm::new(model).response(frequency_hz);
    }
    let (q, p, lines) = (model.outputs(), model.inputs(), frequency_hz.len());
    let zero = Complex64::new(0.0, 0.0);
    let forms: Vec<HessenbergForm> = blocks
        .iter()
        .map(|states| {
            let m = states.len();
            HessenbergForm::new(&StateSpace::new(
                Mat::from_fn(m, m, |i, j| model.a[(states[i], states[j])]),
                Mat::from_fn(m, p, |i, j| model.b[(states[i], j)]),
                Mat::from_fn(q, m, |i, j| model.c[(i, states[j])]),
                Mat::zeros(q, p),
                model.domain,
            ))
        })
        .collect();
    // Line-major `[line][pair]` sums, scattered afterwards.
    let mut by_line = vec![zero; lines * q * p];
    let sum_lines = |f: &[f64], out: &mut [Complex64]| {
        let mut part = vec![zero; out.len()];
        for form in &forms {
            form.response_lines(f, &mut part);
            for (o, v) in out.iter_mut().zip(&part) {
                *o += v;
            }
        }
    };
    by_line
        .par_chunks_mut(LINES_PER_TASK * q * p)
        .zip(frequency_hz.par_chunks(LINES_PER_TASK))
        .for_each(|(out, f)| sum_lines(f, out));
    let mut out = vec![zero; q * p * lines];
    for (k, row) in by_line.chunks_exact(q * p).enumerate() {
        for (i, row) in row.chunks_exact(p).enumerate() {
            for (j, v) in row.iter().enumerate() {
                out[(i * p + j) * lines + k] = v + model.d[(i, j)];
            }
        }
    }
    out
}

/// Frequency response at `frequency_hz`, laid out `[output][input][line]` like
/// [`FrfData::values`]: through the modal form when its eigenvectors are well conditioned
/// (`κ(V) ≤` [`MODAL_CONDITION_LIMIT`]), through the [`HessenbergForm`] otherwise.
///
/// # Errors
/// None at present; kept fallible for forms that can fail.
pub fn frequency_response(model: &StateSpace, frequency_hz: &[f64]) -> Result<Vec<Complex64>> {
    let form = (model.states() > 0)
        .then(|| ModalForm::new(model).ok())
        .flatten();
    Ok(frequency_response_with(model, form.as_ref(), frequency_hz))
}

/// [`frequency_response`] with the modal form of `model` already at hand (the pipeline
/// computes it for the modes): the modal sum when `form` is well conditioned, the
/// [`HessenbergForm`]s of `A`'s diagonal blocks otherwise or without a form.
pub(crate) fn frequency_response_with(
    model: &StateSpace,
    form: Option<&ModalForm>,
    frequency_hz: &[f64],
) -> Vec<Complex64> {
    match form {
        Some(form)
            if form.eigenvector_condition.is_finite()
                && form.eigenvector_condition <= MODAL_CONDITION_LIMIT =>
        {
            frequency_response_modal(model, form, frequency_hz)
        }
        _ => frequency_response_blocks(model, frequency_hz),
    }
}

/// Frequency response from a precomputed [`ModalForm`] of `model`: O(n·q·p) per line,
/// accurate to about `κ(V)·ε` relative ([`ModalForm::eigenvector_condition`]).
///
/// All lines at once, as one complex matrix product `G = W P` with
/// `W[k][m] = 1/(z_k − λ_m)` (lines × states) and `P[m][i·p+j] = (C φ_m)_i (ψ_m B)_j`
/// (states × pairs), so that the work goes to `faer`'s blocked, parallel product.
pub(crate) fn frequency_response_modal(
    model: &StateSpace,
    form: &ModalForm,
    frequency_hz: &[f64],
) -> Vec<Complex64> {
    let (q, p, lines) = (model.outputs(), model.inputs(), frequency_hz.len());
    let n = form.eigenvalues.len();
    // One evaluation point per line (a sine and cosine for discrete time), not per entry.
    let points: Vec<Complex64> = frequency_hz
        .iter()
        .map(|f| evaluation_point(model.domain, *f))
        .collect();
    let weights = Mat::from_fn(lines, n, |k, m| 1.0 / (points[k] - form.eigenvalues[m]));
    let residues = Mat::from_fn(n, q * p, |m, pair| {
        form.shapes[m][pair / p] * form.participations[m][pair % p]
    });
    let g = &weights * &residues;
    let mut out = vec![Complex64::new(0.0, 0.0); q * p * lines];
    for i in 0..q {
        for j in 0..p {
            let d = model.d[(i, j)];
            let column = g.col(i * p + j);
            for (k, v) in out[(i * p + j) * lines..(i * p + j + 1) * lines]
                .iter_mut()
                .enumerate()
            {
                *v = column[k] + d;
            }
        }
    }
    out
}

/// Reference: a dense complex LU solve `(zI − A) X = B` at every line.
pub fn frequency_response_naive(model: &StateSpace, frequency_hz: &[f64]) -> Vec<Complex64> {
    let (n, q, p, lines) = (
        model.states(),
        model.outputs(),
        model.inputs(),
        frequency_hz.len(),
    );
    let bc = Mat::from_fn(n, p, |i, j| Complex64::new(model.b[(i, j)], 0.0));
    let cc = Mat::from_fn(q, n, |i, j| Complex64::new(model.c[(i, j)], 0.0));
    let mut out = vec![Complex64::new(0.0, 0.0); q * p * lines];
    for (k, f) in frequency_hz.iter().enumerate() {
        let z = evaluation_point(model.domain, *f);
        let m = Mat::from_fn(n, n, |i, j| {
            let diag = if i == j { z } else { Complex64::new(0.0, 0.0) };
            diag - model.a[(i, j)]
        });
        let mut x = bc.clone();
        m.partial_piv_lu().solve_in_place(&mut x);
        let g = &cc * &x;
        for i in 0..q {
            for j in 0..p {
                out[(i * p + j) * lines + k] = g[(i, j)] + model.d[(i, j)];
            }
        }
    }
    out
}

/// The model's FRF on the lines of `like`, tagged with `like`'s quantity.
///
/// # Errors
/// [`EraError::ShapeMismatch`] when the model's outputs or inputs differ from `like`'s;
/// [`EraError::NonFinite`] when a line other than 0 Hz hits a pole exactly (at 0 Hz, an
/// integrator's line, the response is written as 0).
pub fn model_frf(model: &StateSpace, like: &FrfData) -> Result<FrfData> {
    if model.outputs() != like.outputs() || model.inputs() != like.inputs() {
        return Err(EraError::ShapeMismatch {
            what: "model outputs x inputs against the FRF".into(),
            expected: like.outputs() * like.inputs(),
            got: model.outputs() * model.inputs(),
        });
    }
    let mut values = frequency_response(model, like.frequency_hz())?;
    // A refined model's lower residual integrates: its response is infinite at 0 Hz.
    // That line was never fitted; it is written as 0, as the identification writes it.
    let lines = like.lines();
    for (i, v) in values.iter_mut().enumerate() {
        if like.frequency_hz()[i % lines] == 0.0 && !(v.re.is_finite() && v.im.is_finite()) {
            *v = Complex64::new(0.0, 0.0);
        }
    }
    like.with_values(values)
}

/// Fit of one output/input pair.
#[derive(Debug, Clone, PartialEq)]
pub struct PairFit {
    /// 0-based output.
    pub output: usize,
    /// 0-based input.
    pub input: usize,
    /// Measured at the point where the force is applied (`i = j` on a square set).
    pub collocated: bool,
    /// `‖G_meas − G_model‖₂ / ‖G_meas‖₂` over the band.
    pub relative_error: f64,
    /// RMS of `20 log10 |G_model| − 20 log10 |G_meas|` over lines where both are
    /// non-zero, dB.
    pub rms_log_magnitude_db: f64,
}

/// Per-pair fit and its means (docs/src/design.md §1.12).
#[derive(Debug, Clone, PartialEq)]
pub struct FitReport {
    /// One entry per pair, `[output][input]` order.
    pub pairs: Vec<PairFit>,
    /// First line of the band (lines zeroed by preprocessing are left out).
    pub first_line: usize,
    /// Lines in the band.
    pub lines: usize,
    /// Mean relative error over collocated pairs (`None` when there are none).
    pub collocated_mean_relative_error: Option<f64>,
    /// Mean relative error over non-collocated pairs.
    pub noncollocated_mean_relative_error: Option<f64>,
    /// Mean RMS log-magnitude error over collocated pairs, dB.
    pub collocated_mean_db: Option<f64>,
    /// Mean RMS log-magnitude error over non-collocated pairs, dB.
    pub noncollocated_mean_db: Option<f64>,
}

fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, count) = values.fold((0.0, 0usize), |(s, c), v| (s + v, c + 1));
    (count > 0).then(|| sum / count as f64)
}

/// `20 log10(|b| / |a|)`, or `None` where either is zero. From the squared magnitudes (no
/// `hypot`, one `log10`) unless they under- or overflow, then from the magnitudes.
fn level_db(a: Complex64, b: Complex64) -> Option<f64> {
    let (a2, b2) = (a.norm_sqr(), b.norm_sqr());
    let ratio = b2 / a2;
    if a2.is_normal() && b2.is_normal() && ratio.is_normal() {
        return Some(10.0 * ratio.log10());
    }
    let (na, nb) = (a.norm(), b.norm());
    (na > 0.0 && nb > 0.0).then(|| 20.0 * (nb.log10() - na.log10()))
}

/// Compares `measured` with `model` (both `[output][input][line]` on the same lines)
/// over lines `first_line ..`. Pairs with `i = j` count as collocated when the set is
/// square.
///
/// # Panics
/// If `model` does not have the measured layout.
#[track_caller]
pub(crate) fn fit_metrics(measured: &FrfData, model: &[Complex64], first_line: usize) -> FitReport {
    assert_eq!(
        model.len(),
        measured.values().len(),
        "model response layout"
    );
    let (q, p, lines) = (measured.outputs(), measured.inputs(), measured.lines());
    let first_line = first_line.min(lines);
    let square = q == p;
    // One log per line is most of the work (about 1.3 ms at 8×8×801). Serial: in the
    // pipeline, right after faer's parallel kernels, a rayon split of it took 4 ms.
    let pairs: Vec<PairFit> = (0..q * p)
        .map(|pair| {
            let (i, j) = (pair / p, pair % p);
            let g = &measured.pair(i, j)[first_line..];
            let start = pair * lines + first_line;
            let h = &model[start..start + g.len()];
            let mut num: f64 = g.iter().zip(h).map(|(a, b)| (a - b).norm_sqr()).sum();
            let mut den: f64 = g.iter().map(|a| a.norm_sqr()).sum();
            if !(num.is_finite() && den.is_finite()) || den < f64::MIN_POSITIVE {
                // Squares of magnitudes beyond about 1e154 overflow, below 1e-154 they
                // underflow: sum them at an exact power-of-two scale instead (the ratio
                // is the same). Ordinary data never takes this path.
                let top = crate::data::frf::largest_component(g.iter().chain(h));
                if top > 0.0 {
                    let k = 2f64.powi(crate::data::frf::exponent_toward_one(top));
                    num = g
                        .iter()
                        .zip(h)
                        .map(|(a, b)| (a * k - b * k).norm_sqr())
                        .sum();
                    den = g.iter().map(|a| (a * k).norm_sqr()).sum();
                }
            }
            let relative_error = if den > 0.0 {
                (num / den).sqrt()
            } else {
                f64::NAN
            };
            let levels = g.iter().zip(h).filter_map(|(a, b)| level_db(*a, *b));
            let rms_log_magnitude_db = mean(levels.map(|d| d * d)).map_or(f64::NAN, f64::sqrt);
            PairFit {
                output: i,
                input: j,
                collocated: square && i == j,
                relative_error,
                rms_log_magnitude_db,
            }
        })
        .collect();
    let mut report = FitReport {
        first_line,
        lines: lines - first_line,
        collocated_mean_relative_error: None,
        noncollocated_mean_relative_error: None,
        collocated_mean_db: None,
        noncollocated_mean_db: None,
        pairs,
    };
    report.set_means();
    report
}

impl FitReport {
    /// Marks which pairs are collocated by `collocated(output, input)` (a channel table's
    /// nodes and directions, where `fit_metrics` could only go by index) and takes the
    /// two groups' means again, so that every output of a run agrees on them.
    pub fn set_collocation(&mut self, collocated: impl Fn(usize, usize) -> bool) {
        for pair in &mut self.pairs {
            pair.collocated = collocated(pair.output, pair.input);
        }
        self.set_means();
    }

    fn set_means(&mut self) {
        let pick = |col: bool, f: fn(&PairFit) -> f64| {
            mean(
                self.pairs
                    .iter()
                    .filter(|x| x.collocated == col)
                    .map(f)
                    .filter(|v| v.is_finite()),
            )
        };
        let means = (
            pick(true, |x| x.relative_error),
            pick(false, |x| x.relative_error),
            pick(true, |x| x.rms_log_magnitude_db),
            pick(false, |x| x.rms_log_magnitude_db),
        );
        (
            self.collocated_mean_relative_error,
            self.noncollocated_mean_relative_error,
            self.collocated_mean_db,
            self.noncollocated_mean_db,
        ) = means;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{truth_model, ModalSpec, ModalStructure};
    use era_testkit::{assert_matches_naive, tol, Scale};

    /// The level difference from squared magnitudes, and from the magnitudes where the
    /// squares under- or overflow; zero on either side has no level.
    #[test]
    fn level_db_from_squares_and_at_the_extremes() {
        let c = |re: f64, im: f64| Complex64::new(re, im);
        let close = |x: Option<f64>, want: f64| (x.unwrap() - want).abs() < 1e-12;
        assert!(close(level_db(c(3.0, 4.0), c(30.0, 40.0)), 20.0));
        assert!(close(level_db(c(1e-200, 0.0), c(0.0, 1e-199)), 20.0));
        assert!(close(level_db(c(1e200, 0.0), c(1e180, 0.0)), -400.0));
        assert!(close(level_db(c(1e-160, 0.0), c(1e160, 0.0)), 6400.0));
        // Subnormal squares whose ratio is normal: from the magnitudes, not the squares.
        let (a, b) = (1.234567e-160, 1.1e-161);
        assert!(close(
            level_db(c(a, 0.0), c(b, 0.0)),
            20.0 * (b / a).log10()
        ));
        assert_eq!(level_db(c(0.0, 0.0), c(1.0, 0.0)), None);
        assert_eq!(level_db(c(1.0, 0.0), c(0.0, 0.0)), None);
    }

    /// The constant of the responses' rounding bound `c · ε · n · κ(V)` (n states, κ(V)
    /// the eigenvector condition where the modal form is used): the Hessenberg reduction
    /// and one complex solve per line, against an LU solve per line.
    const C_RESPONSE: f64 = 32.0;

    /// A response against its reference, `max |a − b| / max |b|` (per-line ratios blow up
    /// at exact zeros, DC of a velocity), within `tol`.
    #[track_caller]
    fn assert_response(what: &str, fast: &[Complex64], naive: &[Complex64], tol: f64) {
        assert_matches_naive(what, fast, naive, Scale::Largest, tol);
    }

    #[test]
    fn diagonal_blocks_are_evaluated_one_by_one_to_round_off() {
        // States interleaved: a 2 × 2 mode on {0, 3}, an integrator chain on {1, 4, 5},
        // another mode on {2, 6}; B, C and D dense.
        let mut a = Mat::<f64>::zeros(7, 7);
        for (x, y, s) in [
            (0, 3, Complex64::new(-0.3, 20.0)),
            (2, 6, Complex64::new(-1.1, 55.0)),
        ] {
            a[(x, x)] = s.re;
            a[(x, y)] = s.im;
            a[(y, x)] = -s.im;
            a[(y, y)] = s.re;
        }
        a[(1, 4)] = 1.0;
        a[(4, 5)] = 1.0;
        a[(5, 5)] = -0.5;
        let b = Mat::from_fn(7, 2, |i, j| ((i * 3 + j) as f64 * 0.7).sin());
        let c = Mat::from_fn(3, 7, |i, j| ((i * 5 + j) as f64 * 0.3).cos());
        let d = Mat::from_fn(3, 2, |i, j| (i + 2 * j) as f64 * 0.1);
        assert_eq!(
            diagonal_blocks(&a),
            vec![vec![0, 3], vec![1, 4, 5], vec![2, 6]]
        );
        let f: Vec<f64> = (1..200).map(|k| 0.05 * k as f64).collect();
        for domain in [
            TimeDomain::Continuous,
            TimeDomain::Discrete {
                sample_time_s: 0.01,
            },
        ] {
            let mut a = a.clone();
            if domain != TimeDomain::Continuous {
                // Keep the discrete poles inside the unit circle.
                a = Mat::from_fn(7, 7, |i, j| {
                    0.01 * a[(i, j)] + f64::from(u8::from(i == j)) * 0.9
                });
            }
            let model = StateSpace::new(a, b.clone(), c.clone(), d.clone(), domain);
            let blocks = frequency_response_blocks(&model, &f);
            let naive = frequency_response_naive(&model, &f);
            assert_response("diagonal blocks", &blocks, &naive, tol(C_RESPONSE, 7, 1.0));
        }
    }

    #[test]
    fn hessenberg_form_is_similar_to_a() {
        let model = truth_model();
        let form = HessenbergForm::new(&model);
        let h = form.h();
        for j in 0..8 {
            for i in j + 2..8 {
                assert_eq!(h[(i, j)], 0.0);
            }
        }
        let mut expected = model.poles().unwrap();
        let mut got = crate::linalg::eigen::balanced_eigen(h).unwrap().0;
        for v in [&mut expected, &mut got] {
            v.sort_by(|a, b| a.im.total_cmp(&b.im));
        }
        // The eigenvalues of a similar matrix: the poles' own conditioning, not rounding.
        assert_response("Hessenberg eigenvalues", &got, &expected, 1e-10);
    }

    #[test]
    fn hessenberg_and_modal_paths_match_the_dense_solve() {
        let freq: Vec<f64> = (0..200).map(|k| 37.0 * k as f64).collect();
        let truth = truth_model().c2d(1.0 / 25_600.0).unwrap();
        let dense = frequency_response_naive(&truth, &freq);
        let fast = frequency_response(&truth, &freq).unwrap();
        assert_response(
            "Hessenberg, truth model",
            &fast,
            &dense,
            tol(C_RESPONSE, 8, 1.0),
        );
        // Well-conditioned modal coordinates: the modal form agrees too.
        let structure = ModalStructure::random(&ModalSpec::new(3, 2, 6)).unwrap();
        let model = structure.state_space(crate::data::frf::Quantity::Velocity);
        let freq: Vec<f64> = (0..300).map(|k| 0.05 * k as f64).collect();
        let dense = frequency_response_naive(&model, &freq);
        let fast = frequency_response(&model, &freq).unwrap();
        assert_response(
            "Hessenberg, modal structure",
            &fast,
            &dense,
            tol(C_RESPONSE, 12, 1.0),
        );
        let modal = frequency_response_modal(&model, &ModalForm::new(&model).unwrap(), &freq);
        let form = ModalForm::new(&model).unwrap();
        assert_response(
            "modal form",
            &modal,
            &dense,
            tol(C_RESPONSE, 12, form.eigenvector_condition),
        );
    }

    /// On an ERA model of the DTA-like set (balanced coordinates, κ(V) small) the
    /// dispatcher takes the modal form, and it equals the Hessenberg solve it replaced.
    #[test]
    fn modal_dispatch_equals_the_hessenberg_solve_on_an_era_model() {
        use crate::identify::{identify, EraOptions};
        use crate::pipeline::realize::SvdPath;
        let structure = ModalStructure::random(&ModalSpec::default()).unwrap();
        let frf = structure
            .frf(801, 0.025, crate::data::frf::Quantity::Acceleration)
            .unwrap();
        let found = identify(
            &frf,
            &EraOptions {
                svd: SvdPath::MatrixFree,
                ..EraOptions::thesis_dta()
            },
        )
        .unwrap();
        let model = &found.model;
        let form = ModalForm::new(model).unwrap();
        assert!(form.eigenvector_condition <= MODAL_CONDITION_LIMIT);
        let reference = HessenbergForm::new(model).response(frf.frequency_hz());
        let fast = frequency_response(model, frf.frequency_hz()).unwrap();
        assert_response(
            "modal dispatch",
            &fast,
            &reference,
            tol(C_RESPONSE, 80, form.eigenvector_condition),
        );
        // An ill-conditioned model (the truth model, physical coordinates) keeps the
        // Hessenberg path, bit for bit.
        let truth = truth_model().c2d(1.0 / 25_600.0).unwrap();
        assert!(ModalForm::new(&truth).unwrap().eigenvector_condition > MODAL_CONDITION_LIMIT);
        let freq: Vec<f64> = (0..100).map(|k| 120.0 * k as f64).collect();
        assert_eq!(
            frequency_response(&truth, &freq).unwrap(),
            HessenbergForm::new(&truth).response(&freq)
        );
    }
}
