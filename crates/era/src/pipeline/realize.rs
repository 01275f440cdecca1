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
//! [`realize`] uses `faer`'s thin SVD; [`realize_naive`] forms the Hankels element by
//! element, takes the full SVD and multiplies with plain loops. It is the reference every
//! faster path is tested against.

use crate::error::{EraError, Result};
use crate::linalg::tsvd::{truncated_svd, TruncatedSvdOptions};
use crate::linalg::LinearOperator;
use crate::pipeline::hankel::{self, HankelShape, ThesisHankel};
use crate::pipeline::hankel_op::HankelOperator;
use crate::sources::frf::MarkovSequence;
use crate::statespace::{StateSpace, TimeDomain};
use faer::Mat;
use std::time::Instant;

/// What the model's `D` is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DirectTerm {
    /// `D = 0`, as in the thesis.
    #[default]
    Zero,
    /// `D = Y_0`, the time-zero Markov block.
    FirstMarkov,
}

/// How the SVD of `H0` is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SvdPath {
    /// Form `H0` and take its thin SVD (all singular values).
    Dense,
    /// Never form `H0`: FFT products ([`crate::pipeline::hankel_op`]) and a truncated SVD
    /// ([`crate::linalg::tsvd`]); only the leading singular values.
    MatrixFree,
    /// Dense while `H0` is small (below [`AUTO_MATRIX_FREE_MIN_DIM`] on its short
    /// side), matrix-free beyond.
    #[default]
    Auto,
}

impl SvdPath {
    /// `"dense"`, `"matrix-free"` or `"auto"`.
    pub fn name(self) -> &'static str {
        crate::names::Named::name_of(&self)
    }

    /// Whether this path goes matrix-free for an `H0` whose short side is `short_side`.
    pub fn matrix_free(self, short_side: usize) -> bool {
        match self {
            SvdPath::Dense => false,
            SvdPath::MatrixFree => true,
            SvdPath::Auto => short_side >= AUTO_MATRIX_FREE_MIN_DIM,
        }
    }
}

/// [`SvdPath::Auto`] goes matrix-free when the short side of `H0` is at least this.
pub const AUTO_MATRIX_FREE_MIN_DIM: usize = 1024;

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

/// A warning that does not stop the run.
#[derive(Debug, Clone, PartialEq)]
pub enum RealizeWarning {
    /// Fewer than `2·ns` singular values (thesis: "increase length of time series").
    FewSingularValues {
        /// Singular values available.
        available: usize,
        /// Requested states.
        states: usize,
    },
    /// The Hankel reaches past half of the circular impulse response, where the inverse
    /// FFT wraps around.
    PastHalfPeriod {
        /// Last Markov index used.
        last_sample: usize,
        /// Samples of the impulse response.
        samples: usize,
    },
}

impl RealizeWarning {
    /// The warning, with the options its remedy names spelled as `naming` spells them
    /// (`Display` uses the option fields, [`crate::params::Naming::Keyword`]).
    pub fn message(&self, naming: crate::params::Naming) -> String {
        let n = |key: &str| naming.name(key);
        match self {
            RealizeWarning::FewSingularValues { available, states } => format!(
                "the Hankel matrix has {available} singular values, fewer than 2 x {states} states: increase {}",
                n("hankel_factor")
            ),
            RealizeWarning::PastHalfPeriod { last_sample, samples } => format!(
                "the Hankel uses Markov samples up to {last_sample} of a {samples}-sample circular impulse response: samples past the half wrap around; pad with {} or lower {}",
                n("pad_to"),
                n("hankel_factor")
            ),
        }
    }
}

impl std::fmt::Display for RealizeWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message(crate::params::Naming::Keyword))
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

/// Checks the options against the data before any heavy work.
fn plan(
    markov: &MarkovSequence,
    options: &RealizeOptions,
) -> Result<(ThesisHankel, Vec<RealizeWarning>)> {
    if options.states == 0 {
        return Err(EraError::InvalidParameter {
            name: "states",
            value: "0".into(),
            reason: "the model needs at least one state".into(),
        });
    }
    if options.hankel_factor == 0 {
        return Err(EraError::InvalidParameter {
            name: "hankel_factor",
            value: "0".into(),
            reason: "must be at least 1".into(),
        });
    }
    let shapes = ThesisHankel::new(options.states, options.hankel_factor)?;
    if shapes.samples_needed() > markov.samples() {
        return Err(EraError::NotEnoughMarkovSamples {
            needed: shapes.samples_needed(),
            available: markov.samples(),
            states: options.states,
            hankel_factor: options.hankel_factor,
        });
    }
    let rows = shapes.h0.block_rows * markov.outputs();
    let cols = shapes.h0.block_cols * markov.inputs();
    check_room(rows, cols, options.states)?;
    let available = rows.min(cols);
    let mut warnings = Vec::new();
    if available < 2 * options.states {
        warnings.push(RealizeWarning::FewSingularValues {
            available,
            states: options.states,
        });
    }
    if shapes.h1.last_sample() > markov.samples() / 2 {
        warnings.push(RealizeWarning::PastHalfPeriod {
            last_sample: shapes.h1.last_sample(),
            samples: markov.samples(),
        });
    }
    Ok((shapes, warnings))
}

/// [`EraError::HankelTooSmall`] unless an `H0` of `rows × cols` has room for `states`
/// (at least one).
pub(crate) fn check_room(rows: usize, cols: usize, states: usize) -> Result<()> {
    if states == 0 || rows.min(cols) < states {
        return Err(EraError::HankelTooSmall {
            rows,
            cols,
            available: rows.min(cols),
            states,
        });
    }
    Ok(())
}

/// Checks what a dense thin SVD of a `rows × cols` Hankel holds at once against
/// [`crate::limits::DENSE`], before anything is allocated: the matrix, its `H1` partner's
/// product and faer's workspace (about three copies) and the factors `U` and `V`.
///
/// # Errors
/// [`EraError::Limit`] above the limit.
pub(crate) fn check_dense_svd(rows: usize, cols: usize) -> Result<()> {
    let (r, c) = (rows as u64, cols as u64);
    let values = r
        .saturating_mul(c)
        .saturating_mul(3)
        .saturating_add(r.saturating_add(c).saturating_mul(r.min(c)));
    crate::limits::DENSE.check(
        crate::names::Prose::from(format!(
            "a dense SVD of the {rows} x {cols} Hankel matrix ("
        ))
        .param(crate::names::Param::Svd)
        .text(" matrix-free holds a few of its columns instead)"),
        values,
    )?;
    Ok(())
}

/// Numerical rank of a singular-value list: values above `max(rows, cols)·ε·σ₁`.
pub fn numerical_rank(singular_values: &[f64], rows: usize, cols: usize) -> (usize, f64) {
    let threshold =
        singular_values.first().copied().unwrap_or(0.0) * rows.max(cols) as f64 * f64::EPSILON;
    (
        singular_values.iter().filter(|s| **s > threshold).count(),
        threshold,
    )
}

fn check_rank(singular_values: &[f64], rows: usize, cols: usize, states: usize) -> Result<()> {
    let (rank, threshold) = numerical_rank(singular_values, rows, cols);
    if rank < states {
        return Err(EraError::RankDeficient {
            rank,
            states,
            threshold,
        });
    }
    Ok(())
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
    let (shapes, warnings) = plan(markov, options)?;
    realize_shapes(
        markov,
        sample_time_s,
        options,
        shapes.h0,
        shapes.h1,
        warnings,
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
    let (rows, cols) = (
        shape.block_rows * markov.outputs(),
        shape.block_cols * markov.inputs(),
    );
    check_room(rows, cols, options.states)?;
    let h1 = HankelShape {
        first_sample: shape.first_sample + 1,
        ..shape
    };
    hankel::check_shape(markov, h1)?;
    realize_shapes(markov, sample_time_s, options, shape, h1, Vec::new())
}

fn realize_shapes(
    markov: &MarkovSequence,
    sample_time_s: f64,
    options: &RealizeOptions,
    h0_shape: HankelShape,
    h1_shape: HankelShape,
    warnings: Vec<RealizeWarning>,
) -> Result<Realization> {
    let short_side =
        (h0_shape.block_rows * markov.outputs()).min(h0_shape.block_cols * markov.inputs());
    let matrix_free = options.svd.matrix_free(short_side);
    if matrix_free {
        return realize_matrix_free(markov, sample_time_s, options, h0_shape, h1_shape, warnings);
    }
    check_dense_svd(
        h0_shape.block_rows * markov.outputs(),
        h0_shape.block_cols * markov.inputs(),
    )?;
    let clock = Instant::now();
    let h0 = hankel::build(markov, h0_shape)?;
    let hankel_size = (h0.nrows(), h0.ncols());
    let svd = crate::linalg::dense::thin_svd_leading(h0, options.states, "H0")?;
    let singular_values = svd.s;
    check_rank(
        &singular_values,
        hankel_size.0,
        hankel_size.1,
        options.states,
    )?;
    let hankel_svd_seconds = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    let n = options.states;
    let un = svd.u.subcols(0, n);
    let vn = svd.v.subcols(0, n);
    let h1 = hankel::build(markov, h1_shape)?;
    let ut_h1_v = un.transpose() * (&h1 * vn);
    let (a, b, c, d) = balanced_matrices(&singular_values[..n], un, vn, &ut_h1_v, markov, options);
    let tails = HankelTails::of(
        &singular_values[..n],
        un,
        vn,
        markov.outputs(),
        markov.inputs(),
    );
    Ok(Realization {
        model: StateSpace::new(a, b, c, d, TimeDomain::Discrete { sample_time_s }),
        singular_values,
        hankel_size,
        warnings,
        hankel_svd_seconds,
        products_seconds: clock.elapsed().as_secs_f64(),
        svd_path: SvdPath::Dense,
        svd_iterations: None,
        tails,
    })
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
    let (shapes, warnings) = plan(markov, options)?;
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

/// §1.9 from the kept singular values `σ`, `U_n`, `V_n` and `U_nᵀ H1 V_n`:
/// `A = S^(−½) (U_nᵀ H1 V_n) S^(−½)`, `B` = first p columns of `S^(½) V_nᵀ`,
/// `C` = first q rows of `U_n S^(½)`, `D` as asked. Shared by both SVD paths.
fn balanced_matrices(
    singular_values: &[f64],
    un: faer::MatRef<'_, f64>,
    vn: faer::MatRef<'_, f64>,
    ut_h1_v: &Mat<f64>,
    markov: &MarkovSequence,
    options: &RealizeOptions,
) -> (Mat<f64>, Mat<f64>, Mat<f64>, Mat<f64>) {
    let (a, b, c) = balanced_abc(
        singular_values,
        un,
        vn,
        ut_h1_v.as_ref(),
        markov.outputs(),
        markov.inputs(),
    );
    (a, b, c, direct_term(markov, options.direct_term))
}

/// `A`, `B`, `C` of §1.9 (see [`balanced_matrices`]); `ut_h1_v` may be larger than
/// `n × n` (a factorization's), only its leading block is read.
fn balanced_abc(
    singular_values: &[f64],
    un: faer::MatRef<'_, f64>,
    vn: faer::MatRef<'_, f64>,
    ut_h1_v: faer::MatRef<'_, f64>,
    q: usize,
    p: usize,
) -> (Mat<f64>, Mat<f64>, Mat<f64>) {
    let n = singular_values.len();
    let root: Vec<f64> = singular_values.iter().map(|s| s.sqrt()).collect();
    let a = Mat::from_fn(n, n, |r, c| ut_h1_v[(r, c)] / (root[r] * root[c]));
    let b = Mat::from_fn(n, p, |r, j| root[r] * vn[(j, r)]);
    let c = Mat::from_fn(q, n, |i, r| un[(i, r)] * root[r]);
    (a, b, c)
}

/// The matrix-free path of [`realize`]: `H0` and `H1` are never formed.
fn realize_matrix_free(
    markov: &MarkovSequence,
    sample_time_s: f64,
    options: &RealizeOptions,
    h0_shape: HankelShape,
    h1_shape: HankelShape,
    warnings: Vec<RealizeWarning>,
) -> Result<Realization> {
    let clock = Instant::now();
    let n = options.states;
    let op0 = HankelOperator::new(markov, h0_shape)?;
    let (rows, cols) = (op0.nrows(), op0.ncols());
    let tsvd_options = TruncatedSvdOptions {
        tolerance: options.svd_tolerance,
        ..TruncatedSvdOptions::new(n)
    };
    let svd = truncated_svd(&op0, &tsvd_options)?;
    check_rank(&svd.s, rows, cols, n)?;
    let hankel_svd_seconds = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    let un = svd.u.subcols(0, n);
    let vn = svd.v.subcols(0, n);
    let op1 = HankelOperator::new(markov, h1_shape)?;
    let h1_v = op1.apply(vn);
    let ut_h1_v = un.transpose() * &h1_v;
    let (a, b, c, d) = balanced_matrices(&svd.s[..n], un, vn, &ut_h1_v, markov, options);
    let tails = HankelTails::of(&svd.s[..n], un, vn, markov.outputs(), markov.inputs());
    let mut singular_values = svd.s;
    singular_values.truncate(n); // only these passed the residual test
    Ok(Realization {
        model: StateSpace::new(a, b, c, d, TimeDomain::Discrete { sample_time_s }),
        singular_values,
        hankel_size: (rows, cols),
        warnings,
        hankel_svd_seconds,
        products_seconds: clock.elapsed().as_secs_f64(),
        svd_path: SvdPath::MatrixFree,
        svd_iterations: Some(svd.iterations),
        tails,
    })
}

/// Extra singular triplets the matrix-free factorization computes past the largest order,
/// so that the singular-value plot shows whether a gap follows it.
pub const EXTRA_SINGULAR_VALUES: usize = 20;

/// What [`Factorization::thesis`] factors and keeps.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct FactorOptions {
    /// `H0` is the thesis Hankel of this many states (`M = hankel_states · lh`).
    pub hankel_states: usize,
    /// The largest order realized from it.
    pub max_states: usize,
    /// Hankel factor `lh`.
    pub hankel_factor: usize,
    /// Dense or matrix-free SVD.
    pub svd: SvdPath,
    /// Residual tolerance of the truncated SVD, relative to `σ₁`.
    pub svd_tolerance: f64,
}

impl FactorOptions {
    /// `H0` of `max_states` (as [`realize`] at that order), automatic SVD path,
    /// tolerance 1e-12.
    pub fn new(max_states: usize, hankel_factor: usize) -> Self {
        FactorOptions {
            hankel_states: max_states,
            max_states,
            hankel_factor,
            svd: SvdPath::Auto,
            svd_tolerance: 1e-12,
        }
    }
}

/// The SVD of `H0`, kept so that a balanced realization of any order up to
/// [`Factorization::max_states`] costs only small products (docs/src/design.md §1.9).
///
/// With `H0 = U S Vᵀ`, the realization at order `n` uses `U_n`, `S_n`, `V_n` — the leading
/// `n` columns — and `U_nᵀ H1 V_n`, the leading `n × n` block of `U_Nᵀ H1 V_N` for any
/// `N ≥ n`. That block product is formed once at the largest order `N`, so a scan over
/// many orders costs one factorisation, one `H1` product and an `n × n` slice per order.
/// On the matrix-free path `H1` is never formed: `H1 V_N` is one operator product.
#[derive(Debug, Clone)]
pub struct Factorization {
    u: Mat<f64>,
    v: Mat<f64>,
    ut_h1_v: Mat<f64>,
    y0: Mat<f64>,
    singular_values: Vec<f64>,
    max_states: usize,
    rank: usize,
    sample_time_s: f64,
    hankel_size: (usize, usize),
    svd_path: SvdPath,
    svd_iterations: Option<usize>,
    warnings: Vec<RealizeWarning>,
    seconds: f64,
    /// ERA/DC's `U_Nᵀ H(0)`, from which `B` and the controllability tail come
    /// ([`crate::pipeline::realize_dc`]); `None` for ERA, whose `V` gives them.
    ut_h0: Option<Mat<f64>>,
}

/// What [`Factorization::from_parts`] assembles: an SVD `U Σ Vᵀ` of some `H0`, the
/// product `U_Nᵀ H1 V_N`, and for ERA/DC `U_Nᵀ H(0)`.
pub(crate) struct FactorParts {
    pub u: Mat<f64>,
    pub v: Mat<f64>,
    pub ut_h1_v: Mat<f64>,
    pub singular_values: Vec<f64>,
    pub max_states: usize,
    pub hankel_size: (usize, usize),
    pub ut_h0: Option<Mat<f64>>,
}

impl Factorization {
    /// A factorization of parts computed elsewhere (ERA/DC's correlations), dense.
    pub(crate) fn from_parts(
        markov: &MarkovSequence,
        sample_time_s: f64,
        parts: FactorParts,
        seconds: f64,
    ) -> Self {
        let (rows, cols) = parts.hankel_size;
        let (rank, _) = numerical_rank(&parts.singular_values, rows, cols);
        let (q, p) = (markov.outputs(), markov.inputs());
        Factorization {
            u: parts.u,
            v: parts.v,
            ut_h1_v: parts.ut_h1_v,
            y0: Mat::from_fn(q, p, |i, j| markov.get(0, i, j)),
            singular_values: parts.singular_values,
            max_states: parts.max_states,
            rank,
            sample_time_s,
            hankel_size: parts.hankel_size,
            svd_path: SvdPath::Dense,
            svd_iterations: None,
            warnings: Vec::new(),
            seconds,
            ut_h0: parts.ut_h0,
        }
    }

    /// Factors the thesis Hankel of `options.hankel_states` states at
    /// `options.hankel_factor` (the `H0` that [`realize`] would build at that order), and
    /// keeps what realizations up to `options.max_states` need.
    ///
    /// # Errors
    /// As [`realize`] at `hankel_states`, and [`EraError::HankelTooSmall`] when `H0` has
    /// fewer singular values than `max_states`. A numerical rank below `max_states` is
    /// allowed (orders above it are refused by [`Factorization::realize`]).
    pub fn thesis(
        markov: &MarkovSequence,
        sample_time_s: f64,
        options: &FactorOptions,
    ) -> Result<Self> {
        let plan_options = RealizeOptions {
            svd: options.svd,
            svd_tolerance: options.svd_tolerance,
            ..RealizeOptions::new(options.hankel_states, options.hankel_factor)
        };
        let (shapes, warnings) = plan(markov, &plan_options)?;
        let (rows, cols) = (
            shapes.h0.block_rows * markov.outputs(),
            shapes.h0.block_cols * markov.inputs(),
        );
        check_room(rows, cols, options.max_states)?;
        let realize_options = RealizeOptions {
            states: options.max_states,
            ..plan_options
        };
        Self::with_shapes(
            markov,
            sample_time_s,
            &realize_options,
            shapes.h0,
            shapes.h1,
            warnings,
        )
    }

    /// Factors a general `H0` of `shape` (`H1` one sample later), as [`realize_general`].
    ///
    /// # Errors
    /// As [`realize_general`].
    pub fn general(
        markov: &MarkovSequence,
        sample_time_s: f64,
        max_states: usize,
        svd: SvdPath,
        shape: HankelShape,
    ) -> Result<Self> {
        let (rows, cols) = (
            shape.block_rows * markov.outputs(),
            shape.block_cols * markov.inputs(),
        );
        check_room(rows, cols, max_states)?;
        let h1 = HankelShape {
            first_sample: shape.first_sample + 1,
            ..shape
        };
        hankel::check_shape(markov, h1)?;
        let options = RealizeOptions {
            svd,
            ..RealizeOptions::new(max_states, 1)
        };
        Self::with_shapes(markov, sample_time_s, &options, shape, h1, Vec::new())
    }

    fn with_shapes(
        markov: &MarkovSequence,
        sample_time_s: f64,
        options: &RealizeOptions,
        h0_shape: HankelShape,
        h1_shape: HankelShape,
        warnings: Vec<RealizeWarning>,
    ) -> Result<Self> {
        let clock = Instant::now();
        let max_states = options.states;
        let (rows, cols) = (
            h0_shape.block_rows * markov.outputs(),
            h0_shape.block_cols * markov.inputs(),
        );
        let matrix_free = options.svd.matrix_free(rows.min(cols));
        let (u, s, v, ut_h1_v, path, iterations) = if matrix_free {
            let op0 = HankelOperator::new(markov, h0_shape)?;
            // Only the realized triplets must converge; the extra singular values are the
            // Ritz values of the oversampled block (lower bounds, for the plot).
            let keep = (max_states + EXTRA_SINGULAR_VALUES).min(rows.min(cols));
            let defaults = TruncatedSvdOptions::new(max_states);
            let tsvd_options = TruncatedSvdOptions {
                tolerance: options.svd_tolerance,
                oversample: defaults.oversample.max(keep - max_states),
                ..defaults
            };
            let mut svd = truncated_svd(&op0, &tsvd_options)?;
            svd.s.truncate(keep);
            let u = svd.u.subcols(0, keep).to_owned();
            let v = svd.v.subcols(0, keep).to_owned();
            let op1 = HankelOperator::new(markov, h1_shape)?;
            let vn = v.subcols(0, max_states);
            let ut_h1_v = u.subcols(0, max_states).transpose() * op1.apply(vn);
            (
                u,
                svd.s,
                v,
                ut_h1_v,
                SvdPath::MatrixFree,
                Some(svd.iterations),
            )
        } else {
            check_dense_svd(rows, cols)?;
            let h0 = hankel::build(markov, h0_shape)?;
            // Only the realized columns of U and V are kept (and, for a tall or wide
            // Hankel, computed).
            let svd = crate::linalg::dense::thin_svd_leading(h0, max_states, "H0")?;
            let h1 = hankel::build(markov, h1_shape)?;
            let ut_h1_v = {
                let (un, vn) = (svd.u.subcols(0, max_states), svd.v.subcols(0, max_states));
                un.transpose() * (&h1 * vn)
            };
            (svd.u, svd.s, svd.v, ut_h1_v, SvdPath::Dense, None)
        };
        let (rank, _) = numerical_rank(&s, rows, cols);
        let (q, p) = (markov.outputs(), markov.inputs());
        Ok(Factorization {
            u,
            v,
            ut_h1_v,
            y0: Mat::from_fn(q, p, |i, j| markov.get(0, i, j)),
            singular_values: s,
            max_states,
            rank,
            sample_time_s,
            hankel_size: (rows, cols),
            svd_path: path,
            svd_iterations: iterations,
            warnings,
            seconds: clock.elapsed().as_secs_f64(),
            ut_h0: None,
        })
    }

    /// The largest order this factorization realizes.
    pub fn max_states(&self) -> usize {
        self.max_states
    }

    /// Numerical rank of `H0` (as [`numerical_rank`]; on the matrix-free path, among the
    /// singular values computed).
    pub fn rank(&self) -> usize {
        self.rank
    }

    /// Singular values of `H0`, largest first: all of them on the dense path, the largest
    /// order plus [`EXTRA_SINGULAR_VALUES`] on the matrix-free path.
    pub fn singular_values(&self) -> &[f64] {
        &self.singular_values
    }

    /// Rows and columns of `H0`.
    pub fn hankel_size(&self) -> (usize, usize) {
        self.hankel_size
    }

    /// The SVD path taken (never `Auto`).
    pub fn svd_path(&self) -> SvdPath {
        self.svd_path
    }

    /// Iterations of the truncated SVD (matrix-free path).
    pub fn svd_iterations(&self) -> Option<usize> {
        self.svd_iterations
    }

    /// Wall time of the Hankel, SVD and `H1` product, s.
    pub fn seconds(&self) -> f64 {
        self.seconds
    }

    /// The balanced realization at `states` (docs/src/design.md §1.9) from the kept factors.
    ///
    /// # Errors
    /// [`EraError::InvalidParameter`] for 0 states or more than [`Self::max_states`];
    /// [`EraError::RankDeficient`] above the numerical rank of `H0`.
    pub fn realize(&self, states: usize, direct: DirectTerm) -> Result<Realization> {
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
        let clock = Instant::now();
        let n = states;
        let (q, p) = (self.y0.nrows(), self.y0.ncols());
        let sv = &self.singular_values[..n];
        let (un, vn) = (self.u.subcols(0, n), self.v.subcols(0, n));
        let (a, mut b, c) = balanced_abc(sv, un, vn, self.ut_h1_v.as_ref(), q, p);
        let mut tails = HankelTails::of(sv, un, vn, q, p);
        if let Some(ut_h0) = &self.ut_h0 {
            // ERA/DC: Q_β = Σ^(−½) U_nᵀ H(0), and B its first p columns.
            let controllability =
                Mat::from_fn(n, ut_h0.ncols(), |r, j| ut_h0[(r, j)] / sv[r].sqrt());
            b = controllability.get(.., ..p).to_owned();
            tails.controllability = controllability;
        }
        let d = match direct {
            DirectTerm::Zero => Mat::zeros(q, p),
            DirectTerm::FirstMarkov => self.y0.clone(),
        };
        let mut warnings = self.warnings.clone();
        let available = self.hankel_size.0.min(self.hankel_size.1);
        if available < 2 * n {
            warnings.push(RealizeWarning::FewSingularValues {
                available,
                states: n,
            });
        }
        Ok(Realization {
            model: StateSpace::new(
                a,
                b,
                c,
                d,
                TimeDomain::Discrete {
                    sample_time_s: self.sample_time_s,
                },
            ),
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
}

crate::names::named!(display DirectTerm, "direct term", [
    DirectTerm::Zero => "zero",
    DirectTerm::FirstMarkov => "markov0",
]);

crate::names::named!(display SvdPath, "svd", [
    SvdPath::Auto => "auto",
    SvdPath::Dense => "dense",
    SvdPath::MatrixFree => "matrix-free",
]);
