//! `era friction estimate | simulate | tune`.

use super::common::CommonArgs;
use clap::{Args, Subcommand, ValueEnum};
use era::friction::compensator::ChannelConfig;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct FrictionArgs {
    #[command(subcommand)]
    pub action: FrictionAction,
}

#[derive(Debug, Subcommand)]
pub enum FrictionAction {
    /// Friction force from free-decay records (Eq. 3.12), found automatically.
    Estimate(FrictionEstimateArgs),
    /// Write a simulated free-decay record.
    Simulate(FrictionSimulateArgs),
    /// The compensation coefficient at which the compensated free decay is neutral.
    Tune(FrictionTuneArgs),
}

#[derive(Debug, Args)]
pub struct FrictionEstimateArgs {
    /// Free-decay CSV files: time_s plus velocity (or displacement).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Net spring stiffness k, force per length (thesis: 1.0 lbf/in).
    #[arg(long, allow_negative_numbers = true)]
    pub stiffness: f64,
    #[command(flatten)]
    pub common: CommonArgs,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum DecayMethodArg {
    /// The exact piecewise solution (Coulomb only).
    Exact,
    /// The event-driven integrator (any damping).
    Integrate,
}

/// The actuator model flags.
#[derive(Debug, Args, Clone)]
pub struct OscillatorArgs {
    /// Net spring stiffness k, force per length (thesis: 1.0 lbf/in).
    #[arg(long, allow_negative_numbers = true)]
    pub stiffness: f64,
    /// Undamped natural frequency, Hz.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1.5)]
    pub natural_frequency_hz: f64,
    /// Viscous damping ratio (fraction), 0 for pure Coulomb friction.
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.0)]
    pub viscous_damping_ratio: f64,
    /// Release displacement (length).
    #[arg(long, allow_negative_numbers = true, default_value_t = 1.5)]
    pub x0: f64,
    /// Samples per second.
    #[arg(long, allow_negative_numbers = true, default_value_t = ChannelConfig::THESIS_RATE_HZ)]
    pub sample_rate: f64,
}

#[derive(Debug, Args)]
pub struct FrictionSimulateArgs {
    /// Coulomb friction force.
    #[arg(long, allow_negative_numbers = true)]
    pub coulomb_force: f64,
    #[command(flatten)]
    pub model: OscillatorArgs,
    /// Rest before the release, s.
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.5)]
    pub hold: f64,
    /// Recorded time after the release, s (default: until the mass sticks, plus 1 s).
    #[arg(long, allow_negative_numbers = true)]
    pub duration: Option<f64>,
    /// Sensor noise RMS as a fraction of the first velocity amplitude (and of x0).
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.0)]
    pub noise: f64,
    /// Noise seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Exact piecewise solution or integrator (integrator when viscous damping is set).
    #[arg(long, value_enum)]
    pub method: Option<DecayMethodArg>,
    /// Record CSV to write.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    #[command(flatten)]
    pub common: CommonArgs,
}

#[derive(Debug, Args)]
pub struct FrictionTuneArgs {
    /// Free-decay records to estimate the actuator from (otherwise give --coulomb-force).
    pub files: Vec<PathBuf>,
    /// Coulomb friction force of the model (when no record is given).
    #[arg(long, allow_negative_numbers = true)]
    pub coulomb_force: Option<f64>,
    #[command(flatten)]
    pub model: OscillatorArgs,
    /// Compensator dead zone, velocity (thesis: 0.2 in/s).
    #[arg(long, allow_negative_numbers = true, default_value_t = ChannelConfig::THESIS_DEAD_ZONE)]
    pub dead_zone: f64,
    /// Fraction of the coefficient applied in service (thesis: 0.85–0.9).
    #[arg(long, allow_negative_numbers = true, default_value_t = ChannelConfig::THESIS_FRACTION)]
    pub fraction: f64,
    /// Cycles simulated per bisection trial.
    #[arg(long, default_value_t = 6)]
    pub cycles: usize,
    #[command(flatten)]
    pub common: CommonArgs,
}
