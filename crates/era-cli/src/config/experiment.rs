//! `era simulate experiment`'s settings ([`Experiment`]), checked and turned into the
//! core's [`ExperimentSpec`]: the structure, the actuators and the analyzer.

use crate::args::{ExperimentArgs, OnOff, StructureQuantity};
use crate::config;
use crate::config::Settings;
use crate::error::usage;
use era::sim::experiment::{
    dta_like_structure, thesis_actuators, Compensation, Drive, ExperimentSpec, Structure, TABLE_5_1,
};
use era::sim::{ModalSpec, ModalStructure};
use std::path::PathBuf;

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

fn check_nonnegative(flag: &str, v: f64) -> anyhow::Result<()> {
    if !(v.is_finite() && v >= 0.0) {
        return usage(format!("{flag} {v}: must be a number >= 0"));
    }
    Ok(())
}

/// The structure the flags describe.
fn structure(a: &config::Experiment) -> anyhow::Result<Structure> {
    if let Some(path) = &a.structure {
        let model = era_io::model_json::ModelJson::read(path)?;
        let ss = model.state_space().map_err(|e| {
            crate::error::UsageError(format!("--structure {}: {e}", path.display()))
        })?;
        let quantity = a.structure_quantity;
        return Structure::from_state_space(&ss, quantity).map_err(|e| {
            crate::error::UsageError(format!(
                "--structure {}: {} (the structure needs one output collocated with each input)",
                path.display(),
                e.message(era::params::Naming::Flag)
            ))
            .into()
        });
    }
    if a.modes.is_none()
        && a.dofs.is_none()
        && a.fmin.is_none()
        && a.fmax.is_none()
        && a.damping.is_none()
    {
        return Ok(Structure::from_modal(&dta_like_structure()));
    }
    let d = ModalSpec::default();
    let (damping_min, damping_max) = match &a.damping {
        Some(text) => crate::config::parse_range(text)?,
        None => (d.damping_min, d.damping_max),
    };
    let dofs = a.dofs.unwrap_or(d.outputs);
    era::params::limits::CHANNELS.check("--dofs", dofs as u64)?;
    let modes = a.modes.unwrap_or(d.modes);
    era::params::limits::STATES.check_product("--modes (2 states each)", &[modes as u64, 2])?;
    let spec = ModalSpec {
        outputs: dofs,
        inputs: dofs,
        modes,
        fmin_hz: a.fmin.unwrap_or(d.fmin_hz),
        fmax_hz: a.fmax.unwrap_or(d.fmax_hz),
        damping_min,
        damping_max,
        collocated: true,
        seed: a.seed,
    };
    let s = ModalStructure::random(&spec)
        .map_err(|e| crate::error::UsageError(e.message(era::params::Naming::Flag)))?;
    Ok(Structure::from_modal(&s))
}

/// Validated flags → the experiment.
pub fn spec(a: &config::Experiment) -> anyhow::Result<ExperimentSpec> {
    check_nonnegative("--friction-scale", a.friction_scale)?;
    check_nonnegative("--accel-noise", a.accel_noise)?;
    check_nonnegative("--lvt-noise", a.lvt_noise)?;
    if a.averages == 0 {
        return usage("--averages 0: need at least one frame");
    }
    era::params::limits::SAMPLES
        .check_product("--averages x 2048 samples", &[a.averages as u64, 2048])?;
    if a.actuators == 0 || a.actuators > TABLE_5_1.len() {
        return usage(format!(
            "--actuators {}: must be 1 to {} (the actuators of Table 5.1)",
            a.actuators,
            TABLE_5_1.len()
        ));
    }
    let compensated = a.compensation;
    let excitation = a.excitation.unwrap_or(if compensated {
        ExperimentSpec::THESIS_COMPENSATED_EXCITATION_RMS_V
    } else {
        ExperimentSpec::THESIS_EXCITATION_RMS_V
    });
    if !(excitation.is_finite() && excitation > 0.0 && excitation <= 1000.0) {
        return usage(format!(
            "--excitation {excitation}: must be a positive RMS voltage up to 1000 V"
        ));
    }
    let structure = structure(a)?;
    if a.actuators > structure.mounts() {
        return usage(format!(
            "--actuators {}: the structure has only {} input DOF(s) to mount them on",
            a.actuators,
            structure.mounts()
        ));
    }
    let mut actuators = thesis_actuators();
    actuators.truncate(a.actuators);
    for act in &mut actuators {
        act.coulomb_force *= a.friction_scale;
        if !act.coulomb_force.is_finite() {
            return usage(format!(
                "--friction-scale {}: the Coulomb forces overflow",
                a.friction_scale
            ));
        }
    }
    let compensation = if compensated {
        let mut c = Compensation::thesis();
        c.coefficients.truncate(a.actuators);
        // The default coefficients follow the friction they were tuned for.
        c.coefficients
            .iter_mut()
            .for_each(|x| *x *= a.friction_scale);
        if let Some(list) = &a.coefficients {
            if list.len() != a.actuators {
                return usage(format!(
                    "--coefficients: {} value(s) for {} actuators",
                    list.len(),
                    a.actuators
                ));
            }
            if let Some(bad) = list.iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
                return usage(format!("--coefficients: {bad} is not a force >= 0"));
            }
            c.coefficients = list.clone();
        }
        Some(c)
    } else {
        if a.coefficients.is_some() {
            return usage("--coefficients needs --compensation on");
        }
        None
    };
    let mut spec = ExperimentSpec::thesis(compensated, a.averages, a.seed);
    spec.structure = structure;
    spec.actuators = actuators;
    spec.compensation = compensation;
    spec.excitation_rms_v = excitation;
    spec.accel_noise_rms = a.accel_noise;
    spec.lvt_noise_rms = a.lvt_noise;
    spec.drive = if a.simultaneous {
        Drive::Simultaneous
    } else {
        Drive::OneAtATime
    };
    spec.validate().map_err(|e| {
        crate::error::UsageError(format!(
            "era simulate experiment: {}",
            e.message(era::params::Naming::Flag)
        ))
    })?;
    Ok(spec)
}
