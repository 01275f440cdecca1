//! The naive reference of the fit: the variable-projection residual `r(θ) = y − Φ(θ)c(θ)`
//! as one long vector, each unit's coefficients by its own dense least-squares solve, and
//! the Jacobian by central differences of `r` (so the full Golub–Pereyra Jacobian, not
//! Kaufman's). Slow, simple, and a check of every index in [`super::varpro`].

use super::model::{basis, Problem};
use super::varpro::{Evaluation, Need, Outcome, DEFICIENT_COLUMN};
use crate::error::Result;
use faer::linalg::solvers::SolveLstsq;
use faer::Mat;

/// The residual vector and the coefficients, or the outcome that stops the fit.
type Projected = std::result::Result<(Vec<f64>, Mat<f64>), Outcome>;

/// `r(θ)` and the coefficients (`columns × pairs`), or the deficient column.
fn residual(problem: &Problem, theta: &[f64]) -> Result<Projected> {
    let poles = problem.parameters.poles(theta);
    let layout = &problem.layout;
    let n_col = layout.columns(poles.len());
    let phi = basis(layout, &problem.omega, &poles);
    let mut r = Vec::new();
    let mut coefficients = Mat::<f64>::zeros(n_col, problem.outputs * problem.inputs);
    for block in &problem.blocks {
        let phi_b = block.stack(&phi);
        for (u, unit) in block.units.iter().enumerate() {
            let qr = phi_b.qr();
            let rr = qr.thin_R();
            for c in 0..n_col {
                let diagonal = rr[(c, c)].abs();
                if diagonal.is_nan() || diagonal <= DEFICIENT_COLUMN * phi_b.col(c).norm_l2() {
                    let pm = layout.per_mode;
                    return Ok(Err(Outcome::Deficient {
                        column: c,
                        mode: (c < poles.len() * pm).then_some(c / pm),
                    }));
                }
            }
            let y = Mat::from_fn(phi_b.nrows(), 1, |i, _| block.rhs[(i, u)]);
            let c = qr.solve_lstsq(&y);
            let fitted = &phi_b * &c;
            r.extend((0..y.nrows()).map(|i| y[(i, 0)] - fitted[(i, 0)]));
            let scale = block.unit_scale(u);
            for &pair in unit {
                for k in 0..n_col {
                    coefficients[(k, pair)] = c[(k, 0)] / scale;
                }
            }
        }
    }
    Ok(Ok((r, coefficients)))
}

/// Cost, finite-difference normal matrix, gradient and coefficients at `theta`.
pub(crate) fn evaluate(problem: &Problem, theta: &[f64], need: Need<'_>) -> Result<Outcome> {
    let jacobian = !matches!(need, Need::Cost);
    let (r0, coefficients) = match residual(problem, theta)? {
        Ok(x) => x,
        Err(outcome) => return Ok(outcome),
    };
    let n_par = if jacobian { theta.len() } else { 0 };
    let mut jac = Mat::<f64>::zeros(r0.len(), n_par);
    for k in 0..n_par {
        let h = 1e-6 * theta[k].abs().max(1.0);
        let mut plus = theta.to_vec();
        let mut minus = theta.to_vec();
        plus[k] += h;
        minus[k] -= h;
        let (Ok((rp, _)), Ok((rm, _))) = (residual(problem, &plus)?, residual(problem, &minus)?)
        else {
            // A neighbour is degenerate: fall back to the one-sided difference.
            let Ok((rp, _)) = residual(problem, &plus)? else {
                continue;
            };
            for i in 0..r0.len() {
                jac[(i, k)] = (rp[i] - r0[i]) / h;
            }
            continue;
        };
        for i in 0..r0.len() {
            jac[(i, k)] = (rp[i] - rm[i]) / (2.0 * h);
        }
    }
    let rv = Mat::from_fn(r0.len(), 1, |i, _| r0[i]);
    let jtj = jac.transpose() * &jac;
    let jtr_m = jac.transpose() * &rv;
    Ok(Outcome::Ready(Evaluation {
        cost: r0.iter().map(|x| x * x).sum::<f64>()
            + problem.blocks.iter().map(|b| b.cost_offset).sum::<f64>(),
        jtj,
        jtr: (0..n_par).map(|k| jtr_m[(k, 0)]).collect(),
        coefficients,
        kept: None,
    }))
}
