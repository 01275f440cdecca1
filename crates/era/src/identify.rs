//! The entry points of the pipeline of docs/src/design.md §1 (the thesis's `frffilt`):
//! FRFs in, a model, its singular values, modes and fit out, at the order
//! [`EraOptions::order`] asks for ([`Order`]: fixed, fixed and judged against a scan, or
//! automatic). One entry point per source: [`identify`] and [`identify_observed`] take the
//! FRFs' own Markov sequence (their inverse transform), [`identify_supplied`] one from
//! elsewhere (OKID's).

use crate::data::frf::FrfData;
use crate::data::identification::{Identification, Stage, StageTimings};
use crate::data::statespace::StateSpace;
use crate::error::Result;
use crate::pipeline::factor::SvdPath;
use crate::pipeline::order::{auto, with_scan};
use crate::pipeline::realize::Realization;
use crate::pipeline::run::{assess, run, Path};
use crate::sources::frf::MarkovSequence;

pub mod oma;
pub(crate) mod options;
pub mod route;
pub mod suspect;

mod zero_start;

pub use crate::pipeline::order::cmif;
pub use options::{EraOptions, ModelDomain, Order, Realizer, ScanOptions};
pub use zero_start::zero_start;

/// Runs docs/src/design.md §1 on `frf` at the order `options.order` asks for.
///
/// # Errors
/// [`EraError::AllZero`](crate::EraError::AllZero) when there is nothing to identify,
/// and every error of the stages (invalid parameters, too few samples, rank deficiency,
/// numerical failure). With a scan, [`EraError::InvalidParameter`](crate::EraError::InvalidParameter)
/// naming `orders` for a range the data does not support; with the automatic order,
/// naming `states` when no mode is stable across the orders.
pub fn identify(frf: &FrfData, options: &EraOptions) -> Result<Identification> {
    identify_observed(frf, options, &mut |_| {}, &mut |_, _| {})
}

/// [`identify`], calling `observer` as each [`Stage`] starts and `progress` with the
/// orders done and in all as a scan realizes them (for progress displays; the core
/// itself draws nothing).
///
/// # Errors
/// As [`identify`].
pub fn identify_observed(
    frf: &FrfData,
    options: &EraOptions,
    observer: &mut dyn FnMut(Stage),
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Identification> {
    dispatch(frf, None, options, observer, progress)
}

/// [`identify_observed`] from a `markov` sequence of another source (OKID's, say) instead
/// of the FRFs' inverse transform: `options.integrations`, `pad_to` and `zero_lines` must
/// be 0 (they shape the FRFs' transform, which is not taken); a low-pass filters the
/// sequence. The model is fitted and judged against `frf`.
///
/// # Errors
/// As [`identify`], and [`EraError::ShapeMismatch`](crate::EraError::ShapeMismatch) when
/// the sequence's outputs or inputs are not the FRFs'.
pub fn identify_supplied(
    frf: &FrfData,
    markov: &MarkovSequence,
    options: &EraOptions,
    observer: &mut dyn FnMut(Stage),
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Identification> {
    dispatch(frf, Some(markov), options, observer, progress)
}

/// The pipeline at the order `options.order` asks for.
fn dispatch(
    frf: &FrfData,
    supplied: Option<&MarkovSequence>,
    options: &EraOptions,
    observer: &mut dyn FnMut(Stage),
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Identification> {
    match options.order {
        Order::Fixed(_) => run(frf, supplied, options, Path::Fast, observer),
        Order::Scan { .. } => with_scan(frf, supplied, options, observer, progress),
        Order::Auto => auto(frf, supplied, options, observer, progress),
    }
}

/// The leading `count` singular values of the `H0` a fixed-order [`identify`] of `frf`
/// with `options` factors (same sequence, Hankel and scale), for a plot that shows the
/// values past the order when the run computed only its own (the matrix-free path).
/// The identification is not touched. `None` for ERA/DC.
///
/// # Errors
/// As [`identify`]'s Markov and SVD stages; [`EraError::InvalidParameter`](crate::EraError::InvalidParameter)
/// when `options.order` has no fixed number of states.
pub fn hankel_singular_values(
    frf: &FrfData,
    options: &EraOptions,
    count: usize,
) -> Result<Option<Vec<f64>>> {
    crate::pipeline::run::hankel_singular_values(frf, options, count)
}

/// [`identify`] with the naive reference of every stage: DFT by definition, element-wise
/// Hankels, full SVD, loop products, a dense solve per line for the fit. It realizes the
/// fixed order of `options.order` (a scan's order, without the scan).
///
/// # Errors
/// As [`identify`], and [`EraError::InvalidParameter`](crate::EraError::InvalidParameter)
/// for the automatic order.
pub fn identify_naive(frf: &FrfData, options: &EraOptions) -> Result<Identification> {
    run(frf, None, options, Path::Naive, &mut |_| {})
}

/// The identification of a model given from elsewhere (a `model.json` written earlier):
/// its modes, indicators (no EMAC: the Hankel tails are not known) and fit against
/// `frf` processed as `options` say. `model` is taken in its own time domain;
/// `singular_values`, `hankel_size` and `svd_path` are what is known of the
/// realization, for the report.
///
/// # Errors
/// As [`identify`]'s last stages, and `c2d` of a continuous model at `sample_time_s`.
pub fn assess_model(
    frf: &FrfData,
    options: &EraOptions,
    model: StateSpace,
    singular_values: Vec<f64>,
    hankel_size: (usize, usize),
    svd_path: SvdPath,
    sample_time_s: f64,
) -> Result<Identification> {
    let discrete = match model.domain {
        crate::TimeDomain::Discrete { .. } => model.clone(),
        crate::TimeDomain::Continuous => model.c2d(sample_time_s)?,
    };
    let realization = Realization {
        model: discrete,
        singular_values,
        hankel_size,
        warnings: Vec::new(),
        hankel_svd_seconds: 0.0,
        products_seconds: 0.0,
        svd_path,
        svd_iterations: None,
        tails: crate::pipeline::realize::HankelTails {
            observability: faer::Mat::zeros(0, 0),
            controllability: faer::Mat::zeros(0, 0),
            outputs: model.outputs(),
            inputs: model.inputs(),
        },
    };
    assess(
        frf,
        options,
        Path::Fast,
        &mut |_| {},
        StageTimings::default(),
        realization,
        model,
        sample_time_s,
    )
}
