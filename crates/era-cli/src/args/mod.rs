//! Command-line arguments (clap), one file per verb and the shared flag groups in
//! [`common`]. Nothing here reads, computes or writes: flags follow docs/src/design.md §1's
//! table, and [`crate::config`] turns them into typed settings.

mod batch;
mod common;
mod compare;
mod demo;
mod experiment;
mod files;
mod frf;
mod friction;
mod geometry;
mod identify;
mod oma;
mod plot;
mod refine;
mod simulate;
mod track;

pub use batch::*;
pub use common::*;
pub use compare::*;
pub use demo::*;
pub use experiment::*;
pub use files::*;
pub use frf::*;
pub use friction::*;
pub use geometry::*;
pub use identify::*;
pub use oma::*;
pub use plot::*;
pub use refine::*;
pub use simulate::*;
pub use track::*;

use clap::{Parser, Subcommand};

/// era — identify state-space models and modal parameters of lightly damped structures
/// from frequency response functions with the Eigensystem Realization Algorithm.
#[derive(Debug, Parser)]
#[command(name = "era", version, about, long_about = None, propagate_version = true)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
    /// Threads for the run, shared by every parallel stage (rayon's loops and faer's
    /// dense kernels): 1 for a batch of runs side by side. Default: every core (or
    /// RAYON_NUM_THREADS).
    #[arg(long, global = true, value_name = "N")]
    pub threads: Option<usize>,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// The thesis's truth-model validation (Table 5.2): truth, ERA without noise, ERA with
    /// noise, side by side.
    Demo(DemoArgs),
    /// Identify a model from an FRF file, or from time histories with --from-time: by
    /// default the automatic order, refined, in continuous time; --preset thesis for the
    /// thesis's plain ERA.
    Identify(Box<IdentifyArgs>),
    /// Estimate FRFs and coherence from input and output time histories (CSV, MAT v5 or
    /// HDF5): Welch-averaged spectra, H1, H2 or Hv.
    Frf(FrfArgs),
    /// Operational modal analysis: the modes of output-only time histories (responses
    /// to unmeasured forces) by SSI-cov or NExT-ERA, with standard deviations from a
    /// jackknife over blocks of the records.
    Oma(Box<OmaArgs>),
    /// Write synthetic FRFs: the truth model or a seeded modal structure.
    Simulate(SimulateArgs),
    /// Coulomb friction of the actuators: estimate from free decay, simulate, tune.
    Friction(FrictionArgs),
    /// Plot an FRF file, overlaid with a model when one is given.
    Plot(PlotArgs),
    /// What an FRF file holds (channels, lines, spacing, quantity, units), read from
    /// the headers only where the format allows: fast on large UFF files.
    Info(InfoArgs),
    /// Convert FRFs between CSV, UFF 58 (ASCII or binary 58b) and MAT. The input format
    /// is told by content, the output format by the extension (.csv, .uff/.unv, .mat).
    Convert(ConvertArgs),
    /// Compare two FRF sets of one structure: overlays, differences by band, and the
    /// modes and fits of their models (given or identified).
    Compare(Box<CompareArgs>),
    /// Identify every record of a manifest (a fleet of monitoring records, the runs of a
    /// test campaign) with one verb and its flags: one Parquet table of modes, one line
    /// per record, failures as rows; shards and resumes.
    Batch(BatchArgs),
    /// Refine a model identified earlier (model.json) against its FRF file: poles,
    /// residues and residual terms by maximum likelihood, with uncertainties.
    Refine(RefineArgs),
    /// Follow the modes of a fleet of records over time: the modes.parquet of `era
    /// batch` (any number of shards) clustered into tracks by frequency and MAC, with
    /// each track's mean, spread and trend, figures and a report.
    Track(TrackArgs),
}
