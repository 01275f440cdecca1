//! `era simulate truth-model | modal | experiment | shaker`.

use super::common::{named, CommonArgs};
use super::experiment::ExperimentArgs;
use clap::{Args, Subcommand, ValueEnum};
use era::sim::ModalSpec;
use std::path::PathBuf;

/// The seeded structures' damping range, `MIN..MAX`: the core's ([`ModalSpec`]).
fn default_damping() -> String {
    let d = ModalSpec::default();
    format!("{}..{}", d.damping_min, d.damping_max)
}

#[derive(Debug, Args)]
pub struct SimulateArgs {
    #[command(subcommand)]
    pub model: SimulateModel,
}

/// Flags of both simulators.
#[derive(Debug, Args)]
pub struct SimulateCommon {
    /// FRF file to write: .uff/.unv (UFF 58), .mat, or CSV for any other name.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Noise RMS as a fraction of each FRF's RMS (0 = none, 0.15 = 15 %).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub noise: f64,
    /// Seed of the noise (and of the modal structure).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub common: CommonArgs,
}

#[derive(Debug, Subcommand)]
pub enum SimulateModel {
    /// The thesis's 4-mass truth model: 3×3 displacement FRFs, 1025 lines 0…12.8 kHz.
    TruthModel(SimulateCommon),
    /// A seeded lightly damped structure with real normal modes (docs/src/design.md §3).
    Modal(ModalArgs),
    /// The thesis's FRF test (§4.5) in the time domain: a structure, reaction-mass
    /// actuators with Coulomb friction and end stops, the 200 Hz compensator, random
    /// excitation and the H1 analyzer.
    Experiment(Box<ExperimentArgs>),
    /// A shaker test in the time domain with exact truth: a seeded modal structure
    /// driven by shakers (white, band-limited or burst random, sine sweeps, impacts),
    /// its responses sampled with sensor noise. Writes a time-history CSV that
    /// `era frf` and `era identify --from-time` read, and the truth as JSON beside it.
    Shaker(Box<ShakerArgs>),
    /// A fleet of output-only records of one monitored structure, one every interval:
    /// its frequencies drift with temperature, drop after a chosen damage, and some
    /// records miss channels. Writes the records, a manifest for `era batch` and the
    /// truth.
    Fleet(Box<FleetArgs>),
}

/// `era simulate shaker`.
#[derive(Debug, Args)]
pub struct ShakerArgs {
    /// Outputs (accelerometers).
    #[arg(long, default_value_t = 8)]
    pub outputs: usize,
    /// Inputs (shakers).
    #[arg(long, default_value_t = 2)]
    pub inputs: usize,
    /// Number of modes.
    #[arg(long, default_value_t = 10)]
    pub modes: usize,
    /// Lowest natural frequency, Hz.
    #[arg(long, default_value_t = 1.9, allow_negative_numbers = true)]
    pub fmin: f64,
    /// Highest natural frequency, Hz.
    #[arg(long, default_value_t = 20.0, allow_negative_numbers = true)]
    pub fmax: f64,
    /// Damping ratio range MIN..MAX, fractions (0.005..0.02 = 0.5 to 2 %).
    #[arg(long, default_value_t = default_damping())]
    pub damping: String,
    /// Sample rate, Hz.
    #[arg(long, default_value_t = 64.0, allow_negative_numbers = true)]
    pub sample_rate: f64,
    /// Record length, s.
    #[arg(long, default_value_t = 300.0, allow_negative_numbers = true)]
    pub duration: f64,
    /// The shakers' signal: white, band-limited (--band), burst (--period, --burst-on),
    /// sweep (--band), impact (--period, --pulse-width).
    #[arg(long, value_enum, default_value_t = ExcitationArg::White)]
    pub excitation: ExcitationArg,
    /// Band of band-limited noise or of a sweep, LO..HI Hz (default: 0..Nyquist for
    /// noise, fmin/2..1.2 fmax for a sweep).
    #[arg(long, value_name = "LO..HI")]
    pub band: Option<String>,
    /// Period of bursts or impacts, s.
    #[arg(long, default_value_t = 8.0, allow_negative_numbers = true)]
    pub period: f64,
    /// Fraction of each burst period with noise on.
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    pub burst_on: f64,
    /// Duration of one impact, s.
    #[arg(long, default_value_t = 0.02, allow_negative_numbers = true)]
    pub pulse_width: f64,
    /// What the outputs measure.
    #[arg(long, value_parser = named::<era::Quantity>(), default_value_t = era::Quantity::default())]
    pub quantity: era::Quantity,
    /// Time-history CSV to write (time_s, force1.., acc1..); the truth goes to
    /// <name>.truth.json beside it.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Sensor noise RMS as a fraction of each channel's RMS (0.02 = 2 %).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub noise: f64,
    /// Seed of the structure, the excitation and the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub common: CommonArgs,
}

/// The shakers' signal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ExcitationArg {
    /// Gaussian white noise.
    White,
    /// Gaussian noise in --band.
    BandLimited,
    /// White noise on for --burst-on of every --period.
    Burst,
    /// A linear sine sweep over --band, one shaker at a time.
    Sweep,
    /// Half-sine impacts every --period, one input at a time.
    Impact,
}

#[derive(Debug, Args)]
pub struct ModalArgs {
    /// Outputs (sensors).
    #[arg(long, default_value_t = ModalSpec::default().outputs)]
    pub outputs: usize,
    /// Inputs (actuators).
    #[arg(long, default_value_t = ModalSpec::default().inputs)]
    pub inputs: usize,
    /// Number of modes.
    #[arg(long, default_value_t = ModalSpec::default().modes)]
    pub modes: usize,
    /// Lowest natural frequency, Hz.
    #[arg(long, default_value_t = ModalSpec::default().fmin_hz, allow_negative_numbers = true)]
    pub fmin: f64,
    /// Highest natural frequency, Hz.
    #[arg(long, default_value_t = ModalSpec::default().fmax_hz, allow_negative_numbers = true)]
    pub fmax: f64,
    /// Damping ratio range MIN..MAX, fractions (0.005..0.02 = 0.5 to 2 %).
    #[arg(long, default_value_t = default_damping())]
    pub damping: String,
    /// Number of lines, from 0 Hz.
    #[arg(long, default_value_t = 801)]
    pub lines: usize,
    /// Line spacing, Hz.
    #[arg(long, default_value_t = 0.025, allow_negative_numbers = true)]
    pub df: f64,
    /// What the FRFs measure per unit force.
    #[arg(long, value_parser = named::<era::Quantity>(), default_value_t = era::Quantity::default())]
    pub quantity: era::Quantity,
    /// Input shapes equal output shapes (square, reciprocal set like the DTA's).
    #[arg(long)]
    pub collocated: bool,
    #[command(flatten)]
    pub sim: SimulateCommon,
}

/// `era simulate fleet`.
#[derive(Debug, Args, Clone)]
pub struct FleetArgs {
    /// Output channels of the structure.
    #[arg(long, default_value_t = 8)]
    pub outputs: usize,
    /// Unmeasured random forces driving it (its ambient load).
    #[arg(long, default_value_t = 2)]
    pub forces: usize,
    /// Number of modes.
    #[arg(long, default_value_t = 6)]
    pub modes: usize,
    /// Lowest natural frequency, Hz.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub fmin: f64,
    /// Highest natural frequency, Hz.
    #[arg(long, default_value_t = 20.0, allow_negative_numbers = true)]
    pub fmax: f64,
    /// Damping ratio range MIN..MAX, fractions.
    #[arg(long, default_value = "0.005..0.02")]
    pub damping: String,
    /// Records in the fleet.
    #[arg(long, default_value_t = 12)]
    pub records: usize,
    /// Length of each record, s.
    #[arg(long, default_value_t = 600.0, allow_negative_numbers = true)]
    pub record_length: f64,
    /// Time from one record's start to the next's, s.
    #[arg(long, default_value_t = 3600.0, allow_negative_numbers = true)]
    pub interval: f64,
    /// Sample rate, Hz.
    #[arg(long, default_value_t = 64.0, allow_negative_numbers = true)]
    pub sample_rate: f64,
    /// Sensor noise RMS as a fraction of each channel's RMS.
    #[arg(long, default_value_t = 0.02, allow_negative_numbers = true)]
    pub noise: f64,
    /// Relative fall of every frequency over the fleet from a warming trend (0.02 = 2 %).
    #[arg(long, default_value_t = 0.02, allow_negative_numbers = true)]
    pub drift: f64,
    /// Amplitude of the daily temperature cycle, °C.
    #[arg(long, default_value_t = 3.0, allow_negative_numbers = true)]
    pub daily: f64,
    /// Damage: from record R (1-based) on, a stiffness loss LOSS (a fraction), R:LOSS.
    #[arg(long, value_name = "R:LOSS")]
    pub damage: Option<String>,
    /// Probability that a record lacks a given channel.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub missing: f64,
    /// Start of the first record, RFC 3339.
    #[arg(long, default_value = "2026-01-01T00:00:00Z")]
    pub start: String,
    /// Seed of the structure, the loads and the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Folder to write: records/NAME.csv, fleet.toml (a manifest for era batch) and
    /// truth.json (each record's exact modes and temperature).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    #[command(flatten)]
    pub common: CommonArgs,
}
