//! `era identify FILE`.

use super::common::{CommonArgs, FrfFactsArgs, PhaseArg, QuantityArg, RefineFitArgs, WelchArgs};
use clap::{Args, ValueEnum};
use std::path::PathBuf;

/// Which defaults `era identify` starts from (era::identify::route).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PresetArg {
    /// The route for measured FRFs: automatic order, refinement, continuous time, D from
    /// the quantity, the band from the coherence, the Welch window corrected.
    Measured,
    /// Plain ERA as the thesis runs it: no refinement, discrete time, D = 0, every line,
    /// the FRFs as given.
    Thesis,
}

impl From<PresetArg> for era::identify::route::Preset {
    fn from(p: PresetArg) -> Self {
        match p {
            PresetArg::Measured => era::identify::route::Preset::Measured,
            PresetArg::Thesis => era::identify::route::Preset::Thesis,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TimeDomainArg {
    Discrete,
    Continuous,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum DirectTermArg {
    /// D = 0, as in the thesis.
    Zero,
    /// D = Y_0, the time-zero Markov block.
    Markov0,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SvdArg {
    /// Form H0 and take its thin SVD (all singular values).
    Dense,
    /// FFT products and a truncated SVD; H0 is never formed.
    MatrixFree,
    /// Dense while the Hankel's short side is below 1024, matrix-free beyond.
    Auto,
}

/// `--states N` or `--states auto`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StatesArg {
    /// A fixed order.
    Fixed(usize),
    /// Choose the physical modes automatically.
    Auto,
}

fn parse_states(text: &str) -> Result<StatesArg, String> {
    if text.trim().eq_ignore_ascii_case("auto") {
        return Ok(StatesArg::Auto);
    }
    text.trim()
        .parse::<usize>()
        .map(StatesArg::Fixed)
        .map_err(|_| format!("'{text}' is neither a number of states nor 'auto'"))
}

#[derive(Debug, Args)]
pub struct IdentifyArgs {
    /// FRF file: CSV (docs/design.md §4), UFF 58/58b, or MAT v5 (FRF + FreqV, xferIJ +
    /// FreqV, or a q × p × lines array + FreqV), told apart by content.
    pub file: PathBuf,
    /// The defaults of every choice below that is not given: `measured` (the default)
    /// is the route measured FRFs need; `thesis` is plain ERA with the thesis's settings
    /// (no refinement, discrete time, D = 0, every line). Explicit flags override either.
    /// Scripts that pass the thesis's flags and want the thesis's numbers add
    /// --preset thesis.
    #[arg(long, value_enum, default_value_t = PresetArg::Measured)]
    pub preset: PresetArg,
    /// Model order: first-order states (thesis ns), two per mode; or `auto` (the
    /// default): scan the orders of --orders, cluster the stable poles and keep the
    /// physical modes (docs/design.md §10).
    #[arg(long, value_name = "N | auto", value_parser = parse_states)]
    pub states: Option<StatesArg>,
    /// M = states × hankel-factor Markov samples go into the Hankel matrix (thesis lh).
    #[arg(long, default_value_t = 5)]
    pub hankel_factor: usize,
    /// Integrations applied to the FRFs (thesis ni): 1 turns acceleration into velocity.
    #[arg(long, default_value_t = 0)]
    pub integrations: usize,
    /// Zero-phase Butterworth low-pass on the impulse responses, cut-off in Hz (thesis
    /// Hzbreak); off when absent.
    #[arg(long, value_name = "HZ", allow_negative_numbers = true)]
    pub lowpass_hz: Option<f64>,
    /// Order of that filter (thesis ford).
    #[arg(long, default_value_t = 4, requires = "lowpass_hz")]
    pub lowpass_order: usize,
    /// Leading FRF lines set to zero (thesis nz).
    #[arg(long, default_value_t = 0)]
    pub zero_lines: usize,
    /// Pad with zero lines to pad-to + 1 lines; 0 = no padding (thesis ndpts).
    #[arg(long, default_value_t = 0)]
    pub pad_to: usize,
    /// Model returned (thesis cord). Default: continuous when the measured preset
    /// refines (measured FRFs are continuous-time data), else discrete, ERA's own.
    #[arg(long, value_enum)]
    pub time_domain: Option<TimeDomainArg>,
    /// The model's D matrix (of ERA's model; a refined model's D is its upper
    /// residual). Default: markov0 for accelerance after --integrations (it tends to a
    /// constant above its modes), zero for mobility and receptance, and zero with
    /// --preset thesis.
    #[arg(long, value_enum)]
    pub direct_term: Option<DirectTermArg>,
    /// How the Hankel SVD is computed.
    #[arg(long, value_enum, default_value_t = SvdArg::Auto)]
    pub svd: SvdArg,
    /// Quantity of the FRFs; overrides the file's "# quantity:" line (acceleration is
    /// assumed when neither says).
    #[arg(long, value_enum)]
    pub quantity: Option<QuantityArg>,
    /// Outputs (sensors) of a MAT file's FRF matrix, when the file does not say and the
    /// set is not square. With --from-time: the output channels of the time file (as
    /// era frf --outputs).
    #[arg(long, value_name = "N | CHANNELS")]
    pub outputs: Option<String>,
    #[command(flatten)]
    pub facts: FrfFactsArgs,
    /// Model orders of the stabilization diagram, MIN..MAX[:STEP] (step 2 by default)
    /// or a list such as 50,70,80; all are realized from one SVD. With --states N the
    /// modes of that model are judged against the scan; with --states auto the default
    /// is a range the data supports (docs/design.md §10).
    #[arg(long, value_name = "MIN..MAX[:STEP]")]
    pub orders: Option<String>,
    /// The band the test excited, LO..HI Hz (a sweep's range, a shaker's band): modes
    /// outside it are not physical, and the refinement fits only its lines (with
    /// residual terms for the modes outside). Default: where the coherence (estimated
    /// with --from-time, or read from NAME.coherence.csv beside the FRF file) is at
    /// least 0.5; every line when there is no coherence, with --preset thesis, or with
    /// --band all.
    #[arg(long, value_name = "LO..HI | all")]
    pub band: Option<String>,
    /// FILE holds time histories: estimate the FRFs first (as era frf), then identify.
    #[arg(long, requires = "inputs")]
    pub from_time: bool,
    /// With --from-time: the input channels of the time file.
    #[arg(long, value_name = "CHANNELS", requires = "from_time")]
    pub inputs: Option<String>,
    /// With --from-time and the automatic order refined (the default): do not check the
    /// physical modes against a second estimate through frames twice as long (half as
    /// long when the records are too short for that). By
    /// default a mode not found again there (leakage, a short frame's bias, one
    /// estimate's noise) is not physical.
    #[arg(long, requires = "from_time")]
    pub no_frame_check: bool,
    #[command(flatten)]
    pub welch: WelchArgs,
    /// With --from-time: also write the estimated FRFs (.csv, .uff or .mat).
    #[arg(long, value_name = "FILE", requires = "from_time")]
    pub save_frf: Option<PathBuf>,
    /// Refine the identified model against the FRFs (the default, but for
    /// --preset thesis): poles, residues and residual terms by maximum likelihood over
    /// the band, starting from the physical modes (--states auto) or every mode
    /// (--states N); model.json and every output then show the refined model, with
    /// standard deviations.
    #[arg(long, conflicts_with = "no_refine")]
    pub refine: bool,
    /// Plain ERA: no refinement.
    #[arg(long)]
    pub no_refine: bool,
    /// Leave the impulse responses of a Welch estimate with tapered (Hann, flat-top)
    /// frames as they are. By default (not with --preset thesis) the window's lag
    /// window, which biases damping and adds doublet poles beside each mode under
    /// random excitation, is divided out when the FRF file (or --from-time) says which
    /// window and frame made it.
    #[arg(long)]
    pub no_window_correction: bool,
    #[command(flatten)]
    pub refine_fit: RefineFitArgs,
    /// Phase in the figures: wrapped (−180…180°, the default) or unwrapped (where the
    /// step between lines is unambiguous, the measurement on the model's branch).
    #[arg(long, value_enum, default_value_t = PhaseArg::Wrapped)]
    pub phase: PhaseArg,
    /// Folder for model.json, fit.json, model.mat, modes.uff, the report and the
    /// figures (created if missing).
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
