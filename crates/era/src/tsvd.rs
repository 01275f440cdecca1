//! Truncated SVD from matrix products only: randomized subspace iteration with a
//! Rayleigh–Ritz step (Halko, Martinsson & Tropp 2011, Alg. 4.4 and 5.1), stopped by an
//! explicit residual test.
//!
//! A first pass from a random start finds the range. Then, with an orthonormal `W`
//! (`cols × k`, `k = rank + oversample`), each iteration forms
//! `Y = H W = Q R`, takes the small SVD `R = U_R Σ V_Rᵀ`, and sets the Ritz triplets
//! `(u_i = Q U_R e_i, σ_i, v_i = W V_R e_i)`. Then `Z = Hᵀ U` both continues the iteration
//! (`W ← orth(Z)`) and measures the residuals
//!
//! ```text
//! ρ_i = ‖Hᵀ u_i − σ_i v_i‖ / σ_1,     i < rank
//! ```
//!
//! (`H v_i − σ_i u_i = 0` holds by construction). **Accuracy control**: iteration stops
//! when `max ρ_i ≤ tolerance`. A singular triplet with residual `ρ` has its singular
//! value correct to `ρ²σ₁²/gap` and its vectors to `ρσ₁/gap`, where `gap` separates
//! `σ_i` from the rest of the spectrum. Convergence goes as `(σ_(k+1)/σ_i)²` per
//! iteration, which is what the oversampling buys.

use crate::error::{EraError, Result};
use crate::hankel_op::LinearOperator;
use crate::sim::Minstd;
use faer::Mat;

/// Settings of [`truncated_svd`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruncatedSvdOptions {
    /// Triplets wanted.
    pub rank: usize,
    /// Extra columns carried along (speeds convergence).
    pub oversample: usize,
    /// Stop when every wanted residual `ρ_i ≤ tolerance` (relative to `σ₁`).
    pub tolerance: f64,
    /// Give up after this many iterations.
    pub max_iterations: usize,
    /// Seed of the random start ([`Minstd`]).
    pub seed: u64,
}

impl TruncatedSvdOptions {
    /// Defaults for `rank` triplets: oversample `rank/2` clamped to 10 … 64, tolerance
    /// 1e-12, at most 300 iterations, seed 1.
    pub fn new(rank: usize) -> Self {
        TruncatedSvdOptions {
            rank,
            oversample: (rank / 2).clamp(10, 64),
            tolerance: 1e-12,
            max_iterations: 300,
            seed: 1,
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
    /// Iterations used.
    pub iterations: usize,
    /// Largest residual of the wanted triplets at the end.
    pub residual: f64,
}

fn orthonormal(m: &Mat<f64>) -> Mat<f64> {
    m.qr().compute_thin_Q()
}

/// The leading `options.rank` singular triplets of `op`.
///
/// # Errors
/// [`EraError::InvalidParameter`] for a rank of 0 or above `min(rows, cols)`;
/// [`EraError::Numerical`] when the small SVD fails or the residual does not reach the
/// tolerance within `max_iterations`.
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
            ),
        });
    }
    let k = (options.rank + options.oversample).min(limit);
    let mut rng = Minstd::new(options.seed);
    // At most three k-wide blocks are alive at once (memory is what limits large cases).
    // The start is uniform on [-1, 1] (any full-rank random test matrix finds the range;
    // Halko et al. §4) and is not orthonormalised: the first pass only finds the range,
    // its residual is not tested, and from the second pass on W = orth(Hᵀ U).
    let mut w = Mat::from_fn(cols, k, |_, _| 2.0 * rng.uniform() - 1.0);
    let mut residual = f64::INFINITY;
    for iteration in 1..=options.max_iterations {
        // Rayleigh–Ritz on span(H W): H W = Q R, R = U_R Σ V_Rᵀ.
        let qr = op.apply(w.as_ref()).qr(); // Y itself is gone once factored
        let (q, r) = (qr.compute_thin_Q(), qr.thin_R().to_owned());
        drop(qr);
        let small = r
            .thin_svd()
            .map_err(|e| EraError::Numerical(format!("small SVD: {e:?}")))?;
        let s: Vec<f64> = (0..small.S().dim()).map(|i| small.S()[i]).collect();
        let u = &q * small.U();
        drop(q);
        let v = &w * small.V();
        drop(w);
        let z = op.apply_transpose(u.as_ref());
        if iteration == 1 {
            drop((u, v));
            w = orthonormal(&z);
            continue;
        }
        let s1 = s[0].max(f64::MIN_POSITIVE);
        residual = (0..options.rank)
            .map(|i| {
                (0..cols)
                    .map(|row| (z[(row, i)] - s[i] * v[(row, i)]).powi(2))
                    .sum::<f64>()
                    .sqrt()
                    / s1
            })
            .fold(0.0, f64::max);
        if residual <= options.tolerance {
            return Ok(TruncatedSvd {
                u,
                s,
                v,
                iterations: iteration,
                residual,
            });
        }
        drop((u, v));
        w = orthonormal(&z);
    }
    Err(EraError::Numerical(format!(
        "the truncated SVD did not converge in {} iterations (residual {residual:.2e}, tolerance {:.0e}): use --svd dense",
        options.max_iterations, options.tolerance
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_dense_svd_on_a_decaying_spectrum() {
        // A = Q1 diag(2^-i) Q2ᵀ with known singular values.
        let (m, n) = (60, 45);
        let mut rng = Minstd::new(9);
        let q1 = orthonormal(&Mat::from_fn(m, n, |_, _| rng.normal()));
        let q2 = orthonormal(&Mat::from_fn(n, n, |_, _| rng.normal()));
        let d = Mat::from_fn(
            n,
            n,
            |i, j| if i == j { 0.7f64.powi(i as i32) } else { 0.0 },
        );
        let a = &q1 * &d * q2.transpose();
        let t = truncated_svd(&a, &TruncatedSvdOptions::new(8)).unwrap();
        for i in 0..8 {
            assert!(
                (t.s[i] - 0.7f64.powi(i as i32)).abs() < 1e-12,
                "{i}: {}",
                t.s[i]
            );
        }
        assert!(t.residual <= 1e-12);
        assert!(truncated_svd(&a, &TruncatedSvdOptions::new(0)).is_err());
    }
}
