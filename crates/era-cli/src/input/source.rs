//! What `era identify` reads: the FRFs of a file, or FRFs estimated here from time
//! histories (saved with `--save-frf`), with the estimate's coherence, description
//! and records.

use crate::config::{Identify, Settings};
use crate::input::{read_frf_with, set_units, FrfFlags, InputFrf};
use crate::output::report::Human;
use crate::output::InputCoherence;
use era_io::atomic::OutputSet;

/// What `identify` read: the FRFs (from a file, or estimated from time histories), and
/// with `--from-time` the estimate's seconds, coherence and description.
pub struct Source {
    /// The FRFs, with what the file said of them.
    pub input: InputFrf,
    /// Seconds of the estimate (with `--from-time`).
    pub estimate_s: Option<f64>,
    /// The estimate's coherence (with `--from-time`).
    pub coherence: Option<InputCoherence>,
    /// How the FRFs were estimated, for the report (with `--from-time`).
    pub time_format: Option<String>,
    /// The records themselves, for OKID (with `--from-time --markov okid`).
    pub records: Option<crate::input::time::TimeRecords>,
    /// Samples per frame of the estimate (with `--from-time`).
    pub frame: usize,
}

/// The FRFs to identify: estimated from time histories with `--from-time` (and saved
/// with `--save-frf`), read from the FRF file otherwise.
pub fn read(
    a: &Identify,
    frf_outputs: Option<OutputSet>,
    human: &Human,
    settings: &Settings,
) -> anyhow::Result<Source> {
    if !a.from_time {
        let outputs = match a.outputs.as_deref() {
            None => None,
            Some(text) => Some(text.trim().parse::<usize>().map_err(|_| {
                crate::error::UsageError(format!(
                    "--outputs {text}: expected the number of outputs of a MAT FRF matrix (channel lists apply with --from-time)"
                ))
            })?),
        };
        let input = read_frf_with(
            &a.file,
            &FrfFlags {
                quantity: a.quantity,
                outputs,
                units: a.units,
                frequency_variable: a.freq_variable.as_deref(),
            },
        )?;
        human.print(&format!("era identify {}\n", a.file.display()));
        return Ok(Source {
            input,
            estimate_s: None,
            coherence: None,
            time_format: None,
            records: None,
            frame: a.welch.frame_or_default(),
        });
    }
    let inputs = a.inputs.as_deref().unwrap_or_default();
    let Some(outputs) = a.outputs.as_deref() else {
        return crate::error::usage("--from-time needs --outputs CHANNELS (e.g. --outputs 3-30)");
    };
    let quantity = a.quantity.unwrap_or(era::Quantity::Acceleration);
    let mut found = crate::input::time::estimate_from_time(
        &a.record_paths(),
        inputs,
        outputs,
        &a.welch,
        quantity,
        a.markov == era::sources::MarkovSource::Okid,
        settings,
    )?;
    set_units(&mut found.input, a.units);
    human.print(&format!(
        "era identify --from-time {}\n{}",
        a.record_paths()
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(" "),
        found.summary
    ));
    if let (Some(path), Some(set)) = (&a.save_frf, frf_outputs) {
        let coherence = crate::output::estimate::write_estimate(
            set,
            path,
            &found.input.file,
            &found.estimate,
            false,
        )?;
        human.print(&format!(
            "  wrote {} and {}\n",
            path.display(),
            coherence.display()
        ));
    }
    let facts = &found.facts;
    let time_format = format!(
        "time histories ({}); FRFs estimated here: {} estimator, {} window, frame {}, {} averages",
        facts.format, facts.estimator, facts.window, facts.frame, facts.averages
    );
    Ok(Source {
        estimate_s: Some(found.timings.1),
        coherence: Some(InputCoherence::multiple(&found.estimate)),
        time_format: Some(time_format),
        frame: found.facts.frame,
        input: found.input,
        records: found.records,
    })
}
