//! `era simulate experiment`: the thesis's FRF test in the time domain.

use super::common::CommonArgs;
use clap::{Args, ValueEnum};
use era::sim::experiment::ExperimentSpec;
use std::path::PathBuf;

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum OnOff {
    On,
    Off,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum StructureQuantity {
    Velocity,
    Acceleration,
}

#[derive(Debug, Args)]
pub struct ExperimentArgs {
    /// Friction compensation in the actuators (thesis §4.4: 200 Hz, dead zone 0.2 in/s,
    /// 85 % of the coefficient).
    #[arg(long, value_enum, default_value_t = OnOff::Off)]
    pub compensation: OnOff,
    /// Frames of 2048 samples (40 s) averaged per excited actuator.
    #[arg(long, default_value_t = 20)]
    pub averages: usize,
    /// Seed of the excitation and the sensor noise (and of a --modes structure).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Multiplies every actuator's true Coulomb force (Table 5.1); 0 gives the linear
    /// system.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub friction_scale: f64,
    /// Compensator coefficients, lbf, one per actuator (e.g. from `era friction tune`);
    /// default: the adjusted coefficients of Table 5.1 times --friction-scale.
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    pub coefficients: Option<Vec<f64>>,
    /// Excitation RMS voltage, V; default 0.6 without compensation, 0.3 with (§4.5).
    #[arg(long, allow_negative_numbers = true)]
    pub excitation: Option<f64>,
    /// Drive every actuator at once with uncorrelated noise (one run), instead of one
    /// at a time.
    #[arg(long)]
    pub simultaneous: bool,
    /// Number of actuators, on structure inputs 1, 2, … (at most 8: Table 5.1 has 8).
    #[arg(long, default_value_t = era::sim::experiment::TABLE_5_1.len())]
    pub actuators: usize,
    /// Accelerometer noise RMS, in/s².
    #[arg(long, default_value_t = ExperimentSpec::THESIS_ACCEL_NOISE_RMS, allow_negative_numbers = true)]
    pub accel_noise: f64,
    /// LVT (relative velocity) noise RMS, in/s.
    #[arg(long, default_value_t = ExperimentSpec::THESIS_LVT_NOISE_RMS, allow_negative_numbers = true)]
    pub lvt_noise: f64,
    /// Structure: a model.json (square, outputs collocated with the inputs); default: the
    /// DTA-like modal structure (40 modes under 14 Hz and 4 up to 20 Hz).
    #[arg(long, value_name = "MODEL_JSON", conflicts_with_all = ["modes", "fmin", "fmax", "damping", "dofs"])]
    pub structure: Option<PathBuf>,
    /// What the --structure model's outputs measure.
    #[arg(long, value_enum, default_value_t = StructureQuantity::Velocity)]
    pub structure_quantity: StructureQuantity,
    /// A seeded modal structure (as `simulate modal`, collocated): number of modes.
    #[arg(long)]
    pub modes: Option<usize>,
    /// Its DOFs (inputs = outputs).
    #[arg(long)]
    pub dofs: Option<usize>,
    /// Its lowest natural frequency, Hz.
    #[arg(long, allow_negative_numbers = true)]
    pub fmin: Option<f64>,
    /// Its highest natural frequency, Hz.
    #[arg(long, allow_negative_numbers = true)]
    pub fmax: Option<f64>,
    /// Its damping ratio range MIN..MAX (fractions).
    #[arg(long)]
    pub damping: Option<String>,
    /// FRF file to write: .csv, .uff/.unv or .mat; the coherence goes beside it, to
    /// <name>.coherence.csv.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Also write the exact FRFs of the linear system (no friction) on the same lines.
    #[arg(long, value_name = "FILE")]
    pub exact_out: Option<PathBuf>,
    /// Write the analyzer's time histories, one CSV per run (time_s, voltages,
    /// accelerations, strokes, LVT velocities, compensation voltages), into DIR.
    #[arg(long, value_name = "DIR")]
    pub time_histories: Option<PathBuf>,
    #[command(flatten)]
    pub common: CommonArgs,
}
