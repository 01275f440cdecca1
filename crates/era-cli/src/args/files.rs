//! `era info FILE` and `era convert IN OUT`.

use super::common::{CommonArgs, FrfReadArgs};
use clap::Args;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct InfoArgs {
    /// FRF file: CSV, UFF (58/58b) or MAT v5.
    pub file: PathBuf,
    /// MAT files: the variable holding the frequencies in Hz, when not FreqV.
    #[arg(long, value_name = "NAME")]
    pub freq_variable: Option<String>,
    #[command(flatten)]
    pub common: CommonArgs,
}

#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// FRF file to read: CSV, UFF (58/58b) or MAT v5, told apart by content.
    pub input: PathBuf,
    /// File to write; its extension picks the format: .csv, .uff (or .unv) or .mat.
    pub output: PathBuf,
    /// UFF output: binary 58b (little-endian IEEE, exact) instead of ASCII.
    #[arg(long)]
    pub binary: bool,
    /// UFF output: single precision (ASCII 6 significant digits, binary f32).
    #[arg(long)]
    pub single: bool,
    #[command(flatten)]
    pub read: FrfReadArgs,
    #[command(flatten)]
    pub common: CommonArgs,
}
