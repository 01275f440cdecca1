//! The pipeline at one order (docs/src/design.md §1, the thesis's `frffilt`): the source's
//! Markov sequence (the FRFs' inverse transform, or one supplied), the realization, then
//! the model's modes, indicators and fit against the measured FRFs.

use crate::data::frf::FrfData;
use crate::data::identification::{Identification, ModeQuality, Stage, StageTimings};
use crate::data::statespace::StateSpace;
use crate::error::{EraError, Result};
use crate::identify::options::{EraOptions, ModelDomain, Realizer};
use crate::modal::indicators::{contributions, emac, mpc, ModeIndicators};
use crate::modal::stabilization::{hard_rejection, SelectionCriteria};
use crate::pipeline::filter::LowPass;
use crate::pipeline::fit::{fit_metrics, frequency_response_naive, frequency_response_with};
use crate::pipeline::modes::{continuous_pole, modal_parameters_of, ModalForm, ModalParameters};
use crate::pipeline::realize::{realize, realize_naive, Realization, RealizeOptions};
use crate::sources::frf::preprocess::{integrate, preprocess, zero_leading_lines};
use crate::sources::frf::{impulse_responses, impulse_responses_naive, MarkovSequence};
use std::time::Instant;

/// The largest FRF magnitude identified as given: `2^300` (about 2e90). Above it the
/// squared norms inside the SVD head for overflow (1e154 overflowed them).
pub(crate) const SAFE_MAGNITUDE_MAX: f64 = 2.037_035_976_334_486e90; // 2^300
/// The smallest largest-magnitude identified as given, `2^-300`.
pub(crate) const SAFE_MAGNITUDE_MIN: f64 = 4.909_093_465_297_727e-91; // 2^-300

/// An exact power-of-two scale `2^e` (`e` even) applied to data whose largest magnitude
/// lies outside [`SAFE_MAGNITUDE_MIN`, `SAFE_MAGNITUDE_MAX`].
///
/// ERA of `s·G` gives the balanced realization `(A, √s·B, √s·C, s·D)` of `G`'s, with
/// singular values `s·σ`: dividing `B` and `C` by `√s`, `D` and `σ` by `s` (exact, as
/// powers of two) gives the model of the data as given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct MagnitudeScale {
    pub(crate) exponent: i32,
}

impl MagnitudeScale {
    fn of(frf: &FrfData) -> Option<Self> {
        let max = crate::data::frf::largest_component(frf.values());
        if max == 0.0 || (SAFE_MAGNITUDE_MIN..=SAFE_MAGNITUDE_MAX).contains(&max) {
            return None;
        }
        // Bring the largest magnitude near 1, with an even exponent so √s is exact (±1000
        // are even, so the bound holds).
        let e = crate::data::frf::exponent_toward_one(max);
        let e = e - e.rem_euclid(2);
        Some(MagnitudeScale { exponent: e })
    }

    pub(crate) fn factor(exponent: i32) -> f64 {
        2f64.powi(exponent)
    }

    fn apply(self, frf: &FrfData) -> Result<FrfData> {
        let s = Self::factor(self.exponent);
        let values = frf.values().iter().map(|v| v * s).collect();
        frf.with_values(values)
    }

    pub(crate) fn undo(self, r: &mut Realization) {
        self.undo_model(&mut r.model);
        let inv = Self::factor(-self.exponent);
        let inv_sqrt = Self::factor(-self.exponent / 2);
        for sv in &mut r.singular_values {
            *sv *= inv;
        }
        scale(&mut r.tails.observability, inv_sqrt);
        scale(&mut r.tails.controllability, inv_sqrt);
    }

    pub(crate) fn undo_model(self, m: &mut StateSpace) {
        let inv = Self::factor(-self.exponent);
        let inv_sqrt = Self::factor(-self.exponent / 2);
        scale(&mut m.b, inv_sqrt);
        scale(&mut m.c, inv_sqrt);
        scale(&mut m.d, inv);
    }
}

/// Multiplies every entry of `mat` by `k`.
fn scale(mat: &mut faer::Mat<f64>, k: f64) {
    for j in 0..mat.ncols() {
        for i in 0..mat.nrows() {
            mat[(i, j)] *= k;
        }
    }
}

/// Which implementation of each stage to use.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Path {
    Fast,
    Naive,
}

/// What the front of the pipeline (§1.1–1.3) hands on.
pub(crate) struct Front {
    pub(crate) scale: Option<MagnitudeScale>,
    pub(crate) markov: MarkovSequence,
}

impl Front {
    /// Seconds between the sequence's blocks.
    pub(crate) fn sample_time_s(&self) -> f64 {
        self.markov.sample_time_s()
    }
}

pub(crate) fn front(
    frf: &FrfData,
    supplied: Option<&MarkovSequence>,
    options: &EraOptions,
    path: Path,
    observer: &mut dyn FnMut(Stage),
    timings: &mut StageTimings,
) -> Result<Front> {
    if frf.is_all_zero() {
        return Err(EraError::AllZero);
    }
    if let Some(given) = supplied {
        return supplied_front(frf, given, options, timings);
    }
    let mut clock = Instant::now();
    // Magnitudes far from 1 overflow (or underflow) the squares inside the SVD: such data
    // is identified at an exact power-of-two scale, and the model is scaled back below.
    // Data inside the safe range is untouched (the thesis results stay bit for bit).
    let scale = MagnitudeScale::of(frf);
    let scaled;
    let working = match scale {
        Some(sc) => {
            scaled = sc.apply(frf)?;
            &scaled
        }
        None => frf,
    };

    Stage::Preprocess.enter(observer)?;
    let pre = preprocess(
        working,
        options.integrations,
        options.pad_to,
        options.zero_lines,
    )?;
    if pre.frf.is_all_zero() {
        return Err(EraError::AllZero);
    }
    timings.preprocess = clock.elapsed().as_secs_f64();
    clock = Instant::now();

    Stage::Markov.enter(observer)?;
    let mut series = match path {
        Path::Fast => impulse_responses(&pre.frf)?,
        Path::Naive => impulse_responses_naive(&pre.frf),
    };
    if let Some((order, cutoff_hz)) = options.lowpass {
        let filter = LowPass::design(order, cutoff_hz, pre.sample_time_s)?;
        for s in series.iter_mut() {
            *s = filter.apply(s)?;
        }
    }
    let markov = MarkovSequence::from_pair_series(frf.outputs(), frf.inputs(), &series)
        .with_sample_time(pre.sample_time_s);
    timings.markov = clock.elapsed().as_secs_f64();
    Ok(Front { scale, markov })
}

/// [`EraError::InvalidParameter`] naming the first of `options`' FRF preprocessing
/// (integrations, padding, zeroed lines) that is not 0: it shapes the FRFs' inverse
/// transform, which a sequence from another source (OKID, output correlations) skips.
pub(crate) fn check_no_frf_shaping(options: &EraOptions) -> Result<()> {
    for (key, value) in [
        ("integrations", options.integrations),
        ("pad_to", options.pad_to),
        ("zero_lines", options.zero_lines),
    ] {
        if value != 0 {
            return Err(EraError::InvalidParameter {
                name: key,
                value: value.to_string(),
                reason: "it shapes the FRFs' inverse transform, and these Markov parameters come from elsewhere (OKID, output correlations): leave it at 0".into(),
            });
        }
    }
    Ok(())
}

/// The front of the pipeline on supplied Markov parameters: checked against the FRFs'
/// shape, low-pass filtered when asked, at the FRFs' magnitude scale.
fn supplied_front(
    frf: &FrfData,
    markov: &MarkovSequence,
    options: &EraOptions,
    timings: &mut StageTimings,
) -> Result<Front> {
    let clock = Instant::now();
    for (what, got, expected) in [
        (
            "outputs of the Markov sequence",
            markov.outputs(),
            frf.outputs(),
        ),
        (
            "inputs of the Markov sequence",
            markov.inputs(),
            frf.inputs(),
        ),
    ] {
        if got != expected {
            return Err(EraError::ShapeMismatch {
                what: format!("{what} (the FRFs have {expected})"),
                expected,
                got,
            });
        }
    }
    check_no_frf_shaping(options)?;
    let ts = markov.sample_time_s();
    if !(ts.is_finite() && ts > 0.0) {
        return Err(EraError::InvalidParameter {
            name: "sample_rate",
            value: ts.to_string(),
            reason: "the sample time must be positive".into(),
        });
    }
    let scale = MagnitudeScale::of(frf);
    let factor = scale.map_or(1.0, |sc| MagnitudeScale::factor(sc.exponent));
    let (q, p) = (markov.outputs(), markov.inputs());
    let mut series: Vec<Vec<f64>> = (0..q * p)
        .map(|k| {
            let mut s = markov.pair_series(k / p, k % p);
            s.iter_mut().for_each(|v| *v *= factor);
            s
        })
        .collect();
    if let Some((order, cutoff_hz)) = options.lowpass {
        let filter = LowPass::design(order, cutoff_hz, ts)?;
        for s in series.iter_mut() {
            *s = filter.apply(s)?;
        }
    }
    timings.markov = clock.elapsed().as_secs_f64();
    Ok(Front {
        scale,
        markov: MarkovSequence::from_pair_series(q, p, &series)
            .with_sample_time(ts)
            .with_kind(markov.kind()),
    })
}

/// The fixed order of `options`; `auto` is refused, `what` saying what needs one.
fn fixed_states(options: &EraOptions, what: &str) -> Result<usize> {
    options
        .order
        .states()
        .ok_or_else(|| EraError::InvalidParameter {
            name: "states",
            value: "auto".into(),
            reason: format!("{what}: give `states N`").into(),
        })
}

pub(crate) fn run(
    frf: &FrfData,
    supplied: Option<&MarkovSequence>,
    options: &EraOptions,
    path: Path,
    observer: &mut dyn FnMut(Stage),
) -> Result<Identification> {
    let states = fixed_states(options, "this path realizes one fixed order")?;
    let mut timings = StageTimings::default();
    let f = front(frf, supplied, options, path, observer, &mut timings)?;
    let clock = Instant::now();
    let realize_options = RealizeOptions {
        direct_term: options.direct_term,
        svd: options.svd,
        ..RealizeOptions::new(states, options.hankel_factor)
    };
    Stage::HankelSvd.enter(observer)?;
    let mut realization = match (path, options.realizer) {
        (_, Realizer::EraDc) => crate::pipeline::realize_dc::realize_dc(
            &f.markov,
            f.sample_time_s(),
            states,
            options.hankel_factor,
            options.direct_term,
        )?,
        (Path::Fast, Realizer::Era) => realize(&f.markov, f.sample_time_s(), &realize_options)?,
        (Path::Fast, Realizer::Shift) => {
            crate::pipeline::realize::realize_shift(&f.markov, f.sample_time_s(), &realize_options)?
        }
        (Path::Naive, Realizer::Shift) => {
            return Err(EraError::InvalidParameter {
                name: "realizer",
                value: Realizer::Shift.to_string(),
                reason: "the naive reference realizes ERA only".into(),
            })
        }
        (Path::Naive, Realizer::Era) => {
            realize_naive(&f.markov, f.sample_time_s(), &realize_options)?
        }
    };
    if let Some(sc) = f.scale {
        sc.undo(&mut realization);
    }
    if supplied.is_some() {
        not_circular(&mut realization);
    }
    let realize_call = clock.elapsed().as_secs_f64();
    timings.hankel_svd = realization.hankel_svd_seconds;
    timings.realize = realize_call - realization.hankel_svd_seconds;
    let discrete = realization.model.clone();
    back(
        frf,
        options,
        path,
        observer,
        timings,
        realization,
        discrete,
        f.sample_time_s(),
    )
}

/// The leading `count` singular values (at most `min(rows, cols)`) of the thesis `H0`
/// that a fixed-order run of `frf` with `options` factors: the same Markov sequence,
/// Hankel shape and magnitude scale, for a plot of what follows the order when the run
/// itself computed only its `states` values (the matrix-free path). Each converges to a
/// residual of `1e-6 σ₁`; should the tail not, the values past the order are the Ritz
/// values of the oversampled block, as a scan's are
/// ([`crate::pipeline::factor::EXTRA_SINGULAR_VALUES`]). `None` for ERA/DC, which
/// factors another matrix.
pub(crate) fn hankel_singular_values(
    frf: &FrfData,
    options: &EraOptions,
    count: usize,
) -> Result<Option<Vec<f64>>> {
    use crate::linalg::tsvd::{truncated_svd, TruncatedSvdOptions};
    use crate::pipeline::hankel::ThesisHankel;
    use crate::pipeline::hankel_op::HankelOperator;
    if options.realizer == Realizer::EraDc {
        return Ok(None);
    }
    let states = fixed_states(options, "the Hankel of one fixed order")?;
    let mut timings = StageTimings::default();
    let f = front(frf, None, options, Path::Fast, &mut |_| {}, &mut timings)?;
    let shapes = ThesisHankel::new(states, options.hankel_factor)?;
    let short =
        (shapes.h0.block_rows * f.markov.outputs()).min(shapes.h0.block_cols * f.markov.inputs());
    let kept = count.max(states).min(short);
    let op = HankelOperator::new(&f.markov, shapes.h0)?;
    // Every value shown converged to a residual of 1e-6 σ₁ (a plot's accuracy); when
    // the tail's cluster does not get there, the realized triplets converge as in the
    // run and the rest are the Ritz values of the oversampled block.
    let all = TruncatedSvdOptions {
        tolerance: 1e-6,
        ..TruncatedSvdOptions::new(kept)
    };
    let mut svd = match truncated_svd(&op, &all) {
        Ok(svd) => svd,
        Err(_) => truncated_svd(
            &op,
            &crate::pipeline::factor::realized_svd_options(states.min(short), kept, 1e-12, 0.0),
        )?,
    };
    svd.s.truncate(kept);
    if let Some(sc) = f.scale {
        let inv = MagnitudeScale::factor(-sc.exponent);
        svd.s.iter_mut().for_each(|s| *s *= inv);
    }
    Ok(Some(svd.s))
}

/// Supplied Markov parameters are a sequence, not one period of a circular impulse
/// response: the warning about the FRFs' wrap-around does not apply to them.
pub(crate) fn not_circular(realization: &mut Realization) {
    realization.warnings.retain(|w| {
        !matches!(
            w,
            crate::pipeline::realize::RealizeWarning::PastHalfPeriod { .. }
        )
    });
}

/// The back of the pipeline: continuous conversion, modes, indicators and fit of a
/// discrete `model` (the realization's own, or one assembled from chosen modes).
#[allow(clippy::too_many_arguments)]
pub(crate) fn back(
    frf: &FrfData,
    options: &EraOptions,
    path: Path,
    observer: &mut dyn FnMut(Stage),
    mut timings: StageTimings,
    realization: Realization,
    discrete: StateSpace,
    sample_time_s: f64,
) -> Result<Identification> {
    let mut clock = Instant::now();
    let mut lap = |slot: &mut f64| {
        *slot = clock.elapsed().as_secs_f64();
        clock = Instant::now();
    };
    Stage::Realize.enter(observer)?;
    let model = match options.domain {
        ModelDomain::Discrete => discrete.clone(),
        ModelDomain::Continuous => discrete.d2c()?,
    };
    let mut convert = 0.0;
    lap(&mut convert);
    timings.realize += convert;
    assess(
        frf,
        options,
        path,
        observer,
        timings,
        realization,
        model,
        sample_time_s,
    )
}

/// Modes, indicators and fit of `model` as it is (its own time domain).
#[allow(clippy::too_many_arguments)]
pub(crate) fn assess(
    frf: &FrfData,
    options: &EraOptions,
    path: Path,
    observer: &mut dyn FnMut(Stage),
    mut timings: StageTimings,
    realization: Realization,
    model: StateSpace,
    sample_time_s: f64,
) -> Result<Identification> {
    let mut clock = Instant::now();
    let mut lap = |slot: &mut f64| {
        *slot = clock.elapsed().as_secs_f64();
        clock = Instant::now();
    };
    Stage::Modes.enter(observer)?;
    let form = ModalForm::new(&model)?;
    let modal = modal_parameters_of(&form, model.domain);
    lap(&mut timings.modes);

    Stage::Fit.enter(observer)?;
    let processed = integrate(frf, options.integrations)?;
    let measured = zero_leading_lines(&processed, options.zero_lines);
    let response = match path {
        Path::Fast => frequency_response_with(&model, Some(&form), measured.frequency_hz()),
        Path::Naive => frequency_response_naive(&model, measured.frequency_hz()),
    };
    let (first_line, band_hz) = fit_band(measured.frequency_hz(), options);
    let fit = fit_metrics(&measured, &response, first_line);
    let quality = mode_quality(
        &modal,
        &form,
        &model,
        &realization,
        &measured,
        first_line,
        band_hz,
    );
    lap(&mut timings.fit);

    Ok(Identification {
        model,
        realization,
        modal,
        fit,
        processed,
        measured,
        first_line,
        sample_time_s,
        model_response: response,
        timings,
        quality,
        band_hz,
        stabilization: None,
        refinement: None,
        suspects: Vec::new(),
    }
    .with_suspects())
}

/// The first fitted line (past the zeroed lines, and past the 0 Hz line of integrated
/// data) and the frequencies of the first and last fitted lines, from the data's lines
/// alone.
pub(crate) fn fit_band(frequency_hz: &[f64], options: &EraOptions) -> (usize, (f64, f64)) {
    let first_line = options
        .zero_lines
        .max(usize::from(options.integrations > 0));
    let last = frequency_hz.len().saturating_sub(1);
    (
        first_line,
        (frequency_hz[first_line.min(last)], frequency_hz[last]),
    )
}

/// Indicators and the hard criteria of every mode of an identification. EMAC comes from
/// the realization's Hankel tails when the model's state basis is the realization's
/// (its own model, discrete or converted); `None` otherwise.
fn mode_quality(
    modal: &ModalParameters,
    form: &ModalForm,
    model: &StateSpace,
    realization: &Realization,
    measured: &FrfData,
    first_line: usize,
    band_hz: (f64, f64),
) -> Vec<ModeQuality> {
    let criteria = SelectionCriteria::default();
    let same_basis = realization.model.states() == model.states()
        && realization.tails.observability.ncols() == model.states();
    // EMAC needs the discrete eigenvalues of the realization's basis.
    let emacs: Option<(ModalForm, Vec<(f64, f64)>)> = if same_basis {
        // A discrete model is the realization's own: its form is already at hand.
        let own = model.domain == realization.model.domain
            && model.a == realization.model.a
            && model.b == realization.model.b
            && model.c == realization.model.c;
        (if own {
            Some(form.clone())
        } else {
            ModalForm::new(&realization.model).ok()
        })
        .map(|f| {
            let e = emac(&f, &realization.tails);
            (f, e)
        })
        .filter(|_| model.states() == realization.model.states())
    } else {
        None
    };
    let lines = &measured.frequency_hz()[first_line..];
    let (q, p, all) = (measured.outputs(), measured.inputs(), measured.lines());
    let mut band_values = Vec::with_capacity(q * p * lines.len());
    for pair in 0..q * p {
        band_values
            .extend_from_slice(&measured.values()[pair * all + first_line..(pair + 1) * all]);
    }
    let shares = contributions(form, model.domain, lines, &band_values);
    modal
        .modes
        .iter()
        .map(|m| {
            // The eigenvalue of `form` this mode came from (same pole).
            let k = nearest(&form.eigenvalues, m.eigenvalue);
            let emac_value = emacs.as_ref().map(|(df, e)| {
                let j = nearest_continuous(df, realization.model.domain, m.continuous_pole);
                e[j].0 * e[j].1
            });
            let m_pc = mpc(&m.shape);
            let indicators = ModeIndicators {
                mpc: m_pc,
                emac: emac_value,
                cmi: emac_value.map(|e| e * m_pc),
                contribution: Some(shares[k]),
            };
            let mut reason = hard_rejection(
                m.frequency_hz,
                m.damping_ratio,
                indicators.cmi,
                band_hz,
                &criteria,
            );
            if reason.is_none() && shares[k] < criteria.contribution_minimum {
                reason = Some(crate::modal::stabilization::Rejection::NoContribution(
                    shares[k],
                ));
            }
            ModeQuality {
                physical: reason.is_none(),
                reason: reason.map(|r| r.to_string()),
                indicators,
                stable_orders: None,
                frequency_std_hz: None,
                damping_ratio_std: None,
            }
        })
        .collect()
}

fn nearest(values: &[crate::Complex64], target: crate::Complex64) -> usize {
    (0..values.len())
        .min_by(|&a, &b| {
            (values[a] - target)
                .norm()
                .total_cmp(&(values[b] - target).norm())
        })
        .unwrap_or(0)
}

fn nearest_continuous(
    form: &ModalForm,
    domain: crate::TimeDomain,
    pole: crate::Complex64,
) -> usize {
    let s: Vec<crate::Complex64> = form
        .eigenvalues
        .iter()
        .map(|z| continuous_pole(*z, domain))
        .collect();
    nearest(&s, pole)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::identify;
    use crate::sim::truth_model_frf;

    fn scaled(frf: &FrfData, factor: f64) -> FrfData {
        frf.with_values(frf.values().iter().map(|v| v * factor).collect())
            .unwrap()
    }

    #[test]
    fn huge_and_tiny_magnitudes_are_identified_at_a_safe_scale() {
        // FRFs of 1e154 and more overflowed the SVD (exit 1); 1e-300 underflowed.
        let truth = truth_model_frf(None).unwrap();
        let opts = EraOptions::thesis_truth_model();
        let reference = identify(&truth, &opts).unwrap();
        assert!(
            MagnitudeScale::of(&truth).is_none(),
            "the thesis data is untouched"
        );
        for factor in [1e160, 1e300, 1e-300, 2f64.powi(-1000)] {
            let data = scaled(&truth, factor);
            let found = identify(&data, &opts).unwrap_or_else(|e| panic!("x {factor:e}: {e}"));
            // Same modes, the model of the data as given: B·C and D scale with it.
            for (a, b) in found.modal.modes.iter().zip(&reference.modal.modes) {
                assert!(
                    (a.frequency_hz - b.frequency_hz).abs() < 1e-9 * b.frequency_hz,
                    "x {factor:e}: {} vs {}",
                    a.frequency_hz,
                    b.frequency_hz
                );
            }
            let r = reference.realization.singular_values[0];
            let f = found.realization.singular_values[0];
            assert!(
                ((f / factor) / r - 1.0).abs() < 1e-9,
                "x {factor:e}: sigma {f:e} vs {r:e}"
            );
            // The model's response is of the data as given: finite, and of its size.
            let peak = |v: &[crate::Complex64]| v.iter().map(|z| z.norm()).fold(0.0, f64::max);
            let (m, g) = (peak(&found.model_response), peak(found.processed.values()));
            assert!(
                m.is_finite() && (m / g - 1.0).abs() < 0.5,
                "x {factor:e}: {m:e} vs {g:e}"
            );
            let rel = found.fit.pairs[0].relative_error;
            let rel0 = reference.fit.pairs[0].relative_error;
            assert!(
                (rel - rel0).abs() < 1e-6,
                "x {factor:e}: fit {rel} vs {rel0}"
            );
        }
    }
}
