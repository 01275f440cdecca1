//! `era.oma`: operational (output-only) modal analysis, as `era oma` runs it: output
//! correlations of the records against reference channels, realized by SSI-cov or
//! NExT-ERA at the automatic or a fixed order, with standard deviations from a
//! delete-one-block jackknife.

use crate::model::{states_of, OmaFacts, PyIdentification};
use crate::thread_count;
use crate::{era_error, guarded_in, value_error, Int};
use era::identify::oma::{oma, OmaMethod, OmaOptions};
use era::params::Naming;
use numpy::{PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// Output-only identification of `data`, responses to unmeasured broadband forces, as
/// `era oma` runs it.
///
/// `data` is one record, (channels, samples) float64 as `identify_time` takes it, or a
/// list of such records of one test (same channels; their correlations are pooled).
/// `outputs` are the 0-based channels (axis 0) to use (default: all); `references`
/// the channels, among the outputs, they are correlated with (default: every output).
/// `method` is 'ssi-cov' (covariance-driven stochastic subspace identification) or
/// 'next-era' (ERA on the correlations); `states` a fixed order or 'auto' (the
/// default: the stabilization diagram's physical modes); `time_lags` the correlation
/// lags (default from the lowest spectral peak); `blocks` the jackknife's blocks
/// (default 12; 1 for no standard deviations).
///
/// The modes carry `frequency_std_hz` and `damping_ratio_std`; their shapes are
/// unscaled (no input, so no modal mass). `Identification.oma` has the method,
/// channels, lags, blocks, samples and each mode's `shape_std`.
#[pyfunction]
#[pyo3(
    name = "oma",
    signature = (data, sample_rate_hz, outputs=None, references=None, method="ssi-cov", states=None, time_lags=None, blocks=None, threads=None),
    text_signature = "(data, sample_rate_hz, outputs=None, references=None, method='ssi-cov', states='auto', time_lags=None, blocks=6, threads=None)"
)]
#[allow(clippy::too_many_arguments)]
pub fn oma_py(
    py: Python<'_>,
    data: &Bound<'_, PyAny>,
    sample_rate_hz: f64,
    outputs: Option<Vec<Int>>,
    references: Option<Vec<Int>>,
    method: &str,
    states: Option<&Bound<'_, PyAny>>,
    time_lags: Option<Int>,
    blocks: Option<Int>,
    threads: Option<Int>,
) -> PyResult<PyIdentification> {
    // Every keyword is checked before the data is touched.
    let threads = thread_count(threads)?;
    let (mut options, chosen) = options_of(sample_rate_hz, method, states, time_lags, blocks)?;
    let arrays = records_of(data)?;
    let n_channels = arrays[0].shape()[0];
    let outputs = match outputs {
        Some(list) => crate::frf::channels("outputs", &list, n_channels)?,
        None => (0..n_channels).collect(),
    };
    options.references = references_of(references, &outputs, n_channels)?;
    let views: Vec<_> = arrays.iter().map(|a| a.readonly()).collect();
    let flats = views
        .iter()
        .map(|v| v.as_slice())
        .collect::<Result<Vec<_>, _>>()?;
    let records: Vec<Vec<&[f64]>> = flats
        .iter()
        .zip(&arrays)
        .map(|(flat, a)| crate::frf::rows(flat, a.shape()[1], &outputs))
        .collect();
    check_channels(&records, &outputs)?;
    let method = options.method;
    let found = guarded_in(py, threads, || {
        let views: Vec<&[&[f64]]> = records.iter().map(Vec::as_slice).collect();
        oma(&views, &options).map_err(|e| keyword_error(e, options.lags.is_none()))
    })?;
    let facts = OmaFacts {
        method: found.method.to_string(),
        references: found.references.iter().map(|&k| outputs[k]).collect(),
        outputs,
        lags: found.lags,
        blocks: found.blocks,
        samples: found.samples,
        sample_rate_hz,
        shape_std: found
            .spread
            .iter()
            .map(|s| s.as_ref().map(|s| s.shape_std.clone()))
            .collect(),
    };
    let mut request = era::identify::route::RouteRequest::new(Default::default());
    request.states = chosen;
    request.refine = Some(false);
    request.without_metadata = true;
    let route = request.resolve(found.identification.measured.quantity(), 0);
    let mut era_options = options.era.clone();
    era_options.realizer = match method {
        OmaMethod::NextEra => era::identify::Realizer::Era,
        _ => era::identify::Realizer::Shift,
    };
    Ok(PyIdentification {
        found: found.identification,
        options: era_options,
        refine: None,
        route,
        source: Default::default(),
        oma: Some(facts),
    })
}

/// The options of the keywords, each checked; and the fixed order asked for.
fn options_of(
    sample_rate_hz: f64,
    method: &str,
    states: Option<&Bound<'_, PyAny>>,
    time_lags: Option<Int>,
    blocks: Option<Int>,
) -> PyResult<(OmaOptions, Option<usize>)> {
    let method: OmaMethod = crate::named("method", method)?;
    if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
        return value_error(format!(
            "sample_rate_hz {sample_rate_hz}: must be a positive number of samples per second"
        ));
    }
    let chosen = match states {
        Some(s) if !s.is_none() => states_of(s)?,
        _ => None,
    };
    if chosen == Some(0) {
        return value_error("states 0: a model needs at least 2 states (one mode), or use 'auto'");
    }
    let mut options = OmaOptions::new(sample_rate_hz);
    options.method = method;
    if let Some(n) = time_lags {
        let n = n.size("time_lags")?;
        if !(2..=era::sources::correlation::MAX_LAGS).contains(&n) {
            return value_error(format!(
                "time_lags {n}: must be from 2 to {}",
                era::sources::correlation::MAX_LAGS
            ));
        }
        options.lags = Some(n);
    }
    if let Some(b) = blocks {
        let b = b.size("blocks")?;
        if !(1..=era::sources::correlation::MAX_BLOCKS).contains(&b) {
            return value_error(format!(
                "blocks {b}: must be from 1 (no standard deviations) to {}",
                era::sources::correlation::MAX_BLOCKS
            ));
        }
        options.blocks = b;
    }
    if let Some(n) = chosen {
        options.era.order = era::Order::Fixed(n);
    }
    Ok((options, chosen))
}

/// `data` as records, each (channels, samples), all with the same channels.
fn records_of<'py>(
    data: &Bound<'py, PyAny>,
) -> PyResult<Vec<Bound<'py, numpy::PyArray<f64, numpy::ndarray::Ix2>>>> {
    // One record or a list of them, each (channels, samples).
    let list: Vec<Bound<'_, PyAny>> = if data.is_instance_of::<pyo3::types::PyList>()
        || data.is_instance_of::<pyo3::types::PyTuple>()
    {
        data.try_iter()?.collect::<PyResult<_>>()?
    } else {
        vec![data.clone()]
    };
    if list.is_empty() {
        return value_error("data: give at least one record (channels, samples)");
    }
    let arrays = list
        .iter()
        .map(crate::time_block)
        .collect::<PyResult<Vec<_>>>()?;
    let n_channels = arrays[0].shape()[0];
    for (k, a) in arrays.iter().enumerate() {
        if a.shape()[0] != n_channels {
            return value_error(format!(
                "data: record {} has {} channels, the first {n_channels}: records of one test have the same channels",
                k + 1,
                a.shape()[0]
            ));
        }
    }
    Ok(arrays)
}

/// The references as positions among the outputs; one that is not an output is named.
fn references_of(
    references: Option<Vec<Int>>,
    outputs: &[usize],
    n_channels: usize,
) -> PyResult<Option<Vec<usize>>> {
    Ok(match references {
        None => None,
        Some(list) => {
            let chosen = crate::frf::channels("references", &list, n_channels)?;
            let mut at = Vec::with_capacity(chosen.len());
            for c in chosen {
                let Some(k) = outputs.iter().position(|&o| o == c) else {
                    return value_error(format!(
                        "references: channel {c} is not among the outputs: a reference is one of the outputs"
                    ));
                };
                if at.contains(&k) {
                    return value_error(format!("references: channel {c} is given twice"));
                }
                at.push(k);
            }
            Some(at)
        }
    })
}

/// Every output finite, and none constant in every record (a dead channel).
fn check_channels(records: &[Vec<&[f64]>], outputs: &[usize]) -> PyResult<()> {
    // A dead or non-finite channel named by its channel in the data.
    for (k, record) in records.iter().enumerate() {
        for (ch, &c) in record.iter().zip(outputs) {
            if let Some(s) = ch.iter().position(|v| !v.is_finite()) {
                return value_error(format!(
                    "data: channel {c} of record {} is not finite at sample {s}",
                    k + 1
                ));
            }
        }
    }
    for (i, &c) in outputs.iter().enumerate() {
        if records.iter().all(|r| r[i].iter().all(|v| *v == r[i][0])) {
            return value_error(format!(
                "outputs: channel {c} is constant in every record (a dead channel): leave it out"
            ));
        }
    }
    Ok(())
}

/// A core error as a `ValueError` naming the keyword (`time_lags` for the lags).
fn keyword_error(e: era::EraError, default_lags: bool) -> PyErr {
    if let era::EraError::InvalidParameter {
        name: "lags",
        value,
        reason,
    } = &e
    {
        return pyo3::exceptions::PyValueError::new_err(format!(
            "time_lags {value}{}: {}",
            if default_lags {
                " (the default from the record)"
            } else {
                ""
            },
            reason.message(Naming::Keyword)
        ));
    }
    era_error(e)
}
