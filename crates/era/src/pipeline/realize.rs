//! Realization by singular value decomposition (docs/src/design.md §1.8–1.9; thesis `mimoera`,
//! Appendix J.1.3; Juang & Pappa, 1985).
//!
//! With `H0 = U S Vᵀ` and the `n` largest singular values kept, the balanced realization
//! is
//!
//! ```text
//! A = S_n^(-1/2) U_nᵀ H1 V_n S_n^(-1/2)
//! B = first p columns of S_n^(1/2) V_nᵀ
//! C = first q rows of U_n S_n^(1/2)
//! D = 0 (thesis) or Y_0
//! ```
//!
//! [`realize`] factors `H0` once at the order asked ([`crate::pipeline::factor`], dense or
//! truncated SVD) and realizes there, as a scan realizes each of its orders from one
//! [`Factorization`]; [`realize_naive`] forms the Hankels element by element, takes the
//! full SVD and multiplies with plain loops. It is the reference every faster path is
//! tested against.

use crate::data::statespace::{StateSpace, TimeDomain};
use crate::error::{EraError, Result};
use crate::pipeline::factor::{check_dense_svd, check_rank, general_h1, plan, Keep};
use crate::pipeline::hankel::{self, HankelShape};
use crate::sources::frf::MarkovSequence;
use faer::Mat;
use std::time::Instant;

pub use crate::pipeline::factor::{
    FactorOptions, Factorization, RealizeWarning, SvdPath, EXTRA_SINGULAR_VALUES,
};

/// What the model's `D` is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DirectTerm {
    /// `D = 0`, as in the thesis.
    #[default]
    Zero,
    /// `D = Y_0`, the time-zero Markov block.
    FirstMarkov,
}

/// Options of the realization step.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct RealizeOptions {
    /// Model order `n` (thesis `ns`).
    pub states: usize,
    /// Hankel factor `lh`: `M = ns·lh` Markov samples feed the Hankel.
    pub hankel_factor: usize,
    /// `D` of the model.
    pub direct_term: DirectTerm,
    /// Dense or matrix-free SVD.
    pub svd: SvdPath,
    /// Residual tolerance of the truncated SVD ([`crate::linalg::tsvd`]), relative to `σ₁`.
    pub svd_tolerance: f64,
}

impl RealizeOptions {
    /// Options with `D = 0`, automatic SVD path, tolerance 1e-12.
    pub fn new(states: usize, hankel_factor: usize) -> Self {
        RealizeOptions {
            states,
            hankel_factor,
            direct_term: DirectTerm::Zero,
            svd: SvdPath::Auto,
            svd_tolerance: 1e-12,
        }
    }
}

/// A realized model with its diagnostics.
#[derive(Debug, Clone)]
pub struct Realization {
    /// The discrete model, `Ts` that of the Markov sequence.
    pub model: StateSpace,
    /// Singular values of `H0`, largest first: all of them on the dense path, the
    /// `states` leading ones (those that passed the residual test) on the matrix-free
    /// path.
    pub singular_values: Vec<f64>,
    /// Rows and columns of `H0`.
    pub hankel_size: (usize, usize),
    /// Warnings of §1.8.
    pub warnings: Vec<RealizeWarning>,
    /// Wall time of the Hankel construction and SVD, s.
    pub hankel_svd_seconds: f64,
    /// Wall time of the products of §1.9, s.
    pub products_seconds: f64,
    /// The SVD path taken (never `Auto`).
    pub svd_path: SvdPath,
    /// Iterations of the truncated SVD (matrix-free path).
    pub svd_iterations: Option<usize>,
    /// The identified observability and controllability tails (for EMAC,
    /// [`crate::modal::indicators`]).
    pub tails: HankelTails,
}

/// The identified observability matrix `U_n S_n^(½)` and controllability matrix
/// `S_n^(½) V_nᵀ`: what the data says `[C; CA; CA²; …]` and `[B, AB, A²B, …]` are, block
/// row by block row. The model predicts each block from its eigenvalues; how well the
/// two agree is the extended modal amplitude coherence (EMAC,
/// [`crate::modal::indicators`]).
#[derive(Debug, Clone)]
pub struct HankelTails {
    /// `U_n S_n^(½)`, `(R·q) × n`.
    pub observability: Mat<f64>,
    /// `S_n^(½) V_nᵀ`, `n × (C·p)`.
    pub controllability: Mat<f64>,
    /// Outputs `q` (block height of `observability`).
    pub outputs: usize,
    /// Inputs `p` (block width of `controllability`).
    pub inputs: usize,
}

impl HankelTails {
    fn of(
        singular_values: &[f64],
        un: faer::MatRef<'_, f64>,
        vn: faer::MatRef<'_, f64>,
        outputs: usize,
        inputs: usize,
    ) -> Self {
        let n = singular_values.len();
        let root: Vec<f64> = singular_values.iter().map(|s| s.sqrt()).collect();
        HankelTails {
            observability: Mat::from_fn(un.nrows(), n, |i, r| un[(i, r)] * root[r]),
            controllability: Mat::from_fn(n, vn.nrows(), |r, j| root[r] * vn[(j, r)]),
            outputs,
            inputs,
        }
    }

    /// Block rows `R` of the observability matrix.
    pub fn block_rows(&self) -> usize {
        self.observability.nrows() / self.outputs.max(1)
    }

    /// Block columns `C` of the controllability matrix.
    pub fn block_cols(&self) -> usize {
        self.controllability.ncols() / self.inputs.max(1)
    }
}

/// What EMAC reads of the identified observability and controllability matrices
/// ([`crate::modal::indicators::emac`]): formed ([`HankelTails`]) or read from the
/// factors in place ([`FactorTails`]).
pub(crate) trait Tails {
    /// Outputs `q`.
    fn outputs(&self) -> usize;
    /// Inputs `p`.
    fn inputs(&self) -> usize;
    /// Block rows `R` of the observability matrix.
    fn block_rows(&self) -> usize;
    /// Block columns `C` of the controllability matrix.
    fn block_cols(&self) -> usize;
    /// Entry `(row, r)` of the observability matrix.
    fn observability(&self, row: usize, r: usize) -> f64;
    /// Entry `(r, col)` of the controllability matrix.
    fn controllability(&self, r: usize, col: usize) -> f64;
}

impl Tails for HankelTails {
    fn outputs(&self) -> usize {
        self.outputs
    }
    fn inputs(&self) -> usize {
        self.inputs
    }
    fn block_rows(&self) -> usize {
        HankelTails::block_rows(self)
    }
    fn block_cols(&self) -> usize {
        HankelTails::block_cols(self)
    }
    fn observability(&self, row: usize, r: usize) -> f64 {
        self.observability[(row, r)]
    }
    fn controllability(&self, r: usize, col: usize) -> f64 {
        self.controllability[(r, col)]
    }
}

fn direct_term(markov: &MarkovSequence, which: DirectTerm) -> Mat<f64> {
    let (q, p) = (markov.outputs(), markov.inputs());
    match which {
        DirectTerm::Zero => Mat::zeros(q, p),
        DirectTerm::FirstMarkov => Mat::from_fn(q, p, |i, j| markov.get(0, i, j)),
    }
}

/// ERA on a Markov sequence with samples `sample_time_s` apart (docs/src/design.md §1.7–1.9).
///
/// # Errors
/// [`EraError::InvalidParameter`], [`EraError::NotEnoughMarkovSamples`],
/// [`EraError::HankelTooSmall`] (§1.8 error), [`EraError::RankDeficient`] when the data's
/// Hankel has numerical rank below `states`, [`EraError::Numerical`] when the SVD fails.
pub fn realize(
    markov: &MarkovSequence,
    sample_time_s: f64,
    options: &RealizeOptions,
) -> Result<Realization> {
    realize_thesis(markov, sample_time_s, options, false)
}

/// [`realize`] with `A` from the shift of the observability factor
/// ([`crate::identify::Realizer::Shift`]).
///
/// # Errors
/// As [`realize`].
pub(crate) fn realize_shift(
    markov: &MarkovSequence,
    sample_time_s: f64,
    options: &RealizeOptions,
) -> Result<Realization> {
    realize_thesis(markov, sample_time_s, options, true)
}

/// The thesis Hankel's realization, `A` from `H1` or from the shift.
fn realize_thesis(
    markov: &MarkovSequence,
    sample_time_s: f64,
    options: &RealizeOptions,
    shift: bool,
) -> Result<Realization> {
    let (shapes, warnings) = plan(markov, options.states, options.hankel_factor)?;
    realize_shapes(
        markov,
        sample_time_s,
        options,
        (shapes.h0, shapes.h1),
        Some(warnings),
        shift,
    )
}

/// ERA with any block-Hankel shape: `H0` of `shape`, `H1` the same shape one sample
/// later. The thesis shape is what [`realize`] uses; this is for other layouts (e.g.
/// `m × m` blocks starting at `Y_1`, as python-control builds them).
///
/// # Errors
/// [`EraError::HankelTooSmall`] when `states` exceeds the short side of `H0`;
/// [`EraError::ShapeMismatch`] when the shapes need samples the sequence lacks; and the
/// errors of [`realize`].
pub fn realize_general(
    markov: &MarkovSequence,
    sample_time_s: f64,
    options: &RealizeOptions,
    shape: HankelShape,
) -> Result<Realization> {
    let h1 = general_h1(markov, shape, options.states)?;
    realize_shapes(markov, sample_time_s, options, (shape, h1), None, false)
}

/// One factorization at the order asked, and its realization there. `shape_warnings`
/// are the thesis shape's ([`plan`]): the realization warns of few singular values itself,
/// and the rest follow; a general shape (`None`) is warned of nothing.
fn realize_shapes(
    markov: &MarkovSequence,
    sample_time_s: f64,
    options: &RealizeOptions,
    (h0_shape, h1_shape): (HankelShape, HankelShape),
    shape_warnings: Option<Vec<RealizeWarning>>,
    shift: bool,
) -> Result<Realization> {
    let keep = Keep {
        max_states: options.states,
        svd: options.svd,
        svd_tolerance: options.svd_tolerance,
        svd_floor_fraction: 0.0,
        extra: 0,
    };
    let mut factors =
        Factorization::of_shapes(markov, sample_time_s, &keep, h0_shape, h1_shape, Vec::new())?;
    factors.shift = shift;
    let mut realization = factors.realize(options.states, options.direct_term)?;
    match shape_warnings {
        Some(warnings) => realization.warnings.extend(
            warnings
                .into_iter()
                .filter(|w| !matches!(w, RealizeWarning::FewSingularValues { .. })),
        ),
        None => realization.warnings.clear(),
    }
    Ok(realization)
}

/// Reference of [`realize`]: element-wise Hankels, the *full* SVD, and the products of
/// §1.9 as plain loops. Slow on purpose; for tests and benchmarks.
///
/// # Errors
/// As [`realize`].
pub fn realize_naive(
    markov: &MarkovSequence,
    sample_time_s: f64,
    options: &RealizeOptions,
) -> Result<Realization> {
    let (shapes, warnings) = plan(markov, options.states, options.hankel_factor)?;
    let clock = Instant::now();
    check_dense_svd(
        shapes.h0.block_rows * markov.outputs(),
        shapes.h0.block_cols * markov.inputs(),
    )?;
    let h0 = hankel::build_naive(markov, shapes.h0)?;
    let h1 = hankel::build_naive(markov, shapes.h1)?;
    let svd = h0
        .svd()
        .map_err(|e| EraError::Numerical(format!("SVD of H0: {e:?}")))?;
    let singular_values: Vec<f64> = (0..svd.S().dim()).map(|k| svd.S()[k]).collect();
    check_rank(&singular_values, h0.nrows(), h0.ncols(), options.states)?;
    let hankel_svd_seconds = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    let n = options.states;
    let (q, p) = (markov.outputs(), markov.inputs());
    let (u, v) = (svd.U(), svd.V());
    let (rows, cols) = (h1.nrows(), h1.ncols());
    // T = H1 V_n, then A' = U_nᵀ T, by loops.
    let mut t = vec![0.0; rows * n];
    for r in 0..rows {
        for k in 0..n {
            let mut acc = 0.0;
            for c in 0..cols {
                acc += h1[(r, c)] * v[(c, k)];
            }
            t[r * n + k] = acc;
        }
    }
    let mut a = Mat::<f64>::zeros(n, n);
    for i in 0..n {
        for k in 0..n {
            let mut acc = 0.0;
            for r in 0..rows {
                acc += u[(r, i)] * t[r * n + k];
            }
            a[(i, k)] = acc / (singular_values[i].sqrt() * singular_values[k].sqrt());
        }
    }
    let b = Mat::from_fn(n, p, |r, j| singular_values[r].sqrt() * v[(j, r)]);
    let c = Mat::from_fn(q, n, |i, r| u[(i, r)] * singular_values[r].sqrt());
    let d = direct_term(markov, options.direct_term);
    let tails = HankelTails::of(
        &singular_values[..n],
        u.subcols(0, n),
        v.subcols(0, n),
        q,
        p,
    );
    Ok(Realization {
        model: StateSpace::new(a, b, c, d, TimeDomain::Discrete { sample_time_s }),
        singular_values,
        hankel_size: (h0.nrows(), h0.ncols()),
        warnings,
        hankel_svd_seconds,
        products_seconds: clock.elapsed().as_secs_f64(),
        svd_path: SvdPath::Dense,
        svd_iterations: None,
        tails,
    })
}

/// `A = S^(−½) (U_nᵀ H1 V_n) S^(−½)` of §1.9, `root` the kept `√σ`. `ut_h1_v` may be
/// larger than `n × n` (a factorization's), only its leading block is read.
fn balanced_a(root: &[f64], ut_h1_v: faer::MatRef<'_, f64>) -> Mat<f64> {
    let n = root.len();
    Mat::from_fn(n, n, |r, c| ut_h1_v[(r, c)] / (root[r] * root[c]))
}

/// `A` of the shift structure: the least-squares solution of `O↑ A = O↓`, where
/// `O = U_n S^(½)` (`tails`' observability) and `O↑`, `O↓` are `O` without its last and
/// its first `q` rows.
fn shift_a(tails: &FactorTails<'_>) -> Result<Mat<f64>> {
    use faer::linalg::solvers::SolveLstsq;
    let (n, q) = (tails.root.len(), tails.outputs);
    let rows = tails.un.nrows();
    if rows < q + n {
        return Err(EraError::HankelTooSmall {
            rows: rows.saturating_sub(q),
            cols: n,
            available: rows.saturating_sub(q),
            states: n,
        });
    }
    let up = Mat::from_fn(rows - q, n, |i, r| tails.observability(i, r));
    let down = Mat::from_fn(rows - q, n, |i, r| tails.observability(i + q, r));
    let a = up.qr().solve_lstsq(down);
    if a.col_iter().flat_map(|c| c.iter()).any(|v| !v.is_finite()) {
        return Err(EraError::Numerical(
            "the shift solve of A is not finite".into(),
        ));
    }
    Ok(a)
}

impl Factorization {
    /// `states` checked against the factorization: 1 to [`Self::max_states`], within
    /// the numerical rank of `H0`.
    fn check_states(&self, states: usize) -> Result<()> {
        if states == 0 || states > self.max_states {
            return Err(EraError::InvalidParameter {
                name: "states",
                value: states.to_string(),
                reason: format!("the factorization realizes 1 to {} states", self.max_states)
                    .into(),
            });
        }
        if states > self.rank {
            return Err(EraError::RankDeficient {
                rank: self.rank,
                states,
                threshold: self.singular_values.first().copied().unwrap_or(0.0)
                    * self.hankel_size.0.max(self.hankel_size.1) as f64
                    * f64::EPSILON,
            });
        }
        Ok(())
    }

    /// The discrete model of `tails`' states (checked) from the kept factors: `A`
    /// balanced (§1.9) or from the shift, `B` the first `p` columns of the
    /// controllability tail (`S^(½) V_nᵀ`, or ERA/DC's `Σ^(−½) U_nᵀ H(0)`) and `C` the
    /// first `q` rows of the observability tail `U_n S^(½)`.
    fn model_at(&self, tails: &FactorTails<'_>, direct: DirectTerm) -> Result<StateSpace> {
        let (q, p) = (tails.outputs, tails.inputs);
        let n = tails.root.len();
        let a = if self.shift {
            shift_a(tails)?
        } else {
            balanced_a(&tails.root, self.ut_h1_v.as_ref())
        };
        let b = Mat::from_fn(n, p, |r, j| tails.controllability(r, j));
        let c = Mat::from_fn(q, n, |i, r| tails.observability(i, r));
        let d = match direct {
            DirectTerm::Zero => Mat::zeros(q, p),
            DirectTerm::FirstMarkov => self.y0.clone(),
        };
        Ok(StateSpace::new(
            a,
            b,
            c,
            d,
            TimeDomain::Discrete {
                sample_time_s: self.sample_time_s,
            },
        ))
    }

    /// The balanced realization at `states` (docs/src/design.md §1.9) from the kept factors.
    ///
    /// # Errors
    /// [`EraError::InvalidParameter`] for 0 states or more than [`Self::max_states`];
    /// [`EraError::RankDeficient`] above the numerical rank of `H0`.
    pub fn realize(&self, states: usize, direct: DirectTerm) -> Result<Realization> {
        self.check_states(states)?;
        let clock = Instant::now();
        let n = states;
        let view = self.tails(n);
        let model = self.model_at(&view, direct)?;
        let tails = view.to_owned();
        let mut warnings = self.warnings.clone();
        let available = self.hankel_size.0.min(self.hankel_size.1);
        if available < 2 * n {
            warnings.push(RealizeWarning::FewSingularValues {
                available,
                states: n,
            });
        }
        Ok(Realization {
            model,
            singular_values: self.singular_values.clone(),
            hankel_size: self.hankel_size,
            warnings,
            hankel_svd_seconds: self.seconds,
            products_seconds: clock.elapsed().as_secs_f64(),
            svd_path: self.svd_path,
            svd_iterations: self.svd_iterations,
            tails,
        })
    }

    /// The discrete model at `states` and its tails read in place: what a scan needs of
    /// each order, without copying the `(R·q) × n` and `n × (C·p)` tails out of the
    /// factors (a fifth of a scan's time on a thesis-size Hankel).
    ///
    /// # Errors
    /// As [`Self::realize`].
    pub(crate) fn realize_in_place(
        &self,
        states: usize,
        direct: DirectTerm,
    ) -> Result<(StateSpace, FactorTails<'_>)> {
        self.check_states(states)?;
        let tails = self.tails(states);
        Ok((self.model_at(&tails, direct)?, tails))
    }

    /// The tails at `n` states, as views of the factors.
    fn tails(&self, n: usize) -> FactorTails<'_> {
        FactorTails {
            root: self.singular_values[..n].iter().map(|s| s.sqrt()).collect(),
            un: self.u.subcols(0, n),
            vn: self.v.subcols(0, n),
            ut_h0: self.ut_h0.as_ref().map(|m| m.get(..n, ..)),
            outputs: self.y0.nrows(),
            inputs: self.y0.ncols(),
        }
    }
}

/// [`HankelTails`] read from a factorization's `U_n`, `V_n` and `σ` without forming
/// them: `observability[(i, r)] = U[(i, r)]·√σ_r`, and `controllability[(r, j)] =
/// √σ_r·V[(j, r)]` (ERA) or `U_nᵀH(0)[(r, j)]/√σ_r` (ERA/DC), the same products as
/// [`HankelTails`] holds.
pub(crate) struct FactorTails<'a> {
    root: Vec<f64>,
    un: faer::MatRef<'a, f64>,
    vn: faer::MatRef<'a, f64>,
    ut_h0: Option<faer::MatRef<'a, f64>>,
    outputs: usize,
    inputs: usize,
}

impl FactorTails<'_> {
    /// The tails formed: what [`Realization::tails`] holds.
    fn to_owned(&self) -> HankelTails {
        let n = self.root.len();
        let cols = self.block_cols() * self.inputs;
        HankelTails {
            observability: Mat::from_fn(self.un.nrows(), n, |i, r| self.observability(i, r)),
            controllability: Mat::from_fn(n, cols, |r, j| self.controllability(r, j)),
            outputs: self.outputs,
            inputs: self.inputs,
        }
    }
}

impl Tails for FactorTails<'_> {
    fn outputs(&self) -> usize {
        self.outputs
    }
    fn inputs(&self) -> usize {
        self.inputs
    }
    fn block_rows(&self) -> usize {
        self.un.nrows() / self.outputs.max(1)
    }
    fn block_cols(&self) -> usize {
        match self.ut_h0 {
            Some(m) => m.ncols() / self.inputs.max(1),
            None => self.vn.nrows() / self.inputs.max(1),
        }
    }
    fn observability(&self, row: usize, r: usize) -> f64 {
        self.un[(row, r)] * self.root[r]
    }
    fn controllability(&self, r: usize, col: usize) -> f64 {
        match self.ut_h0 {
            Some(m) => m[(r, col)] / self.root[r],
            None => self.root[r] * self.vn[(col, r)],
        }
    }
}

crate::params::names::named!(display DirectTerm, "direct term", [
    DirectTerm::Zero => "zero",
    DirectTerm::FirstMarkov => "markov0",
]);

#[cfg(test)]
mod tails_tests {
    use super::*;
    use crate::pipeline::factor::FactorOptions;
    use crate::pipeline::realize_dc::{factor_dc, DcShape};

    /// A decaying random Markov sequence of 3 outputs and 2 inputs.
    fn markov() -> MarkovSequence {
        let mut rng = crate::linalg::rng::Minstd::new(3);
        let mut m = MarkovSequence::zeros(3, 2, 300);
        for k in 1..300 {
            let decay = (-0.01 * k as f64).exp();
            for i in 0..3 {
                for j in 0..2 {
                    m.set(k, i, j, decay * rng.normal());
                }
            }
        }
        m
    }

    /// The tails a realization forms are the factors' products as they were formed
    /// before the scan read them in place: `U·√σ`, and `√σ·Vᵀ` (ERA) or
    /// `U_nᵀH(0)/√σ` (ERA/DC, whose `B` is its first columns), bit for bit.
    #[test]
    fn the_formed_tails_are_the_factors_products() {
        let markov = markov();
        let era = Factorization::thesis(&markov, 0.01, &FactorOptions::new(16, 6)).unwrap();
        let dc = factor_dc(&markov, 0.01, &DcShape::new(16, 6, 3), 16, 6).unwrap();
        for f in [&era, &dc] {
            for n in [4, 9, 16] {
                let r = f.realize(n, DirectTerm::Zero).unwrap();
                let sv = &f.singular_values[..n];
                let root: Vec<f64> = sv.iter().map(|s| s.sqrt()).collect();
                let obs = Mat::from_fn(f.u.nrows(), n, |i, k| f.u[(i, k)] * root[k]);
                let ctrl = match &f.ut_h0 {
                    Some(m) => Mat::from_fn(n, m.ncols(), |k, j| m[(k, j)] / sv[k].sqrt()),
                    None => Mat::from_fn(n, f.v.nrows(), |k, j| root[k] * f.v[(j, k)]),
                };
                assert_eq!(r.tails.observability, obs, "observability at {n}");
                assert_eq!(r.tails.controllability, ctrl, "controllability at {n}");
                assert_eq!(r.model.b, ctrl.get(.., ..2).to_owned(), "B at {n}");
                assert_eq!(r.model.c, obs.get(..3, ..).to_owned(), "C at {n}");
            }
        }
        assert!(era.ut_h0.is_none() && dc.ut_h0.is_some());
    }
}
