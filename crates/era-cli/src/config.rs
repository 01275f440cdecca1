//! Flags to typed settings: every verb's output switches are one [`Settings`], and
//! every verb gets settings of its own that its command takes instead of the clap
//! structs: the small ones here ([`Demo`], [`Info`], [`Convert`], [`Plot`], [`Frf`],
//! [`Compare`], [`Refine`], [`Simulate`]), the others in a file per verb ([`identify`],
//! [`oma`], [`track`], [`batch`], [`friction`], [`experiment`], [`shaker`], [`fleet`]),
//! with what the data decides once it is read ([`identify::Plan`]). Values are checked
//! under the flags' names before anything is read; the core names option fields
//! (`era::params::Naming`) and this module adds the flag names, so other front ends
//! (Python) can word the same checks their own way.

pub mod batch;
pub mod compare;
pub mod experiment;
pub mod fleet;
pub mod friction;
pub mod identify;
pub mod oma;
pub mod shaker;
pub mod track;

pub use batch::Batch;
pub use experiment::Experiment;
pub use friction::{Friction, FrictionEstimate, FrictionSimulate, FrictionTune};
pub use identify::{apply_route, options, route_request, window_corrected, Identify};
pub use oma::Oma;
pub use shaker::{Excitation, Shaker};
pub use track::Track;

use crate::args::{
    CommonArgs, CompareArgs, ConvertArgs, DemoArgs, FrfArgs, InfoArgs, ModalArgs, PlotArgs,
    RefineArgs, RefineFitArgs, SimulateArgs, SimulateCommon, SimulateModel, WelchArgs,
};
use crate::input::FrfFlags;
use era::estimate::WelchOptions;
use era::refine::RefineOptions;
use std::path::PathBuf;

/// How much a verb says on the terminal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verbosity {
    /// Nothing but errors (and the JSON with `--json`).
    Quiet,
    /// The human summary.
    Normal,
}

/// What every verb's output switches say: how much to print, whether to draw progress
/// on stderr, whether JSON owns stdout, and whether to time the stages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Settings {
    /// Human text or none.
    pub verbosity: Verbosity,
    /// Spinners and bars on stderr (indicatif hides them when stderr is no terminal).
    pub progress: bool,
    /// JSON on stdout, human text on stderr.
    pub json: bool,
    /// The wall time of each stage.
    pub timings: bool,
}

impl Settings {
    /// Nothing printed, nothing drawn: for a run inside a run (the frame check).
    pub fn silent() -> Self {
        Settings {
            verbosity: Verbosity::Quiet,
            progress: false,
            json: false,
            timings: false,
        }
    }
}

impl From<&CommonArgs> for Settings {
    fn from(a: &CommonArgs) -> Self {
        Settings {
            verbosity: if a.quiet {
                Verbosity::Quiet
            } else {
                Verbosity::Normal
            },
            progress: !a.quiet,
            json: a.json,
            timings: a.timings,
        }
    }
}

/// `era demo`: the noise of the truth model's FRFs, its seed, and where to write.
#[derive(Debug, Clone)]
pub struct Demo {
    /// Seed of the noise generator.
    pub seed: u64,
    /// Noise RMS as a fraction of each FRF's RMS.
    pub noise: f64,
    /// Folder for the files, when asked for.
    pub out: Option<PathBuf>,
    /// The output switches.
    pub settings: Settings,
}

impl From<&DemoArgs> for Demo {
    fn from(a: &DemoArgs) -> Self {
        Demo {
            seed: a.seed,
            noise: a.noise,
            out: a.out.clone(),
            settings: Settings::from(&a.common),
        }
    }
}

/// `era info`: the file, and how to find a MAT file's frequencies.
#[derive(Debug, Clone)]
pub struct Info {
    /// The file.
    pub file: PathBuf,
    /// A MAT file's frequency variable, when not `FreqV`.
    pub freq_variable: Option<String>,
    /// The output switches.
    pub settings: Settings,
}

impl From<&InfoArgs> for Info {
    fn from(a: &InfoArgs) -> Self {
        Info {
            file: a.file.clone(),
            freq_variable: a.freq_variable.clone(),
            settings: Settings::from(&a.common),
        }
    }
}

/// `era convert`: the file read, how to read it, and the file written.
#[derive(Debug, Clone)]
pub struct Convert<'a> {
    /// FRF file to read.
    pub input: PathBuf,
    /// File to write (its extension picks the format).
    pub output: PathBuf,
    /// UFF output: binary 58b.
    pub binary: bool,
    /// UFF output: single precision.
    pub single: bool,
    /// How to read the input.
    pub read: FrfFlags<'a>,
    /// The output switches.
    pub settings: Settings,
}

impl<'a> From<&'a ConvertArgs> for Convert<'a> {
    fn from(a: &'a ConvertArgs) -> Self {
        Convert {
            input: a.input.clone(),
            output: a.output.clone(),
            binary: a.binary,
            single: a.single,
            read: FrfFlags::from(&a.read),
            settings: Settings::from(&a.common),
        }
    }
}

/// `era plot`: the FRF file, the model to overlay, and where the figures go.
#[derive(Debug, Clone)]
pub struct Plot<'a> {
    /// FRF file.
    pub file: PathBuf,
    /// model.json to overlay.
    pub model: Option<PathBuf>,
    /// Integrations before plotting (the model's, or 0, when `None`).
    pub integrations: Option<usize>,
    /// Leading lines left out (the model's, or 0, when `None`).
    pub zero_lines: Option<usize>,
    /// How to read the file.
    pub read: FrfFlags<'a>,
    /// How the phase is drawn.
    pub phase: era_plot::PhaseView,
    /// The pairs overlaid one by one (`--pairs`).
    pub pairs: era_plot::PairSelection,
    /// Folder for the figures.
    pub out: PathBuf,
    /// `--geometry`, when given: the model's modes drawn on it.
    pub geometry: Option<PathBuf>,
    /// The output switches.
    pub settings: Settings,
}

impl<'a> From<&'a PlotArgs> for Plot<'a> {
    fn from(a: &'a PlotArgs) -> Self {
        Plot {
            file: a.file.clone(),
            model: a.model.clone(),
            integrations: a.integrations,
            zero_lines: a.zero_lines,
            read: FrfFlags::from(&a.read),
            phase: a.phase.into(),
            pairs: a.pairs.pairs.clone(),
            out: a.out.clone(),
            geometry: a.geometry.geometry.clone(),
            settings: Settings::from(&a.common),
        }
    }
}

/// How FRFs are estimated from time histories (`era frf`, `era identify --from-time`).
#[derive(Debug, Clone)]
pub struct Welch {
    /// Samples per frame; `None` picks it from the record ([`DEFAULT_FRAME`], or the
    /// judging frame when OKID keeps the records).
    pub frame: Option<usize>,
    /// Window of each frame.
    pub window: era::estimate::Window,
    /// Overlap of consecutive frames, as a fraction of the frame.
    pub overlap: f64,
    /// The FRF estimator.
    pub estimator: era::estimate::Estimator,
    /// Trend removed from each frame.
    pub detrend: era::estimate::Detrend,
    /// Lines kept up to this frequency, Hz.
    pub max_hz: Option<f64>,
    /// Sample rate given, Hz (else the file's).
    pub sample_rate: Option<f64>,
    /// MAT input: the matrices to read.
    pub variable: Vec<String>,
    /// HDF5 input: the datasets to read.
    pub dataset: Vec<String>,
}

pub use era::estimate::{DEFAULT_FRAME, JUDGING_AVERAGES};

impl Welch {
    /// The frame given, or [`DEFAULT_FRAME`].
    pub fn frame_or_default(&self) -> usize {
        self.frame.unwrap_or(DEFAULT_FRAME)
    }
}

impl From<&WelchArgs> for Welch {
    fn from(a: &WelchArgs) -> Self {
        Welch {
            frame: a.frame,
            window: a.window,
            overlap: a.overlap,
            estimator: a.estimator,
            detrend: a.detrend,
            max_hz: a.max_hz,
            sample_rate: a.sample_rate,
            variable: a.variable.clone(),
            dataset: a.dataset.clone(),
        }
    }
}

/// `era frf`: the time files, their channels, the Welch settings and the file written.
#[derive(Debug, Clone)]
pub struct Frf<'a> {
    /// Time-history files (records of one test).
    pub files: Vec<PathBuf>,
    /// Input channels, as given.
    pub inputs: String,
    /// Output channels, as given.
    pub outputs: String,
    /// How the FRFs are estimated.
    pub welch: Welch,
    /// What the outputs measure.
    pub quantity: era::Quantity,
    /// Units written into the FRF file.
    pub units: Option<&'a crate::args::UnitsArg>,
    /// FRF file to write.
    pub out: PathBuf,
    /// UFF output: binary 58b.
    pub binary: bool,
    /// The output switches.
    pub settings: Settings,
}

impl<'a> From<&'a FrfArgs> for Frf<'a> {
    fn from(a: &'a FrfArgs) -> Self {
        Frf {
            files: a.files.clone(),
            inputs: a.inputs.clone(),
            outputs: a.outputs.clone(),
            welch: Welch::from(&a.welch),
            quantity: a.quantity,
            units: a.units.as_ref(),
            out: a.out.clone(),
            binary: a.binary,
            settings: Settings::from(&a.common),
        }
    }
}

/// `era compare`: the two FRF sets, their models (given, or identified with `era
/// identify`'s flags), the bands and where the files go.
#[derive(Debug, Clone)]
pub struct Compare {
    /// First FRF set.
    pub a: PathBuf,
    /// Second FRF set.
    pub b: PathBuf,
    /// Model of A.
    pub model_a: Option<PathBuf>,
    /// Model of B.
    pub model_b: Option<PathBuf>,
    /// Band edges, Hz.
    pub bands: Vec<f64>,
    /// Lowest and highest frequency of the fit error, Hz.
    pub fit_band: Vec<f64>,
    /// Folder for the files.
    pub out: Option<PathBuf>,
    /// `era identify` flags to identify both sets with ([`compare::compare_identify_options`]).
    pub identify: Option<Vec<String>>,
    /// The output switches.
    pub settings: Settings,
}

impl From<&CompareArgs> for Compare {
    fn from(a: &CompareArgs) -> Self {
        Compare {
            a: a.a.clone(),
            b: a.b.clone(),
            model_a: a.model_a.clone(),
            model_b: a.model_b.clone(),
            bands: a.bands.clone(),
            fit_band: a.fit_band.clone(),
            out: a.out.clone(),
            identify: a.identify.clone(),
            settings: Settings::from(&a.common),
        }
    }
}

/// What both FRF simulators write: the file, its noise and the seed.
#[derive(Debug, Clone)]
pub struct SimOutput {
    /// FRF file to write.
    pub out: PathBuf,
    /// Noise RMS as a fraction of each FRF's RMS.
    pub noise: f64,
    /// Seed of the noise (and of the modal structure).
    pub seed: u64,
    /// The output switches.
    pub settings: Settings,
}

impl From<&SimulateCommon> for SimOutput {
    fn from(a: &SimulateCommon) -> Self {
        SimOutput {
            out: a.out.clone(),
            noise: a.noise,
            seed: a.seed,
            settings: Settings::from(&a.common),
        }
    }
}

/// `era simulate modal`: the seeded structure, its lines and the file written.
#[derive(Debug, Clone)]
pub struct Modal {
    /// Outputs (sensors).
    pub outputs: usize,
    /// Inputs (actuators).
    pub inputs: usize,
    /// Number of modes.
    pub modes: usize,
    /// Lowest natural frequency, Hz.
    pub fmin: f64,
    /// Highest natural frequency, Hz.
    pub fmax: f64,
    /// Damping ratio range `MIN..MAX`, as given.
    pub damping: String,
    /// Number of lines, from 0 Hz.
    pub lines: usize,
    /// Line spacing, Hz.
    pub df: f64,
    /// What the FRFs measure per unit force.
    pub quantity: era::Quantity,
    /// Input shapes equal output shapes.
    pub collocated: bool,
    /// The file, its noise and the seed.
    pub sim: SimOutput,
}

impl From<&ModalArgs> for Modal {
    fn from(a: &ModalArgs) -> Self {
        Modal {
            outputs: a.outputs,
            inputs: a.inputs,
            modes: a.modes,
            fmin: a.fmin,
            fmax: a.fmax,
            damping: a.damping.clone(),
            lines: a.lines,
            df: a.df,
            quantity: a.quantity,
            collocated: a.collocated,
            sim: SimOutput::from(&a.sim),
        }
    }
}

impl Modal {
    /// The structure the flags describe: the noise and the damping range checked, and
    /// the sizes against their limits under the flags' names, before anything is
    /// allocated.
    pub fn spec(&self) -> anyhow::Result<era::sim::ModalSpec> {
        check_noise(self.sim.noise)?;
        let (damping_min, damping_max) = parse_range(&self.damping)?;
        let request = era::sim::ModalRequest::new(
            era::sim::ModalSpec {
                outputs: self.outputs,
                inputs: self.inputs,
                modes: self.modes,
                fmin_hz: self.fmin,
                fmax_hz: self.fmax,
                damping_min,
                damping_max,
                collocated: self.collocated,
                seed: self.sim.seed,
            },
            self.lines,
            self.df,
        );
        request.check(era::params::Naming::Flag)?;
        Ok(request.spec)
    }
}

/// `era simulate truth-model|modal|experiment|shaker`.
#[derive(Debug, Clone)]
pub enum Simulate {
    /// The thesis's truth model's FRFs.
    TruthModel(SimOutput),
    /// A seeded modal structure's FRFs.
    Modal(Modal),
    /// The thesis's FRF test in the time domain.
    Experiment(Box<Experiment>),
    /// A shaker test in the time domain.
    Shaker(Box<Shaker>),
    /// A fleet of output-only records (its flags are taken as they are; the command
    /// checks them as it builds the core's spec).
    Fleet(Box<crate::args::FleetArgs>),
}

impl From<&SimulateArgs> for Simulate {
    fn from(a: &SimulateArgs) -> Self {
        match &a.model {
            SimulateModel::TruthModel(s) => Simulate::TruthModel(SimOutput::from(s)),
            SimulateModel::Modal(m) => Simulate::Modal(Modal::from(m)),
            SimulateModel::Experiment(e) => {
                Simulate::Experiment(Box::new(Experiment::from(e.as_ref())))
            }
            SimulateModel::Shaker(s) => Simulate::Shaker(Box::new(Shaker::from(s.as_ref()))),
            SimulateModel::Fleet(f) => Simulate::Fleet(f.clone()),
        }
    }
}

/// `era refine`: the model, the FRF file it came from, how to refine and where the
/// files go.
#[derive(Debug, Clone)]
pub struct Refine<'a> {
    /// model.json of an earlier identification.
    pub model: PathBuf,
    /// The FRF file it was identified from.
    pub file: PathBuf,
    /// How to read the file.
    pub read: FrfFlags<'a>,
    /// How the refinement fits, checked ([`refine_options`]).
    pub options: RefineOptions,
    /// Folder for the files, when asked for.
    pub out: Option<PathBuf>,
    /// Model files but no figures and no report.
    pub no_figures: bool,
    /// The output switches.
    pub settings: Settings,
    /// `--geometry`, when given.
    pub geometry: Option<PathBuf>,
    /// The pairs overlaid one by one (`--pairs`).
    pub pairs: era_plot::PairSelection,
}

impl<'a> Refine<'a> {
    /// The settings of the flags, checked before anything is read.
    pub fn new(a: &'a RefineArgs) -> anyhow::Result<Self> {
        if a.fit.weighting == Some(crate::args::WeightingArg::Coherence) {
            return crate::error::usage(
                "--weighting coherence weights by an estimate's coherence, which era refine does not have: use it with era identify --from-time",
            );
        }
        Ok(Refine {
            model: a.model.clone(),
            file: a.file.clone(),
            read: FrfFlags::from(&a.read),
            options: refine_options(&a.fit)?,
            out: a.out.clone(),
            no_figures: a.no_figures,
            settings: Settings::from(&a.common),
            geometry: a.geometry.geometry.clone(),
            pairs: a.pairs.pairs.clone(),
        })
    }
}

/// `LO..HI` as two numbers, or `None`.
pub fn parse_band(text: &str) -> Option<(f64, f64)> {
    let (lo, hi) = text.split_once("..")?;
    Some((lo.trim().parse().ok()?, hi.trim().parse().ok()?))
}

/// The refinement options of the flags, checked before anything is read: at least one
/// iteration, and no more than [`era::params::limits::ITERATIONS`].
pub fn refine_options(fit: &RefineFitArgs) -> anyhow::Result<RefineOptions> {
    let mut o = RefineOptions::default();
    if let Some(r) = fit.residuals {
        o.residuals = r;
    }
    o.reciprocal = fit.reciprocal;
    o.rank_one = !fit.free_residues;
    o.add_missed = !fit.no_added_modes;
    // The coherence's values come with time histories: `identify` sets them.
    if let Some(crate::args::WeightingArg::Named(w)) = fit.weighting.clone() {
        o.weighting = w;
    }
    if let Some(n) = fit.max_iterations {
        if n == 0 {
            return crate::error::usage(
                "--max-iterations 0: the refinement needs at least one iteration",
            );
        }
        era::params::limits::ITERATIONS.check("--max-iterations", n as u64)?;
        o.max_iterations = n;
    }
    Ok(o)
}

/// Whether any refinement flag was given (they need `--refine` on `era identify`).
pub fn refine_given(fit: &RefineFitArgs) -> bool {
    fit.residuals.is_some()
        || fit.reciprocal
        || fit.free_residues
        || fit.no_added_modes
        || fit.max_iterations.is_some()
        || fit.weighting.is_some()
}

pub fn parse_range(text: &str) -> anyhow::Result<(f64, f64)> {
    let Some((lo, hi)) = text.split_once("..") else {
        return crate::error::usage(format!(
            "--damping {text}: expected MIN..MAX, e.g. 0.005..0.02"
        ));
    };
    match (lo.trim().parse::<f64>(), hi.trim().parse::<f64>()) {
        (Ok(lo), Ok(hi)) => Ok((lo, hi)),
        _ => crate::error::usage(format!("--damping {text}: MIN and MAX must be numbers")),
    }
}

/// The Welch settings of the flags at `rate` samples per second.
pub fn welch_options(welch: &Welch, rate: f64) -> WelchOptions {
    let mut o = WelchOptions::new(rate, welch.frame_or_default());
    o.overlap = welch.overlap;
    o.window = welch.window;
    o.detrend = welch.detrend;
    o
}

/// `--noise`, checked by the simulator's rule.
pub fn check_noise(noise: f64) -> anyhow::Result<()> {
    Ok(era::sim::check_noise(era::params::Naming::Flag, noise)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::args::IdentifyArgs;
    use clap::Parser;
    use era::identify::EraOptions;

    fn parsed(args: &[&str]) -> crate::args::Command {
        let argv = ["era"].iter().chain(args);
        crate::args::Cli::try_parse_from(argv).unwrap().command
    }

    fn identify_args(args: &[&str]) -> IdentifyArgs {
        let argv: Vec<&str> = ["identify", "frf.csv"]
            .iter()
            .chain(args)
            .copied()
            .collect();
        match parsed(&argv) {
            crate::args::Command::Identify(a) => *a,
            _ => unreachable!(),
        }
    }

    /// Every flag left out is the core's default: clap reads them from the core, and
    /// this fails when one is written out again and drifts.
    #[test]
    fn flags_left_out_are_the_cores_defaults() {
        let a = identify_args(&["--states", "8"]);
        let mut expected = EraOptions::default();
        expected.order = era::Order::Fixed(8);
        assert_eq!(options(&a).unwrap(), expected);
        assert_eq!(a.lowpass_order, EraOptions::DEFAULT_LOWPASS_ORDER);
        let a = identify_args(&["--states", "8", "--lowpass-hz", "100"]);
        assert_eq!(
            options(&a).unwrap().lowpass,
            Some((EraOptions::DEFAULT_LOWPASS_ORDER, 100.0))
        );
        assert_eq!(
            refine_options(&a.refine_fit).unwrap(),
            RefineOptions::default()
        );
        assert_eq!(a.preset, era::identify::route::Preset::default());
        assert_eq!(a.markov, era::sources::MarkovSource::default());
        assert_eq!(a.welch.estimator, era::estimate::Estimator::default());
        assert_eq!(
            welch_options(&Welch::from(&a.welch), 100.0),
            WelchOptions::new(100.0, era::estimate::DEFAULT_FRAME)
        );
        let crate::args::Command::Frf(f) = parsed(&[
            "frf",
            "rec.csv",
            "--inputs",
            "1",
            "--outputs",
            "2",
            "--out",
            "f.csv",
        ]) else {
            unreachable!()
        };
        assert_eq!(f.welch.estimator, era::estimate::Estimator::default());
        assert_eq!(
            welch_options(&Welch::from(&f.welch), 100.0),
            WelchOptions::new(100.0, era::estimate::DEFAULT_FRAME)
        );
        assert_eq!(f.quantity, era::Quantity::default());
    }

    /// The scenarios' flags left out are the core's settings where the core has them
    /// (the seeded structure, the thesis's test and compensator): this fails when a
    /// front end's default drifts from the core's.
    #[test]
    fn scenario_flags_left_out_are_the_cores() {
        use era::friction::compensator::ChannelConfig;
        use era::sim::experiment::{thesis_actuators, ExperimentSpec};
        let Simulate::Modal(m) = Simulate::from(&sim_args(&["modal", "--out", "m.csv"])) else {
            unreachable!()
        };
        let spec = era::sim::ModalSpec::default();
        assert_eq!(
            (m.outputs, m.inputs, m.modes, m.fmin, m.fmax),
            (
                spec.outputs,
                spec.inputs,
                spec.modes,
                spec.fmin_hz,
                spec.fmax_hz
            )
        );
        assert_eq!(
            parse_range(&m.damping).unwrap(),
            (spec.damping_min, spec.damping_max)
        );
        let Simulate::Shaker(s) = Simulate::from(&sim_args(&["shaker", "--out", "s.csv"])) else {
            unreachable!()
        };
        assert_eq!(
            parse_range(&s.damping).unwrap(),
            (spec.damping_min, spec.damping_max)
        );
        let Simulate::Experiment(e) = Simulate::from(&sim_args(&["experiment", "--out", "e.csv"]))
        else {
            unreachable!()
        };
        let thesis = ExperimentSpec::thesis(e.compensation, e.averages, e.seed);
        assert_eq!(e.accel_noise, thesis.accel_noise_rms);
        assert_eq!(e.lvt_noise, thesis.lvt_noise_rms);
        assert_eq!(e.actuators, thesis_actuators().len());
        let crate::args::Command::Friction(f) = parsed(&["friction", "tune", "--stiffness", "1"])
        else {
            unreachable!()
        };
        let Friction::Tune(t) = Friction::from(&f) else {
            unreachable!()
        };
        let channel = ChannelConfig::thesis(1.0);
        assert_eq!(
            (t.dead_zone, t.fraction),
            (channel.dead_zone, channel.fraction)
        );
        let compensator = era::sim::experiment::Compensation::thesis();
        assert_eq!(t.model.sample_rate, compensator.rate_hz);
    }

    /// `era oma`'s flags left out are the core's options (`OmaOptions::new`), and the
    /// order flags become the core's orders.
    #[test]
    fn oma_flags_left_out_are_the_cores_defaults() {
        let oma = |args: &[&str]| {
            let argv: Vec<&str> = ["oma", "rec.csv", "--outputs", "1-4"]
                .iter()
                .chain(args)
                .copied()
                .collect();
            match parsed(&argv) {
                crate::args::Command::Oma(a) => Oma::new(&a),
                _ => unreachable!(),
            }
        };
        let o = oma(&[]).unwrap();
        assert_eq!(o.options, era::identify::oma::OmaOptions::new(1.0));
        assert!(o.auto && o.references.is_none() && o.sample_rate.is_none());
        let o = oma(&["--states", "20"]).unwrap();
        assert_eq!(o.options.era.order, era::Order::Fixed(20));
        assert!(!o.auto);
        let o = oma(&["--states", "20", "--orders", "10..30"]).unwrap();
        assert_eq!(o.options.era.order, era::Order::Scan { states: 20 });
        for bad in [
            &["--blocks", "0"][..],
            &["--time-lags", "1"],
            &["--sample-rate", "0"],
            &["--states", "0"],
            &["--orders", "9..3"],
        ] {
            assert!(oma(bad).is_err(), "{bad:?}");
        }
    }

    fn sim_args(args: &[&str]) -> SimulateArgs {
        let argv: Vec<&str> = ["simulate"].iter().chain(args).copied().collect();
        match parsed(&argv) {
            crate::args::Command::Simulate(a) => a,
            _ => unreachable!(),
        }
    }
}
