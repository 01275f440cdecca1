//! `era.identify_time`: a model from input and output time histories, as
//! `era identify --from-time` makes it: the Welch H1 FRFs (window-corrected, the band
//! from their coherence) to fit and judge the model against, and the Markov parameters
//! from OKID's observer (the default) or from those FRFs.

use crate::model::{
    era_options, refine_options_of, route_request, states_of, PyIdentification, Run,
};
use crate::{era_error, guarded_in, thread_count, value_error, Int};
use era::estimate::estimate;
use era::identify::{EraOptions, ScanOptions};
use era::params::Naming;
use era::sources::okid::{okid, ObserverOrder, OkidOptions, Record};
use era::sources::MarkovSource;
use numpy::{PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// Identifies a state-space model from time histories, as `era identify --from-time`:
/// `data` is (channels, samples) float64 sampled at `sample_rate_hz`; `inputs` and
/// `outputs` are 0-based channel indices into axis 0.
///
/// `markov='okid'` (the default) takes the Markov parameters from a least-squares
/// observer fitted to the records (no window, no leakage; `observer_order` lags, or
/// 'auto' for the least BIC; `markov_samples` blocks, default 2048); `markov='frf'`
/// from the Welch H1 FRFs, inverse transformed. Either way the H1 FRFs (`frame` samples
/// per frame: default 2048, or with OKID the largest power of two up to 2048 that
/// gives 8 averages; `window`, `overlap`, `estimator`, `detrend`) are what the model is
/// fitted and judged against and what a refinement fits; their lag window is divided
/// out, and the band is where their coherence is at least 0.5 unless `band` says.
///
/// The preset 'measured' does not refine OKID's model (a refinement against the
/// Welch FRFs would bring their bias back); `refine=True` refines it, weighted by the
/// estimate's multiple coherence unless `weighting` ('pair-noise', 'uniform',
/// 'coherence') says otherwise. The other keywords are `identify`'s. OKID's observer is
/// reported in `parameters['okid']`.
#[pyfunction]
#[pyo3(
    signature = (data, sample_rate_hz, inputs, outputs, states=None, markov="okid", observer_order=None, markov_samples=None, era_dc=None, frame=None, window=None, overlap=None, estimator=None, detrend=None, quantity=None, hankel_factor=None, lowpass=None, time_domain=None, direct_term=None, svd=None, refine=None, residuals=None, weighting=None, max_iterations=None, added_modes=None, band=None, preset=None, threads=None),
    text_signature = "(data, sample_rate_hz, inputs, outputs, states='auto', markov='okid', observer_order='auto', markov_samples=None, era_dc=False, frame=None, window='hann', overlap=0.5, estimator='h1', detrend='mean', quantity='acceleration', hankel_factor=5, lowpass=None, time_domain=None, direct_term=None, svd='auto', refine=None, residuals='both', weighting=None, max_iterations=100, added_modes=True, band=None, preset='measured', threads=None)"
)]
#[allow(clippy::too_many_arguments)]
pub fn identify_time(
    py: Python<'_>,
    data: &Bound<'_, PyAny>,
    sample_rate_hz: f64,
    inputs: Vec<Int>,
    outputs: Vec<Int>,
    states: Option<&Bound<'_, PyAny>>,
    markov: &str,
    observer_order: Option<&Bound<'_, PyAny>>,
    markov_samples: Option<Int>,
    era_dc: Option<bool>,
    frame: Option<Int>,
    window: Option<&str>,
    overlap: Option<f64>,
    estimator: Option<&str>,
    detrend: Option<&str>,
    quantity: Option<&str>,
    hankel_factor: Option<Int>,
    lowpass: Option<&Bound<'_, PyAny>>,
    time_domain: Option<&str>,
    direct_term: Option<&str>,
    svd: Option<&str>,
    refine: Option<bool>,
    residuals: Option<&str>,
    weighting: Option<&str>,
    max_iterations: Option<Int>,
    added_modes: Option<bool>,
    band: Option<(f64, f64)>,
    preset: Option<&str>,
    threads: Option<Int>,
) -> PyResult<PyIdentification> {
    // Every keyword is checked before the data is touched.
    let threads = thread_count(threads)?;
    let source: MarkovSource = crate::named("markov", markov)?;
    let okid_route = source == MarkovSource::Okid;
    let (observer, markov_samples) = observer_of(observer_order, markov_samples, okid_route)?;
    let welch_keywords = crate::frf::WelchKeywords::parse(
        sample_rate_hz,
        window,
        overlap,
        estimator,
        detrend,
        quantity,
    )?;
    let frame = frame.map(|f| f.size("frame")).transpose()?;
    let chosen = match states {
        Some(s) if !s.is_none() => states_of(s)?,
        _ => None,
    };
    let mut request = route_request(preset, chosen, refine, time_domain, direct_term, band)?;
    // Time histories carry their coherence and their window.
    request.without_metadata = false;
    request.markov = source;
    let route = request.resolve(welch_keywords.quantity, 0);
    let mut options = era_options(chosen.unwrap_or(0), hankel_factor, lowpass, svd, era_dc)?;
    options.domain = route.domain;
    options.direct_term = route.direct_term;
    let checked = {
        let mut o = options.clone();
        o.order = era::Order::Fixed(o.order.states().unwrap_or(0).max(1));
        o
    };
    checked.check(Naming::Keyword).map_err(era_error)?;

    let array = crate::time_block(data)?;
    let (n_channels, samples) = (array.shape()[0], array.shape()[1]);
    let inputs = crate::frf::channels("inputs", &inputs, n_channels)?;
    let outputs = crate::frf::channels("outputs", &outputs, n_channels)?;
    let frame = frame.unwrap_or_else(|| {
        if okid_route {
            era::estimate::judging_frame(samples, 1, welch_keywords.overlap)
        } else {
            era::estimate::DEFAULT_FRAME
        }
    });
    let view = array.readonly();
    let flat = view.as_slice()?;
    let rows = crate::frf::rows;
    let refine_options = refine_options_of(
        (outputs.len(), inputs.len()),
        residuals,
        match weighting {
            Some(w) if w.trim().eq_ignore_ascii_case("coherence") => None,
            other => other,
        },
        Some(false),
        added_modes,
        max_iterations,
    )?;
    let okid_options = {
        let mut o = OkidOptions::default();
        o.observer_order = observer.unwrap_or(ObserverOrder::Auto { max: None });
        o.markov_samples =
            markov_samples.unwrap_or_else(|| era::sources::okid::default_markov_samples(samples));
        o.sample_time_s = 1.0 / sample_rate_hz;
        o
    };
    let job = Job {
        xs: rows(flat, samples, &inputs),
        ys: rows(flat, samples, &outputs),
        welch: &welch_keywords,
        frame,
        okid: okid_route.then_some(&okid_options),
        route: &route,
        band,
        options: &options,
        refine_options: &refine_options,
        // The estimate's coherence weights the refinement when asked, and by default
        // when OKID's model is refined (as the CLI's --weighting coherence).
        by_coherence: match weighting {
            Some(w) => w.trim().eq_ignore_ascii_case("coherence"),
            None => okid_route,
        },
        fixed_order: chosen.is_some(),
    };
    let (found, facts, refine_options) = guarded_in(py, threads, || job.run().map_err(era_error))?;
    let mut source_facts = era_io::model_json::ModelParameters::default();
    source_facts.markov = Some(source);
    source_facts.frame = Some(frame);
    source_facts.okid = facts;
    Ok(PyIdentification {
        found,
        options,
        refine: route.refine.then_some(refine_options),
        route,
        source: source_facts,
        oma: None,
    })
}

/// `observer_order=` and `markov_samples=`, checked: OKID's observer only.
fn observer_of(
    observer_order: Option<&Bound<'_, PyAny>>,
    markov_samples: Option<Int>,
    okid_route: bool,
) -> PyResult<(Option<ObserverOrder>, Option<usize>)> {
    let observer = observer_order_of(observer_order)?;
    let markov_samples = markov_samples
        .map(|n| n.size("markov_samples"))
        .transpose()?;
    if !okid_route && (observer.is_some() || markov_samples.is_some()) {
        return value_error(
            "observer_order and markov_samples set OKID's observer, which runs with markov='okid' only",
        );
    }
    if let Some(n) = markov_samples {
        if n < 2 {
            return value_error(format!(
                "markov_samples {n}: OKID returns at least 2 Markov blocks (the direct term and one more)"
            ));
        }
        era::params::limits::SAMPLES
            .check("markov_samples", n as u64)
            .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    }
    Ok((observer, markov_samples))
}

/// One `identify_time` call once its keywords are checked: the records, and what to
/// run on them.
struct Job<'a> {
    xs: Vec<&'a [f64]>,
    ys: Vec<&'a [f64]>,
    welch: &'a crate::frf::WelchKeywords,
    frame: usize,
    /// OKID's options, when the Markov parameters come from its observer.
    okid: Option<&'a OkidOptions>,
    route: &'a era::identify::route::Route,
    band: Option<(f64, f64)>,
    options: &'a EraOptions,
    refine_options: &'a era::refine::RefineOptions,
    /// The refinement weighted by the estimate's coherence.
    by_coherence: bool,
    fixed_order: bool,
}

impl Job<'_> {
    /// The Welch H1 FRFs (window-corrected, the band from their coherence), OKID's
    /// Markov parameters when asked, then the identification as `identify` runs it.
    /// Returns it with OKID's record and the refinement's settings as run.
    fn run(
        &self,
    ) -> era::Result<(
        era::Identification,
        Option<era_io::model_json::OkidJson>,
        era::refine::RefineOptions,
    )> {
        let (welch, route) = (self.welch, self.route);
        let estimated = estimate(
            &self.xs,
            &self.ys,
            &welch.options(self.frame),
            welch.estimator,
            welch.quantity,
        )?;
        let coherence: Vec<Vec<f64>> = (0..estimated.frf.outputs())
            .map(|i| estimated.multiple(i).to_vec())
            .collect();
        let mut frf = estimated.frf;
        // H1's lag window (a tapered window's bias), as the CLI divides it out.
        if route.window_correction {
            let lag = era::sources::frf::LagWindow::of_estimate(
                welch.estimator,
                welch.window,
                self.frame,
                welch.sample_rate_hz,
            )?;
            if let Some(lag) = lag {
                frf = lag.correct_frf(&frf)?;
            }
        }
        let band = self.band.or_else(|| {
            route
                .coherence_band
                .then(|| era::data::frf::coherence_band(frf.frequency_hz(), &coherence))
                .flatten()
        });
        let fit = era::data::frf::fit_lines(&frf, 0, band).map_err(|why| {
            let (lo, hi) = band.unwrap_or_default();
            era::EraError::InvalidParameter {
                name: "band",
                value: format!("({lo}, {hi})"),
                reason: why.into(),
            }
        })?;
        let observed = match self.okid {
            Some(o) => {
                let record = Record {
                    inputs: &self.xs,
                    outputs: &self.ys,
                };
                Some(okid(std::slice::from_ref(&record), o)?)
            }
            None => None,
        };
        let mut scan = ScanOptions::default();
        scan.band_hz = fit.band_hz;
        let mut era_run = self.options.clone();
        era_run.domain = route.realization_domain();
        let mut refine_run = self.refine_options.clone();
        refine_run.band = fit.lines;
        if self.by_coherence {
            let curves: Vec<&[f64]> = coherence.iter().map(Vec::as_slice).collect();
            refine_run.weighting =
                era::refine::Weighting::coherence_of(&curves, frf.outputs(), frf.inputs())
                    .ok_or_else(|| {
                        era::EraError::Numerical(
                            "the estimate's coherence does not match its FRFs".into(),
                        )
                    })?;
        }
        let run = Run {
            data: &frf,
            supplied: observed.as_ref().map(|o| &o.markov),
            era: &era_run,
            fixed_order: self.fixed_order,
            scan: &scan,
            refine: route.refine.then_some(&refine_run),
            domain: route.domain,
            fitted_hz: fit.fitted_hz,
        };
        let found = run.identify()?;
        let facts = observed.map(|o| era_io::model_json::okid_json(&o));
        Ok((found, facts, refine_run))
    }
}

/// `observer_order=`: an int, 'auto' or `None` (both the information criterion).
fn observer_order_of(value: Option<&Bound<'_, PyAny>>) -> PyResult<Option<ObserverOrder>> {
    let Some(v) = value.filter(|v| !v.is_none()) else {
        return Ok(None);
    };
    if let Ok(text) = v.extract::<String>() {
        return if text.trim().eq_ignore_ascii_case("auto") {
            Ok(Some(ObserverOrder::Auto { max: None }))
        } else {
            value_error(format!(
                "observer_order '{text}': expected a number of lags (an int) or 'auto'"
            ))
        };
    }
    Ok(Some(ObserverOrder::Fixed(
        v.extract::<Int>()?.size("observer_order")?,
    )))
}
