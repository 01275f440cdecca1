//! `era friction simulate|tune`'s flags checked and turned into the core's
//! [`Oscillator`], [`DecaySpec`] and [`TuneSpec`].

use crate::config::{Actuator, FrictionSimulate, FrictionTune};
use crate::error::usage;
use era::friction::simulate::{DecaySpec, Method};
use era::friction::tune::TuneSpec;
use era::friction::Oscillator;
use era::params::Naming;

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
