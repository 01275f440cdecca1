//! `era friction estimate|simulate|tune`'s settings ([`Friction`]), and their flags
//! checked and turned into the core's [`Oscillator`], [`DecaySpec`] and [`TuneSpec`].

use crate::args::{DecayMethodArg, FrictionAction, FrictionArgs, OscillatorArgs};
use crate::config::Settings;
use crate::error::usage;
use era::friction::simulate::{DecaySpec, Method};
use era::friction::tune::TuneSpec;
use era::friction::Oscillator;
use era::params::Naming;
use std::path::PathBuf;

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

pub fn check_stiffness(k: f64) -> anyhow::Result<()> {
    Ok(era::friction::check_stiffness(Naming::Flag, k)?)
}

pub fn oscillator(m: &Actuator, coulomb_force: f64) -> anyhow::Result<Oscillator> {
    check_stiffness(m.stiffness)?;
    let o = Oscillator {
        stiffness: m.stiffness,
        natural_frequency_hz: m.natural_frequency_hz,
        coulomb_force,
        viscous_damping_ratio: m.viscous_damping_ratio,
    };
    o.validate()?;
    Ok(o)
}

/// The free decay `era friction simulate` asks for: the method `exact` unless there is
/// viscous damping (refused with it), `integrate` otherwise.
pub fn decay_spec(a: &FrictionSimulate) -> anyhow::Result<DecaySpec> {
    let osc = oscillator(&a.model, a.coulomb_force)?;
    let method = match a.method {
        Some(Method::Exact) if osc.viscous_damping_ratio != 0.0 => {
            return usage("--method exact is for Coulomb friction alone: drop --viscous-damping-ratio or use --method integrate");
        }
        Some(method) => method,
        None if osc.viscous_damping_ratio != 0.0 => Method::Integrate,
        None => Method::Exact,
    };
    Ok(DecaySpec {
        oscillator: osc,
        x0: a.model.x0,
        sample_rate_hz: a.model.sample_rate,
        hold_s: a.hold,
        duration_s: a.duration,
        noise_fraction: a.noise,
        seed: a.seed,
        method,
    })
}

/// Where `era friction tune` takes the friction from: records (their estimates, read
/// later) or `--coulomb-force`, one of the two.
pub fn check_tune_source(a: &FrictionTune) -> anyhow::Result<()> {
    check_stiffness(a.model.stiffness)?;
    match (a.files.is_empty(), a.coulomb_force) {
        (true, None) => usage("give free-decay record file(s) or --coulomb-force"),
        (false, Some(_)) => usage("give either record file(s) or --coulomb-force, not both"),
        _ => Ok(()),
    }
}

/// The compensator's tuning for an actuator with `coulomb_force` at
/// `natural_frequency_hz`, the other settings the flags'.
pub fn tune_spec(
    a: &FrictionTune,
    coulomb_force: f64,
    natural_frequency_hz: f64,
) -> anyhow::Result<TuneSpec> {
    let osc = Oscillator {
        natural_frequency_hz,
        ..oscillator(&a.model, coulomb_force)?
    };
    Ok(TuneSpec {
        oscillator: osc,
        x0: a.model.x0,
        dead_zone: a.dead_zone,
        sample_rate_hz: a.model.sample_rate,
        cycles: a.cycles,
        fraction: a.fraction,
    })
}
