//! Flags to typed settings: every verb's output switches are one [`Settings`], and
//! every verb gets settings of its own ([`Demo`], [`Identify`], [`Frf`], [`Simulate`],
//! [`Friction`], [`Plot`], [`Info`], [`Convert`], [`Compare`], [`Refine`]) that its
//! command takes instead of the clap structs. `identify`'s (and `compare`'s) arguments
//! become an [`EraOptions`] and an [`OrderRange`], checked under the flags' names before
//! anything is read. The core names option fields ([`Naming`]); this module adds the
//! flag names, so other front ends (Python) can word the same checks their own way.

pub mod batch;
pub mod compare;
pub mod experiment;
pub mod fleet;
pub mod friction;
pub mod identify;
pub mod shaker;

use crate::args::{
    CommonArgs, CompareArgs, ConvertArgs, DecayMethodArg, DemoArgs, ExcitationArg, ExperimentArgs,
    FrfArgs, FrictionAction, FrictionArgs, IdentifyArgs, InfoArgs, ModalArgs, OnOff,
    OscillatorArgs, PlotArgs, RefineArgs, RefineFitArgs, ShakerArgs, SimulateArgs, SimulateCommon,
    SimulateModel, StatesArg, StructureQuantity, WelchArgs,
};
use crate::input::FrfFlags;
use era::estimate::WelchOptions;
use era::identify::route::{Route, RouteRequest};
use era::identify::{EraOptions, ModelDomain};
use era::modal::stabilization::OrderRange;
use era::params::Naming;
use era::pipeline::realize::DirectTerm;
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

/// The actuator model of `era friction simulate|tune`.
#[derive(Debug, Clone, Copy)]
pub struct Actuator {
    /// Net spring stiffness, force per length.
    pub stiffness: f64,
    /// Undamped natural frequency, Hz.
    pub natural_frequency_hz: f64,
    /// Viscous damping ratio (fraction).
    pub viscous_damping_ratio: f64,
    /// Release displacement (length).
    pub x0: f64,
    /// Samples per second.
    pub sample_rate: f64,
}

impl From<&OscillatorArgs> for Actuator {
    fn from(a: &OscillatorArgs) -> Self {
        Actuator {
            stiffness: a.stiffness,
            natural_frequency_hz: a.natural_frequency_hz,
            viscous_damping_ratio: a.viscous_damping_ratio,
            x0: a.x0,
            sample_rate: a.sample_rate,
        }
    }
}

/// `era friction estimate`: the free-decay records and the spring's stiffness.
#[derive(Debug, Clone)]
pub struct FrictionEstimate {
    /// Free-decay records.
    pub files: Vec<PathBuf>,
    /// Net spring stiffness.
    pub stiffness: f64,
    /// The output switches.
    pub settings: Settings,
}

/// `era friction simulate`: the actuator, its release and the record written.
#[derive(Debug, Clone)]
pub struct FrictionSimulate {
    /// Coulomb friction force.
    pub coulomb_force: f64,
    /// The actuator.
    pub model: Actuator,
    /// Time held before the release, s.
    pub hold: f64,
    /// Recorded time after the release, s (until the mass sticks, plus 1 s, when `None`).
    pub duration: Option<f64>,
    /// Noise as a fraction of the record's RMS.
    pub noise: f64,
    /// Seed of the noise.
    pub seed: u64,
    /// How the record is made (by the damping, when `None`).
    pub method: Option<era::friction::simulate::Method>,
    /// Record to write.
    pub out: PathBuf,
    /// The output switches.
    pub settings: Settings,
}

/// `era friction tune`: the actuator, from records or from its friction force, and
/// the compensator's settings.
#[derive(Debug, Clone)]
pub struct FrictionTune {
    /// Free-decay records.
    pub files: Vec<PathBuf>,
    /// Coulomb friction force, instead of records.
    pub coulomb_force: Option<f64>,
    /// The actuator.
    pub model: Actuator,
    /// Dead zone of the compensator.
    pub dead_zone: f64,
    /// Fraction of the neutral coefficient applied.
    pub fraction: f64,
    /// Cycles simulated.
    pub cycles: usize,
    /// The output switches.
    pub settings: Settings,
}

/// `era friction estimate|simulate|tune`.
#[derive(Debug, Clone)]
pub enum Friction {
    /// Friction force from free-decay records.
    Estimate(FrictionEstimate),
    /// A simulated free-decay record.
    Simulate(FrictionSimulate),
    /// The compensation coefficient.
    Tune(FrictionTune),
}

impl From<&FrictionArgs> for Friction {
    fn from(a: &FrictionArgs) -> Self {
        use era::friction::simulate::Method;
        match &a.action {
            FrictionAction::Estimate(e) => Friction::Estimate(FrictionEstimate {
                files: e.files.clone(),
                stiffness: e.stiffness,
                settings: Settings::from(&e.common),
            }),
            FrictionAction::Simulate(s) => Friction::Simulate(FrictionSimulate {
                coulomb_force: s.coulomb_force,
                model: Actuator::from(&s.model),
                hold: s.hold,
                duration: s.duration,
                noise: s.noise,
                seed: s.seed,
                method: s.method.map(|m| match m {
                    DecayMethodArg::Exact => Method::Exact,
                    DecayMethodArg::Integrate => Method::Integrate,
                }),
                out: s.out.clone(),
                settings: Settings::from(&s.common),
            }),
            FrictionAction::Tune(t) => Friction::Tune(FrictionTune {
                files: t.files.clone(),
                coulomb_force: t.coulomb_force,
                model: Actuator::from(&t.model),
                dead_zone: t.dead_zone,
                fraction: t.fraction,
                cycles: t.cycles,
                settings: Settings::from(&t.common),
            }),
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
    /// `era identify` flags to identify both sets with ([`compare_identify_options`]).
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

/// The shakers' signal of `era simulate shaker`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Excitation {
    /// Gaussian white noise.
    White,
    /// Gaussian noise in the band.
    BandLimited,
    /// White noise on for part of every period.
    Burst,
    /// A linear sine sweep over the band.
    Sweep,
    /// Half-sine impacts every period.
    Impact,
}

/// `era simulate shaker`: the structure, the shakers' signal, the record and its noise.
#[derive(Debug, Clone)]
pub struct Shaker {
    /// Outputs (accelerometers).
    pub outputs: usize,
    /// Inputs (shakers).
    pub inputs: usize,
    /// Number of modes.
    pub modes: usize,
    /// Lowest natural frequency, Hz.
    pub fmin: f64,
    /// Highest natural frequency, Hz.
    pub fmax: f64,
    /// Damping ratio range `MIN..MAX`, as given.
    pub damping: String,
    /// Sample rate, Hz.
    pub sample_rate: f64,
    /// Record length, s.
    pub duration: f64,
    /// The shakers' signal.
    pub excitation: Excitation,
    /// Band `LO..HI` Hz, as given.
    pub band: Option<String>,
    /// Period of bursts or impacts, s.
    pub period: f64,
    /// Fraction of each burst period with noise on.
    pub burst_on: f64,
    /// Duration of one impact, s.
    pub pulse_width: f64,
    /// What the outputs measure.
    pub quantity: era::Quantity,
    /// Time-history CSV to write.
    pub out: PathBuf,
    /// Sensor noise RMS as a fraction of each channel's RMS.
    pub noise: f64,
    /// Seed of the structure, the excitation and the noise.
    pub seed: u64,
    /// The output switches.
    pub settings: Settings,
}

impl From<&ShakerArgs> for Shaker {
    fn from(a: &ShakerArgs) -> Self {
        Shaker {
            outputs: a.outputs,
            inputs: a.inputs,
            modes: a.modes,
            fmin: a.fmin,
            fmax: a.fmax,
            damping: a.damping.clone(),
            sample_rate: a.sample_rate,
            duration: a.duration,
            excitation: match a.excitation {
                ExcitationArg::White => Excitation::White,
                ExcitationArg::BandLimited => Excitation::BandLimited,
                ExcitationArg::Burst => Excitation::Burst,
                ExcitationArg::Sweep => Excitation::Sweep,
                ExcitationArg::Impact => Excitation::Impact,
            },
            band: a.band.clone(),
            period: a.period,
            burst_on: a.burst_on,
            pulse_width: a.pulse_width,
            quantity: a.quantity,
            out: a.out.clone(),
            noise: a.noise,
            seed: a.seed,
            settings: Settings::from(&a.common),
        }
    }
}

/// `era simulate experiment`: the thesis's FRF test in the time domain.
#[derive(Debug, Clone)]
pub struct Experiment {
    /// Friction compensation in the actuators.
    pub compensation: bool,
    /// Frames averaged per excited actuator.
    pub averages: usize,
    /// Seed of the excitation and the sensor noise.
    pub seed: u64,
    /// Multiplies every actuator's true Coulomb force.
    pub friction_scale: f64,
    /// Compensator coefficients, lbf, one per actuator.
    pub coefficients: Option<Vec<f64>>,
    /// Excitation RMS voltage, V (by the compensation, when `None`).
    pub excitation: Option<f64>,
    /// Every actuator at once.
    pub simultaneous: bool,
    /// Number of actuators.
    pub actuators: usize,
    /// Accelerometer noise RMS, in/s².
    pub accel_noise: f64,
    /// LVT noise RMS, in/s.
    pub lvt_noise: f64,
    /// Structure from a model.json.
    pub structure: Option<PathBuf>,
    /// What the structure model's outputs measure.
    pub structure_quantity: era::Quantity,
    /// A seeded modal structure: number of modes.
    pub modes: Option<usize>,
    /// Its DOFs.
    pub dofs: Option<usize>,
    /// Its lowest natural frequency, Hz.
    pub fmin: Option<f64>,
    /// Its highest natural frequency, Hz.
    pub fmax: Option<f64>,
    /// Its damping ratio range `MIN..MAX`, as given.
    pub damping: Option<String>,
    /// FRF file to write.
    pub out: PathBuf,
    /// File for the exact FRFs of the linear system.
    pub exact_out: Option<PathBuf>,
    /// Folder for the analyzer's time histories.
    pub time_histories: Option<PathBuf>,
    /// The output switches.
    pub settings: Settings,
}

impl From<&ExperimentArgs> for Experiment {
    fn from(a: &ExperimentArgs) -> Self {
        Experiment {
            compensation: a.compensation == OnOff::On,
            averages: a.averages,
            seed: a.seed,
            friction_scale: a.friction_scale,
            coefficients: a.coefficients.clone(),
            excitation: a.excitation,
            simultaneous: a.simultaneous,
            actuators: a.actuators,
            accel_noise: a.accel_noise,
            lvt_noise: a.lvt_noise,
            structure: a.structure.clone(),
            structure_quantity: match a.structure_quantity {
                StructureQuantity::Velocity => era::Quantity::Velocity,
                StructureQuantity::Acceleration => era::Quantity::Acceleration,
            },
            modes: a.modes,
            dofs: a.dofs,
            fmin: a.fmin,
            fmax: a.fmax,
            damping: a.damping.clone(),
            out: a.out.clone(),
            exact_out: a.exact_out.clone(),
            time_histories: a.time_histories.clone(),
            settings: Settings::from(&a.common),
        }
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

/// The refinement's weighting asked for by name: one of the core's (set in
/// [`Identify::refine`]), or the estimate's coherence, whose values come with the data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WeightingGiven {
    /// `uniform` or `pair-noise`.
    Named,
    /// `coherence`.
    Coherence,
}

/// `era identify`: the data and how to read or estimate it, ERA's options, the route
/// asked for, the refinement and where the files go; checked under the flags' names
/// before anything is read.
#[derive(Debug, Clone)]
pub struct Identify<'a> {
    /// The FRF file, or the first time-history file.
    pub file: PathBuf,
    /// More time-history files (records of one test).
    pub more: Vec<PathBuf>,
    /// ERA's options ([`options`]); the route's domain and direct term are set once the
    /// data is read ([`apply_route`]).
    pub options: EraOptions,
    /// The route asked for ([`route_request`]).
    pub request: RouteRequest,
    /// The refinement's options, checked ([`refine_options`]).
    pub refine: RefineOptions,
    /// The weighting asked for by name, when given.
    pub weighting: Option<WeightingGiven>,
    /// The scan's orders (`--orders`), when given.
    pub orders: Option<OrderRange>,
    /// What the FRFs (or the outputs) measure, when given.
    pub quantity: Option<era::Quantity>,
    /// `--outputs`: the FRF file's output count, or the time files' output channels.
    pub outputs: Option<String>,
    /// Input channels of the time files.
    pub inputs: Option<String>,
    /// Units of the FRFs, when given.
    pub units: Option<&'a crate::args::UnitsArg>,
    /// A MAT file's frequency variable, when not `FreqV`.
    pub freq_variable: Option<String>,
    /// `--band`, as given.
    pub band: Option<String>,
    /// The data are time histories.
    pub from_time: bool,
    /// No check of the model against a second frame.
    pub no_frame_check: bool,
    /// Where the Markov parameters come from.
    pub markov: era::sources::MarkovSource,
    /// OKID's observer order.
    pub observer_order: era::sources::okid::ObserverOrder,
    /// Markov blocks OKID returns, when given.
    pub markov_samples: Option<usize>,
    /// How FRFs are estimated from the time histories.
    pub welch: Welch,
    /// File for the estimated FRFs.
    pub save_frf: Option<PathBuf>,
    /// How the figures draw the phase.
    pub phase: era_plot::PhaseView,
    /// The pairs overlaid one by one (`--pairs`).
    pub pairs: era_plot::PairSelection,
    /// Folder for the files, when asked for.
    pub out: Option<PathBuf>,
    /// Model files but no figures and no report.
    pub no_figures: bool,
    /// The output switches.
    pub settings: Settings,
    /// `--geometry`, when given.
    pub geometry: Option<PathBuf>,
}

impl<'a> Identify<'a> {
    /// The time files: the first and any more records of the test.
    pub fn record_paths(&self) -> Vec<PathBuf> {
        std::iter::once(self.file.clone())
            .chain(self.more.iter().cloned())
            .collect()
    }

    /// The settings of the flags, checked in the order the flags' errors are reported.
    pub fn new(a: &'a IdentifyArgs) -> anyhow::Result<Self> {
        use crate::args::{ObserverOrderArg, WeightingArg};
        use era::sources::okid::ObserverOrder;
        let options = options(a)?;
        let orders = scan_orders(a)?;
        let request = route_request(a);
        let refine = identify_refine_options(a, &request)?;
        Ok(Identify {
            file: a.file.clone(),
            more: a.more.clone(),
            options,
            request,
            refine,
            weighting: a.refine_fit.weighting.as_ref().map(|w| match w {
                WeightingArg::Named(_) => WeightingGiven::Named,
                WeightingArg::Coherence => WeightingGiven::Coherence,
            }),
            orders,
            quantity: a.quantity,
            outputs: a.outputs.clone(),
            inputs: a.inputs.clone(),
            units: a.facts.units.as_ref(),
            freq_variable: a.facts.freq_variable.clone(),
            band: a.band.clone(),
            from_time: a.from_time,
            no_frame_check: a.no_frame_check,
            markov: a.markov,
            observer_order: match a.observer_order {
                Some(ObserverOrderArg::Fixed(p)) => ObserverOrder::Fixed(p),
                Some(ObserverOrderArg::Auto) | None => ObserverOrder::Auto { max: None },
            },
            markov_samples: a.markov_samples,
            welch: Welch::from(&a.welch),
            save_frf: a.save_frf.clone(),
            phase: a.phase.into(),
            pairs: a.pairs.pairs.clone(),
            out: a.out.clone(),
            no_figures: a.no_figures,
            settings: Settings::from(&a.common),
            geometry: a.geometry.geometry.clone(),
        })
    }
}

/// The refinement's options, refused when given while the route asked for does not
/// refine: whether it refines depends on the preset, not on the data's quantity, so it
/// is known before anything is read.
fn identify_refine_options(
    a: &IdentifyArgs,
    request: &RouteRequest,
) -> anyhow::Result<RefineOptions> {
    let refine = request.resolve(era::Quantity::Acceleration, 0).refine;
    if !refine && refine_given(&a.refine_fit) {
        return crate::error::usage(
            "--residuals, --reciprocal, --free-residues, --no-added-modes, --weighting and --max-iterations set the refinement, which is off (--no-refine, --preset thesis or --markov okid): add --refine",
        );
    }
    refine_options(&a.refine_fit)
}

/// The route the flags ask for: the preset, and every choice given explicitly
/// (era::identify::route resolves the rest once the data's quantity is known).
pub fn route_request(a: &IdentifyArgs) -> RouteRequest {
    let mut r = RouteRequest::new(a.preset);
    r.states = match a.states {
        Some(StatesArg::Fixed(n)) => Some(n),
        Some(StatesArg::Auto) | None => None,
    };
    r.refine = if a.refine {
        Some(true)
    } else if a.no_refine {
        Some(false)
    } else {
        None
    };
    r.domain = a.time_domain;
    r.direct_term = a.direct_term;
    match a.band.as_deref().map(str::trim) {
        Some(t) if t.eq_ignore_ascii_case("all") => r.coherence_band = Some(false),
        // Parsed and checked against the data by the identification; the route only
        // says it is given.
        Some(t) => r.band_hz = parse_band(t),
        None => {}
    }
    r.window_correction = a.no_window_correction.then_some(false);
    r.markov = a.markov;
    r
}

/// The flags of the time-history route that only some routes take, refused elsewhere
/// before anything is read.
fn check_time_flags(a: &IdentifyArgs) -> anyhow::Result<()> {
    use era::sources::MarkovSource;
    if !a.from_time && !a.more.is_empty() {
        return crate::error::usage(format!(
            "{}: identify takes one FRF file; several files are records of one test with --from-time",
            a.more[0].display()
        ));
    }
    let okid = a.markov == MarkovSource::Okid;
    if !okid {
        for (given, flag) in [
            (a.observer_order.is_some(), "--observer-order"),
            (a.markov_samples.is_some(), "--markov-samples"),
        ] {
            if given {
                return crate::error::usage(format!(
                    "{flag} sets OKID's observer, which runs with --markov okid only"
                ));
            }
        }
        return Ok(());
    }
    for (value, flag) in [
        (a.integrations, "--integrations"),
        (a.pad_to, "--pad-to"),
        (a.zero_lines, "--zero-lines"),
    ] {
        if value != 0 {
            return crate::error::usage(format!(
                "{flag} {value}: it shapes the FRFs' inverse transform, and with --markov okid the Markov parameters come from the observer: leave it out"
            ));
        }
    }
    if let Some(n) = a.markov_samples {
        if n < 2 {
            return crate::error::usage(format!(
                "--markov-samples {n}: OKID returns at least 2 Markov blocks (the direct term and one more)"
            ));
        }
        era::params::limits::SAMPLES.check("--markov-samples", n as u64)?;
    }
    Ok(())
}

/// `LO..HI` as two numbers, or `None`.
pub fn parse_band(text: &str) -> Option<(f64, f64)> {
    let (lo, hi) = text.split_once("..")?;
    Some((lo.trim().parse().ok()?, hi.trim().parse().ok()?))
}

/// The route's domain and direct term in `options` (the rest of the route is the
/// front end's: refinement, band, window correction).
pub fn apply_route(options: &mut EraOptions, route: &Route) {
    options.domain = route.domain;
    options.direct_term = route.direct_term;
}

/// The options ERA runs with on `route` ([`Route::realization_domain`]).
pub fn era_options(options: &EraOptions, route: &Route) -> EraOptions {
    let mut o = options.clone();
    o.domain = route.realization_domain();
    o
}

/// Options from flags, with the checks clap cannot do (those of the library call are
/// [`EraOptions::check`], shared with the Python package; `--orders` is the CLI's own).
/// The domain and direct term are those given, or the thesis's until
/// [`apply_route`] sets the route's.
pub fn options(a: &IdentifyArgs) -> anyhow::Result<EraOptions> {
    let auto = !matches!(a.states, Some(StatesArg::Fixed(_)));
    let states = match a.states {
        Some(StatesArg::Fixed(n)) => n,
        // The scan sets its own orders; this is only echoed.
        _ => 0,
    };
    let mut opts = EraOptions::new(states, a.hankel_factor);
    opts.integrations = a.integrations;
    opts.lowpass = a.lowpass_hz.map(|hz| (a.lowpass_order, hz));
    opts.zero_lines = a.zero_lines;
    opts.pad_to = a.pad_to;
    opts.domain = a.time_domain.unwrap_or(ModelDomain::Discrete);
    opts.direct_term = a.direct_term.unwrap_or(DirectTerm::Zero);
    opts.svd = a.svd;
    if a.era_dc {
        opts.realizer = era::identify::Realizer::EraDc;
    }
    check_time_flags(a)?;
    // Sizes are checked against their limits here, under the flag's name, before anything
    // is read or allocated (the core checks them again for library users). With
    // --states auto every other parameter is checked as for one state.
    let checked = {
        let mut o = opts.clone();
        o.order = era::Order::Fixed(states.max(usize::from(auto)));
        o
    };
    checked.check(Naming::Flag)?;
    use era::params::limits::SAMPLES;
    if let Some(range) = scan_orders(a)? {
        SAMPLES.check_product(
            format!("--orders {} x --hankel-factor (Markov samples)", range.max),
            &[range.max as u64, a.hankel_factor as u64],
        )?;
    }
    Ok(opts)
}

/// `--orders` parsed, naming the flag in errors.
pub fn scan_orders(a: &IdentifyArgs) -> anyhow::Result<Option<OrderRange>> {
    match &a.orders {
        None => Ok(None),
        Some(text) => OrderRange::parse(text).map(Some).map_err(|e| {
            crate::error::UsageError(format!("--orders {text}: {}", reason_of(&e))).into()
        }),
    }
}

fn reason_of(e: &era::EraError) -> String {
    match e {
        era::EraError::InvalidParameter { reason, .. } => reason.message(Naming::Flag),
        other => other.message(Naming::Flag),
    }
}

/// `frf` with the lag window of the Welch estimate it came from divided out (see
/// [`lag_window`]), and the reason to echo; `None` when `metadata` names no such
/// window. Leading lines that are zero in every pair (a padded late start) stay zero:
/// the correction works on the impulse responses and would spread values into them.
pub fn window_corrected(
    frf: &era::FrfData,
    metadata: &std::collections::BTreeMap<String, String>,
) -> anyhow::Result<Option<(era::FrfData, String)>> {
    let Some((lag, why)) = lag_window(metadata) else {
        return Ok(None);
    };
    Ok(Some((lag.correct_frf(frf)?, why)))
}

/// The lag window of the Welch estimate an FRF file came from, when its metadata (an
/// `era frf` CSV, or `--from-time`) names the H1 estimator, a tapered window, the frame
/// and the sample rate; `None` for a rectangular window (transients need no
/// correction), another estimator, or when the file does not say. The reason goes to
/// the echo.
pub fn lag_window(
    metadata: &std::collections::BTreeMap<String, String>,
) -> Option<(era::sources::frf::LagWindow, String)> {
    use era::estimate::{Estimator, Window};
    // The words `era frf` writes; a file that says anything else is not corrected.
    let estimator = match metadata.get("estimator")?.trim() {
        "h1" => Estimator::H1,
        _ => return None,
    };
    let window = match metadata.get("window")?.trim() {
        "hann" => Window::Hann,
        "flattop" | "flat-top" => Window::FlatTop,
        _ => return None,
    };
    let frame: usize = metadata.get("frame")?.trim().parse().ok()?;
    let rate: f64 = metadata.get("sample_rate_hz")?.trim().parse().ok()?;
    let lag = era::sources::frf::LagWindow::of_estimate(estimator, window, frame, rate).ok()??;
    Some((
        lag,
        format!(
            "the Welch estimate's {} lag window (frames of {frame} samples at {rate} Hz) divided out of the FRFs (their impulse responses)",
            window.name()
        ),
    ))
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

/// `era oma`: the time files, their output and reference channels, and the library's
/// [`era::identify::oma::OmaOptions`] but for the sample rate (read from the files).
#[derive(Debug, Clone)]
pub struct Oma {
    /// Time-history files (records of one test).
    pub files: Vec<PathBuf>,
    /// Output channels, as given.
    pub outputs: String,
    /// Reference channels, as given (`None`: every output).
    pub references: Option<String>,
    /// Sample rate given, Hz (else the files').
    pub sample_rate: Option<f64>,
    /// MAT variables and HDF5 datasets to read.
    pub selection: era_io::time::TimeSelection,
    /// The library's options; `sample_rate_hz` is set once the files are read, and
    /// `references` once the channels are known.
    pub options: era::identify::oma::OmaOptions,
    /// `--states auto` (or none given).
    pub auto: bool,
    /// The model files in `out` but no figures.
    pub no_figures: bool,
    /// Folder for the files, when asked for.
    pub out: Option<PathBuf>,
    /// `--geometry`, when given.
    pub geometry: Option<PathBuf>,
    /// The output switches.
    pub settings: Settings,
}

impl Oma {
    /// The settings of `era oma`'s flags, each checked under its flag's name before
    /// anything is read: a positive sample rate, lags and blocks within the core's
    /// bounds, the orders parsed.
    pub fn new(a: &crate::args::OmaArgs) -> anyhow::Result<Self> {
        use era::identify::oma::OmaOptions;
        use era::sources::correlation::{MAX_BLOCKS, MAX_LAGS};
        if let Some(r) = a.sample_rate {
            if !(r.is_finite() && r > 0.0) {
                return crate::error::usage(format!(
                    "--sample-rate {r}: must be a positive number of samples per second"
                ));
            }
        }
        if let Some(n) = a.time_lags {
            if !(2..=MAX_LAGS).contains(&n) {
                return crate::error::usage(format!(
                    "--time-lags {n}: must be from 2 to {MAX_LAGS} (the correlations R_0 .. R_(N-1); the Hankel takes R_1 on)"
                ));
            }
        }
        if !(1..=MAX_BLOCKS).contains(&a.blocks) {
            return crate::error::usage(format!(
                "--blocks {}: must be from 1 (no standard deviations) to {MAX_BLOCKS}",
                a.blocks
            ));
        }
        let mut options = OmaOptions::new(1.0);
        options.method = a.method;
        options.lags = a.time_lags;
        options.blocks = a.blocks;
        let auto = !matches!(a.states, Some(StatesArg::Fixed(_)));
        let orders = match &a.orders {
            None => None,
            Some(text) => Some(OrderRange::parse(text).map_err(|e| {
                crate::error::UsageError(format!("--orders {text}: {}", reason_of(&e)))
            })?),
        };
        options.era.scan.orders = orders;
        options.era.order =
            match a.states {
                Some(StatesArg::Fixed(0)) => return crate::error::usage(
                    "--states 0: a model needs at least 2 states (one mode), or use --states auto",
                ),
                Some(StatesArg::Fixed(n)) if a.orders.is_some() => era::Order::Scan { states: n },
                Some(StatesArg::Fixed(n)) => era::Order::Fixed(n),
                _ => era::Order::Auto,
            };
        Ok(Oma {
            files: a.files.clone(),
            outputs: a.outputs.clone(),
            references: a.references.clone(),
            sample_rate: a.sample_rate,
            selection: era_io::time::TimeSelection {
                variables: a.variable.clone(),
                datasets: a.dataset.clone(),
            },
            options,
            auto,
            no_figures: a.no_figures,
            out: a.out.clone(),
            geometry: a.geometry.geometry.clone(),
            settings: Settings::from(&a.common),
        })
    }
}

/// `era track`: the folders to read, where to write, and the core's
/// [`era::modal::track::TrackOptions`].
#[derive(Debug, Clone)]
pub struct Track {
    /// Folders holding a modes.parquet each (shards of one fleet).
    pub dirs: Vec<PathBuf>,
    /// Folder for the outputs.
    pub out: PathBuf,
    /// The core's options.
    pub options: era::modal::track::TrackOptions,
    /// The output switches.
    pub settings: Settings,
}

impl Track {
    /// The settings of `era track`'s flags, each checked under its flag's name: the
    /// tolerance a fraction, the MAC from 0 to below 1, the minimum records a count of
    /// at least 1 or a fraction in (0, 1].
    pub fn new(a: &crate::args::TrackArgs) -> anyhow::Result<Self> {
        use era::modal::track::{MinRecords, TrackOptions};
        let f = a.frequency_tolerance;
        if !(f.is_finite() && f > 0.0 && f < 1.0) {
            return crate::error::usage(format!(
                "--frequency-tolerance {f}: must be a fraction between 0 and 1 (0.05 is 5 %)"
            ));
        }
        if !(0.0..1.0).contains(&a.mac_min) {
            return crate::error::usage(format!(
                "--mac-min {}: must be from 0 to below 1",
                a.mac_min
            ));
        }
        let text = a.min_records.trim();
        let min_records = if let Ok(n) = text.parse::<usize>() {
            if n == 0 {
                return crate::error::usage(
                    "--min-records 0: must be a count of at least 1 or a fraction such as 0.5",
                );
            }
            MinRecords::Count(n)
        } else {
            match text.parse::<f64>() {
                Ok(v) if v > 0.0 && v <= 1.0 => MinRecords::Fraction(v),
                _ => {
                    return crate::error::usage(format!(
                        "--min-records {text}: must be a count of records (10) or a fraction of them above 0 and at most 1 (0.5)"
                    ))
                }
            }
        };
        let mut options = TrackOptions::default();
        options.all_modes = a.all_modes;
        options.frequency_tolerance = f;
        options.mac_min = a.mac_min;
        options.min_records = min_records;
        Ok(Track {
            dirs: a.dirs.clone(),
            out: a.out.clone(),
            options,
            settings: Settings::from(&a.common),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

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

/// `era batch`'s settings.
#[derive(Debug, Clone)]
pub struct Batch {
    /// The manifest.
    pub manifest: PathBuf,
    /// The tables' folder.
    pub out: PathBuf,
    /// `(I, N)`: every N-th record from the I-th (1-based).
    pub shard: Option<(usize, usize)>,
    /// Skip the records an earlier run finished.
    pub resume: bool,
    /// Records side by side.
    pub jobs: usize,
    /// Each record's model files in `out/records/<id>/`.
    pub keep_models: bool,
    /// Accept record files outside the manifest's folder.
    pub allow_outside: bool,
    /// The output switches.
    pub settings: Settings,
}

impl From<&crate::args::BatchArgs> for Batch {
    fn from(a: &crate::args::BatchArgs) -> Self {
        Batch {
            manifest: a.manifest.clone(),
            out: a.out.clone(),
            shard: a.shard,
            resume: a.resume,
            jobs: a.jobs,
            keep_models: a.keep_models,
            allow_outside: a.allow_outside,
            settings: (&a.common).into(),
        }
    }
}
