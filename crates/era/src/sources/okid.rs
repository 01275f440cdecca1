//! OKID, observer/Kalman filter identification (Juang, Phan, Horta & Longman 1991): the
//! Markov parameters of a system straight from its input and output time histories, with
//! no FRF, no window and no leakage.
//!
//! **The observer.** For `x_{k+1} = A x_k + B u_k`, `y_k = C x_k + D u_k` and any gain `G`,
//! the observer `x_{k+1} = Ā x_k + B̄ v_k` with `Ā = A + G C`, `B̄ = [B + G D, −G]` and
//! `v_k = [u_k; y_k]` describes the same data. When `Ā^p ≈ 0` (a deadbeat observer
//! without noise; the steady-state Kalman filter's, `p` large enough, with it)
//!
//! ```text
//! y_k = D u_k + Σ_{i=1..p} ( Ȳ⁽¹⁾_i u_{k−i} + Ȳ⁽²⁾_i y_{k−i} ),
//! Ȳ⁽¹⁾_i = C Ā^(i−1) (B + G D),   Ȳ⁽²⁾_i = −C Ā^(i−1) G,
//! ```
//!
//! a linear regression of each output sample on the current inputs and `p` past inputs
//! and outputs. Its rows are every sample `k ≥ p_max` of every record of the test (records
//! are never joined across their ends).
//!
//! **The solve.** The data matrix `[Φ | Y]` (one row per sample, the regressors ordered
//! `u_k, (u_{k−1}, y_{k−1}), …, (u_{k−p}, y_{k−p})`) is reduced to its triangular factor
//! `R` by Householder QR in blocks of rows: each block is stacked under the `R` so far and
//! factored again, so a long record is never held as one matrix, and fixed groups of
//! blocks are factored in parallel and merged in order (the result does not depend on the
//! thread count). Channels are scaled to unit RMS first (after removing each record's
//! mean) so that forces and accelerations of any units weigh alike. Normal equations are
//! never formed: their condition number is the square of the data's.
//!
//! **The observer order.** Because the regressors of order `p` are the first
//! `m_p = r + p(r+q)` columns, one `R` gives the residual of every order below `p_max`:
//! `S_p = R₁₂[m_p.., :]ᵀ R₁₂[m_p.., :] + R₂₂ᵀ R₂₂`. The order chosen by default minimises
//! the Bayesian information criterion `N ln det(S_p/N) + q m_p ln N`; `S_p/N` is floored at
//! `1e-12` of the unit output variance so that exact data picks the smallest order that
//! reproduces it. The coefficients are `R₁₁⁺ R₁₂` at the chosen order, the
//! pseudo-inverse through the SVD of the small triangle (noise-free data makes the
//! lagged outputs of orders above `n/q` dependent; any solution gives the same system
//! Markov parameters).
//!
//! **The system Markov parameters** follow from `(I − Ȳ⁽²⁾(z)) H(z) = D + Ȳ⁽¹⁾(z)`:
//!
//! ```text
//! Y_0 = D,   Y_k = Ȳ⁽¹⁾_k + Σ_{i=1..min(k,p)} Ȳ⁽²⁾_i Y_{k−i}   (Ȳ⁽¹⁾_k = 0 for k > p).
//! ```
//!
//! The sum runs to `i = k` (the term `Ȳ⁽²⁾_k D`): dropping it is wrong whenever `D ≠ 0`,
//! as it is for accelerations. Run forward, the recursion is the filter
//! `(I − Ȳ⁽²⁾(z))⁻¹`, stable only when every root of `det(z^p I − Σ Ȳ⁽²⁾_i z^(p−i))`
//! (the eigenvalues of its block companion matrix) lies inside the unit circle. A
//! least-squares observer on real data can have roots outside it; then `H` is evaluated
//! on the unit circle, `H(e^{jω}) = (I − Ȳ⁽²⁾(e^{jω}))⁻¹ (D + Ȳ⁽¹⁾(e^{jω}))`, and inverse
//! transformed: the causal, bounded sequence whose transfer function the observer's
//! is on the circle, with the anti-causal part of the unstable roots folded to the end of
//! the transform, past the samples kept.
//!
//! **The observer gain's Markov parameters** `Y^o_k = C A^(k−1) G` follow from
//! `(I − Ȳ⁽²⁾(z)) H_G(z) = −Ȳ⁽²⁾(z)`: `Y^o_k = −Ȳ⁽²⁾_k + Σ_{i=1..k−1} Ȳ⁽²⁾_i Y^o_{k−i}`.
//! Given a realization `(A, C)` of the system, `G = O⁺ [Y^o_1; …; Y^o_L]` with the
//! observability matrix `O`, and the Kalman gain of the innovation form
//! `x_{k+1} = A x_k + B u_k + K e_k` is `K = −G` ([`kalman_gain`]).
//!
//! faer has the QR, the SVD and the eigenvalues used here; the blocked, mergeable QR of a
//! regression that is never held whole is written here because a one-shot `qr()` needs
//! the whole data matrix.

use crate::data::statespace::StateSpace;
use crate::error::{EraError, Result};
use crate::linalg::fft::real_fft_plans;
use crate::sources::MarkovSequence;
use faer::linalg::solvers::{Solve, SolveLstsq};
use faer::Mat;
use num_complex::Complex64;
use rayon::prelude::*;

/// One record of one test: input and output channels, all of one length, sampled at
/// the test's rate.
#[derive(Debug, Clone, Copy)]
pub struct Record<'a> {
    /// Input (force) channels.
    pub inputs: &'a [&'a [f64]],
    /// Output (response) channels.
    pub outputs: &'a [&'a [f64]],
}

/// How the observer order `p` is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ObserverOrder {
    /// This order.
    Fixed(usize),
    /// The order below `max` (default `default_max_observer_order`) that minimises the
    /// information criterion.
    Auto {
        /// The largest order tried.
        max: Option<usize>,
    },
}

impl Default for ObserverOrder {
    fn default() -> Self {
        ObserverOrder::Auto { max: None }
    }
}

/// Settings of [`okid`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct OkidOptions {
    /// The observer order (default: chosen from the data).
    pub observer_order: ObserverOrder,
    /// System Markov blocks to return, `Y_0 … Y_(L−1)` (default 1024).
    pub markov_samples: usize,
    /// Also return the observer gain's Markov parameters (default false).
    pub gain: bool,
    /// Seconds between the records' samples, which the Markov sequence carries
    /// (default 1).
    pub sample_time_s: f64,
}

impl Default for OkidOptions {
    fn default() -> Self {
        OkidOptions {
            observer_order: ObserverOrder::default(),
            markov_samples: DEFAULT_MARKOV_SAMPLES,
            gain: false,
            sample_time_s: 1.0,
        }
    }
}

/// Default number of system Markov blocks.
pub(crate) const DEFAULT_MARKOV_SAMPLES: usize = 1024;

/// The front ends' default number of Markov blocks for records whose longest has
/// `longest` samples: the judging frame ([`crate::estimate::DEFAULT_FRAME`]), or
/// the record when it is shorter (blocks past the record are not in the data).
pub fn default_markov_samples(longest: usize) -> usize {
    crate::estimate::DEFAULT_FRAME.min(longest)
}

/// Points on the unit circle at which the observer's transfer function is evaluated for
/// `samples` Markov blocks at observer order `p`: enough that the inverse transform's
/// aliasing stays below the blocks' own decay.
fn unit_circle_points(samples: usize, p: usize) -> usize {
    samples
        .saturating_mul(8)
        .max(4 * p + 4)
        .checked_next_power_of_two()
        .unwrap_or(usize::MAX)
        .max(4096)
}

/// The most regressors (`r + p(r+q)`) an observer may have: its triangle and the SVD
/// of it stay below a second and 40 MB.
pub const MAX_REGRESSORS: usize = 2000;

/// How the system Markov parameters were obtained from the observer's.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum MarkovRoute {
    /// The recursion, run forward (a stable observer).
    Recursion,
    /// On the unit circle and inverse transformed (an observer with roots outside it).
    UnitCircle {
        /// Points of the transform.
        points: usize,
    },
}

/// What [`okid`] found.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct Okid {
    /// The system Markov blocks, `Y_0 = D`, `Y_k = C A^(k−1) B`.
    pub markov: MarkovSequence,
    /// The observer gain's Markov blocks `C A^(k−1) G` (block 0 is zero), when asked.
    pub gain_markov: Option<MarkovSequence>,
    /// The observer order used.
    pub observer_order: usize,
    /// The information criterion of every order tried (empty for a fixed order).
    pub criterion: Vec<(usize, f64)>,
    /// The largest modulus of the observer's roots (≥ 1: not stable).
    pub observer_radius: f64,
    /// How the system Markov parameters were obtained.
    pub route: MarkovRoute,
    /// Equations (samples) in the regression.
    pub equations: usize,
    /// Unknowns per output, `r + p(r+q)`.
    pub regressors: usize,
    /// Numerical rank of the regressors at the chosen order.
    pub rank: usize,
    /// RMS of the one-step residual of each output, relative to the output's RMS.
    pub residual: Vec<f64>,
}

/// The observer's Markov parameters in scaled units.
#[derive(Debug, Clone)]
struct Observer {
    q: usize,
    r: usize,
    /// `D`, q×r.
    d: Mat<f64>,
    /// `Ȳ⁽¹⁾_i`, q×r, i = 1..p.
    y1: Vec<Mat<f64>>,
    /// `Ȳ⁽²⁾_i`, q×q, i = 1..p.
    y2: Vec<Mat<f64>>,
}

/// The default largest observer order for `q` outputs: enough lags for `p q ≥ 200`
/// states (at least 10), within [`MAX_REGRESSORS`].
pub(crate) fn default_max_observer_order(inputs: usize, outputs: usize) -> usize {
    let p = 200usize.div_ceil(outputs.max(1)).max(10);
    p.min((MAX_REGRESSORS - inputs.min(MAX_REGRESSORS)) / (inputs + outputs).max(1))
        .max(1)
}

/// The channels' shape, checked: `(inputs, outputs, samples per record)`.
fn check_records(records: &[Record]) -> Result<(usize, usize, Vec<usize>)> {
    let first = records.first().ok_or_else(|| EraError::ShapeMismatch {
        what: "records (at least 1)".into(),
        expected: 1,
        got: 0,
    })?;
    let (r, q) = (first.inputs.len(), first.outputs.len());
    if r == 0 || q == 0 {
        return Err(EraError::ShapeMismatch {
            what: "number of input and output channels (at least 1 each)".into(),
            expected: 1,
            got: r.min(q),
        });
    }
    let mut lengths = Vec::with_capacity(records.len());
    for (n, rec) in records.iter().enumerate() {
        for (what, got, expected) in [
            ("input channels", rec.inputs.len(), r),
            ("output channels", rec.outputs.len(), q),
        ] {
            if got != expected {
                return Err(EraError::ShapeMismatch {
                    what: format!("{what} of record {} (record 1 has {expected})", n + 1),
                    expected,
                    got,
                });
            }
        }
        lengths.push(crate::estimate::check_record(
            rec.inputs,
            rec.outputs,
            Some(n + 1),
        )?);
    }
    Ok((r, q, lengths))
}

/// The records as the regression sees them: each channel less its mean (per record),
/// over its RMS (over all records). The records are read in place, sample by sample, as
/// the blocks of the data matrix are built: a long record is never copied.
struct Scaled<'a> {
    records: &'a [Record<'a>],
    /// `means[record][c]`, inputs first.
    means: Vec<Vec<f64>>,
    input_scale: Vec<f64>,
    output_scale: Vec<f64>,
}

impl<'a> Record<'a> {
    /// Channel `c`, inputs first.
    fn channel(&self, c: usize) -> &'a [f64] {
        let r = self.inputs.len();
        if c < r {
            self.inputs[c]
        } else {
            self.outputs[c - r]
        }
    }
}

impl Scaled<'_> {
    /// Channel `c` (inputs first) of record `n`.
    fn channel(&self, n: usize, c: usize) -> &[f64] {
        self.records[n].channel(c)
    }

    fn scale(&self, c: usize) -> f64 {
        let r = self.input_scale.len();
        if c < r {
            self.input_scale[c]
        } else {
            self.output_scale[c - r]
        }
    }

    /// Samples of record `n`.
    fn len(&self, n: usize) -> usize {
        self.records[n].inputs[0].len()
    }
}

fn scale_records<'a>(records: &'a [Record<'a>], r: usize, q: usize) -> Result<Scaled<'a>> {
    let means: Vec<Vec<f64>> = records
        .iter()
        .map(|rec| {
            (0..r + q)
                .map(|c| {
                    let ch = rec.channel(c);
                    ch.iter().sum::<f64>() / ch.len().max(1) as f64
                })
                .collect()
        })
        .collect();
    let total: usize = records.iter().map(|rec| rec.inputs[0].len()).sum();
    let mut scale = vec![0.0; r + q];
    for (c, s) in scale.iter_mut().enumerate() {
        let centred = || {
            records
                .iter()
                .zip(&means)
                .flat_map(move |(rec, m)| rec.channel(c).iter().map(move |v| v - m[c]))
        };
        // Scaled by the largest magnitude first: the sum of squares cannot overflow.
        let peak = centred().fold(0.0f64, |m, v| m.max(v.abs()));
        if peak > 0.0 {
            let ss: f64 = centred().map(|v| (v / peak) * (v / peak)).sum();
            *s = peak * (ss / total.max(1) as f64).sqrt();
        }
    }
    for (j, s) in scale.iter().take(r).enumerate() {
        if !(*s > 0.0 && s.is_finite()) {
            return Err(EraError::DeficientInput {
                input: j + 1,
                reason: "it has no energy (constant over every record): OKID needs every input to excite the structure".into(),
            });
        }
    }
    // An output that is constant carries nothing; it keeps scale 1 (its blocks are zero).
    for s in scale.iter_mut().skip(r) {
        if !(*s > 0.0 && s.is_finite()) {
            *s = 1.0;
        }
    }
    Ok(Scaled {
        records,
        means,
        output_scale: scale.split_off(r),
        input_scale: scale,
    })
}

/// Regressors of order `p`: `r + p(r+q)`.
fn regressors(r: usize, q: usize, p: usize) -> usize {
    r + p * (r + q)
}

/// Rows `ks` of record `n` of the data matrix `[Φ | Y]` at order `p`.
fn data_rows(
    data: &Scaled,
    n: usize,
    r: usize,
    q: usize,
    p: usize,
    ks: std::ops::Range<usize>,
) -> Mat<f64> {
    let m = regressors(r, q, p);
    let rows = ks.len();
    let mut block = Mat::<f64>::zeros(rows, m + q);
    for col in 0..m + q {
        // Which channel at which lag this column holds.
        let (channel, lag) = if col < r {
            (col, 0)
        } else if col < m {
            let c = col - r;
            (c % (r + q), c / (r + q) + 1)
        } else {
            (r + col - m, 0)
        };
        let src = data.channel(n, channel);
        let (mean, scale) = (data.means[n][channel], data.scale(channel));
        for (row, k) in ks.clone().enumerate() {
            block[(row, col)] = (src[k - lag] - mean) / scale;
        }
    }
    block
}

/// The upper triangle `R` of `[upper; block]` (rows beyond the columns dropped).
fn stack_qr(upper: Option<Mat<f64>>, block: Mat<f64>) -> Mat<f64> {
    let stacked = match upper {
        None => block,
        Some(u) => {
            let cols = block.ncols();
            let (a, b) = (u.nrows(), block.nrows());
            Mat::from_fn(a + b, cols, |i, j| {
                if i < a {
                    u[(i, j)]
                } else {
                    block[(i - a, j)]
                }
            })
        }
    };
    stacked.qr().thin_R().to_owned()
}

/// The most rows of one block of the blocked QR.
fn block_rows(columns: usize) -> usize {
    (4 * columns).max(BLOCK_BYTES / 8 / columns.max(1))
}

/// Rows per block for `rows` rows of a record: blocks of equal size, at most `most`
/// rows, and an even number of them when there are several, so that two threads share
/// them evenly (the split depends on the record, never on the thread count).
fn balanced_step(rows: usize, most: usize) -> usize {
    let mut count = rows.div_ceil(most.max(1)).max(1);
    if count > 1 && count % 2 == 1 {
        count += 1;
    }
    rows.div_ceil(count).max(1)
}

/// Bytes of one block of the data matrix at most (at least four rows per column). Each
/// thread holds a block, its stack with the triangle so far and the factor of that: with
/// 32 MB blocks a 60-minute record of 18 MB peaked 208 MB above itself, with 16 MB
/// 107 MB (the whole data matrix would be 479 MB). DaISy's 23 MB data matrix is then
/// two equal blocks factored side by side: 0.044 s, against 0.059 s in three blocks of
/// 8 MB and 0.072 s in one.
const BLOCK_BYTES: usize = 16 << 20;

/// How the data matrix is factored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Blocks {
    /// Whole, in one QR (the reference).
    Whole,
    /// In blocks of [`block_rows`] rows.
    Budget,
    /// In blocks of this many rows (tests of the merge).
    #[cfg(test)]
    Rows(usize),
}

/// The triangle of the whole data matrix of every record at order `p`, rows `k ≥ first`
/// of each record, and the number of rows.
fn data_triangle(
    data: &Scaled,
    r: usize,
    q: usize,
    p: usize,
    first: usize,
    blocks: Blocks,
) -> Result<(Mat<f64>, usize)> {
    let cols = regressors(r, q, p) + q;
    let mut spans: Vec<(usize, std::ops::Range<usize>)> = Vec::new();
    let naive = blocks == Blocks::Whole;
    for n in 0..data.records.len() {
        let len = data.len(n);
        let step = match blocks {
            Blocks::Whole => len.max(1),
            Blocks::Budget => balanced_step(len.saturating_sub(first), block_rows(cols)),
            #[cfg(test)]
            Blocks::Rows(rows) => rows.max(1),
        };
        let mut k = first;
        while k < len {
            let end = (k + step).min(len);
            spans.push((n, k..end));
            k = end;
        }
    }
    let rows: usize = spans.iter().map(|(_, s)| s.len()).sum();
    if naive {
        let mut whole = Mat::<f64>::zeros(rows, cols);
        let mut at = 0;
        for (n, s) in &spans {
            let b = data_rows(data, *n, r, q, p, s.clone());
            for i in 0..b.nrows() {
                for j in 0..cols {
                    whole[(at + i, j)] = b[(i, j)];
                }
            }
            at += b.nrows();
        }
        return Ok((whole.qr().thin_R().to_owned(), rows));
    }
    // Fixed groups of consecutive blocks (independent of the thread count), each reduced
    // in order, then merged in order.
    const GROUPS: usize = 8;
    let per_group = spans.len().div_ceil(GROUPS).max(1);
    // rayon's workers do not see the caller's cancel token: it is handed to them.
    let token = crate::cancel::current();
    let partial: Vec<Mat<f64>> = spans
        .par_chunks(per_group)
        .map(|group| {
            let mut upper = None;
            for (n, s) in group {
                crate::cancel::check_token(&token)?;
                let b = data_rows(data, *n, r, q, p, s.clone());
                upper = Some(stack_qr(upper, b));
            }
            Ok(upper.expect("a group has a block"))
        })
        .collect::<Result<_>>()?;
    let mut upper: Option<Mat<f64>> = None;
    for t in partial {
        upper = Some(match upper {
            None => t,
            Some(u) => stack_qr(Some(u), t),
        });
    }
    Ok((upper.expect("at least one block"), rows))
}

/// `ln det(S/N + floor·I)` for a symmetric positive semi-definite `S`.
fn log_det(s: &Mat<f64>, n: f64) -> f64 {
    let q = s.nrows();
    let m = Mat::from_fn(q, q, |i, j| {
        s[(i, j)] / n + if i == j { LOG_DET_FLOOR } else { 0.0 }
    });
    match m.llt(faer::Side::Lower) {
        Ok(llt) => (0..q).map(|i| 2.0 * llt.L()[(i, i)].ln()).sum(),
        Err(_) => f64::NEG_INFINITY,
    }
}

/// Observer roots this far outside the unit circle still run the recursion: they grow
/// by at most `e^(1e-6 k)` over `k` blocks (exact data puts free roots on the circle).
const MARGINAL_ROOT: f64 = 1e-6;

/// Floor of the residual covariance, in units of the outputs' variance.
const LOG_DET_FLOOR: f64 = 1e-12;

/// Singular values of the regressors' triangle below this fraction of the largest are
/// taken as dependence.
const RANK_TOLERANCE: f64 = 1e-10;

/// An input whose column of the triangle is below this fraction of its norm is (nearly)
/// a linear combination of the inputs before it.
const DEPENDENT_INPUT: f64 = 1e-6;

/// The information criterion of every order `1..=p_max` from the triangle at `p_max`.
fn criterion(tri: &Mat<f64>, rows: usize, r: usize, q: usize, p_max: usize) -> Vec<(usize, f64)> {
    let m = regressors(r, q, p_max);
    let n = rows as f64;
    // S = R₂₂ᵀ R₂₂, then the rows of R₁₂ from the top order down.
    let mut s = Mat::<f64>::zeros(q, q);
    let add_row = |s: &mut Mat<f64>, row: usize| {
        for a in 0..q {
            let va = tri[(row, m + a)];
            if va == 0.0 {
                continue;
            }
            for b in 0..q {
                s[(a, b)] += va * tri[(row, m + b)];
            }
        }
    };
    for row in m..(m + q).min(tri.nrows()) {
        add_row(&mut s, row);
    }
    let mut out = Vec::with_capacity(p_max);
    let mut next = m;
    for p in (1..=p_max).rev() {
        let mp = regressors(r, q, p);
        for row in mp..next {
            add_row(&mut s, row);
        }
        next = mp;
        let value = n * log_det(&s, n) + (q * mp) as f64 * n.ln();
        out.push((p, value));
    }
    out.reverse();
    out
}

/// Least-squares coefficients `θ` (m_p × q) at order `p` from the triangle at `p_max`,
/// and the numerical rank of the regressors.
fn coefficients(
    tri: &Mat<f64>,
    r: usize,
    q: usize,
    p: usize,
    p_max: usize,
) -> Result<(Mat<f64>, usize)> {
    let m = regressors(r, q, p_max);
    let mp = regressors(r, q, p);
    let r11 = tri.get(..mp, ..mp).to_owned();
    let r12 = tri.get(..mp, m..m + q).to_owned();
    let svd = r11
        .svd()
        .map_err(|e| EraError::Numerical(format!("SVD of the OKID regressors: {e:?}")))?;
    let sv: Vec<f64> = (0..mp).map(|i| svd.S()[i]).collect();
    let top = sv.first().copied().unwrap_or(0.0);
    let rank = sv.iter().filter(|&&v| v > RANK_TOLERANCE * top).count();
    // θ = V Σ⁺ Uᵀ R₁₂ over the kept singular values.
    let utr = svd.U().get(.., ..rank).transpose() * &r12;
    let scaled = Mat::from_fn(rank, q, |i, j| utr[(i, j)] / sv[i]);
    let theta = svd.V().get(.., ..rank) * &scaled;
    Ok((theta, rank))
}

fn unpack(theta: &Mat<f64>, r: usize, q: usize, p: usize) -> Observer {
    let d = Mat::from_fn(q, r, |i, j| theta[(j, i)]);
    let mut y1 = Vec::with_capacity(p);
    let mut y2 = Vec::with_capacity(p);
    for lag in 1..=p {
        let base = r + (lag - 1) * (r + q);
        y1.push(Mat::from_fn(q, r, |i, j| theta[(base + j, i)]));
        y2.push(Mat::from_fn(q, q, |i, j| theta[(base + r + j, i)]));
    }
    Observer { q, r, d, y1, y2 }
}

/// The largest modulus of the roots of `det(z^p I − Σ Ȳ⁽²⁾_i z^(p−i))`.
fn observer_radius(obs: &Observer) -> Result<f64> {
    let (p, q) = (obs.y2.len(), obs.q);
    if p == 0 {
        return Ok(0.0);
    }
    let n = p * q;
    let companion = Mat::from_fn(n, n, |i, j| {
        if i < q {
            obs.y2[j / q][(i, j % q)]
        } else if j + q == i {
            1.0
        } else {
            0.0
        }
    });
    let roots = companion
        .eigenvalues()
        .map_err(|e| EraError::Numerical(format!("roots of the OKID observer: {e:?}")))?;
    Ok(roots.iter().map(|z| z.norm()).fold(0.0, f64::max))
}

/// `Y_0 … Y_(L−1)` by the recursion, scaled units, `[k][i][j]`.
fn recursion(obs: &Observer, samples: usize) -> Vec<Mat<f64>> {
    let p = obs.y2.len();
    let mut y: Vec<Mat<f64>> = Vec::with_capacity(samples);
    for k in 0..samples {
        let next = if k == 0 {
            obs.d.clone()
        } else {
            let mut acc = if k <= p {
                obs.y1[k - 1].clone()
            } else {
                Mat::zeros(obs.q, obs.r)
            };
            for i in 1..=k.min(p) {
                acc += &obs.y2[i - 1] * &y[k - i];
            }
            acc
        };
        y.push(next);
    }
    y
}

/// The observer gain's Markov blocks `Y^o_0 = 0, Y^o_k`, scaled units.
fn gain_recursion(obs: &Observer, samples: usize) -> Vec<Mat<f64>> {
    let p = obs.y2.len();
    let q = obs.q;
    let mut y: Vec<Mat<f64>> = Vec::with_capacity(samples);
    for k in 0..samples {
        let next = if k == 0 {
            Mat::zeros(q, q)
        } else {
            let mut acc = if k <= p {
                -&obs.y2[k - 1]
            } else {
                Mat::zeros(q, q)
            };
            for i in 1..k.min(p + 1) {
                acc += &obs.y2[i - 1] * &y[k - i];
            }
            acc
        };
        y.push(next);
    }
    y
}

/// `Y_0 … Y_(L−1)` from the observer's transfer function on the unit circle (`points`
/// of it), scaled units.
fn unit_circle(obs: &Observer, samples: usize, points: usize) -> Result<Vec<Mat<f64>>> {
    let (p, q, r) = (obs.y2.len(), obs.q, obs.r);
    let (forward, inverse) = real_fft_plans(points);
    let lines = points / 2 + 1;
    let transform = |coeff: &dyn Fn(usize) -> f64| -> Vec<Complex64> {
        let mut buf = vec![0.0; points];
        for (k, slot) in buf.iter_mut().enumerate().take(p + 1) {
            *slot = coeff(k);
        }
        let mut out = forward.make_output_vec();
        forward
            .process(&mut buf, &mut out)
            .expect("buffers of the planned length");
        out
    };
    // Numerator N = D + Ȳ⁽¹⁾(z), q×r; denominator I − Ȳ⁽²⁾(z), q×q; per line.
    let num: Vec<Vec<Complex64>> = (0..q * r)
        .into_par_iter()
        .map(|e| {
            let (i, j) = (e / r, e % r);
            transform(&|k| {
                if k == 0 {
                    obs.d[(i, j)]
                } else {
                    obs.y1[k - 1][(i, j)]
                }
            })
        })
        .collect();
    let den: Vec<Vec<Complex64>> = (0..q * q)
        .into_par_iter()
        .map(|e| {
            let (i, j) = (e / q, e % q);
            let delta = if i == j { 1.0 } else { 0.0 };
            transform(&|k| {
                if k == 0 {
                    delta
                } else {
                    -obs.y2[k - 1][(i, j)]
                }
            })
        })
        .collect();
    let h: Vec<Mat<Complex64>> = (0..lines)
        .into_par_iter()
        .map(|l| {
            let a = Mat::from_fn(q, q, |i, j| den[i * q + j][l]);
            let b = Mat::from_fn(q, r, |i, j| num[i * r + j][l]);
            a.partial_piv_lu().solve(&b)
        })
        .collect();
    if h.iter()
        .any(|m| (0..q).any(|i| (0..r).any(|j| !m[(i, j)].is_finite())))
    {
        return Err(EraError::Numerical(
            "the OKID observer has a root on the unit circle: its transfer function is infinite there".into(),
        ));
    }
    let series: Vec<Vec<f64>> = (0..q * r)
        .into_par_iter()
        .map(|e| {
            let (i, j) = (e / r, e % r);
            let mut spec: Vec<Complex64> = h.iter().map(|m| m[(i, j)]).collect();
            // The real transform's end lines must be real.
            spec[0].im = 0.0;
            spec[lines - 1].im = 0.0;
            let mut out = inverse.make_output_vec();
            inverse
                .process(&mut spec, &mut out)
                .expect("buffers of the planned length");
            out.truncate(samples);
            out.iter_mut().for_each(|v| *v /= points as f64);
            out
        })
        .collect();
    Ok((0..samples)
        .map(|k| Mat::from_fn(q, r, |i, j| series[i * r + j][k]))
        .collect())
}

/// Blocks in scaled units back to the data's units: `Y[i][j] · s_out[i] / s_in[j]`.
fn unscale(blocks: &[Mat<f64>], out_scale: &[f64], in_scale: &[f64]) -> MarkovSequence {
    let (q, r) = (out_scale.len(), in_scale.len());
    MarkovSequence::from_fn(q, r, blocks.len(), |k, i, j| {
        blocks[k][(i, j)] * out_scale[i] / in_scale[j]
    })
}

/// The system's Markov parameters from input and output time histories.
///
/// # Errors
/// [`EraError::ShapeMismatch`] for no records or channels, or channels of unequal length
/// or count; [`EraError::NonFiniteSample`]; [`EraError::DeficientInput`] for an input
/// with no energy or one that is a linear combination of the others;
/// [`EraError::InvalidParameter`] naming `observer_order` or `markov_samples` for an
/// order the records are too short for or beyond [`MAX_REGRESSORS`], or no samples;
/// [`EraError::Numerical`] when a decomposition fails.
pub fn okid(records: &[Record], options: &OkidOptions) -> Result<Okid> {
    run(records, options, Blocks::Budget)
}

/// [`okid`] with the whole data matrix factored at once (the reference of the blocked
/// QR).
///
/// # Errors
/// As [`okid`].
#[cfg(test)]
fn okid_naive(records: &[Record], options: &OkidOptions) -> Result<Okid> {
    run(records, options, Blocks::Whole)
}

fn run(records: &[Record], options: &OkidOptions, blocks: Blocks) -> Result<Okid> {
    let (r, q, lengths) = check_records(records)?;
    if options.markov_samples < 2 {
        return Err(EraError::InvalidParameter {
            name: "markov_samples",
            value: options.markov_samples.to_string(),
            reason: "need at least 2 Markov blocks (the direct term and one more)".into(),
        });
    }
    let longest = lengths.iter().copied().max().unwrap_or(0);
    if options.markov_samples > longest {
        return Err(EraError::InvalidParameter {
            name: "markov_samples",
            value: options.markov_samples.to_string(),
            reason: format!(
                "the longest record has {longest} samples: Markov blocks past it are not in the data"
            ).into(),
        });
    }
    crate::params::limits::VALUES.check_product(
        crate::params::names::Prose::default().param(crate::params::names::Param::MarkovSamples),
        &[options.markov_samples as u64, r as u64, q as u64],
    )?;
    let equations = |p: usize| -> usize { lengths.iter().map(|&l| l.saturating_sub(p)).sum() };
    // An order is usable when the regression has at least twice as many equations as
    // unknowns.
    let usable = |p: usize| equations(p) >= 2 * regressors(r, q, p) && p < longest;
    let (p_max, fixed) = match options.observer_order {
        ObserverOrder::Fixed(p) => {
            if p == 0 || regressors(r, q, p) > MAX_REGRESSORS {
                return Err(EraError::InvalidParameter {
                    name: "observer_order",
                    value: p.to_string(),
                    reason: format!(
                        "need 1 to {} lags for {r} inputs and {q} outputs (at most {MAX_REGRESSORS} regressors)",
                        (MAX_REGRESSORS - r.min(MAX_REGRESSORS)) / (r + q)
                    ).into(),
                });
            }
            if !usable(p) {
                return Err(too_short(p, r, q, &lengths));
            }
            (p, true)
        }
        ObserverOrder::Auto { max } => {
            let cap = max.unwrap_or_else(|| default_max_observer_order(r, q));
            if cap == 0 || regressors(r, q, cap) > MAX_REGRESSORS {
                return Err(EraError::InvalidParameter {
                    name: "observer_order",
                    value: format!("auto up to {cap}"),
                    reason: format!(
                        "the largest order must be 1 to {}",
                        (MAX_REGRESSORS - r.min(MAX_REGRESSORS)) / (r + q)
                    )
                    .into(),
                });
            }
            let mut p = cap;
            while p > 1 && !usable(p) {
                p -= 1;
            }
            if !usable(p) {
                return Err(too_short(1, r, q, &lengths));
            }
            (p, false)
        }
    };
    // The unit circle's transfer function (the route an unstable observer takes) holds
    // `points` values per input-output pair: checked before anything is built.
    crate::params::limits::VALUES.check_product(
        crate::params::names::Prose::default()
            .param(crate::params::names::Param::MarkovSamples)
            .text(" (the observer's transfer function on the unit circle)"),
        &[
            unit_circle_points(options.markov_samples, p_max) as u64,
            r as u64,
            q as u64,
        ],
    )?;
    let data = scale_records(records, r, q)?;
    let (tri, rows) = data_triangle(&data, r, q, p_max, p_max, blocks)?;
    // Dependent inputs: the current inputs come first, so their diagonal says whether
    // input j adds anything to inputs 1..j−1.
    let norm = (rows as f64).sqrt();
    for j in 0..r {
        if tri[(j, j)].abs() < DEPENDENT_INPUT * norm {
            return Err(EraError::DeficientInput {
                input: j + 1,
                reason: if j == 0 {
                    "it has no energy in the samples the observer uses".into()
                } else {
                    format!(
                        "it is a linear combination of inputs 1–{j} (its independent part is {:.1e} of its RMS): drop it, or excite the structure with independent signals",
                        tri[(j, j)].abs() / norm
                    )
                },
            });
        }
    }
    let crit = if fixed {
        Vec::new()
    } else {
        criterion(&tri, rows, r, q, p_max)
    };
    let p = if fixed {
        p_max
    } else {
        crit.iter()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map_or(p_max, |c| c.0)
    };
    let (theta, rank) = coefficients(&tri, r, q, p, p_max)?;
    let residual = residual_rms(&tri, rows, r, q, p, p_max);
    let obs = unpack(&theta, r, q, p);
    let samples = options.markov_samples;
    let points = unit_circle_points(samples, p);
    // The roots decide the route. Their eigenvalue problem runs on one thread while the
    // other computes the unit circle's sequence (the recursion's is cheap and follows),
    // so a route that needs the circle does not wait for the roots first.
    let (radius, circle) = rayon::join(
        || observer_radius(&obs),
        || unit_circle(&obs, samples, points),
    );
    let radius = radius?;
    let (blocks, route) = if radius <= 1.0 + MARGINAL_ROOT {
        (recursion(&obs, samples), MarkovRoute::Recursion)
    } else {
        (circle?, MarkovRoute::UnitCircle { points })
    };
    let markov = unscale(&blocks, &data.output_scale, &data.input_scale)
        .with_sample_time(options.sample_time_s);
    let gain_markov = options.gain.then(|| {
        let g = gain_recursion(&obs, samples);
        unscale(&g, &data.output_scale, &data.output_scale).with_sample_time(options.sample_time_s)
    });
    Ok(Okid {
        markov,
        gain_markov,
        observer_order: p,
        criterion: crit,
        observer_radius: radius,
        route,
        equations: rows,
        regressors: regressors(r, q, p),
        rank,
        residual,
    })
}

fn too_short(p: usize, r: usize, q: usize, lengths: &[usize]) -> EraError {
    let m = regressors(r, q, p);
    EraError::InvalidParameter {
        name: "observer_order",
        value: p.to_string(),
        reason: format!(
            "an observer of order {p} has {m} unknowns per output and needs at least {} samples past its first {p}; the records have {} samples ({}): record longer, or a lower order",
            2 * m,
            lengths.iter().sum::<usize>(),
            lengths
                .iter()
                .map(|l| l.to_string())
                .collect::<Vec<_>>()
                .join(" + ")
        ).into(),
    }
}

/// RMS of each output's one-step residual at order `p`, relative to its RMS (scaled
/// units: the outputs have unit RMS).
fn residual_rms(
    tri: &Mat<f64>,
    rows: usize,
    r: usize,
    q: usize,
    p: usize,
    p_max: usize,
) -> Vec<f64> {
    let m = regressors(r, q, p_max);
    let mp = regressors(r, q, p);
    (0..q)
        .map(|i| {
            let ss: f64 = (mp..(m + q).min(tri.nrows()))
                .map(|row| tri[(row, m + i)].powi(2))
                .sum();
            (ss / rows.max(1) as f64).sqrt()
        })
        .collect()
}

/// The Kalman gain `K` of the innovation form `x_{k+1} = A x_k + B u_k + K e_k` of a
/// discrete `model` realized from [`Okid::markov`], from the observer gain's Markov
/// blocks ([`Okid::gain_markov`]): `K = −O⁺ [Y^o_1; …; Y^o_L]`, with `L` the fewest blocks
/// whose observability matrix has `2n` rows or more (at least 4).
///
/// # Errors
/// [`EraError::ShapeMismatch`] when the blocks' outputs differ from the model's or there
/// are too few of them; [`EraError::Numerical`] when the solve fails.
pub fn kalman_gain(model: &StateSpace, gain_markov: &MarkovSequence) -> Result<Mat<f64>> {
    let (n, q) = (model.states(), model.outputs());
    if gain_markov.outputs() != q || gain_markov.inputs() != q {
        return Err(EraError::ShapeMismatch {
            what: "outputs of the observer gain's Markov blocks".into(),
            expected: q,
            got: gain_markov.outputs(),
        });
    }
    let blocks = (2 * n).div_ceil(q.max(1)).max(4);
    if gain_markov.samples() < blocks + 1 {
        return Err(EraError::ShapeMismatch {
            what: "observer gain Markov blocks".into(),
            expected: blocks + 1,
            got: gain_markov.samples(),
        });
    }
    let mut obs = Mat::<f64>::zeros(blocks * q, n);
    let mut ca = model.c.clone();
    for k in 0..blocks {
        for i in 0..q {
            for j in 0..n {
                obs[(k * q + i, j)] = ca[(i, j)];
            }
        }
        ca = &ca * &model.a;
    }
    let rhs = Mat::from_fn(blocks * q, q, |row, j| {
        gain_markov.get(row / q + 1, row % q, j)
    });
    let g = obs.qr().solve_lstsq(&rhs);
    Ok(-g)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::frf::Quantity;
    use crate::linalg::rng::Minstd;
    use crate::sim::{time_response, ModalSpec, ModalStructure};
    use era_testkit::{assert_matches_naive, Scale};

    /// A sampled structure and a white-noise record of it: (model, inputs, outputs).
    fn test_record(
        spec: &ModalSpec,
        fs: f64,
        samples: usize,
        seed: u64,
    ) -> (StateSpace, Vec<Vec<f64>>, Vec<Vec<f64>>) {
        let s = ModalStructure::random(spec).unwrap();
        let model = s.state_space(Quantity::Acceleration).c2d(1.0 / fs).unwrap();
        let mut rng = Minstd::new(seed);
        let inputs: Vec<Vec<f64>> = (0..spec.inputs)
            .map(|_| (0..samples).map(|_| rng.normal()).collect())
            .collect();
        let outputs = time_response(&model, &inputs).unwrap();
        (model, inputs, outputs)
    }

    fn exact_markov(model: &StateSpace, k: usize) -> Mat<f64> {
        if k == 0 {
            return model.d.clone();
        }
        let mut x = model.b.clone();
        for _ in 1..k {
            x = &model.a * &x;
        }
        &model.c * &x
    }

    fn refs(v: &[Vec<f64>]) -> Vec<&[f64]> {
        v.iter().map(Vec::as_slice).collect()
    }

    fn max_rel_error(found: &MarkovSequence, model: &StateSpace, samples: usize) -> f64 {
        let mut worst = 0.0f64;
        let mut scale = 0.0f64;
        for k in 0..samples {
            let e = exact_markov(model, k);
            for i in 0..e.nrows() {
                for j in 0..e.ncols() {
                    scale = scale.max(e[(i, j)].abs());
                    worst = worst.max((found.get(k, i, j) - e[(i, j)]).abs());
                }
            }
        }
        worst / scale
    }

    #[test]
    fn exact_data_gives_the_markov_parameters() {
        let spec = ModalSpec {
            fmin_hz: 1.0,
            fmax_hz: 20.0,
            collocated: false,
            ..ModalSpec::new(3, 2, 4)
        };
        let (model, u, y) = test_record(&spec, 64.0, 3000, 5);
        let (ui, yi) = (refs(&u), refs(&y));
        let rec = Record {
            inputs: &ui,
            outputs: &yi,
        };
        for order in [
            ObserverOrder::Fixed(3),
            ObserverOrder::Fixed(5),
            ObserverOrder::Fixed(12),
            ObserverOrder::default(),
        ] {
            let found = okid(
                &[rec],
                &OkidOptions {
                    observer_order: order,
                    markov_samples: 200,
                    ..OkidOptions::default()
                },
            )
            .unwrap();
            let err = max_rel_error(&found.markov, &model, 200);
            assert!(
                err < 1e-8,
                "{order:?}: relative error {err:e} (p = {})",
                found.observer_order
            );
        }
    }

    #[test]
    fn blocked_qr_matches_the_whole_matrix() {
        let spec = ModalSpec {
            fmin_hz: 1.0,
            fmax_hz: 20.0,
            collocated: false,
            ..ModalSpec::new(3, 2, 5)
        };
        let (_, u, mut y) = test_record(&spec, 64.0, 5000, 9);
        let mut rng = Minstd::new(77);
        for ch in y.iter_mut() {
            for v in ch.iter_mut() {
                *v += 0.05 * rng.normal();
            }
        }
        let (ui, yi) = (refs(&u), refs(&y));
        let (ua, ya) = (refs(&u[..]), refs(&y[..]));
        let half = 2500;
        let u1: Vec<&[f64]> = ua.iter().map(|c| &c[..half]).collect();
        let y1: Vec<&[f64]> = ya.iter().map(|c| &c[..half]).collect();
        let u2: Vec<&[f64]> = ua.iter().map(|c| &c[half..]).collect();
        let y2: Vec<&[f64]> = ya.iter().map(|c| &c[half..]).collect();
        for recs in [
            vec![Record {
                inputs: &ui,
                outputs: &yi,
            }],
            vec![
                Record {
                    inputs: &u1,
                    outputs: &y1,
                },
                Record {
                    inputs: &u2,
                    outputs: &y2,
                },
            ],
        ] {
            let options = OkidOptions {
                observer_order: ObserverOrder::Auto { max: Some(12) },
                markov_samples: 100,
                ..OkidOptions::default()
            };
            let naive = okid_naive(&recs, &options).unwrap();
            // The default budget (one block here), and blocks of 300 rows merged in
            // fixed groups.
            for blocks in [Blocks::Budget, Blocks::Rows(300)] {
                let fast = run(&recs, &options, blocks).unwrap();
                assert_eq!(fast.observer_order, naive.observer_order);
                assert_eq!(fast.equations, naive.equations);
                let blocks_of = |o: &Okid| -> Vec<f64> {
                    (0..100)
                        .flat_map(|k| (0..3).flat_map(move |i| (0..2).map(move |j| (k, i, j))))
                        .map(|(k, i, j)| o.markov.get(k, i, j))
                        .collect()
                };
                // Two least-squares solutions of the observer equations: their agreement
                // is bounded by the equations' conditioning, which is not computed here.
                assert_matches_naive(
                    &format!("OKID Markov blocks, {blocks:?}"),
                    &blocks_of(&fast),
                    &blocks_of(&naive),
                    Scale::Largest,
                    1e-10,
                );
            }
        }
    }

    /// The recursion keeps the `Ȳ⁽²⁾_k D` term: with a direct term, dropping it is wrong
    /// in the first `p` blocks.
    #[test]
    fn the_recursion_keeps_the_direct_term() {
        let spec = ModalSpec {
            fmin_hz: 2.0,
            fmax_hz: 10.0,
            collocated: false,
            ..ModalSpec::new(2, 1, 2)
        };
        let (model, u, y) = test_record(&spec, 50.0, 2000, 3);
        assert!(model.d.norm_max() > 1e-3, "acceleration has a direct term");
        let (ui, yi) = (refs(&u), refs(&y));
        let found = okid(
            &[Record {
                inputs: &ui,
                outputs: &yi,
            }],
            &OkidOptions {
                observer_order: ObserverOrder::Fixed(8),
                markov_samples: 20,
                ..OkidOptions::default()
            },
        )
        .unwrap();
        assert!(max_rel_error(&found.markov, &model, 20) < 1e-8);
    }

    #[test]
    fn the_unit_circle_route_matches_the_recursion_on_a_stable_observer() {
        let spec = ModalSpec {
            fmin_hz: 2.0,
            fmax_hz: 10.0,
            damping_min: 0.05,
            damping_max: 0.1,
            collocated: false,
            ..ModalSpec::new(2, 1, 2)
        };
        let (_, u, mut y) = test_record(&spec, 50.0, 4000, 4);
        let mut rng = Minstd::new(8);
        for ch in y.iter_mut() {
            for v in ch.iter_mut() {
                *v += 0.01 * rng.normal();
            }
        }
        let (ui, yi) = (refs(&u), refs(&y));
        let records = [Record {
            inputs: &ui,
            outputs: &yi,
        }];
        let data = scale_records(&records, 1, 2).unwrap();
        let (tri, _) = data_triangle(&data, 1, 2, 10, 10, Blocks::Budget).unwrap();
        let (theta, _) = coefficients(&tri, 1, 2, 10, 10).unwrap();
        let obs = unpack(&theta, 1, 2, 10);
        assert!(observer_radius(&obs).unwrap() < 0.99);
        let a = recursion(&obs, 64);
        let b = unit_circle(&obs, 64, 1 << 16).unwrap();
        let column = |m: &[Mat<f64>]| -> Vec<f64> {
            m.iter()
                .flat_map(|x| (0..2).map(move |i| x[(i, 0)]))
                .collect()
        };
        let (fast, reference) = (column(&b), column(&a));
        assert_matches_naive(
            "unit-circle blocks",
            &fast,
            &reference,
            Scale::Absolute,
            1e-9,
        );
    }

    #[test]
    fn the_kalman_gain_of_an_innovation_model() {
        // x+ = A x + B u + K e, y = C x + e, with A − K C stable: a long record's
        // observer is the Kalman filter, so its gain is −K.
        let a = faer::mat![[0.9, 0.2], [-0.2, 0.9]];
        let b = faer::mat![[1.0], [0.5]];
        let c = faer::mat![[1.0, 0.0], [0.0, 1.0]];
        let k_true = faer::mat![[0.5, 0.1], [-0.1, 0.4]];
        let model = StateSpace::new(
            a.clone(),
            b.clone(),
            c.clone(),
            Mat::zeros(2, 1),
            crate::TimeDomain::Discrete { sample_time_s: 1.0 },
        );
        let mut rng = Minstd::new(21);
        let n = 200_000;
        let u: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
        let mut x = Mat::<f64>::zeros(2, 1);
        let mut y = vec![vec![0.0; n]; 2];
        for k in 0..n {
            let e = faer::mat![[0.3 * rng.normal()], [0.3 * rng.normal()]];
            let out = &c * &x + &e;
            y[0][k] = out[(0, 0)];
            y[1][k] = out[(1, 0)];
            x = &a * &x + &b * u[k] + &k_true * &e;
        }
        let ui = [u.as_slice()];
        let yi = refs(&y);
        let found = okid(
            &[Record {
                inputs: &ui,
                outputs: &yi,
            }],
            &OkidOptions {
                observer_order: ObserverOrder::Fixed(20),
                markov_samples: 40,
                gain: true,
                ..OkidOptions::default()
            },
        )
        .unwrap();
        let k = kalman_gain(&model, found.gain_markov.as_ref().unwrap()).unwrap();
        let err = (&k - &k_true).norm_max();
        assert!(err < 0.02, "K = {k:?}, error {err}");
    }

    #[test]
    fn bad_records_are_refused_by_name() {
        let spec = ModalSpec {
            collocated: false,
            ..ModalSpec::new(2, 2, 2)
        };
        let (_, u, y) = test_record(&spec, 64.0, 2000, 1);
        let yi = refs(&y);
        // More Markov blocks than the record has samples: refused by name, before any
        // allocation (10^8 once asked for 16 GB on the unit circle).
        for n in [2001, 100_000_000, usize::MAX / 2] {
            let e = okid(
                &[Record {
                    inputs: &refs(&u),
                    outputs: &yi,
                }],
                &OkidOptions {
                    markov_samples: n,
                    ..OkidOptions::default()
                },
            )
            .unwrap_err();
            assert!(
                matches!(
                    e,
                    EraError::InvalidParameter {
                        name: "markov_samples",
                        ..
                    }
                ),
                "{e}"
            );
            assert!(
                e.to_string()
                    .contains("the longest record has 2000 samples"),
                "{e}"
            );
        }
        // An input with no energy.
        let flat = vec![3.0; 2000];
        let ui = [u[0].as_slice(), flat.as_slice()];
        let e = okid(
            &[Record {
                inputs: &ui,
                outputs: &yi,
            }],
            &OkidOptions::default(),
        )
        .unwrap_err();
        assert!(
            matches!(e, EraError::DeficientInput { input: 2, .. }),
            "{e}"
        );
        // A linear combination of the others.
        let twice: Vec<f64> = u[0].iter().map(|v| -2.0 * v).collect();
        let ui = [u[0].as_slice(), twice.as_slice()];
        let e = okid(
            &[Record {
                inputs: &ui,
                outputs: &yi,
            }],
            &OkidOptions::default(),
        )
        .unwrap_err();
        assert!(
            matches!(e, EraError::DeficientInput { input: 2, .. }),
            "{e}"
        );
        assert!(e.to_string().contains("linear combination"), "{e}");
        // NaN.
        let mut nan = u[1].clone();
        nan[17] = f64::NAN;
        let ui = [u[0].as_slice(), nan.as_slice()];
        let e = okid(
            &[Record {
                inputs: &ui,
                outputs: &yi,
            }],
            &OkidOptions::default(),
        )
        .unwrap_err();
        assert!(
            matches!(
                e,
                EraError::NonFiniteSample {
                    role: "input",
                    channel: 2,
                    sample: 17
                }
            ),
            "{e}"
        );
        // Too short for the order.
        let ui = refs(&u);
        let short_u: Vec<&[f64]> = ui.iter().map(|c| &c[..30]).collect();
        let short_y: Vec<&[f64]> = yi.iter().map(|c| &c[..30]).collect();
        let e = okid(
            &[Record {
                inputs: &short_u,
                outputs: &short_y,
            }],
            &OkidOptions {
                observer_order: ObserverOrder::Fixed(10),
                markov_samples: 20,
                ..OkidOptions::default()
            },
        )
        .unwrap_err();
        assert!(
            matches!(
                e,
                EraError::InvalidParameter {
                    name: "observer_order",
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("needs at least"), "{e}");
    }
}
