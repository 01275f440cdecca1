//! The factorization of `H0` (docs/src/design.md §1.8–1.9): the thesis Hankel (or any
//! block-Hankel shape) of the Markov sequence and its SVD, dense or truncated, kept in one
//! [`Factorization`] from which [`crate::pipeline::realize`] takes the balanced
//! realization at any order up to the largest.
//!
//! With `H0 = U S Vᵀ`, the realization at order `n` needs `U_n`, `S_n`, `V_n` (the leading
//! `n` columns) and `U_nᵀ H1 V_n`, the leading `n × n` block of `U_Nᵀ H1 V_N` for any
//! `N ≥ n`. The dense path forms `H0` and takes its thin SVD; the matrix-free path applies
//! `H0` and `H1` by FFT correlations ([`crate::pipeline::hankel_op`]) and takes a truncated
//! SVD ([`crate::linalg::tsvd`]) of the leading triplets only.

use crate::error::{EraError, Result};
use crate::linalg::tsvd::{truncated_svd, TruncatedSvdOptions};
use crate::linalg::LinearOperator;
use crate::pipeline::hankel::{self, HankelShape, ThesisHankel};
use crate::pipeline::hankel_op::HankelOperator;
use crate::sources::frf::MarkovSequence;
use faer::Mat;
use std::time::Instant;

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
        crate::params::names::Named::name_of(&self)
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
    pub(crate) fn message(&self, naming: crate::params::Naming) -> String {
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

/// The thesis Hankel of `states` at `hankel_factor`, checked against the data before any
/// heavy work, and the warnings of its shape (§1.8).
pub(super) fn plan(
    markov: &MarkovSequence,
    states: usize,
    hankel_factor: usize,
) -> Result<(ThesisHankel, Vec<RealizeWarning>)> {
    if states == 0 {
        return Err(EraError::InvalidParameter {
            name: "states",
            value: "0".into(),
            reason: "the model needs at least one state".into(),
        });
    }
    if hankel_factor == 0 {
        return Err(EraError::InvalidParameter {
            name: "hankel_factor",
            value: "0".into(),
            reason: "must be at least 1".into(),
        });
    }
    let shapes = ThesisHankel::new(states, hankel_factor)?;
    if shapes.samples_needed() > markov.samples() {
        return Err(EraError::NotEnoughMarkovSamples {
            needed: shapes.samples_needed(),
            available: markov.samples(),
            states,
            hankel_factor,
        });
    }
    let rows = shapes.h0.block_rows * markov.outputs();
    let cols = shapes.h0.block_cols * markov.inputs();
    check_room(rows, cols, states)?;
    let available = rows.min(cols);
    let mut warnings = Vec::new();
    if available < 2 * states {
        warnings.push(RealizeWarning::FewSingularValues { available, states });
    }
    if shapes.h1.last_sample() > markov.samples() / 2 {
        warnings.push(RealizeWarning::PastHalfPeriod {
            last_sample: shapes.h1.last_sample(),
            samples: markov.samples(),
        });
    }
    Ok((shapes, warnings))
}

/// `H1` of a general `H0` of `shape`: the same shape one sample later, checked against
/// the sequence, once `H0` is checked to have room for `states`.
pub(super) fn general_h1(
    markov: &MarkovSequence,
    shape: HankelShape,
    states: usize,
) -> Result<HankelShape> {
    check_room(
        shape.block_rows * markov.outputs(),
        shape.block_cols * markov.inputs(),
        states,
    )?;
    let h1 = HankelShape {
        first_sample: shape.first_sample + 1,
        ..shape
    };
    hankel::check_shape(markov, h1)?;
    Ok(h1)
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
/// [`crate::params::limits::DENSE`], before anything is allocated: the matrix, its `H1` partner's
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
    crate::params::limits::DENSE.check(
        crate::params::names::Prose::from(format!(
            "a dense SVD of the {rows} x {cols} Hankel matrix ("
        ))
        .param(crate::params::names::Param::Svd)
        .text(" matrix-free holds a few of its columns instead)"),
        values,
    )?;
    Ok(())
}

/// Numerical rank of a singular-value list: values above `max(rows, cols)·ε·σ₁`.
pub(crate) fn numerical_rank(singular_values: &[f64], rows: usize, cols: usize) -> (usize, f64) {
    let threshold =
        singular_values.first().copied().unwrap_or(0.0) * rows.max(cols) as f64 * f64::EPSILON;
    (
        singular_values.iter().filter(|s| **s > threshold).count(),
        threshold,
    )
}

pub(super) fn check_rank(
    singular_values: &[f64],
    rows: usize,
    cols: usize,
    states: usize,
) -> Result<()> {
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

/// Extra singular triplets the matrix-free factorization computes past the largest order,
/// so that the singular-value plot shows whether a gap follows it.
pub const EXTRA_SINGULAR_VALUES: usize = 20;

/// The truncated SVD's settings for `max_states` realized triplets among `kept` values:
/// only the realized ones must converge (to `tolerance`, or `floor_fraction`), the rest
/// ride along as oversampling and come out as the block's Ritz values.
pub(crate) fn realized_svd_options(
    max_states: usize,
    kept: usize,
    tolerance: f64,
    floor_fraction: f64,
) -> TruncatedSvdOptions {
    let defaults = TruncatedSvdOptions::new(max_states);
    TruncatedSvdOptions {
        tolerance,
        floor_fraction,
        oversample: defaults.oversample.max(kept.saturating_sub(max_states)),
        ..defaults
    }
}

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
    /// Stop the truncated SVD also at this fraction of its smallest wanted singular value
    /// ([`crate::linalg::tsvd::TruncatedSvdOptions::floor_fraction`]; 0: off).
    pub svd_floor_fraction: f64,
}

impl FactorOptions {
    /// `H0` of `max_states` (as [`crate::pipeline::realize::realize`] at that order), automatic SVD path,
    /// tolerance 1e-12.
    pub fn new(max_states: usize, hankel_factor: usize) -> Self {
        FactorOptions {
            hankel_states: max_states,
            max_states,
            hankel_factor,
            svd: SvdPath::Auto,
            svd_tolerance: 1e-12,
            svd_floor_fraction: 0.0,
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
    pub(super) u: Mat<f64>,
    pub(super) v: Mat<f64>,
    pub(super) ut_h1_v: Mat<f64>,
    pub(super) y0: Mat<f64>,
    pub(super) singular_values: Vec<f64>,
    pub(super) max_states: usize,
    pub(super) rank: usize,
    pub(super) sample_time_s: f64,
    pub(super) hankel_size: (usize, usize),
    pub(super) svd_path: SvdPath,
    pub(super) svd_iterations: Option<usize>,
    pub(super) warnings: Vec<RealizeWarning>,
    pub(super) seconds: f64,
    /// ERA/DC's `U_Nᵀ H(0)`, from which `B` and the controllability tail come
    /// ([`crate::pipeline::realize_dc`]); `None` for ERA, whose `V` gives them.
    pub(super) ut_h0: Option<Mat<f64>>,
    /// `A` from the shift of the observability factor ([`crate::identify::Realizer::Shift`]).
    pub(super) shift: bool,
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

/// What [`Factorization::of_shapes`] computes and keeps.
pub(super) struct Keep {
    /// The largest order realized.
    pub max_states: usize,
    /// Dense or matrix-free SVD.
    pub svd: SvdPath,
    /// Residual tolerance of the truncated SVD, relative to `σ₁`.
    pub svd_tolerance: f64,
    /// See [`FactorOptions::svd_floor_fraction`].
    pub svd_floor_fraction: f64,
    /// Singular values computed past `max_states` on the matrix-free path (for the plot;
    /// 0 for a realization at one order).
    pub extra: usize,
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
            shift: false,
        }
    }

    /// Factors the thesis Hankel of `options.hankel_states` states at
    /// `options.hankel_factor` (the `H0` that [`crate::pipeline::realize::realize`] would build at that order), and
    /// keeps what realizations up to `options.max_states` need.
    ///
    /// # Errors
    /// As [`crate::pipeline::realize::realize`] at `hankel_states`, and [`EraError::HankelTooSmall`] when `H0` has
    /// fewer singular values than `max_states`. A numerical rank below `max_states` is
    /// allowed (orders above it are refused by [`Factorization::realize`]).
    pub fn thesis(
        markov: &MarkovSequence,
        sample_time_s: f64,
        options: &FactorOptions,
    ) -> Result<Self> {
        let (shapes, warnings) = plan(markov, options.hankel_states, options.hankel_factor)?;
        let (rows, cols) = (
            shapes.h0.block_rows * markov.outputs(),
            shapes.h0.block_cols * markov.inputs(),
        );
        check_room(rows, cols, options.max_states)?;
        let keep = Keep {
            max_states: options.max_states,
            svd: options.svd,
            svd_tolerance: options.svd_tolerance,
            svd_floor_fraction: options.svd_floor_fraction,
            extra: EXTRA_SINGULAR_VALUES,
        };
        Self::of_shapes(markov, sample_time_s, &keep, shapes.h0, shapes.h1, warnings)
    }

    /// Factors a general `H0` of `shape` (`H1` one sample later), as [`crate::pipeline::realize::realize_general`].
    ///
    /// # Errors
    /// As [`crate::pipeline::realize::realize_general`].
    pub fn general(
        markov: &MarkovSequence,
        sample_time_s: f64,
        max_states: usize,
        svd: SvdPath,
        shape: HankelShape,
    ) -> Result<Self> {
        let h1 = general_h1(markov, shape, max_states)?;
        let keep = Keep {
            max_states,
            svd,
            svd_tolerance: 1e-12,
            svd_floor_fraction: 0.0,
            extra: EXTRA_SINGULAR_VALUES,
        };
        Self::of_shapes(markov, sample_time_s, &keep, shape, h1, Vec::new())
    }

    /// Factors `H0` of `h0_shape` (`H1` of `h1_shape`), shapes already checked, keeping
    /// what `keep` says; `warnings` are those of the shapes, given to every realization.
    pub(super) fn of_shapes(
        markov: &MarkovSequence,
        sample_time_s: f64,
        keep: &Keep,
        h0_shape: HankelShape,
        h1_shape: HankelShape,
        warnings: Vec<RealizeWarning>,
    ) -> Result<Self> {
        let clock = Instant::now();
        let max_states = keep.max_states;
        let (rows, cols) = (
            h0_shape.block_rows * markov.outputs(),
            h0_shape.block_cols * markov.inputs(),
        );
        let matrix_free = keep.svd.matrix_free(rows.min(cols));
        let (u, s, v, ut_h1_v, path, iterations) = if matrix_free {
            let op0 = HankelOperator::new(markov, h0_shape)?;
            // Only the realized triplets must converge; the extra singular values are the
            // Ritz values of the oversampled block (lower bounds, for the plot).
            let kept = (max_states + keep.extra).min(rows.min(cols));
            let tsvd_options = realized_svd_options(
                max_states,
                kept,
                keep.svd_tolerance,
                keep.svd_floor_fraction,
            );
            let mut svd = truncated_svd(&op0, &tsvd_options)?;
            svd.s.truncate(kept);
            let u = svd.u.subcols(0, kept).to_owned();
            let v = svd.v.subcols(0, kept).to_owned();
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
            shift: false,
        })
    }

    /// The same factors, realizing `A` from the shift of the observability factor
    /// ([`crate::identify::Realizer::Shift`]) instead of `H1`.
    #[must_use]
    pub(crate) fn with_shift(mut self) -> Self {
        self.shift = true;
        self
    }

    /// The largest order this factorization realizes.
    pub fn max_states(&self) -> usize {
        self.max_states
    }

    /// Numerical rank of `H0` (as `numerical_rank`; on the matrix-free path, among the
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
}

crate::params::names::named!(display SvdPath, "svd", [
    SvdPath::Auto => "auto",
    SvdPath::Dense => "dense",
    SvdPath::MatrixFree => "matrix-free",
]);
