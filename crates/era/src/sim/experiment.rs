//! The thesis's FRF test (§4.5, Figs. 4.2–4.3) in software: a lightly damped structure,
//! reaction-mass actuators with Coulomb friction and end stops, the 200 Hz friction
//! compensator of Appendix K, random excitation and the analyzer.
//!
//! # The coupled system
//! The structure is any linear model with force inputs at the actuator mounts and
//! acceleration outputs ([`Structure`]): `ẋ_s = A_s x_s + B_s F`, mount accelerations
//! `ÿ = C_m x_s + D_m F`, sensor accelerations `a = C_a x_s + D_a F`. For a modal model
//! (`ModalStructure`, unit modal masses) the mounts use the input shapes, the sensors the
//! output shapes (collocated by default: an accelerometer on each housing, as in §4.5).
//!
//! Actuator `j` (§2.2, §3.1) is a proof mass `m_j` on a spring `k_j` (and a weak viscous
//! damper `c_j`) inside a housing fixed to mount `j`; `z_j` is the mass's displacement
//! relative to the housing, so the LVT reads `ż_j`. With `f_j` the force between mass and
//! housing (motor force `g·V_j` plus friction),
//!
//! ```text
//! m_j (ÿ_j + z̈_j) = −k_j z_j − c_j ż_j + f_j          (proof mass)
//! F_j = −m_j (ÿ_j + z̈_j) = k_j z_j + c_j ż_j − f_j     (reaction on the structure)
//! ```
//!
//! The reaction does not depend on an acceleration, so a **sliding** actuator couples
//! without an algebraic loop. A **stuck** actuator (`ż_j = 0`, `z_j` constant) moves
//! with its housing: `F_j = −m_j ÿ_j`, which loops through `D_m`; for the stuck set `S`,
//! `F_S = −(I + M_S D_m,SS)⁻¹ M_S (C_m,S x_s + D_m,SF F_F)`. The friction that holds it is
//! `F_f,j = m_j ÿ_j + k_j z_j − g V_j`.
//!
//! # Exact stick–slip (Eq. 3.1 with static = kinetic friction, as `friction::simulate`)
//! Each stuck set `S` is a linear time-invariant system `ẋ = A_S x + B_S f` on the
//! structure states and the sliding actuators' `(z, ż)`. It is diagonalised once,
//! `A_S = V Λ V⁻¹` (complex; one of each conjugate pair kept, weight 2), and cached.
//! Between events the inputs are linear in time (`f = f₀ + f₁τ`: the excitation voltage is
//! interpolated linearly between its samples, the compensator output and the friction are
//! constant), so each modal coordinate has the closed form
//!
//! ```text
//! ξ(τ) = e^{λτ} ξ₀ + φ₁(λ,τ) w f₀ + φ₂(λ,τ) w f₁,
//! φ₁ = (e^{λτ} − 1)/λ,   φ₂ = (e^{λτ} − 1 − λτ)/λ²       (w = V⁻¹B_S)
//! ```
//!
//! (series for small `|λτ|`): an exact ZOH/FOH step, with no integration error. Each
//! event function is affine in `ξ` and `f`, `g(τ) = Re Σ r_k ξ_k(τ) + d·f(τ) + c₀`, so its
//! value and slope cost one pass over the modes; events are located on the way by
//! safeguarded Newton in a sign-change bracket:
//! - a sliding mass's velocity reaches 0: it sticks when the holding force is within
//!   `F_C` (`|F_f| ≤ F_C`), else it reverses;
//! - a stuck mass's holding force leaves `[−F_C, F_C]`: it breaks away, sliding against it;
//! - a sliding mass reaches its end stop `±stroke`: a rigid impact with restitution `e`,
//!   the impulse `P` applied like the motor force, `Δξ = w_j P`,
//!   `P = −(1+e) ż_j / (B_S)_{ż_j, j}`; rebounds slower than [`REST_SPEED`] leave it
//!   resting on the stop (held against any push into the stop, freed by a pull above `F_C`).
//!
//! Between grid points a velocity that goes to zero and back within one step (5 ms at the
//! defaults) is not seen: the check is at the step's ends. A contact that grazes (no
//! positive value of its event function just after its last event, roundoff at the
//! level of 1e-16) is left as it is until the next grid point, where a sliding mass whose
//! velocity has the wrong sign is stopped and the stick/break-away test decides again.
//!
//! # Compensator, excitation, analyzer
//! The [`FrictionCompensator`](crate::friction::compensator::FrictionCompensator)
//! samples the LVT velocities (with seeded noise) at 200 Hz; its output voltage is held
//! until the next sample (ZOH) and added to the excitation.
//! The excitation is Gaussian noise at 4× the analyzer rate (204.8 Hz), low-passed to the
//! band by a windowed-sinc FIR filter and scaled to its RMS; between samples the voltage is
//! linear. The analyzer samples the excitation voltage and the accelerations (plus seeded
//! noise) at 51.2 Hz, and [`crate::estimate`] forms H1 per excited actuator from
//! Hann-windowed frames of 2048 samples without overlap; the 8 columns make the 8×8 set,
//! cut to 801 lines (0–20 Hz).
//!
//! Written here rather than taken from an ODE crate: no Rust ODE solver handles a
//! discontinuous right-hand side with sticking (a change of the system's dimension), and
//! the closed-form modal step is both exact and cheaper than any integrator.

mod events;
mod stepper;

use super::{ModalSpec, ModalStructure};
use crate::data::frf::{FrfData, Quantity};
use crate::data::statespace::{StateSpace, TimeDomain};
use crate::error::{EraError, Result};
use crate::estimate::{self, Detrend, Estimator, WelchOptions, Window};
use crate::linalg::eigen::balanced_eigen;
use faer::linalg::solvers::Solve;
use faer::Mat;
use num_complex::Complex64;
use rayon::prelude::*;
use std::collections::HashMap;
use std::f64::consts::PI;
use std::sync::{Arc, Mutex};

/// Table 5.1 of the thesis, per actuator (1, 2, 3, 4, 5, 6, 9, 10): the Coulomb
/// coefficient calculated from free decay and the adjusted one used by the compensator,
/// lbf.
pub const TABLE_5_1: [(u32, f64, f64); 8] = [
    (1, 0.0591, 0.0325),
    (2, 0.0565, 0.0500),
    (3, 0.0549, 0.0250),
    (4, 0.0353, 0.0100),
    (5, 0.0574, 0.0150),
    (6, 0.0518, 0.0500),
    (9, 0.2824, 0.0325),
    (10, 0.3188, 0.0175),
];

/// Motor constant of the thesis's actuators, lbf per volt (Appendix K: `outcal = 1/0.2`
/// volts per lbf).
pub const MOTOR_LBF_PER_VOLT: f64 = 0.2;

/// Rebound speed (in/s) below which a mass is left resting on its end stop.
pub const REST_SPEED: f64 = 1e-3;

/// Relative speed (in/s) below which a sliding mass's velocity of the wrong sign is
/// roundoff, not motion.
pub(crate) const GRAZING_SPEED: f64 = 1e-9;

/// Events allowed within one grid step before the simulation gives up (a chattering
/// that the event logic cannot resolve).
pub(crate) const MAX_EVENTS_PER_STEP: usize = 10_000;

/// One reaction-mass actuator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Actuator {
    /// Suspension stiffness `k`, lbf/in (thesis 1.0).
    pub stiffness: f64,
    /// Natural frequency on a rigid base, Hz (thesis 1.5).
    pub natural_frequency_hz: f64,
    /// Viscous damping ratio of the suspension (back-EMF, air), fraction.
    pub viscous_damping_ratio: f64,
    /// True Coulomb friction force `F_C`, lbf.
    pub coulomb_force: f64,
    /// Stroke: the end stops are at `±stroke`, in (thesis ±1 in).
    pub stroke: f64,
    /// Coefficient of restitution at the end stops, in `[0, 1]`.
    pub restitution: f64,
    /// Motor force per volt, lbf/V.
    pub motor_force_per_volt: f64,
}

impl Actuator {
    /// The thesis's actuator with Coulomb force `coulomb_force`: 1 lbf/in, 1.5 Hz, ±1 in,
    /// 0.2 lbf/V, 2 % viscous damping, restitution 0.5.
    pub fn thesis(coulomb_force: f64) -> Self {
        Actuator {
            stiffness: 1.0,
            natural_frequency_hz: 1.5,
            viscous_damping_ratio: 0.02,
            coulomb_force,
            stroke: 1.0,
            restitution: 0.5,
            motor_force_per_volt: MOTOR_LBF_PER_VOLT,
        }
    }
    /// Proof mass `k/ω²`.
    pub fn mass(&self) -> f64 {
        let w = 2.0 * PI * self.natural_frequency_hz;
        self.stiffness / (w * w)
    }
    /// Viscous coefficient `2ζ√(km)`.
    pub(crate) fn viscous_coefficient(&self) -> f64 {
        2.0 * self.viscous_damping_ratio * (self.stiffness * self.mass()).sqrt()
    }
    fn validate(&self, j: usize) -> Result<()> {
        let bad = |name: &'static str, v: f64, reason: &str| {
            Err(EraError::InvalidParameter {
                name,
                value: v.to_string(),
                reason: format!("actuator {}: {reason}", j + 1).into(),
            })
        };
        if !(self.stiffness.is_finite() && self.stiffness > 0.0) {
            return bad("stiffness", self.stiffness, "must be positive");
        }
        if !(self.natural_frequency_hz.is_finite() && self.natural_frequency_hz > 0.0) {
            return bad(
                "natural_frequency_hz",
                self.natural_frequency_hz,
                "must be positive",
            );
        }
        if !(self.viscous_damping_ratio.is_finite()
            && (0.0..1.0).contains(&self.viscous_damping_ratio))
        {
            return bad(
                "viscous_damping_ratio",
                self.viscous_damping_ratio,
                "must be in [0, 1)",
            );
        }
        if !(self.coulomb_force.is_finite() && self.coulomb_force >= 0.0) {
            return bad(
                "friction",
                self.coulomb_force,
                "the Coulomb force must be >= 0",
            );
        }
        if self.stroke.is_nan() || self.stroke <= 0.0 {
            return bad("stroke", self.stroke, "must be positive (inf: no stops)");
        }
        if !(self.restitution.is_finite() && (0.0..=1.0).contains(&self.restitution)) {
            return bad("restitution", self.restitution, "must be in [0, 1]");
        }
        if !(self.motor_force_per_volt.is_finite() && self.motor_force_per_volt != 0.0) {
            return bad(
                "motor_force_per_volt",
                self.motor_force_per_volt,
                "must be finite and non-zero",
            );
        }
        Ok(())
    }
}

/// The structure as the actuators see it: continuous `ẋ = A x + B F` with `F` the forces
/// at the mounts (one per input), mount accelerations `C_m x + D_m F` (one per input) and
/// sensor accelerations `C_a x + D_a F`.
#[derive(Debug, Clone)]
pub struct Structure {
    /// `A`, n×n.
    pub a: Mat<f64>,
    /// `B`, n×p.
    pub b: Mat<f64>,
    /// Mount accelerations, p×n.
    pub c_mount: Mat<f64>,
    /// p×p.
    pub d_mount: Mat<f64>,
    /// Sensor accelerations, q×n.
    pub c_sensor: Mat<f64>,
    /// q×p.
    pub d_sensor: Mat<f64>,
}

impl Structure {
    /// From a modal model (unit modal masses): mounts on the input shapes, sensors on the
    /// output shapes.
    pub fn from_modal(s: &ModalStructure) -> Self {
        let sensors = s.state_space(Quantity::Acceleration);
        let mounts = ModalStructure {
            output_shapes: s.input_shapes.clone(),
            ..s.clone()
        }
        .state_space(Quantity::Acceleration);
        Structure {
            a: sensors.a.clone(),
            b: sensors.b.clone(),
            c_mount: mounts.c.clone(),
            d_mount: mounts.d.clone(),
            c_sensor: sensors.c.clone(),
            d_sensor: sensors.d.clone(),
        }
    }

    /// From a square state-space model whose outputs are collocated with its inputs (an
    /// accelerometer on each actuator housing, as in §4.5); a discrete model is converted
    /// with `d2c`. Velocity outputs are differentiated, `a = C A x + C B F` (their direct
    /// term must be 0); acceleration outputs are taken as they are.
    ///
    /// # Errors
    /// [`EraError::ShapeMismatch`] when the model is not square;
    /// [`EraError::InvalidParameter`] for displacement outputs, a velocity model with a
    /// direct term, or an unstable model (a pole with `Re s ≥ 0`).
    pub fn from_state_space(model: &StateSpace, quantity: Quantity) -> Result<Self> {
        if model.outputs() != model.inputs() {
            return Err(EraError::ShapeMismatch {
                what: "structure outputs (one accelerometer per actuator mount) against its inputs"
                    .into(),
                expected: model.inputs(),
                got: model.outputs(),
            });
        }
        let cont = match model.domain {
            TimeDomain::Continuous => model.clone(),
            TimeDomain::Discrete { .. } => model.d2c()?,
        };
        if let Some(p) = cont.poles()?.iter().find(|p| p.re.is_nan() || p.re >= 0.0) {
            return Err(EraError::InvalidParameter {
                name: "structure",
                value: format!("pole {:.6}{:+.6}j", p.re, p.im),
                reason:
                    "the structure model is not stable: a time simulation would grow without bound"
                        .into(),
            });
        }
        let (c, d) = match quantity {
            Quantity::Acceleration => (cont.c.clone(), cont.d.clone()),
            Quantity::Velocity => {
                if cont.d.norm_l2() > 0.0 {
                    return Err(EraError::InvalidParameter {
                        name: "structure",
                        value: "velocity model with D != 0".into(),
                        reason: crate::params::names::Prose::from("a velocity direct term would need an impulsive acceleration: identify with ")
                            .param(crate::params::names::Param::DirectTerm)
                            .text(" zero"),
                    });
                }
                (&cont.c * &cont.a, &cont.c * &cont.b)
            }
            Quantity::Displacement => {
                return Err(EraError::InvalidParameter {
                    name: "structure",
                    value: "displacement".into(),
                    reason: "a structure model needs velocity or acceleration outputs".into(),
                })
            }
        };
        Ok(Structure {
            a: cont.a.clone(),
            b: cont.b.clone(),
            c_mount: c.clone(),
            d_mount: d.clone(),
            c_sensor: c,
            d_sensor: d,
        })
    }

    /// Mounts (inputs).
    pub fn mounts(&self) -> usize {
        self.b.ncols()
    }
    /// Sensors (outputs).
    pub fn sensors(&self) -> usize {
        self.c_sensor.nrows()
    }
    /// States.
    pub fn states(&self) -> usize {
        self.a.nrows()
    }
}

/// The default DTA-like structure: 8×8 collocated, the 40 modes of `ModalSpec::default()`
/// (0.5–14 Hz, ζ 0.5–2 %) and 4 more from 14 to 20 Hz.
pub fn dta_like_structure() -> ModalStructure {
    let low = ModalStructure::random(&ModalSpec::default()).expect("valid default spec");
    let high = ModalStructure::random(&ModalSpec {
        modes: 4,
        fmin_hz: 14.0,
        fmax_hz: 20.0,
        seed: 123_456_789,
        ..ModalSpec::default()
    })
    .expect("valid spec");
    let mut s = low;
    s.frequencies_hz.extend(high.frequencies_hz);
    s.damping_ratios.extend(high.damping_ratios);
    s.output_shapes.extend(high.output_shapes);
    s.input_shapes.extend(high.input_shapes);
    s
}

/// The default actuators: thesis actuators with the Table 5.1 coefficients calculated
/// from free decay for actuators 1–6, and the adjusted ones for the horizontal actuators
/// 9 and 10 (whose free decays lasted one cycle, so their calculated values are not
/// friction, §5.1).
pub fn thesis_actuators() -> Vec<Actuator> {
    TABLE_5_1
        .iter()
        .map(|&(n, calc, adj)| Actuator::thesis(if n >= 9 { adj } else { calc }))
        .collect()
}

/// How the actuators are driven.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Drive {
    /// One actuator at a time (the thesis): one run per actuator, one FRF column each.
    OneAtATime,
    /// All actuators at once, uncorrelated: one run, H1 from the 8 inputs together.
    Simultaneous,
}

/// Compensator settings (thesis §4.4: 200 Hz, dead zone 0.2 in/s, 85 %).
#[derive(Debug, Clone, PartialEq)]
pub struct Compensation {
    /// Coefficient per actuator, lbf.
    pub coefficients: Vec<f64>,
    /// Dead zone, in/s.
    pub dead_zone: f64,
    /// Fraction of the coefficient applied.
    pub fraction: f64,
    /// Sample rate, Hz.
    pub rate_hz: f64,
}

impl Compensation {
    /// The thesis's compensator with the adjusted coefficients of Table 5.1.
    pub fn thesis() -> Self {
        Compensation {
            coefficients: TABLE_5_1.iter().map(|t| t.2).collect(),
            dead_zone: crate::friction::compensator::ChannelConfig::THESIS_DEAD_ZONE,
            fraction: crate::friction::compensator::ChannelConfig::THESIS_FRACTION,
            rate_hz: crate::friction::compensator::ChannelConfig::THESIS_RATE_HZ,
        }
    }
}

/// Everything about one simulated test.
#[derive(Debug, Clone)]
pub struct ExperimentSpec {
    /// The structure.
    pub structure: Structure,
    /// The actuators, on mounts 1, 2, … .
    pub actuators: Vec<Actuator>,
    /// The compensator; `None` for none.
    pub compensation: Option<Compensation>,
    /// Compensator sample rate when there is no compensation (the LVTs are still read),
    /// Hz.
    pub lvt_rate_hz: f64,
    /// Excitation RMS voltage, V (thesis 0.6 without, 0.3 with compensation).
    pub excitation_rms_v: f64,
    /// Excitation bandwidth, Hz (20).
    pub band_hz: f64,
    /// Drive pattern.
    pub drive: Drive,
    /// Analyzer sample rate, Hz (51.2).
    pub analyzer_rate_hz: f64,
    /// Samples per frame (2048).
    pub frame: usize,
    /// Frames averaged per run.
    pub averages: usize,
    /// Lines kept (801: 0–20 Hz).
    pub lines: usize,
    /// Time simulated before the analyzer starts, s (transients of the start from rest).
    pub settle_s: f64,
    /// Accelerometer noise RMS, in/s².
    pub accel_noise_rms: f64,
    /// LVT noise RMS, in/s.
    pub lvt_noise_rms: f64,
    /// Seed of every random stream.
    pub seed: u64,
}

impl ExperimentSpec {
    /// The thesis's accelerometer noise RMS, in/s² ([`ExperimentSpec::thesis`]).
    pub const THESIS_ACCEL_NOISE_RMS: f64 = 0.01;
    /// The thesis's LVT noise RMS, in/s ([`ExperimentSpec::thesis`]).
    pub const THESIS_LVT_NOISE_RMS: f64 = 0.05;
    /// The thesis's excitation RMS voltage without compensation, V (§4.5).
    pub const THESIS_EXCITATION_RMS_V: f64 = 0.6;
    /// The thesis's excitation RMS voltage with compensation, V (§4.5).
    pub const THESIS_COMPENSATED_EXCITATION_RMS_V: f64 = 0.3;

    /// The thesis's test on the DTA-like structure, `averages` frames per actuator, with
    /// or without compensation (0.3 V or 0.6 V excitation).
    pub fn thesis(compensated: bool, averages: usize, seed: u64) -> Self {
        ExperimentSpec {
            structure: Structure::from_modal(&dta_like_structure()),
            actuators: thesis_actuators(),
            compensation: compensated.then(Compensation::thesis),
            lvt_rate_hz: crate::friction::compensator::ChannelConfig::THESIS_RATE_HZ,
            excitation_rms_v: if compensated {
                Self::THESIS_COMPENSATED_EXCITATION_RMS_V
            } else {
                Self::THESIS_EXCITATION_RMS_V
            },
            band_hz: 20.0,
            drive: Drive::OneAtATime,
            analyzer_rate_hz: 51.2,
            frame: 2048,
            averages,
            lines: 801,
            settle_s: 20.0,
            accel_noise_rms: Self::THESIS_ACCEL_NOISE_RMS,
            lvt_noise_rms: Self::THESIS_LVT_NOISE_RMS,
            seed,
        }
    }

    /// Checks the parameters.
    ///
    /// # Errors
    /// [`EraError::InvalidParameter`] naming the parameter, [`EraError::ShapeMismatch`]
    /// for more actuators than structure mounts, [`EraError::Limit`] for a run too long.
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &'static str, v: String, reason: String| {
            Err(EraError::InvalidParameter {
                name,
                value: v,
                reason: reason.into(),
            })
        };
        let a = self.actuators.len();
        if a == 0 {
            return bad("actuators", "0".into(), "need at least one actuator".into());
        }
        if a > 32 {
            return bad("actuators", a.to_string(), "at most 32 actuators".into());
        }
        if a > self.structure.mounts() {
            return Err(EraError::ShapeMismatch {
                what: "actuators: the structure has fewer input DOFs (mounts) than actuators"
                    .into(),
                expected: self.structure.mounts(),
                got: a,
            });
        }
        for (j, act) in self.actuators.iter().enumerate() {
            act.validate(j)?;
        }
        if let Some(c) = &self.compensation {
            if c.coefficients.len() != a {
                return Err(EraError::ShapeMismatch {
                    what: "compensator coefficients, one per actuator".into(),
                    expected: a,
                    got: c.coefficients.len(),
                });
            }
            if !(c.rate_hz.is_finite() && c.rate_hz > 0.0) {
                return bad(
                    "compensator_rate",
                    c.rate_hz.to_string(),
                    "must be positive".into(),
                );
            }
        }
        let pos = |name: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                bad(name, v.to_string(), "must be positive".into())
            }
        };
        let nonneg = |name: &'static str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                bad(name, v.to_string(), "must be >= 0".into())
            }
        };
        pos("lvt_rate", self.lvt_rate_hz)?;
        pos("analyzer_rate", self.analyzer_rate_hz)?;
        nonneg("excitation", self.excitation_rms_v)?;
        nonneg("settle", self.settle_s)?;
        nonneg("accel_noise", self.accel_noise_rms)?;
        nonneg("lvt_noise", self.lvt_noise_rms)?;
        if !(self.band_hz.is_finite()
            && self.band_hz > 0.0
            && self.band_hz < self.analyzer_rate_hz / 2.0)
        {
            return bad(
                "band",
                self.band_hz.to_string(),
                format!(
                    "must be positive and below the analyzer's Nyquist frequency {} Hz",
                    self.analyzer_rate_hz / 2.0
                ),
            );
        }
        if self.averages == 0 {
            return bad("averages", "0".into(), "need at least one frame".into());
        }
        if self.frame < 16 || self.lines < 2 || self.lines > self.frame / 2 + 1 {
            return bad(
                "frame/lines",
                format!("{} / {}", self.frame, self.lines),
                "need a frame of 16 samples or more and 2 … frame/2+1 lines".into(),
            );
        }
        let runs = if self.drive == Drive::OneAtATime {
            a
        } else {
            1
        };
        crate::params::limits::SAMPLES.check_product(
            "analyzer samples (averages x frame)",
            &[self.averages as u64, self.frame as u64],
        )?;
        // Grid steps: about (excitation rate + LVT rate) per simulated second, per run.
        let seconds = self.settle_s + (self.averages * self.frame) as f64 / self.analyzer_rate_hz;
        crate::params::limits::STEPS.check_product(
            "simulation steps (runs x seconds x grid rate)",
            &[
                runs as u64,
                crate::params::limits::saturating_count(
                    seconds * (KNOTS_PER_SAMPLE as f64 * self.analyzer_rate_hz + self.lvt_rate()),
                ),
            ],
        )?;
        self.grid()?;
        Ok(())
    }

    fn lvt_rate(&self) -> f64 {
        self.compensation
            .as_ref()
            .map_or(self.lvt_rate_hz, |c| c.rate_hz)
    }

    /// The common time base: ticks per second, ticks per excitation sample, per LVT
    /// sample.
    fn grid(&self) -> Result<(f64, usize, usize)> {
        let knot = KNOTS_PER_SAMPLE as f64 * self.analyzer_rate_hz;
        let lvt = self.lvt_rate();
        for m in 1..=4096usize {
            let rate = m as f64 * knot;
            let per_lvt = rate / lvt;
            if (per_lvt - per_lvt.round()).abs() < 1e-9 * per_lvt && per_lvt.round() >= 1.0 {
                return Ok((rate, m, per_lvt.round() as usize));
            }
        }
        Err(EraError::InvalidParameter {
            name: "compensator_rate",
            value: lvt.to_string(),
            reason: format!(
                "must be commensurate with the excitation rate {knot} Hz (a common tick of at least 1/{} s)",
                4096.0 * knot
            ).into(),
        })
    }
}

/// Excitation samples per analyzer sample.
pub(crate) const KNOTS_PER_SAMPLE: usize = 4;

/// The recorded channels of one run, at the analyzer rate (after the settling time).
#[derive(Debug, Clone, Default)]
pub struct RunRecord {
    /// Excited actuators (0-based).
    pub excited: Vec<usize>,
    /// Excitation voltage per actuator (all actuators; zero when not excited).
    pub voltage: Vec<Vec<f64>>,
    /// Sensor accelerations, with noise.
    pub acceleration: Vec<Vec<f64>>,
    /// Relative displacement of each proof mass.
    pub stroke: Vec<Vec<f64>>,
    /// LVT velocity of each proof mass (without noise).
    pub relative_velocity: Vec<Vec<f64>>,
    /// Compensation voltage applied at each analyzer sample.
    pub compensation_v: Vec<Vec<f64>>,
    /// Events: velocity reversals, sticks, break-aways, end-stop impacts.
    pub counts: EventCounts,
}

/// How often each event happened.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct EventCounts {
    /// Sliding masses that stopped and reversed.
    pub reversals: u64,
    /// Sliding masses that stopped and stuck.
    pub sticks: u64,
    /// Stuck masses that broke away.
    pub breakaways: u64,
    /// End-stop impacts.
    pub impacts: u64,
}

impl EventCounts {
    fn add(&mut self, o: &EventCounts) {
        self.reversals += o.reversals;
        self.sticks += o.sticks;
        self.breakaways += o.breakaways;
        self.impacts += o.impacts;
    }
}

/// The experiment's result.
#[derive(Debug, Clone)]
pub struct Experiment {
    /// H1 from excitation voltage to sensor acceleration, `lines` lines (in/s² per V).
    pub frf: FrfData,
    /// Ordinary coherence `[output][input][line]` (per run: the excited input's).
    pub coherence: Vec<f64>,
    /// The exact FRFs of the linear system (no friction) on the same lines.
    pub exact: FrfData,
    /// Events over all runs.
    pub counts: EventCounts,
    /// Largest stroke reached per actuator, in.
    pub max_stroke: Vec<f64>,
    /// The runs' records when asked for.
    pub records: Vec<RunRecord>,
}

/// Runs the whole experiment: one run per actuator (or one simultaneous run), the
/// analyzer, and the exact FRFs. `progress` is called with the number of runs done.
/// Runs are independent and go in parallel; each has its own seeded streams, so the
/// result does not depend on the number of threads.
///
/// # Errors
/// From [`ExperimentSpec::validate`], the eigendecompositions and the estimator.
pub fn run_experiment(
    spec: &ExperimentSpec,
    keep_records: bool,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Experiment> {
    spec.validate()?;
    let a = spec.actuators.len();
    let q = spec.structure.sensors();
    let runs: Vec<Vec<usize>> = match spec.drive {
        Drive::OneAtATime => (0..a).map(|j| vec![j]).collect(),
        Drive::Simultaneous => vec![(0..a).collect()],
    };
    let done = std::sync::atomic::AtomicUsize::new(0);
    let sys = System::new(spec)?;
    let shared: SharedConfigs = Mutex::new(HashMap::new());
    let records: Vec<Result<RunRecord>> = runs
        .par_iter()
        .enumerate()
        .map(|(r, excited)| {
            let out = stepper::simulate_run_shared(
                spec,
                &sys,
                &shared,
                excited,
                r as u64,
                RunOptions::default(),
            )
            .map(|o| o.record);
            progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
            out
        })
        .collect();
    let records: Vec<RunRecord> = records.into_iter().collect::<Result<_>>()?;
    let opts = WelchOptions {
        sample_rate_hz: spec.analyzer_rate_hz,
        frame: spec.frame,
        overlap: 0.0,
        window: Window::Hann,
        detrend: Detrend::Mean,
    };
    let lines = spec.lines;
    let mut values = vec![Complex64::new(0.0, 0.0); q * a * lines];
    let mut coherence = vec![0.0; q * a * lines];
    let mut counts = EventCounts::default();
    let mut max_stroke = vec![0.0f64; a];
    for rec in &records {
        counts.add(&rec.counts);
        for (j, s) in rec.stroke.iter().enumerate() {
            max_stroke[j] = s.iter().fold(max_stroke[j], |m, x| m.max(x.abs()));
        }
        let inputs: Vec<&[f64]> = rec.excited.iter().map(|&j| &rec.voltage[j][..]).collect();
        let outputs: Vec<&[f64]> = rec.acceleration.iter().map(|v| &v[..]).collect();
        let mut est = estimate::estimate(
            &inputs,
            &outputs,
            &opts,
            Estimator::H1,
            Quantity::Acceleration,
        )?;
        est.truncate(lines)?;
        for (col, &j) in rec.excited.iter().enumerate() {
            for i in 0..q {
                let h = est.frf.pair(i, col);
                let c = est.coherence(i, col);
                let at = (i * a + j) * lines;
                values[at..at + lines].copy_from_slice(&h[..lines]);
                coherence[at..at + lines].copy_from_slice(&c[..lines]);
            }
        }
    }
    let freq = estimate_lines(spec);
    let frf = FrfData::new(freq.clone(), q, a, values, Quantity::Acceleration)?;
    let exact = exact_frf(spec, &freq)?;
    Ok(Experiment {
        frf,
        coherence,
        exact,
        counts,
        max_stroke,
        records: if keep_records { records } else { Vec::new() },
    })
}

fn estimate_lines(spec: &ExperimentSpec) -> Vec<f64> {
    let df = spec.analyzer_rate_hz / spec.frame as f64;
    (0..spec.lines).map(|k| k as f64 * df).collect()
}

/// The exact FRFs of the linear system (structure and actuators, no friction, every mass
/// sliding) from motor voltage to sensor acceleration at `frequency_hz`.
///
/// # Errors
/// From the frequency response.
pub(crate) fn exact_frf(spec: &ExperimentSpec, frequency_hz: &[f64]) -> Result<FrfData> {
    let sys = System::new(spec)?;
    let (am, bm, cm, dm) = sys.matrices(0);
    let a = spec.actuators.len();
    let gains: Vec<f64> = spec
        .actuators
        .iter()
        .map(|x| x.motor_force_per_volt)
        .collect();
    let b = Mat::from_fn(bm.nrows(), a, |i, j| bm[(i, j)] * gains[j]);
    let d = Mat::from_fn(dm.nrows(), a, |i, j| dm[(i, j)] * gains[j]);
    let ss = StateSpace::new(am, b, cm, d, TimeDomain::Continuous);
    let values = crate::pipeline::fit::frequency_response(&ss, frequency_hz)?;
    FrfData::new(
        frequency_hz.to_vec(),
        spec.structure.sensors(),
        a,
        values,
        Quantity::Acceleration,
    )
}

// ---------------------------------------------------------------------------------------
// The coupled system and its configurations.

/// The parts of the coupled system that do not depend on the stuck set.
struct System {
    s: Structure,
    act: Vec<Actuator>,
    mass: Vec<f64>,
    visc: Vec<f64>,
}

impl System {
    fn new(spec: &ExperimentSpec) -> Result<Self> {
        Ok(System {
            s: spec.structure.clone(),
            mass: spec.actuators.iter().map(Actuator::mass).collect(),
            visc: spec
                .actuators
                .iter()
                .map(Actuator::viscous_coefficient)
                .collect(),
            act: spec.actuators.clone(),
        })
    }

    fn n_s(&self) -> usize {
        self.s.states()
    }

    /// `(A, B, C_acc, D_acc)` of stuck set `mask` on the dynamic state
    /// `[x_s; z_F; ż_F]`, plus nothing else; see [`Config`] for the other outputs.
    fn matrices(&self, mask: u64) -> (Mat<f64>, Mat<f64>, Mat<f64>, Mat<f64>) {
        let l = self.linear(mask);
        (l.a, l.b, l.c_acc, l.d_acc)
    }

    /// Every linear map of stuck set `mask`.
    fn linear(&self, mask: u64) -> Linear {
        let a = self.act.len();
        let ns = self.n_s();
        let free: Vec<usize> = (0..a).filter(|j| mask >> j & 1 == 0).collect();
        let stuck: Vec<usize> = (0..a).filter(|j| mask >> j & 1 == 1).collect();
        let nf = free.len();
        let n = ns + 2 * nf;
        // Mount forces F (a) = Px·x + Pf·f.
        let mut px = Mat::<f64>::zeros(a, n);
        let mut pf = Mat::<f64>::zeros(a, a);
        for (k, &j) in free.iter().enumerate() {
            px[(j, ns + k)] = self.act[j].stiffness;
            px[(j, ns + nf + k)] = self.visc[j];
            pf[(j, j)] = -1.0;
        }
        if !stuck.is_empty() {
            // F_S = −L (C_m,S x_s + D_m,SF F_F), L = (I + M_S D_SS)⁻¹ M_S.
            let ssz = stuck.len();
            let mut lhs = Mat::<f64>::from_fn(ssz, ssz, |r, c| {
                f64::from(u8::from(r == c))
                    + self.mass[stuck[r]] * self.s.d_mount[(stuck[r], stuck[c])]
            });
            let _ = &mut lhs;
            let lu = lhs.partial_piv_lu();
            let mut ms = Mat::<f64>::zeros(ssz, ssz);
            for r in 0..ssz {
                ms[(r, r)] = self.mass[stuck[r]];
            }
            let lmat = lu.solve(&ms);
            // G = C_m,S x_s + D_m,SF (Px_F x + Pf_F f): rows over x (n) and f (a).
            let mut gx = Mat::<f64>::zeros(ssz, n);
            let mut gf = Mat::<f64>::zeros(ssz, a);
            for (r, &j) in stuck.iter().enumerate() {
                for c in 0..ns {
                    gx[(r, c)] = self.s.c_mount[(j, c)];
                }
                for &jf in &free {
                    let dm = self.s.d_mount[(j, jf)];
                    for c in 0..n {
                        gx[(r, c)] += dm * px[(jf, c)];
                    }
                    for c in 0..a {
                        gf[(r, c)] += dm * pf[(jf, c)];
                    }
                }
            }
            let fx = &lmat * &gx;
            let ff = &lmat * &gf;
            for (r, &j) in stuck.iter().enumerate() {
                for c in 0..n {
                    px[(j, c)] = -fx[(r, c)];
                }
                for c in 0..a {
                    pf[(j, c)] = -ff[(r, c)];
                }
            }
        }
        // Outputs of the structure: ÿ_mount (a rows) and sensors, over x and f.
        let out = |cm: &Mat<f64>, dm: &Mat<f64>, rows: usize| -> (Mat<f64>, Mat<f64>) {
            let mut ox = Mat::<f64>::zeros(rows, n);
            let mut of = Mat::<f64>::zeros(rows, a);
            for r in 0..rows {
                for c in 0..ns {
                    ox[(r, c)] = cm[(r, c)];
                }
                for m in 0..a {
                    let d = dm[(r, m)];
                    if d != 0.0 {
                        for c in 0..n {
                            ox[(r, c)] += d * px[(m, c)];
                        }
                        for c in 0..a {
                            of[(r, c)] += d * pf[(m, c)];
                        }
                    }
                }
            }
            (ox, of)
        };
        let (yx, yf) = out(&self.s.c_mount, &self.s.d_mount, a);
        let (c_acc, d_acc) = out(&self.s.c_sensor, &self.s.d_sensor, self.s.sensors());
        let mut am = Mat::<f64>::zeros(n, n);
        let mut bm = Mat::<f64>::zeros(n, a);
        // ẋ_s = A_s x_s + B_s F.
        for r in 0..ns {
            for c in 0..ns {
                am[(r, c)] = self.s.a[(r, c)];
            }
            for m in 0..a {
                let bv = self.s.b[(r, m)];
                if bv != 0.0 {
                    for c in 0..n {
                        am[(r, c)] += bv * px[(m, c)];
                    }
                    for c in 0..a {
                        bm[(r, c)] += bv * pf[(m, c)];
                    }
                }
            }
        }
        // ż and z̈ of the sliding masses.
        for (k, &j) in free.iter().enumerate() {
            am[(ns + k, ns + nf + k)] = 1.0;
            let r = ns + nf + k;
            let m = self.mass[j];
            for c in 0..n {
                am[(r, c)] = -yx[(j, c)];
            }
            am[(r, ns + k)] -= self.act[j].stiffness / m;
            am[(r, ns + nf + k)] -= self.visc[j] / m;
            for c in 0..a {
                bm[(r, c)] = -yf[(j, c)];
            }
            bm[(r, j)] += 1.0 / m;
        }
        Linear {
            free,
            a: am,
            b: bm,
            c_acc,
            d_acc,
            mount_x: yx,
            mount_f: yf,
        }
    }
}

struct Linear {
    free: Vec<usize>,
    a: Mat<f64>,
    b: Mat<f64>,
    c_acc: Mat<f64>,
    d_acc: Mat<f64>,
    mount_x: Mat<f64>,
    mount_f: Mat<f64>,
}

/// Step coefficients `e^{λh}`, `φ₁`, `φ₂` for one step length.
struct StepCoeffs {
    e: Vec<Complex64>,
    p1: Vec<Complex64>,
    p2: Vec<Complex64>,
}

/// A stuck set, diagonalised.
struct Config {
    ns: usize,
    /// Position of actuator j's (z, ż) in the dynamic state, when sliding.
    slot: Vec<Option<usize>>,
    nf: usize,
    lam: Vec<Complex64>,
    /// ξ = vinv · x, m×n row-major.
    vinv: Vec<Complex64>,
    /// x = Re(v ξ), n×m row-major, weights folded in.
    v: Vec<Complex64>,
    /// w = V⁻¹B, m×a row-major.
    w: Vec<Complex64>,
    /// Sensor accelerations: rows over ξ (q×m, weighted) and direct over f (q×a).
    acc_x: Vec<Complex64>,
    acc_f: Vec<f64>,
    /// Mount accelerations (a×m, weighted) and direct (a×a), for holding forces.
    mount_x: Vec<Complex64>,
    mount_f: Vec<f64>,
    /// `(B_S)_{ż_j, j}` for sliding j (impact impulse).
    bz: Vec<f64>,
}

fn phi_coeffs(lam: Complex64, h: f64) -> (Complex64, Complex64, Complex64) {
    let z = lam * h;
    let e = z.exp();
    if z.norm_sqr() < 0.0025 {
        // φ₁/h = Σ z^k/(k+1)!, φ₂/h² = Σ z^k/(k+2)!; 9 terms reach 0.05⁹/9! ≈ 5e-18.
        let (mut t1, mut t2) = (Complex64::new(1.0, 0.0), Complex64::new(0.5, 0.0));
        let (mut s1, mut s2) = (t1, t2);
        for k in 1..9 {
            t1 = t1 * z / (k as f64 + 1.0);
            t2 = t2 * z / (k as f64 + 2.0);
            s1 += t1;
            s2 += t2;
        }
        (e, s1 * h, s2 * h * h)
    } else {
        // One complex division: 1/λ = conj(λ)/|λ|².
        let inv = lam.conj() / lam.norm_sqr();
        let p1 = (e - 1.0) * inv;
        (e, p1, (p1 - h) * inv)
    }
}

impl Config {
    fn new(sys: &System, mask: u64) -> Result<Self> {
        let lin = sys.linear(mask);
        let n = lin.a.nrows();
        let a = sys.act.len();
        let ns = sys.n_s();
        let nf = lin.free.len();
        let (values, vectors) = balanced_eigen(&lin.a)?;
        let lu = vectors.partial_piv_lu();
        let inv = lu.solve(&Mat::<Complex64>::identity(n, n));
        // Keep one of each conjugate pair (weight 2) and the real eigenvalues (weight 1).
        let scale = values
            .iter()
            .map(|l| l.norm())
            .fold(0.0, f64::max)
            .max(1e-300);
        let mut keep: Vec<(usize, f64)> = Vec::new();
        for (k, l) in values.iter().enumerate() {
            if l.im > 1e-10 * scale {
                keep.push((k, 2.0));
            } else if l.im.abs() <= 1e-10 * scale {
                keep.push((k, 1.0));
            }
        }
        let pairs = keep.iter().filter(|k| k.1 == 2.0).count();
        if 2 * pairs + (keep.len() - pairs) != n {
            keep = (0..n).map(|k| (k, 1.0)).collect();
        }
        let m = keep.len();
        let lam: Vec<Complex64> = keep.iter().map(|&(k, _)| values[k]).collect();
        let mut vinv = vec![Complex64::new(0.0, 0.0); m * n];
        let mut v = vec![Complex64::new(0.0, 0.0); n * m];
        for (r, &(k, wt)) in keep.iter().enumerate() {
            for c in 0..n {
                vinv[r * n + c] = inv[(k, c)];
                v[c * m + r] = vectors[(c, k)] * wt;
            }
        }
        let mut w = vec![Complex64::new(0.0, 0.0); m * a];
        for r in 0..m {
            for j in 0..a {
                let mut s = Complex64::new(0.0, 0.0);
                for c in 0..n {
                    s += vinv[r * n + c] * lin.b[(c, j)];
                }
                w[r * a + j] = s;
            }
        }
        let rows_over_xi = |mx: &Mat<f64>| -> Vec<Complex64> {
            let rows = mx.nrows();
            let mut out = vec![Complex64::new(0.0, 0.0); rows * m];
            for i in 0..rows {
                for r in 0..m {
                    let mut s = Complex64::new(0.0, 0.0);
                    for c in 0..n {
                        s += v[c * m + r] * mx[(i, c)];
                    }
                    out[i * m + r] = s;
                }
            }
            out
        };
        let flat = |mx: &Mat<f64>| -> Vec<f64> {
            (0..mx.nrows())
                .flat_map(|i| (0..mx.ncols()).map(move |j| (i, j)))
                .map(|(i, j)| mx[(i, j)])
                .collect()
        };
        let mut slot = vec![None; a];
        let mut bz = vec![0.0; a];
        for (k, &j) in lin.free.iter().enumerate() {
            slot[j] = Some(k);
            bz[j] = lin.b[(ns + nf + k, j)];
        }
        let _ = n;
        Ok(Config {
            ns,
            slot,
            nf,
            lam,
            acc_x: rows_over_xi(&lin.c_acc),
            acc_f: flat(&lin.d_acc),
            mount_x: rows_over_xi(&lin.mount_x),
            mount_f: flat(&lin.mount_f),
            vinv,
            v,
            w,
            bz,
        })
    }

    fn n(&self) -> usize {
        self.ns + 2 * self.nf
    }
    fn m(&self) -> usize {
        self.lam.len()
    }

    /// ξ after `h` from `xi` under `f0 + f1 τ` (b0 = w f0, b1 = w f1 precomputed), with
    /// the step coefficients `c` for this `h` when given.
    fn advance_into(
        &self,
        xi: &[Complex64],
        b0: &[Complex64],
        b1: &[Complex64],
        h: f64,
        c: Option<&StepCoeffs>,
        out: &mut [Complex64],
    ) {
        let m = self.m();
        if let Some(c) = c {
            for k in 0..m {
                out[k] = c.e[k] * xi[k] + c.p1[k] * b0[k] + c.p2[k] * b1[k];
            }
        } else {
            for k in 0..m {
                let (e, p1, p2) = phi_coeffs(self.lam[k], h);
                out[k] = e * xi[k] + p1 * b0[k] + p2 * b1[k];
            }
        }
    }

    fn step_coeffs(&self, h: f64) -> StepCoeffs {
        let m = self.m();
        let mut c = StepCoeffs {
            e: Vec::with_capacity(m),
            p1: Vec::with_capacity(m),
            p2: Vec::with_capacity(m),
        };
        for l in &self.lam {
            let (e, p1, p2) = phi_coeffs(*l, h);
            c.e.push(e);
            c.p1.push(p1);
            c.p2.push(p2);
        }
        c
    }

    /// `b = w f`.
    fn input(&self, f: &[f64], out: &mut [Complex64]) {
        let a = f.len();
        for (r, o) in out.iter_mut().enumerate() {
            let row = &self.w[r * a..(r + 1) * a];
            let mut s = Complex64::new(0.0, 0.0);
            for (wv, fv) in row.iter().zip(f) {
                if *fv != 0.0 {
                    s += wv * fv;
                }
            }
            *o = s;
        }
    }

    /// Component `c` of the dynamic state.
    fn state(&self, xi: &[Complex64], c: usize) -> f64 {
        let m = self.m();
        let row = &self.v[c * m..(c + 1) * m];
        row.iter().zip(xi).map(|(a, b)| (a * b).re).sum()
    }

    fn full_state(&self, xi: &[Complex64]) -> Vec<f64> {
        (0..self.n()).map(|c| self.state(xi, c)).collect()
    }

    fn modal_of(&self, x: &[f64]) -> Vec<Complex64> {
        let n = self.n();
        (0..self.m())
            .map(|r| {
                self.vinv[r * n..(r + 1) * n]
                    .iter()
                    .zip(x)
                    .map(|(a, b)| a * b)
                    .sum()
            })
            .collect()
    }

    fn row_value(rows: &[Complex64], direct: &[f64], i: usize, xi: &[Complex64], f: &[f64]) -> f64 {
        let m = xi.len();
        let a = f.len();
        let s: f64 = rows[i * m..(i + 1) * m]
            .iter()
            .zip(xi)
            .map(|(r, x)| (r * x).re)
            .sum();
        s + direct[i * a..(i + 1) * a]
            .iter()
            .zip(f)
            .map(|(d, x)| d * x)
            .sum::<f64>()
    }
}

/// Per-actuator mechanical state outside the dynamic vector.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Mode {
    /// Sliding with velocity sign `+1`/`−1` (friction `−F_C·sign`).
    Sliding(f64),
    /// Stuck at `z`; `stop` is ±1 when resting against an end stop.
    Stuck { z: f64, stop: f64 },
}

/// What the compensator did, for tests of its timing.
#[derive(Debug, Clone, Default)]
pub struct CompensatorTrace {
    /// Sample times, s (from the start of the run, settling included).
    pub time_s: Vec<f64>,
    /// Velocities read (with noise), one vector per sample.
    pub velocity: Vec<Vec<f64>>,
    /// Voltages output, one vector per sample (held until the next).
    pub output_v: Vec<Vec<f64>>,
}

/// Initial condition and options of a single run for tests.
#[derive(Debug, Clone, Default)]
#[non_exhaustive]
pub struct RunOptions {
    /// Initial relative displacements of the proof masses, released from rest
    /// (`None`: all at 0).
    pub initial_stroke: Option<Vec<f64>>,
    /// Record the proof masses' `(z, ż)` at these times, s (from the start of the run).
    pub probe_times_s: Vec<f64>,
}

/// The output of [`simulate_run_with`].
#[derive(Debug, Clone, Default)]
pub struct RunOutput {
    /// The analyzer's record.
    pub record: RunRecord,
    /// The compensator's trace.
    pub compensator: CompensatorTrace,
    /// `(z_j, ż_j)` per probe time, per actuator.
    pub probes: Vec<Vec<(f64, f64)>>,
}

/// One run: the actuators in `excited` driven, everything recorded. `run` selects the
/// random streams (seed and run give the streams; the same pair, the same numbers).
///
/// # Errors
/// From the eigendecompositions; [`EraError::Numerical`] when events do not resolve.
pub fn simulate_run_with(
    spec: &ExperimentSpec,
    excited: &[usize],
    run: u64,
    opts: RunOptions,
) -> Result<RunOutput> {
    spec.validate()?;
    let sys = System::new(spec)?;
    stepper::simulate_run_shared(spec, &sys, &Mutex::new(HashMap::new()), excited, run, opts)
}

/// Stuck-set configurations shared by the runs of one experiment.
type SharedConfigs = Mutex<HashMap<u64, Arc<Config>>>;
