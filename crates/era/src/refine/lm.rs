//! Levenberg–Marquardt for the free stage ([`super::fit`]) and the rank-one stage
//! ([`super::rank_one`]): one loop ([`descend`]) over a small problem trait
//! ([`LeastSquares`]) that both stages implement; the damped normal equations
//! `(N + λ diag N) δ = −g` (Marquardt's scaling), the per-mode limit on a step and the
//! stopping thresholds; and the two rules for `λ` behind one trait ([`Damping`]): the
//! free stage's ([`Geometric`]) and the rank-one stage's ([`Nielsen`]).

use crate::error::Result;
use faer::Mat;

/// What a trial step did.
pub(crate) enum Trial {
    /// It lowered the cost and the problem moved there: `rho` is its gain ratio (NaN
    /// where the problem has no prediction), `restart` says that the set of modes
    /// changed (`λ` starts again), `converged` that the decrease ends the fit.
    Lower {
        rho: f64,
        restart: bool,
        converged: bool,
    },
    /// The problem changed without a step (a mode dropped): `λ` starts again.
    Restart,
    /// It did not lower the cost.
    Higher,
}

/// A nonlinear least-squares problem at its current point, as [`descend`] drives it.
pub(crate) trait LeastSquares {
    /// Whether the current cost is an exact fit.
    fn exact(&self) -> bool;
    /// The step of the damped normal equations at `λ`, or `None` when they give none.
    fn step(&mut self, lambda: f64) -> Option<Vec<f64>>;
    /// Tries `step`, moving there when it lowers the cost; `iteration` is the number it
    /// then gets.
    fn attempt(&mut self, step: Vec<f64>, iteration: usize) -> Result<Trial>;
}

/// Levenberg–Marquardt: at most `max_iterations` accepted steps from the problem's
/// current point, `λ` moved by `damping`; the accepted steps and whether it converged
/// (an exact fit, a decrease the problem calls converged, or no step lowering the cost
/// at any `λ`).
pub(crate) fn descend(
    problem: &mut impl LeastSquares,
    damping: &mut impl Damping,
    max_iterations: usize,
) -> Result<(usize, bool)> {
    let mut iterations = 0;
    while iterations < max_iterations {
        crate::cancel::check()?;
        if problem.exact() {
            return Ok((iterations, true));
        }
        let Some(step) = problem.step(damping.lambda()) else {
            if damping.singular() {
                return Ok((iterations, false));
            }
            continue;
        };
        match problem.attempt(step, iterations + 1)? {
            Trial::Lower {
                rho,
                restart,
                converged,
            } => {
                iterations += 1;
                damping.accepted(rho);
                if restart {
                    damping.reset();
                } else if converged {
                    return Ok((iterations, true));
                }
            }
            Trial::Restart => damping.reset(),
            Trial::Higher => {
                if damping.rejected() {
                    // No step lowers the cost any more: a minimum to working precision.
                    return Ok((iterations, true));
                }
            }
        }
    }
    Ok((iterations, false))
}

/// Levenberg–Marquardt's `λ` and how it moves after each trial.
pub(crate) trait Damping {
    /// The current `λ`.
    fn lambda(&self) -> f64;
    /// After a step that lowered the cost, with gain ratio `rho` (actual over predicted
    /// decrease; a rule may not use it).
    fn accepted(&mut self, rho: f64);
    /// After a step that did not lower the cost; whether `λ` has grown past any use.
    fn rejected(&mut self) -> bool;
    /// After damped normal equations that gave no step; whether `λ` has grown past any
    /// use.
    fn singular(&mut self) -> bool;
    /// Starts again, for a problem whose modes changed.
    fn reset(&mut self);
}

/// `λ` at which both rules start, and to which the free stage returns when its set of
/// modes changes.
const START_LAMBDA: f64 = 1e-3;
/// `λ` beyond which no step can lower the cost any more.
const MAX_LAMBDA: f64 = 1e16;
/// Floor of `λ` after accepted steps.
const MIN_LAMBDA: f64 = 1e-15;

/// The free stage's rule: `λ/5` after an accepted step, `4λ` after a rejected one.
pub(crate) struct Geometric {
    lambda: f64,
}

impl Geometric {
    pub(crate) fn new() -> Self {
        Geometric {
            lambda: START_LAMBDA,
        }
    }
}

impl Damping for Geometric {
    fn lambda(&self) -> f64 {
        self.lambda
    }

    fn accepted(&mut self, _rho: f64) {
        self.lambda = (self.lambda / 5.0).max(MIN_LAMBDA);
    }

    fn rejected(&mut self) -> bool {
        self.singular()
    }

    fn singular(&mut self) -> bool {
        self.lambda *= 4.0;
        self.lambda > MAX_LAMBDA
    }

    fn reset(&mut self) {
        self.lambda = START_LAMBDA;
    }
}

/// The rank-one stage's rule: Nielsen's (1999) update of `λ` from the gain ratio
/// `ρ = actual / predicted decrease`, `λ·max(1/3, 1 − (2ρ − 1)³)` after an accepted step
/// and `λ·ν`, `ν ← 2ν` after a rejected one: no oscillation between accepted and
/// rejected steps.
pub(crate) struct Nielsen {
    lambda: f64,
    nu: f64,
}

impl Nielsen {
    pub(crate) fn new() -> Self {
        Nielsen {
            lambda: START_LAMBDA,
            nu: 2.0,
        }
    }
}

impl Damping for Nielsen {
    fn lambda(&self) -> f64 {
        self.lambda
    }

    fn accepted(&mut self, rho: f64) {
        self.lambda = (self.lambda * (1.0 / 3.0f64).max(1.0 - (2.0 * rho.min(1.0) - 1.0).powi(3)))
            .max(MIN_LAMBDA);
        self.nu = 2.0;
    }

    fn rejected(&mut self) -> bool {
        self.lambda *= self.nu;
        self.nu *= 2.0;
        self.lambda > MAX_LAMBDA
    }

    fn singular(&mut self) -> bool {
        self.lambda *= 4.0;
        self.lambda > MAX_LAMBDA
    }

    fn reset(&mut self) {
        *self = Nielsen::new();
    }
}

/// A step that lowers the cost by less than this many noise variances `σ̂²` ends the
/// fit.
pub(crate) const STATISTICAL_STOP: f64 = 1e-2;
/// Cost below this fraction of the (weighted) data's squared norm is an exact fit.
pub(crate) const EXACT_FIT: f64 = 1e-28;

/// Largest step of a mode's frequency, in units of its `σ` (half the half-power
/// bandwidth): the cost is far from quadratic beyond a resonance's width.
const MAX_FREQUENCY_STEP: f64 = 2.0;
/// Largest step of `ln σ` (a factor `e^0.7 ≈ 2` in damping).
const MAX_LOG_DAMPING_STEP: f64 = 0.7;

/// Shortens each mode's part of the step to the region where its linearisation holds,
/// so that one badly predicted mode does not force `λ` up for all.
pub(crate) fn limit_step(mut step: Vec<f64>, theta: &[f64], log_damping: bool) -> Vec<f64> {
    for r in 0..theta.len() / 2 {
        let sigma = if log_damping {
            theta[2 * r].exp()
        } else {
            theta[2 * r].abs()
        };
        let damping_step = if log_damping {
            step[2 * r].abs() / MAX_LOG_DAMPING_STEP
        } else {
            step[2 * r].abs() / (0.5 * sigma)
        };
        let frequency_step = step[2 * r + 1].abs() / (MAX_FREQUENCY_STEP * sigma);
        let worst = damping_step.max(frequency_step);
        if worst > 1.0 {
            step[2 * r] /= worst;
            step[2 * r + 1] /= worst;
        }
    }
    step
}

/// `ω_d < 0` is the conjugate pole: keep the representative with `Im s > 0`.
pub(crate) fn normalise(theta: &mut [f64]) {
    for r in 0..theta.len() / 2 {
        theta[2 * r + 1] = theta[2 * r + 1].abs();
    }
}

/// `(JᵀJ + λ diag JᵀJ) δ = −Jᵀr` (Marquardt's scaling, with a floor on the diagonal).
pub(crate) fn marquardt_step(jtj: &Mat<f64>, jtr: &[f64], lambda: f64) -> Option<Vec<f64>> {
    use faer::linalg::solvers::Solve;
    let m = damped(jtj, lambda)?;
    let rhs = Mat::from_fn(jtr.len(), 1, |k, _| -jtr[k]);
    let step = match m.llt(faer::Side::Lower) {
        Ok(llt) => llt.solve(&rhs),
        Err(_) => m.partial_piv_lu().solve(&rhs),
    };
    finite_column(&step)
}

/// `N + λ diag N`, each diagonal entry floored at 1e-14 of the largest (Marquardt's
/// scaling), or `None` when `N` has no positive finite diagonal.
pub(crate) fn damped(normal: &Mat<f64>, lambda: f64) -> Option<Mat<f64>> {
    let n = normal.nrows();
    let largest = (0..n).map(|k| normal[(k, k)]).fold(0.0, f64::max);
    if !(largest > 0.0 && largest.is_finite()) {
        return None;
    }
    let mut m = normal.clone();
    for k in 0..n {
        m[(k, k)] += lambda * normal[(k, k)].max(1e-14 * largest);
    }
    Some(m)
}

/// The column as a vector, or `None` when an entry is not finite.
pub(crate) fn finite_column(step: &Mat<f64>) -> Option<Vec<f64>> {
    let v: Vec<f64> = (0..step.nrows()).map(|k| step[(k, 0)]).collect();
    v.iter().all(|x| x.is_finite()).then_some(v)
}
