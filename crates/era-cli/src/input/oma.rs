//! What `era oma` reads: the time files as `era frf` reads them, the output channels
//! chosen and checked by name (a dead or non-finite channel is named before any work),
//! the references, and the records' agreement on rate and channels.

use crate::config::Oma;
use anyhow::Context as _;
use era_io::time::{parse_channels, read_time_file, TimeHistory};

/// The records of one test as read: the output channels of each, the sample rate and
/// the labels.
pub struct Records {
    /// Per record, its output channels.
    pub channels: Vec<Vec<Vec<f64>>>,
    /// Samples per second, and where it came from.
    pub rate: f64,
    /// Where the rate came from.
    pub rate_from: String,
    /// The first file's format.
    pub format: String,
    /// The output columns (0-based, in the file).
    pub columns: Vec<usize>,
    /// Each output's label, `3 (y1)`.
    pub labels: Vec<String>,
    /// Each output's name in the file (`y1`), or its 1-based column number.
    pub names: Vec<String>,
    /// The references, 0-based among the outputs, when given.
    pub references: Option<Vec<usize>>,
}

/// Reads every file, selects the outputs and checks that the records agree.
pub fn read_records(a: &Oma, spinner: &indicatif::ProgressBar) -> anyhow::Result<Records> {
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
