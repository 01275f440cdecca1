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
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};

/// Relative size of `|R_cc|` to the column norm below which a column is taken as a
/// combination of the others (a pole coalesced with another).
pub(crate) const DEFICIENT_COLUMN: f64 = 1e-11;

/// `A = QR` (thin) by Householder reflections, on the calling thread.
fn thin_qr(a: Mat<f64>) -> (Mat<f64>, Mat<f64>) {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::{householder, qr::no_pivoting::factor};
    let (m, n) = a.shape();
    let size = m.min(n);
    let mut qr = a;
    let block = factor::recommended_block_size::<f64>(m, n);
    let mut coeff = Mat::<f64>::zeros(block, size);
    factor::qr_in_place(
        qr.as_mut(),
        coeff.as_mut(),
        Par::Seq,
        MemStack::new(&mut MemBuffer::new(factor::qr_in_place_scratch::<f64>(
            m,
            n,
            block,
            Par::Seq,
            Default::default(),
        ))),
        Default::default(),
    );
    let r = Mat::from_fn(size, n, |i, j| if i <= j { qr[(i, j)] } else { 0.0 });
    let mut q = Mat::<f64>::identity(m, size);
    householder::apply_block_householder_sequence_on_the_left_in_place_with_conj(
        qr.as_ref(),
        coeff.as_ref(),
        faer::Conj::No,
        q.as_mut(),
        Par::Seq,
        MemStack::new(&mut MemBuffer::new(
            householder::apply_block_householder_sequence_on_the_left_in_place_scratch::<f64>(
                m, block, size,
            ),
        )),
    );
    (q, r)
}

/// `Aᵀ B` on the calling thread.
fn at_b(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::<f64>::zeros(a.ncols(), b.ncols());
    matmul(
        out.as_mut(),
        Accum::Replace,
        a.transpose(),
        b,
        1.0,
        Par::Seq,
    );
    out
}

/// Cost, Kaufman normal matrix, gradient and coefficients at `theta`; with `jacobian`
/// false only the cost and the coefficients.
///
/// The products run on the calling thread, side by side under `rayon::join`: at this
/// size (1602 × 82 for the 8 × 8 set) splitting each product across threads costs more
/// in synchronisation than it saves. `E = D − Q(QᵀD)` is formed: `DᵀD − (QᵀD)ᵀ(QᵀD)`
/// would cancel as the fit converges.
pub(crate) fn evaluate(problem: &Problem, theta: &[f64], jacobian: bool) -> Result<Outcome> {
    let poles = problem.parameters.poles(theta);
    let layout = &problem.layout;
    let pm = layout.per_mode;
    let n_par = theta.len();
    let n_col = layout.columns(poles.len());
    let (phi, deriv) = rayon::join(
        || basis(layout, &problem.omega, &poles),
        || jacobian.then(|| basis_derivatives(layout, problem.parameters, &problem.omega, &poles)),
    );
    let n_jac = if jacobian { n_par } else { 0 };
    let mut jtj = Mat::<f64>::zeros(n_jac, n_jac);
    let mut jtr = vec![0.0; n_jac];
    let mut cost = 0.0;
    let pairs = problem.outputs * problem.inputs;
    let mut coefficients = Mat::<f64>::zeros(n_col, pairs);
    for block in &problem.blocks {
        let phi_b = block.stack(&phi);
        let mut norms = vec![0.0; n_col];
        for (c, norm) in norms.iter_mut().enumerate() {
            *norm = phi_b.col(c).norm_l2();
        }
        let d_b = deriv.as_ref().map(|d| block.stack(d));
        let (q, r) = thin_qr(phi_b);
        for (c, &norm) in norms.iter().enumerate() {
            let diagonal = r[(c, c)].abs();
            if diagonal.is_nan() || diagonal <= DEFICIENT_COLUMN * norm {
                return Ok(Outcome::Deficient {
                    column: c,
                    mode: (c < poles.len() * pm).then_some(c / pm),
                });
            }
        }
        let (qty, x) = rayon::join(
            || at_b(q.as_ref(), block.rhs.as_ref()),
            || d_b.as_ref().map(|d| at_b(q.as_ref(), d.as_ref())),
        );
        let mut theta_b = qty.clone();
        r.solve_upper_triangular_in_place(&mut theta_b);
        let mut res = block.rhs.clone();
        matmul(
            res.as_mut(),
            Accum::Add,
            q.as_ref(),
            qty.as_ref(),
            -1.0,
            Par::Seq,
        );
        cost += res.squared_norm_l2() + block.cost_offset;
        for (u, unit) in block.units.iter().enumerate() {
            let scale = block.unit_scale(u);
            for &pair in unit {
                for c in 0..n_col {
                    coefficients[(c, pair)] = theta_b[(c, u)] / scale;
                }
            }
        }
        let (Some(mut e), Some(x)) = (d_b, x) else {
            continue;
        };
        // E = P⊥D, formed: DᵀD − XᵀX would cancel as the fit converges.
        matmul(
            e.as_mut(),
            Accum::Add,
            q.as_ref(),
            x.as_ref(),
            -1.0,
            Par::Seq,
        );
        let (g, dtr) = rayon::join(
            || at_b(e.as_ref(), e.as_ref()),
            || at_b(e.as_ref(), res.as_ref()),
        );
        let mut z = Mat::<f64>::zeros(dtr.nrows(), theta_b.nrows());
        matmul(
            z.as_mut(),
            Accum::Replace,
            dtr.as_ref(),
            theta_b.transpose(),
            1.0,
            Par::Seq,
        );
        let mut t = Mat::<f64>::zeros(n_col, n_col);
        matmul(
            t.as_mut(),
            Accum::Replace,
            theta_b.as_ref(),
            theta_b.transpose(),
            1.0,
            Par::Seq,
        );
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
    }
    Ok(Outcome::Ready(Evaluation {
        cost,
        jtj,
        jtr,
        coefficients,
    }))
}
