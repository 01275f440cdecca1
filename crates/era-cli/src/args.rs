//! Command-line arguments (clap). Flags follow docs/design.md §1's table.

use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

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
    /// Identify a model from an FRF file (docs/design.md §1), or from time histories with
    /// --from-time. By default on the route measured data need (automatic order,
    /// refinement, continuous time); --preset thesis for plain ERA as the thesis runs it.
    Identify(Box<IdentifyArgs>),
    /// Estimate FRFs and coherence from input and output time histories (CSV, MAT v5 or
    /// HDF5): Welch-averaged spectra, H1, H2 or Hv.
    Frf(FrfArgs),
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
    Compare(Box<crate::compare::CompareArgs>),
    /// Refine a model identified earlier (model.json) against its FRF file: poles,
    /// residues and residual terms by maximum likelihood, with uncertainties.
    Refine(RefineArgs),
}

/// The residual terms of a refined model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ResidualsArg {
    /// Modes only.
    None,
    /// L/(jω)² in displacement: modes below the band.
    Lower,
    /// A constant in the data's quantity: modes above the band, or D.
    Upper,
    /// Both.
    Both,
}

impl From<ResidualsArg> for era::refine::Residuals {
    fn from(r: ResidualsArg) -> Self {
        match r {
            ResidualsArg::None => era::refine::Residuals::None,
            ResidualsArg::Lower => era::refine::Residuals::Lower,
            ResidualsArg::Upper => era::refine::Residuals::Upper,
            ResidualsArg::Both => era::refine::Residuals::Both,
        }
    }
}

/// How a refinement fits (docs: README "Refinement").
#[derive(Debug, Args, Clone)]
pub struct RefineFitArgs {
    /// Residual terms of the refined model (default both).
    #[arg(long, value_enum, value_name = "none|lower|upper|both")]
    pub residuals: Option<ResidualsArg>,
    /// Reciprocity: symmetric residues and residuals (square, collocated sets); with
    /// rank-one residues each is `ψψᵀ`.
    #[arg(long)]
    pub reciprocal: bool,
    /// Keep a free residue matrix per pole instead of a mode shape times a
    /// participation (rank one, the default): faster, but a pole may then stand in for
    /// several modes, and the model has up to 2·min(outputs, inputs) states per mode.
    #[arg(long)]
    pub free_residues: bool,
    /// Fit the start's modes only: do not look in the residual for modes the start
    /// missed (by default their poles are added and the fit repeated).
    #[arg(long)]
    pub no_added_modes: bool,
    /// Levenberg–Marquardt iterations of the refinement at most (default 100).
    #[arg(long, value_name = "N")]
    pub max_iterations: Option<usize>,
    /// Weights of the refinement's cost (default pair-noise).
    #[arg(long, value_enum, value_name = "uniform|pair-noise")]
    pub weighting: Option<WeightingArg>,
}

/// How the refinement weights the pairs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum WeightingArg {
    /// Every pair and line alike.
    Uniform,
    /// Each pair by the inverse of its noise variance, estimated from a first uniform
    /// fit's residual (maximum likelihood when the pairs' noise levels differ).
    PairNoise,
}

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
    #[arg(long, value_enum, default_value_t = QuantityArg::Acceleration)]
    pub quantity: QuantityArg,
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

/// How FRFs are estimated from time histories (era frf, era identify --from-time).
#[derive(Debug, Args, Clone)]
pub struct WelchArgs {
    /// Samples per frame (FFT length): lines are frame/2 + 1, spaced fs/frame.
    #[arg(long, default_value_t = 2048)]
    pub frame: usize,
    /// Window of each frame.
    #[arg(long, value_enum, default_value_t = WindowArg::Hann)]
    pub window: WindowArg,
    /// Overlap of consecutive frames, as a fraction of the frame (0 ≤ overlap < 1).
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    pub overlap: f64,
    /// FRF estimator: h1 (noise on the outputs), h2 (noise on the inputs), hv (total
    /// least squares).
    #[arg(long, value_enum, default_value_t = EstimatorArg::H1)]
    pub estimator: EstimatorArg,
    /// Trend removed from each frame before windowing.
    #[arg(long, value_enum, default_value_t = DetrendArg::Mean)]
    pub detrend: DetrendArg,
    /// Keep the lines up to this frequency (the analyzer's span). ERA then sees a
    /// Nyquist frequency of max-hz, as after decimation: use it when the modes lie far
    /// below fs/2.
    #[arg(long, value_name = "HZ", allow_negative_numbers = true)]
    pub max_hz: Option<f64>,
    /// Sample rate, Hz: needed for MAT files, and overrides what a CSV or HDF5 file
    /// says.
    #[arg(long, value_name = "HZ", allow_negative_numbers = true)]
    pub sample_rate: Option<f64>,
    /// MAT input: the matrix to read (repeat to place several side by side).
    #[arg(long, value_name = "NAME")]
    pub variable: Vec<String>,
    /// HDF5 input: a 2-D dataset (columns are channels), or 1-D datasets, one per
    /// channel (repeat the flag).
    #[arg(long, value_name = "PATH")]
    pub dataset: Vec<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum WindowArg {
    Rectangular,
    Hann,
    FlatTop,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum EstimatorArg {
    H1,
    H2,
    Hv,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum DetrendArg {
    None,
    Mean,
    Linear,
}

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
    /// Phase in the figures: wrapped (−180…180°, the default) or unwrapped (where the
    /// step between lines is unambiguous, the measurement on the model's branch).
    #[arg(long, value_enum, default_value_t = PhaseArg::Wrapped)]
    pub phase: PhaseArg,
    /// Folder for the figures (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    #[command(flatten)]
    pub common: CommonArgs,
}

/// Flags every verb has.
#[derive(Debug, Args, Clone)]
pub struct CommonArgs {
    /// Print machine-readable JSON on stdout (human text then goes to stderr).
    #[arg(long)]
    pub json: bool,
    /// Print the wall time of each stage (also in the JSON, under timings_s).
    #[arg(long)]
    pub timings: bool,
    /// Print nothing but errors (and the JSON with --json).
    #[arg(long, short)]
    pub quiet: bool,
}

#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Seed of the noise generator (MINSTD; the Octave peer's run_truth(seed) draws the
    /// same noise).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Noise RMS as a fraction of each FRF's RMS (0.15 = the thesis's 15 %).
    #[arg(long, default_value_t = 0.15, allow_negative_numbers = true)]
    pub noise: f64,
    /// Folder for the FRFs (CSV), both models and fits (model.json, fit.json).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub common: CommonArgs,
}

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

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum QuantityArg {
    Acceleration,
    Velocity,
    Displacement,
}

impl From<QuantityArg> for era::Quantity {
    fn from(q: QuantityArg) -> Self {
        match q {
            QuantityArg::Acceleration => era::Quantity::Acceleration,
            QuantityArg::Velocity => era::Quantity::Velocity,
            QuantityArg::Displacement => era::Quantity::Displacement,
        }
    }
}

/// What an FRF file may not say about itself, given on the command line (identify,
/// plot, convert, refine).
#[derive(Debug, Args)]
pub struct FrfFactsArgs {
    /// Units of the FRFs, RESPONSE,FORCE (e.g. m/s^2,N or in,lbf); overrides the file's.
    /// Plots, tables and the report show them; files written carry them.
    #[arg(long, value_name = "RESPONSE,FORCE", value_parser = parse_units)]
    pub units: Option<UnitsArg>,
    /// MAT files: the variable holding the frequencies in Hz, when not FreqV.
    #[arg(long, value_name = "NAME")]
    pub freq_variable: Option<String>,
}

/// How plot, convert and refine read an FRF file beyond its name (identify's
/// `--outputs` also takes time-history channels, so it has its own).
#[derive(Debug, Args)]
pub struct FrfReadArgs {
    /// Quantity of the FRFs; overrides the file's "# quantity:" line (acceleration is
    /// assumed when neither says).
    #[arg(long, value_enum)]
    pub quantity: Option<QuantityArg>,
    /// Outputs (sensors) of a MAT file's FRF matrix, when the file does not say and the
    /// set is not square.
    #[arg(long, value_name = "N")]
    pub outputs: Option<usize>,
    #[command(flatten)]
    pub facts: FrfFactsArgs,
}

impl FrfReadArgs {
    /// The flags as [`crate::input::read_frf_with`] takes them.
    pub fn flags(&self) -> crate::input::FrfFlags<'_> {
        crate::input::FrfFlags {
            quantity: self.quantity,
            outputs: self.outputs,
            units: self.facts.units.as_ref(),
            frequency_variable: self.facts.freq_variable.as_deref(),
        }
    }
}

/// `--units RESPONSE,FORCE`: the FRFs' units, e.g. `m/s^2,N` or `in,lbf`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnitsArg {
    /// The response's unit (`m/s^2`).
    pub response: String,
    /// The force's (reference's) unit (`N`).
    pub force: String,
}

/// The UFF units field is 20 characters; a longer unit would be cut when written.
const UNIT_CHARS: usize = 20;

/// Parses `RESPONSE,FORCE`. A comma, not a slash, separates them: units themselves
/// have slashes (`m/s^2/N` could be `m` per `s^2/N`).
pub fn parse_units(text: &str) -> Result<UnitsArg, String> {
    let expected = "expected RESPONSE,FORCE, e.g. m/s^2,N or m/s,N or in,lbf";
    let (response, force) = text
        .split_once(',')
        .ok_or_else(|| format!("no ',' in '{text}': {expected}"))?;
    let (response, force) = (response.trim(), force.trim());
    for (part, what) in [(response, "response"), (force, "force")] {
        if part.is_empty() {
            return Err(format!("the {what} unit is empty in '{text}': {expected}"));
        }
        if part.contains(',') || part.chars().any(char::is_control) {
            return Err(format!(
                "the {what} unit '{}' has a comma or a control character: {expected}",
                part.escape_default()
            ));
        }
        if part.chars().count() > UNIT_CHARS {
            return Err(format!(
                "the {what} unit '{part}' is longer than {UNIT_CHARS} characters (the UFF units field)"
            ));
        }
    }
    Ok(UnitsArg {
        response: response.to_string(),
        force: force.to_string(),
    })
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
    /// A seeded lightly damped structure with real normal modes (docs/design.md §3).
    Modal(ModalArgs),
    /// The thesis's FRF test (§4.5) in the time domain: a structure, reaction-mass
    /// actuators with Coulomb friction and end stops, the 200 Hz compensator, random
    /// excitation and the H1 analyzer.
    Experiment(Box<crate::experiment::ExperimentArgs>),
    /// A shaker test in the time domain with exact truth: a seeded modal structure
    /// driven by shakers (white, band-limited or burst random, sine sweeps, impacts),
    /// its responses sampled with sensor noise. Writes a time-history CSV that
    /// `era frf` and `era identify --from-time` read, and the truth as JSON beside it.
    Shaker(Box<ShakerArgs>),
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
    #[arg(long, default_value = "0.005..0.02")]
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
    #[arg(long, value_enum, default_value_t = QuantityArg::Acceleration)]
    pub quantity: QuantityArg,
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
    #[arg(long, default_value_t = 8)]
    pub outputs: usize,
    /// Inputs (actuators).
    #[arg(long, default_value_t = 8)]
    pub inputs: usize,
    /// Number of modes.
    #[arg(long, default_value_t = 40)]
    pub modes: usize,
    /// Lowest natural frequency, Hz.
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    pub fmin: f64,
    /// Highest natural frequency, Hz.
    #[arg(long, default_value_t = 14.0, allow_negative_numbers = true)]
    pub fmax: f64,
    /// Damping ratio range MIN..MAX, fractions (0.005..0.02 = 0.5 to 2 %).
    #[arg(long, default_value = "0.005..0.02")]
    pub damping: String,
    /// Number of lines, from 0 Hz.
    #[arg(long, default_value_t = 801)]
    pub lines: usize,
    /// Line spacing, Hz.
    #[arg(long, default_value_t = 0.025, allow_negative_numbers = true)]
    pub df: f64,
    /// What the FRFs measure per unit force.
    #[arg(long, value_enum, default_value_t = QuantityArg::Acceleration)]
    pub quantity: QuantityArg,
    /// Input shapes equal output shapes (square, reciprocal set like the DTA's).
    #[arg(long)]
    pub collocated: bool,
    #[command(flatten)]
    pub sim: SimulateCommon,
}

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
    #[arg(long, allow_negative_numbers = true, default_value_t = 200.0)]
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
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.2)]
    pub dead_zone: f64,
    /// Fraction of the coefficient applied in service (thesis: 0.85–0.9).
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.85)]
    pub fraction: f64,
    /// Cycles simulated per bisection trial.
    #[arg(long, default_value_t = 6)]
    pub cycles: usize,
    #[command(flatten)]
    pub common: CommonArgs,
}

/// How the figures draw the phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub enum PhaseArg {
    /// −180° … 180°: each line's own phase, nothing inferred (the default).
    #[default]
    Wrapped,
    /// Unwrapped where unambiguous: the model's phase, the measurement on its branch.
    Unwrapped,
}

impl From<PhaseArg> for era_plot::PhaseView {
    fn from(p: PhaseArg) -> Self {
        match p {
            PhaseArg::Wrapped => era_plot::PhaseView::Wrapped,
            PhaseArg::Unwrapped => era_plot::PhaseView::Unwrapped,
        }
    }
}
