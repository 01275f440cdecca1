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

use super::model::{basis, basis_derivatives, Problem};
use crate::error::Result;
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};

/// What an evaluation of the projected functional gives.
pub(crate) struct Evaluation {
    /// `‖r‖²`, weighted.
    pub cost: f64,
    /// `JᵀJ` over the pole parameters.
    pub jtj: Mat<f64>,
    /// `Jᵀr`.
    pub jtr: Vec<f64>,
    /// Linear coefficients, `columns × pairs`.
    pub coefficients: Mat<f64>,
    /// What a cost-only evaluation of the fast path keeps for the Jacobian at the same
    /// point ([`Need::JacobianAfter`]).
    pub kept: Option<Kept>,
}

/// An evaluation, or the column of the basis that is a combination of the others.
pub(crate) enum Outcome {
    Ready(Evaluation),
    Deficient { column: usize, mode: Option<usize> },
}

/// What an evaluation must give.
#[derive(Clone, Copy)]
pub(crate) enum Need<'a> {
    /// The cost and the coefficients only (`jtj` and `jtr` empty): a trial step that
    /// may be rejected.
    Cost,
    /// Everything.
    Jacobian,
    /// Everything, at the point of this cost-only evaluation: the fast path starts from
    /// the factorisations it kept, so an accepted trial costs no second QR.
    JacobianAfter(&'a Evaluation),
}

/// `evaluate(problem, θ, need)`.
pub(crate) type Evaluator = fn(&Problem, &[f64], Need<'_>) -> Result<Outcome>;

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

/// What a cost-only evaluation keeps so that the Jacobian at the same point needs no
/// second basis and QR: the point, and per block `Q`, `Θ` and the residual `P⊥Y`.
pub(crate) struct Kept {
    theta: Vec<f64>,
    blocks: Vec<Factored>,
}

/// One block's thin `Q`, coefficients `Θ = R⁻¹QᵀY` and residual `P⊥Y`.
struct Factored {
    q: Mat<f64>,
    theta: Mat<f64>,
    residual: Mat<f64>,
}

/// Most bytes of factors a cost-only evaluation keeps (8 × 8, 801 lines, 40 modes and one
/// shared basis: about 2 MB; with a basis per pair, 64 of those). Beyond, the accepted
/// point is factored again.
const KEEP_BYTES: usize = 256 << 20;

/// A column of the basis that is a combination of the others ([`Outcome::Deficient`]).
struct Deficient {
    column: usize,
    mode: Option<usize>,
}

/// `block`'s part of the basis `phi` factored: its cost, its factors, and its units'
/// coefficients written into `coefficients`; or the first deficient column.
fn factor_block(
    problem: &Problem,
    block: &super::model::Block,
    phi: &Mat<f64>,
    modes: usize,
    coefficients: &mut Mat<f64>,
) -> std::result::Result<(f64, Factored), Deficient> {
    let pm = problem.layout.per_mode;
    let n_col = phi.ncols();
    let phi_b = block.stack(phi);
    let norms: Vec<f64> = (0..n_col).map(|c| phi_b.col(c).norm_l2()).collect();
    let (q, r) = thin_qr(phi_b);
    for (c, &norm) in norms.iter().enumerate() {
        let diagonal = r[(c, c)].abs();
        if diagonal.is_nan() || diagonal <= DEFICIENT_COLUMN * norm {
            return Err(Deficient {
                column: c,
                mode: (c < modes * pm).then_some(c / pm),
            });
        }
    }
    let qty = at_b(q.as_ref(), block.rhs.as_ref());
    let mut theta_b = qty.clone();
    r.solve_upper_triangular_in_place(&mut theta_b);
    let mut residual = block.rhs.clone();
    matmul(
        residual.as_mut(),
        Accum::Add,
        q.as_ref(),
        qty.as_ref(),
        -1.0,
        Par::Seq,
    );
    let cost = residual.squared_norm_l2() + block.cost_offset;
    for (u, unit) in block.units.iter().enumerate() {
        let scale = block.unit_scale(u);
        for &pair in unit {
            for c in 0..n_col {
                coefficients[(c, pair)] = theta_b[(c, u)] / scale;
            }
        }
    }
    Ok((
        cost,
        Factored {
            q,
            theta: theta_b,
            residual,
        },
    ))
}

/// Block `f`'s part of the Kaufman normal matrix and gradient, added to `jtj` and `jtr`;
/// `deriv` the basis derivatives at the same point.
fn add_jacobian(
    problem: &Problem,
    block: &super::model::Block,
    f: &Factored,
    deriv: &Mat<f64>,
    jtj: &mut Mat<f64>,
    jtr: &mut [f64],
) {
    let pm = problem.layout.per_mode;
    let n_par = jtr.len();
    let n_col = f.theta.nrows();
    let mut e = block.stack(deriv);
    let x = at_b(f.q.as_ref(), e.as_ref());
    // E = P⊥D, formed: DᵀD − XᵀX would cancel as the fit converges.
    matmul(
        e.as_mut(),
        Accum::Add,
        f.q.as_ref(),
        x.as_ref(),
        -1.0,
        Par::Seq,
    );
    let (g, dtr) = rayon::join(
        || at_b(e.as_ref(), e.as_ref()),
        || at_b(e.as_ref(), f.residual.as_ref()),
    );
    let theta_b = &f.theta;
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

/// Cost, Kaufman normal matrix, gradient and coefficients at `theta`; with
/// [`Need::Cost`] only the cost and the coefficients, and the factors are kept (up to
/// [`KEEP_BYTES`]) for an accepted trial's [`Need::JacobianAfter`].
///
/// The products run on the calling thread, side by side under `rayon::join`: at this
/// size (1602 × 82 for the 8 × 8 set) splitting each product across threads costs more
/// in synchronisation than it saves. `E = D − Q(QᵀD)` is formed: `DᵀD − (QᵀD)ᵀ(QᵀD)`
/// would cancel as the fit converges.
pub(crate) fn evaluate(problem: &Problem, theta: &[f64], need: Need<'_>) -> Result<Outcome> {
    let poles = problem.parameters.poles(theta);
    let layout = &problem.layout;
    let n_par = theta.len();
    let n_col = layout.columns(poles.len());
    let pairs = problem.outputs * problem.inputs;
    let kept = match need {
        Need::JacobianAfter(e) => e
            .kept
            .as_ref()
            .filter(|k| k.theta == theta)
            .map(|k| (e, &k.blocks)),
        _ => None,
    };
    if let Some((e, blocks)) = kept {
        let deriv = basis_derivatives(layout, problem.parameters, &problem.omega, &poles);
        let mut jtj = Mat::<f64>::zeros(n_par, n_par);
        let mut jtr = vec![0.0; n_par];
        for (block, f) in problem.blocks.iter().zip(blocks) {
            add_jacobian(problem, block, f, &deriv, &mut jtj, &mut jtr);
        }
        return Ok(Outcome::Ready(Evaluation {
            cost: e.cost,
            jtj,
            jtr,
            coefficients: e.coefficients.clone(),
            kept: None,
        }));
    }
    let jacobian = !matches!(need, Need::Cost);
    let keep = !jacobian
        && problem
            .blocks
            .iter()
            .map(|b| 8 * (b.rhs.nrows() * (n_col + 2 * b.rhs.ncols()) + n_col * b.rhs.ncols()))
            .sum::<usize>()
            <= KEEP_BYTES;
    let (phi, deriv) = rayon::join(
        || basis(layout, &problem.omega, &poles),
        || jacobian.then(|| basis_derivatives(layout, problem.parameters, &problem.omega, &poles)),
    );
    let n_jac = if jacobian { n_par } else { 0 };
    let mut jtj = Mat::<f64>::zeros(n_jac, n_jac);
    let mut jtr = vec![0.0; n_jac];
    let mut cost = 0.0;
    let mut coefficients = Mat::<f64>::zeros(n_col, pairs);
    let mut factors = Vec::new();
    for block in &problem.blocks {
        let (cost_b, f) = match factor_block(problem, block, &phi, poles.len(), &mut coefficients) {
            Ok(x) => x,
            Err(Deficient { column, mode }) => return Ok(Outcome::Deficient { column, mode }),
        };
        cost += cost_b;
        if let Some(deriv) = &deriv {
            add_jacobian(problem, block, &f, deriv, &mut jtj, &mut jtr);
        } else if keep {
            factors.push(f);
        }
    }
    Ok(Outcome::Ready(Evaluation {
        cost,
        jtj,
        jtr,
        coefficients,
        kept: keep.then(|| Kept {
            theta: theta.to_vec(),
            blocks: factors,
        }),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::refine::{RefineOptions, Residuals};
    use crate::sim::{add_noise, ModalSpec, ModalStructure};
    use crate::Quantity;
    use num_complex::Complex64;

    fn ready(outcome: Outcome) -> Evaluation {
        match outcome {
            Outcome::Ready(e) => e,
            Outcome::Deficient { column, .. } => panic!("deficient column {column}"),
        }
    }

    #[test]
    fn an_accepted_trial_gives_the_jacobian_from_its_kept_factors() {
        let spec = ModalSpec {
            fmin_hz: 2.0,
            fmax_hz: 9.0,
            ..ModalSpec::new(2, 3, 4)
        };
        let s = ModalStructure::random(&spec).unwrap();
        let frf = add_noise(&s.frf(301, 0.025, Quantity::Velocity).unwrap(), 0.05, 5).unwrap();
        let options = RefineOptions {
            residuals: Residuals::Both,
            weighting: crate::refine::Weighting::Uniform,
            ..RefineOptions::default()
        };
        let problem = Problem::new(&frf, &options).unwrap();
        let poles: Vec<Complex64> = s.poles().iter().map(|s| 1.001 * s).collect();
        let theta = problem.parameters.theta(&poles);
        let trial = ready(evaluate(&problem, &theta, Need::Cost).unwrap());
        assert!(trial.kept.is_some());
        assert_eq!(trial.jtj.nrows(), 0);
        let after = ready(evaluate(&problem, &theta, Need::JacobianAfter(&trial)).unwrap());
        let fresh = ready(evaluate(&problem, &theta, Need::Jacobian).unwrap());
        // The same operations on the same factors: equal to the last bit.
        assert_eq!(after.cost, fresh.cost);
        assert_eq!(after.jtr, fresh.jtr);
        assert_eq!(after.jtj, fresh.jtj);
        assert_eq!(after.coefficients, fresh.coefficients);
        assert!(fresh.jtj.nrows() == theta.len() && fresh.jtr.iter().any(|g| *g != 0.0));
        // Factors kept at another point are not used.
        let mut moved = theta.clone();
        moved[1] *= 1.0 + 1e-3;
        let elsewhere = ready(evaluate(&problem, &moved, Need::JacobianAfter(&trial)).unwrap());
        let at_moved = ready(evaluate(&problem, &moved, Need::Jacobian).unwrap());
        assert_eq!(elsewhere.jtj, at_moved.jtj);
        assert_ne!(elsewhere.jtj, fresh.jtj);
    }
}
