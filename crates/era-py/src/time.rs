//! `era.identify_time`: a model from input and output time histories, as
//! `era identify --from-time` makes it: the Welch H1 FRFs (window-corrected, the band
//! from their coherence) to fit and judge the model against, and the Markov parameters
//! from OKID's observer (the default) or from those FRFs.

use crate::model::{
    lowpass_of, refine_options_of, route_request, states_of, svd_path, thread_count,
    PyIdentification, Run,
};
use crate::{era_error, guarded, value_error, Int};
use era::frf::estimate::estimate;
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
    signature = (data, sample_rate_hz, inputs, outputs, states=None, markov="okid", observer_order=None, markov_samples=None, era_dc=false, frame=None, window="hann", overlap=0.5, estimator="h1", detrend="mean", quantity="acceleration", hankel_factor=Int(5), lowpass=None, time_domain=None, direct_term=None, svd="auto", refine=None, residuals="both", weighting=None, max_iterations=Int(100), added_modes=true, band=None, preset="measured", threads=None),
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
    era_dc: bool,
    frame: Option<Int>,
    window: &str,
    overlap: f64,
    estimator: &str,
    detrend: &str,
    quantity: &str,
    hankel_factor: Int,
    lowpass: Option<&Bound<'_, PyAny>>,
    time_domain: Option<&str>,
    direct_term: Option<&str>,
    svd: &str,
    refine: Option<bool>,
    residuals: &str,
    weighting: Option<&str>,
    max_iterations: Int,
    added_modes: bool,
    band: Option<(f64, f64)>,
    preset: &str,
    threads: Option<Int>,
) -> PyResult<PyIdentification> {
    // Every keyword is checked before the data is touched.
    let threads = thread_count(threads)?;
    let source: MarkovSource = crate::named("markov", markov)?;
    let okid_route = source == MarkovSource::Okid;
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
        era::limits::SAMPLES
            .check("markov_samples", n as u64)
            .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    }
    let welch_keywords = crate::frf::WelchKeywords::parse(
        sample_rate_hz,
        window,
        overlap,
        estimator,
        detrend,
        quantity,
    )?;
    let (window, estimator, tag) = (
        welch_keywords.window,
        welch_keywords.estimator,
        welch_keywords.quantity,
    );
    let frame = frame.map(|f| f.size("frame")).transpose()?;
    let chosen = match states {
        Some(s) if !s.is_none() => states_of(s)?,
        _ => None,
    };
    let mut request = route_request(preset, chosen, refine, time_domain, direct_term, band)?;
    // Time histories carry their coherence and their window.
    request.without_metadata = false;
    request.markov = source;
    let route = request.resolve(tag, 0);
    let mut options = EraOptions::new(chosen.unwrap_or(0), hankel_factor.size("hankel_factor")?);
    options.lowpass = lowpass_of(lowpass)?;
    options.domain = route.domain;
    options.direct_term = route.direct_term;
    options.svd = svd_path(svd)?;
    if era_dc {
        options.realizer = era::identify::Realizer::EraDc;
    }
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
            era::frf::estimate::judging_frame(samples, 1, overlap)
        } else {
            era::frf::estimate::DEFAULT_FRAME
        }
    });
    let welch = welch_keywords.options(frame);
    let view = array.readonly();
    let flat = view.as_slice()?;
    let rows = crate::frf::rows;
    let (xs, ys) = (rows(flat, samples, &inputs), rows(flat, samples, &outputs));
    let refine_options = refine_options_of(
        (outputs.len(), inputs.len()),
        residuals,
        match weighting {
            Some(w) if !w.trim().eq_ignore_ascii_case("coherence") => w,
            _ => "pair-noise",
        },
        false,
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
    let (found, source_facts) = guarded(py, || {
        era::parallel::with_threads(Naming::Keyword, threads, || -> era::Result<_> {
            let estimated = estimate(&xs, &ys, &welch, estimator, tag)?;
            let coherence: Vec<Vec<f64>> = (0..estimated.frf.outputs())
                .map(|i| estimated.multiple(i).to_vec())
                .collect();
            let mut frf = estimated.frf;
            // H1's lag window (a tapered window's bias), as the CLI divides it out.
            if route.window_correction {
                let lag = era::sources::frf::LagWindow::of_estimate(
                    estimator,
                    window,
                    frame,
                    sample_rate_hz,
                )?;
                if let Some(lag) = lag {
                    frf = lag.correct_frf(&frf)?;
                }
            }
            let band = band.or_else(|| {
                route
                    .coherence_band
                    .then(|| era::frf::coherence_band(frf.frequency_hz(), &coherence))
                    .flatten()
            });
            let fit = era::frf::fit_lines(&frf, 0, band).map_err(|why| {
                let (lo, hi) = band.unwrap_or_default();
                era::EraError::InvalidParameter {
                    name: "band",
                    value: format!("({lo}, {hi})"),
                    reason: why,
                }
            })?;
            let observed = if okid_route {
                let record = Record {
                    inputs: &xs,
                    outputs: &ys,
                };
                Some(okid(std::slice::from_ref(&record), &okid_options)?)
            } else {
                None
            };
            let mut scan = ScanOptions::default();
            scan.band_hz = fit.band_hz;
            let mut era_run = options.clone();
            era_run.domain = route.realization_domain();
            let mut refine_run = refine_options.clone();
            refine_run.band = fit.lines;
            // The estimate's coherence weights the refinement when asked, and by default
            // when OKID's model is refined (as the CLI's --weighting coherence).
            let by_coherence = match weighting {
                Some(w) => w.trim().eq_ignore_ascii_case("coherence"),
                None => okid_route,
            };
            if by_coherence {
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
                fixed_order: chosen.is_some(),
                scan: &scan,
                refine: route.refine.then_some(&refine_run),
                domain: route.domain,
                fitted_hz: fit.fitted_hz,
            };
            let found = run.identify()?;
            Ok((
                found,
                (
                    observed.map(|o| era_io::model_json::okid_json(&o)),
                    refine_run,
                ),
            ))
        })
        .and_then(|r| r)
        .map_err(era_error)
    })?;
    let (facts, refine_options) = source_facts;
    let mut source = std::collections::BTreeMap::new();
    source.insert("markov".to_string(), serde_json::json!(markov));
    source.insert("frame".to_string(), serde_json::json!(frame));
    if let Some(f) = facts {
        source.insert("okid".to_string(), f);
    }
    Ok(PyIdentification {
        found,
        options,
        refine: route.refine.then_some(refine_options),
        route,
        source,
    })
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
