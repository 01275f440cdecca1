//! Truncated SVD from matrix products only: block Golub–Kahan–Lanczos with full
//! reorthogonalisation and a Rayleigh–Ritz step, stopped by a residual test. It runs in
//! two phases: an unrestarted one in narrow blocks while its basis fits, then, if that
//! has not converged, the restarted iteration in blocks as wide as the answer.
//!
//! **The unrestarted phase** ([`TruncatedSvdOptions::block`], `b ≈ rank/6`, 8 … 20). From
//! `V_0 = orth(HᵀH Ω)` with `b` random columns, the recurrence below runs without
//! restarts, each new block orthogonalised against the whole basis so far (held as one
//! matrix: one GEMM per sweep). A narrow block buys a higher polynomial degree per column
//! of basis, and a basis that is never thrown away keeps every direction it found, so
//! the wanted triplets converge in far fewer columns of products and of dense work than
//! with wide blocks and restarts (`cargo run --release -p era --example tsvd_probe`
//! prints the passes and columns of each variant on the thesis set). The Rayleigh–Ritz step (the small SVD of `T`) runs only at
//! checkpoints: first when the basis holds `rank + oversample` columns (and at least
//! `rank + 2b`), then where the
//! residual's geometric decrease between the last two checkpoints predicts convergence
//! (between one block and half the basis further on). The phase hands its best `k` Ritz
//! triplets, with `Hᵀ u` (no product needed), to the restarted iteration when the basis
//! would outgrow its room (the memory budget, or half the smaller side) or the residual
//! stalls at the products' rounding floor. It runs first only with room for `2k`
//! columns: where there is less, data with a gap past the rank (exact low-rank data) are
//! served better by the restarted iteration's opening, which settles them in two passes
//! of `k` columns, and the phase runs after the opening only when that has not. A block
//! Krylov space finds at most `b` copies of a repeated singular value, hence the floor
//! `b ≥ 8`.
//!
//! **The opening** of the restarted iteration. It runs first where the unrestarted phase
//! has room for fewer than `2k` columns (or `block = 0`); where it does not settle the
//! data and the phase has room for `k + b`, the phase runs next, from a fresh start.
//! The first two passes are randomized subspace iteration (Halko,
//! Martinsson & Tropp 2011, Alg. 4.4 and 5.1): `Q = orth(H Ω)`, `W = orth(Hᵀ Q)` finds the
//! range, then `H W = Q R`, `R = X Σ Yᵀ` gives the Ritz triplets `(Q X, Σ, W Y)` and
//! `Hᵀ Q X` their residuals. Data with a clear gap past the order (exact Markov data of a
//! finite-order system) stop there, at three Householder QRs and a `k × k` SVD in all.
//! Otherwise the pass's Ritz vectors `u = Q X` and `v = W Y`, with `Σ` and `Hᵀ u`, are
//! the first blocks `U_0`, `V_0`, `T_00` (diagonal) and `Hᵀ U_0` of the Krylov recurrence
//! below, so none of its products is repeated. Where the memory budget allows only one
//! block (depth 1, the largest cases), subspace iteration simply continues from
//! `orth(Hᵀ u)`, with at most three tall blocks alive at once.
//!
//! **Why Krylov.** Subspace iteration (Halko, Martinsson & Tropp 2011, Alg. 4.4) keeps
//! only the last block `(HᵀH)^t H Ω`; its error in the `i`-th triplet falls as
//! `(σ_(k+1)/σ_i)^(2t)` with `k` the block width. When the spectrum has no gap past the
//! wanted rank (15 % noise on the DTA-like set: `σ81/σ80 = 0.995`) that takes dozens of
//! passes. A block Krylov space keeps every block,
//!
//! ```text
//! K_s = span{ Ω, HᵀH Ω, (HᵀH)² Ω, …, (HᵀH)^(s−1) Ω },
//! ```
//!
//! and its Ritz vectors are as good as the best polynomial of degree `s` in `HᵀH`, whose
//! error falls as `exp(−2 s √gap)` instead of `(1 − gap)^(2s)` (Musco & Musco 2015,
//! "Randomized block Krylov methods for stronger and faster approximate singular value
//! decomposition", NeurIPS; Golub & Van Loan §10.4). One *pass* is one product with `H`
//! and one with `Hᵀ`, `b` columns each, as one iteration of subspace iteration was.
//!
//! **The recurrence.** With orthonormal `V_0` (`cols × b`), pass `j` forms
//!
//! ```text
//! H V_j   = Σ_(i<j) U_i T_ij + U_j T_jj          (U_j T_jj = QR of the orthogonalised block)
//! Hᵀ U_j  = Σ_(i≤j) V_i S_ij + V_(j+1) L_j        (V_(j+1) L_j likewise)
//! ```
//!
//! orthogonalising each new block against *all* earlier ones (block Gram–Schmidt, a
//! second sweep when a column lost more than `1 − 1/√2` of its norm in the first: Kahan
//! and Parlett's "twice is enough", Giraud, Langou & Rozložník 2005), so `U = [U_0 … U_j]` and
//! `V = [V_0 … V_j]` stay orthonormal to rounding. Then `H V = U T` holds exactly, the
//! small SVD `T = X Σ Yᵀ` gives the Ritz triplets `(u_i = U x_i, σ_i, v_i = V y_i)`, and
//! the residual needs no further product:
//!
//! ```text
//! Hᵀ u_i − σ_i v_i = V (S − Tᵀ) x_i + V_(j+1) L_j x_i[last block],
//! ρ_i = ‖Hᵀ u_i − σ_i v_i‖ / σ_1 = ‖[(S − Tᵀ) x_i ; L_j x_i[last block]]‖ / σ_1.
//! ```
//!
//! `S` and `T` are computed separately from the two products (`S = Tᵀ` only in exact
//! arithmetic), so this is the same residual the explicit product `Hᵀ U X` would give, to
//! rounding. `H v_i − σ_i u_i = 0` holds by construction. **Accuracy control**: iteration
//! stops when `max ρ_i ≤ tolerance` over the wanted triplets. A triplet with residual `ρ`
//! has its singular value correct to `ρ²σ₁²/gap` and its vectors to `ρσ₁/gap`.
//!
//! **Stopping on noisy data** ([`TruncatedSvdOptions::floor_fraction`]). The computed
//! triplets are the exact ones of `H + E` for some `E` with `‖E‖` of the order of the
//! largest residual `ρσ₁`. When the wanted rank reaches into the noise floor (a default
//! order scan reaches 1.5 times the signal's order and more), its smallest wanted singular value
//! `σ_rank` is of the order of the noise's own perturbation of `H`. Stopping once
//! `ρσ₁ ≤ f·σ_rank` then adds a perturbation a fraction `f` of the noise's. The triplets
//! far above the floor (the signal's) converge faster than the rest, and what stays
//! unsettled is mostly which directions of the noise floor the trailing triplets take,
//! which no exact SVD of noisy data makes a better estimate of anything: more passes
//! leave the poles' error against the truth as it was. What a user can see is the
//! stabilization diagram past the signal's order, where noise poles of consecutive
//! orders, drawn from the same few Krylov directions, agree more often. On exact data
//! `σ_rank` is at rounding and the tolerance alone applies. `cargo run --release -p era
//! --example scan_floor` measures the poles' shift and their error against the truth
//! (the scan's `f` is 0.3).
//!
//! **Restarts.** The basis grows by `b` columns a pass on each side, and the small SVD
//! costs `O((s b)³)`. Once the basis holds `depth` blocks (fewer when it would pass a
//! memory budget; the first cycle counts the opening's block) the iteration restarts from `orth(Hᵀ U X_b)`, the block subspace iteration
//! would take, which the recurrence already holds: `Hᵀ U X_b = V S X_b + V_(j+1) L_j X_b`.
//! (At depth 1 the opening's subspace iteration simply continues.)
//!
//! **Orthonormalisation.** Each block `P` (tall, `b` columns) is factored by CholeskyQR2
//! (Yamamoto, Nakatsukasa, Yanagisawa & Fukaya 2015): `PᵀP = R₁ᵀR₁`, `Q₁ = P R₁⁻¹`, once
//! more on `Q₁`; two Gram products and two triangular solves, all level-3, instead of a
//! Householder QR's panel sweeps. It is orthonormal to rounding while `κ(P) ≲ ε^(−1/2)`.
//! For `κ(P)` up to about `ε⁻¹` a first Cholesky of the shifted Gram matrix
//! `PᵀP + s I`, `s = 11 (m b + b(b+1)) ε ‖P‖²_F`, brings `κ` down first (shifted
//! CholeskyQR3, Fukaya, Kannan, Nakatsukasa, Yamamoto & Yanagisawa 2020). A numerically
//! rank-deficient block (exact low-rank data) falls back to faer's Householder QR, and its
//! arbitrary completing columns are orthogonalised against the basis once more.
//!
//! Why ours: faer 0.24 has a matrix-free partial SVD (`faer::matrix_free::eigen::partial_svd`,
//! Lanczos bidiagonalization with thick restarts), but it multiplies one vector at a time,
//! so the Hankel products (from [`crate::pipeline::hankel_op`]) run on one core and the
//! reorthogonalisation is vector by vector. `cargo run --release -p era --example
//! partial_svd_peer` compares the two on the DTA-like Hankels at era's tolerances (the
//! book's performance chapter has its table); this iteration is the faster in most of
//! those cases.

use crate::error::{EraError, Result};
use crate::linalg::rng::Minstd;
use crate::linalg::LinearOperator;
use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::{Accum, Mat, MatRef, Par, Side};

/// Settings of [`truncated_svd`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct TruncatedSvdOptions {
    /// Triplets wanted.
    pub rank: usize,
    /// Extra columns carried along: the block width is `rank + oversample`.
    pub oversample: usize,
    /// Stop when every wanted residual `ρ_i ≤ tolerance` (relative to `σ₁`).
    pub tolerance: f64,
    /// Give up after this many passes of the restarted iteration. The range-finding pass
    /// always runs, and the first residual is measured at pass 2, so fewer than 2 always
    /// fails. The unrestarted phase is bounded by its room, and by as many passes of its
    /// own; the restarted iteration that may follow it counts from 0 again.
    pub max_iterations: usize,
    /// Seed of the random start ([`Minstd`]).
    pub seed: u64,
    /// Blocks of the Krylov basis before a restart (1: subspace iteration). Capped so that
    /// the two bases stay within [`BASIS_BUDGET_BYTES`] and each basis within half the
    /// operator's smaller side.
    pub depth: usize,
    /// Block width of the unrestarted Krylov phase (0: none, the restarted iteration
    /// alone). The phase runs while its basis fits the same bounds as `depth`: first when
    /// it has room for twice `rank + oversample` columns, after the restarted iteration's
    /// opening when it has room for `rank + oversample` and a block and the opening has
    /// not converged, and not at all with less room.
    pub block: usize,
    /// Also stop once every wanted residual is below this fraction of the smallest wanted
    /// singular value, `ρ_i σ₁ ≤ floor_fraction · σ_rank` (0: off; the tolerance alone).
    /// See the module doc's "Stopping on noisy data".
    pub floor_fraction: f64,
}

/// Memory the two Krylov bases may take before the depth is cut (the large cases).
pub const BASIS_BUDGET_BYTES: usize = 96 << 20;

impl TruncatedSvdOptions {
    /// Defaults for `rank` triplets: oversample `rank/2` clamped to 10 … 64, tolerance
    /// 1e-12, at most 300 passes, seed 1, depth 4, and a first phase in blocks of
    /// [`default_block`]`(rank)` columns.
    pub fn new(rank: usize) -> Self {
        TruncatedSvdOptions {
            rank,
            oversample: (rank / 2).clamp(10, 64),
            tolerance: 1e-12,
            max_iterations: 300,
            seed: 1,
            depth: 4,
            block: default_block(rank),
            floor_fraction: 0.0,
        }
    }

    /// The residual at which the iteration stops, given the current Ritz values `sigma`
    /// (largest first): the tolerance, or `floor_fraction · σ_rank / σ₁` where that is
    /// larger.
    fn target(&self, sigma: &[f64]) -> f64 {
        match (sigma.first(), sigma.get(self.rank.wrapping_sub(1))) {
            (Some(&s1), Some(&sk)) if self.floor_fraction > 0.0 && s1 > 0.0 && sk.is_finite() => {
                self.tolerance.max(self.floor_fraction * sk / s1)
            }
            _ => self.tolerance,
        }
    }
}

/// The leading singular triplets.
#[derive(Debug, Clone)]
pub struct TruncatedSvd {
    /// Left vectors, `rows × k`.
    pub u: Mat<f64>,
    /// Singular values, largest first (`k` of them; the first `rank` converged).
    pub s: Vec<f64>,
    /// Right vectors, `cols × k`.
    pub v: Mat<f64>,
    /// Passes used (one product with `H` and one with `Hᵀ`: a block of
    /// [`TruncatedSvdOptions::block`] columns each in the unrestarted phase, `k` in the
    /// restarted iteration).
    pub iterations: usize,
    /// Columns multiplied by `H`, and as many by `Hᵀ`, over all passes.
    pub columns: usize,
    /// Largest residual of the wanted triplets at the end.
    pub residual: f64,
    /// Where the wall time went.
    pub timings: TsvdTimings,
}

/// Wall time of a [`truncated_svd`] by kind of work, s: what the cost model
/// (`examples/cost_model.rs`) sets against the products' floor.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TsvdTimings {
    /// Products with `H` and `Hᵀ`.
    pub products: f64,
    /// Block Gram–Schmidt and CholeskyQR of the new blocks.
    pub orthogonalisation: f64,
    /// The small SVDs of `T`, the residuals, restarts and the final vectors.
    pub rayleigh_ritz: f64,
}

/// `x R⁻¹` for upper-triangular `R = Lᵀ`, as `x · (L⁻¹)ᵀ`: `L⁻¹` is `b × b`, and
/// the product with the tall `x` is one parallel GEMM, where a triangular solve with
/// `m` right-hand sides in rows ran on one thread. `R` is well conditioned here
/// ([`cholesky_factor`] refuses `min R_ii < 1e-6 · max R_ii` before CholeskyQR2 uses it),
/// and the second CholeskyQR pass removes what the explicit inverse loses.
fn solve_right_upper(x: MatRef<'_, f64>, lower: MatRef<'_, f64>) -> Mat<f64> {
    let b = lower.nrows();
    let mut inverse = Mat::<f64>::identity(b, b);
    solve_lower_triangular_in_place(lower, inverse.as_mut(), Par::Seq);
    x * inverse.transpose()
}

/// The lower triangle of `xᵀx` (the upper is left zero): half the flops of the full
/// product, and all that the lower Cholesky factor reads.
fn gram_lower(x: MatRef<'_, f64>) -> Mat<f64> {
    let b = x.ncols();
    let mut g = Mat::<f64>::zeros(b, b);
    triangular::matmul(
        g.as_mut(),
        BlockStructure::TriangularLower,
        Accum::Replace,
        x.transpose(),
        BlockStructure::Rectangular,
        x,
        BlockStructure::Rectangular,
        1.0,
        faer::get_global_parallelism(),
    );
    g
}

/// `R` (upper) with `xᵀx + shift·I = RᵀR`, or `None` when Cholesky fails or
/// `min R_ii / max R_ii < min_ratio` (then `κ(x)` is at least the inverse of that).
fn cholesky_factor(x: MatRef<'_, f64>, shift: f64, min_ratio: f64) -> Option<Mat<f64>> {
    let mut g = gram_lower(x);
    for i in 0..g.nrows() {
        g[(i, i)] += shift;
    }
    let llt = g.llt(Side::Lower).ok()?;
    let l = llt.L().to_owned();
    let diag: Vec<f64> = (0..l.nrows()).map(|i| l[(i, i)]).collect();
    let (lo, hi) = diag.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), d| {
        (lo.min(*d), hi.max(*d))
    });
    (lo.is_finite() && lo > 0.0 && lo >= min_ratio * hi).then_some(l)
}

/// `P = Q R` with `Q` orthonormal (see the module doc). Returns `(Q, R, householder)`;
/// `householder` says the block was numerically rank-deficient.
fn block_qr(mut p: Mat<f64>) -> (Mat<f64>, Mat<f64>, bool) {
    let (m, b) = (p.nrows(), p.ncols());
    // CholeskyQR2 is safe while κ(P) ≤ ε^(−1/2) ≈ 7e7; the diagonal ratio of R only
    // bounds κ from below, so keep a margin.
    const CHOLQR2_RATIO: f64 = 1e-6;
    // Kept for the Householder fallback when a Cholesky step has touched `p`.
    let mut original = None;
    let mut r_total = Mat::<f64>::identity(b, b);
    let mut first = cholesky_factor(p.as_ref(), 0.0, CHOLQR2_RATIO);
    if first.is_none() {
        let frob2: f64 = p.norm_l2().powi(2);
        let shift = 11.0 * ((m * b + b * (b + 1)) as f64) * f64::EPSILON * frob2;
        if frob2 > 0.0 && frob2.is_finite() {
            if let Some(l) = cholesky_factor(p.as_ref(), shift, 0.0) {
                original = Some(p.clone());
                p = solve_right_upper(p.as_ref(), l.as_ref());
                r_total = l.transpose().to_owned();
                first = cholesky_factor(p.as_ref(), 0.0, CHOLQR2_RATIO);
            }
        }
    }
    if let Some(l1) = first {
        if original.is_none() {
            original = Some(p.clone());
        }
        p = solve_right_upper(p.as_ref(), l1.as_ref());
        if let Some(l2) = cholesky_factor(p.as_ref(), 0.0, CHOLQR2_RATIO) {
            p = solve_right_upper(p.as_ref(), l2.as_ref());
            let r = l2.transpose() * l1.transpose() * &r_total;
            return (p, r, false);
        }
    }
    let p = original.unwrap_or(p);
    let qr = p.qr();
    (qr.compute_thin_Q(), qr.thin_R().to_owned(), true)
}

/// Orthogonalises `p` against the orthonormal blocks of `basis` twice, then factors it:
/// `p = Σ_i basis_i C_i + Q R` with `Q` orthonormal and orthogonal to the basis.
/// Returns `(Q, [C_i], R)`.
fn extend_basis(basis: &[Mat<f64>], mut p: Mat<f64>) -> (Mat<f64>, Vec<Mat<f64>>, Mat<f64>) {
    let b = p.ncols();
    let mut coefficients: Vec<Mat<f64>> = basis.iter().map(|q| Mat::zeros(q.ncols(), b)).collect();
    let project = |x: &mut Mat<f64>, coefficients: &mut [Mat<f64>], scale: Option<&Mat<f64>>| {
        for sweep in 0..2 {
            let before = column_norms(x.as_ref());
            for (q, c) in basis.iter().zip(coefficients.iter_mut()) {
                let step = q.transpose() * &*x;
                matmul(
                    x.as_mut(),
                    Accum::Add,
                    q,
                    &step,
                    -1.0,
                    faer::get_global_parallelism(),
                );
                match scale {
                    None => *c += &step,
                    Some(r) => *c += &step * r,
                }
            }
            // Kahan–Parlett: a column that kept ≥ 1/√2 of its norm is orthogonal to the
            // basis to rounding after one sweep; otherwise sweep once more.
            let after = column_norms(x.as_ref());
            let kept = before
                .iter()
                .zip(&after)
                .all(|(b, a)| *a >= std::f64::consts::FRAC_1_SQRT_2 * b);
            if sweep == 0 && kept {
                break;
            }
        }
    };
    project(&mut p, &mut coefficients, None);
    let (mut q, mut r, householder) = block_qr(p);
    if householder && !basis.is_empty() {
        // The completing columns of a rank-deficient block are arbitrary: make them
        // orthogonal to the basis too. Q = Q' + Σ basis_i c_i, so p's C_i gain c_i R.
        project(&mut q, &mut coefficients, Some(&r));
        let (q2, r2, _) = block_qr(q);
        q = q2;
        r = &r2 * &r;
    }
    (q, coefficients, r)
}

fn column_norms(x: MatRef<'_, f64>) -> Vec<f64> {
    (0..x.ncols()).map(|j| x.col(j).norm_l2()).collect()
}

/// `Σ_i blocks_i · x[rows of block i]`.
fn combine(blocks: &[Mat<f64>], x: MatRef<'_, f64>) -> Mat<f64> {
    let rows = blocks[0].nrows();
    let mut out = Mat::<f64>::zeros(rows, x.ncols());
    let mut at = 0;
    for blk in blocks {
        let w = blk.ncols();
        out += blk * x.subrows(at, w);
        at += w;
    }
    out
}

/// The leading `options.rank` singular triplets of `op`.
///
/// # Errors
/// [`EraError::InvalidParameter`] for a rank of 0 or above `min(rows, cols)`;
/// [`EraError::Numerical`] when the small SVD fails or the residual does not reach the
/// tolerance within `max_iterations` passes.
pub fn truncated_svd(
    op: &dyn LinearOperator,
    options: &TruncatedSvdOptions,
) -> Result<TruncatedSvd> {
    let (rows, cols) = (op.nrows(), op.ncols());
    let limit = rows.min(cols);
    if options.rank == 0 || options.rank > limit {
        return Err(EraError::InvalidParameter {
            name: "states",
            value: options.rank.to_string(),
            reason: format!(
                "a truncated SVD of a {rows} x {cols} operator needs 1 to {limit} triplets"
            )
            .into(),
        });
    }
    let k = (options.rank + options.oversample).min(limit);
    let block_bytes = 8 * k * (rows + cols);
    let depth = options
        .depth
        .min(BASIS_BUDGET_BYTES / block_bytes.max(1))
        // A basis wider than half the smaller side costs as much dense work (Gram–Schmidt,
        // the small SVD) as the dense SVD itself: the order scan's 306 + 64 columns at
        // 1592² ran at depth 2 (17 passes, 5.1 s of CPU) rather than 4 (13 passes, 13 s),
        // measured before the subspace-iteration opening.
        .min(limit / 2 / k)
        .max(1);
    let mut rng = Minstd::new(options.seed);
    let mut timings = TsvdTimings::default();
    let block = options.block.min(limit);
    let deep_width = deep_width(rows, cols, block);
    // Passes and columns before the restarted iteration's current run.
    let mut before = (0, 0);
    // The phase needs room: noisy data converge at 2–3 × rank columns. Where it has less,
    // data with a gap past the rank (exact low-rank data: the 8000², 400-state case took
    // 2.6 s in the phase and its hand-over, 1.2 s in the opening's 2 passes) are served by
    // the opening, and the phase runs only if the opening has not converged.
    let room = block > 0 && deep_width >= k + block;
    let mut opened = None;
    if !(room && deep_width >= 2 * k) {
        let step = opening(op, k, options, &mut rng, &mut timings)?;
        if step.residual <= options.target(&step.s) || !room {
            opened = Some((step, 2));
        } else {
            before = (2, 2 * k);
        }
    }
    let (mut step, mut pass) = match opened {
        Some(opened) => opened,
        None => match deep_krylov(op, options, k, block, deep_width, &mut rng, &mut timings)? {
            Deep::Converged(mut svd) => {
                svd.iterations += before.0;
                svd.columns += before.1;
                return Ok(svd);
            }
            Deep::Exhausted { step, passes } => {
                before = (before.0 + passes, before.1 + passes * block);
                (step, before.0)
            }
        },
    };
    let columns = |passes: usize| before.1 + (passes - before.0) * k;
    loop {
        crate::cancel::check()?;
        if step.residual <= options.target(&step.s) {
            return Ok(TruncatedSvd {
                u: step.u,
                s: step.s,
                v: step.v,
                iterations: pass,
                columns: columns(pass),
                residual: step.residual,
                timings,
            });
        }
        // The restarted iteration's own passes: those after the phase.
        if pass - before.0 >= options.max_iterations {
            return Err(not_converged(options, step.residual));
        }
        if depth > 1 {
            // The pass's Ritz vectors are the Krylov recurrence's first blocks:
            // U_0 = u, V_0 = v, T_00 = Σ, and Hᵀ U_0 is formed.
            let mut svd = krylov(op, step, options, k, depth, pass - before.0, timings)?;
            svd.iterations += before.0;
            svd.columns = columns(svd.iterations);
            return Ok(svd);
        }
        // Subspace iteration continues from orth(Hᵀ u).
        let mut clock = Stopwatch::new();
        drop((step.u, step.v));
        let w = householder_q(step.back);
        clock.lap(&mut timings.orthogonalisation);
        pass += 1;
        step = subspace_step(op, w, options.rank, &mut clock, &mut timings)?;
    }
}

/// The restarted iteration's opening: pass 1 finds the range from a random start (any
/// full-rank test matrix does; Halko et al. §4), pass 2 is one step of subspace
/// iteration with the explicit residual. Data with a gap past the order (exact or nearly
/// exact low rank) stop here.
fn opening(
    op: &dyn LinearOperator,
    k: usize,
    options: &TruncatedSvdOptions,
    rng: &mut Minstd,
    timings: &mut TsvdTimings,
) -> Result<SubspaceStep> {
    let mut clock = Stopwatch::new();
    let start = Mat::from_fn(op.ncols(), k, |_, _| 2.0 * rng.uniform() - 1.0);
    let range = op.apply(start.as_ref());
    drop(start);
    clock.lap(&mut timings.products);
    let q = householder_q(range);
    let back = op.apply_transpose(q.as_ref());
    drop(q);
    clock.lap(&mut timings.products);
    let w = householder_q(back);
    clock.lap(&mut timings.orthogonalisation);
    if options.max_iterations < 2 {
        return Err(not_converged(options, f64::INFINITY));
    }
    subspace_step(op, w, options.rank, &mut clock, timings)
}

/// Wall-clock laps into [`TsvdTimings`] slots.
struct Stopwatch(std::time::Instant);

impl Stopwatch {
    fn new() -> Self {
        Stopwatch(std::time::Instant::now())
    }
    /// Adds the time since the last lap to `slot`.
    fn lap(&mut self, slot: &mut f64) {
        *slot += self.0.elapsed().as_secs_f64();
        self.0 = std::time::Instant::now();
    }
}

fn not_converged(options: &TruncatedSvdOptions, residual: f64) -> EraError {
    EraError::SvdNotConverged {
        passes: options.max_iterations,
        residual,
        tolerance: options.tolerance,
    }
}

/// `Q` of faer's Householder QR: orthonormal whatever the rank of `x` (the completing
/// columns of a rank-deficient `x` are arbitrary), at about half CholeskyQR2's flops.
fn householder_q(x: Mat<f64>) -> Mat<f64> {
    let qr = x.qr();
    drop(x);
    qr.compute_thin_Q()
}

/// The Ritz triplets of one pass of subspace iteration, `Hᵀ u` and the residual.
struct SubspaceStep {
    u: Mat<f64>,
    s: Vec<f64>,
    v: Mat<f64>,
    /// `Hᵀ u`.
    back: Mat<f64>,
    residual: f64,
}

/// One pass of subspace iteration from an orthonormal `w`: `H W = Q R`, `R = X Σ Yᵀ`,
/// the Ritz triplets `(u = Q X, Σ, v = W Y)`, and `Hᵀ u`, which gives the residuals and
/// the next iterate. At most three tall blocks are alive at once, as memory limits the
/// large cases.
fn subspace_step(
    op: &dyn LinearOperator,
    w: Mat<f64>,
    rank: usize,
    clock: &mut Stopwatch,
    timings: &mut TsvdTimings,
) -> Result<SubspaceStep> {
    // The product is gone once factored.
    let qr = op.apply(w.as_ref()).qr();
    let (q, r) = (qr.compute_thin_Q(), qr.thin_R().to_owned());
    drop(qr);
    clock.lap(&mut timings.products);
    let small = r
        .thin_svd()
        .map_err(|e| EraError::Numerical(format!("small SVD: {e:?}")))?;
    let s: Vec<f64> = (0..small.S().dim()).map(|i| small.S()[i]).collect();
    let u = &q * small.U();
    drop(q);
    let v = &w * small.V();
    drop(w);
    clock.lap(&mut timings.rayleigh_ritz);
    let back = op.apply_transpose(u.as_ref());
    clock.lap(&mut timings.products);
    // ρ_i = ‖Hᵀ u_i − σ_i v_i‖ / σ₁ (H v_i = σ_i u_i holds by construction).
    let s1 = s[0].max(f64::MIN_POSITIVE);
    let residual = (0..rank)
        .map(|i| {
            let gap: f64 = back
                .col(i)
                .iter()
                .zip(v.col(i).iter())
                .map(|(z, vi)| (z - s[i] * vi).powi(2))
                .sum();
            gap.sqrt() / s1
        })
        .fold(0.0, worst);
    clock.lap(&mut timings.rayleigh_ritz);
    Ok(SubspaceStep {
        u,
        s,
        v,
        back,
        residual,
    })
}

/// The largest residual so far, NaN counting as not converged (`f64::max` would drop it).
fn worst(so_far: f64, residual: f64) -> f64 {
    if residual.is_nan() {
        f64::INFINITY
    } else {
        so_far.max(residual)
    }
}

/// The largest Ritz residual `ρ_i = ‖[inner_i ; outer_i]‖ / σ₁` over the columns: `inner`
/// is `(S − Tᵀ) X` and `outer` the last block row's `L X` (module doc), one column per
/// wanted triplet. NaN counts as not converged.
fn ritz_residual(inner: MatRef<'_, f64>, outer: MatRef<'_, f64>, s1: f64) -> f64 {
    (0..inner.ncols())
        .map(|i| {
            let a = inner.col(i).norm_l2();
            let b = outer.col(i).norm_l2();
            (a * a + b * b).sqrt() / s1
        })
        .fold(0.0, worst)
}

/// The restarted block Golub–Kahan–Lanczos iteration of the module doc, seeded with the
/// opening's last pass (its Ritz triplets and `Hᵀ u`), after `done` passes.
fn krylov(
    op: &dyn LinearOperator,
    seed: SubspaceStep,
    options: &TruncatedSvdOptions,
    k: usize,
    depth: usize,
    done: usize,
    mut timings: TsvdTimings,
) -> Result<TruncatedSvd> {
    let mut clock = Stopwatch::new();
    let mut v_blocks: Vec<Mat<f64>> = vec![seed.v];
    let mut u_blocks: Vec<Mat<f64>> = vec![seed.u];
    // T = Uᵀ H V and S = Vᵀ Hᵀ U, grown a block row and column a pass.
    let seed_residual = seed.residual;
    let mut t = Mat::from_fn(k, k, |i, j| if i == j { seed.s[i] } else { 0.0 });
    // The seed's right step: Hᵀ U_0 = V_0 S_00 + V_1 L_0.
    let (v1, coefficients, tail) = extend_basis(&v_blocks, seed.back);
    let mut s_mat = coefficients.into_iter().next().expect("one block");
    let mut previous_tail = Some(tail);
    v_blocks.push(v1);
    clock.lap(&mut timings.orthogonalisation);
    let mut residual = seed_residual;
    let mut lap = |slot: &mut f64| clock.lap(slot);
    for pass in done + 1..=options.max_iterations {
        let j = u_blocks.len();
        let width = (j + 1) * k;
        // Left: H V_j = Σ U_i T_ij + U_j T_jj.
        lap(&mut timings.rayleigh_ritz);
        let hv = op.apply(v_blocks[j].as_ref());
        lap(&mut timings.products);
        let (u_new, coefficients, r) = extend_basis(&u_blocks, hv);
        lap(&mut timings.orthogonalisation);
        u_blocks.push(u_new);
        let mut grown = Mat::<f64>::zeros(width, width);
        grown
            .as_mut()
            .submatrix_mut(0, 0, j * k, j * k)
            .copy_from(&t);
        for (i, c) in coefficients.iter().enumerate() {
            grown
                .as_mut()
                .submatrix_mut(i * k, j * k, k, k)
                .copy_from(c);
        }
        grown
            .as_mut()
            .submatrix_mut(j * k, j * k, k, k)
            .copy_from(&r);
        t = grown;
        // Right: Hᵀ U_j = Σ_(i≤j) V_i S_ij + V_(j+1) L_j.
        lap(&mut timings.orthogonalisation);
        let htu = op.apply_transpose(u_blocks[j].as_ref());
        lap(&mut timings.products);
        let (v_next, coefficients, tail) = extend_basis(&v_blocks, htu);
        lap(&mut timings.orthogonalisation);
        let mut grown = Mat::<f64>::zeros(width, width);
        grown
            .as_mut()
            .submatrix_mut(0, 0, j * k, j * k)
            .copy_from(&s_mat);
        for (i, c) in coefficients.iter().enumerate() {
            grown
                .as_mut()
                .submatrix_mut(i * k, j * k, k, k)
                .copy_from(c);
        }
        if let Some(previous) = previous_tail.take() {
            // V_j entered the basis as V_(j−1)'s successor: S_(j, j−1) = L_(j−1).
            grown
                .as_mut()
                .submatrix_mut(j * k, (j - 1) * k, k, k)
                .copy_from(&previous);
        }
        s_mat = grown;
        // Rayleigh–Ritz: T = X Σ Yᵀ.
        let small = t
            .thin_svd()
            .map_err(|e| EraError::Numerical(format!("small SVD: {e:?}")))?;
        let (x, y) = (small.U(), small.V());
        let sigma: Vec<f64> = (0..small.S().dim()).map(|i| small.S()[i]).collect();
        let s1 = sigma[0].max(f64::MIN_POSITIVE);
        let wanted = x.subcols(0, options.rank);
        let inner = (&s_mat - t.transpose()) * wanted;
        let outer = &tail * wanted.subrows(j * k, k);
        residual = ritz_residual(inner.as_ref(), outer.as_ref(), s1);
        if residual <= options.target(&sigma) {
            let keep = k.min(width);
            let u = combine(&u_blocks, x.subcols(0, keep));
            let v = combine(&v_blocks, y.subcols(0, keep));
            lap(&mut timings.rayleigh_ritz);
            return Ok(TruncatedSvd {
                u,
                s: sigma[..keep].to_vec(),
                v,
                iterations: pass,
                columns: 0, // set by the caller, who knows the passes before
                residual,
                timings,
            });
        }
        if j + 1 < depth {
            v_blocks.push(v_next);
            previous_tail = Some(tail);
        } else {
            // Restart from orth(Hᵀ U X_k) = orth(V S X_k + V_(j+1) L_j X_k[last]).
            let xk = x.subcols(0, k);
            let mut restart = combine(&v_blocks, (&s_mat * xk).as_ref());
            restart += &v_next * (&tail * xk.subrows(j * k, k));
            drop(v_next);
            u_blocks.clear();
            v_blocks.clear();
            lap(&mut timings.rayleigh_ritz);
            v_blocks.push(block_qr(restart).0);
            lap(&mut timings.orthogonalisation);
            t = Mat::zeros(0, 0);
            s_mat = Mat::zeros(0, 0);
        }
    }
    Err(not_converged(options, residual))
}

/// The default [`TruncatedSvdOptions::block`] for `rank` triplets: `rank/6` clamped to
/// 8 … 20. Narrow blocks raise the polynomial degree a column of basis buys; the floor
/// keeps a cluster of up to 8 equal singular values within one block (a block Krylov
/// space finds at most `b` copies of a repeated singular value). The ceiling: wider
/// blocks were slower at every rank above the thesis size's 80 that was measured (the
/// DTA-like 3192² Hankel at 180 triplets and 5–15 % noise, `cargo run --release -p era
/// --example partial_svd_peer` with `BLOCK=b`: 0.38–0.47 s at 20 against 0.66–0.69 s at
/// 30), but much narrower ones can be far slower: the lightly damped 4800² case of
/// `cargo bench -p era --bench scale` at 240 triplets took 0.14 s at 20 and 32, and 3.7 s
/// at 13.
pub fn default_block(rank: usize) -> usize {
    (rank / 6).clamp(8, 20)
}

/// The widest basis of the unrestarted phase: both bases within
/// [`BASIS_BUDGET_BYTES`] and within half the smaller side, in whole blocks.
fn deep_width(rows: usize, cols: usize, block: usize) -> usize {
    if block == 0 {
        return 0;
    }
    let columns = (BASIS_BUDGET_BYTES / (8 * (rows + cols)).max(1)).min(rows.min(cols) / 2);
    // V holds one block more than U.
    columns.saturating_sub(block) / block * block
}

/// How the unrestarted phase ended.
enum Deep {
    Converged(TruncatedSvd),
    /// Out of room (or passes) first: its best `k` Ritz triplets and `Hᵀ u`, which seed
    /// the restarted iteration, after `passes` passes.
    Exhausted {
        step: SubspaceStep,
        passes: usize,
    },
}

/// The unrestarted block Golub–Kahan–Lanczos phase: the recurrence of the module doc
/// in blocks of `b ≪ rank` columns from `V_0 = orth(HᵀH Ω)`, with full
/// reorthogonalisation against one growing basis (one GEMM a sweep) and the
/// Rayleigh–Ritz step only at checkpoints. The next checkpoint is where the residual's
/// geometric decrease over the last two predicts convergence (within `W + b … 3W/2`).
fn deep_krylov(
    op: &dyn LinearOperator,
    options: &TruncatedSvdOptions,
    k: usize,
    b: usize,
    max_width: usize,
    rng: &mut Minstd,
    timings: &mut TsvdTimings,
) -> Result<Deep> {
    let (rows, cols) = (op.nrows(), op.ncols());
    let mut clock = Stopwatch::new();
    let start = Mat::from_fn(cols, b, |_, _| 2.0 * rng.uniform() - 1.0);
    let range = op.apply(start.as_ref());
    drop(start);
    let back = op.apply_transpose(range.as_ref());
    drop(range);
    clock.lap(&mut timings.products);
    let mut v = Mat::<f64>::with_capacity(cols, max_width + b);
    append_columns(&mut v, &block_qr(back).0);
    let mut u = Mat::<f64>::with_capacity(rows, max_width);
    // T = Uᵀ H V (W × W) and S = Vᵀ Hᵀ U ((W + b) × W), as in `krylov`.
    let mut t = Mat::<f64>::zeros(0, 0);
    let mut s_mat = Mat::<f64>::zeros(0, 0);
    clock.lap(&mut timings.orthogonalisation);
    let mut pass = 1;
    let mut next_check = k.max(options.rank + 2 * b);
    let mut last: Option<(usize, f64)> = None;
    loop {
        crate::cancel::check()?;
        pass += 1;
        let w = u.ncols();
        // Left: H V_j = U C + U_j R.
        let hv = op.apply(v.subcols(w, b));
        clock.lap(&mut timings.products);
        let (u_new, coefficients, r) = if w == 0 {
            extend_basis(&[], hv)
        } else {
            extend_basis(std::slice::from_ref(&u), hv)
        };
        append_columns(&mut u, &u_new);
        t.resize_with(w + b, w + b, |_, _| 0.0);
        if let Some(c) = coefficients.first() {
            t.as_mut().submatrix_mut(0, w, w, b).copy_from(c);
        }
        t.as_mut().submatrix_mut(w, w, b, b).copy_from(&r);
        clock.lap(&mut timings.orthogonalisation);
        // Right: Hᵀ U_j = V D + V_(j+1) L.
        let htu = op.apply_transpose(u_new.as_ref());
        drop(u_new);
        clock.lap(&mut timings.products);
        let (v_new, coefficients, l) = extend_basis(std::slice::from_ref(&v), htu);
        let vw = v.ncols();
        append_columns(&mut v, &v_new);
        drop(v_new);
        s_mat.resize_with(vw + b, w + b, |_, _| 0.0);
        s_mat
            .as_mut()
            .submatrix_mut(0, w, vw, b)
            .copy_from(&coefficients[0]);
        s_mat.as_mut().submatrix_mut(vw, w, b, b).copy_from(&l);
        clock.lap(&mut timings.orthogonalisation);
        let w = w + b;
        let out_of_room = w + b > max_width || pass >= options.max_iterations;
        if w < next_check && !out_of_room {
            continue;
        }
        if w < k {
            // Out of passes before the basis holds the triplets asked for.
            return Err(not_converged(options, f64::INFINITY));
        }
        // Rayleigh–Ritz: T = X Σ Yᵀ; ρ_i from S − Tᵀ and the last block row of S.
        let small = t
            .thin_svd()
            .map_err(|e| EraError::Numerical(format!("small SVD: {e:?}")))?;
        let (x, y) = (small.U(), small.V());
        let sigma: Vec<f64> = (0..k).map(|i| small.S()[i]).collect();
        let s1 = sigma[0].max(f64::MIN_POSITIVE);
        let wanted = x.subcols(0, options.rank);
        let inner = (s_mat.subrows(0, w) - t.transpose()) * wanted;
        let outer = s_mat.subrows(w, b) * wanted;
        let residual = ritz_residual(inner.as_ref(), outer.as_ref(), s1);
        let xk = x.subcols(0, k);
        let target = options.target(&sigma);
        if residual <= target {
            let (ritz_u, ritz_v) = (&u * xk, v.subcols(0, w) * y.subcols(0, k));
            clock.lap(&mut timings.rayleigh_ritz);
            return Ok(Deep::Converged(TruncatedSvd {
                u: ritz_u,
                s: sigma,
                v: ritz_v,
                iterations: pass,
                columns: pass * b,
                residual,
                timings: *timings,
            }));
        }
        // At the rounding floor of the products (exact low-rank data in a wide basis:
        // 1.1e-12 at 432 columns for 306 triplets of the noise-free DTA-like set), a wider
        // basis does not help; the restarted iteration, whose basis is the Ritz vectors
        // themselves, gets below it.
        let stalled =
            last.is_some_and(|(_, r0)| residual > 0.5 * r0 && residual < 100.0 * options.tolerance);
        if out_of_room || stalled {
            // Hᵀ U X_k = V S X_k, with V's last block included. Each basis is dropped once
            // its products are formed, so that at most one is alive beside k-column blocks.
            let ritz_u = &u * xk;
            drop(u);
            let back = &v * (&s_mat * xk);
            let ritz_v = v.subcols(0, w) * y.subcols(0, k);
            drop(v);
            clock.lap(&mut timings.rayleigh_ritz);
            return Ok(Deep::Exhausted {
                step: SubspaceStep {
                    u: ritz_u,
                    s: sigma,
                    v: ritz_v,
                    back,
                    residual,
                },
                passes: pass,
            });
        }
        next_check = next_checkpoint(w, residual, last, target, b);
        last = Some((w, residual));
        clock.lap(&mut timings.rayleigh_ritz);
    }
}

/// Where to take the next Rayleigh–Ritz step: where the geometric decrease of the
/// residual between the last two checkpoints reaches the tolerance, rounded up to a whole
/// block, and at least one block and at most half the basis further on.
fn next_checkpoint(
    width: usize,
    residual: f64,
    last: Option<(usize, f64)>,
    tolerance: f64,
    b: usize,
) -> usize {
    let (near, far) = (width + b, width + (width / 2).max(b));
    let predicted = last.and_then(|(w0, r0)| {
        let rate = (residual / r0).ln() / (width - w0) as f64;
        (rate < 0.0 && residual.is_finite() && residual > 0.0)
            .then(|| width as f64 + (tolerance / residual).ln() / rate)
    });
    match predicted {
        // Clamped before the cast: a residual that barely moved predicts a huge width.
        Some(p) if p.is_finite() => {
            ((p.clamp(near as f64, far as f64) / b as f64).ceil() as usize * b).clamp(near, far)
        }
        _ => width + (width / 4).max(b),
    }
}

/// Appends `block`'s columns to `basis` (whose capacity was reserved).
fn append_columns(basis: &mut Mat<f64>, block: &Mat<f64>) {
    let at = basis.ncols();
    basis.resize_with(block.nrows(), at + block.ncols(), |_, _| 0.0);
    basis
        .as_mut()
        .subcols_mut(at, block.ncols())
        .copy_from(block);
}

#[cfg(test)]
mod tests {
    use super::*;
    use era_testkit::{assert_matches_naive, Scale};

    #[test]
    fn matches_the_dense_svd_on_a_decaying_spectrum() {
        // A = Q1 diag(2^-i) Q2ᵀ with known singular values.
        let (m, n) = (60, 45);
        let mut rng = Minstd::new(9);
        let q1 = block_qr(Mat::from_fn(m, n, |_, _| rng.normal())).0;
        let q2 = block_qr(Mat::from_fn(n, n, |_, _| rng.normal())).0;
        let d = Mat::from_fn(
            n,
            n,
            |i, j| if i == j { 0.7f64.powi(i as i32) } else { 0.0 },
        );
        let a = &q1 * &d * q2.transpose();
        let t = truncated_svd(&a, &TruncatedSvdOptions::new(8)).unwrap();
        let known: Vec<f64> = (0..8).map(|i| 0.7f64.powi(i)).collect();
        // Converged to the options' tolerance (1e-12 of σ₁ = 1), not to rounding.
        let (fast, scale) = (&t.s[..8], Scale::Absolute);
        assert_matches_naive("truncated σ, known", fast, &known, scale, 1e-12);
        let dense = a.thin_svd().unwrap();
        let dense: Vec<f64> = (0..8).map(|i| dense.S()[i]).collect();
        assert_matches_naive("truncated σ, dense SVD", fast, &dense, scale, 1e-12);
        assert!(t.residual <= 1e-12);
        assert!(truncated_svd(&a, &TruncatedSvdOptions::new(0)).is_err());
    }

    /// The noise-floor stop: on a rank-10 signal plus white noise, asked for 30 triplets
    /// (20 in the noise floor), it stops with every residual below the fraction of
    /// `σ_30`, sooner than the tolerance alone, and its top ten triplets are those of the
    /// tight run to a small part of the noise's own size.
    #[test]
    fn the_floor_stop_ends_at_a_fraction_of_the_smallest_wanted_value() {
        let (m, n, signal) = (400, 300, 10);
        let mut rng = Minstd::new(21);
        let left = block_qr(Mat::from_fn(m, signal, |_, _| rng.normal())).0;
        let right = block_qr(Mat::from_fn(n, signal, |_, _| rng.normal())).0;
        let d = Mat::from_fn(signal, signal, |i, j| {
            if i == j {
                0.8f64.powi(i as i32)
            } else {
                0.0
            }
        });
        let noise = 1e-3;
        let a = &left * &d * right.transpose() + Mat::from_fn(m, n, |_, _| noise * rng.normal());
        let mut tight = TruncatedSvdOptions::new(30);
        tight.tolerance = 1e-10;
        let mut loose = tight;
        loose.floor_fraction = 0.03;
        let t = truncated_svd(&a, &tight).unwrap();
        let l = truncated_svd(&a, &loose).unwrap();
        assert!(t.residual <= 1e-10);
        assert!(l.residual <= 0.03 * l.s[29] / l.s[0], "{:e}", l.residual);
        assert!(l.residual > 1e-10, "the floor stop never ended early");
        assert!(
            l.columns < t.columns,
            "{} vs {} columns",
            l.columns,
            t.columns
        );
        // The signal's values move by far less than the noise's own size: entries of
        // 1e-3, whose spectrum reaches about (√m + √n)·1e-3 ≈ 0.037.
        for i in 0..signal {
            let shift = (l.s[i] - t.s[i]).abs();
            assert!(shift < 0.03 * noise, "σ_{i}: shift {shift:e}");
        }
    }

    /// `P = Q R`, `QᵀQ = I` and `R` upper triangular on the three paths of
    /// [`block_qr`]: well conditioned (CholeskyQR2), κ ≈ 1e11 (shifted CholeskyQR3) and
    /// rank-deficient (Householder).
    #[test]
    fn block_qr_factors_on_every_path() {
        let (m, b) = (300, 24);
        let mut rng = Minstd::new(3);
        let g = Mat::from_fn(m, b, |_, _| rng.normal());
        let basis = block_qr(Mat::from_fn(b, b, |_, _| rng.normal())).0;
        for (decay, rank, householder) in [(0.8f64, b, false), (0.33, b, false), (1.0, b / 2, true)]
        {
            // Columns scaled by decay^j (κ = decay^-(b-1)), or a rank-`rank` product.
            let p = if rank < b {
                let left = Mat::from_fn(m, rank, |_, _| rng.normal());
                let right = Mat::from_fn(rank, b, |_, _| rng.normal());
                &left * &right
            } else {
                Mat::from_fn(m, b, |i, j| g[(i, j)] * decay.powi(j as i32)) * &basis
            };
            let (q, r, fell_back) = block_qr(p.clone());
            assert_eq!(fell_back, householder, "decay {decay}, rank {rank}");
            let eye = Mat::<f64>::identity(b, b);
            let loss = (q.transpose() * &q - &eye).norm_l2();
            assert!(loss < 1e-13, "orthogonality {loss:e}");
            let back = (&q * &r - &p).norm_l2() / p.norm_l2();
            assert!(back < 1e-13, "reconstruction {back:e}");
            for j in 0..b {
                for i in j + 1..b {
                    assert!(r[(i, j)].abs() <= 1e-14 * p.norm_l2(), "R not triangular");
                }
            }
        }
    }

    /// Exact rank below the block width: without the unrestarted phase, the opening's
    /// two passes of subspace iteration already give the triplets to rounding, at any
    /// depth.
    #[test]
    fn exact_low_rank_stops_after_the_opening() {
        let (m, n, r) = (90, 70, 6);
        let mut rng = Minstd::new(4);
        let q1 = block_qr(Mat::from_fn(m, r, |_, _| rng.normal())).0;
        let q2 = block_qr(Mat::from_fn(n, r, |_, _| rng.normal())).0;
        let d = Mat::from_fn(r, r, |i, j| if i == j { 3.0 / (1 + i) as f64 } else { 0.0 });
        let a = &q1 * &d * q2.transpose();
        for depth in [1, 4] {
            let options = TruncatedSvdOptions {
                depth,
                block: 0,
                ..TruncatedSvdOptions::new(r)
            };
            let t = truncated_svd(&a, &options).unwrap();
            assert_eq!(t.iterations, 2, "depth {depth}");
            // Two passes are the fewest that measure a residual.
            let one = TruncatedSvdOptions {
                max_iterations: 1,
                ..options
            };
            assert!(truncated_svd(&a, &one).is_err());
            for i in 0..r {
                assert!(
                    (t.s[i] - 3.0 / (1 + i) as f64).abs() < 1e-13,
                    "{i}: {}",
                    t.s[i]
                );
            }
        }
    }

    #[test]
    fn depth_one_is_subspace_iteration_and_converges_too() {
        let (m, n) = (80, 70);
        let mut rng = Minstd::new(5);
        let q1 = block_qr(Mat::from_fn(m, n, |_, _| rng.normal())).0;
        let q2 = block_qr(Mat::from_fn(n, n, |_, _| rng.normal())).0;
        let d = Mat::from_fn(
            n,
            n,
            |i, j| if i == j { 0.97f64.powi(i as i32) } else { 0.0 },
        );
        let a = &q1 * &d * q2.transpose();
        // The restarted iteration alone (no unrestarted phase first).
        let shallow = TruncatedSvdOptions {
            depth: 1,
            block: 0,
            ..TruncatedSvdOptions::new(6)
        };
        let deep = TruncatedSvdOptions {
            depth: 4,
            block: 0,
            ..TruncatedSvdOptions::new(6)
        };
        let (s1, s4) = (
            truncated_svd(&a, &shallow).unwrap(),
            truncated_svd(&a, &deep).unwrap(),
        );
        for t in [&s1, &s4] {
            for i in 0..6 {
                assert!(
                    (t.s[i] - 0.97f64.powi(i as i32)).abs() < 1e-12,
                    "{i}: {}",
                    t.s[i]
                );
            }
            // The vectors are singular vectors: A v = σ u.
            let av = &a * &t.v;
            for i in 0..6 {
                let r: f64 = (0..m)
                    .map(|k| (av[(k, i)] - t.s[i] * t.u[(k, i)]).powi(2))
                    .sum();
                assert!(r.sqrt() < 1e-11, "{i}: {}", r.sqrt());
            }
        }
        // Out of passes right after the opening: the error gives the residual it reached.
        let short = TruncatedSvdOptions {
            max_iterations: 2,
            ..deep
        };
        let message = truncated_svd(&a, &short).unwrap_err().to_string();
        assert!(
            message.contains("2 passes") && !message.contains("inf"),
            "{message}"
        );
        // A slowly decaying spectrum is where the Krylov space pays.
        assert!(
            s4.iterations < s1.iterations,
            "{} vs {}",
            s4.iterations,
            s1.iterations
        );
    }

    /// `A = Q1 diag(d) Q2ᵀ` with orthonormal random `Q1`, `Q2` (`m × d.len()`,
    /// `n × d.len()`).
    fn with_singular_values(m: usize, n: usize, d: &[f64], seed: u64) -> Mat<f64> {
        let mut rng = Minstd::new(seed);
        let r = d.len();
        let q1 = block_qr(Mat::from_fn(m, r, |_, _| rng.normal())).0;
        let q2 = block_qr(Mat::from_fn(n, r, |_, _| rng.normal())).0;
        let d = Mat::from_fn(r, r, |i, j| if i == j { d[i] } else { 0.0 });
        &q1 * &d * q2.transpose()
    }

    /// Largest `|σ_i − d_i|` and `‖A v_i − σ_i u_i‖`, `‖Aᵀ u_i − σ_i v_i‖` over the first
    /// `rank` triplets.
    fn triplet_errors(a: &Mat<f64>, t: &TruncatedSvd, d: &[f64], rank: usize) -> (f64, f64) {
        let (av, atu) = (a * &t.v, a.transpose() * &t.u);
        let mut value: f64 = 0.0;
        let mut vector: f64 = 0.0;
        for i in 0..rank {
            value = value.max((t.s[i] - d[i]).abs());
            let left = (0..a.nrows())
                .map(|k| (av[(k, i)] - t.s[i] * t.u[(k, i)]).powi(2))
                .sum::<f64>();
            let right = (0..a.ncols())
                .map(|k| (atu[(k, i)] - t.s[i] * t.v[(k, i)]).powi(2))
                .sum::<f64>();
            vector = vector.max(left.sqrt()).max(right.sqrt());
        }
        (value, vector)
    }

    /// The unrestarted phase on a slowly decaying spectrum, where it converges within its
    /// room: the triplets of the dense answer, in fewer columns of products than the
    /// restarted iteration alone.
    #[test]
    fn the_unrestarted_phase_matches_the_dense_svd() {
        let (m, n, rank) = (400, 300, 20);
        let d: Vec<f64> = (0..n).map(|i| 0.97f64.powi(i as i32)).collect();
        let a = with_singular_values(m, n, &d, 11);
        let options = TruncatedSvdOptions::new(rank);
        assert_eq!(options.block, 8);
        let t = truncated_svd(&a, &options).unwrap();
        let (value, vector) = triplet_errors(&a, &t, &d, rank);
        assert!(value < 1e-12, "singular values {value:e}");
        assert!(vector < 1e-11, "vectors {vector:e}");
        assert!(t.residual <= 1e-12);
        assert_eq!(t.s.len(), rank + options.oversample);
        // Within its room (half of 300 columns): no restarted pass, so every pass is one
        // block of 8 columns each way, and fewer columns than the restarted iteration's.
        assert!(t.iterations * 8 < 150, "{} passes", t.iterations);
        assert_eq!(t.columns, t.iterations * 8);
        let restarted = truncated_svd(
            &a,
            &TruncatedSvdOptions {
                block: 0,
                ..options
            },
        )
        .unwrap();
        let k = rank + options.oversample;
        assert_eq!(restarted.columns, restarted.iterations * k);
        assert!(
            t.columns < restarted.columns,
            "{} columns against {}",
            t.columns,
            restarted.columns
        );
    }

    /// A basis with too little room for the answer hands its Ritz triplets to the
    /// restarted iteration, which finishes from them; and a repeated singular value (a
    /// cluster up to the block width) comes out as often as it occurs.
    #[test]
    fn the_unrestarted_phase_hands_over_and_finds_repeated_values() {
        // Room: half of 80 columns less a block, 32 = 2k; the answer needs more.
        let (m, n, rank) = (90, 80, 6);
        let d: Vec<f64> = (0..n).map(|i| 0.99f64.powi(i as i32)).collect();
        let a = with_singular_values(m, n, &d, 5);
        let options = TruncatedSvdOptions::new(rank);
        assert_eq!(deep_width(m, n, options.block), 32);
        let t = truncated_svd(&a, &options).unwrap();
        let (value, vector) = triplet_errors(&a, &t, &d, rank);
        assert!(value < 1e-12 && vector < 1e-11, "{value:e} {vector:e}");
        // 32 columns are 4 passes of 8 after the start: the restarted iteration ran on,
        // in passes of k = 16 columns.
        assert!(t.iterations > 5, "{} passes", t.iterations);
        assert_eq!(t.columns, 5 * 8 + (t.iterations - 5) * 16);
        // The restarted iteration's passes count from 0 after the phase: a budget of
        // fewer passes than the two together, but as many as either, still converges.
        let restarted = t.iterations - 5;
        let budget = TruncatedSvdOptions {
            max_iterations: restarted.max(5),
            ..options
        };
        assert!(budget.max_iterations < t.iterations);
        let again = truncated_svd(&a, &budget).unwrap();
        assert_eq!(
            (again.iterations, again.s.clone()),
            (t.iterations, t.s.clone())
        );
        // With less room (24 columns, under 2k) the opening goes first: exact low-rank
        // data stop there, after 2 passes of k columns; the others go on to the phase
        // (3 blocks after its start fill the room) and then to the restarted iteration.
        assert_eq!(deep_width(m - 2, n - 2, options.block), 24);
        let exact = with_singular_values(m - 2, n - 2, &d[..rank], 5);
        let t = truncated_svd(&exact, &options).unwrap();
        assert_eq!((t.iterations, t.columns), (2, 32));
        let slow = with_singular_values(m - 2, n - 2, &d[..n - 2], 5);
        let t = truncated_svd(&slow, &options).unwrap();
        let (value, vector) = triplet_errors(&slow, &t, &d, rank);
        assert!(value < 1e-12 && vector < 1e-11, "{value:e} {vector:e}");
        assert!(t.iterations > 6, "{} passes", t.iterations);
        assert_eq!(t.columns, 2 * 16 + 4 * 8 + (t.iterations - 6) * 16);
        // Out of passes inside the phase: an error, not a panic.
        let short = TruncatedSvdOptions {
            max_iterations: 2,
            ..options
        };
        assert!(truncated_svd(&a, &short).is_err());

        let mut d = vec![2.0, 1.5, 1.5, 1.5, 1.5, 1.5, 1.5, 1.0];
        d.extend((0..40).map(|i| 0.5 * 0.9f64.powi(i)));
        let a = with_singular_values(300, 260, &d, 8);
        let t = truncated_svd(&a, &TruncatedSvdOptions::new(12)).unwrap();
        let (value, vector) = triplet_errors(&a, &t, &d, 12);
        assert!(value < 1e-12 && vector < 1e-11, "{value:e} {vector:e}");
    }

    /// Exact low rank inside the unrestarted phase: the Krylov space is exhausted after
    /// one block, the next blocks are rounding (completed by Householder and kept
    /// orthogonal to the basis), and the triplets come out to rounding.
    #[test]
    fn the_unrestarted_phase_survives_an_exhausted_krylov_space() {
        let d = [3.0, 2.0, 1.5, 1.0, 0.5];
        let a = with_singular_values(200, 150, &d, 6);
        let t = truncated_svd(&a, &TruncatedSvdOptions::new(5)).unwrap();
        let (value, vector) = triplet_errors(&a, &t, &d, 5);
        assert!(value < 1e-13 && vector < 1e-13, "{value:e} {vector:e}");
        let u = t.u.subcols(0, 5);
        let loss = (u.transpose() * u - Mat::<f64>::identity(5, 5)).norm_l2();
        assert!(loss < 1e-13, "orthogonality {loss:e}");
    }
}
