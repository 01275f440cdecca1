//! The fast evaluation of the variable-projection functional: one QR per block of pairs
//! sharing a basis, and Kaufman's Jacobian contracted without ever forming it.
//!
//! With `Φ = QR` (thin), the coefficients of every unit of a block are `Θ = R⁻¹QᵀY` and the
//! residuals `P⊥Y`, `P⊥ = I − QQᵀ`. The derivative of the basis with respect to a pole
//! parameter `θ_k` touches only that mode's columns `c`, so Kaufman's Jacobian column of
//! unit `u` is `J_k,u = −Σ_c E_(k,c) Θ_(c,u)` with `E = P⊥ ∂Φ` (the `2L × 2·per_mode·N`
//! derivative columns projected once per block). Its normal matrix and gradient follow
//! from small Gram matrices:
//!
//! ```text
//! (JᵀJ)_kl = Σ_(c,c') (EᵀE)_((k,c),(l,c')) (ΘΘᵀ)_(c,c'),   (Jᵀr)_k = −Σ_c (EᵀP⊥Y Θᵀ)_((k,c),c)
//! ```
//!
//! so an iteration of the 8 × 8, 40-mode, 801-line set costs a QR of a 1602 × 82 matrix
//! and a few products of that size, not the 102 528 × 80 Jacobian.

use super::fit::{Evaluation, Outcome};
use super::model::{basis, basis_derivatives, Problem};
use crate::error::Result;
use faer::Mat;

/// Relative size of `|R_cc|` to the column norm below which a column is taken as a
/// combination of the others (a pole coalesced with another).
pub(crate) const DEFICIENT_COLUMN: f64 = 1e-11;

/// Cost, Kaufman normal matrix, gradient and coefficients at `theta`.
pub(crate) fn evaluate(problem: &Problem, theta: &[f64]) -> Result<Outcome> {
    let poles = problem.parameters.poles(theta);
    let layout = &problem.layout;
    let pm = layout.per_mode;
    let n_par = theta.len();
    let n_col = layout.columns(poles.len());
    let phi = basis(layout, &problem.omega, &poles);
    let deriv = basis_derivatives(layout, problem.parameters, &problem.omega, &poles);
    let mut jtj = Mat::<f64>::zeros(n_par, n_par);
    let mut jtr = vec![0.0; n_par];
    let mut cost = 0.0;
    let pairs = problem.outputs * problem.inputs;
    let mut coefficients = Mat::<f64>::zeros(n_col, pairs);
    for block in &problem.blocks {
        let phi_b = block.stack(&phi);
        let qr = phi_b.qr();
        let q = qr.compute_thin_Q();
        let r = qr.thin_R().to_owned();
        for c in 0..n_col {
            let norm = phi_b.col(c).norm_l2();
            let diagonal = r[(c, c)].abs();
            if diagonal.is_nan() || diagonal <= DEFICIENT_COLUMN * norm {
                return Ok(Outcome::Deficient {
                    column: c,
                    mode: (c < poles.len() * pm).then_some(c / pm),
                });
            }
        }
        let qty = q.transpose() * &block.rhs;
        let mut theta_b = qty.clone();
        r.solve_upper_triangular_in_place(&mut theta_b);
        let res = &block.rhs - &q * &qty;
        cost += res.squared_norm_l2() + block.cost_offset;
        let d_b = block.stack(&deriv);
        let e = &d_b - &q * (q.transpose() * &d_b);
        let g = e.transpose() * &e;
        let t = &theta_b * theta_b.transpose();
        let z = (e.transpose() * &res) * theta_b.transpose();
        for k in 0..n_par {
            let mode_k = k / 2;
            for c in 0..pm {
                let dk = k * pm + c;
                let col_k = mode_k * pm + c;
                jtr[k] -= z[(dk, col_k)];
                for l in 0..n_par {
                    let mode_l = l / 2;
                    for c2 in 0..pm {
                        let dl = l * pm + c2;
                        jtj[(k, l)] += g[(dk, dl)] * t[(col_k, mode_l * pm + c2)];
                    }
                }
            }
        }
        for (u, unit) in block.units.iter().enumerate() {
            let scale = block.unit_scale(u);
            for &pair in unit {
                for c in 0..n_col {
                    coefficients[(c, pair)] = theta_b[(c, u)] / scale;
                }
            }
        }
    }
    Ok(Outcome::Ready(Evaluation {
        cost,
        jtj,
        jtr,
        coefficients,
    }))
}
