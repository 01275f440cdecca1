//! The free stage, shared by the fast and the naive evaluation: start poles, its steps
//! under [`super::lm::descend`], the dropping of modes that collapse or coalesce, and
//! the result with its uncertainties (the rank-one stage, when it follows, starts from
//! this fit).

use super::lm::{
    descend, limit_step, marquardt_step, normalise, Geometric, LeastSquares, Trial, EXACT_FIT,
    STATISTICAL_STOP,
};
use super::model::{basis, Problem, ResidualKind};
use super::uncertainty::mode_std;
use super::varpro::{Evaluation, Evaluator, Need, Outcome};
use super::{RefineOptions, RefinedMode, Refinement};
use crate::data::frf::FrfData;
use crate::error::{EraError, Result};
use faer::linalg::solvers::DenseSolveCore;
use faer::Mat;
use num_complex::Complex64;
use std::f64::consts::PI;

/// A mode whose share of the band's FRF norm falls below this has collapsed.
pub const MIN_CONTRIBUTION: f64 = 1e-10;
/// Two poles closer than this, relative to their modulus, have coalesced.
pub const COALESCED: f64 = 1e-9;
/// The active modes: their start indices and parameters.
struct State {
    ids: Vec<usize>,
    theta: Vec<f64>,
}

impl State {
    fn drop_mode(&mut self, m: usize, reason: String, dropped: &mut Vec<(usize, String)>) {
        dropped.push((self.ids[m], reason));
        self.ids.remove(m);
        self.theta.drain(2 * m..2 * m + 2);
    }
}

fn invalid(name: &'static str, value: String, reason: impl Into<String>) -> EraError {
    EraError::InvalidParameter {
        name,
        value,
        reason: reason.into().into(),
    }
}

/// Start poles into the upper half plane (and the left one when stability is enforced);
/// real poles and duplicates are dropped.
fn start_poles(
    start: &[Complex64],
    options: &RefineOptions,
    dropped: &mut Vec<(usize, String)>,
) -> Result<(Vec<usize>, Vec<Complex64>)> {
    if start.is_empty() {
        return Err(invalid(
            "start poles",
            "none".into(),
            "refinement needs at least one start pole",
        ));
    }
    let mut ids = Vec::new();
    let mut poles: Vec<Complex64> = Vec::new();
    for (k, &s0) in start.iter().enumerate() {
        if !(s0.re.is_finite() && s0.im.is_finite()) {
            return Err(invalid(
                "start poles",
                format!("{s0}"),
                format!("start pole {k} is not finite"),
            ));
        }
        let mut s = if s0.im < 0.0 { s0.conj() } else { s0 };
        if s.im <= 1e-8 * s.norm() || s.norm() == 0.0 {
            dropped.push((
                k,
                format!("a real pole ({:.6e} rad/s) is not a vibration mode", s.re),
            ));
            continue;
        }
        if options.enforce_stability && s.re >= 0.0 {
            // Reflect an unstable start pole; one on the axis gets ζ = 1e-4.
            s.re = if s.re > 0.0 { -s.re } else { -1e-4 * s.im };
        }
        if let Some(other) = poles
            .iter()
            .position(|p| (p - s).norm() <= COALESCED * s.norm())
        {
            // Named by frequency: after added poles (`Refinement::added`) the index
            // of this round's pole list is not the caller's.
            dropped.push((
                k,
                format!(
                    "a duplicate of the start pole at {:.6} Hz",
                    poles[other].norm() / (2.0 * PI)
                ),
            ));
            continue;
        }
        ids.push(k);
        poles.push(s);
    }
    Ok((ids, poles))
}

/// A mode of an earlier rank-one fit: its pole and residue.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Warm<'a> {
    pub pole: Complex64,
    pub residue: &'a [Complex64],
}

/// Runs the fit with `evaluate` (fast or naive). `warm[k]`, where given, is start pole
/// `k` as an earlier rank-one fit left it: the rank-one stage starts that mode from
/// there rather than from this fit's free one (which moved its pole to suit a free
/// residue). `placed` says that the start poles are a free fit's to the same data (with
/// other weights): where the rank-one stage follows, which moves every pole again, the
/// free stage then takes no step.
pub(crate) fn run(
    frf: &FrfData,
    start: &[Complex64],
    warm: &[Option<Warm>],
    placed: bool,
    options: &RefineOptions,
    progress: &mut dyn FnMut(usize, f64),
    evaluate: Evaluator,
) -> Result<Refinement> {
    let problem = Problem::new(frf, options)?;
    let mut dropped = Vec::new();
    let (ids, poles) = start_poles(start, options, &mut dropped)?;
    problem.check_size(poles.len())?;
    let mut state = State {
        theta: problem.parameters.theta(&poles),
        ids,
    };
    let weighted_norm2: f64 = problem
        .blocks
        .iter()
        .map(|b| b.rhs.squared_norm_l2() + b.cost_offset)
        .sum();
    // A fit of no iterations needs the Jacobian only for the standard deviations, and a
    // fit whose poles are placed and that the rank-one stage follows not at all: it
    // takes no free iteration, and the rank-one stage gives the deviations (a fit with
    // fewer modes after the settling is still within its size).
    let placed_for_rank_one = placed && super::rank_one::will_run(&problem, state.ids.len());
    let jacobian =
        (options.max_iterations > 0 || options.standard_deviations) && !placed_for_rank_one;
    let current = settle(&problem, &mut state, evaluate, &mut dropped, jacobian)?;
    let cost_before = current.cost;
    let fit_before = fit_of(&problem, &state.theta, &current.coefficients);
    progress(0, current.cost);
    // Where the rank-one stage follows, the free fit is only its start: that stage moves
    // every pole again, to its own tolerance.
    let rank_one_follows = super::rank_one::will_run(&problem, state.ids.len());
    let free_tolerance = if rank_one_follows {
        options.tolerance.max(super::START_TOLERANCE)
    } else {
        options.tolerance
    };
    let mut stage = FreeStage {
        problem: &problem,
        state,
        current,
        evaluate,
        dropped,
        progress,
        weighted_norm2,
        tolerance: free_tolerance,
    };
    let (iterations, converged) = if placed && rank_one_follows {
        (0, true)
    } else {
        descend(&mut stage, &mut Geometric::new(), options.max_iterations)?
    };
    let FreeStage {
        state,
        mut current,
        dropped,
        ..
    } = stage;
    // The factors a cost-only evaluation keeps serve an accepted step, and no step follows.
    current.kept = None;
    finish(
        &problem,
        state,
        current,
        dropped,
        warm,
        Summary {
            iterations,
            converged,
            cost_before,
            fit_before,
            max_iterations: options.max_iterations,
            tolerance: options.tolerance,
        },
    )
}

/// The free stage as [`descend`] drives it: the active modes, the evaluation at their
/// point, and the modes dropped so far.
struct FreeStage<'p, 'f> {
    problem: &'p Problem,
    state: State,
    current: Evaluation,
    evaluate: Evaluator,
    dropped: Vec<(usize, String)>,
    progress: &'f mut dyn FnMut(usize, f64),
    /// The (weighted) data's squared norm.
    weighted_norm2: f64,
    /// Relative decrease that ends the fit.
    tolerance: f64,
}

impl LeastSquares for FreeStage<'_, '_> {
    fn exact(&self) -> bool {
        self.current.cost <= EXACT_FIT * self.weighted_norm2
    }

    fn step(&mut self, lambda: f64) -> Option<Vec<f64>> {
        marquardt_step(&self.current.jtj, &self.current.jtr, lambda)
    }

    fn attempt(&mut self, step: Vec<f64>, iteration: usize) -> Result<Trial> {
        let (problem, evaluate) = (self.problem, self.evaluate);
        let step = limit_step(step, &self.state.theta, problem.parameters.log_damping);
        let mut trial = self.state.theta.clone();
        for (t, d) in trial.iter_mut().zip(&step) {
            *t += d;
        }
        normalise(&mut trial);
        let outcome = if trial.iter().all(|t| t.is_finite()) {
            Some(evaluate(problem, &trial, Need::Cost)?)
        } else {
            None
        };
        match outcome {
            Some(Outcome::Ready(next)) if next.cost < self.current.cost => {
                let decrease = self.current.cost - next.cost;
                let relative = decrease / self.current.cost;
                self.state.theta = trial;
                // The trial was evaluated without its Jacobian; the accepted point needs it.
                let accepted =
                    match evaluate(problem, &self.state.theta, Need::JacobianAfter(&next))? {
                        Outcome::Ready(e) => e,
                        Outcome::Deficient { .. } => {
                            return Err(EraError::Numerical(
                                "the basis was deficient at a point that was not a moment before"
                                    .into(),
                            ))
                        }
                    };
                // The trial's kept factors are spent.
                drop(next);
                let before_checks = self.state.ids.len();
                self.current = settle_ready(
                    problem,
                    &mut self.state,
                    accepted,
                    evaluate,
                    &mut self.dropped,
                    true,
                )?;
                (self.progress)(iteration, self.current.cost);
                // The free stage's rule takes no gain ratio.
                if self.state.ids.len() != before_checks {
                    return Ok(Trial::Lower {
                        rho: f64::NAN,
                        restart: true,
                        converged: false,
                    });
                }
                // A decrease below a hundredth of one noise unit `σ²` moves the
                // parameters by about a tenth of their standard deviation or less: the
                // rest is noise (module doc, "Stopping").
                let noise_unit = problem
                    .degrees_of_freedom(self.state.theta.len())
                    .map_or(0.0, |dof| self.current.cost / dof as f64);
                Ok(Trial::Lower {
                    rho: f64::NAN,
                    restart: false,
                    converged: relative <= self.tolerance
                        || decrease <= STATISTICAL_STOP * noise_unit,
                })
            }
            Some(Outcome::Deficient { mode: Some(m), .. }) => {
                // The step drives two poles onto each other: drop the one it names.
                let s = problem.parameters.pole(&trial, m);
                self.state.drop_mode(
                    m,
                    format!(
                        "its pole coalesced with another at {:.6} Hz",
                        s.norm() / (2.0 * PI)
                    ),
                    &mut self.dropped,
                );
                self.current = settle(problem, &mut self.state, evaluate, &mut self.dropped, true)?;
                Ok(Trial::Restart)
            }
            _ => Ok(Trial::Higher),
        }
    }
}

struct Summary {
    iterations: usize,
    converged: bool,
    cost_before: f64,
    fit_before: f64,
    max_iterations: usize,
    tolerance: f64,
}

/// Evaluates, dropping the modes that make the basis deficient, then checks for
/// collapse.
fn settle(
    problem: &Problem,
    state: &mut State,
    evaluate: Evaluator,
    dropped: &mut Vec<(usize, String)>,
    jacobian: bool,
) -> Result<Evaluation> {
    loop {
        crate::cancel::check()?;
        if state.ids.is_empty() {
            return Err(invalid(
                "start poles",
                format!("{} dropped", dropped.len()),
                format!(
                    "every start pole was dropped: {}",
                    dropped
                        .iter()
                        .map(|(k, why)| format!("pole {k}: {why}"))
                        .collect::<Vec<_>>()
                        .join("; ")
                ),
            ));
        }
        let need = if jacobian { Need::Jacobian } else { Need::Cost };
        match evaluate(problem, &state.theta, need)? {
            Outcome::Ready(e) => {
                return settle_ready(problem, state, e, evaluate, dropped, jacobian)
            }
            Outcome::Deficient { mode: Some(m), .. } => {
                let s = problem.parameters.pole(&state.theta, m);
                state.drop_mode(
                    m,
                    format!(
                        "its pole coalesced with another at {:.6} Hz",
                        s.norm() / (2.0 * PI)
                    ),
                    dropped,
                );
            }
            Outcome::Deficient { column, mode: None } => {
                return Err(EraError::Numerical(format!(
                "the residual term in basis column {column} is a combination of the modes' columns"
            )))
            }
        }
    }
}

/// Drops collapsed, coalesced or real modes of a ready evaluation, re-evaluating after.
fn settle_ready(
    problem: &Problem,
    state: &mut State,
    e: Evaluation,
    evaluate: Evaluator,
    dropped: &mut Vec<(usize, String)>,
    jacobian: bool,
) -> Result<Evaluation> {
    let poles = problem.parameters.poles(&state.theta);
    let contributions: Vec<f64> = contributions(problem, &poles, &e.coefficients)
        .into_iter()
        .map(|c| c.0)
        .collect();
    let mut victim: Option<(usize, String)> = None;
    for (m, s) in poles.iter().enumerate() {
        if s.im <= 1e-8 * s.norm() {
            victim = Some((m, "its pole became real".into()));
            break;
        }
        if contributions[m].is_nan() || contributions[m] < MIN_CONTRIBUTION {
            victim = Some((
                m,
                format!(
                    "its contribution collapsed to {:.2e} of the data at {:.6} Hz",
                    contributions[m],
                    s.norm() / (2.0 * PI)
                ),
            ));
            break;
        }
        if let Some(o) = (0..m).find(|&o| (poles[o] - s).norm() <= COALESCED * s.norm()) {
            let weaker = if contributions[o] < contributions[m] {
                o
            } else {
                m
            };
            victim = Some((
                weaker,
                format!(
                    "its pole coalesced with another at {:.6} Hz",
                    s.norm() / (2.0 * PI)
                ),
            ));
            break;
        }
    }
    match victim {
        None => Ok(e),
        Some((m, why)) => {
            state.drop_mode(m, why, dropped);
            settle(problem, state, evaluate, dropped, jacobian)
        }
    }
}

/// Per mode, `‖Σ_pairs mode FRF‖ / ‖data‖` over the band (unweighted), and its
/// weighted energy `Σ_pairs w²‖mode FRF‖²` (NaN when the weights vary by line).
///
/// A pair's energy `‖Φ_r c‖²` is `cᵀ (Φ_rᵀ Φ_r) c` with the mode's `pm × pm` Gram, formed
/// once: the mode's FRF itself (lines × pairs, 0.8 MB on a thesis-size set) was formed
/// and freed for each mode at every evaluation the fit settles, 3 ms a time.
fn contributions(
    problem: &Problem,
    poles: &[Complex64],
    coefficients: &Mat<f64>,
) -> Vec<(f64, f64)> {
    let phi = basis(&problem.layout, &problem.omega, poles);
    let pm = problem.layout.per_mode;
    let norm = problem.data_norm2.sqrt();
    (0..poles.len())
        .map(|r| {
            let cols = phi.subcols(r * pm, pm);
            let gram = cols.transpose() * cols;
            let coef = coefficients.subrows(r * pm, pm);
            let energy = |pair: usize| {
                let c = coef.col(pair);
                let e: f64 = (0..pm)
                    .map(|a| c[a] * (0..pm).map(|b| gram[(a, b)] * c[b]).sum::<f64>())
                    .sum();
                // Round-off can take a vanishing energy below zero; NaN stays NaN.
                if e < 0.0 {
                    0.0
                } else {
                    e
                }
            };
            let energies: Vec<f64> = (0..coef.ncols()).map(energy).collect();
            let total: f64 = energies.iter().sum();
            let weighted = problem.pair_weights.as_ref().map_or(f64::NAN, |w| {
                energies
                    .iter()
                    .enumerate()
                    .map(|(pair, e)| w[pair] * w[pair] * e)
                    .sum()
            });
            (total.sqrt() / norm, weighted)
        })
        .collect()
}

/// `‖G − Ĝ‖/‖G‖` over the band, unweighted.
fn fit_of(problem: &Problem, theta: &[f64], coefficients: &Mat<f64>) -> f64 {
    let poles = problem.parameters.poles(theta);
    let model = basis(&problem.layout, &problem.omega, &poles) * coefficients;
    let nl = problem.omega.len();
    let mut err = 0.0;
    for (pair, data) in problem.data.iter().enumerate() {
        for (k, g) in data.iter().enumerate() {
            err += (g - Complex64::new(model[(k, pair)], model[(nl + k, pair)])).norm_sqr();
        }
    }
    (err / problem.data_norm2).sqrt()
}

fn finish(
    problem: &Problem,
    mut state: State,
    mut e: Evaluation,
    dropped: Vec<(usize, String)>,
    warm: &[Option<Warm>],
    mut summary: Summary,
) -> Result<Refinement> {
    let (q, p) = (problem.outputs, problem.inputs);
    let layout = &problem.layout;
    let pm = layout.per_mode;
    let joint = if problem.rank_one_follows() {
        let warm: Vec<Option<Warm>> = state
            .ids
            .iter()
            .map(|&k| warm.get(k).copied().flatten())
            .collect();
        let mut poles = problem.parameters.poles(&state.theta);
        for (s, w) in poles.iter_mut().zip(&warm) {
            if let Some(w) = w {
                *s = w.pole;
            }
        }
        let theta = problem.parameters.theta(&poles);
        super::rank_one::fit(
            problem,
            &theta,
            &e.coefficients,
            &warm
                .iter()
                .map(|w| w.map(|w| w.residue))
                .collect::<Vec<_>>(),
            summary.max_iterations,
            summary.tolerance,
        )?
    } else {
        None
    };
    let rank_one = joint.is_some();
    let (noise_variance, covariance) = match joint {
        Some(j) => {
            state.theta = j.theta;
            e.coefficients = j.coefficients;
            e.cost = j.cost;
            summary.iterations += j.iterations;
            summary.converged &= j.converged;
            (j.noise_variance, j.covariance)
        }
        None => {
            let noise_variance = problem
                .degrees_of_freedom(state.theta.len())
                .map_or(f64::NAN, |dof| e.cost / dof as f64);
            // Without the Jacobian (a fit read for its cost alone), no deviations.
            let formed = e.jtj.nrows() == state.theta.len();
            let covariance = formed.then(|| covariance(&e.jtj, noise_variance)).flatten();
            (noise_variance, covariance)
        }
    };
    let poles = problem.parameters.poles(&state.theta);
    let n_modes = poles.len();
    let contributions = contributions(problem, &poles, &e.coefficients);
    // A mode's free parameters: its pole, and its residue's: a shape and a
    // participation (`u vᵀ`, one complex scale fixed) or `ψψᵀ`; or a free matrix of `pm`
    // reals per independent entry (the pairs `(i, j)` and `(j, i)` share one when
    // reciprocal).
    let entries = if problem.reciprocal {
        q * (q + 1) / 2
    } else {
        q * p
    };
    let mode_parameters = 2 + match (rank_one, problem.reciprocal) {
        (true, false) => 2 * (q + p) - 2,
        (true, true) => 2 * q,
        (false, _) => pm * entries,
    };
    let mut modes: Vec<RefinedMode> = poles
        .iter()
        .enumerate()
        .map(|(r, &s)| {
            let residue = (0..q * p)
                .map(|pair| {
                    if pm == 2 {
                        Complex64::new(
                            e.coefficients[(2 * r, pair)],
                            e.coefficients[(2 * r + 1, pair)],
                        )
                    } else {
                        Complex64::new(0.0, e.coefficients[(r, pair)])
                    }
                })
                .collect();
            let block = covariance.as_ref().map(|c| {
                [
                    [c[(2 * r, 2 * r)], c[(2 * r, 2 * r + 1)]],
                    [c[(2 * r + 1, 2 * r)], c[(2 * r + 1, 2 * r + 1)]],
                ]
            });
            let (frequency_std_hz, damping_ratio_std) = match block {
                Some(b) => mode_std(s, problem.parameters, b),
                None => (f64::NAN, f64::NAN),
            };
            RefinedMode {
                pole: s,
                frequency_hz: s.norm() / (2.0 * PI),
                damping_ratio: -s.re / s.norm(),
                residue,
                frequency_std_hz,
                damping_ratio_std,
                contribution: contributions[r].0,
                significance: contributions[r].1 / (noise_variance * mode_parameters as f64),
                start: state.ids[r],
            }
        })
        .collect();
    modes.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    let mut lower = None;
    let mut upper = None;
    for (m, &(kind, _)) in layout.residuals.iter().enumerate() {
        let row = n_modes * pm + m;
        let mat = Mat::from_fn(q, p, |i, j| e.coefficients[(row, i * p + j)]);
        match kind {
            ResidualKind::Lower => lower = Some(mat),
            ResidualKind::Upper => upper = Some(mat),
        }
    }
    let mut dropped = dropped;
    dropped.sort_by_key(|d| d.0);
    Ok(Refinement {
        fit_after: fit_of(problem, &state.theta, &e.coefficients),
        modes,
        lower,
        upper,
        dropped,
        added: Vec::new(),
        iterations: summary.iterations,
        converged: summary.converged,
        cost_before: summary.cost_before,
        cost_after: e.cost,
        fit_before: summary.fit_before,
        noise_variance,
        quantity: problem.quantity,
        outputs: q,
        inputs: p,
        band: problem.band,
        sample_time_s: problem.layout.sample_time_s,
        rank_one,
    })
}

/// `σ² (JᵀJ)⁻¹`, or `None` when it is not finite.
fn covariance(jtj: &Mat<f64>, noise_variance: f64) -> Option<Mat<f64>> {
    if !noise_variance.is_finite() {
        return None;
    }
    let inv = jtj.partial_piv_lu().inverse();
    let cov = Mat::from_fn(inv.nrows(), inv.ncols(), |i, j| {
        noise_variance * inv[(i, j)]
    });
    (0..cov.nrows())
        .all(|i| (0..cov.ncols()).all(|j| cov[(i, j)].is_finite()))
        .then_some(cov)
}
