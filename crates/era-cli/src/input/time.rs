//! Time histories in: the records of a test read (any time format, channels chosen by
//! label or index) and their FRFs and coherence estimated with Welch's method, with
//! the summary the terminal prints and the facts the FRF file records. `era frf`
//! writes the estimate; `era identify --from-time` identifies it (and OKID takes the
//! records themselves); `era oma` reads the sample rate the same way.

use crate::config::{Settings, Welch};
use crate::input::InputFrf;
use anyhow::Context as _;
use era::estimate::{self, Estimator, FrfEstimate, WelchOptions};
use era_io::csv::FrfFile;
use era_io::format::FrfFormat;
use era_io::time::{parse_channels, read_time_file, TimeHistory, TimeSelection};
use era_io::uff::{Channel, ChannelTable, Dof};
use serde_json::json;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// FRFs estimated from a time file, with what a summary needs.
pub struct FromTime {
    /// The FRFs as a file would hold them (metadata: the estimation settings).
    pub input: InputFrf,
    /// The estimate (coherence, spectra).
    pub estimate: FrfEstimate,
    /// Human summary lines.
    pub summary: String,
    /// JSON summary.
    pub json: serde_json::Value,
    /// How the estimate was made.
    pub facts: EstimateFacts,
    /// Seconds reading and estimating.
    pub timings: (f64, f64),
    /// The selected channels of every record, when asked for (OKID reads them).
    pub records: Option<TimeRecords>,
}

/// The selected channels of one record.
pub struct TimeRecord {
    /// Its file.
    pub path: PathBuf,
    /// Its input channels.
    pub inputs: Vec<Vec<f64>>,
    /// Its output channels.
    pub outputs: Vec<Vec<f64>>,
}

/// The selected channels of the records of one test, as read.
pub struct TimeRecords {
    /// Every record.
    pub records: Vec<TimeRecord>,
    /// Samples per second.
    pub rate: f64,
    /// The first record's label of each input and output, `3 (force2)`.
    pub input_labels: Vec<String>,
}

/// How FRFs were estimated from time histories: the file format, the estimator, the
/// window, the frame and the number of averages.
pub struct EstimateFacts {
    /// The time file's format.
    pub format: String,
    /// `h1`, `h2` or `hv`.
    pub estimator: String,
    /// The window's name.
    pub window: String,
    /// Samples per frame.
    pub frame: usize,
    /// Frames averaged.
    pub averages: usize,
}

/// UFF entity names are 10 characters wide.
fn entity(label: &str) -> String {
    let cleaned: String = label
        .chars()
        .map(|c| if c.is_ascii_graphic() { c } else { '_' })
        .take(10)
        .collect();
    if cleaned.is_empty() {
        "NONE".into()
    } else {
        cleaned
    }
}

/// The first record: its table, sample rate (and where it came from) and the selected
/// input and output columns. It describes the result; later records must agree
/// (pooling checks lines and channel counts).
struct FirstRecord {
    history: TimeHistory,
    rate: f64,
    rate_from: String,
    inputs: Vec<usize>,
    outputs: Vec<usize>,
}

/// The spectra of every record, the first record, and the seconds reading and
/// estimating them.
struct Records {
    /// The Welch settings run, the frame resolved.
    welch: Welch,
    spectra: Vec<estimate::Spectra>,
    kept: Option<Vec<TimeRecord>>,
    first: Option<FirstRecord>,
    read_s: f64,
    estimate_s: f64,
}

/// The sample rate of `history`: `--sample-rate` or the file's, and where it came from.
pub(crate) fn sample_rate(
    path: &Path,
    history: &TimeHistory,
    given: Option<f64>,
) -> anyhow::Result<(f64, String)> {
    Ok(match (given, &history.sample_rate) {
        (Some(r), Some((f, from))) if (r - f).abs() > 1e-9 * f => (
            r,
            format!("--sample-rate (the file says {f} Hz, from {from})"),
        ),
        (Some(r), _) => (r, "--sample-rate".to_string()),
        (None, Some((f, from))) => (*f, from.clone()),
        (None, None) => {
            return crate::error::usage(format!(
                "{}: this {} file does not give the sample rate: set --sample-rate HZ",
                path.display(),
                history.format.name()
            ))
        }
    })
}

/// Reads each time file, selects its channels and computes its spectra.
fn read_records(
    paths: &[PathBuf],
    inputs: &str,
    outputs: &str,
    welch: &Welch,
    est: Estimator,
    keep: bool,
    spinner: &indicatif::ProgressBar,
) -> anyhow::Result<Records> {
    let selection = TimeSelection {
        variables: welch.variable.clone(),
        datasets: welch.dataset.clone(),
    };
    let mut records = Records {
        welch: welch.clone(),
        spectra: Vec::new(),
        kept: keep.then(Vec::new),
        first: None,
        read_s: 0.0,
        estimate_s: 0.0,
    };
    for path in paths {
        spinner.set_message(format!("reading {}", path.display()));
        let clock = Instant::now();
        let history = read_time_file(path, &selection)
            .with_context(|| format!("reading {}", path.display()))?;
        records.read_s += clock.elapsed().as_secs_f64();
        let (rate, rate_from) = sample_rate(path, &history, welch.sample_rate)?;
        if records.welch.frame.is_none() {
            // Kept for OKID, the FRFs only judge the model: enough averages to judge
            // it (a frame of 256 samples or more).
            records.welch.frame = Some(if keep {
                era::estimate::judging_frame(history.samples(), paths.len(), welch.overlap)
            } else {
                crate::config::DEFAULT_FRAME
            });
        }
        let welch = &records.welch;
        if let Some(first) = &records.first {
            let r0 = first.rate;
            if (rate - r0).abs() > 1e-9 * r0 {
                return crate::error::usage(format!(
                    "{}: sample rate {rate} Hz, the first file's is {r0} Hz: records to average must share it",
                    path.display()
                ));
            }
        }
        let pick = |flag: &str, spec: &str| {
            parse_channels(spec, &history).map_err(|m| {
                crate::error::UsageError(format!("{flag} {spec}: {m} ({})", path.display()))
            })
        };
        let input_cols = pick("--inputs", inputs)?;
        let output_cols = pick("--outputs", outputs)?;
        let opts = crate::config::welch_options(welch, rate);
        let columns = |cols: &[usize]| -> Vec<&[f64]> {
            cols.iter()
                .map(|&c| history.columns[c].as_slice())
                .collect()
        };
        let (xs, ys) = (columns(&input_cols), columns(&output_cols));
        spinner.set_message(format!("spectra of {}", path.display()));
        let clock = Instant::now();
        let spectra = estimate::spectra(&xs, &ys, &opts, est == Estimator::H2)
            .map_err(|e| describe_estimate_error(e, &history, &input_cols, &output_cols))
            .with_context(|| format!("estimating FRFs from {}", path.display()))?;
        records.estimate_s += clock.elapsed().as_secs_f64();
        records.spectra.push(spectra);
        if let Some(kept) = records.kept.as_mut() {
            let owned = |cols: &[&[f64]]| cols.iter().map(|c| c.to_vec()).collect::<Vec<_>>();
            kept.push(TimeRecord {
                path: path.clone(),
                inputs: owned(&xs),
                outputs: owned(&ys),
            });
        }
        if records.first.is_none() {
            records.first = Some(FirstRecord {
                history,
                rate,
                rate_from,
                inputs: input_cols,
                outputs: output_cols,
            });
        }
    }
    Ok(records)
}

/// Keeps the lines of `found` up to `max` Hz (`--max-hz`).
fn keep_up_to(found: &mut FrfEstimate, max: f64) -> anyhow::Result<()> {
    let f = found.frf.frequency_hz();
    let top = f[f.len() - 1];
    if !(max.is_finite() && max >= f[1] && max <= top) {
        return crate::error::usage(format!(
            "--max-hz {max}: must lie between the first line above 0 Hz ({} Hz) and the Nyquist frequency ({top} Hz)",
            f[1]
        ));
    }
    let keep = f.iter().take_while(|&&v| v <= max * (1.0 + 1e-12)).count();
    found.truncate(keep)?;
    Ok(())
}

/// Reads the time files (records of one test), selects the channels and estimates the
/// FRFs from their pooled spectra.
pub fn estimate_from_time(
    paths: &[PathBuf],
    inputs: &str,
    outputs: &str,
    welch: &Welch,
    quantity: era::Quantity,
    keep_records: bool,
    settings: &Settings,
) -> anyhow::Result<FromTime> {
    if let Some(r) = welch.sample_rate {
        if !(r.is_finite() && r > 0.0) {
            return crate::error::usage(format!(
                "--sample-rate {r}: must be a positive number of samples per second"
            ));
        }
    }
    let est = welch.estimator;
    let spinner = crate::output::progress::spinner(settings);
    let mut records = read_records(paths, inputs, outputs, welch, est, keep_records, &spinner)?;
    let mut estimate_s = records.estimate_s;
    let welch = &records.welch;
    let Some(first) = records.first else {
        return crate::error::usage("no time-history file given");
    };
    let label = |c: &usize| format!("{} ({})", c + 1, first.history.label(*c));
    let kept = records.kept.take().map(|kept| TimeRecords {
        records: kept,
        rate: first.rate,
        input_labels: first.inputs.iter().map(label).collect(),
    });
    let path = &paths[0];
    let opts = crate::config::welch_options(welch, first.rate);
    spinner.set_message("estimating FRFs");
    let clock = Instant::now();
    let pooled = estimate::Spectra::pool(&records.spectra)
        .with_context(|| "averaging the records".to_string())?;
    let found = estimate::estimate_from_spectra(pooled, est, quantity);
    spinner.finish_and_clear();
    let mut found = found
        .map_err(|e| describe_estimate_error(e, &first.history, &first.inputs, &first.outputs))
        .with_context(|| format!("estimating FRFs from {}", path.display()))?;
    estimate_s += clock.elapsed().as_secs_f64();
    if let Some(max) = welch.max_hz {
        keep_up_to(&mut found, max)?;
    }
    let file = FrfFile {
        frf: found.frf.clone(),
        quantity_given: true,
        metadata: estimate_metadata(paths, &opts, est, found.spectra.frames(), welch.max_hz),
        channels: Some(channel_table(&first)),
    };
    let (summary, json) = describe_estimate(paths, &first, &found, &opts, est);
    let note = format!(" [estimated from {}]", first.history.format.name());
    let facts = EstimateFacts {
        format: first.history.format.name().to_string(),
        estimator: est.name().to_string(),
        window: opts.window.name().to_string(),
        frame: opts.frame,
        averages: found.spectra.frames(),
    };
    Ok(FromTime {
        input: InputFrf {
            file,
            format: FrfFormat::Csv,
            note,
        },
        estimate: found,
        summary,
        json,
        facts,
        timings: (records.read_s, estimate_s),
        records: kept,
    })
}

/// The channel table of an estimate: node = column, direction 3, the column's name.
fn channel_table(first: &FirstRecord) -> ChannelTable {
    let history = &first.history;
    let channel = |c: usize| Channel {
        dof: Dof {
            node: c as i64 + 1,
            direction: 3,
        },
        entity: match &history.names {
            Some(n) => entity(&n[c]),
            None => "NONE".into(),
        },
    };
    ChannelTable {
        outputs: first.outputs.iter().map(|&c| channel(c)).collect(),
        inputs: first.inputs.iter().map(|&c| channel(c)).collect(),
    }
}

/// The estimation settings, kept with the FRFs as metadata (`# key: value` in a CSV).
fn estimate_metadata(
    paths: &[PathBuf],
    opts: &WelchOptions,
    est: Estimator,
    frames: usize,
    max_hz: Option<f64>,
) -> BTreeMap<String, String> {
    let mut metadata = BTreeMap::new();
    for (k, v) in [
        ("source", format!("era frf {}", joined(paths, " "))),
        ("estimator", est.name().to_string()),
        ("window", opts.window.name().to_string()),
        ("frame", opts.frame.to_string()),
        ("overlap", opts.overlap.to_string()),
        ("detrend", opts.detrend.name().to_string()),
        ("averages", frames.to_string()),
        ("sample_rate_hz", opts.sample_rate_hz.to_string()),
        (
            "max_hz",
            max_hz.map_or("none".to_string(), |m| m.to_string()),
        ),
    ] {
        metadata.insert(k.to_string(), v);
    }
    metadata
}

/// The paths, `separator`-joined.
pub fn joined(paths: &[PathBuf], separator: &str) -> String {
    paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(separator)
}

/// The lines of the excited band: every input within 40 dB of its largest
/// autospectrum; every line above 0 Hz when none is.
fn excited_band(found: &FrfEstimate) -> Vec<usize> {
    let (p, lines) = (found.frf.inputs(), found.frf.lines());
    let band: Vec<usize> = (1..lines)
        .filter(|&k| {
            (0..p).all(|j| {
                let g = found.spectra.gxx(j, j);
                let top = g.iter().map(|v| v.re).fold(0.0, f64::max);
                g[k].re >= 1e-4 * top
            })
        })
        .collect();
    if band.is_empty() {
        (1..lines).collect()
    } else {
        band
    }
}

/// The human summary and the JSON of an estimate.
fn describe_estimate(
    paths: &[PathBuf],
    first: &FirstRecord,
    found: &FrfEstimate,
    opts: &WelchOptions,
    est: Estimator,
) -> (String, serde_json::Value) {
    let (history, rate) = (&first.history, first.rate);
    let (input_cols, output_cols) = (&first.inputs, &first.outputs);
    let label = |c: usize| history.label(c);
    let frames = found.spectra.frames();
    let (q, p, lines) = (found.frf.outputs(), found.frf.inputs(), found.frf.lines());
    let mut summary = String::new();
    let _ = writeln!(
        summary,
        "  time histories: {} ({}), sample rate {rate} Hz from {}",
        history.description,
        history.format.name(),
        first.rate_from
    );
    if paths.len() > 1 {
        let _ = writeln!(
            summary,
            "  averaged over {} records: {} (the channels and description are the first's)",
            paths.len(),
            joined(paths, ", ")
        );
    }
    let names = |cols: &[usize]| {
        cols.iter()
            .map(|&c| match &history.names {
                Some(_) => format!("{} ({})", c + 1, label(c)),
                None => (c + 1).to_string(),
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    let _ = writeln!(summary, "  inputs: {}", names(input_cols));
    let _ = writeln!(summary, "  outputs: {}", names(output_cols));
    let _ = writeln!(
        summary,
        "  {} estimate: {} frames of {} samples ({} window, {} % overlap = {} samples, detrend {}), {lines} lines at {} Hz",
        est.name().to_uppercase(),
        frames,
        opts.frame,
        opts.window.name(),
        opts.overlap * 100.0,
        opts.overlap_samples(),
        opts.detrend.name(),
        found.frf.spacing_hz(),
    );
    if frames < 10 {
        let _ = writeln!(
            summary,
            "  note: only {frames} averages: coherence and FRF variance are poorly estimated; a shorter --frame gives more"
        );
    }
    if !found.unexcited_lines.is_empty() {
        let _ = writeln!(
            summary,
            "  note: {} line(s) without input power (first at {} Hz): FRF and coherence set to 0 there",
            found.unexcited_lines.len(),
            found.frf.frequency_hz()[found.unexcited_lines[0]]
        );
    }
    // Multiple coherence per output over the excited band: the median, and the share
    // of lines above 0.9.
    let band = excited_band(found);
    let f = found.frf.frequency_hz();
    let _ = writeln!(
        summary,
        "  excited band (inputs within 40 dB of their peak): {} .. {} Hz, {} lines",
        f[band[0]],
        f[band[band.len() - 1]],
        band.len()
    );
    let per_output = coherence_per_output(found, &band, output_cols, &label);
    summary.push_str(&coherence_line(&per_output, q, output_cols, &label));
    let json = json!({
        "files": paths, "format": history.format.name(), "samples": history.samples(),
        "sample_rate_hz": rate, "sample_rate_from": first.rate_from,
        "inputs": input_cols.iter().map(|&c| json!({"column": c + 1, "name": label(c)})).collect::<Vec<_>>(),
        "outputs": output_cols.iter().map(|&c| json!({"column": c + 1, "name": label(c)})).collect::<Vec<_>>(),
        "estimator": est.name(), "window": opts.window.name(), "frame": opts.frame,
        "overlap": opts.overlap, "overlap_samples": opts.overlap_samples(), "detrend": opts.detrend.name(),
        "averages": frames, "lines": lines, "spacing_hz": found.frf.spacing_hz(),
        "pairs": q * p, "unexcited_lines": found.unexcited_lines.len(),
        "excited_band_hz": [f[band[0]], f[band[band.len() - 1]]],
        "coherence": per_output,
    });
    (summary, json)
}

/// Each output's multiple coherence over `band`: the median and the share above 0.9.
fn coherence_per_output(
    found: &FrfEstimate,
    band: &[usize],
    output_cols: &[usize],
    label: &dyn Fn(usize) -> String,
) -> Vec<serde_json::Value> {
    let mut per_output = Vec::new();
    for (i, &column) in output_cols.iter().enumerate() {
        let all = found.multiple(i);
        let mut m: Vec<f64> = band.iter().map(|&k| all[k]).collect();
        m.sort_by(f64::total_cmp);
        let median = m[m.len() / 2];
        let good = m.iter().filter(|v| **v > 0.9).count() as f64 / m.len() as f64;
        per_output.push(json!({"output": i + 1, "channel": label(column),
            "median_multiple_coherence": median, "share_above_0_9": good}));
    }
    per_output
}

/// The summary line of the medians: every output's (up to 8) or their range, and the
/// lowest.
fn coherence_line(
    per_output: &[serde_json::Value],
    q: usize,
    output_cols: &[usize],
    label: &dyn Fn(usize) -> String,
) -> String {
    let medians: Vec<f64> = per_output
        .iter()
        .map(|v| v["median_multiple_coherence"].as_f64().unwrap_or(0.0))
        .collect();
    let lowest = medians
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))
        .map(|(i, v)| (i, *v))
        .unwrap_or((0, 0.0));
    format!(
        "  multiple coherence (median over the band): {} per output; lowest output {} ({}) at {:.4}\n",
        if q <= 8 {
            medians
                .iter()
                .map(|v| format!("{v:.4}"))
                .collect::<Vec<_>>()
                .join(" ")
        } else {
            let mut sorted = medians.clone();
            sorted.sort_by(f64::total_cmp);
            format!("{:.4} .. {:.4}", sorted[0], sorted[sorted.len() - 1])
        },
        lowest.0 + 1,
        label(output_cols[lowest.0]),
        lowest.1
    )
}

/// Names the channels in a singular-input or non-finite error (the library numbers
/// them among the selected inputs and outputs).
fn describe_estimate_error(
    e: era::EraError,
    history: &TimeHistory,
    inputs: &[usize],
    outputs: &[usize],
) -> anyhow::Error {
    let with = |text: String| anyhow::Error::new(e.clone()).context(text);
    match &e {
        era::EraError::NonFiniteSample {
            role,
            channel,
            sample,
        } => {
            let c = if *role == "input" { inputs } else { outputs }[channel - 1];
            with(format!(
                "channel {} ({}) is not finite at sample {sample}",
                c + 1,
                history.label(c)
            ))
        }
        era::EraError::SingularInputSpectrum { .. } => with(format!(
            "inputs (file channels {}) cannot be separated",
            inputs
                .iter()
                .map(|c| format!("{} = {}", c + 1, history.label(*c)))
                .collect::<Vec<_>>()
                .join(", ")
        )),
        _ => anyhow::Error::new(e),
    }
}
