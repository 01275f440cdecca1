//! The order (docs/src/design.md §10): a scan across orders from one factorization of
//! `H0` ([`crate::pipeline::factor`]), its stabilization diagram and clustering
//! ([`crate::modal::stabilization`]), and from them either a fixed order's modes judged
//! against the scan, or the automatic order: a modal model of the modes that stay.

use crate::data::frf::FrfData;
use crate::data::identification::{Identification, Stabilization, Stage, StageTimings};
use crate::data::statespace::StateSpace;
use crate::error::{EraError, Result};
use crate::identify::options::{EraOptions, Realizer, ScanOptions};
use crate::modal::stabilization::{scan, select, OrderRange, Scan, Selection, SelectionCriteria};
use crate::pipeline::factor::{FactorOptions, Factorization};
use crate::pipeline::hankel::HankelShape;
use crate::pipeline::run::{back, fit_band, front, not_circular, run, Front, MagnitudeScale, Path};
use crate::sources::frf::preprocess::integrate;
use crate::sources::frf::MarkovSequence;
use std::time::Instant;

impl Stabilization {
    /// The record of a scan, its selection and the factorization it came from; the CMIF
    /// is taken of the identification's `measured` data.
    #[allow(clippy::too_many_arguments)]
    fn new(
        range: OrderRange,
        scan: Scan,
        selection: Selection,
        factorization: &Factorization,
        measured: &FrfData,
        seconds: f64,
        model_note: Option<String>,
    ) -> Self {
        Stabilization {
            range,
            scan,
            selection,
            singular_values: factorization.singular_values().to_vec(),
            hankel_size: factorization.hankel_size(),
            cmif: cmif(measured),
            seconds,
            factor_seconds: factorization.seconds(),
            svd_iterations: factorization.svd_iterations(),
            model_note,
        }
    }
}

/// The largest order whose thesis Hankel at `hankel_factor` stays within the first half
/// of a circular impulse response of `markov_samples` samples (`n·lh ≤ samples/2`, where
/// the inverse FFT does not wrap around), capped at [`DEFAULT_MAX_ORDER`]: the `H0` a scan
/// factors.
pub(crate) fn supported_hankel_states(markov_samples: usize, hankel_factor: usize) -> usize {
    (markov_samples / 2 / hankel_factor.max(1)).min(DEFAULT_MAX_ORDER)
}

/// The default orders of a scan: from a quarter to [`DEFAULT_ORDER_STRETCH`] times the
/// supported Hankel order ([`supported_hankel_states`]), within half the short side of
/// `H0`, in even steps, at most 40 orders.
///
/// # Errors
/// [`EraError::InvalidParameter`] naming `states` when the data is too short for any
/// scan.
pub(crate) fn default_orders(
    markov_samples: usize,
    hankel_factor: usize,
    outputs: usize,
    inputs: usize,
) -> Result<OrderRange> {
    let base = supported_hankel_states(markov_samples, hankel_factor);
    let shapes = crate::pipeline::hankel::ThesisHankel::new(base.max(2), hankel_factor.max(1));
    let short_side = shapes
        .map(|t| t.h0.block_rows * outputs.min(inputs))
        .unwrap_or(0);
    let max = ((base as f64 * DEFAULT_ORDER_STRETCH) as usize).min(short_side / 2) / 2 * 2;
    if base < 8 || max < 8 {
        return Err(EraError::InvalidParameter {
            name: "states",
            value: "auto".into(),
            reason: crate::params::names::Prose::from(format!("{markov_samples} Markov samples at "))
                .param(crate::params::names::Param::HankelFactor)
                .text(format!(
                    " {hankel_factor} support a Hankel of {base} states; a scan needs at least 8: pad with "
                ))
            .param(crate::params::names::Param::PadTo)
            .text(", lower ")
            .param(crate::params::names::Param::HankelFactor)
            .text(", or give ")
            .param(crate::params::names::Param::States)
            .text(" N"),
        });
    }
    let min = (base / 4).max(2) / 2 * 2;
    let step = (max - min).div_ceil(39).max(2).next_multiple_of(2);
    OrderRange::new(min, max, step)
}

/// States of the probe Hankel whose singular values bound a default scan
/// ([`signal_order`]).
pub(crate) const PROBE_STATES: usize = 100;

/// The rows of the probe Hankel of many outputs and inputs, first (one whose square
/// form has more than [`PROBE_SIDE_MAX`] rows and columns): it keeps its span of
/// samples but takes fewer block rows, so that its cost stays a fraction of the scan's.
/// Its order is taken while the signal has at most a third of its 400 values (133
/// states); a probe of noisy data that finds more is taken again at [`PROBE_SIDE_MAX`].
pub(crate) const PROBE_SIDE: usize = 400;

/// The probe's side when the first probe found too many singular values above its
/// noise floor to tell the order (more than a third of them).
pub(crate) const PROBE_SIDE_MAX: usize = 800;

/// The probe's `H0` over the span of a thesis Hankel of [`PROBE_STATES`] states at
/// `hankel_factor`: square in blocks, unless both sides would exceed
/// [`PROBE_SIDE_MAX`], when it has `side / outputs` block rows and the rest of the span
/// in columns. `None` when the samples support fewer than 8 states.
fn probe_shape(markov: &MarkovSequence, hankel_factor: usize, side: usize) -> Option<HankelShape> {
    let states = supported_hankel_states(markov.samples(), hankel_factor).min(PROBE_STATES);
    if states < 8 {
        return None;
    }
    let square = crate::pipeline::hankel::ThesisHankel::new(states, hankel_factor)
        .ok()?
        .h0;
    let blocks = square.block_rows;
    let (q, p) = (markov.outputs(), markov.inputs());
    if q * blocks <= PROBE_SIDE_MAX || p * blocks <= PROBE_SIDE_MAX {
        return Some(square);
    }
    let rows = side.div_ceil(q).min(blocks);
    Some(HankelShape {
        block_rows: rows,
        block_cols: 2 * blocks - rows,
        ..square
    })
}

/// A probe's noise floor below this fraction of `σ₁` is rounding or the truncation of
/// exact FRFs (1.5e-12 on the exact DTA-like set), not a measurement's noise: a larger
/// probe would count more of the same, so it is not taken.
const EXACT_FLOOR: f64 = 1e-10;

/// The lowest noise floor, relative to `σ₁`, that the probe takes from the Gram
/// matrix's eigenvalues ([`crate::linalg::dense::gram_singular_values`]): values there
/// are known to a few 1e-5 of themselves. Below it the probe takes the SVD as well.
const GRAM_PROBE_FLOOR: f64 = 1e-4;

/// What one probe Hankel tells of the order ([`signal_order`]).
enum ProbeCount {
    /// The number of singular values above the noise floor.
    Order(usize),
    /// More than a third of the values stand above the floor, too many to trust the
    /// median as the noise; `noisy` when the floor lies above [`EXACT_FLOOR`] (the
    /// data's noise, not rounding or the truncation of exact FRFs).
    TooMany { noisy: bool },
    /// The values cannot tell (too few, or none).
    Undecided,
}

/// The order the data supports: the number of singular values of a small Hankel of
/// the Markov sequence ([`probe_shape`], its singular values only) above the noise
/// floor. The floor is Gavish & Donoho's (2014) optimal hard threshold for a matrix of
/// unknown white noise, `ω(β)·σ_med` with `β` the aspect ratio and
/// `ω(β) ≈ 0.56β³ − 0.95β² + 1.82β + 1.43`: the median singular value measures the
/// noise when most singular values are noise. A probe of many channels takes
/// [`PROBE_SIDE`] rows first, and [`PROBE_SIDE_MAX`] when that one finds more than a
/// third of its values above the floor of noisy data. `None` when the probe cannot tell (too few
/// samples, or more than a third of its singular values above the floor).
///
/// # Errors
/// [`EraError::Interrupted`] when the call is cancelled while the probe runs.
pub(crate) fn signal_order(markov: &MarkovSequence, hankel_factor: usize) -> Result<Option<usize>> {
    let Some(shape) = probe_shape(markov, hankel_factor, PROBE_SIDE) else {
        return Ok(None);
    };
    match probe_count(markov, shape)? {
        ProbeCount::Order(rank) => Ok(Some(rank)),
        ProbeCount::TooMany { noisy: true } => {
            match probe_shape(markov, hankel_factor, PROBE_SIDE_MAX) {
                Some(larger) if larger.block_rows > shape.block_rows => {
                    match probe_count(markov, larger)? {
                        ProbeCount::Order(rank) => Ok(Some(rank)),
                        _ => Ok(None),
                    }
                }
                _ => Ok(None),
            }
        }
        ProbeCount::TooMany { noisy: false } | ProbeCount::Undecided => Ok(None),
    }
}

/// What the probe Hankel of `shape` tells of the order ([`signal_order`]).
fn probe_count(markov: &MarkovSequence, shape: HankelShape) -> Result<ProbeCount> {
    let Ok(h) = crate::pipeline::hankel::build(markov, shape) else {
        return Ok(ProbeCount::Undecided);
    };
    let (rows, cols) = h.shape();
    let beta = rows.min(cols) as f64 / rows.max(cols) as f64;
    let omega = 0.56 * beta.powi(3) - 0.95 * beta.powi(2) + 1.82 * beta + 1.43;
    // The floor ω·σ_med, or None when the values cannot tell (fewer than 8, or none).
    let floor_of = |sv: &[f64]| {
        if sv.len() < 8 || sv[0] <= 0.0 || !sv[0].is_finite() {
            return None;
        }
        let mut sorted = sv.to_vec();
        sorted.sort_by(f64::total_cmp);
        Some(omega * sorted[sorted.len() / 2])
    };
    // Noisy data first, from the Gram matrix (half the SVD's flops); where its floor
    // lies below what the Gram matrix resolves (exact or nearly exact data), the SVD.
    let gram = match crate::linalg::dense::gram_singular_values(h, "the probe Hankel") {
        Err(EraError::Interrupted) => return Err(EraError::Interrupted),
        Ok(sv) => floor_of(&sv)
            .filter(|&f| f >= GRAM_PROBE_FLOOR * sv[0])
            .map(|f| (sv, f)),
        Err(_) => None,
    };
    let (sv, floor) = match gram {
        Some(found) => found,
        None => {
            let Ok(h) = crate::pipeline::hankel::build(markov, shape) else {
                return Ok(ProbeCount::Undecided);
            };
            let sv = match crate::linalg::dense::singular_values(h, "the probe Hankel") {
                Ok(sv) => sv,
                Err(EraError::Interrupted) => return Err(EraError::Interrupted),
                Err(_) => return Ok(ProbeCount::Undecided),
            };
            let Some(floor) = floor_of(&sv) else {
                return Ok(ProbeCount::Undecided);
            };
            (sv, floor)
        }
    };
    let noisy = floor >= EXACT_FLOOR * sv[0];
    // Exact data: the floor is rounding, far below the signal.
    let floor = floor.max(1e-13 * sv[0]);
    let rank = sv.iter().take_while(|&&v| v > floor).count();
    Ok(if rank * 3 <= sv.len() {
        ProbeCount::Order(rank)
    } else {
        ProbeCount::TooMany { noisy }
    })
}

/// The default scan bounded by the data's order `rank` ([`signal_order`]): from half of
/// it to twice it plus 20 (noise poles appear past the signal order, and weak modes
/// settle there), within the default range, in even steps, at most 40 orders. `None`
/// when that is the default range anyway.
fn orders_for_rank(rank: usize, default: &OrderRange) -> Option<OrderRange> {
    let max = (2 * rank + 20).next_multiple_of(2);
    if max >= default.max {
        return None;
    }
    let min = (rank / 2).max(2).next_multiple_of(2).min(max);
    let step = (max - min).div_ceil(39).max(2).next_multiple_of(2);
    OrderRange::new(min, max, step).ok()
}

/// The largest Hankel order of a default scan.
pub(crate) const DEFAULT_MAX_ORDER: usize = 400;

/// How far past the supported Hankel order a default scan realizes (weak modes appear
/// only at high orders).
pub(crate) const DEFAULT_ORDER_STRETCH: f64 = 1.5;

/// CMIF: singular values of the FRF matrix at each line, largest first.
pub fn cmif(frf: &FrfData) -> Vec<Vec<f64>> {
    let (q, p, lines) = (frf.outputs(), frf.inputs(), frf.lines());
    (0..lines)
        .map(|k| {
            let g = faer::Mat::<faer::c64>::from_fn(q, p, |i, j| {
                let v = frf.values()[(i * p + j) * lines + k];
                faer::c64::new(v.re, v.im)
            });
            match g.singular_values() {
                Ok(s) => s,
                Err(_) => vec![f64::NAN; q.min(p)],
            }
        })
        .collect()
}

fn scan_front(
    frf: &FrfData,
    supplied: Option<&MarkovSequence>,
    options: &EraOptions,
    scan_options: &ScanOptions,
    observer: &mut dyn FnMut(Stage),
    progress: &mut dyn FnMut(usize, usize),
    timings: &mut StageTimings,
) -> Result<(Front, Factorization, OrderRange, Scan, f64)> {
    let f = front(frf, supplied, options, Path::Fast, observer, timings)?;
    // The range, and the data's order from the probe when a default scan asked it.
    let (range, probe_rank) = match scan_options.orders.clone() {
        Some(r) => (r, None),
        None => {
            let default = default_orders(
                f.markov.samples(),
                options.hankel_factor,
                frf.outputs(),
                frf.inputs(),
            )?;
            let clock = Instant::now();
            let probe_rank = signal_order(&f.markov, options.hankel_factor)?;
            let bounded = probe_rank.and_then(|rank| orders_for_rank(rank, &default));
            timings.hankel_svd += clock.elapsed().as_secs_f64();
            (bounded.unwrap_or(default), probe_rank)
        }
    };
    let supported = supported_hankel_states(f.markov.samples(), options.hankel_factor);
    // A default scan factors the Hankel of every supported sample, whatever its orders
    // (a range bounded by the data's order keeps the record's whole span); an explicit
    // range factors the Hankel of its largest order.
    let hankel_states = if scan_options.orders.is_none() {
        supported
    } else {
        range.max.min(supported)
    }
    .max(1);
    let clock = Instant::now();
    Stage::HankelSvd.enter(observer)?;
    let factorization = match options.realizer {
        Realizer::Era | Realizer::Shift => Factorization::thesis(
            &f.markov,
            f.sample_time_s(),
            &FactorOptions {
                hankel_states,
                max_states: range.max,
                hankel_factor: options.hankel_factor,
                svd: options.svd,
                svd_tolerance: scan_options.svd_tolerance,
                // The noise-floor stop only where the smallest kept singular value is
                // known to lie in the noise: a default scan whose top order is half as
                // much again as the order the probe found, past which the probe's own
                // singular values were below the noise floor (an explicit range may
                // stop inside the signal).
                svd_floor_fraction: if probe_rank.is_some_and(|r| 2 * range.max >= 3 * r) {
                    scan_options.svd_floor_fraction
                } else {
                    0.0
                },
            },
        )
        .map(|f| {
            if options.realizer == Realizer::Shift {
                f.with_shift()
            } else {
                f
            }
        }),
        Realizer::EraDc => crate::pipeline::realize_dc::factor_dc(
            &f.markov,
            f.sample_time_s(),
            &crate::pipeline::realize_dc::DcShape::new(
                hankel_states,
                options.hankel_factor,
                f.markov.outputs(),
            ),
            range.max,
            options.hankel_factor,
        ),
    }
    .map_err(|e| match e {
        EraError::NotEnoughMarkovSamples { needed, available, .. } => EraError::InvalidParameter {
            name: "orders",
            value: range.to_string(),
            reason: crate::params::names::Prose::from(format!(
                "the largest order needs {needed} Markov samples at "
            ))
            .param(crate::params::names::Param::HankelFactor)
            .text(format!(
                " {}, the data has {available}: lower the orders or ",
                options.hankel_factor
            ))
            .param(crate::params::names::Param::HankelFactor)
            .text(", or pad with ")
            .param(crate::params::names::Param::PadTo),
        },
        EraError::HankelTooSmall { available, .. } => EraError::InvalidParameter {
            name: "orders",
            value: range.to_string(),
            reason: format!(
                "the data supports a Hankel matrix with {available} singular values, fewer than the largest order: lower the orders"
            ).into(),
        },
        other => other,
    })?;
    // The factorization's SVD, and its products (H1's projection) as the realization's.
    let factored = clock.elapsed().as_secs_f64();
    timings.hankel_svd += factorization.seconds();
    timings.realize += (factored - factorization.seconds()).max(0.0);
    // Exact low-order data: the default range starts above the Hankel's rank, or most of
    // it lies above (a range bounded by the data's order starts at half of it); scan up
    // to the rank instead (an explicit --orders is taken as given).
    let rank = factorization.rank() / 2 * 2;
    let range = if scan_options.orders.is_none()
        && (rank < range.min || 2 * rank < range.min + range.max)
        && rank >= 2
    {
        OrderRange::new(2, rank, 2)?
    } else {
        range
    };
    let scan_clock = Instant::now();
    let s = scan(&factorization, &range, &scan_options.diagram, progress)?;
    timings.scan = scan_clock.elapsed().as_secs_f64();
    Ok((f, factorization, range, s, clock.elapsed().as_secs_f64()))
}

/// The selection criteria for a scan of `range`: as given, except that a scan cut short
/// by the Hankel's rank (exact low-order data, whose top order is the exact model) takes
/// a mode seen at a single order.
fn criteria_for(scan_options: &ScanOptions, range: &OrderRange) -> SelectionCriteria {
    let mut c = scan_options.selection;
    if scan_options.orders.is_none() && range.min == 2 && range.step == 2 && range.max < 40 {
        c.min_poles = 1;
    }
    c
}

/// [`Order::Scan`](crate::identify::options::Order::Scan): the fixed order of
/// `options`, plus a scan across `options.scan`'s orders: the stabilization diagram, and
/// each mode of the fixed-order model judged physical only when a physical cluster of
/// the scan matches it (within the cluster tolerances) and it passes the hard criteria.
///
/// # Errors
/// As [`crate::identify::identify`], and [`EraError::InvalidParameter`] naming `orders`
/// for a range the data does not support.
pub(crate) fn with_scan(
    frf: &FrfData,
    supplied: Option<&MarkovSequence>,
    options: &EraOptions,
    observer: &mut dyn FnMut(Stage),
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Identification> {
    let scan_options = &options.scan;
    let mut found = run(frf, supplied, options, Path::Fast, observer)?;
    let mut timings = StageTimings::default();
    let (_, factorization, range, s, seconds) = scan_front(
        frf,
        supplied,
        options,
        scan_options,
        &mut |_| {},
        progress,
        &mut timings,
    )?;
    let clock = Instant::now();
    let selection = select(&s, found.band_hz, &criteria_for(scan_options, &range));
    for (m, q) in found.modal.modes.iter().zip(found.quality.iter_mut()) {
        let cluster = selection.clusters.iter().filter(|c| c.physical).find(|c| {
            let rep = &s.poles[c.representative];
            (rep.frequency_hz - m.frequency_hz).abs()
                <= scan_options.selection.frequency_tolerance * m.frequency_hz
                && crate::modal::indicators::mac(&rep.shape, &m.shape)
                    >= scan_options.selection.mac_minimum
        });
        match cluster {
            Some(c) => q.stable_orders = Some(c.members.len()),
            None if q.physical => {
                q.physical = false;
                q.reason = Some("not stable across the scanned orders".into());
            }
            None => {}
        }
    }
    found.suspects = crate::identify::suspect::check_identification(&found);
    found.stabilization = Some(Stabilization::new(
        range,
        s,
        selection,
        &factorization,
        &found.measured,
        seconds,
        None,
    ));
    // The scan's own front, factorization and realizations beside the fixed order's.
    let t = &mut found.timings;
    t.preprocess += timings.preprocess;
    t.markov += timings.markov;
    t.hankel_svd += timings.hankel_svd;
    t.realize += timings.realize;
    t.scan = timings.scan;
    t.selection = clock.elapsed().as_secs_f64();
    Ok(found)
}

/// [`Order::Auto`](crate::identify::options::Order::Auto): scans the orders of
/// `options.scan`, chooses the physical modes by clustering
/// ([`crate::modal::stabilization::select`]), and builds the model from them: a modal
/// model of the chosen poles only (each taken from the highest order its cluster
/// reached), in real block-diagonal form, discrete at the data's sample time (converted
/// to continuous on request).
///
/// # Errors
/// As [`with_scan`], and [`EraError::InvalidParameter`] naming `states` when no cluster
/// is physical.
pub(crate) fn auto(
    frf: &FrfData,
    supplied: Option<&MarkovSequence>,
    options: &EraOptions,
    observer: &mut dyn FnMut(Stage),
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Identification> {
    let scan_options = &options.scan;
    let mut timings = StageTimings::default();
    let (f, factorization, range, s, seconds) = scan_front(
        frf,
        supplied,
        options,
        scan_options,
        observer,
        progress,
        &mut timings,
    )?;
    let clock = Instant::now();
    // The band needs the lines only: the data is integrated once, in `assess`.
    let (_, band_hz) = fit_band(frf.frequency_hz(), options);
    let band_hz = match scan_options.band_hz {
        Some((lo, hi)) => (band_hz.0.max(lo), band_hz.1.min(hi)),
        None => band_hz,
    };
    let mut selection = select(&s, band_hz, &criteria_for(scan_options, &range));
    if scan_options.significance {
        // Supplied Markov parameters (OKID's) are judged against their own transfer
        // function: the FRFs beside them are a Welch estimate whose resolution and
        // averages they do not share.
        let own;
        let against = match supplied {
            Some(_) => {
                own = crate::sources::frf::frf_of_markov(
                    &f.markov,
                    f.sample_time_s(),
                    frf.quantity(),
                )?;
                &own
            }
            None => frf,
        };
        judge_significance(
            &mut selection,
            &s,
            against,
            options,
            band_hz,
            f.sample_time_s(),
        )?;
        if supplied.is_some() {
            let factor = f
                .scale
                .map_or(1.0, |sc| MagnitudeScale::factor(sc.exponent));
            drop_negligible(&mut selection, &s, frf, band_hz, f.sample_time_s(), factor);
        }
    }
    let chosen: Vec<&crate::modal::stabilization::ScanPole> = selection
        .physical()
        .map(|c| &s.poles[c.representative])
        .collect();
    if chosen.is_empty() {
        return Err(EraError::InvalidParameter {
            name: "states",
            value: "auto".into(),
            reason: crate::params::names::Prose::from(format!(
                "no mode is stable across orders {range} (rule: {}): give ",
                selection.rule()
            ))
            .param(crate::params::names::Param::States)
            .text(" N, or a wider ")
            .param(crate::params::names::Param::Orders)
            .text(" range"),
        });
    }
    let top = *s.orders.last().expect("a scan has orders");
    // The realization at the highest order, for its diagnostics (singular values,
    // warnings); its model is replaced by the chosen modes.
    let mut realization = factorization.realize(top, options.direct_term)?;
    if supplied.is_some() {
        not_circular(&mut realization);
    }
    let mut discrete = modal_model(&chosen, &realization.model.d, f.sample_time_s());
    if let Some(sc) = f.scale {
        sc.undo(&mut realization);
        sc.undo_model(&mut discrete);
    }
    timings.selection = clock.elapsed().as_secs_f64();
    let note = format!(
        "a modal model of the {} physical modes ({} states), each pole taken from the highest order its cluster reached (of the realizations {range} from one factorization of H0 at {} states)",
        chosen.len(),
        2 * chosen.len(),
        range.max
    );
    let mut found = back(
        frf,
        options,
        Path::Fast,
        observer,
        timings,
        realization,
        discrete,
        f.sample_time_s(),
    )?;
    // Indicators of the chosen poles come from the scan (their own order's factors).
    for (m, q) in found.modal.modes.iter().zip(found.quality.iter_mut()) {
        let j = (0..chosen.len())
            .min_by(|&a, &b| {
                (chosen[a].frequency_hz - m.frequency_hz)
                    .abs()
                    .total_cmp(&(chosen[b].frequency_hz - m.frequency_hz).abs())
            })
            .expect("chosen is not empty");
        let p = chosen[j];
        q.indicators.emac = Some(p.emac);
        q.indicators.cmi = Some(p.cmi());
        let cluster = selection
            .physical()
            .find(|c| std::ptr::eq(&s.poles[c.representative], p));
        q.stable_orders = cluster.map(|c| c.members.len());
        if q.physical && q.indicators.cmi < Some(scan_options.selection.cmi_minimum) {
            q.physical = false;
            q.reason = Some(
                crate::modal::stabilization::Rejection::LowCmi(p.cmi()).to_string()
                    + " at the order its pole was taken from",
            );
        }
        if q.physical {
            q.reason = None;
        }
    }
    found.suspects = crate::identify::suspect::check_identification(&found);
    found.stabilization = Some(Stabilization::new(
        range,
        s,
        selection,
        &factorization,
        &found.measured,
        seconds,
        Some(note),
    ));
    Ok(found)
}

/// Step 5 of the automatic choice (docs/src/design.md §10): each physical cluster's mode
/// judged against the noise of the data. The representatives' poles are fitted to the
/// processed FRFs over the band, with free residues and residual terms (a linear least
/// squares, [`crate::refine`] with no iteration), in the domain that fits better (a
/// continuous model, or the zero-order-hold image). The residual gives the noise
/// variance `σ̂²`, and each mode's significance is its energy in the fit over `σ̂²`
/// per parameter ([`crate::refine::RefinedMode::significance`]). The least
/// significant mode below Schwarz's bar ([`crate::refine::Refinement::significance_minimum`])
/// is marked [`Rejection::Insignificant`] and the rest refitted, until every mode
/// passes. A noise mode is stable across orders (the orders realize the same data), so
/// recurrence cannot tell it; the noise can. The noise from the residual includes what
/// no mode explains (leakage, nonlinearity), which only raises the bar.
///
/// [`Rejection::Insignificant`]: crate::modal::stabilization::Rejection::Insignificant
fn judge_significance(
    selection: &mut Selection,
    scan: &Scan,
    frf: &FrfData,
    options: &EraOptions,
    band_hz: (f64, f64),
    sample_time_s: f64,
) -> Result<()> {
    use crate::modal::stabilization::Rejection;
    let processed = integrate(frf, options.integrations)?;
    let freq = processed.frequency_hz();
    let (first_line, _) = fit_band(freq, options);
    let (first, end) = crate::data::frf::band_lines(freq, band_hz, first_line);
    if end <= first + 2 {
        return Ok(());
    }
    let probe = crate::refine::RefineOptions {
        max_iterations: 0,
        add_missed: false,
        rank_one: false,
        band: Some((first, end)),
        weighting: crate::refine::Weighting::Uniform,
        standard_deviations: false,
        ..Default::default()
    };
    let mut alive: Vec<usize> = (0..selection.clusters.len())
        .filter(|&c| selection.clusters[c].physical)
        .collect();
    let mut domain: Option<Option<f64>> = None;
    while !alive.is_empty() {
        let poles: Vec<crate::Complex64> = alive
            .iter()
            .map(|&c| scan.poles[selection.clusters[c].representative].continuous_pole)
            .collect();
        let fit = |ts: Option<f64>| {
            let mut o = probe.clone();
            o.sample_time_s = ts;
            crate::refine::refine(&processed, &poles, &o, &mut |_, _| {})
        };
        let r = match domain {
            Some(ts) => fit(ts),
            None => {
                // The domain that fits better, decided once on the full set.
                let (c, z) = crate::refine::refine_in_both_domains(
                    &processed,
                    &poles,
                    &probe,
                    sample_time_s,
                );
                match (c, z) {
                    (_, Err(EraError::Interrupted)) => Err(EraError::Interrupted),
                    (Ok(c), Ok(z)) => {
                        let zoh = z.cost_before < c.cost_before;
                        domain = Some(zoh.then_some(sample_time_s));
                        Ok(if zoh { z } else { c })
                    }
                    (Ok(c), Err(_)) => {
                        domain = Some(None);
                        Ok(c)
                    }
                    (Err(e), _) => Err(e),
                }
            }
        };
        // A fit the data cannot support (too few lines for the modes) judges nothing; an
        // interruption is passed on.
        let r = match r {
            Ok(r) => r,
            Err(EraError::Interrupted) => return Err(EraError::Interrupted),
            Err(_) => return Ok(()),
        };
        let least = r.significance_minimum();
        // Start poles the fit dropped (coalesced with another, real) go first, with
        // the fit's reason.
        if let Some((k, _)) = r.dropped.first() {
            let c = alive.remove(*k);
            let cluster = &mut selection.clusters[c];
            cluster.physical = false;
            cluster.rejection = Some(Rejection::Dropped);
            continue;
        }
        let mut worst: Option<(usize, f64)> = None;
        for m in &r.modes {
            if m.significance.is_finite()
                && m.significance < least
                && worst.is_none_or(|(_, w)| m.significance < w)
            {
                worst = Some((m.start, m.significance));
            }
        }
        let Some((k, significance)) = worst else {
            mark_satellites(selection, scan, &alive, &freq[first..end], sample_time_s);
            break;
        };
        let c = alive.remove(k);
        let cluster = &mut selection.clusters[c];
        cluster.physical = false;
        cluster.rejection = Some(Rejection::Insignificant(significance.max(0.0), least));
    }
    Ok(())
}

/// Supplied Markov parameters are judged against their own transfer function
/// ([`judge_significance`]), where the observer's own noise poles are significant too:
/// they are told by their share of the measured FRFs, below
/// [`SelectionCriteria::contribution_minimum`] (the bar the table applies to every
/// mode), and leave the model before it is built. `factor` is the magnitude scale of
/// the scan's poles against `frf`.
///
/// [`SelectionCriteria::contribution_minimum`]: crate::modal::stabilization::SelectionCriteria::contribution_minimum
fn drop_negligible(
    selection: &mut Selection,
    scan: &Scan,
    frf: &FrfData,
    band_hz: (f64, f64),
    sample_time_s: f64,
    factor: f64,
) {
    use crate::modal::stabilization::Rejection;
    let freq = frf.frequency_hz();
    let (first, end) = crate::data::frf::band_lines(freq, band_hz, 0);
    if end <= first {
        return;
    }
    let lines = frf.lines();
    let reference = (0..frf.outputs() * frf.inputs())
        .flat_map(|pair| frf.values()[pair * lines + first..pair * lines + end].iter())
        .map(|v| v.norm_sqr())
        .sum::<f64>()
        .sqrt();
    if !(reference > 0.0 && reference.is_finite()) {
        return;
    }
    let domain = crate::TimeDomain::Discrete { sample_time_s };
    let points: Vec<crate::Complex64> = freq[first..end]
        .iter()
        .map(|f| crate::pipeline::fit::evaluation_point(domain, *f))
        .collect();
    let minimum = SelectionCriteria::default().contribution_minimum;
    for cluster in selection.clusters.iter_mut().filter(|c| c.physical) {
        let pole = &scan.poles[cluster.representative];
        let share = crate::modal::indicators::term_energy(
            &pole.shape,
            &pole.participation,
            pole.eigenvalue,
            &points,
        )
        .max(0.0)
        .sqrt()
            / factor
            / reference;
        if share < minimum {
            cluster.physical = false;
            cluster.rejection = Some(Rejection::NoContribution(share));
        }
    }
}

/// A mode this close (relative frequency) to a stronger one may be its satellite
/// (step 6 of the automatic choice, docs/src/trust.md).
pub(crate) const SATELLITE_DISTANCE: f64 = 0.05;

/// A satellite's norm over the band is below this fraction of its host's
/// (step 6 of the automatic choice, docs/src/trust.md). In the shaker study (docs/src/trust.md) the satellites were at
/// 2–23 %; the weaker partners of true close pairs passed by their consistency.
pub(crate) const SATELLITE_SHARE: f64 = 0.25;

/// Step 6 of the automatic choice: satellites. Errors of a strong mode's estimate
/// (leakage the window correction leaves, a bias of the FRF estimate, a nonlinearity)
/// are structured like a mode beside it, and ERA gives them a weak pole of their own,
/// stable across orders and significant against the noise. Such a pole is told by
/// three things together: it lies within [`SATELLITE_DISTANCE`] of a physical mode,
/// the norm of its own term over the band (ERA's shape and participation) is below
/// [`SATELLITE_SHARE`] of that mode's, and its consistency over the record (median CMI)
/// is below 0.5 and below half of that mode's. A weak mode of the structure beside a
/// strong one is as consistent as its neighbour and is kept.
fn mark_satellites(
    selection: &mut Selection,
    scan: &Scan,
    alive: &[usize],
    band_lines_hz: &[f64],
    sample_time_s: f64,
) {
    use crate::modal::stabilization::Rejection;
    // The norm of each pole pair's own term (ERA's shape and participation) over the band.
    let domain = crate::TimeDomain::Discrete { sample_time_s };
    let points: Vec<crate::Complex64> = band_lines_hz
        .iter()
        .map(|f| crate::pipeline::fit::evaluation_point(domain, *f))
        .collect();
    let share = |k: usize| {
        let pole = &scan.poles[selection.clusters[alive[k]].representative];
        crate::modal::indicators::term_energy(
            &pole.shape,
            &pole.participation,
            pole.eigenvalue,
            &points,
        )
        .max(0.0)
        .sqrt()
    };
    let facts: Vec<(f64, f64, f64)> = alive
        .iter()
        .enumerate()
        .map(|(k, &c)| {
            let cluster = &selection.clusters[c];
            (
                scan.poles[cluster.representative].frequency_hz,
                share(k),
                cluster.median_cmi,
            )
        })
        .collect();
    for (k, &c) in alive.iter().enumerate() {
        let (f, s, cmi) = facts[k];
        let host = facts.iter().enumerate().find(|&(j, &(fj, sj, cj))| {
            j != k
                && (f - fj).abs() <= SATELLITE_DISTANCE * fj
                && s < SATELLITE_SHARE * sj
                && cmi < 0.5 * cj
                && cmi < 0.5
        });
        if let Some((_, &(fj, sj, cj))) = host {
            let cluster = &mut selection.clusters[c];
            cluster.physical = false;
            cluster.rejection = Some(Rejection::Satellite {
                host_hz: fj,
                share: s / sj,
                cmi,
                host_cmi: cj,
            });
        }
    }
}

/// A discrete model of the chosen poles in real block-diagonal form: per pole
/// `λ = α + iβ` with shape `c = Cφ` and participation `b = ψB`, the block
/// `A = [[α, −β], [β, α]]`, `B = [Re b; Im b]`, `C = [2 Re c, −2 Im c]`, whose response
/// `c b/(z − λ) + c̄ b̄/(z − λ̄)` is the pole pair's term. `d` is the realization's `D`.
pub(crate) fn modal_model(
    poles: &[&crate::modal::stabilization::ScanPole],
    d: &faer::Mat<f64>,
    sample_time_s: f64,
) -> StateSpace {
    let n = 2 * poles.len();
    let (q, p) = (d.nrows(), d.ncols());
    let mut a = faer::Mat::<f64>::zeros(n, n);
    let mut b = faer::Mat::<f64>::zeros(n, p);
    let mut c = faer::Mat::<f64>::zeros(q, n);
    for (k, pole) in poles.iter().enumerate() {
        let (i0, i1) = (2 * k, 2 * k + 1);
        let z = pole.eigenvalue;
        a[(i0, i0)] = z.re;
        a[(i0, i1)] = -z.im;
        a[(i1, i0)] = z.im;
        a[(i1, i1)] = z.re;
        for j in 0..p {
            b[(i0, j)] = pole.participation[j].re;
            b[(i1, j)] = pole.participation[j].im;
        }
        for i in 0..q {
            c[(i, i0)] = 2.0 * pole.shape[i].re;
            c[(i, i1)] = -2.0 * pole.shape[i].im;
        }
    }
    StateSpace::new(
        a,
        b,
        c,
        d.clone(),
        crate::TimeDomain::Discrete { sample_time_s },
    )
}

#[cfg(test)]
mod probe_tests {
    use super::*;
    use crate::sim::{add_noise, ModalSpec, ModalStructure};

    fn markov_of(frf: &FrfData) -> MarkovSequence {
        let options = EraOptions::new(80, 5);
        let mut t = StageTimings::default();
        front(frf, None, &options, Path::Fast, &mut |_| {}, &mut t)
            .unwrap()
            .markov
    }

    /// The accelerance of the seeded structure of `spec`, 801 lines at 0.025 Hz.
    fn modal_frf(spec: ModalSpec) -> FrfData {
        ModalStructure::random(&spec)
            .unwrap()
            .frf(801, 0.025, crate::Quantity::Acceleration)
            .unwrap()
    }

    #[test]
    fn the_probe_is_capped_for_many_channels_and_finds_the_order_of_noisy_data() {
        // The DTA-like set: 8 x 8, 40 modes (80 states), 5 % noise.
        let clean = modal_frf(ModalSpec {
            seed: 7,
            ..ModalSpec::default()
        });
        let markov = markov_of(&add_noise(&clean, 0.05, 7).unwrap());
        let shape = probe_shape(&markov, 5, PROBE_SIDE).unwrap();
        // The square probe would be 249 x 249 blocks (1992 x 1992): the same span of
        // samples in 50 block rows (100 at the larger side).
        assert_eq!((shape.block_rows, shape.block_cols), (50, 448));
        let larger = probe_shape(&markov, 5, PROBE_SIDE_MAX).unwrap();
        assert_eq!((larger.block_rows, larger.block_cols), (100, 398));
        let rank = signal_order(&markov, 5).unwrap().unwrap();
        assert!(
            (78..=90).contains(&rank),
            "order {rank}, 80 states in truth"
        );
        // Exact data: the sampled FRFs' truncation stands above rounding in many more
        // singular values, and the scan keeps its default range.
        let exact = markov_of(&clean);
        // The first probe's floor is then at the FRFs' truncation, under
        // `EXACT_FLOOR`: no larger probe is taken.
        let first = probe_shape(&exact, 5, PROBE_SIDE).unwrap();
        assert!(matches!(
            probe_count(&exact, first).unwrap(),
            ProbeCount::TooMany { noisy: false }
        ));
        let default = default_orders(exact.samples(), 5, 8, 8).unwrap();
        if let Some(r) = signal_order(&exact, 5).unwrap() {
            assert!(orders_for_rank(r, &default).is_none(), "order {r}");
        }
    }

    #[test]
    fn a_probe_of_few_channels_stays_square() {
        let frf = modal_frf(ModalSpec {
            seed: 3,
            outputs: 2,
            inputs: 2,
            modes: 6,
            ..ModalSpec::default()
        });
        let shape = probe_shape(&markov_of(&frf), 5, PROBE_SIDE).unwrap();
        assert_eq!(shape.block_rows, shape.block_cols);
    }

    #[test]
    fn a_noisy_order_beyond_the_first_probe_is_found_by_the_larger_one() {
        // 8 x 8 with 80 modes (160 states): more than a third of the first probe's 400
        // singular values stand above its floor, too many to trust. At 5 % noise the
        // floor comes from the Gram matrix; at 1e-6 it lies below what the Gram matrix
        // resolves and comes from the SVD, and is still the noise's.
        let clean = modal_frf(ModalSpec {
            seed: 11,
            modes: 80,
            ..ModalSpec::default()
        });
        for noise in [0.05, 1e-6] {
            let markov = markov_of(&add_noise(&clean, noise, 11).unwrap());
            let first = probe_shape(&markov, 5, PROBE_SIDE).unwrap();
            assert!(
                matches!(
                    probe_count(&markov, first).unwrap(),
                    ProbeCount::TooMany { noisy: true }
                ),
                "noise {noise}"
            );
            let rank = signal_order(&markov, 5).unwrap().unwrap();
            // At 1e-6 the sampled FRFs' truncation stands above the noise in more
            // values (as on exact data, below): an order above the truth's.
            let plausible = if noise > 1e-3 { 150..=190 } else { 160..=266 };
            assert!(
                plausible.contains(&rank),
                "noise {noise}: order {rank}, 160 states in truth"
            );
        }
    }
}
