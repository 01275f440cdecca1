//! Operational (output-only) modal analysis: records of responses to unmeasured forces
//! in, modes with standard deviations out.
//!
//! 1. [`crate::sources::correlation`] turns the records into output correlations
//!    `R_k` against reference channels, kept in blocks.
//! 2. The pipeline realizes them as it realizes impulse responses ([`super::identify_supplied`]),
//!    at a fixed order or the automatic one: by ERA (`A` from `H1`: NExT-ERA) or by the
//!    shift of the observability factor (covariance-driven SSI). Both start from the
//!    same factorization of the block Hankel of `R_1, R_2, …`; SSI-cov's block Toeplitz
//!    is that Hankel with its block columns reversed, which changes neither the singular
//!    values nor the column space. The "FRF" the model is fitted to and judged against is
//!    the correlations' own transform, the positive half of the output spectrum
//!    (outputs × references).
//! 3. **Uncertainty** by the delete-one-block jackknife: the correlations without block
//!    `b` are realized again at each mode's own order (its pole's, for the automatic
//!    order) on the same Hankel, the mode is found again by frequency and MAC, and the
//!    spread of the `B` estimates gives the variance,
//!    `σ² = (B − 1)/B · Σ_b (θ_b − θ̄)²`. The correlations are means, and a mode's
//!    frequency, damping and shape smooth functions of them, which is where the
//!    jackknife holds; it needs no linearization of the SVD and eigenvalue steps
//!    (Reynders, Pintelon & De Roeck 2008 propagate the same block covariance
//!    through first derivatives instead).
//!
//! Mode shapes are unscaled: with no measured input there is no modal mass, and the
//! "participations" are the references' (`ψ G`), not forces'.

use crate::data::frf::Quantity;
use crate::data::identification::{Identification, Stage};
use crate::error::{EraError, Result};
use crate::identify::{EraOptions, Order, Realizer};
use crate::modal::indicators::mac;
use crate::pipeline::factor::{FactorOptions, Factorization};
use crate::pipeline::modes::continuous_pole;
use crate::pipeline::realize::DirectTerm;
use crate::sources::correlation::{correlations, CorrelationOptions, Correlations};
use crate::sources::MarkovSequence;
use num_complex::Complex64;
use rayon::prelude::*;
use std::time::Instant;

/// How the correlations are realized.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum OmaMethod {
    /// Covariance-driven stochastic subspace identification: `A` from the shift of the
    /// observability factor ([`Realizer::Shift`]).
    #[default]
    SsiCov,
    /// NExT-ERA: ERA on the correlations (`A` from `H1`, [`Realizer::Era`]).
    NextEra,
}

crate::params::names::named!(display OmaMethod, "method", [
    OmaMethod::SsiCov => "ssi-cov",
    OmaMethod::NextEra => "next-era",
]);

/// Blocks of the jackknife by default. Each block left out perturbs the estimate by a
/// sixth of the data, well above the jitter of the order's truncation, which the
/// jackknife multiplies by `B − 1`: on simulated records of one structure, 6 blocks give
/// standard deviations 1.1–1.6 times the scatter over records, 12 blocks 1.5–2.
pub const DEFAULT_BLOCKS: usize = 6;

/// Hankel factor of output-only identification by default: the correlations' Hankel
/// spans half the lags whatever the factor, and a factor of 1 lets the scan reach
/// 0.75 states per lag (96 at the least default lags), enough for a few dozen modes.
pub(crate) const DEFAULT_OMA_HANKEL_FACTOR: usize = 1;

/// Settings of [`oma`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct OmaOptions {
    /// Samples per second of every record.
    pub sample_rate_hz: f64,
    /// SSI-cov or NExT-ERA.
    pub method: OmaMethod,
    /// Reference channels (0-based, among the outputs); `None` for every output.
    pub references: Option<Vec<usize>>,
    /// Correlation lags; `None` for [`crate::sources::correlation::default_lags`].
    pub lags: Option<usize>,
    /// Blocks of the jackknife, at most (at least 2 for standard deviations; 0 or 1
    /// for none). A record too short for them takes as many as hold twice the lags each
    /// ([`Oma::blocks`] says how many were used).
    pub blocks: usize,
    /// The pipeline's settings: the order (automatic by default), the scan, the Hankel
    /// factor, the model's time domain. Its FRF preprocessing (integrations, padding,
    /// zeroed lines) must stay 0, and its realizer is the method's.
    pub era: EraOptions,
}

impl OmaOptions {
    /// SSI-cov at the automatic order, every output a reference, the default lags and
    /// [`DEFAULT_BLOCKS`] blocks, `D = R_0`.
    pub fn new(sample_rate_hz: f64) -> Self {
        let era = EraOptions {
            order: Order::Auto,
            hankel_factor: DEFAULT_OMA_HANKEL_FACTOR,
            direct_term: DirectTerm::FirstMarkov,
            ..EraOptions::default()
        };
        OmaOptions {
            sample_rate_hz,
            method: OmaMethod::SsiCov,
            references: None,
            lags: None,
            blocks: DEFAULT_BLOCKS,
            era,
        }
    }
}

/// The standard deviations of one mode, from the jackknife.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeSpread {
    /// Of the frequency, Hz.
    pub frequency_std_hz: f64,
    /// Of the damping ratio.
    pub damping_ratio_std: f64,
    /// Of each shape entry (the shape scaled as the mode's, largest entry 1), as the
    /// root of the summed variances of its real and imaginary parts.
    pub shape_std: Vec<f64>,
    /// Blocks in which the mode was found again.
    pub blocks_found: usize,
}

/// An output-only identification.
#[derive(Debug, Clone)]
pub struct Oma {
    /// The identification (its `quality` carries the frequency and damping standard
    /// deviations); its "FRFs" are the positive half spectra of the correlations.
    pub identification: Identification,
    /// Per mode of `identification.modal.modes`: the jackknife's spread, or `None` when
    /// no blocks were asked for or the mode was not found in enough of them.
    pub spread: Vec<Option<ModeSpread>>,
    /// How the correlations were realized.
    pub method: OmaMethod,
    /// The reference channels (0-based).
    pub references: Vec<usize>,
    /// Correlation lags.
    pub lags: usize,
    /// Samples per channel over all records.
    pub samples: usize,
    /// Blocks of the jackknife used (1: no standard deviations).
    pub blocks: usize,
    /// The singular values of the output spectral matrix (Welch, the default segment):
    /// the frequency-domain first look to set beside the modes.
    pub spectrum: crate::sources::correlation::spectrum::OutputSpectrum,
    /// Wall time of the correlations (and the output spectrum), s.
    pub correlation_seconds: f64,
    /// Wall time of the jackknife, s.
    pub uncertainty_seconds: f64,
}

/// [`oma_observed`] with no observer.
///
/// # Errors
/// As [`oma_observed`].
pub fn oma(records: &[&[&[f64]]], options: &OmaOptions) -> Result<Oma> {
    oma_observed(records, options, &mut |_| {}, &mut |_, _| {})
}

/// Output-only identification of `records` (each a set of output channels of one length,
/// the same channels in every record) as `options` say; `observer` and `progress` as
/// [`super::identify_observed`]'s.
///
/// # Errors
/// [`EraError::InvalidParameter`] for a sample rate that is not positive, FRF
/// preprocessing asked of the pipeline, too few blocks for the lags; the correlations'
/// errors ([`correlations`]) and the pipeline's.
pub fn oma_observed(
    records: &[&[&[f64]]],
    options: &OmaOptions,
    observer: &mut dyn FnMut(Stage),
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Oma> {
    let fs = options.sample_rate_hz;
    if !(fs.is_finite() && fs > 0.0) {
        return Err(EraError::InvalidParameter {
            name: "sample_rate_hz",
            value: fs.to_string(),
            reason: "must be a positive number of samples per second".into(),
        });
    }
    // Before the correlations: the pipeline would refuse it after them.
    crate::pipeline::run::check_no_frf_shaping(&options.era)?;
    let clock = Instant::now();
    Stage::Markov.enter(observer)?;
    let references = options
        .references
        .as_ref()
        .map_or_else(|| records.first().map_or(0, |r| r.len()), Vec::len);
    let lags = match options.lags {
        Some(l) => l,
        None => crate::sources::correlation::default_lags(records, fs, references)?,
    };
    // A short record takes fewer blocks: each must hold twice the lags.
    let samples: usize = records
        .iter()
        .map(|r| r.first().map_or(0, |c| c.len()))
        .sum();
    let blocks = options.blocks.min(samples / (2 * lags.max(1))).max(1);
    let corr = correlations(
        records,
        &CorrelationOptions {
            references: options.references.clone(),
            lags,
            blocks,
            sample_time_s: 1.0 / fs,
        },
    )?;
    let spectrum = crate::sources::correlation::spectrum::output_spectrum(records, fs, None)?;
    let correlation_seconds = clock.elapsed().as_secs_f64();
    let half =
        crate::sources::frf::frf_of_markov(&corr.sequence, 1.0 / fs, Quantity::Acceleration)?;
    let mut era = options.era.clone();
    let jackknifed = corr.blocks() >= 2;
    if jackknifed {
        // The significance test weighs a mode against the residual of a fit to the
        // "FRF"; the half spectrum of correlations cut at the last lag leaks around
        // every lightly damped peak, which that residual takes for noise. The jackknife
        // judges the same question from the data's own scatter.
        era.scan.significance = false;
    }
    // A fixed order's Hankel is the thesis Hankel of that order (`states × factor`
    // samples): the factor is raised until it spans half the lags, as a scan's does.
    // A scan's Hankel of every supported sample must have room for its states: with few
    // references its columns are few, and the factor is raised until they suffice.
    match era.order.states() {
        Some(n) if n > 0 => era.hankel_factor = era.hankel_factor.max(lags.div_ceil(2 * n)),
        _ => era.hankel_factor = scan_factor(era.hankel_factor, lags, corr.references.len()),
    }
    era.realizer = match options.method {
        OmaMethod::SsiCov => Realizer::Shift,
        OmaMethod::NextEra => Realizer::Era,
    };
    let mut found = super::identify_supplied(&half, &corr.sequence, &era, observer, progress)?;
    found.timings.markov += correlation_seconds;
    let clock = Instant::now();
    let spread = if corr.blocks() >= 2 {
        jackknife(&found, &corr, &era, true)?
    } else {
        vec![None; found.modal.modes.len()]
    };
    if jackknifed {
        judge_spread(&mut found, &spread, corr.blocks());
    }
    Ok(Oma {
        identification: found,
        spread,
        method: options.method,
        references: corr.references.clone(),
        lags,
        samples: corr.samples,
        blocks: corr.blocks(),
        spectrum,
        correlation_seconds,
        uncertainty_seconds: clock.elapsed().as_secs_f64(),
    })
}

/// The least Hankel factor from `factor` up whose scan Hankel (every supported sample of
/// `lags`) has at least as many columns as the states it is factored for, with
/// `references` inputs: one reference needs 3, two need 2, more need 1.
fn scan_factor(factor: usize, lags: usize, references: usize) -> usize {
    let mut lh = factor.max(1);
    while lh < 8 {
        let states = crate::pipeline::order::supported_hankel_states(lags, lh);
        match crate::pipeline::hankel::ThesisHankel::new(states.max(2), lh) {
            Ok(t) if t.h0.block_cols * references >= states => break,
            _ => lh += 1,
        }
    }
    lh
}

/// Each mode's standard deviations into its quality, and the modes the data do not pin
/// down marked not physical: one found again in too few blocks, or one whose frequency
/// scatters by more than its half-power half-bandwidth `ζ f` (Reynders, Houbrechts &
/// De Roeck 2012 also reject modes by their uncertainty). A damping that scatters is
/// not a reason: a lightly damped mode of a short record has a clear peak and an
/// uncertain damping, which its standard deviation says.
fn judge_spread(found: &mut Identification, spread: &[Option<ModeSpread>], blocks: usize) {
    for ((mode, q), s) in found
        .modal
        .modes
        .iter()
        .zip(found.quality.iter_mut())
        .zip(spread)
    {
        let why = match s {
            None => Some(format!(
                "found again in fewer than {} of the {blocks} jackknife blocks: the data do not pin it down",
                needed_blocks(blocks)
            )),
            Some(s) => {
                q.frequency_std_hz = Some(s.frequency_std_hz);
                q.damping_ratio_std = Some(s.damping_ratio_std);
                let half_band = mode.damping_ratio.abs() * mode.frequency_hz;
                if s.frequency_std_hz > half_band {
                    Some(format!(
                        "its frequency scatters by {:.3} Hz over the blocks, more than its half-power half-bandwidth {:.3} Hz: the data do not pin it down",
                        s.frequency_std_hz, half_band
                    ))
                } else {
                    None
                }
            }
        };
        if let (true, Some(why)) = (q.physical, why) {
            q.physical = false;
            q.reason = Some(why);
        }
    }
    judge_doubles(found);
    found.suspects = crate::identify::suspect::check_identification(found);
}

/// Two physical modes closer in frequency than [`DOUBLE_SIGMAS`] of their combined
/// standard deviation, with shapes of MAC at least [`DOUBLE_MAC`], are one mode to the
/// data: no test on these blocks tells them apart, and their shapes are one direction
/// mixed. The one whose frequency scatters more is marked not physical. Two
/// true close modes with distinct shapes (MAC ≤ 0.4 between their estimates on the
/// simulated records) stay apart; a close pair the records cannot separate is reported
/// once, as a peer's clustering would.
fn judge_doubles(found: &mut Identification) {
    let modes = &found.modal.modes;
    let physical: Vec<usize> = (0..modes.len())
        .filter(|&k| found.quality.get(k).is_some_and(|q| q.physical))
        .collect();
    let mut verdicts = Vec::new();
    for (n, &a) in physical.iter().enumerate() {
        for &b in &physical[n + 1..] {
            let (qa, qb) = (&found.quality[a], &found.quality[b]);
            let (Some(sa), Some(sb)) = (qa.frequency_std_hz, qb.frequency_std_hz) else {
                continue;
            };
            let apart = (modes[a].frequency_hz - modes[b].frequency_hz).abs() / sa.hypot(sb);
            let mac = crate::modal::indicators::mac(&modes[a].shape, &modes[b].shape);
            if !(apart < DOUBLE_SIGMAS && mac >= DOUBLE_MAC) {
                continue;
            }
            // The one the blocks pin down less is the one to drop.
            let (weak, strong) = if sa > sb { (a, b) } else { (b, a) };
            verdicts.push((
                weak,
                format!(
                    "the data do not tell it from mode {} ({:.4} Hz): {apart:.1} standard deviations apart in frequency, MAC {mac:.2} between their shapes",
                    strong + 1,
                    modes[strong].frequency_hz
                ),
            ));
        }
    }
    for (k, why) in verdicts {
        let q = &mut found.quality[k];
        if q.physical {
            q.physical = false;
            q.reason = Some(why);
        }
    }
}

/// Frequencies closer than this many combined standard deviations cannot be told apart.
const DOUBLE_SIGMAS: f64 = 2.0;

/// Shapes at least this collinear (MAC) are one direction.
const DOUBLE_MAC: f64 = 0.6;

/// Blocks a mode must be found again in for its spread to count.
fn needed_blocks(blocks: usize) -> usize {
    (blocks - blocks / 5).max(2)
}

/// The order each mode's pole came from: its cluster representative's for the
/// automatic order, the model's own otherwise.
fn mode_orders(found: &Identification, era: &EraOptions) -> Vec<usize> {
    let states = found.realization.model.states();
    let chosen: Vec<&crate::modal::stabilization::ScanPole> =
        match (&found.stabilization, era.order) {
            (Some(st), Order::Auto) => st
                .selection
                .physical()
                .map(|c| &st.scan.poles[c.representative])
                .collect(),
            _ => Vec::new(),
        };
    found
        .modal
        .modes
        .iter()
        .map(|m| {
            chosen
                .iter()
                .min_by(|a, b| {
                    (a.frequency_hz - m.frequency_hz)
                        .abs()
                        .total_cmp(&(b.frequency_hz - m.frequency_hz).abs())
                })
                .map_or(states, |p| p.order)
        })
        .collect()
}

/// The Hankel the identification factored, in states at its Hankel factor: a fixed
/// order's own (the thesis Hankel of that order), or the scan's for the automatic order.
fn hankel_states(era: &EraOptions, markov_samples: usize, orders_max: usize) -> usize {
    let supported =
        crate::pipeline::order::supported_hankel_states(markov_samples, era.hankel_factor);
    match era.order {
        Order::Fixed(n) | Order::Scan { states: n } => n,
        Order::Auto => match &era.scan.orders {
            None => supported,
            Some(r) => r.max.min(supported),
        }
        .max(orders_max.min(supported)),
    }
    .max(1)
}

/// A pole of a block's realization: frequency, damping, shape.
struct BlockPole {
    frequency_hz: f64,
    damping_ratio: f64,
    shape: Vec<Complex64>,
}

/// The complex poles of the realization at `states` of `factors`, with their shapes
/// `C φ` (no left eigenvectors: a block needs the poles and shapes only).
fn block_poles(factors: &Factorization, states: usize) -> Result<Vec<BlockPole>> {
    let r = factors.realize(states, DirectTerm::Zero)?;
    let (eigenvalues, vectors) = crate::linalg::eigen::balanced_eigen(&r.model.a)?;
    let c = &r.model.c;
    Ok(eigenvalues
        .iter()
        .enumerate()
        .filter(|(_, z)| z.im > 0.0)
        .map(|(k, z)| {
            let s = continuous_pole(*z, r.model.domain);
            let shape = (0..c.nrows())
                .map(|i| {
                    (0..c.ncols())
                        .map(|j| vectors[(j, k)] * c[(i, j)])
                        .sum::<Complex64>()
                })
                .collect();
            BlockPole {
                frequency_hz: s.norm() / (2.0 * std::f64::consts::PI),
                damping_ratio: -s.re / s.norm(),
                shape,
            }
        })
        .collect())
}

/// The jackknife of every mode over the blocks of `corr`.
///
/// With `warm`, each block's factors come from subspace iteration started at the whole
/// data's ([`warm_factors`]); without, from a dense SVD of each block's Hankel (the
/// reference the tests hold the warm start to).
fn jackknife(
    found: &Identification,
    corr: &Correlations,
    era: &EraOptions,
    warm: bool,
) -> Result<Vec<Option<ModeSpread>>> {
    let orders = mode_orders(found, era);
    let top = orders.iter().copied().max().unwrap_or(0);
    if top == 0 {
        return Ok(Vec::new());
    }
    let hankel = hankel_states(era, corr.sequence.samples(), top);
    let mut distinct = orders.clone();
    distinct.sort_unstable();
    distinct.dedup();
    let start = warm_start(found, hankel, era.hankel_factor, corr);
    let token = crate::cancel::current();
    // Per block, per mode: the pole found again (frequency, damping, shape scaled to
    // the mode's), or None.
    type Found = Option<(f64, f64, Vec<Complex64>)>;
    let per_block: Vec<Vec<Found>> = (0..corr.blocks())
        .into_par_iter()
        .map(|b| -> Result<Vec<Found>> {
            crate::cancel::check_token(&token)?;
            let seq = normalized(&corr.leave_out(b)?);
            let mut factors = match (&start, warm) {
                (Some(v0), true) => {
                    warm_factors(&seq, hankel, era.hankel_factor, v0.as_ref(), top, era.svd)?
                }
                _ => Factorization::thesis(
                    &seq,
                    seq.sample_time_s(),
                    &FactorOptions {
                        hankel_states: hankel,
                        max_states: top,
                        hankel_factor: era.hankel_factor,
                        svd: era.svd,
                        svd_tolerance: era.scan.svd_tolerance,
                        // Its blocks' orders are not bounded by a probe: the
                        // tolerance alone.
                        svd_floor_fraction: 0.0,
                    },
                )?,
            };
            if era.realizer == Realizer::Shift {
                factors = factors.with_shift();
            }
            let mut poles = Vec::with_capacity(distinct.len());
            for &n in &distinct {
                // An order above the block's numerical rank finds nothing.
                poles.push(block_poles(&factors, n).unwrap_or_default());
            }
            Ok(found
                .modal
                .modes
                .iter()
                .zip(&orders)
                .map(|(mode, n)| {
                    let at = distinct.binary_search(n).expect("the order is listed");
                    rediscover(mode, &poles[at])
                })
                .collect())
        })
        .collect::<Result<_>>()?;
    let needed = needed_blocks(corr.blocks());
    Ok(found
        .modal
        .modes
        .iter()
        .enumerate()
        .map(|(m, mode)| {
            let got: Vec<&(f64, f64, Vec<Complex64>)> =
                per_block.iter().filter_map(|b| b[m].as_ref()).collect();
            if got.len() < needed {
                return None;
            }
            let n = got.len() as f64;
            let spread_of = |values: &mut dyn Iterator<Item = f64>| {
                let v: Vec<f64> = values.collect();
                let mean = v.iter().sum::<f64>() / n;
                ((n - 1.0) / n * v.iter().map(|x| (x - mean).powi(2)).sum::<f64>()).sqrt()
            };
            let shape_std = (0..mode.shape.len())
                .map(|i| {
                    let mean = got.iter().map(|g| g.2[i]).sum::<Complex64>() / n;
                    ((n - 1.0) / n * got.iter().map(|g| (g.2[i] - mean).norm_sqr()).sum::<f64>())
                        .sqrt()
                })
                .collect();
            Some(ModeSpread {
                frequency_std_hz: spread_of(&mut got.iter().map(|g| g.0)),
                damping_ratio_std: spread_of(&mut got.iter().map(|g| g.1)),
                shape_std,
                blocks_found: got.len(),
            })
        })
        .collect())
}

/// Columns beyond the top order that the warm start carries (random, so that the
/// directions just past the top order are in the subspace too).
const WARM_EXTRA: usize = 16;

/// Subspace iterations of the warm start.
const WARM_ITERATIONS: usize = 4;

/// The right singular subspace of the whole data's `H0` (its controllability matrix's
/// rows), when the identification's realization has the jackknife's Hankel: the start
/// of every block's factorization.
fn warm_start(
    found: &Identification,
    hankel_states: usize,
    hankel_factor: usize,
    corr: &Correlations,
) -> Option<faer::Mat<f64>> {
    let shapes = crate::pipeline::hankel::ThesisHankel::new(hankel_states, hankel_factor).ok()?;
    let cols = shapes.h0.block_cols * corr.sequence.inputs();
    let ctrl = &found.realization.tails.controllability;
    if ctrl.ncols() != cols || ctrl.nrows() == 0 {
        return None;
    }
    let k = (ctrl.nrows() + WARM_EXTRA).min(cols);
    let mut g = crate::linalg::rng::Minstd::new(0x5eed);
    let v = faer::Mat::from_fn(cols, k, |j, r| {
        if r < ctrl.nrows() {
            ctrl[(r, j)]
        } else {
            g.normal()
        }
    });
    Some(v.qr().compute_thin_Q())
}

/// The factors of a block's `H0` by subspace iteration from `v0` (the whole data's right
/// singular subspace, which the block's differs from by a fraction of the data), with a
/// Rayleigh–Ritz step at the end: `H0 V = U S Wᵀ`, `V ← V W`. The block's Hankel
/// differs from the whole data's by a small perturbation, so a few iterations reach
/// the leading triplets that a dense SVD of each block would give, at a few products'
/// cost.
fn warm_factors(
    seq: &MarkovSequence,
    hankel_states: usize,
    hankel_factor: usize,
    v0: faer::MatRef<'_, f64>,
    max_states: usize,
    svd: crate::pipeline::factor::SvdPath,
) -> Result<Factorization> {
    use crate::linalg::LinearOperator;
    use crate::pipeline::hankel::{build, HankelShape};
    use crate::pipeline::hankel_op::HankelOperator;
    let clock = Instant::now();
    let shapes = crate::pipeline::hankel::ThesisHankel::new(hankel_states, hankel_factor)?;
    // The Hankel products by FFT where the pipeline would factor matrix-free, dense below.
    let short = (shapes.h0.block_rows * seq.outputs()).min(shapes.h0.block_cols * seq.inputs());
    let operator = |shape: HankelShape| -> Result<Box<dyn LinearOperator>> {
        Ok(if svd.matrix_free(short) {
            Box::new(HankelOperator::new(seq, shape)?)
        } else {
            Box::new(build(seq, shape)?)
        })
    };
    let (h0, h1) = (operator(shapes.h0)?, operator(shapes.h1)?);
    let mut v = v0.to_owned();
    for _ in 0..WARM_ITERATIONS {
        let q = h0.apply(v.as_ref()).qr().compute_thin_Q();
        v = h0.apply_transpose(q.as_ref()).qr().compute_thin_Q();
    }
    let z = h0.apply(v.as_ref());
    let svd = crate::linalg::dense::thin_svd(z, "a jackknife block's H0")?;
    let v = &v * &svd.v;
    let n = max_states.min(svd.s.len());
    let (un, vn) = (svd.u.subcols(0, n), v.subcols(0, n));
    let ut_h1_v = un.transpose() * h1.apply(vn);
    Ok(Factorization::from_parts(
        seq,
        seq.sample_time_s(),
        crate::pipeline::factor::FactorParts {
            hankel_size: (h0.nrows(), h0.ncols()),
            u: svd.u,
            v,
            ut_h1_v,
            singular_values: svd.s,
            max_states: n,
            ut_h0: None,
        },
        clock.elapsed().as_secs_f64(),
    ))
}

/// The sequence over its largest magnitude (the poles and shapes do not change; the
/// SVD's squares stay far from overflow).
fn normalized(seq: &MarkovSequence) -> MarkovSequence {
    let mut largest = 0.0f64;
    for k in 0..seq.samples() {
        for i in 0..seq.outputs() {
            for j in 0..seq.inputs() {
                largest = largest.max(seq.get(k, i, j).abs());
            }
        }
    }
    if largest == 0.0 || !largest.is_finite() {
        return seq.clone();
    }
    let scale = (-largest.log2().round()).exp2();
    MarkovSequence::from_fn(seq.outputs(), seq.inputs(), seq.samples(), |k, i, j| {
        seq.get(k, i, j) * scale
    })
    .with_sample_time(seq.sample_time_s())
    .with_kind(seq.kind())
}

/// The pole of a block that is `mode` again: within 10 % in frequency and MAC ≥ 0.5,
/// the best by relative frequency distance plus `1 − MAC`; its shape scaled onto the
/// mode's (the complex factor of least squares).
fn rediscover(
    mode: &crate::pipeline::modes::Mode,
    poles: &[BlockPole],
) -> Option<(f64, f64, Vec<Complex64>)> {
    let f = mode.frequency_hz;
    let best = poles
        .iter()
        .filter(|p| (p.frequency_hz - f).abs() <= 0.1 * f)
        .map(|p| (p, mac(&p.shape, &mode.shape)))
        .filter(|(_, m)| *m >= 0.5)
        .min_by(|(a, ma), (b, mb)| {
            ((a.frequency_hz - f).abs() / f + 1.0 - ma)
                .total_cmp(&((b.frequency_hz - f).abs() / f + 1.0 - mb))
        })?
        .0;
    let num: Complex64 = best
        .shape
        .iter()
        .zip(&mode.shape)
        .map(|(b, m)| b.conj() * m)
        .sum();
    let den: f64 = best.shape.iter().map(|b| b.norm_sqr()).sum();
    if den == 0.0 {
        return None;
    }
    let alpha = num / den;
    Some((
        best.frequency_hz,
        best.damping_ratio,
        best.shape.iter().map(|b| b * alpha).collect(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::shaker::{simulate_shaker_test, ShakerTest};
    use crate::sim::ModalSpec;

    #[test]
    fn the_warm_started_blocks_give_the_dense_blocks_spread() {
        let mut spec = ModalSpec::new(6, 2, 6);
        spec.fmin_hz = 1.0;
        spec.fmax_hz = 12.0;
        spec.seed = 21;
        let mut test = ShakerTest::new(spec, 40.0, 300.0);
        test.noise = 0.02;
        let rec = simulate_shaker_test(&test).unwrap();
        let outputs: Vec<&[f64]> = rec.outputs.iter().map(Vec::as_slice).collect();
        let options = OmaOptions::new(40.0);
        let found = oma(&[outputs.as_slice()], &options).unwrap();
        let corr = correlations(
            &[outputs.as_slice()],
            &CorrelationOptions {
                references: None,
                lags: found.lags,
                blocks: options.blocks,
                sample_time_s: 1.0 / 40.0,
            },
        )
        .unwrap();
        let mut era = options.era.clone();
        era.realizer = Realizer::Shift;
        let id = &found.identification;
        let warm = jackknife(id, &corr, &era, true).unwrap();
        let dense = jackknife(id, &corr, &era, false).unwrap();
        let mut compared = 0;
        for (m, (w, d)) in warm.iter().zip(&dense).enumerate() {
            if !id.quality[m].physical {
                continue;
            }
            let (w, d) = (w.as_ref().unwrap(), d.as_ref().unwrap());
            assert!(
                (w.frequency_std_hz / d.frequency_std_hz - 1.0).abs() < 0.05,
                "mode {m}"
            );
            assert!(
                (w.damping_ratio_std / d.damping_ratio_std - 1.0).abs() < 0.05,
                "mode {m}"
            );
            compared += 1;
        }
        assert!(compared >= 4, "{compared} physical modes");
    }
}
