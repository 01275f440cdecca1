//! The core's long calls as the verbs make them: a spinner on stderr while each runs,
//! and its errors worded with the flags' names. ERA ([`identify`]), OKID
//! ([`observe`]), the refinement ([`refine`]), operational modal analysis ([`oma`])
//! and a fleet's records ([`fleet_record`]).

use crate::config::{Identify, Oma, Settings};
use crate::input::time::{joined, TimeRecords};
use anyhow::Context;
use era::data::identification::Identification;
use era::identify::{identify_observed, identify_supplied, Order, ScanOptions};
use era::refine::identification::refine_identification_in;
use era::refine::RefineOptions;
use era::sources::MarkovSequence;
use std::path::Path;
use std::time::Instant;

/// ERA on `frf` (read from `file`) as the flags ask: the automatic order, a fixed order
/// judged against a scan, or a fixed order alone; a spinner on stderr meanwhile.
pub fn identify(
    file: &Path,
    frf: &era::FrfData,
    supplied: Option<&MarkovSequence>,
    era_opts: &era::EraOptions,
    scan_options: &ScanOptions,
    auto: bool,
    settings: &Settings,
) -> anyhow::Result<era::Identification> {
    let spinner = crate::output::progress::spinner(settings);
    let mut on_stage = |stage: era::Stage| spinner.set_message(stage.name());
    let mut on_order = |done: usize, total: usize| {
        spinner.set_message(format!("stabilization: order {done} of {total}"));
    };
    let (stage, order) = (&mut on_stage, &mut on_order);
    let mut options = era_opts.clone();
    options.scan = scan_options.clone();
    let states = era_opts.order.states().unwrap_or(0);
    options.order = match (auto, scan_options.orders.is_some()) {
        (true, _) => Order::Auto,
        (false, true) => Order::Scan { states },
        (false, false) => Order::Fixed(states),
    };
    let found = match supplied {
        None => identify_observed(frf, &options, stage, order),
        Some(m) => identify_supplied(frf, m, &options, stage, order),
    }
    .map_err(|e| match e {
        era::EraError::NotEnoughMarkovSamples {
            needed, available, ..
        } if supplied.is_some() => anyhow::Error::from(crate::error::UsageError(format!(
            "--markov-samples {available}: the Hankel matrix needs {needed} Markov samples (states x hankel factor, plus the direct term): raise --markov-samples, or lower --states or --hankel-factor"
        ))),
        // The scan's orders, and the automatic order, under their flags.
        other => flag_error(other, |name, value| {
            (name == "orders" || (name == "states" && value == "auto"))
                .then(|| (format!("--{name}"), ""))
        }),
    })
    .with_context(|| format!("identifying {}", file.display()));
    spinner.finish_and_clear();
    found
}

/// Runs the refinement of `found` with a spinner that counts the iterations.
pub fn refine(
    found: Identification,
    frf: &era::FrfData,
    options: &RefineOptions,
    domain: Option<era::ModelDomain>,
    settings: &Settings,
) -> anyhow::Result<Identification> {
    let spinner = crate::output::progress::spinner(settings);
    spinner.set_message("refinement");
    let mut on_stage = |_: era::Stage| {};
    let mut on_step = |iteration: usize, cost: f64| {
        spinner.set_message(format!(
            "refinement: iteration {iteration}, cost {cost:.3e}"
        ));
    };
    let refined =
        refine_identification_in(found, frf, options, domain, &mut on_stage, &mut on_step)
            .map_err(|e| {
                flag_error(e, |name, _| {
                    (name == "max-iterations").then(|| (format!("--{name}"), ""))
                })
            })
            .context("refining the model");
    spinner.finish_and_clear();
    refined
}

/// The Markov parameters OKID found in the records, and its seconds.
pub struct Observed {
    /// What OKID found.
    pub okid: era::sources::okid::Okid,
    /// Its seconds.
    pub seconds: f64,
}

impl Observed {
    /// The system's Markov parameters.
    pub fn supplied(&self) -> &MarkovSequence {
        &self.okid.markov
    }
}

/// OKID on the records (`--markov okid`), a spinner meanwhile; an input it cannot use
/// is named by its channel.
pub fn observe(
    a: &Identify,
    records: &TimeRecords,
    settings: &Settings,
) -> anyhow::Result<Observed> {
    use era::sources::okid::{okid, OkidOptions, Record};
    let mut options = OkidOptions::default();
    options.observer_order = a.observer_order;
    let longest = records
        .records
        .iter()
        .filter_map(|r| r.inputs.first().map(|c| c.len()))
        .max()
        .unwrap_or(0);
    options.markov_samples = a
        .markov_samples
        .unwrap_or_else(|| era::sources::okid::default_markov_samples(longest));
    options.sample_time_s = 1.0 / records.rate;
    let inputs: Vec<Vec<&[f64]>> = records
        .records
        .iter()
        .map(|r| channels(&r.inputs))
        .collect();
    let outputs: Vec<Vec<&[f64]>> = records
        .records
        .iter()
        .map(|r| channels(&r.outputs))
        .collect();
    let recs: Vec<Record> = inputs
        .iter()
        .zip(&outputs)
        .map(|(ins, outs)| Record {
            inputs: ins,
            outputs: outs,
        })
        .collect();
    let spinner = crate::output::progress::spinner(settings);
    spinner.set_message("OKID: the observer's least squares");
    let clock = Instant::now();
    let found = okid(&recs, &options);
    spinner.finish_and_clear();
    let found = found.map_err(|e| {
        let named = match &e {
            era::EraError::DeficientInput { input, .. } => Some(format!(
                "--inputs: channel {} cannot drive OKID",
                records.input_labels[input - 1]
            )),
            _ => None,
        };
        let files = records
            .records
            .iter()
            .map(|r| r.path.display().to_string())
            .collect::<Vec<_>>()
            .join(", ");
        let err = anyhow::Error::new(e).context(format!("OKID on {files}"));
        match named {
            Some(text) => err.context(text),
            None => err,
        }
    })?;
    Ok(Observed {
        okid: found,
        seconds: clock.elapsed().as_secs_f64(),
    })
}

/// The channels of a record as slices.
fn channels(set: &[Vec<f64>]) -> Vec<&[f64]> {
    set.iter().map(Vec::as_slice).collect()
}

/// A core error with the flag the user knows: the lags, blocks and references are
/// `--time-lags`, `--blocks` and `--references` here.
fn flagged(e: era::EraError, a: &Oma) -> anyhow::Error {
    flag_error(e, |name, _| match name {
        "lags" if a.options.lags.is_none() => {
            Some(("--time-lags".into(), " (the default from the record)"))
        }
        "lags" => Some(("--time-lags".into(), "")),
        "blocks" | "references" | "orders" | "states" => Some((format!("--{name}"), "")),
        _ => None,
    })
}

/// Operational modal analysis of `records` with `options`, `spinner` saying the stage
/// (and cleared); the core's errors name `era oma`'s flags.
pub fn oma(
    a: &Oma,
    records: &crate::input::oma::Records,
    options: &era::OmaOptions,
    spinner: indicatif::ProgressBar,
) -> anyhow::Result<era::Oma> {
    let slices: Vec<Vec<&[f64]>> = records.channels.iter().map(|r| channels(r)).collect();
    let views: Vec<&[&[f64]]> = slices.iter().map(Vec::as_slice).collect();
    spinner.set_message("output correlations");
    let found = {
        let mut on_stage = |stage: era::Stage| spinner.set_message(stage.name());
        let mut on_order = |done: usize, total: usize| {
            spinner.set_message(format!("stabilization: order {done} of {total}"));
        };
        era::identify::oma::oma_observed(&views, options, &mut on_stage, &mut on_order)
    };
    spinner.finish_and_clear();
    found
        .map_err(|e| flagged(e, a))
        .with_context(|| format!("output-only identification of {}", joined(&a.files, " ")))
}

/// A core error on a parameter of `era simulate fleet`, under its flag's name.
fn fleet_flagged(e: era::EraError) -> anyhow::Error {
    flag_error(e, |name, _| {
        let flag = match name {
            "index" => "records".to_string(),
            "inputs" => "forces".to_string(),
            _ => name.replace('_', "-"),
        };
        Some((format!("--{flag}"), ""))
    })
}

/// Record `index` of the fleet `spec`; the core's errors name `era simulate fleet`'s
/// flags.
pub fn fleet_record(
    spec: &era::sim::fleet::FleetSpec,
    index: usize,
) -> anyhow::Result<era::sim::fleet::FleetRecord> {
    era::sim::fleet::fleet_record(spec, index).map_err(fleet_flagged)
}

/// `e` as a usage error worded `FLAG VALUE NOTE: reason` when it is an invalid parameter
/// that `flag` names (the flag and a note for the core's parameter name and value,
/// `None` to keep `e` as it is); any other error as it is.
pub fn flag_error(
    e: era::EraError,
    flag: impl FnOnce(&str, &str) -> Option<(String, &'static str)>,
) -> anyhow::Error {
    if let era::EraError::InvalidParameter {
        name,
        value,
        reason,
    } = &e
    {
        if let Some((flag, note)) = flag(name, value) {
            return crate::error::UsageError(format!(
                "{flag} {value}{note}: {}",
                reason.message(era::params::Naming::Flag)
            ))
            .into();
        }
    }
    anyhow::Error::from(e)
}
