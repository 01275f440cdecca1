//! Rank-one residues fitted jointly with the poles: `R_r = u_r v_rᵀ` (`u_r` over the
//! outputs, `v_r` over the inputs), or `R_r = ψ_r ψ_rᵀ` when reciprocal, the form of a
//! structure's mode. It starts from the free fit (its poles, each residue's leading
//! singular pair, its residual terms) and minimises the same weighted cost by
//! Levenberg–Marquardt over every parameter at once.
//!
//! # Why jointly
//!
//! A free residue per pole can take up more than its mode: near a close pair or a mode
//! the start missed, one pole with a rank-two residue stands in for two modes, or a pole
//! wanders between modes fitting what their residues leave. Truncating such a fit to rank
//! one at fixed poles loses the data there (on the 8 × 8 DTA-like set with 5 % noise the
//! fit went from 0.049 to 0.069). Moving the poles with the shapes lets each pole be one
//! mode again.
//!
//! # The normal equations from small Gram matrices
//!
//! The model of pair `k = (i, j)` is `m_k = Φ c_k` with the free fit's real basis `Φ`
//! (`2L × columns`: per mode `(Re R, Im R)`, then the residual terms) and
//! `c_k = (Re u_ir v_jr, Im u_ir v_jr, …, K_k)`. A derivative by a shape, participation
//! or residual parameter is `Φ a` with `a` two entries of a 2 × 2 complex-product block
//! (or one entry for a residual term); a derivative by a pole parameter is `D b_k`, `D`
//! the basis derivatives and `b_k` the pair's residue entries. So with
//! `H = ΦᵀΦ`, `E = DᵀΦ` (kept as `Eᵀ`), `M = DᵀD` and the projections `Φᵀr_k`, `Dᵀr_k` of the residuals,
//! every entry of `JᵀWJ` and `JᵀWr` is a short sum over a pair's few nonzeros:
//! `O(q·p·(4N)²)` per iteration, not `O(L·q·p·(4N)²)`.
//!
//! An output's shapes and residual terms couple with the poles, the participations and
//! each other, and with nothing of another output. So `N` is kept by blocks ([`Blocks`]):
//! `N_zz` over the poles and participations `z`, and per output `N_ii` and `N_iz`. The
//! outputs are eliminated by one Schur complement, `S = N_zz − N_Izᵀ N_II⁻¹ N_Iz`
//! ([`Reduced`]), and each trial step is one Cholesky factorisation of `S`. On 8 × 8 with
//! 40 modes and one residual term that is 640 unknowns where `N` has 1344, and no 1344²
//! matrix is formed. A
//! reciprocal fit (`v = u`) has no parameter of one output only; its `N` stays dense.
//!
//! The scale of `u_r` against `v_r` is free (`u c, v/c` give the same residue): one entry
//! of each `v_r`, its largest at the start, is held fixed. The weights must be constant
//! over the band per pair (uniform, or [`super::Weighting::PairNoise`]'s); real-mode
//! fits keep free residues.
//!
//! # Creeping descents and Newton's steps
//!
//! Gauss–Newton's `N = JᵀWJ` leaves out the residuals' curvature
//! `Q = Σ w² Σ r ∇²m` ([`curvature_entries`]). Where the residual keeps a structure (a
//! close pair, a mode not yet in the fit), `N` overstates the cost's curvature along the
//! weak directions: each step is too short, its gain ratio climbs towards 2 and the
//! decreases shrink by a constant ratio, tens of iterations for a few noise variances.
//! After [`CREEP_STEPS`] such steps in a row ([`CREEP_RHO`]) the descent solves Newton's
//! equations `N − Q` instead, the cost's own Hessian. `Q` is nonzero only within one
//! mode (its pole parameters with each other, with its shape and participation entries,
//! and a shape entry with a participation entry), so it costs the basis's second
//! derivatives ([`basis_second_derivatives`]) and a few entries per pair and mode.
//! Newton's step heads for any stationary point, a saddle as readily as a minimum, so it
//! is taken only where the cost is convex (the undamped reduced `N − Q` positive
//! definite); elsewhere the point's equations are Gauss–Newton's again until the next
//! creep. The covariance stays that of `N`.
//!
//! # Uncertainty
//!
//! The poles' covariance is the pole block of `σ̂² N⁻¹`, `N` the normal matrix over every
//! free parameter, `σ̂² = cost/(observations − parameters)`: fewer nuisance parameters
//! than the free fit's, so slightly smaller standard deviations where modes overlap.

use super::lm::{
    damped, descend, finite_column, limit_step, normalise, LeastSquares, Nielsen, Trial, EXACT_FIT,
    STATISTICAL_STOP,
};
use super::model::{
    basis, basis_derivatives, basis_second_derivatives, Problem, PARAMETER_COUPLES,
};
use crate::error::{EraError, Result};
use faer::linalg::solvers::Solve;
use faer::Mat;
use num_complex::Complex64;

/// Most free parameters of the joint fit; beyond, the residues stay free. A reciprocal
/// fit's normal matrix is dense (4000² values are 128 MB, one per thread while it is
/// assembled); the others hold `N_zz`, about half the parameters squared, per thread.
pub(crate) const MAX_PARAMETERS: usize = 4000;

/// The joint fit's free parameters with `modes` modes, counted by the layout itself
/// (which participation entry is held does not change the count).
fn parameters(problem: &Problem, modes: usize) -> usize {
    Indices::new(
        modes,
        problem.outputs,
        problem.inputs,
        problem.layout.residuals.len(),
        problem.reciprocal,
        &vec![0; modes],
    )
    .free
}

/// Whether the rank-one stage will run after a free fit with `modes` modes (it steps
/// aside beyond [`MAX_PARAMETERS`]; dropped modes only make it smaller).
pub(crate) fn will_run(problem: &Problem, modes: usize) -> bool {
    problem.rank_one_follows() && parameters(problem, modes) <= MAX_PARAMETERS
}

/// The result of the joint fit.
pub(crate) struct Joint {
    pub theta: Vec<f64>,
    /// `columns × pairs`, in the free fit's layout.
    pub coefficients: Mat<f64>,
    pub cost: f64,
    /// `σ̂² (N⁻¹)` over the pole parameters.
    pub covariance: Option<Mat<f64>>,
    pub noise_variance: f64,
    pub iterations: usize,
    pub converged: bool,
}

/// Every parameter of the rank-one model.
#[derive(Clone)]
struct Parameters {
    theta: Vec<f64>,
    /// `u[i·N + r]`.
    u: Vec<Complex64>,
    /// `v[j·N + r]`.
    v: Vec<Complex64>,
    /// `k[pair·n_res + e]`.
    k: Vec<f64>,
}

/// Where each raw parameter (θ, u, v, K, in that order) goes among the free ones.
struct Indices {
    n: usize,
    q: usize,
    p: usize,
    n_res: usize,
    reduced: Vec<Option<usize>>,
    free: usize,
}

impl Indices {
    fn u(&self, i: usize, r: usize, part: usize) -> usize {
        2 * self.n + (i * self.n + r) * 2 + part
    }
    fn v(&self, j: usize, r: usize, part: usize) -> usize {
        2 * self.n + 2 * self.q * self.n + (j * self.n + r) * 2 + part
    }
    fn k(&self, pair: usize, e: usize) -> usize {
        2 * self.n + 2 * (self.q + self.p) * self.n + pair * self.n_res + e
    }
    fn raw(&self) -> usize {
        self.k(self.q * self.p, 0)
    }

    fn new(n: usize, q: usize, p: usize, n_res: usize, reciprocal: bool, fixed: &[usize]) -> Self {
        let mut ix = Indices {
            n,
            q,
            p,
            n_res,
            reduced: Vec::new(),
            free: 0,
        };
        let mut reduced = vec![None; ix.raw()];
        let mut next = 0;
        let mut take = |slot: &mut Option<usize>| {
            *slot = Some(next);
            next += 1;
        };
        for slot in reduced.iter_mut().take(2 * n) {
            take(slot);
        }
        for i in 0..q {
            for r in 0..n {
                for part in 0..2 {
                    take(&mut reduced[ix.u(i, r, part)]);
                }
            }
        }
        if reciprocal {
            // v_j = u_j (ψ), K_ij = K_ji.
            for j in 0..p {
                for r in 0..n {
                    for part in 0..2 {
                        reduced[ix.v(j, r, part)] = reduced[ix.u(j, r, part)];
                    }
                }
            }
            for i in 0..q {
                for j in i..p {
                    for e in 0..n_res {
                        take(&mut reduced[ix.k(i * p + j, e)]);
                        reduced[ix.k(j * p + i, e)] = reduced[ix.k(i * p + j, e)];
                    }
                }
            }
        } else {
            for j in 0..p {
                for r in 0..n {
                    if fixed[r] == j {
                        continue;
                    }
                    for part in 0..2 {
                        take(&mut reduced[ix.v(j, r, part)]);
                    }
                }
            }
            for pair in 0..q * p {
                for e in 0..n_res {
                    take(&mut reduced[ix.k(pair, e)]);
                }
            }
        }
        ix.reduced = reduced;
        ix.free = next;
        ix
    }
}

/// The data over the band, `2L × pairs` (real parts over imaginary parts).
fn stacked_data(problem: &Problem) -> Mat<f64> {
    let nl = problem.omega.len();
    Mat::from_fn(2 * nl, problem.data.len(), |row, pair| {
        let v = problem.data[pair][row % nl];
        if row < nl {
            v.re
        } else {
            v.im
        }
    })
}

fn coefficients(x: &Parameters, ix: &Indices, n_col: usize) -> Mat<f64> {
    let (n, q, p) = (ix.n, ix.q, ix.p);
    Mat::from_fn(n_col, q * p, |c, pair| {
        let (i, j) = (pair / p, pair % p);
        if c < 2 * n {
            let z = x.u[i * n + c / 2] * x.v[j * n + c / 2];
            if c % 2 == 0 {
                z.re
            } else {
                z.im
            }
        } else {
            x.k[pair * ix.n_res + (c - 2 * n)]
        }
    })
}

/// The free fit's basis `Φ` at some poles, with its Gram matrix `H = ΦᵀΦ`, which the
/// best shapes for a trial ([`solve_linear`]) and, once the trial is accepted, the
/// normal equations ([`Grams`]) both read.
struct Basis {
    phi: Mat<f64>,
    h: Mat<f64>,
}

/// The free fit's basis `Φ` at the poles of `theta`, and its Gram matrix.
fn basis_at(problem: &Problem, theta: &[f64]) -> Basis {
    let phi = basis(
        &problem.layout,
        &problem.omega,
        &problem.parameters.poles(theta),
    );
    let h = phi.transpose() * &phi;
    Basis { phi, h }
}

/// Weighted cost and the residual `Y − ΦC`, `phi` the basis at `x`'s poles.
fn cost(
    x: &Parameters,
    ix: &Indices,
    phi: &Mat<f64>,
    y: &Mat<f64>,
    weights: &[f64],
) -> (f64, Mat<f64>) {
    let c = coefficients(x, ix, phi.ncols());
    let residual = y - phi * &c;
    let total = (0..residual.ncols())
        .map(|pair| weights[pair] * weights[pair] * residual.col(pair).squared_norm_l2())
        .sum();
    (total, residual)
}

/// The projections every entry of `JᵀWJ` and `JᵀWr` is a short sum of (module doc).
struct Grams {
    h: Mat<f64>,
    /// `Eᵀ = ΦᵀD`: a pole parameter's two columns lie down its columns.
    e_t: Mat<f64>,
    m: Mat<f64>,
    phi_r: Mat<f64>,
    d_r: Mat<f64>,
    /// `D₂ᵀr`, the second derivatives of the basis ([`basis_second_derivatives`]) against
    /// the residuals, when the curvature of the cost is wanted ([`curvature_entries`]).
    d2_r: Option<Mat<f64>>,
}

impl Grams {
    fn new(
        problem: &Problem,
        x: &Parameters,
        basis: &Basis,
        residual: &Mat<f64>,
        second: bool,
    ) -> Self {
        let poles = problem.parameters.poles(&x.theta);
        let d = basis_derivatives(&problem.layout, problem.parameters, &problem.omega, &poles);
        let phi = &basis.phi;
        let d2_r = second.then(|| {
            let d2 = basis_second_derivatives(
                &problem.layout,
                problem.parameters,
                &problem.omega,
                &poles,
            );
            d2.transpose() * residual
        });
        Grams {
            h: basis.h.clone(),
            e_t: phi.transpose() * &d,
            m: d.transpose() * &d,
            phi_r: phi.transpose() * residual,
            d_r: d.transpose() * residual,
            d2_r,
        }
    }
}

/// Output `i`'s part of `Q = Σ_k w_k² Σ_l r_kl ∇²m_kl`, the residuals' curvature that
/// Gauss–Newton leaves out of the cost's Hessian `N − Q` (`N = JᵀWJ`), as
/// `(f, g, value)` over free parameters: each unordered couple once per pair, so that a
/// couple of pole parameters, or a pole's with a shape entry, comes once for every
/// input and the consumer sums them. A pair's model is
/// `Σ_r Φ_r (Re z_r, Im z_r)` with `z_r = u_ir v_jr`: its second derivatives are nonzero
/// only within one mode, between its two pole parameters (`D₂`), between a pole
/// parameter and a shape or participation entry (`D`), and between a shape and a
/// participation entry (`Φ`, the bilinear product); the residual terms are linear.
/// Near a minimum with small residuals `Q` is negligible and Gauss–Newton converges
/// fast; where a structured residual remains (a close pair, a mode the fit has not
/// got yet) `Q` is what makes its steps creep. `grams` must hold `D₂ᵀr`.
fn curvature_entries(
    grams: &Grams,
    x: &Parameters,
    ix: &Indices,
    weights: &[f64],
    i: usize,
) -> Vec<(usize, usize, f64)> {
    let (n, p) = (ix.n, ix.p);
    let Some(d2_r) = grams.d2_r.as_ref() else {
        return Vec::new();
    };
    let (phi_r, d_r) = (&grams.phi_r, &grams.d_r);
    let mut out = Vec::with_capacity(p * n * 16);
    for j in 0..p {
        let pair = i * p + j;
        let w2 = weights[pair] * weights[pair];
        for r in 0..n {
            let (u, v) = (x.u[i * n + r], x.v[j * n + r]);
            let z = u * v;
            let pole = |t: usize| ix.reduced[2 * r + t];
            // Pole with pole.
            for (c, &(t, t2)) in PARAMETER_COUPLES.iter().enumerate() {
                if let (Some(f), Some(g)) = (pole(t), pole(t2)) {
                    let col = (3 * r + c) * 2;
                    let value = w2 * (z.re * d2_r[(col, pair)] + z.im * d2_r[(col + 1, pair)]);
                    out.push((f, g, value));
                }
            }
            // Pole with a shape or participation entry: ∂(Re z, Im z) of each entry.
            let linear = product_derivatives(ix, (i, j, r), u, v);
            for t in 0..2 {
                let Some(f) = pole(t) else { continue };
                let col = (2 * r + t) * 2;
                for &(raw, [alpha, beta]) in &linear {
                    if let Some(g) = ix.reduced[raw] {
                        let value = w2 * (alpha * d_r[(col, pair)] + beta * d_r[(col + 1, pair)]);
                        out.push((f, g, value));
                    }
                }
            }
            // Shape with participation: Re z = u'v' − u''v'', Im z = u'v'' + u''v'.
            let (re, im) = (phi_r[(2 * r, pair)], phi_r[(2 * r + 1, pair)]);
            for (pu, pv, value) in [(0, 0, re), (0, 1, im), (1, 0, im), (1, 1, -re)] {
                if let (Some(f), Some(g)) = (ix.reduced[ix.u(i, r, pu)], ix.reduced[ix.v(j, r, pv)])
                {
                    out.push((f, g, w2 * value));
                }
            }
        }
    }
    out
}

/// The shape and participation entries of mode `r` in pair `(i, j)`, by raw index, with
/// the derivatives of the pair's residue `z = u_ir v_jr` by each, `∂(Re z, Im z)`.
fn product_derivatives(
    ix: &Indices,
    (i, j, r): (usize, usize, usize),
    u: Complex64,
    v: Complex64,
) -> [(usize, [f64; 2]); 4] {
    [
        (ix.u(i, r, 0), [v.re, v.im]),
        (ix.u(i, r, 1), [-v.im, v.re]),
        (ix.v(j, r, 0), [u.re, u.im]),
        (ix.v(j, r, 1), [-u.im, u.re]),
    ]
}

/// `δᵀQδ` of the entries of [`curvature_entries`].
fn curvature_form(entries: &[(usize, usize, f64)], step: &[f64]) -> f64 {
    entries
        .iter()
        .map(|&(f, g, value)| {
            let both = if f == g { 1.0 } else { 2.0 };
            both * value * step[f] * step[g]
        })
        .sum()
}

/// Output `i`'s part of `N = JᵀWJ` and `g = JᵀWr`, added entry by entry to `normal`
/// and `g` (each unordered couple of entries is visited once and written on both sides
/// of the diagonal).
fn output_entries(
    grams: &Grams,
    x: &Parameters,
    ix: &Indices,
    weights: &[f64],
    i: usize,
    normal: &mut Mat<f64>,
    g: &mut [f64],
) {
    let mut entry = |f: usize, other: usize, value: f64, mirrored: bool| {
        normal[(f, other)] += value;
        if mirrored {
            normal[(other, f)] += value;
        }
    };
    let mut gradient = |f: usize, value: f64| g[f] += value;
    let (n, p, n_res) = (ix.n, ix.p, ix.n_res);
    let Grams {
        h,
        e_t,
        m,
        phi_r,
        d_r,
        ..
    } = grams;
    // A linear parameter of a pair: its free index, its (column, value) entries and how
    // many of them are used.
    type Linear = (usize, [(usize, f64); 2], usize);
    let mut linear: Vec<Linear> = Vec::with_capacity(4 * n + n_res);
    // A pole parameter: its free index and (derivative column, value) entries.
    let mut poles_of_pair: Vec<(usize, [(usize, f64); 2])> = Vec::with_capacity(2 * n);
    for j in 0..p {
        let pair = i * p + j;
        let w2 = weights[pair] * weights[pair];
        linear.clear();
        poles_of_pair.clear();
        for r in 0..n {
            let (u, v) = (x.u[i * n + r], x.v[j * n + r]);
            let (a, b) = (2 * r, 2 * r + 1);
            // R = u v: ∂(Re R, Im R)/∂(Re u) = (Re v, Im v), /∂(Im u) = (−Im v, Re v).
            for (raw, [dre, dim]) in product_derivatives(ix, (i, j, r), u, v) {
                if let Some(f) = ix.reduced[raw] {
                    linear.push((f, [(a, dre), (b, dim)], 2));
                }
            }
            let z = u * v;
            for t in 0..2 {
                let col = (2 * r + t) * 2;
                poles_of_pair.push((2 * r + t, [(col, z.re), (col + 1, z.im)]));
            }
        }
        for e_res in 0..n_res {
            if let Some(f) = ix.reduced[ix.k(pair, e_res)] {
                linear.push((f, [(2 * n + e_res, 1.0), (0, 0.0)], 1));
            }
        }
        for (k, &(fx, ex, nx)) in linear.iter().enumerate() {
            gradient(
                fx,
                w2 * ex[..nx]
                    .iter()
                    .map(|&(c, a)| a * phi_r[(c, pair)])
                    .sum::<f64>(),
            );
            for (l, &(fy, ey, ny)) in linear.iter().enumerate().skip(k) {
                let mut s = 0.0;
                for &(cx, ax) in &ex[..nx] {
                    for &(cy, ay) in &ey[..ny] {
                        s += ax * ay * h[(cx, cy)];
                    }
                }
                entry(fx, fy, w2 * s, l != k);
            }
        }
        for (k, &(ft, et)) in poles_of_pair.iter().enumerate() {
            gradient(
                ft,
                w2 * et.iter().map(|&(c, a)| a * d_r[(c, pair)]).sum::<f64>(),
            );
            for (l, &(fs, es)) in poles_of_pair.iter().enumerate().skip(k) {
                let mut s = 0.0;
                for &(ct, at) in &et {
                    for &(cs, as_) in &es {
                        s += at * as_ * m[(ct, cs)];
                    }
                }
                entry(ft, fs, w2 * s, l != k);
            }
            for &(fx, ex, nx) in &linear {
                let mut s = 0.0;
                for &(ct, at) in &et {
                    for &(cx, ax) in &ex[..nx] {
                        s += at * ax * e_t[(cx, ct)];
                    }
                }
                entry(ft, fx, w2 * s, true);
            }
        }
    }
}

/// `(N, g)` over the free parameters at `x`, dense (`N = JᵀWJ`, `g = JᵀW r`): the
/// reciprocal fit's, where no parameter belongs to one output only, and the reference
/// the blocks are tested against.
fn dense_normal(
    problem: &Problem,
    x: &Parameters,
    ix: &Indices,
    basis: &Basis,
    residual: &Mat<f64>,
    weights: &[f64],
) -> (Mat<f64>, Vec<f64>) {
    let grams = Grams::new(problem, x, basis, residual, false);
    let free = ix.free;
    let add_output = |(mut normal, mut gradient): (Mat<f64>, Vec<f64>), i: usize| {
        output_entries(&grams, x, ix, weights, i, &mut normal, &mut gradient);
        (normal, gradient)
    };
    use rayon::prelude::*;
    // One accumulator per thread, not per output: each is `free²` values.
    let per_thread = ix.q.div_ceil(rayon::current_num_threads().max(1));
    (0..ix.q)
        .into_par_iter()
        .with_min_len(per_thread)
        .fold(
            || (Mat::<f64>::zeros(free, free), vec![0.0; free]),
            add_output,
        )
        .reduce(
            || (Mat::<f64>::zeros(free, free), vec![0.0; free]),
            |(mut a, mut ga), (b, gb)| {
                a += &b;
                for (x, y) in ga.iter_mut().zip(&gb) {
                    *x += y;
                }
                (a, ga)
            },
        )
}

/// Output `i`'s part of [`Blocks`]: the sums of [`output_entries`], arranged as products
/// with the 2 × 2 blocks of each mode so that the inner loops run down columns. Per pair
/// `(i, j)` with `R_r = u_r v_r`, `Bv` (`Bu`) is the block-diagonal map from `(Re u, Im u)`
/// (`(Re v, Im v)`) to `(Re R, Im R)`, and `P` maps each pole parameter to its two
/// derivative columns with `(Re R, Im R)`:
/// `N_uu = Bvᵀ H Bv`, `N_uv = Bvᵀ H Bu`, `N_vv = Buᵀ H Bu`, `N_θθ = Pᵀ M P`,
/// `N_θu = Pᵀ E Bv`, `N_θv = Pᵀ E Bu`, and the residual terms' rows of `H` and `E`.
/// `H Bv` depends on the input alone and `H Bu` on the output alone: `h_bv` holds the
/// former per input, and the latter is formed once here. `N_θθ` is not summed here but
/// once over every pair ([`add_pole_block`]).
#[allow(clippy::too_many_arguments)]
fn add_output_blocks(
    grams: &Grams,
    h_bv: &[Mat<f64>],
    x: &Parameters,
    ix: &Indices,
    part: &Partition,
    weights: &[f64],
    i: usize,
    (shared, gz): (&mut [Shared], &mut [f64]),
    (nii, niz, gi): (&mut Mat<f64>, &mut Mat<f64>, &mut [f64]),
) {
    let m2 = 2 * ix.n;
    let n = ix.n;
    let mut sums = OutputSums {
        theta_z: part.pole_slots(n),
        u_local: (0..m2)
            .map(|k| local_slot(part, ix.reduced[ix.u(i, k / 2, k % 2)]))
            .collect(),
        shared,
        gz,
        nii,
        niz,
        gi,
    };
    let bu: Vec<_> = (0..n).map(|r| complex_map(x.u[i * n + r])).collect();
    let mut scratch = Scratch {
        h_bu: times_blocks(&grams.h, &bu),
        pe_column: vec![0.0; grams.h.ncols()],
        column: vec![0.0; m2],
    };
    for (j, yv) in h_bv.iter().enumerate() {
        let maps = PairMaps::new(x, ix, part, weights, i, j);
        sums.add_shapes(yv, &maps, j, &mut scratch);
        sums.add_residual_terms(grams, &maps);
        sums.add_poles(grams, &maps, j, &mut scratch);
        sums.add_gradient(grams, &maps);
    }
}

/// `N_θθ = Σ_pairs w Pᵀ M P` ([`add_output_blocks`]) at once: entry `(k, l)` is
/// `Σ_αβ M[2k+α, 2l+β] G[2(k/2)+α, 2(l/2)+β]` with `G = Zᵀ W Z`, `Zᵀ` the residues
/// `(Re R_r, Im R_r)` of every pair by column ([`coefficients`]' modes' rows) and `W` the
/// pairs' weights: one GEMM over the pairs instead of a `4N × 2N` product per pair.
fn add_pole_block(
    grams: &Grams,
    x: &Parameters,
    ix: &Indices,
    part: &Partition,
    weights: &[f64],
    nzz: &mut Mat<f64>,
) {
    let m2 = 2 * ix.n;
    let z_t = coefficients(x, ix, m2);
    let weighted = Mat::from_fn(m2, ix.q * ix.p, |k, pair| {
        weights[pair] * weights[pair] * z_t[(k, pair)]
    });
    let g = &z_t * weighted.transpose();
    let m = &grams.m;
    let theta_z = part.pole_slots(ix.n);
    for l in 0..m2 {
        let (l0, l1) = (m.col_as_slice(2 * l), m.col_as_slice(2 * l + 1));
        let (g0, g1) = (g.col_as_slice(2 * (l / 2)), g.col_as_slice(2 * (l / 2) + 1));
        for k in 0..m2 {
            let (a, b) = (2 * k, 2 * (k / 2));
            nzz[(theta_z[k], theta_z[l])] +=
                l0[a] * g0[b] + l0[a + 1] * g0[b + 1] + l1[a] * g1[b] + l1[a + 1] * g1[b + 1];
        }
    }
}

/// Where free parameter `f` sits among an output's own parameters.
fn local_slot(part: &Partition, f: Option<usize>) -> usize {
    match f.map(|f| part.slot[f]) {
        Some(Slot::Local(a)) => a,
        _ => unreachable!("an output's shapes and residual terms are its own"),
    }
}

/// Where free parameter `f` sits among the shared parameters, if it is one.
fn shared_slot(part: &Partition, f: Option<usize>) -> Option<usize> {
    match f.map(|f| part.slot[f]) {
        Some(Slot::Shared(a)) => Some(a),
        _ => None,
    }
}

/// Where input `j`'s participation entries `(mode, Re/Im)` sit among the shared
/// parameters (`None` for the held one).
fn participation_slots(ix: &Indices, part: &Partition, j: usize) -> Vec<Option<usize>> {
    (0..2 * ix.n)
        .map(|k| shared_slot(part, ix.reduced[ix.v(j, k / 2, k % 2)]))
        .collect()
}

/// The 2 × 2 map of a complex factor c: (Re w, Im w) ↦ (Re cw, Im cw), as [row][col].
fn complex_map(c: Complex64) -> [[f64; 2]; 2] {
    [[c.re, -c.im], [c.im, c.re]]
}

/// Pair `(i, j)` in [`add_output_blocks`]: its weight, the 2 × 2 maps `Bv`, `Bu`, the
/// residues `R_r = u_r v_r`, and where its participations and residual terms sit.
struct PairMaps {
    pair: usize,
    w: f64,
    bv: Vec<[[f64; 2]; 2]>,
    bu: Vec<[[f64; 2]; 2]>,
    z: Vec<Complex64>,
    v_z: Vec<Option<usize>>,
    k_local: Vec<usize>,
}

impl PairMaps {
    fn new(
        x: &Parameters,
        ix: &Indices,
        part: &Partition,
        weights: &[f64],
        i: usize,
        j: usize,
    ) -> Self {
        let (n, p, n_res) = (ix.n, ix.p, ix.n_res);
        let pair = i * p + j;
        PairMaps {
            pair,
            w: weights[pair] * weights[pair],
            bv: (0..n).map(|r| complex_map(x.v[j * n + r])).collect(),
            bu: (0..n).map(|r| complex_map(x.u[i * n + r])).collect(),
            z: (0..n).map(|r| x.u[i * n + r] * x.v[j * n + r]).collect(),
            v_z: participation_slots(ix, part, j),
            k_local: (0..n_res)
                .map(|res| local_slot(part, ix.reduced[ix.k(pair, res)]))
                .collect(),
        }
    }
}

/// Work space of [`add_output_blocks`]: the output's `H Bu`, and a column of `(Pᵀ E)ᵀ`
/// and one of the shapes' blocks, reused from pair to pair.
struct Scratch {
    h_bu: Mat<f64>,
    pe_column: Vec<f64>,
    column: Vec<f64>,
}

/// `H B` over the modes' columns of `H` (`2N × 2N`), `B` block-diagonal with the 2 × 2
/// blocks `b`.
fn times_blocks(h: &Mat<f64>, b: &[[[f64; 2]; 2]]) -> Mat<f64> {
    let m2 = 2 * b.len();
    let mut y = Mat::<f64>::zeros(m2, m2);
    for (r, br) in b.iter().enumerate() {
        let (h0, h1) = (
            &h.col_as_slice(2 * r)[..m2],
            &h.col_as_slice(2 * r + 1)[..m2],
        );
        for (c, (&a0, &a1)) in br[0].iter().zip(&br[1]).enumerate() {
            for (out, (x0, x1)) in y
                .col_as_slice_mut(2 * r + c)
                .iter_mut()
                .zip(h0.iter().zip(h1))
            {
                *out = x0 * a0 + x1 * a1;
            }
        }
    }
    y
}

/// One input's part of `N_zz` that the outputs add to, by the input's own participation
/// entries `(mode, Re/Im)` (`2N`, the held one included, dropped when placed): `N_vv`
/// (`2N × 2N`) and `N_vθ` (`2N` × the `2N` pole parameters). Per thread a few of these
/// instead of all of `N_zz` (0.8 against 3.3 MB on 8 × 8 with 40 modes).
struct Shared {
    vv: Mat<f64>,
    vt: Mat<f64>,
}

impl Shared {
    fn zeros(m2: usize) -> Self {
        Shared {
            vv: Mat::zeros(m2, m2),
            vt: Mat::zeros(m2, m2),
        }
    }

    /// Adds `other`, entry by entry.
    fn add(&mut self, other: &Shared) {
        self.vv += &other.vv;
        self.vt += &other.vt;
    }

    /// Adds these sums into `N_zz` where input `j`'s free participation entries sit.
    fn place(&self, ix: &Indices, part: &Partition, j: usize, nzz: &mut Mat<f64>) {
        let v_z = participation_slots(ix, part, j);
        let theta_z = part.pole_slots(ix.n);
        for (col, &c) in v_z.iter().enumerate() {
            let Some(c) = c else { continue };
            for (row, &r) in v_z.iter().enumerate() {
                if let Some(r) = r {
                    nzz[(r, c)] += self.vv[(row, col)];
                }
            }
        }
        for (t, &tz) in theta_z.iter().enumerate() {
            for (row, &r) in v_z.iter().enumerate() {
                if let Some(r) = r {
                    nzz[(r, tz)] += self.vt[(row, t)];
                }
            }
        }
    }
}

/// Output `i`'s sums in [`Blocks`] (shared–shared `shared` per input and `gz`; own–own
/// `nii`, own–shared `niz`, `gi`), and where the output's shapes (`u_local`) and the
/// poles (`theta_z`) sit.
struct OutputSums<'a> {
    shared: &'a mut [Shared],
    gz: &'a mut [f64],
    nii: &'a mut Mat<f64>,
    niz: &'a mut Mat<f64>,
    gi: &'a mut [f64],
    u_local: Vec<usize>,
    theta_z: Vec<usize>,
}

impl OutputSums<'_> {
    /// `N_uu = Bvᵀ H Bv`, `N_uv = Bvᵀ H Bu`, `N_vv = Buᵀ H Bu`, from the pair's input's
    /// `H Bv` (`yv`) and its output's `H Bu`.
    /// Column by column, each written where it belongs.
    fn add_shapes(&mut self, yv: &Mat<f64>, maps: &PairMaps, j: usize, scratch: &mut Scratch) {
        let PairMaps { w, bv, bu, v_z, .. } = maps;
        let w = *w;
        let Scratch { h_bu, column, .. } = scratch;
        let OutputSums {
            shared,
            nii,
            niz,
            u_local,
            ..
        } = self;
        let vv = &mut shared[j].vv;
        for col in 0..u_local.len() {
            left_column(bv, yv.col_as_slice(col), column);
            let out = nii.col_as_slice_mut(u_local[col]);
            for (&row, v) in u_local.iter().zip(column.iter()) {
                out[row] += w * v;
            }
            let Some(c) = v_z[col] else { continue };
            left_column(bv, h_bu.col_as_slice(col), column);
            let out = niz.col_as_slice_mut(c);
            for (&row, v) in u_local.iter().zip(column.iter()) {
                out[row] += w * v;
            }
            left_column(bu, h_bu.col_as_slice(col), column);
            for (out, v) in vv.col_as_slice_mut(col).iter_mut().zip(column.iter()) {
                *out += w * v;
            }
        }
    }

    /// The residual terms: their columns of H against the shapes, and each other, and
    /// their gradient.
    fn add_residual_terms(&mut self, grams: &Grams, maps: &PairMaps) {
        let Grams { h, phi_r, .. } = grams;
        let m2 = self.u_local.len();
        let n = m2 / 2;
        let PairMaps {
            pair,
            w,
            bv,
            bu,
            v_z,
            k_local,
            ..
        } = maps;
        let (pair, w) = (*pair, *w);
        let OutputSums {
            nii,
            niz,
            gi,
            u_local,
            ..
        } = self;
        for (res, &kl) in k_local.iter().enumerate() {
            let hk = &h.col_as_slice(m2 + res)[..m2];
            for r in 0..n {
                for a in 0..2 {
                    let (row, (gv, gu)) = (
                        2 * r + a,
                        (
                            bv[r][0][a] * hk[2 * r] + bv[r][1][a] * hk[2 * r + 1],
                            bu[r][0][a] * hk[2 * r] + bu[r][1][a] * hk[2 * r + 1],
                        ),
                    );
                    nii[(u_local[row], kl)] += w * gv;
                    nii[(kl, u_local[row])] += w * gv;
                    if let Some(c) = v_z[row] {
                        niz[(kl, c)] += w * gu;
                    }
                }
            }
            for (res2, &kl2) in k_local.iter().enumerate() {
                nii[(kl, kl2)] += w * h[(m2 + res, m2 + res2)];
            }
            gi[kl] += w * phi_r[(m2 + res, pair)];
        }
    }

    /// The poles' coupling with the rest, one pole parameter `k` at a time: its column
    /// `(Pᵀ E)ᵀ` from `Eᵀ`, then `N_θu = Pᵀ E Bv`, `N_θv = Pᵀ E Bu` and the residual terms'
    /// rows, each written down column `k` (`N_vθ`, which [`Blocks::new`] mirrors;
    /// `N_θθ` is [`add_pole_block`]'s).
    fn add_poles(&mut self, grams: &Grams, maps: &PairMaps, j: usize, scratch: &mut Scratch) {
        let e_t = &grams.e_t;
        let m2 = self.u_local.len();
        let PairMaps {
            w,
            bv,
            bu,
            z,
            k_local,
            ..
        } = maps;
        let w = *w;
        let pe = &mut scratch.pe_column;
        let OutputSums {
            shared,
            niz,
            u_local,
            theta_z,
            ..
        } = self;
        let vt = &mut shared[j].vt;
        for (k, &tz) in theta_z.iter().enumerate() {
            let zk = z[k / 2];
            let (e0, e1) = (e_t.col_as_slice(2 * k), e_t.col_as_slice(2 * k + 1));
            for (out, (x0, x1)) in pe.iter_mut().zip(e0.iter().zip(e1)) {
                *out = zk.re * x0 + zk.im * x1;
            }
            let own = niz.col_as_slice_mut(tz);
            let shared = vt.col_as_slice_mut(k);
            for (r, (br, ur)) in bv.iter().zip(bu).enumerate() {
                let (p0, p1) = (pe[2 * r], pe[2 * r + 1]);
                for c in 0..2 {
                    let col = 2 * r + c;
                    own[u_local[col]] += w * (p0 * br[0][c] + p1 * br[1][c]);
                    shared[col] += w * (p0 * ur[0][c] + p1 * ur[1][c]);
                }
            }
            for (res, &kl) in k_local.iter().enumerate() {
                own[kl] += w * pe[m2 + res];
            }
        }
    }

    /// The gradient over the shapes, participations and poles.
    fn add_gradient(&mut self, grams: &Grams, maps: &PairMaps) {
        let Grams { phi_r, d_r, .. } = grams;
        let m2 = self.u_local.len();
        let n = m2 / 2;
        let PairMaps {
            pair,
            w,
            bv,
            bu,
            z,
            v_z,
            ..
        } = maps;
        let (pair, w) = (*pair, *w);
        let OutputSums {
            gz,
            gi,
            u_local,
            theta_z,
            ..
        } = self;
        for r in 0..n {
            for a in 0..2 {
                let row = 2 * r + a;
                let (f0, f1) = (phi_r[(2 * r, pair)], phi_r[(2 * r + 1, pair)]);
                gi[u_local[row]] += w * (bv[r][0][a] * f0 + bv[r][1][a] * f1);
                if let Some(c) = v_z[row] {
                    gz[c] += w * (bu[r][0][a] * f0 + bu[r][1][a] * f1);
                }
            }
        }
        for k in 0..m2 {
            let zk = z[k / 2];
            gz[theta_z[k]] += w * (zk.re * d_r[(2 * k, pair)] + zk.im * d_r[(2 * k + 1, pair)]);
        }
    }
}

/// `out = Bᵀ y` for `B` block-diagonal with the 2 × 2 blocks `b`.
fn left_column(b: &[[[f64; 2]; 2]], y: &[f64], out: &mut [f64]) {
    for ((br, yr), o) in b.iter().zip(y.chunks_exact(2)).zip(out.chunks_exact_mut(2)) {
        o[0] = br[0][0] * yr[0] + br[1][0] * yr[1];
        o[1] = br[0][1] * yr[0] + br[1][1] * yr[1];
    }
}

/// Where a free parameter sits in [`Blocks`].
#[derive(Clone, Copy)]
enum Slot {
    /// Among `z`, the poles and participations, shared by every output.
    Shared(usize),
    /// Among its output's shapes and residual terms.
    Local(usize),
}

/// The free parameters split for the Schur complement (non-reciprocal fits): `z`, the
/// poles and participations (poles first), and per output its shapes and residual
/// terms, which couple with nothing of another output.
struct Partition {
    z: Vec<usize>,
    /// Per output, its free indices.
    blocks: Vec<Vec<usize>>,
    /// First row of each block in the stacked `N_Iz`.
    offsets: Vec<usize>,
    slot: Vec<Slot>,
}

impl Partition {
    fn new(ix: &Indices) -> Self {
        let (n, q, p, n_res) = (ix.n, ix.q, ix.p, ix.n_res);
        let mut slot = vec![Slot::Shared(usize::MAX); ix.free];
        let blocks: Vec<Vec<usize>> = (0..q)
            .map(|i| {
                let mut b: Vec<usize> = (0..n)
                    .flat_map(|r| [ix.u(i, r, 0), ix.u(i, r, 1)])
                    .chain(
                        (0..p)
                            .flat_map(|j| (0..n_res).map(move |e| (i * p + j, e)))
                            .map(|(pair, e)| ix.k(pair, e)),
                    )
                    .filter_map(|raw| ix.reduced[raw])
                    .collect();
                b.sort_unstable();
                for (k, &f) in b.iter().enumerate() {
                    slot[f] = Slot::Local(k);
                }
                b
            })
            .collect();
        let z: Vec<usize> = (0..ix.free)
            .filter(|&f| matches!(slot[f], Slot::Shared(_)))
            .collect();
        for (k, &f) in z.iter().enumerate() {
            slot[f] = Slot::Shared(k);
        }
        let offsets = blocks
            .iter()
            .scan(0, |next, b| {
                let at = *next;
                *next += b.len();
                Some(at)
            })
            .collect();
        Partition {
            z,
            blocks,
            offsets,
            slot,
        }
    }

    /// Where the `2N` pole parameters sit among the shared ones.
    fn pole_slots(&self, n: usize) -> Vec<usize> {
        (0..2 * n)
            .map(|t| shared_slot(self, Some(t)).expect("the poles are shared"))
            .collect()
    }

    fn local(&self) -> usize {
        self.blocks.iter().map(Vec::len).sum()
    }
}

/// The normal equations of a non-reciprocal fit by blocks: `N_zz` over the shared
/// parameters, and per output `N_ii` and `N_iz`. Nothing else of `N` is nonzero, so
/// the dense `free²` matrix (1344² on 8 × 8 with 40 modes and one residual term) is
/// never formed.
struct Blocks<'a> {
    part: &'a Partition,
    nzz: Mat<f64>,
    gz: Vec<f64>,
    nii: Vec<Mat<f64>>,
    /// Every output's `N_iz`, stacked by [`Partition::offsets`].
    niz: Mat<f64>,
    /// Every output's `g_i`, stacked likewise.
    gi: Vec<f64>,
    /// Per output, its entries of the residuals' curvature `Q` ([`curvature_entries`]),
    /// when the steps are Newton's ([`Blocks::newton`]); empty otherwise.
    curvature: Vec<Vec<(usize, usize, f64)>>,
}

impl<'a> Blocks<'a> {
    #[allow(clippy::too_many_arguments)]
    fn new(
        problem: &Problem,
        x: &Parameters,
        ix: &Indices,
        part: &'a Partition,
        basis: &Basis,
        residual: &Mat<f64>,
        weights: &[f64],
        second: bool,
    ) -> Self {
        use rayon::prelude::*;
        let grams = Grams::new(problem, x, basis, residual, second);
        let nz = part.z.len();
        // Per output: (N_ii, N_iz, g_i); N_zz and g_z summed per thread.
        type Own = (Mat<f64>, Mat<f64>, Vec<f64>);
        type Acc = (Vec<Shared>, Vec<f64>, Vec<(usize, Own)>);
        let n = ix.n;
        let h_bv: Vec<Mat<f64>> = (0..ix.p)
            .map(|j| {
                let bv: Vec<_> = (0..n).map(|r| complex_map(x.v[j * n + r])).collect();
                times_blocks(&grams.h, &bv)
            })
            .collect();
        let add_output = |(mut shared, mut gz, mut own): Acc, i: usize| {
            let m = part.blocks[i].len();
            let mut nii = Mat::<f64>::zeros(m, m);
            let mut niz = Mat::<f64>::zeros(m, nz);
            let mut gi = vec![0.0; m];
            add_output_blocks(
                &grams,
                &h_bv,
                x,
                ix,
                part,
                weights,
                i,
                (&mut shared, &mut gz),
                (&mut nii, &mut niz, &mut gi),
            );
            own.push((i, (nii, niz, gi)));
            (shared, gz, own)
        };
        let per_thread = ix.q.div_ceil(rayon::current_num_threads().max(1));
        let empty = || {
            let shared = (0..ix.p).map(|_| Shared::zeros(2 * n)).collect();
            (shared, vec![0.0; nz], Vec::new())
        };
        let (shared, gz, mut own) = (0..ix.q)
            .into_par_iter()
            .with_min_len(per_thread)
            .fold(empty, add_output)
            .reduce(empty, |(mut a, mut ga, mut oa), (b, gb, ob)| {
                for (a, b) in a.iter_mut().zip(&b) {
                    a.add(b);
                }
                for (x, y) in ga.iter_mut().zip(&gb) {
                    *x += y;
                }
                oa.extend(ob);
                (a, ga, oa)
            });
        let mut nzz = Mat::<f64>::zeros(nz, nz);
        for (j, sums) in shared.iter().enumerate() {
            sums.place(ix, part, j, &mut nzz);
        }
        add_pole_block(&grams, x, ix, part, weights, &mut nzz);
        // `add_poles` wrote the poles' coupling with the participations below the
        // diagonal only (the poles are the first of `z`).
        let m2 = 2 * n;
        debug_assert!(part.pole_slots(n).into_iter().eq(0..m2));
        for c in m2..nz {
            for k in 0..m2 {
                nzz[(k, c)] = nzz[(c, k)];
            }
        }
        own.sort_unstable_by_key(|(i, _)| *i);
        let mut niz = Mat::<f64>::zeros(part.local(), nz);
        let mut gi = vec![0.0; part.local()];
        let mut nii = Vec::with_capacity(ix.q);
        for ((i, (block, coupling, g)), &at) in own.into_iter().zip(&part.offsets) {
            debug_assert_eq!(at, part.offsets[i]);
            niz.as_mut()
                .subrows_mut(at, coupling.nrows())
                .copy_from(&coupling);
            gi[at..at + g.len()].copy_from_slice(&g);
            nii.push(block);
        }
        let curvature = if second {
            (0..ix.q)
                .into_par_iter()
                .map(|i| curvature_entries(&grams, x, ix, weights, i))
                .collect()
        } else {
            Vec::new()
        };
        Blocks {
            part,
            nzz,
            gz,
            nii,
            niz,
            gi,
            curvature,
        }
    }

    /// Newton's normal equations `N − Q`, the cost's own Hessian, when the curvature
    /// was formed: `Q` touches `N_zz` (a pole with a pole or a participation) and
    /// `N_iz` (a shape with a pole or a participation), not `N_ii`.
    fn newton(&self) -> Option<Blocks<'a>> {
        if !self.has_curvature() {
            return None;
        }
        let part = self.part;
        let mut nzz = self.nzz.clone();
        let mut niz = self.niz.clone();
        for (i, entries) in self.curvature.iter().enumerate() {
            for &(f, g, value) in entries {
                match (part.slot[f], part.slot[g]) {
                    (Slot::Shared(a), Slot::Shared(b)) => {
                        nzz[(a, b)] -= value;
                        if a != b {
                            nzz[(b, a)] -= value;
                        }
                    }
                    (Slot::Local(k), Slot::Shared(c)) | (Slot::Shared(c), Slot::Local(k)) => {
                        niz[(part.offsets[i] + k, c)] -= value;
                    }
                    (Slot::Local(_), Slot::Local(_)) => {
                        unreachable!("no two shapes of an output have a second derivative")
                    }
                }
            }
        }
        Some(Blocks {
            part,
            nzz,
            gz: self.gz.clone(),
            nii: self.nii.clone(),
            niz,
            gi: self.gi.clone(),
            curvature: Vec::new(),
        })
    }

    /// Whether the residuals' curvature was formed (and not dropped).
    fn has_curvature(&self) -> bool {
        self.curvature.iter().any(|entries| !entries.is_empty())
    }

    /// `δᵀQδ` of the curvature held (0 without).
    fn curvature_form(&self, step: &[f64]) -> f64 {
        self.curvature
            .iter()
            .map(|entries| curvature_form(entries, step))
            .sum()
    }

    /// `δᵀg` and `δᵀNδ` for a full step `δ`.
    fn gradient_and_curvature(&self, step: &[f64]) -> (f64, f64) {
        let part = self.part;
        let dz = Mat::from_fn(part.z.len(), 1, |k, _| step[part.z[k]]);
        let mut dg: f64 = (0..part.z.len()).map(|k| dz[(k, 0)] * self.gz[k]).sum();
        let nzz_dz = &self.nzz * &dz;
        let niz_dz = &self.niz * &dz;
        let mut curvature: f64 = (0..part.z.len()).map(|k| dz[(k, 0)] * nzz_dz[(k, 0)]).sum();
        for ((b, nii), &at) in part.blocks.iter().zip(&self.nii).zip(&part.offsets) {
            for (row, &f) in b.iter().enumerate() {
                let d = step[f];
                dg += d * self.gi[at + row];
                // Both off-diagonal blocks, `N_iz` and `N_zi`.
                curvature += 2.0 * d * niz_dz[(at + row, 0)];
                curvature += d
                    * (0..b.len())
                        .map(|c| nii[(row, c)] * step[b[c]])
                        .sum::<f64>();
            }
        }
        (dg, curvature)
    }

    /// The dense `(N, g)`, for the rare fit where an output's block is singular.
    fn dense(&self) -> (Mat<f64>, Vec<f64>) {
        let part = self.part;
        let free = part.slot.len();
        let mut normal = Mat::<f64>::zeros(free, free);
        let mut gradient = vec![0.0; free];
        for (a, &fa) in part.z.iter().enumerate() {
            gradient[fa] = self.gz[a];
            for (b, &fb) in part.z.iter().enumerate() {
                normal[(fa, fb)] = self.nzz[(a, b)];
            }
        }
        for ((b, nii), &at) in part.blocks.iter().zip(&self.nii).zip(&part.offsets) {
            for (row, &f) in b.iter().enumerate() {
                gradient[f] = self.gi[at + row];
                for (col, &g) in b.iter().enumerate() {
                    normal[(f, g)] = nii[(row, col)];
                }
                for (c, &g) in part.z.iter().enumerate() {
                    normal[(f, g)] = self.niz[(at + row, c)];
                    normal[(g, f)] = self.niz[(at + row, c)];
                }
            }
        }
        (normal, gradient)
    }
}

/// The normal equations at the current point.
enum Normal<'a> {
    Dense(Mat<f64>, Vec<f64>),
    Blocks(Blocks<'a>),
}

impl<'a> Normal<'a> {
    /// By blocks when there is a partition, dense otherwise; the blocks with the
    /// residuals' curvature when `second`.
    #[allow(clippy::too_many_arguments)]
    fn new(
        problem: &Problem,
        x: &Parameters,
        ix: &Indices,
        part: Option<&'a Partition>,
        basis: &Basis,
        residual: &Mat<f64>,
        weights: &[f64],
        second: bool,
    ) -> Self {
        match part {
            Some(part) => Normal::Blocks(Blocks::new(
                problem, x, ix, part, basis, residual, weights, second,
            )),
            None => {
                let (normal, gradient) = dense_normal(problem, x, ix, basis, residual, weights);
                Normal::Dense(normal, gradient)
            }
        }
    }

    /// `δᵀg` and `δᵀNδ`.
    fn gradient_and_curvature(&self, step: &[f64]) -> (f64, f64) {
        match self {
            Normal::Blocks(b) => b.gradient_and_curvature(step),
            Normal::Dense(normal, gradient) => {
                let d = Mat::from_fn(step.len(), 1, |k, _| step[k]);
                let nd = normal * &d;
                let dg = step.iter().zip(gradient).map(|(a, b)| a * b).sum();
                (dg, (0..step.len()).map(|k| step[k] * nd[(k, 0)]).sum())
            }
        }
    }

    /// `(N + λ diag N) δ = g` solved densely (a reciprocal fit, or blocks that could not
    /// be reduced).
    fn dense_step(&self, lambda: f64) -> Option<Vec<f64>> {
        match self {
            Normal::Dense(normal, gradient) => damped_step(normal, gradient, lambda),
            Normal::Blocks(b) => {
                let (normal, gradient) = b.dense();
                damped_step(&normal, &gradient, lambda)
            }
        }
    }
}

/// The normal equations with every output's shapes and residual terms eliminated:
/// `S = N_zz − Σ_i N_zi N_ii⁻¹ N_iz` over the poles and participations `z`. The shapes
/// and residual terms of output `i` couple only with `z`, so `N_ii` is one small block
/// per output; `S` is formed once per accepted point (one GEMM over the stacked
/// `N_Iz`), and each trial `λ` costs one Cholesky factorisation of `S` (640 unknowns for
/// 8 × 8 and 40 modes, against 1344).
struct Reduced<'a> {
    part: &'a Partition,
    s: Mat<f64>,
    g: Vec<f64>,
    /// Stacked like `N_Iz`: `N_ii⁻¹ N_iz` and `N_ii⁻¹ g_i`.
    x: Mat<f64>,
    xg: Vec<f64>,
}

impl<'a> Reduced<'a> {
    fn new(blocks: &Blocks<'a>) -> Option<Self> {
        use rayon::prelude::*;
        let part = blocks.part;
        let nz = part.z.len();
        // Each output's `N_ii⁻¹ [N_iz, g_i]` on its own thread.
        let solved: Vec<Mat<f64>> = blocks
            .nii
            .par_iter()
            .zip(&part.offsets)
            .map(|(nii, &at)| -> Option<Mat<f64>> {
                let m = nii.nrows();
                let largest = (0..m).map(|k| nii[(k, k)]).fold(0.0, f64::max);
                let mut a = nii.clone();
                for k in 0..m {
                    a[(k, k)] += 1e-13 * largest;
                }
                let rhs = Mat::from_fn(m, nz + 1, |row, c| {
                    if c < nz {
                        blocks.niz[(at + row, c)]
                    } else {
                        blocks.gi[at + row]
                    }
                });
                let x = a.llt(faer::Side::Lower).ok()?.solve(&rhs);
                (0..m)
                    .all(|r| x.row(r).iter().all(|v| v.is_finite()))
                    .then_some(x)
            })
            .collect::<Option<_>>()?;
        let local = part.local();
        let mut x = Mat::<f64>::zeros(local, nz);
        let mut xg = vec![0.0; local];
        for (block, &at) in solved.iter().zip(&part.offsets) {
            let m = block.nrows();
            x.as_mut()
                .subrows_mut(at, m)
                .copy_from(block.as_ref().subcols(0, nz));
            for row in 0..m {
                xg[at + row] = block[(row, nz)];
            }
        }
        // S = N_zz − N_Izᵀ X, its lower triangle by one GEMM, then mirrored.
        let mut s = blocks.nzz.clone();
        faer::linalg::matmul::triangular::matmul(
            s.as_mut(),
            faer::linalg::matmul::triangular::BlockStructure::TriangularLower,
            faer::Accum::Add,
            blocks.niz.transpose(),
            faer::linalg::matmul::triangular::BlockStructure::Rectangular,
            x.as_ref(),
            faer::linalg::matmul::triangular::BlockStructure::Rectangular,
            -1.0,
            faer::get_global_parallelism(),
        );
        for c in 0..nz {
            for r in 0..c {
                s[(r, c)] = s[(c, r)];
            }
        }
        let correction = blocks.niz.transpose() * Mat::from_fn(local, 1, |k, _| xg[k]);
        let g = (0..nz).map(|k| blocks.gz[k] - correction[(k, 0)]).collect();
        Some(Reduced { part, s, g, x, xg })
    }

    /// The full step for `(S + λ diag S) δz = g'`, the eliminated part by
    /// back-substitution.
    fn step(&self, lambda: f64) -> Option<Vec<f64>> {
        let part = self.part;
        let dz = damped_step(&self.s, &self.g, lambda)?;
        let mut full = vec![0.0; part.slot.len()];
        for (k, &f) in part.z.iter().enumerate() {
            full[f] = dz[k];
        }
        let coupled = &self.x * Mat::from_fn(dz.len(), 1, |k, _| dz[k]);
        for (b, &at) in part.blocks.iter().zip(&part.offsets) {
            for (row, &f) in b.iter().enumerate() {
                full[f] = self.xg[at + row] - coupled[(at + row, 0)];
            }
        }
        full.iter().all(|v| v.is_finite()).then_some(full)
    }
}

/// `(N + λ diag N) δ = g`, or `None` when it is not solvable.
fn damped_step(normal: &Mat<f64>, gradient: &[f64], lambda: f64) -> Option<Vec<f64>> {
    let rhs = Mat::from_fn(gradient.len(), 1, |k, _| gradient[k]);
    let step = damped(normal, lambda)?
        .llt(faer::Side::Lower)
        .ok()?
        .solve(&rhs);
    finite_column(&step)
}

/// The factor that keeps the poles' part of `step` from `x` within each resonance's
/// width ([`limit_step`]): 1 when it already is.
fn step_factor(x: &Parameters, ix: &Indices, step: &[f64], log_damping: bool) -> f64 {
    let theta_raw: Vec<f64> = (0..x.theta.len())
        .map(|index| ix.reduced[index].map_or(0.0, |f| step[f]))
        .collect();
    let limited = limit_step(theta_raw.clone(), &x.theta, log_damping);
    theta_raw
        .iter()
        .zip(&limited)
        .filter(|(a, _)| **a != 0.0)
        .map(|(a, b)| b / a)
        .fold(1.0, f64::min)
}

/// The quadratic model's decrease of the cost for `factor · step` from the point whose
/// normal equations are `normal`: `2fδᵀg − f²δᵀ(N − Q)δ`, with the residuals'
/// curvature `Q` where it was formed (Newton's model), `2fδᵀg − f²δᵀNδ` otherwise.
fn model_decrease(normal: &Normal<'_>, step: &[f64], factor: f64) -> f64 {
    let (dg, dnd) = normal.gradient_and_curvature(step);
    let dqd = match normal {
        Normal::Blocks(blocks) => blocks.curvature_form(step),
        Normal::Dense(..) => 0.0,
    };
    2.0 * factor * dg - factor * factor * (dnd - dqd)
}

/// The parameters after `step` (shortened as below), and the factor it was shortened by.
fn apply(x: &Parameters, ix: &Indices, step: &[f64], log_damping: bool) -> (Parameters, f64) {
    // The poles' part of the step is kept within each resonance's width (as in the
    // free fit); the whole step is shortened by the same factor, so that the shapes
    // move with the poles they were computed for.
    let factor = step_factor(x, ix, step, log_damping);
    let raw = |index: usize| ix.reduced[index].map_or(0.0, |f| factor * step[f]);
    let mut next = x.clone();
    for (k, t) in next.theta.iter_mut().enumerate() {
        *t += raw(k);
    }
    normalise(&mut next.theta);
    let n = ix.n;
    for i in 0..ix.q {
        for r in 0..n {
            next.u[i * n + r] += Complex64::new(raw(ix.u(i, r, 0)), raw(ix.u(i, r, 1)));
        }
    }
    for j in 0..ix.p {
        for r in 0..n {
            next.v[j * n + r] += Complex64::new(raw(ix.v(j, r, 0)), raw(ix.v(j, r, 1)));
        }
    }
    for pair in 0..ix.q * ix.p {
        for e in 0..ix.n_res {
            next.k[pair * ix.n_res + e] += raw(ix.k(pair, e));
        }
    }
    (next, factor)
}

/// The shapes and residual terms that fit best for the poles and participations of `x`
/// (a linear least-squares problem per output), in place; a reciprocal model has no
/// linear part apart from its residual terms and is left as it is.
///
/// For fixed poles every pair's cost is `w²(cᵀHc − 2cᵀΦᵀy)` plus a constant
/// (`H = ΦᵀΦ`, `y` the pair's data), and output `i`'s coefficients are linear in
/// `(u_i, K_i·)`: one normal system of `2N + p·n_res` unknowns per output, from `H` and
/// `ΦᵀY` alone (two GEMMs; no factorisation of `Φ`, whose own conditioning the normal
/// system squares anyway).
fn solve_linear(
    problem: &Problem,
    x: &mut Parameters,
    ix: &Indices,
    basis: &Basis,
    y: &Mat<f64>,
    weights: &[f64],
) -> bool {
    if problem.reciprocal {
        return true;
    }
    let (n, q, p, n_res) = (ix.n, ix.q, ix.p, ix.n_res);
    let h = &basis.h;
    // `Φᵀy` of every pair.
    let phi_y = basis.phi.transpose() * y;
    let size = 2 * n + p * n_res;
    // Each output's shapes and residual terms are its own system: solved side by side.
    let solve_output = |i: usize| -> Option<Mat<f64>> {
        let mut a = Mat::<f64>::zeros(size, size);
        let mut b = Mat::<f64>::zeros(size, 1);
        for j in 0..p {
            let pair = i * p + j;
            let w2 = weights[pair] * weights[pair];
            // The columns of M_r: (Re u, Im u) → (Re R, Im R) for R = u v.
            let m = |r: usize| {
                let v = x.v[j * n + r];
                [[v.re, v.im], [-v.im, v.re]]
            };
            for ra in 0..n {
                for (sa, ca) in m(ra).iter().enumerate() {
                    let row = 2 * ra + sa;
                    b[(row, 0)] += w2
                        * (0..2)
                            .map(|t| ca[t] * phi_y[(2 * ra + t, pair)])
                            .sum::<f64>();
                    for rb in 0..n {
                        for (sb, cb) in m(rb).iter().enumerate() {
                            let mut v = 0.0;
                            for t in 0..2 {
                                for t2 in 0..2 {
                                    v += ca[t] * h[(2 * ra + t, 2 * rb + t2)] * cb[t2];
                                }
                            }
                            a[(row, 2 * rb + sb)] += w2 * v;
                        }
                    }
                    for e in 0..n_res {
                        let col = 2 * n + j * n_res + e;
                        let v: f64 = (0..2).map(|t| ca[t] * h[(2 * ra + t, 2 * n + e)]).sum();
                        a[(row, col)] += w2 * v;
                        a[(col, row)] += w2 * v;
                    }
                }
            }
            for e in 0..n_res {
                let row = 2 * n + j * n_res + e;
                b[(row, 0)] += w2 * phi_y[(2 * n + e, pair)];
                for e2 in 0..n_res {
                    a[(row, 2 * n + j * n_res + e2)] += w2 * h[(2 * n + e, 2 * n + e2)];
                }
            }
        }
        let solution = a.llt(faer::Side::Lower).ok()?.solve(&b);
        (0..size)
            .all(|k| solution[(k, 0)].is_finite())
            .then_some(solution)
    };
    use rayon::prelude::*;
    let Some(solutions) = (0..q)
        .into_par_iter()
        .map(solve_output)
        .collect::<Option<Vec<_>>>()
    else {
        return false;
    };
    for (i, solution) in solutions.iter().enumerate() {
        for r in 0..n {
            x.u[i * n + r] = Complex64::new(solution[(2 * r, 0)], solution[(2 * r + 1, 0)]);
        }
        for j in 0..p {
            for e in 0..n_res {
                x.k[(i * p + j) * n_res + e] = solution[(2 * n + j * n_res + e, 0)];
            }
        }
    }
    true
}

/// The start: the free fit's poles and residual terms, each residue's leading singular
/// pair (`ψ = u √(uᴴv/uᴴu)` when reciprocal). A mode with a `warm` residue (an earlier
/// rank-one fit's) takes its pair from that one instead.
fn start(
    problem: &Problem,
    theta: &[f64],
    free: &Mat<f64>,
    warm: &[Option<&[Complex64]>],
) -> Result<Parameters> {
    let (q, p) = (problem.outputs, problem.inputs);
    let n = theta.len() / 2;
    let n_res = problem.layout.residuals.len();
    let mut u = vec![Complex64::new(0.0, 0.0); q * n];
    let mut v = vec![Complex64::new(0.0, 0.0); p * n];
    for r in 0..n {
        let residue = match warm.get(r).copied().flatten().filter(|w| w.len() == q * p) {
            Some(w) => Mat::from_fn(q, p, |i, j| {
                faer::c64::new(w[i * p + j].re, w[i * p + j].im)
            }),
            None => Mat::from_fn(q, p, |i, j| {
                faer::c64::new(free[(2 * r, i * p + j)], free[(2 * r + 1, i * p + j)])
            }),
        };
        let svd = residue
            .thin_svd()
            .map_err(|e| EraError::Numerical(format!("SVD of a residue: {e:?}")))?;
        let root = svd.S()[0].re.sqrt();
        for i in 0..q {
            let z = svd.U()[(i, 0)] * root;
            u[i * n + r] = Complex64::new(z.re, z.im);
        }
        for j in 0..p {
            let z = svd.V()[(j, 0)].conj() * root;
            v[j * n + r] = Complex64::new(z.re, z.im);
        }
        if problem.reciprocal {
            let uu: f64 = (0..q).map(|i| u[i * n + r].norm_sqr()).sum();
            let uv: Complex64 = (0..q).map(|i| u[i * n + r].conj() * v[i * n + r]).sum();
            let scale = if uu > 0.0 {
                (uv / uu).sqrt()
            } else {
                Complex64::new(0.0, 0.0)
            };
            for i in 0..q {
                u[i * n + r] *= scale;
                v[i * n + r] = u[i * n + r];
            }
        }
    }
    let k = (0..q * p)
        .flat_map(|pair| (0..n_res).map(move |e| (pair, e)))
        .map(|(pair, e)| free[(2 * n + e, pair)])
        .collect();
    Ok(Parameters {
        theta: theta.to_vec(),
        u,
        v,
        k,
    })
}

/// Fits the rank-one model from the poles `theta` (the free fit's, or a warm mode's
/// earlier rank-one pole) and the residues of the free fit's coefficients `free` (or a
/// warm mode's `warm` residue), or `None` when the problem does not allow it (weights
/// varying by line, real modes).
///
/// # Errors
/// [`EraError::Numerical`] when an SVD of a start residue fails.
pub(crate) fn fit(
    problem: &Problem,
    theta: &[f64],
    free: &Mat<f64>,
    warm: &[Option<&[Complex64]>],
    max_iterations: usize,
    tolerance: f64,
) -> Result<Option<Joint>> {
    let Some(weights) = problem
        .pair_weights
        .as_ref()
        .filter(|_| problem.rank_one_follows())
    else {
        return Ok(None);
    };
    let (q, p) = (problem.outputs, problem.inputs);
    let n = theta.len() / 2;
    let n_res = problem.layout.residuals.len();
    let x = start(problem, theta, free, warm)?;
    // Hold each participation's largest entry (the scale between u and v is free).
    let fixed: Vec<usize> = (0..n)
        .map(|r| {
            (0..p)
                .max_by(|&a, &b| x.v[a * n + r].norm().total_cmp(&x.v[b * n + r].norm()))
                .unwrap_or(0)
        })
        .collect();
    let ix = Indices::new(n, q, p, n_res, problem.reciprocal, &fixed);
    debug_assert_eq!(ix.free, parameters(problem, n));
    if ix.free > MAX_PARAMETERS {
        return Ok(None);
    }
    // A reciprocal fit's shapes are also its participations: no output owns a
    // parameter, and its normal equations stay dense (756 unknowns on 8 × 8).
    let partition = (!problem.reciprocal).then(|| Partition::new(&ix));
    let stage = Stage {
        problem,
        ix: &ix,
        part: partition.as_ref(),
        y: stacked_data(problem),
        weights,
        dof: problem.observations.checked_sub(ix.free).filter(|&d| d > 0),
        newton: NEWTON,
        turned_away: std::cell::Cell::new(0),
    };
    let mut point = stage.first_point(x);
    let (iterations, converged) = stage.descend(&mut point, max_iterations, tolerance)?;
    let noise_variance = stage.dof.map_or(f64::NAN, |d| point.cost / d as f64);
    let covariance = pole_covariance(&point, n, noise_variance);
    Ok(Some(Joint {
        coefficients: coefficients(&point.x, &ix, point.basis.phi.ncols()),
        theta: point.x.theta,
        cost: point.cost,
        covariance,
        noise_variance,
        iterations,
        converged,
    }))
}

/// What stays fixed during the rank-one fit: the problem, the parameters' layout and
/// partition, the stacked data and the pairs' weights.
struct Stage<'a> {
    problem: &'a Problem,
    ix: &'a Indices,
    part: Option<&'a Partition>,
    y: Mat<f64>,
    weights: &'a [f64],
    /// Observations less free parameters, when positive.
    dof: Option<usize>,
    /// Whether a descent that creeps turns to Newton's steps, with the residuals'
    /// curvature ([`curvature_entries`], [`CREEP_RHO`]); Gauss–Newton's otherwise, and
    /// where the undamped reduced `N − Q` is not positive definite. Fits by blocks only
    /// (a reciprocal fit's dense equations take Gauss–Newton's steps).
    newton: bool,
    /// Points where Newton's equations were turned away because the cost is not convex
    /// there (a count for the tests).
    turned_away: std::cell::Cell<usize>,
}

/// A point of the rank-one fit with its basis, cost, residual and normal equations.
struct Point<'a> {
    x: Parameters,
    basis: Basis,
    cost: f64,
    residual: Mat<f64>,
    normal: Normal<'a>,
    /// The shapes eliminated from the equations the steps solve (Newton's where
    /// `normal` holds the curvature), once computed.
    reduced: Option<Reduced<'a>>,
}

impl<'a> Stage<'a> {
    /// The start point: `x` with the best shapes for its participations.
    fn first_point(&self, mut x: Parameters) -> Point<'a> {
        let basis = basis_at(self.problem, &x.theta);
        let mut solved = x.clone();
        if solve_linear(
            self.problem,
            &mut solved,
            self.ix,
            &basis,
            &self.y,
            self.weights,
        ) {
            x = solved;
        }
        let (cost, residual) = cost(&x, self.ix, &basis.phi, &self.y, self.weights);
        let normal = self.normal(&x, &basis, &residual, false);
        Point {
            x,
            basis,
            cost,
            residual,
            normal,
            reduced: None,
        }
    }

    /// The normal equations at `x`, with the residuals' curvature when `second`.
    fn normal(
        &self,
        x: &Parameters,
        basis: &Basis,
        residual: &Mat<f64>,
        second: bool,
    ) -> Normal<'a> {
        Normal::new(
            self.problem,
            x,
            self.ix,
            self.part,
            basis,
            residual,
            self.weights,
            second,
        )
    }

    /// Levenberg–Marquardt from `point` ([`Nielsen`]'s damping); the iterations taken and
    /// whether it converged.
    fn descend(
        &self,
        point: &mut Point<'a>,
        max_iterations: usize,
        tolerance: f64,
    ) -> Result<(usize, bool)> {
        let weights = self.weights;
        let data_norm2: f64 = (0..self.y.ncols())
            .map(|pair| weights[pair] * weights[pair] * self.y.col(pair).squared_norm_l2())
            .sum();
        let mut problem = Descent::new(self, point, tolerance, data_norm2);
        descend(&mut problem, &mut Nielsen::new(), max_iterations)
    }

    /// The point `step` leads to from `point`, with the shapes that fit its poles and
    /// participations best, its basis, cost and residual (`None` when not finite); the
    /// factor the step was shortened by; the quadratic model's predicted decrease
    /// ([`model_decrease`]).
    #[allow(clippy::type_complexity)]
    fn trial(
        &self,
        point: &Point<'a>,
        step: &[f64],
    ) -> (Option<(Parameters, Basis, f64, Mat<f64>)>, f64, f64) {
        let (mut trial, factor) =
            apply(&point.x, self.ix, step, self.problem.parameters.log_damping);
        let predicted = model_decrease(&point.normal, step, factor);
        // The step's poles and participations, with the shapes that fit them best
        // (variable projection: the bilinear product makes the linearised shape step
        // poor far from the optimum).
        let trial_basis = basis_at(self.problem, &trial.theta);
        let mut solved = trial.clone();
        if solve_linear(
            self.problem,
            &mut solved,
            self.ix,
            &trial_basis,
            &self.y,
            self.weights,
        ) {
            trial = solved;
        }
        let finite = trial.theta.iter().all(|t| t.is_finite())
            && trial
                .u
                .iter()
                .chain(&trial.v)
                .all(|z| z.re.is_finite() && z.im.is_finite());
        let evaluated = finite.then(|| {
            let (c, r) = cost(&trial, self.ix, &trial_basis.phi, &self.y, self.weights);
            (trial, trial_basis, c, r)
        });
        (evaluated, factor, predicted)
    }
}

/// The rank-one fit as [`descend`] drives it.
struct Descent<'s, 'a> {
    stage: &'s Stage<'a>,
    point: &'s mut Point<'a>,
    /// Relative decrease that ends the fit.
    tolerance: f64,
    /// The weighted data's squared norm.
    data_norm2: f64,
    /// Whether a small, well-predicted step is followed by a look at the next one
    /// ([`Descent::nothing_left`]); always, but for the test that compares.
    look_ahead: bool,
    /// Whether the normal equations hold the residuals' curvature (Newton's steps):
    /// from the [`CREEP_STEPS`]-th step in a row whose gain ratio passed [`CREEP_RHO`]
    /// on, until a point where the undamped reduced `N − Q` is not positive definite.
    curvature: bool,
    /// Accepted Gauss–Newton steps in a row whose gain ratio passed [`CREEP_RHO`].
    creeping: usize,
}

impl LeastSquares for Descent<'_, '_> {
    fn exact(&self) -> bool {
        self.point.cost <= EXACT_FIT * self.data_norm2
    }

    fn step(&mut self, lambda: f64) -> Option<Vec<f64>> {
        let point = &mut *self.point;
        let Normal::Blocks(blocks) = &mut point.normal else {
            return point.normal.dense_step(lambda);
        };
        // Where this point falls back from Newton's equations, its equations and its
        // model of the step are Gauss–Newton's, as are the next points', until the next
        // creep.
        let mut to_gauss_newton = |blocks: &mut Blocks| {
            blocks.curvature.clear();
            self.curvature = false;
            self.creeping = 0;
        };
        if point.reduced.is_none() {
            // Newton's equations only where the cost is convex (the undamped reduced
            // `N − Q` positive definite): elsewhere Newton's step heads for a saddle as
            // readily as for a minimum, and Gauss–Newton's does not.
            if let Some(newton) = blocks.newton() {
                point.reduced = Reduced::new(&newton).filter(|r| r.step(0.0).is_some());
                if point.reduced.is_none() {
                    let away = &self.stage.turned_away;
                    away.set(away.get() + 1);
                    to_gauss_newton(blocks);
                }
            }
            if point.reduced.is_none() {
                point.reduced = Reduced::new(blocks);
            }
        }
        let mut step = point.reduced.as_ref().and_then(|r| r.step(lambda));
        if step.is_none() && blocks.has_curvature() {
            // Newton's damped equations failed where the undamped ones did not.
            to_gauss_newton(blocks);
            point.reduced = Reduced::new(blocks);
            step = point.reduced.as_ref().and_then(|r| r.step(lambda));
        }
        if point.reduced.is_none() {
            // An output's block is singular: the dense (Gauss–Newton) equations.
            return point.normal.dense_step(lambda);
        }
        step
    }

    fn attempt(&mut self, step: Vec<f64>, _iteration: usize) -> Result<Trial> {
        let (trial, factor, predicted) = self.stage.trial(self.point, &step);
        let point = &mut *self.point;
        match trial {
            Some((next, trial_basis, next_cost, next_residual)) if next_cost < point.cost => {
                let decrease = point.cost - next_cost;
                point.x = next;
                point.cost = next_cost;
                point.residual = next_residual;
                point.basis = trial_basis;
                let rho = if predicted > 0.0 {
                    decrease / predicted
                } else {
                    1.0
                };
                // Gauss–Newton steps that each took much more off the cost than their
                // model predicted are a creep ([`CREEP_RHO`]): Newton's steps from here.
                if !self.curvature {
                    self.creeping = if factor == 1.0 && rho > CREEP_RHO {
                        self.creeping + 1
                    } else {
                        0
                    };
                    self.curvature = self.stage.newton && self.creeping >= CREEP_STEPS;
                }
                point.normal =
                    self.stage
                        .normal(&point.x, &point.basis, &point.residual, self.curvature);
                point.reduced = None;
                let noise_unit = self.stage.dof.map_or(0.0, |d| point.cost / d as f64);
                // A step shortened by one mode's limit says nothing about convergence.
                let mut converged = factor == 1.0
                    && (decrease <= self.tolerance * (point.cost + decrease)
                        || decrease <= STATISTICAL_STOP * noise_unit);
                if !converged
                    && self.look_ahead
                    && factor == 1.0
                    && predicted > 0.0
                    && decrease <= FINAL_STEP_CHECK * noise_unit
                    && (rho - 1.0).abs() <= FINAL_STEP_RHO
                {
                    converged = self.nothing_left(noise_unit);
                }
                Ok(Trial::Lower {
                    rho,
                    restart: false,
                    converged,
                })
            }
            _ => Ok(Trial::Higher),
        }
    }
}

/// Whether a creeping rank-one descent turns to Newton's steps ([`Stage::newton`]).
const NEWTON: bool = true;

/// The gain ratio past which an accepted Gauss–Newton step marks a creep: it took this
/// many times the decrease its model predicted. Where the residual keeps a structure
/// (a close pair, a mode not yet in the fit) `N` overstates the cost's curvature
/// along the weak directions, each step is too short, the next finds the same
/// direction again, and the gain ratios climb towards 2 while the decreases shrink by
/// a constant ratio; Newton's model `N − Q` has the curvature right.
const CREEP_RHO: f64 = 1.2;

/// Accepted steps in a row past [`CREEP_RHO`] that mark a creep (one alone can be a
/// long step's luck).
const CREEP_STEPS: usize = 2;

/// An accepted step that took less than this many noise variances off the cost, as its
/// model predicted (within [`FINAL_STEP_RHO`]), is followed by a look at the
/// next full step's predicted decrease ([`Descent::nothing_left`]).
const FINAL_STEP_CHECK: f64 = 1.0;
/// How far the gain ratio of such a step may be from 1.
const FINAL_STEP_RHO: f64 = 0.1;

impl<'s, 'a> Descent<'s, 'a> {
    /// A descent from `point` with Gauss–Newton's equations, that looks ahead.
    fn new(
        stage: &'s Stage<'a>,
        point: &'s mut Point<'a>,
        tolerance: f64,
        data_norm2: f64,
    ) -> Self {
        Descent {
            stage,
            point,
            tolerance,
            data_norm2,
            look_ahead: true,
            curvature: false,
            creeping: 0,
        }
    }

    /// Whether the undamped step from the current point (Gauss–Newton's, or Newton's
    /// where the fit took to them; within the poles' limit) is predicted, by the same
    /// equations' model, to take less than [`STATISTICAL_STOP`] noise variances off the
    /// cost: the fit has then converged as surely as after taking that step, which it
    /// skips (its trial, its normal equations and their elimination). In a fit by blocks
    /// the elimination formed here serves the next step or, when it is Gauss–Newton's,
    /// the covariance.
    fn nothing_left(&mut self, noise_unit: f64) -> bool {
        let Some(next) = self.step(0.0) else {
            return false;
        };
        let log_damping = self.stage.problem.parameters.log_damping;
        if step_factor(&self.point.x, self.stage.ix, &next, log_damping) < 1.0 {
            return false;
        }
        let predicted = model_decrease(&self.point.normal, &next, 1.0);
        predicted.is_finite() && predicted <= STATISTICAL_STOP * noise_unit
    }
}

/// `σ̂² (N⁻¹)` over the pole parameters at `point`, when finite. The pole block of `N⁻¹`:
/// with the shapes eliminated it is the pole block of `S⁻¹` (the poles come first among
/// `z`), so only `S` is factorised.
fn pole_covariance(point: &Point<'_>, n: usize, noise_variance: f64) -> Option<Mat<f64>> {
    let covariance = noise_variance.is_finite().then(|| {
        let poles_block = |m: &Mat<f64>| {
            let unit = Mat::from_fn(m.nrows(), 2 * n, |a, b| f64::from(u8::from(a == b)));
            let x = match m.llt(faer::Side::Lower) {
                Ok(llt) => llt.solve(&unit),
                Err(_) => m.partial_piv_lu().solve(&unit),
            };
            Mat::from_fn(2 * n, 2 * n, |a, b| noise_variance * x[(a, b)])
        };
        let fresh;
        // Gauss–Newton's elimination: the covariance is that of `N = JᵀWJ`.
        let newton = matches!(&point.normal, Normal::Blocks(b) if b.has_curvature());
        let kept = if newton { None } else { point.reduced.as_ref() };
        let reduced = match kept {
            Some(r) => Some(r),
            None => {
                fresh = match &point.normal {
                    Normal::Blocks(blocks) => Reduced::new(blocks),
                    Normal::Dense(..) => None,
                };
                fresh.as_ref()
            }
        };
        match (reduced, &point.normal) {
            (Some(r), _) => poles_block(&r.s),
            (None, Normal::Dense(n, _)) => poles_block(n),
            (None, Normal::Blocks(b)) => poles_block(&b.dense().0),
        }
    });
    covariance.filter(|c| (0..c.nrows()).all(|a| (0..c.ncols()).all(|b| c[(a, b)].is_finite())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::refine::{RefineOptions, Residuals};
    use crate::sim::{add_noise, ModalSpec, ModalStructure};
    use crate::Quantity;
    use era_testkit::{assert_matches_naive, Scale};

    /// A noisy `q × p` set with 5 modes (`quantity` and `residuals` set how many
    /// residual terms), at parameters off the optimum (so the residual and every block
    /// are far from zero); participation `r % p` is held.
    fn case(
        (q, p): (usize, usize),
        quantity: Quantity,
        residuals: Residuals,
        reciprocal: bool,
    ) -> (Problem, Parameters, Indices, Basis, Mat<f64>, Vec<f64>) {
        let spec = ModalSpec {
            fmin_hz: 2.0,
            fmax_hz: 9.0,
            collocated: reciprocal,
            ..ModalSpec::new(q, p, 5)
        };
        let s = ModalStructure::random(&spec).unwrap();
        let frf = add_noise(&s.frf(301, 0.025, quantity).unwrap(), 0.05, 3).unwrap();
        let options = RefineOptions {
            residuals,
            reciprocal,
            weighting: crate::refine::Weighting::Uniform,
            ..RefineOptions::default()
        };
        let problem = Problem::new(&frf, &options).unwrap();
        let poles: Vec<Complex64> = s
            .poles()
            .iter()
            .map(|s| Complex64::new(1.1 * 1.002 * s.re, 1.002 * s.im))
            .collect();
        let theta = problem.parameters.theta(&poles);
        let n = poles.len();
        let wave =
            |k: usize, a: f64| Complex64::new((a * k as f64).sin(), (1.7 * a * k as f64).cos());
        let u: Vec<Complex64> = (0..q * n).map(|k| wave(k + 1, 0.9)).collect();
        let v: Vec<Complex64> = if reciprocal {
            u.clone()
        } else {
            (0..p * n).map(|k| wave(k + 1, 1.3)).collect()
        };
        let n_res = problem.layout.residuals.len();
        let x = Parameters {
            theta,
            u,
            v,
            k: (0..q * p * n_res).map(|k| 0.01 * k as f64).collect(),
        };
        let fixed: Vec<usize> = (0..n).map(|r| r % p).collect();
        let ix = Indices::new(n, q, p, n_res, reciprocal, &fixed);
        // The count the free fit decides its tolerance by.
        assert_eq!(parameters(&problem, n), ix.free);
        let basis = basis_at(&problem, &x.theta);
        let y = stacked_data(&problem);
        let weights: Vec<f64> = (0..q * p).map(|k| 1.0 + 0.1 * k as f64).collect();
        let (_, residual) = cost(&x, &ix, &basis.phi, &y, &weights);
        (problem, x, ix, basis, residual, weights)
    }

    #[test]
    fn blocks_hold_the_dense_normal_equations_and_the_same_step() {
        use Quantity::{Acceleration, Displacement, Velocity};
        // No residual term, one (acceleration: both are one constant), two; one output,
        // one input, both.
        for (shape, quantity, residuals) in [
            ((3, 4), Acceleration, Residuals::Upper),
            ((3, 4), Velocity, Residuals::None),
            ((2, 3), Velocity, Residuals::Both),
            ((1, 3), Displacement, Residuals::Both),
            ((4, 1), Acceleration, Residuals::Both),
            ((1, 1), Velocity, Residuals::Lower),
        ] {
            blocks_agree(case(shape, quantity, residuals, false));
        }
    }

    #[test]
    fn a_warm_mode_starts_from_its_own_residue_and_the_others_from_the_free_ones() {
        for reciprocal in [false, true] {
            let (problem, x, ix, ..) =
                case((3, 3), Quantity::Velocity, Residuals::Both, reciprocal);
            let (n, q, p) = (ix.n, ix.q, ix.p);
            let n_res = ix.n_res;
            // Free coefficients: mode r's residue a fixed non-rank-one matrix.
            let free = Mat::from_fn(2 * n + n_res, q * p, |row, pair| {
                (0.3 + row as f64).sin() * (1.1 + pair as f64).cos()
            });
            // Mode 1 warm: the rank-one (and, when reciprocal, symmetric) residue u vᵀ.
            let warm_residue: Vec<Complex64> = (0..q * p)
                .map(|pair| x.u[(pair / p) * n + 1] * x.v[(pair % p) * n + 1])
                .collect();
            let mut warm = vec![None; n];
            warm[1] = Some(warm_residue.as_slice());
            let started = start(&problem, &x.theta, &free, &warm).unwrap();
            let product = |y: &Parameters, r: usize, pair: usize| {
                y.u[(pair / p) * n + r] * y.v[(pair % p) * n + r]
            };
            for (pair, w) in warm_residue.iter().enumerate() {
                let d = product(&started, 1, pair) - w;
                assert!(d.norm() <= 1e-12 * w.norm().max(1.0), "{reciprocal} {pair}");
            }
            // Every other mode: the leading singular pair of its free residue, as with
            // no warm mode at all.
            let cold = start(&problem, &x.theta, &free, &vec![None; n]).unwrap();
            for r in (0..n).filter(|&r| r != 1) {
                for pair in 0..q * p {
                    let d = product(&started, r, pair) - product(&cold, r, pair);
                    assert!(d.norm() <= 1e-12, "{reciprocal} mode {r} pair {pair}");
                }
            }
            // And the warm residue's product is not the free one's.
            let free_one = Complex64::new(free[(2, 0)], free[(3, 0)]);
            assert!(
                (product(&cold, 1, 0) - product(&started, 1, 0)).norm() > 1e-3 * free_one.norm()
            );
        }
    }

    /// The stage of a fit by blocks, with its degrees of freedom.
    fn stage_of<'a>(
        problem: &'a Problem,
        ix: &'a Indices,
        part: &'a Partition,
        weights: &'a [f64],
        newton: bool,
    ) -> Stage<'a> {
        Stage {
            problem,
            ix,
            part: Some(part),
            y: stacked_data(problem),
            weights,
            dof: Some(problem.observations - ix.free),
            newton,
            turned_away: std::cell::Cell::new(0),
        }
    }

    /// Runs `test` on the stage of `case((3, 4), …)` by blocks, with its start and its
    /// degrees of freedom.
    fn on_stage(test: impl for<'a> FnOnce(&Stage<'a>, Parameters, usize)) {
        let (problem, x, ix, .., weights) =
            case((3, 4), Quantity::Acceleration, Residuals::Upper, false);
        let part = Partition::new(&ix);
        let dof = problem.observations - ix.free;
        let stage = stage_of(&problem, &ix, &part, &weights, NEWTON);
        test(&stage, x, dof);
    }

    #[test]
    fn a_fit_stopped_before_its_last_step_has_nothing_statistical_left() {
        on_stage(|stage, x, dof| {
            fn look<'a>(stage: &Stage<'a>, point: &mut Point<'a>, dof: usize) -> bool {
                let noise_unit = point.cost / dof as f64;
                Descent::new(stage, point, 0.0, 1.0).nothing_left(noise_unit)
            }
            // Off the optimum the next step has much to take.
            let mut point = stage.first_point(x);
            assert!(!look(stage, &mut point, dof));
            let (_, converged) = stage.descend(&mut point, 200, 0.0).unwrap();
            assert!(converged);
            // Where the fit stopped, the full Gauss–Newton step, taken, lowers the cost by
            // less than the statistical stop; and the look says so.
            let noise_unit = point.cost / dof as f64;
            let step = Descent::new(stage, &mut point, 0.0, 1.0).step(0.0).unwrap();
            let (trial, factor, _) = stage.trial(&point, &step);
            assert_eq!(factor, 1.0);
            let after = trial.unwrap().2;
            assert!(
                point.cost - after <= STATISTICAL_STOP * noise_unit,
                "{} noise units left",
                (point.cost - after) / noise_unit
            );
            assert!(look(stage, &mut point, dof));
        });
    }

    #[test]
    fn the_look_ahead_saves_the_last_step_and_moves_the_poles_by_a_sliver_of_their_spread() {
        on_stage(|stage, x, dof| {
            fn run<'a>(stage: &Stage<'a>, x: &Parameters, look_ahead: bool) -> (Point<'a>, usize) {
                let mut point = stage.first_point(x.clone());
                let mut descent = Descent {
                    look_ahead,
                    ..Descent::new(stage, &mut point, 0.0, 1.0)
                };
                let (iterations, converged) =
                    descend(&mut descent, &mut Nielsen::new(), 200).unwrap();
                assert!(converged, "look ahead {look_ahead}");
                (point, iterations)
            }
            let (ahead, fewer) = run(stage, &x, true);
            let (full, more) = run(stage, &x, false);
            assert!(fewer < more, "{fewer} against {more} iterations");
            // The elimination the look formed is kept for the covariance.
            assert!(ahead.reduced.is_some());
            let covariance = pole_covariance(&full, stage.ix.n, full.cost / dof as f64).unwrap();
            for (k, (a, b)) in ahead.x.theta.iter().zip(&full.x.theta).enumerate() {
                let spread = covariance[(k, k)].sqrt();
                assert!(
                    (a - b).abs() <= 0.02 * spread,
                    "pole parameter {k}: {a} against {b}, σ {spread}"
                );
            }
        });
    }

    /// A 3 × 4 set with 3 modes in 4–6 Hz and 5 % noise, fitted with the second mode
    /// left out of the start: the residual keeps a mode's structure. Returns the
    /// iterations, whether converged, and the cost of a descent from there, the noise
    /// variance and the points where Newton's equations were turned away: with
    /// Gauss–Newton's steps only, and with Newton's where it creeps.
    fn descend_without_a_mode(seed: u64) -> [(usize, bool, f64, f64, usize); 2] {
        let spec = ModalSpec {
            fmin_hz: 4.0,
            fmax_hz: 6.0,
            seed,
            ..ModalSpec::new(3, 4, 3)
        };
        let s = ModalStructure::random(&spec).unwrap();
        let frf = add_noise(
            &s.frf(301, 0.025, Quantity::Acceleration).unwrap(),
            0.05,
            seed,
        )
        .unwrap();
        let options = RefineOptions {
            residuals: Residuals::Upper,
            weighting: crate::refine::Weighting::Uniform,
            ..RefineOptions::default()
        };
        let problem = Problem::new(&frf, &options).unwrap();
        let poles: Vec<Complex64> = [0, 2].iter().map(|&k| s.poles()[k]).collect();
        let (n, q, p) = (poles.len(), 3, 4);
        let wave =
            |k: usize, a: f64| Complex64::new((a * k as f64).sin(), (1.7 * a * k as f64).cos());
        let n_res = problem.layout.residuals.len();
        let x = Parameters {
            theta: problem.parameters.theta(&poles),
            u: (0..q * n).map(|k| wave(k + 1, 0.9)).collect(),
            v: (0..p * n).map(|k| wave(k + 1, 1.3)).collect(),
            k: vec![0.0; q * p * n_res],
        };
        let fixed: Vec<usize> = (0..n).map(|r| r % p).collect();
        let ix = Indices::new(n, q, p, n_res, false, &fixed);
        let part = Partition::new(&ix);
        let weights = vec![1.0; q * p];
        let dof = problem.observations - ix.free;
        [false, true].map(|newton| {
            let stage = stage_of(&problem, &ix, &part, &weights, newton);
            let mut point = stage.first_point(x.clone());
            let (iterations, converged) = stage.descend(&mut point, 500, 0.0).unwrap();
            (
                iterations,
                converged,
                point.cost,
                point.cost / dof as f64,
                stage.turned_away.get(),
            )
        })
    }

    #[test]
    fn a_creeping_descent_turns_to_newton_and_reaches_the_same_minimum_sooner() {
        // Gauss–Newton creeps towards this minimum (gain ratios near 2); Newton's steps
        // take it in about half the iterations.
        let [gn, newton] = descend_without_a_mode(18);
        assert!(gn.1 && newton.1);
        assert!(
            newton.0 + 4 <= gn.0,
            "{} against {} iterations",
            newton.0,
            gn.0
        );
        assert!(
            (newton.2 - gn.2).abs() <= 0.1 * gn.3,
            "costs {} and {} (noise variance {})",
            newton.2,
            gn.2,
            gn.3
        );
    }

    #[test]
    fn newton_steps_are_turned_away_where_the_cost_is_not_convex() {
        // Gauss–Newton crosses a plateau (its gain ratios past 1.2 there) to a minimum
        // of a third of the plateau's cost. On the plateau the cost is not convex, and
        // Newton's step would head for its saddle point: its equations are turned away
        // there, and the descent reaches the same minimum.
        let [gn, newton] = descend_without_a_mode(1);
        assert!(gn.1 && newton.1);
        assert_eq!(gn.4, 0);
        assert!(newton.4 >= 1, "Newton's equations were never turned away");
        assert!(
            newton.2 <= gn.2 + 0.1 * gn.3,
            "Newton's descent stopped at {} where Gauss–Newton's reached {}",
            newton.2,
            gn.2
        );
    }

    #[test]
    fn the_parameter_count_matches_the_reciprocal_layout() {
        for residuals in [Residuals::None, Residuals::Both] {
            case((3, 3), Quantity::Velocity, residuals, true);
        }
    }

    /// `N − Q` against the cost's Hessian by central differences of the gradient `g`
    /// (`cost = Σ w²‖r‖²`, `∇cost = −2g`, so the Hessian is `−2 ∂g/∂x`), densely and by
    /// blocks: the curvature entries hold every second derivative of the model.
    #[test]
    fn newton_equations_hold_the_hessian_of_the_cost() {
        for (shape, quantity, residuals) in [
            ((3, 4), Quantity::Acceleration, Residuals::Upper),
            ((2, 3), Quantity::Velocity, Residuals::Both),
        ] {
            let (problem, x, ix, basis, residual, weights) =
                case(shape, quantity, residuals, false);
            let (normal, _) = dense_normal(&problem, &x, &ix, &basis, &residual, &weights);
            let grams = Grams::new(&problem, &x, &basis, &residual, true);
            let mut newton = normal.clone();
            for i in 0..ix.q {
                for (f, g, value) in curvature_entries(&grams, &x, &ix, &weights, i) {
                    newton[(f, g)] -= value;
                    if f != g {
                        newton[(g, f)] -= value;
                    }
                }
            }
            let y = stacked_data(&problem);
            let gradient_at = |step: &[f64]| {
                let (moved, factor) = apply(&x, &ix, step, problem.parameters.log_damping);
                assert_eq!(factor, 1.0);
                let b = basis_at(&problem, &moved.theta);
                let (_, r) = cost(&moved, &ix, &b.phi, &y, &weights);
                dense_normal(&problem, &moved, &ix, &b, &r, &weights).1
            };
            let raw_value = |f: usize| {
                let raw = (0..ix.raw()).find(|&k| ix.reduced[k] == Some(f)).unwrap();
                let (n, q) = (ix.n, ix.q);
                if raw < 2 * n {
                    x.theta[raw]
                } else if raw < 2 * n + 2 * q * n {
                    let z = x.u[(raw - 2 * n) / 2];
                    if raw % 2 == 0 {
                        z.re
                    } else {
                        z.im
                    }
                } else {
                    1.0
                }
            };
            let mut hessian = Mat::<f64>::zeros(ix.free, ix.free);
            for f in 0..ix.free {
                let h = 1e-5 * raw_value(f).abs().max(1.0);
                let mut step = vec![0.0; ix.free];
                step[f] = h;
                let up = gradient_at(&step);
                step[f] = -h;
                let down = gradient_at(&step);
                for g in 0..ix.free {
                    hessian[(g, f)] = -(up[g] - down[g]) / (2.0 * h);
                }
            }
            let scale = (0..ix.free)
                .map(|k| newton[(k, k)].abs())
                .fold(0.0, f64::max);
            let worst = (0..ix.free)
                .flat_map(|a| (0..ix.free).map(move |b| (a, b)))
                .map(|(a, b)| (hessian[(a, b)] - newton[(a, b)]).abs())
                .fold(0.0, f64::max);
            assert!(
                worst <= 1e-6 * scale,
                "{shape:?}: N − Q off the Hessian by {worst:e} of {scale:e}"
            );
            // Gauss–Newton's N alone is not the Hessian off the optimum.
            let gn = (0..ix.free)
                .flat_map(|a| (0..ix.free).map(move |b| (a, b)))
                .map(|(a, b)| (hessian[(a, b)] - normal[(a, b)]).abs())
                .fold(0.0, f64::max);
            assert!(
                gn > 1e3 * worst,
                "{shape:?}: Q is {gn:e}, the difference {worst:e}"
            );
            // By blocks: the same N − Q.
            let part = Partition::new(&ix);
            let blocks = Blocks::new(&problem, &x, &ix, &part, &basis, &residual, &weights, true);
            let (rebuilt, _) = blocks.newton().unwrap().dense();
            assert_matches_naive("N − Q by blocks", &rebuilt, &newton, Scale::Largest, 1e-13);
            // δᵀQδ of the blocks is that of the dense Q.
            let step: Vec<f64> = (0..ix.free).map(|k| (0.37 * k as f64).sin()).collect();
            let q_dense = &normal - &newton;
            let d = Mat::from_fn(ix.free, 1, |k, _| step[k]);
            let dqd = (d.transpose() * &q_dense * &d)[(0, 0)];
            assert_matches_naive(
                "δᵀQδ",
                &[blocks.curvature_form(&step)],
                &[dqd],
                Scale::Mixed(1.0),
                1e-11,
            );
        }
    }

    fn blocks_agree(
        (problem, x, ix, basis, residual, weights): (
            Problem,
            Parameters,
            Indices,
            Basis,
            Mat<f64>,
            Vec<f64>,
        ),
    ) {
        let (normal, gradient) = dense_normal(&problem, &x, &ix, &basis, &residual, &weights);
        let part = Partition::new(&ix);
        let blocks = Blocks::new(&problem, &x, &ix, &part, &basis, &residual, &weights, false);
        // Every entry of N and g, including the zeros between outputs.
        let (rebuilt, g) = blocks.dense();
        // Sums over the 600 stacked lines in another order. Their rounding bound,
        // 2 · ε · 600 of the largest entry (Cauchy–Schwarz bounds every |term| sum of a
        // Gram matrix by its largest diagonal), is 2.7e-13: the measured 2e-16 keeps the
        // stricter fixed bound.
        let (largest, tol) = (Scale::Largest, 1e-13);
        assert_matches_naive("N by blocks", &rebuilt, &normal, largest, tol);
        assert_matches_naive("g by blocks", &g, &gradient, largest, tol);
        // δᵀg and δᵀNδ of an arbitrary step.
        let step: Vec<f64> = (0..ix.free).map(|k| (0.37 * k as f64).sin()).collect();
        let dense = Normal::Dense(normal.clone(), gradient.clone());
        let (dg, dnd) = dense.gradient_and_curvature(&step);
        let (bg, bnd) = Normal::Blocks(blocks).gradient_and_curvature(&step);
        assert_matches_naive("δᵀg by blocks", &[bg], &[dg], Scale::Mixed(1.0), 1e-12);
        assert_matches_naive("δᵀNδ by blocks", &[bnd], &[dnd], Scale::Entry, 1e-12);
        // Without damping, eliminating the shapes gives the dense solution.
        let Normal::Blocks(blocks) = Normal::new(
            &problem,
            &x,
            &ix,
            Some(&part),
            &basis,
            &residual,
            &weights,
            false,
        ) else {
            unreachable!()
        };
        let reduced = Reduced::new(&blocks).unwrap();
        let by_blocks = reduced.step(0.0).unwrap();
        // The step solves N δ = g: its residual is at rounding level against ‖g‖.
        let d = Mat::from_fn(ix.free, 1, |k, _| by_blocks[k]);
        let nd = &normal * &d;
        let misfit = (0..ix.free)
            .map(|k| (nd[(k, 0)] - gradient[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        let g_norm = gradient.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!(misfit <= 1e-9 * g_norm, "{misfit} against {g_norm}");
    }
}
