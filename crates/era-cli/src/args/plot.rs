//! `era plot FILE`.

use super::common::{CommonArgs, FrfReadArgs, PhaseArg};
use clap::Args;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct PlotArgs {
    /// FRF file: CSV, UFF 58/58b or MAT v5, told apart by content.
    pub file: PathBuf,
    /// model.json to overlay (from era identify --out).
    #[arg(long, value_name = "MODEL_JSON")]
    pub model: Option<PathBuf>,
    /// Integrations applied to the FRFs before plotting (default: the model's, or 0).
    #[arg(long)]
    pub integrations: Option<usize>,
    /// Leading lines left out (default: the model's, or 0).
    #[arg(long)]
    pub zero_lines: Option<usize>,
    #[command(flatten)]
    pub read: FrfReadArgs,
    #[command(flatten)]
    pub geometry: super::GeometryArgs,
    /// Phase in the figures: wrapped (−180…180°, the default) or unwrapped (where the
    /// step between lines is unambiguous, the measurement on the model's branch).
    #[arg(long, value_enum, default_value_t = PhaseArg::Wrapped)]
    pub phase: PhaseArg,
    #[command(flatten)]
    pub pairs: super::common::PairsArgs,
    /// Folder for the figures (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    #[command(flatten)]
    pub common: CommonArgs,
}
