//! `era identify FILE`.

use super::common::{named, CommonArgs, FrfFactsArgs, PhaseArg, RefineFitArgs, WelchArgs};
use clap::Args;
use era::identify::route::Preset;
use era::identify::{EraOptions, ModelDomain};
use era::pipeline::realize::{DirectTerm, SvdPath};
use era::sources::MarkovSource;
use era::Quantity;
use std::path::PathBuf;

/// `--states N` or `--states auto`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StatesArg {
    /// A fixed order.
    Fixed(usize),
    /// Choose the physical modes automatically.
    Auto,
}

/// `N` as `Some(N)`, `auto` as `None`; anything else is neither a number of `what` nor
/// `auto`.
fn count_or_auto(text: &str, what: &str) -> Result<Option<usize>, String> {
    if text.trim().eq_ignore_ascii_case("auto") {
        return Ok(None);
    }
    text.trim()
        .parse::<usize>()
        .map(Some)
        .map_err(|_| format!("'{text}' is neither a number of {what} nor 'auto'"))
}

pub fn parse_states(text: &str) -> Result<StatesArg, String> {
    Ok(count_or_auto(text, "states")?.map_or(StatesArg::Auto, StatesArg::Fixed))
}

/// `--observer-order N` or `--observer-order auto`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ObserverOrderArg {
    /// These many lags.
    Fixed(usize),
    /// Chosen by the information criterion.
    Auto,
}

fn parse_observer_order(text: &str) -> Result<ObserverOrderArg, String> {
    Ok(count_or_auto(text, "lags")?.map_or(ObserverOrderArg::Auto, ObserverOrderArg::Fixed))
}

/// What `era identify --help` shows before the flags.
const IDENTIFY_EXAMPLES: &str = "\
Examples:
  era identify frf.csv --out run
      measured FRFs: the automatic order, refined, with model.json, figures and
      run/report.html
  era identify frf.uff --states 40 --no-refine
      plain ERA at 40 states (20 modes)
  era identify rec.csv --from-time --inputs force --outputs 2-9 --out run
      time histories: the FRFs are estimated first (as era frf), then identified
  era identify rec.csv --from-time --inputs 1-2 --outputs 3-30 --markov okid
      time histories: the Markov parameters by OKID, the H1 FRFs for the fit
  era identify frf.csv --preset thesis --states 8 --hankel-factor 5
      the thesis's own ERA, number for number";

/// What `era identify --help` shows after the flags.
const IDENTIFY_THESIS_NAMES: &str = "\
The thesis's names (Woods 1994): --states ns, --hankel-factor lh, --integrations ni, \
--lowpass-hz Hzbreak, --lowpass-order ford, --zero-lines nz, --pad-to ndpts, \
--time-domain cord.";

#[derive(Debug, Args)]
#[command(before_help = IDENTIFY_EXAMPLES, after_help = IDENTIFY_THESIS_NAMES)]
pub struct IdentifyArgs {
    /// FRF file (CSV, UFF 58/58b or MAT v5, told apart by content), or time histories
    /// with --from-time.
    pub file: PathBuf,
    /// With --from-time, more records of the same test (same channels and sample rate):
    /// their spectra are averaged with the first's, and OKID fits one observer to all.
    #[arg(value_name = "MORE_RECORDS")]
    pub more: Vec<PathBuf>,
    /// Defaults for every choice not given: measured (automatic order, refinement,
    /// continuous time, D from the quantity, the band from the coherence, the Welch window
    /// corrected) or thesis (plain ERA as the thesis runs it: no refinement, discrete
    /// time, D = 0, every line, the FRFs as given). Explicit flags override either.
    #[arg(long, value_parser = named::<Preset>(), default_value_t = Preset::default(), help_heading = "Route")]
    pub preset: Preset,
    /// Model order in states (two per mode), or `auto` (the default): scan --orders,
    /// cluster the stable poles and keep the physical modes.
    #[arg(long, value_name = "N | auto", value_parser = parse_states, help_heading = "Route")]
    pub states: Option<StatesArg>,
    /// Markov samples in the Hankel matrix: states × this factor.
    #[arg(long, default_value_t = EraOptions::default().hankel_factor, help_heading = "ERA")]
    pub hankel_factor: usize,
    /// Integrations of the FRFs before ERA: 1 turns acceleration into velocity.
    #[arg(long, default_value_t = EraOptions::default().integrations, help_heading = "ERA")]
    pub integrations: usize,
    /// Zero-phase Butterworth low-pass on the impulse responses, cut-off in Hz (off when
    /// absent).
    #[arg(
        long,
        value_name = "HZ",
        allow_negative_numbers = true,
        help_heading = "ERA"
    )]
    pub lowpass_hz: Option<f64>,
    /// Order of that low-pass filter.
    #[arg(
        long,
        default_value_t = EraOptions::DEFAULT_LOWPASS_ORDER,
        requires = "lowpass_hz",
        help_heading = "ERA"
    )]
    pub lowpass_order: usize,
    /// Leading FRF lines set to zero.
    #[arg(long, default_value_t = EraOptions::default().zero_lines, help_heading = "ERA")]
    pub zero_lines: usize,
    /// Pad with zero lines to pad-to + 1 lines (0: no padding).
    #[arg(long, default_value_t = EraOptions::default().pad_to, help_heading = "ERA")]
    pub pad_to: usize,
    /// Model returned. Default: continuous when the measured preset refines, else
    /// discrete (ERA's own).
    #[arg(long, value_parser = named::<ModelDomain>(), help_heading = "ERA")]
    pub time_domain: Option<ModelDomain>,
    /// D of ERA's model: zero or markov0 (Y0, the time-zero Markov block); a refined
    /// model's D is its upper residual. Default: markov0 for accelerance after
    /// --integrations, zero otherwise and with --preset thesis.
    #[arg(long, value_parser = named::<DirectTerm>(), help_heading = "ERA")]
    pub direct_term: Option<DirectTerm>,
    /// Realize by ERA/DC (ERA on the shifted correlations of the Hankel blocks) instead
    /// of ERA, at a fixed order or in the stabilization scan (dense SVDs only).
    #[arg(long, help_heading = "ERA")]
    pub era_dc: bool,
    /// How the Hankel SVD is computed: dense (H0 formed, every singular value),
    /// matrix-free (FFT products and a truncated SVD) or auto (dense while the Hankel's
    /// short side is below 1024).
    #[arg(long, value_parser = named::<SvdPath>(), default_value_t = SvdPath::default(), help_heading = "ERA")]
    pub svd: SvdPath,
    /// Quantity of the FRFs; overrides the file's "# quantity:" line (acceleration when
    /// neither says).
    #[arg(long, value_parser = named::<Quantity>(), help_heading = "Reading the file")]
    pub quantity: Option<Quantity>,
    /// Outputs of a MAT file's FRF matrix, when the file does not say and the set is not
    /// square; with --from-time, the output channels (as era frf --outputs).
    #[arg(long, value_name = "N | CHANNELS", help_heading = "Reading the file")]
    pub outputs: Option<String>,
    #[command(flatten, next_help_heading = "Reading the file")]
    pub facts: FrfFactsArgs,
    #[command(flatten)]
    pub geometry: super::GeometryArgs,
    /// Orders of the stabilization diagram, MIN..MAX[:STEP] (step 2) or a list such as
    /// 50,70,80, all from one SVD. Default with --states auto: a range the data support.
    #[arg(long, value_name = "MIN..MAX[:STEP]", help_heading = "Route")]
    pub orders: Option<String>,
    /// The band the test excited, LO..HI Hz: modes outside it are not physical, and the
    /// refinement fits its lines only. Default: where the coherence is at least 0.5
    /// (every line without coherence, with --preset thesis, or with --band all).
    #[arg(long, value_name = "LO..HI | all", help_heading = "Route")]
    pub band: Option<String>,
    /// FILE holds time histories: estimate the FRFs first (as era frf), then identify.
    #[arg(
        long,
        requires = "inputs",
        help_heading = "Time histories (--from-time)"
    )]
    pub from_time: bool,
    /// The input channels of the time file.
    #[arg(
        long,
        value_name = "CHANNELS",
        requires = "from_time",
        help_heading = "Time histories (--from-time)"
    )]
    pub inputs: Option<String>,
    /// Do not check the physical modes against a second estimate with frames twice (or
    /// half) as long; by default a mode not found again there is not physical.
    #[arg(
        long,
        requires = "from_time",
        help_heading = "Time histories (--from-time)"
    )]
    pub no_frame_check: bool,
    /// Where the Markov parameters come from: frf (the Welch H1 FRFs, inverse
    /// transformed) or okid (a least-squares observer fitted to the records themselves:
    /// no window, no leakage). The H1 FRFs are estimated either way: the fit, the
    /// figures and the refinement use them.
    #[arg(
        long,
        value_parser = named::<MarkovSource>(),
        default_value_t = MarkovSource::default(),
        requires = "from_time",
        help_heading = "Time histories (--from-time)"
    )]
    pub markov: MarkovSource,
    /// OKID's observer order (lags of past inputs and outputs), or auto (the default):
    /// the order below a cap that minimises the Bayesian information criterion.
    #[arg(
        long,
        value_name = "N | auto",
        value_parser = parse_observer_order,
        help_heading = "Time histories (--from-time)"
    )]
    pub observer_order: Option<ObserverOrderArg>,
    /// Markov blocks OKID returns (default 2048, the FRF route's default frame).
    #[arg(long, value_name = "N", help_heading = "Time histories (--from-time)")]
    pub markov_samples: Option<usize>,
    #[command(flatten, next_help_heading = "Time histories (--from-time)")]
    pub welch: WelchArgs,
    /// Also write the estimated FRFs (.csv, .uff or .mat).
    #[arg(
        long,
        value_name = "FILE",
        requires = "from_time",
        help_heading = "Time histories (--from-time)"
    )]
    pub save_frf: Option<PathBuf>,
    /// Refine the model against the FRFs (the default, but for --preset thesis): poles,
    /// residues and residual terms by maximum likelihood over the band, with standard
    /// deviations.
    #[arg(long, conflicts_with = "no_refine", help_heading = "Route")]
    pub refine: bool,
    /// Plain ERA: no refinement.
    #[arg(long, help_heading = "Route")]
    pub no_refine: bool,
    /// Keep a Welch estimate's tapered-window bias: by default (not with --preset thesis)
    /// its lag window is divided out when the file says which window and frame made it.
    #[arg(long, help_heading = "ERA")]
    pub no_window_correction: bool,
    #[command(flatten, next_help_heading = "Refinement")]
    pub refine_fit: RefineFitArgs,
    /// Phase in the figures: wrapped (−180…180°, each line's own) or unwrapped (where
    /// unambiguous: the model's phase, the measurement on its branch).
    #[arg(long, value_enum, default_value_t = PhaseArg::Wrapped, help_heading = "Output")]
    pub phase: PhaseArg,
    #[command(flatten, next_help_heading = "Output")]
    pub pairs: super::common::PairsArgs,
    /// Folder for model.json, fit.json, model.mat, modes.uff, the report and the
    /// figures (created if missing).
    #[arg(long, value_name = "DIR", help_heading = "Output")]
    pub out: Option<PathBuf>,
    /// The model files in --out but no figures and no report.html (an earlier run's stay
    /// as they were): for batch runs.
    #[arg(long, requires = "out", help_heading = "Output")]
    pub no_figures: bool,
    #[command(flatten, next_help_heading = "Output")]
    pub common: CommonArgs,
}
