//! `era compare A B`.

use super::common::CommonArgs;
use super::identify::IdentifyArgs;
use clap::{Args, Parser};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct CompareArgs {
    /// First FRF set (CSV, UFF or MAT).
    pub a: PathBuf,
    /// Second FRF set, of the same shape and lines.
    pub b: PathBuf,
    /// Model of A (model.json), for the modes and the fit.
    #[arg(long, value_name = "MODEL_JSON", requires = "model_b")]
    pub model_a: Option<PathBuf>,
    /// Model of B (model.json).
    #[arg(long, value_name = "MODEL_JSON", requires = "model_a")]
    pub model_b: Option<PathBuf>,
    /// Band edges, Hz, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "0,1,2,5,10,14,20")]
    pub bands: Vec<f64>,
    /// Lowest and highest frequency of the fit error, Hz.
    #[arg(long, value_delimiter = ',', default_value = "0.1,14")]
    pub fit_band: Vec<f64>,
    /// Folder for compare.html, compare.json and one PNG per pair.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub common: CommonArgs,
    /// Identify both sets with these `era identify` flags (everything after --identify),
    /// e.g. --identify --states 80 --hankel-factor 5 --integrations 1: plain ERA at that
    /// order (no refinement), with identify's defaults otherwise (--preset thesis for
    /// the thesis's).
    #[arg(long, num_args = 1.., allow_hyphen_values = true, conflicts_with_all = ["model_a", "model_b"])]
    pub identify: Option<Vec<String>>,
}

#[derive(Debug, Parser)]
#[command(name = "--identify", no_binary_name = true)]
pub struct IdentifyFlags {
    #[command(flatten)]
    pub args: IdentifyArgs,
}
