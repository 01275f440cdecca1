//! The whole pipeline of docs/design.md §1 (the thesis's `frffilt`): FRFs in, a model, its
//! singular values, modes and fit out.

use crate::error::{EraError, Result};
use crate::filter::LowPass;
use crate::frf::FrfData;
use crate::markov::{impulse_responses, impulse_responses_naive, MarkovSequence};
use crate::modal::{modal_parameters_of, ModalForm, ModalParameters};
use crate::preprocess::{integrate, preprocess, zero_leading_lines};
use crate::realize::{realize, realize_naive, DirectTerm, Realization, RealizeOptions, SvdPath};
use crate::response::{fit_metrics, frequency_response_naive, FitReport, HessenbergForm};
use crate::statespace::StateSpace;
use std::time::Instant;

/// Model returned (thesis `cord`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ModelDomain {
    /// The discrete model ERA gives (thesis `cord = 2`).
    #[default]
    Discrete,
    /// Its zero-order-hold inverse (thesis `cord = 1`).
    Continuous,
}

/// Every parameter of the pipeline (docs/design.md §1 table).
#[derive(Debug, Clone, PartialEq)]
pub struct EraOptions {
    /// Model order (thesis `ns`).
    pub states: usize,
    /// Hankel factor (thesis `lh`).
    pub hankel_factor: usize,
    /// Integrations of the FRFs (thesis `ni`).
    pub integrations: usize,
    /// Zero-phase Butterworth `(order, cut-off Hz)` on the impulse responses (thesis
    /// `ford`, `Hzbreak`); `None` for no filter.
    pub lowpass: Option<(usize, f64)>,
    /// Leading lines set to zero (thesis `nz`).
    pub zero_lines: usize,
    /// Pad to `pad_to + 1` lines; 0 for none (thesis `ndpts`).
    pub pad_to: usize,
    /// Model returned (thesis `cord`).
    pub domain: ModelDomain,
    /// `D = 0` or `Y_0`.
    pub direct_term: DirectTerm,
    /// Dense, matrix-free or automatic SVD.
    pub svd: SvdPath,
}

impl EraOptions {
    /// Options with the thesis's defaults for everything but the order and Hankel factor.
    pub fn new(states: usize, hankel_factor: usize) -> Self {
        EraOptions {
            states,
            hankel_factor,
            integrations: 0,
            lowpass: None,
            zero_lines: 0,
            pad_to: 0,
            domain: ModelDomain::Discrete,
            direct_term: DirectTerm::Zero,
            svd: SvdPath::Auto,
        }
    }
    /// The thesis's DTA settings (Appendix J): `ns 80, lh 5, ni 1, nz 3, ndpts 1024`.
    pub fn thesis_dta() -> Self {
        EraOptions {
            integrations: 1,
            zero_lines: 3,
            pad_to: 1024,
            ..Self::new(80, 5)
        }
    }
    /// The thesis's truth-model settings (Appendix J.2.2): `ns 8, lh 4, ni 0, nz 0,
    /// ndpts 1024`.
    pub fn thesis_truth_model() -> Self {
        EraOptions {
            pad_to: 1024,
            ..Self::new(8, 4)
        }
    }
}

impl EraOptions {
    /// Checks what a front end asked for before anything is read or allocated: at least
    /// one state, a Hankel factor of at least 1, the states, Markov samples
    /// (`states × hankel_factor`) and padded lines within [`crate::limits`], and a
    /// Butterworth low-pass of order 1 to 20 at a positive cut-off. Messages name each
    /// parameter as `naming` does (the CLI's `--states`, Python's `states`).
    ///
    /// The stages check their own parameters again for library users; this is the
    /// check a front end makes first, so that a bad flag is refused with its own name.
    ///
    /// # Errors
    /// [`EraError::Invalid`] or [`EraError::Limit`].
    pub fn check(&self, naming: crate::params::Naming) -> Result<()> {
        use crate::limits::{LINES, SAMPLES, STATES};
        use crate::params::invalid;
        let name = |key: &str| naming.name(key);
        if self.states == 0 {
            return invalid(format!(
                "{} 0: the model needs at least one state",
                name("states")
            ));
        }
        if self.hankel_factor == 0 {
            return invalid(format!("{} 0: must be at least 1", name("hankel_factor")));
        }
        STATES.check(name("states"), self.states as u64)?;
        SAMPLES.check_product(
            format!(
                "{} x {} (Markov samples)",
                name("states"),
                name("hankel_factor")
            ),
            &[self.states as u64, self.hankel_factor as u64],
        )?;
        if self.pad_to != 0 {
            LINES.check(
                format!("{} (lines, pad-to + 1)", name("pad_to")),
                (self.pad_to as u64).saturating_add(1),
            )?;
        }
        if let Some((order, hz)) = self.lowpass {
            if !(1..=20).contains(&order) {
                return invalid(format!(
                    "{} {order}: the Butterworth order must be 1 to 20",
                    name("lowpass_order")
                ));
            }
            if !(hz.is_finite() && hz > 0.0) {
                return invalid(format!(
                    "{} {hz}: must be a positive frequency",
                    name("lowpass_hz")
                ));
            }
        }
        Ok(())
    }
}

/// A stage of the pipeline, reported to an observer as it starts
/// ([`identify_observed`]); front ends turn these into progress displays.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Integration, padding, zeroing.
    Preprocess,
    /// Inverse FFT (and filter).
    Markov,
    /// Hankel and SVD (the long one).
    HankelSvd,
    /// Realization products and continuous conversion.
    Realize,
    /// Eigendecomposition and modes.
    Modes,
    /// Model FRF and fit.
    Fit,
}

impl Stage {
    /// Human name.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Preprocess => "preprocessing",
            Stage::Markov => "Markov parameters",
            Stage::HankelSvd => "Hankel + SVD",
            Stage::Realize => "realization",
            Stage::Modes => "modes",
            Stage::Fit => "fit",
        }
    }
}

/// Wall time of each stage, seconds.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StageTimings {
    /// Integration, padding, zeroing.
    pub preprocess: f64,
    /// Inverse FFT (and filter) to Markov parameters.
    pub markov: f64,
    /// Hankel construction and SVD.
    pub hankel_svd: f64,
    /// The realization products of §1.9, and the continuous conversion when asked.
    pub realize: f64,
    /// Eigendecomposition and modal parameters.
    pub modes: f64,
    /// Model FRF and fit metrics.
    pub fit: f64,
}

/// Everything `identify` found.
#[derive(Debug, Clone)]
pub struct Identification {
    /// The identified model (discrete, or continuous on request).
    pub model: StateSpace,
    /// The realization diagnostics (singular values, Hankel size, warnings); its model
    /// is the discrete one.
    pub realization: Realization,
    /// Modes and real poles.
    pub modal: ModalParameters,
    /// Fit against the processed measurement.
    pub fit: FitReport,
    /// The measurement after the same integrations, on its own lines: what the fit and
    /// plots compare against.
    pub processed: FrfData,
    /// Sample time of the impulse responses, s.
    pub sample_time_s: f64,
    /// The model's FRF on the lines of `processed`, `[output][input][line]` as in
    /// [`FrfData::values`]: what the fit compared, kept for plots.
    pub model_response: Vec<crate::Complex64>,
    /// Stage times.
    pub timings: StageTimings,
}

/// The largest FRF magnitude identified as given: `2^300` (about 2e90). Above it the
/// squared norms inside the SVD head for overflow (1e154 overflowed them).
pub const SAFE_MAGNITUDE_MAX: f64 = 2.037_035_976_334_486e90; // 2^300
/// The smallest largest-magnitude identified as given, `2^-300`.
pub const SAFE_MAGNITUDE_MIN: f64 = 4.909_093_465_297_727e-91; // 2^-300

/// An exact power-of-two scale `2^e` (`e` even) applied to data whose largest magnitude
/// lies outside [`SAFE_MAGNITUDE_MIN`, `SAFE_MAGNITUDE_MAX`].
///
/// ERA of `s·G` gives the balanced realization `(A, √s·B, √s·C, s·D)` of `G`'s, with
/// singular values `s·σ`: dividing `B` and `C` by `√s`, `D` and `σ` by `s` (exact, as
/// powers of two) gives the model of the data as given.
#[derive(Debug, Clone, Copy, PartialEq)]
struct MagnitudeScale {
    exponent: i32,
}

impl MagnitudeScale {
    fn of(frf: &FrfData) -> Option<Self> {
        let max = crate::frf::largest_component(frf.values());
        if max == 0.0 || (SAFE_MAGNITUDE_MIN..=SAFE_MAGNITUDE_MAX).contains(&max) {
            return None;
        }
        // Bring the largest magnitude near 1, with an even exponent so √s is exact (±1000
        // are even, so the bound holds).
        let e = crate::frf::exponent_toward_one(max);
        let e = e - e.rem_euclid(2);
        Some(MagnitudeScale { exponent: e })
    }

    fn factor(exponent: i32) -> f64 {
        2f64.powi(exponent)
    }

    fn apply(self, frf: &FrfData) -> Result<FrfData> {
        let s = Self::factor(self.exponent);
        let values = frf.values().iter().map(|v| v * s).collect();
        FrfData::new(
            frf.frequency_hz().to_vec(),
            frf.outputs(),
            frf.inputs(),
            values,
            frf.quantity(),
        )
    }

    fn undo(self, r: &mut Realization) {
        let inv = Self::factor(-self.exponent);
        let inv_sqrt = Self::factor(-self.exponent / 2);
        let m = &mut r.model;
        for (mat, k) in [(&mut m.b, inv_sqrt), (&mut m.c, inv_sqrt), (&mut m.d, inv)] {
            for j in 0..mat.ncols() {
                for i in 0..mat.nrows() {
                    mat[(i, j)] *= k;
                }
            }
        }
        for sv in &mut r.singular_values {
            *sv *= inv;
        }
    }
}

/// Which implementation of each stage to use.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Path {
    Fast,
    Naive,
}

/// Runs docs/design.md §1 on `frf`.
///
/// # Errors
/// [`EraError::AllZero`] when there is nothing to identify, and every error of the
/// stages (invalid parameters, too few samples, rank deficiency, numerical failure).
pub fn identify(frf: &FrfData, options: &EraOptions) -> Result<Identification> {
    run(frf, options, Path::Fast, &mut |_| {})
}

/// [`identify`], calling `observer` as each [`Stage`] starts (for progress displays;
/// the core itself draws nothing).
///
/// # Errors
/// As [`identify`].
pub fn identify_observed(
    frf: &FrfData,
    options: &EraOptions,
    observer: &mut dyn FnMut(Stage),
) -> Result<Identification> {
    run(frf, options, Path::Fast, observer)
}

/// [`identify`] with the naive reference of every stage: DFT by definition, element-wise
/// Hankels, full SVD, loop products, a dense solve per line for the fit.
///
/// # Errors
/// As [`identify`].
pub fn identify_naive(frf: &FrfData, options: &EraOptions) -> Result<Identification> {
    run(frf, options, Path::Naive, &mut |_| {})
}

fn run(
    frf: &FrfData,
    options: &EraOptions,
    path: Path,
    observer: &mut dyn FnMut(Stage),
) -> Result<Identification> {
    if frf.is_all_zero() {
        return Err(EraError::AllZero);
    }
    let mut timings = StageTimings::default();
    let mut clock = Instant::now();
    let mut lap = |slot: &mut f64| {
        *slot = clock.elapsed().as_secs_f64();
        clock = Instant::now();
    };

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

    observer(Stage::Preprocess);
    let pre = preprocess(
        working,
        options.integrations,
        options.pad_to,
        options.zero_lines,
    )?;
    if pre.frf.is_all_zero() {
        return Err(EraError::AllZero);
    }
    lap(&mut timings.preprocess);

    observer(Stage::Markov);
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
    let markov = MarkovSequence::from_pair_series(frf.outputs(), frf.inputs(), &series);
    lap(&mut timings.markov);

    let realize_options = RealizeOptions {
        direct_term: options.direct_term,
        svd: options.svd,
        ..RealizeOptions::new(options.states, options.hankel_factor)
    };
    observer(Stage::HankelSvd);
    let mut realization = match path {
        Path::Fast => realize(&markov, pre.sample_time_s, &realize_options)?,
        Path::Naive => realize_naive(&markov, pre.sample_time_s, &realize_options)?,
    };
    if let Some(sc) = scale {
        sc.undo(&mut realization);
    }
    let mut realize_call = 0.0;
    lap(&mut realize_call);

    observer(Stage::Realize);
    let model = match options.domain {
        ModelDomain::Discrete => realization.model.clone(),
        ModelDomain::Continuous => realization.model.d2c()?,
    };
    lap(&mut timings.realize);
    // realize() did the Hankel and SVD, then the products: split it into its stages.
    timings.hankel_svd = realization.hankel_svd_seconds;
    timings.realize += realize_call - realization.hankel_svd_seconds;

    observer(Stage::Modes);
    let form = ModalForm::new(&model)?;
    let modal = modal_parameters_of(&form, model.domain);
    lap(&mut timings.modes);

    observer(Stage::Fit);
    let processed = integrate(frf, options.integrations)?;
    let measured = zero_leading_lines(&processed, options.zero_lines);
    let response = match path {
        Path::Fast => HessenbergForm::new(&model).response(measured.frequency_hz()),
        Path::Naive => frequency_response_naive(&model, measured.frequency_hz()),
    };
    let first_line = options
        .zero_lines
        .max(usize::from(options.integrations > 0));
    let fit = fit_metrics(&measured, &response, first_line);
    lap(&mut timings.fit);

    Ok(Identification {
        model,
        realization,
        modal,
        fit,
        processed,
        sample_time_s: pre.sample_time_s,
        model_response: response,
        timings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::truth_model_frf;

    fn scaled(frf: &FrfData, factor: f64) -> FrfData {
        FrfData::new(
            frf.frequency_hz().to_vec(),
            frf.outputs(),
            frf.inputs(),
            frf.values().iter().map(|v| v * factor).collect(),
            frf.quantity(),
        )
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
