//! Flag groups that several verbs share: the output switches every verb has, how an FRF
//! file is read, how FRFs are estimated from time histories, how a refinement fits, and
//! how figures draw the phase.

use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::{Args, ValueEnum};
use era::estimate::{Detrend, Estimator, Window};
use era::params::names::{Named, UnknownName};
use era::refine::{Residuals, Weighting};
use era::Quantity;
use std::str::FromStr;

/// The parser of a core enum's words: clap offers the core's names
/// ([`era::params::names::Named`]) and reads them with the core's `FromStr`, so the CLI and
/// Python spell every value alike.
pub fn named<T>() -> impl TypedValueParser<Value = T>
where
    T: Named + FromStr<Err = UnknownName> + Clone + Send + Sync + 'static,
{
    PossibleValuesParser::new(T::NAMES).try_map(|word| word.parse::<T>())
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

/// Which pairs get an overlay of their own (identify, refine, plot).
#[derive(Debug, Args, Clone)]
pub struct PairsArgs {
    /// Pairs drawn one by one (pairs/ and the report): all, collocated, or
    /// OUTPUT:INPUT pairs counted from 1, comma-separated (e.g. 1:1,2:3). The grid
    /// always shows every pair.
    #[arg(long, value_name = "LIST", default_value = "all", value_parser = parse_pairs)]
    pub pairs: era_plot::PairSelection,
}

/// Parses `--pairs`.
fn parse_pairs(text: &str) -> Result<era_plot::PairSelection, String> {
    text.parse()
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
    #[arg(long, value_parser = named::<Quantity>())]
    pub quantity: Option<Quantity>,
    /// Outputs (sensors) of a MAT file's FRF matrix, when the file does not say and the
    /// set is not square.
    #[arg(long, value_name = "N")]
    pub outputs: Option<usize>,
    #[command(flatten)]
    pub facts: FrfFactsArgs,
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

/// How FRFs are estimated from time histories (era frf, era identify --from-time).
#[derive(Debug, Args, Clone)]
pub struct WelchArgs {
    /// Samples per frame (FFT length): lines are frame/2 + 1, spaced fs/frame. Default
    /// 2048; with --markov okid, where these FRFs only judge and refine the model, the
    /// largest power of two up to 2048 that gives at least 8 averages.
    #[arg(long, value_name = "N")]
    pub frame: Option<usize>,
    /// Window of each frame.
    #[arg(long, value_parser = named::<Window>(), default_value_t = Window::default())]
    pub window: Window,
    /// Overlap of consecutive frames, as a fraction of the frame (0 ≤ overlap < 1).
    #[arg(long, default_value_t = era::estimate::WelchOptions::DEFAULT_OVERLAP, allow_negative_numbers = true)]
    pub overlap: f64,
    /// FRF estimator: h1 (noise on the outputs), h2 (noise on the inputs), hv (total
    /// least squares).
    #[arg(long, value_parser = named::<Estimator>(), default_value_t = Estimator::default())]
    pub estimator: Estimator,
    /// Trend removed from each frame before windowing.
    #[arg(long, value_parser = named::<Detrend>(), default_value_t = Detrend::default())]
    pub detrend: Detrend,
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

/// How a refinement fits (docs/src/refinement.md).
#[derive(Debug, Args, Clone)]
pub struct RefineFitArgs {
    /// Residual terms of the refined model: none (modes only), lower (L/(jω)² in
    /// displacement: modes below the band), upper (a constant in the data's quantity:
    /// modes above the band, or D) or both (the default).
    #[arg(long, value_parser = named::<Residuals>(), value_name = "none|lower|upper|both")]
    pub residuals: Option<Residuals>,
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
    /// Weights of the refinement's cost: uniform (every pair and line alike), pair-noise
    /// (the default: each pair by the inverse of its noise variance, estimated from a
    /// first uniform fit's residual), or coherence (with --from-time: each line by the
    /// estimate's multiple coherence; the default when --markov okid refines).
    #[arg(long, value_parser = parse_weighting, value_name = "uniform|pair-noise|coherence")]
    pub weighting: Option<WeightingArg>,
}

/// `--weighting`: one of the core's named weightings, or the estimate's coherence (its
/// values come with the data).
#[derive(Debug, Clone, PartialEq)]
pub enum WeightingArg {
    /// `uniform` or `pair-noise`.
    Named(Weighting),
    /// `coherence`.
    Coherence,
}

fn parse_weighting(text: &str) -> Result<WeightingArg, String> {
    if text.trim().eq_ignore_ascii_case("coherence") {
        return Ok(WeightingArg::Coherence);
    }
    text.parse::<Weighting>()
        .map(WeightingArg::Named)
        .map_err(|e| {
            let names: Vec<String> = e.expected.iter().map(|n| format!("'{n}'")).collect();
            format!("'{text}': expected {} or 'coherence'", names.join(", "))
        })
}

/// How the figures draw the phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub enum PhaseArg {
    // −180° … 180°: each line's own phase, nothing inferred (the default).
    #[default]
    Wrapped,
    // Unwrapped where unambiguous: the model's phase, the measurement on its branch.
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
