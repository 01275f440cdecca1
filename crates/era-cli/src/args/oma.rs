//! `era oma FILE...`.

use super::common::{named, CommonArgs};
use super::identify::{parse_states, StatesArg};
use clap::Args;
use era::identify::oma::{OmaMethod, DEFAULT_BLOCKS};
use std::path::PathBuf;

/// What `era oma --help` shows before the flags.
const OMA_EXAMPLES: &str = "\
Examples:
  era oma rec.csv --outputs 2-9
      the modes of responses to unmeasured forces: SSI-cov, every output a reference,
      the automatic order, standard deviations from 6 jackknife blocks
  era oma day1.mat day2.mat --variable acc --sample-rate 100 --outputs 1-30 --out run
      two records of one test; model.json, the figures and run/report.html
  era oma rec.csv --outputs 1-8 --references 1,5 --method next-era --time-lags 400
      two reference channels, NExT-ERA, 400 correlation lags";

#[derive(Debug, Args)]
#[command(before_help = OMA_EXAMPLES)]
pub struct OmaArgs {
    /// Time-history files: CSV (time_s plus named channels), MAT v5 or HDF5, told apart
    /// by content. Several files are records of one test (same channels and sample
    /// rate): their correlations are pooled.
    #[arg(required = true, value_name = "TIME_FILE")]
    pub files: Vec<PathBuf>,
    /// Output (response) channels: 1-based column numbers, ranges and names, e.g. 3-30
    /// or acc. Leave out the forces and any dead channel.
    #[arg(long, value_name = "CHANNELS")]
    pub outputs: String,
    /// Reference channels the outputs are correlated with, among --outputs (default:
    /// every output). A few channels where every mode shows keep the work small.
    #[arg(long, value_name = "CHANNELS")]
    pub references: Option<String>,
    /// Sample rate, Hz: needed for MAT files, and overrides what a CSV or HDF5 file
    /// says.
    #[arg(long, value_name = "HZ", allow_negative_numbers = true)]
    pub sample_rate: Option<f64>,
    /// How the correlations are realized: ssi-cov (covariance-driven stochastic
    /// subspace identification, A from the shift of the observability factor) or
    /// next-era (ERA on the correlations, as on impulse responses).
    #[arg(long, value_parser = named::<OmaMethod>(), default_value_t = OmaMethod::default())]
    pub method: OmaMethod,
    /// Model order in states (two per mode), or `auto` (the default): scan --orders,
    /// cluster the stable poles and keep the physical modes.
    #[arg(long, value_name = "N | auto", value_parser = parse_states)]
    pub states: Option<StatesArg>,
    /// Correlation lags R_0 .. R_(N-1) (default: four periods of the lowest spectral
    /// peak, within a tenth of the record).
    #[arg(long, value_name = "N")]
    pub time_lags: Option<usize>,
    /// Contiguous blocks of the records for the jackknife's standard deviations (1 for
    /// none).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_BLOCKS)]
    pub blocks: usize,
    /// Orders of the stabilization diagram, MIN..MAX[:STEP] (step 2) or a list such as
    /// 50,70,80, all from one SVD. Default with --states auto: a range the data support.
    #[arg(long, value_name = "MIN..MAX[:STEP]")]
    pub orders: Option<String>,
    /// MAT input: the matrix to read (repeat to place several side by side).
    #[arg(long, value_name = "NAME")]
    pub variable: Vec<String>,
    /// HDF5 input: a 2-D dataset (columns are channels), or 1-D datasets, one per
    /// channel (repeat the flag).
    #[arg(long, value_name = "PATH")]
    pub dataset: Vec<String>,
    /// Folder for model.json, fit.json, model.mat, modes.uff, the figures and
    /// report.html (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// The model files in --out but no figures and no report.html.
    #[arg(long, requires = "out")]
    pub no_figures: bool,
    #[command(flatten)]
    pub geometry: super::GeometryArgs,
    #[command(flatten)]
    pub common: CommonArgs,
}
