//! `era frf TIME_FILE...`.

use super::common::{named, parse_units, CommonArgs, UnitsArg, WelchArgs};
use clap::Args;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct FrfArgs {
    /// Time-history files: CSV (time_s plus named channels), MAT v5 or HDF5, told apart
    /// by content. Several files are records of one test: their spectra are averaged.
    #[arg(required = true, value_name = "TIME_FILE")]
    pub files: Vec<PathBuf>,
    /// Input (force) channels: 1-based column numbers, ranges and names, e.g. 1,2 or
    /// force.
    #[arg(long, value_name = "CHANNELS")]
    pub inputs: String,
    /// Output (response) channels, e.g. 3-30 or acc.
    #[arg(long, value_name = "CHANNELS")]
    pub outputs: String,
    #[command(flatten)]
    pub welch: WelchArgs,
    /// What the outputs measure (the FRFs' quantity).
    #[arg(long, value_parser = named::<era::Quantity>(), default_value_t = era::Quantity::default())]
    pub quantity: era::Quantity,
    /// Units of the estimated FRFs, RESPONSE,FORCE (e.g. m/s^2,N), written into the FRF
    /// file for identify, plot and the report; time files seldom carry them.
    #[arg(long, value_name = "RESPONSE,FORCE", value_parser = parse_units)]
    pub units: Option<UnitsArg>,
    /// FRF file to write: .csv, .uff/.unv (UFF 58) or .mat. The coherence goes beside
    /// it, to <name>.coherence.csv.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// UFF output: binary 58b instead of ASCII.
    #[arg(long)]
    pub binary: bool,
    #[command(flatten)]
    pub common: CommonArgs,
}
