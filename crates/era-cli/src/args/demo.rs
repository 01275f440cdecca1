//! `era demo`.

use super::common::CommonArgs;
use clap::Args;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Seed of the noise generator (MINSTD; the Octave peer's run_truth(seed) draws the
    /// same noise).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Noise RMS as a fraction of each FRF's RMS (0.15 = the thesis's 15 %).
    #[arg(long, default_value_t = 0.15, allow_negative_numbers = true)]
    pub noise: f64,
    /// Folder for the FRFs (CSV), both models and fits (model.json, fit.json).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub common: CommonArgs,
}
