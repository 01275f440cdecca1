//! `era refine MODEL FILE`.

use super::common::{CommonArgs, FrfReadArgs, RefineFitArgs};
use clap::Args;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct RefineArgs {
    /// model.json of an earlier `era identify`.
    pub model: PathBuf,
    /// The FRF file it was identified from (same shape and lines).
    pub file: PathBuf,
    #[command(flatten)]
    pub read: FrfReadArgs,
    #[command(flatten)]
    pub fit: RefineFitArgs,
    #[command(flatten)]
    pub geometry: super::GeometryArgs,
    #[command(flatten)]
    pub pairs: super::common::PairsArgs,
    /// Folder for model.json, fit.json, model.mat, modes.uff, the report and the
    /// figures of the refined model (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Write the model files in --out (model.json, fit.json, model.mat, modes.uff,
    /// model_frf.uff) but no figures and no report.html: for batch runs, where the
    /// figures take most of the time. A report and figures that an earlier run left in
    /// the folder stay as they were (the run says so).
    #[arg(long, requires = "out")]
    pub no_figures: bool,
    #[command(flatten)]
    pub common: CommonArgs,
}
