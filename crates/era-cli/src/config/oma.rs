//! `era oma`'s flags checked into its settings and the core's `OmaOptions`.

use crate::args::StatesArg;
use crate::config::Settings;
use era::modal::stabilization::OrderRange;
use std::path::PathBuf;
/// `era oma`: the time files, their output and reference channels, and the library's
/// [`era::identify::oma::OmaOptions`] but for the sample rate (read from the files).
#[derive(Debug, Clone)]
pub struct Oma {
    /// Time-history files (records of one test).
    pub files: Vec<PathBuf>,
    /// Output channels, as given.
    pub outputs: String,
    /// Reference channels, as given (`None`: every output).
    pub references: Option<String>,
    /// Sample rate given, Hz (else the files').
    pub sample_rate: Option<f64>,
    /// MAT variables and HDF5 datasets to read.
    pub selection: era_io::time::TimeSelection,
    /// The library's options; `sample_rate_hz` is set once the files are read, and
    /// `references` once the channels are known.
    pub options: era::identify::oma::OmaOptions,
    /// `--states auto` (or none given).
    pub auto: bool,
    /// The model files in `out` but no figures.
    pub no_figures: bool,
    /// Folder for the files, when asked for.
    pub out: Option<PathBuf>,
    /// `--geometry`, when given.
    pub geometry: Option<PathBuf>,
    /// The output switches.
    pub settings: Settings,
}

impl Oma {
    /// The settings of `era oma`'s flags, each checked under its flag's name before
    /// anything is read: a positive sample rate, lags and blocks within the core's
    /// bounds, the orders parsed.
    pub fn new(a: &crate::args::OmaArgs) -> anyhow::Result<Self> {
        use era::identify::oma::OmaOptions;
        use era::sources::correlation::{MAX_BLOCKS, MAX_LAGS};
        if let Some(r) = a.sample_rate {
            if !(r.is_finite() && r > 0.0) {
                return crate::error::usage(format!(
                    "--sample-rate {r}: must be a positive number of samples per second"
                ));
            }
        }
        if let Some(n) = a.time_lags {
            if !(2..=MAX_LAGS).contains(&n) {
                return crate::error::usage(format!(
                    "--time-lags {n}: must be from 2 to {MAX_LAGS} (the correlations R_0 .. R_(N-1); the Hankel takes R_1 on)"
                ));
            }
        }
        if !(1..=MAX_BLOCKS).contains(&a.blocks) {
            return crate::error::usage(format!(
                "--blocks {}: must be from 1 (no standard deviations) to {MAX_BLOCKS}",
                a.blocks
            ));
        }
        let mut options = OmaOptions::new(1.0);
        options.method = a.method;
        options.lags = a.time_lags;
        options.blocks = a.blocks;
        let auto = !matches!(a.states, Some(StatesArg::Fixed(_)));
        let orders = match &a.orders {
            None => None,
            Some(text) => Some(OrderRange::parse(text).map_err(|e| {
                crate::error::UsageError(format!(
                    "--orders {text}: {}",
                    crate::config::identify::reason_of(&e)
                ))
            })?),
        };
        options.era.scan.orders = orders;
        options.era.order =
            match a.states {
                Some(StatesArg::Fixed(0)) => return crate::error::usage(
                    "--states 0: a model needs at least 2 states (one mode), or use --states auto",
                ),
                Some(StatesArg::Fixed(n)) if a.orders.is_some() => era::Order::Scan { states: n },
                Some(StatesArg::Fixed(n)) => era::Order::Fixed(n),
                _ => era::Order::Auto,
            };
        Ok(Oma {
            files: a.files.clone(),
            outputs: a.outputs.clone(),
            references: a.references.clone(),
            sample_rate: a.sample_rate,
            selection: era_io::time::TimeSelection {
                variables: a.variable.clone(),
                datasets: a.dataset.clone(),
            },
            options,
            auto,
            no_figures: a.no_figures,
            out: a.out.clone(),
            geometry: a.geometry.geometry.clone(),
            settings: Settings::from(&a.common),
        })
    }
}
