//! `era oma FILE...`: operational modal analysis. The time files are read as `era frf`
//! reads them, the output channels checked by name (a dead or non-finite channel is
//! named before any work), and [`era::identify::oma::oma_observed`] does the rest; the
//! files, figures and report are [`crate::output::oma`]'s.

use crate::config::Oma;
use crate::output::oma::{oma_json, oma_table, write_model_json, write_oma, OmaRun, Records};
use crate::output::prepare_out_dir;
use crate::output::report::{print_json, stabilization_summary, timings_table, Human};
use anyhow::Context as _;
use era::identify::oma::oma_observed;
use era_io::time::{parse_channels, read_time_file, TimeHistory};
use std::path::PathBuf;
use std::time::Instant;

/// Reads every file, selects the outputs and checks that the records agree.
fn read_records(a: &Oma, spinner: &indicatif::ProgressBar) -> anyhow::Result<Records> {
    let mut records: Option<Records> = None;
    for path in &a.files {
        spinner.set_message(format!("reading {}", path.display()));
        let history = read_time_file(path, &a.selection)
            .with_context(|| format!("reading {}", path.display()))?;
        let (rate, rate_from) = crate::input::time::sample_rate(path, &history, a.sample_rate)?;
        let pick = |flag: &str, spec: &str| {
            parse_channels(spec, &history).map_err(|m| {
                crate::error::UsageError(format!("{flag} {spec}: {m} ({})", path.display()))
            })
        };
        let columns = pick("--outputs", &a.outputs)?;
        check_channels(path, &history, &columns)?;
        let channels: Vec<Vec<f64>> = columns
            .iter()
            .map(|&c| history.columns[c].clone())
            .collect();
        let label = |c: usize| match &history.names {
            Some(_) => format!("{} ({})", c + 1, history.label(c)),
            None => (c + 1).to_string(),
        };
        match records.as_mut() {
            None => {
                let references = match &a.references {
                    None => None,
                    Some(spec) => Some(references(
                        spec,
                        &pick("--references", spec)?,
                        &columns,
                        &label,
                    )?),
                };
                records = Some(Records {
                    channels: vec![channels],
                    rate,
                    rate_from,
                    format: history.format.name().to_string(),
                    labels: columns.iter().map(|&c| label(c)).collect(),
                    names: columns
                        .iter()
                        .map(|&c| match &history.names {
                            Some(n) => n[c].clone(),
                            None => (c + 1).to_string(),
                        })
                        .collect(),
                    columns,
                    references,
                });
            }
            Some(first) => {
                if (rate - first.rate).abs() > 1e-9 * first.rate {
                    return crate::error::usage(format!(
                        "{}: sample rate {rate} Hz, the first file's is {} Hz: records of one test must share it",
                        path.display(),
                        first.rate
                    ));
                }
                if columns.len() != first.columns.len() {
                    return crate::error::usage(format!(
                        "{}: --outputs {} selects {} channels here, {} in the first file: records of one test have the same channels",
                        path.display(),
                        a.outputs,
                        columns.len(),
                        first.columns.len()
                    ));
                }
                first.channels.push(channels);
            }
        }
    }
    let Some(records) = records else {
        return crate::error::usage("no time-history file given");
    };
    dead_channels(&records)?;
    Ok(records)
}

/// The references as positions among the outputs; one that is not an output is named.
fn references(
    spec: &str,
    chosen: &[usize],
    outputs: &[usize],
    label: &dyn Fn(usize) -> String,
) -> anyhow::Result<Vec<usize>> {
    let mut out = Vec::with_capacity(chosen.len());
    for &c in chosen {
        let Some(k) = outputs.iter().position(|&o| o == c) else {
            return crate::error::usage(format!(
                "--references {spec}: channel {} is not among the --outputs: a reference is one of the outputs",
                label(c)
            ));
        };
        if out.contains(&k) {
            return crate::error::usage(format!(
                "--references {spec}: channel {} is given twice",
                label(c)
            ));
        }
        out.push(k);
    }
    Ok(out)
}

/// Every selected channel finite: a NaN or infinity is named by file, channel and sample.
fn check_channels(
    path: &std::path::Path,
    history: &TimeHistory,
    columns: &[usize],
) -> anyhow::Result<()> {
    for &c in columns {
        if let Some(sample) = history.columns[c].iter().position(|v| !v.is_finite()) {
            return crate::error::usage(format!(
                "{}: --outputs channel {} ({}) is not finite at sample {} ({}): leave the channel out or clean the record",
                path.display(),
                c + 1,
                history.label(c),
                sample + 1,
                history.columns[c][sample]
            ));
        }
    }
    Ok(())
}

/// No output constant in every record (a dead channel, which correlates with nothing).
fn dead_channels(records: &Records) -> anyhow::Result<()> {
    for (k, label) in records.labels.iter().enumerate() {
        let varies = records.channels.iter().any(|r| {
            let ch = &r[k];
            ch.iter().any(|v| *v != ch[0])
        });
        if !varies {
            return crate::error::usage(format!(
                "--outputs: channel {label} is constant in every record (a dead channel): leave it out of --outputs"
            ));
        }
    }
    Ok(())
}

/// A core error with the flag the user knows: the lags, blocks and references are
/// `--time-lags`, `--blocks` and `--references` here.
fn flagged(e: era::EraError, a: &Oma) -> anyhow::Error {
    if let era::EraError::InvalidParameter {
        name,
        value,
        reason,
    } = &e
    {
        let flag = match *name {
            "lags" => Some((
                "--time-lags",
                if a.options.lags.is_none() {
                    " (the default from the record)"
                } else {
                    ""
                },
            )),
            "blocks" => Some(("--blocks", "")),
            "references" => Some(("--references", "")),
            "orders" | "states" => Some((
                if *name == "orders" {
                    "--orders"
                } else {
                    "--states"
                },
                "",
            )),
            _ => None,
        };
        if let Some((flag, note)) = flag {
            return crate::error::UsageError(format!(
                "{flag} {value}{note}: {}",
                reason.message(era::params::Naming::Flag)
            ))
            .into();
        }
    }
    anyhow::Error::from(e)
}

/// `era oma`.
pub fn run(a: &Oma) -> anyhow::Result<super::Done> {
    let settings = a.settings;
    let human = Human::new(&settings);
    let mut outputs = match &a.out {
        Some(dir) => Some(prepare_out_dir(dir)?),
        None => None,
    };
    // The geometry is read and checked before the records: a bad one costs no time.
    let geometry = crate::output::geometry::read(a.geometry.as_deref(), &human)?;
    let spinner = crate::output::progress::spinner(&settings);
    let clock = Instant::now();
    let records = read_records(a, &spinner)?;
    let read_s = clock.elapsed().as_secs_f64();
    let mut options = a.options.clone();
    options.sample_rate_hz = records.rate;
    options.references = records.references.clone();
    let slices: Vec<Vec<&[f64]>> = records
        .channels
        .iter()
        .map(|r| r.iter().map(Vec::as_slice).collect())
        .collect();
    let views: Vec<&[&[f64]]> = slices.iter().map(Vec::as_slice).collect();
    spinner.set_message("output correlations");
    let found = {
        let mut on_stage = |stage: era::Stage| spinner.set_message(stage.name());
        let mut on_order = |done: usize, total: usize| {
            spinner.set_message(format!("stabilization: order {done} of {total}"));
        };
        oma_observed(&views, &options, &mut on_stage, &mut on_order)
    };
    spinner.finish_and_clear();
    let found = found
        .map_err(|e| flagged(e, a))
        .with_context(|| format!("output-only identification of {}", joined(&a.files)))?;
    let run = OmaRun {
        files: &a.files,
        records: &records,
        oma: &found,
        options: &options,
        auto: a.auto,
        geometry: geometry.as_ref(),
    };
    human.print(&format!("era oma {}\n", joined(&a.files)));
    human.print(&run.summary());
    human.print(&oma_table(&found));
    if let Some(st) = &found.identification.stabilization {
        human.print(&stabilization_summary(st));
    }
    let mut timings = era_io::model_json::timings_map(&found.identification.timings);
    timings.insert("read".into(), read_s);
    // The correlations are the Markov stage's work: a part of it, not added again.
    timings.insert(
        format!("markov{}correlations", crate::output::report::PART),
        found.correlation_seconds,
    );
    timings.insert("uncertainty".into(), found.uncertainty_seconds);
    let mut json = oma_json(&run);
    if let Some(set) = outputs.as_mut() {
        let clock = Instant::now();
        write_oma(set, &run, !a.no_figures, &settings)?;
        timings.insert("write".into(), clock.elapsed().as_secs_f64());
    }
    if settings.timings {
        if let Some(wall) = crate::output::report::process_seconds() {
            timings.insert(crate::output::report::WALL.into(), wall);
        }
        human.print(&timings_table(&timings));
        json["timings_s"] = serde_json::json!(timings);
    }
    if let Some(set) = outputs.as_mut() {
        write_model_json(set, &json)?;
    }
    if let (Some(dir), Some(set)) = (&a.out, outputs) {
        set.commit()?;
        human.print(&format!(
            "\nwrote {}\n",
            crate::output::oma::written_list(dir, !a.no_figures, a.geometry.is_some())
        ));
    }
    if settings.json {
        print_json(&json)?;
    }
    Ok(super::Done {
        json,
        channels: records.names.clone(),
    })
}

/// The paths, space-joined.
fn joined(paths: &[PathBuf]) -> String {
    paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(" ")
}
