//! Coulomb friction of reaction-mass actuators: free-decay identification, simulation,
//! compensation and tuning (thesis §3.1, §4.3–4.4, Table 5.1, Appendix K, Appendix L.3).
//!
//! Each actuator is a single-degree-of-freedom oscillator with dry friction,
//!
//! ```text
//! m ẍ + c ẋ + F_C sgn(ẋ) + k x = u(t),        ω_n² = k/m   (Eq. 3.1, c = 0 in the thesis)
//! ```
//!
//! Released from rest at `x0`, each half-cycle is a half sine about the shifted centre
//! `±F_C/k`, and the velocity amplitude drops by `2 F_C ω_n / k` every half-cycle
//! (Eq. 3.10): linearly, where viscous damping decays exponentially. Over `cycles`
//! cycles the drop `Δy` gives the friction force (Eq. 3.12):
//!
//! ```text
//! F_C = Δy · k / (8π f_n · cycles)
//! ```
//!
//! - [`simulate`]: the exact piecewise solution (Eqs. 3.3–3.9) and an event-driven
//!   integrator for forced, viscous and compensated motion.
//! - [`estimate`]: automatic free-decay analysis of a record (what the thesis did with
//!   mouse clicks in `FC.M`).
//! - [`compensator`]: the sampled dead-zone compensator of Appendix K, allocation-free.
//! - [`tune`]: bisection for the coefficient at which the compensated decay is neutral
//!   (what the thesis did by hand with its "tweak" routine).
//!
//! Units are the caller's, consistently: the thesis used inches, lbf and seconds, with
//! `k = 1.0 lbf/in`, so forces come out in lbf and velocities in in/s.

pub mod compensator;
pub mod estimate;
pub mod simulate;
pub mod tune;

use thiserror::Error;

/// Problems with friction records and parameters.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum FrictionError {
    /// A parameter is out of range.
    #[error("invalid parameter {name} = {value}: {reason}")]
    InvalidParameter {
        /// The parameter's field name, snake case (`sample_rate`); a front end spells it
        /// its own way ([`FrictionError::message`]).
        name: &'static str,
        /// Value given.
        value: String,
        /// Why.
        reason: String,
    },
    /// Too few samples to analyse.
    #[error("the record has {samples} samples, at least {needed} are needed")]
    TooFewSamples {
        /// Samples found.
        samples: usize,
        /// Samples needed.
        needed: usize,
    },
    /// Time does not increase strictly.
    #[error("time is not strictly increasing at sample {index} ({previous} s then {time} s)")]
    NonMonotonicTime {
        /// 0-based sample.
        index: usize,
        /// The previous time, s.
        previous: f64,
        /// This time, s.
        time: f64,
    },
    /// NaN or infinity.
    #[error("non-finite {column} at sample {index}")]
    NonFinite {
        /// Column name.
        column: &'static str,
        /// 0-based sample.
        index: usize,
    },
    /// The record does not oscillate (it stops within a cycle, like the thesis's
    /// horizontal actuators 9 and 10).
    #[error(
        "the record never oscillates: {half_cycles} half-cycle(s) above the noise after release, at least 3 are needed"
    )]
    NeverOscillates {
        /// Half-cycles found.
        half_cycles: usize,
    },
    /// A size or amount of work asked for is above a resource limit.
    #[error(transparent)]
    Limit(#[from] crate::params::limits::LimitError),
    /// A simulation produced NaN or infinite values: the parameters are beyond what
    /// double precision can represent.
    #[error("{what} is not finite for {parameters}: the parameters are beyond what double precision can simulate")]
    NonFiniteResult {
        /// What came out non-finite.
        what: &'static str,
        /// The parameters, as `name value` pairs.
        parameters: String,
    },
    /// Oscillates, but not long enough for a fit.
    #[error(
        "too few cycles to fit: {usable} usable half-cycle(s) after skipping the release transient and the stuck tail, at least {needed} are needed"
    )]
    TooFewCycles {
        /// Usable half-cycles.
        usable: usize,
        /// Needed.
        needed: usize,
    },
    /// A compensator buffer has the wrong length.
    #[error("expected {expected} channels, got {got}")]
    Expected {
        /// Channels configured.
        expected: usize,
        /// Length given.
        got: usize,
    },
}

/// Friction records and parameters are the caller's.
impl crate::error::InputError for FrictionError {
    fn is_input_error(&self) -> bool {
        true
    }
}

impl FrictionError {
    /// The message with a refused parameter spelled as `naming`'s front end spells it
    /// (`--sample-rate` from the CLI); other variants read as their `Display`.
    pub fn message(&self, naming: crate::params::Naming) -> String {
        match self {
            FrictionError::InvalidParameter {
                name,
                value,
                reason,
            } => crate::error::refused_parameter(name, value, reason, &|p| naming.spell(p)),
            other => other.to_string(),
        }
    }

    /// [`FrictionError::InvalidParameter`] from a parameter's field name, its value and
    /// the reason.
    pub(crate) fn invalid(name: &'static str, value: f64, reason: impl Into<String>) -> Self {
        FrictionError::InvalidParameter {
            name,
            value: show(value),
            reason: reason.into(),
        }
    }
}

/// Checks the spring stiffness a front end was given: `{stiffness} {k}: must be a
/// positive stiffness (thesis: 1.0 lbf/in)`, named as `naming` does (the CLI's
/// `--stiffness`, Python's `stiffness`).
///
/// # Errors
/// [`crate::EraError::Invalid`] for zero, negative or non-finite values.
pub fn check_stiffness(naming: crate::params::Naming, stiffness: f64) -> crate::Result<()> {
    if !(stiffness.is_finite() && physical(stiffness)) {
        return crate::params::invalid(format!(
            "{} {}: must be a positive stiffness from {:e} to {:e} (thesis: 1.0 lbf/in)",
            naming.name("stiffness"),
            show(stiffness),
            PHYSICAL_RANGE.0,
            PHYSICAL_RANGE.1
        ));
    }
    Ok(())
}

/// The magnitudes an actuator's parameters may take, in any consistent units: a
/// stiffness, a frequency, a force, a displacement or a dead zone outside them is no
/// actuator's (1e308 overflowed the estimate to inf, and 1e300 made the tuning run for
/// 15 s and print coefficients of 300 digits).
pub(crate) const PHYSICAL_RANGE: (f64, f64) = (1e-12, 1e12);

/// Whether `x`'s magnitude lies in [`PHYSICAL_RANGE`].
pub(crate) fn physical(x: f64) -> bool {
    (PHYSICAL_RANGE.0..=PHYSICAL_RANGE.1).contains(&x.abs())
}

/// The reason a value outside [`PHYSICAL_RANGE`] is refused.
pub(crate) fn range_reason(what: &str) -> String {
    format!(
        "must be {what} from {:e} to {:e} in magnitude (no actuator's value lies outside)",
        PHYSICAL_RANGE.0, PHYSICAL_RANGE.1
    )
}

/// A parameter value for a message or a table: plain for ordinary magnitudes
/// (`1e-4 ≤ |x| < 1e7`), in exponent form beyond (`1e308`, not 309 digits; `1e11`, not
/// twelve).
pub fn show(x: f64) -> String {
    let a = x.abs();
    if x.is_finite() && a != 0.0 && !(1e-4..1e7).contains(&a) {
        format!("{x:e}")
    } else {
        x.to_string()
    }
}

/// Result alias.
pub type Result<T> = std::result::Result<T, FrictionError>;

/// A reaction-mass actuator: oscillator with Coulomb (and optionally viscous) damping.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Oscillator {
    /// Net spring stiffness `k` (force per length; thesis 1.0 lbf/in).
    pub stiffness: f64,
    /// Undamped natural frequency `f_n`, Hz.
    pub natural_frequency_hz: f64,
    /// Coulomb friction force `F_C` (force).
    pub coulomb_force: f64,
    /// Viscous damping ratio `ζ` (fraction), 0 for the thesis's model.
    pub viscous_damping_ratio: f64,
}

impl Oscillator {
    /// A Coulomb-only oscillator.
    pub fn coulomb(stiffness: f64, natural_frequency_hz: f64, coulomb_force: f64) -> Self {
        Oscillator {
            stiffness,
            natural_frequency_hz,
            coulomb_force,
            viscous_damping_ratio: 0.0,
        }
    }

    /// The four parameters by their flag names, for messages ("stiffness 1,
    /// natural-frequency-hz 1.5, coulomb-force 0.05, viscous-damping-ratio 0").
    pub fn describe(&self) -> String {
        format!(
            "stiffness {}, natural-frequency-hz {}, coulomb-force {}, viscous-damping-ratio {}",
            show(self.stiffness),
            show(self.natural_frequency_hz),
            show(self.coulomb_force),
            show(self.viscous_damping_ratio)
        )
    }

    /// Checks every parameter.
    ///
    /// # Errors
    /// [`FrictionError::InvalidParameter`] for a non-positive stiffness or frequency, a
    /// negative friction force, or a damping ratio outside `[0, 1)`.
    pub fn validate(&self) -> Result<()> {
        let bad = |name, value: f64, reason: &str| Err(FrictionError::invalid(name, value, reason));
        if !(self.stiffness > 0.0 && physical(self.stiffness)) {
            return bad("stiffness", self.stiffness, &range_reason("positive"));
        }
        if !(self.natural_frequency_hz > 0.0 && physical(self.natural_frequency_hz)) {
            return bad(
                "natural_frequency_hz",
                self.natural_frequency_hz,
                &range_reason("positive"),
            );
        }
        if !(self.coulomb_force == 0.0
            || (self.coulomb_force > 0.0 && physical(self.coulomb_force)))
        {
            return bad(
                "coulomb_force",
                self.coulomb_force,
                &range_reason("0, or positive"),
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
        Ok(())
    }

    /// `ω_n = 2π f_n`, rad/s.
    pub fn omega(&self) -> f64 {
        2.0 * std::f64::consts::PI * self.natural_frequency_hz
    }
    /// Moving mass `m = k/ω_n²`.
    pub fn mass(&self) -> f64 {
        self.stiffness / (self.omega() * self.omega())
    }
    /// Viscous coefficient `c = 2ζ√(k m)`.
    pub(crate) fn viscous_coefficient(&self) -> f64 {
        2.0 * self.viscous_damping_ratio * (self.stiffness * self.mass()).sqrt()
    }
    /// Velocity drop per cycle of a Coulomb free decay, `4 F_C ω_n / k` (Eq. 3.10).
    pub fn velocity_drop_per_cycle(&self) -> f64 {
        4.0 * self.coulomb_force * self.omega() / self.stiffness
    }
}

/// Eq. 3.12: `F_C = Δy · k / (8π f_n · cycles)`.
pub(crate) fn coulomb_force_from_decay(
    velocity_drop: f64,
    stiffness: f64,
    natural_frequency_hz: f64,
    cycles: f64,
) -> f64 {
    velocity_drop * stiffness / (8.0 * std::f64::consts::PI * natural_frequency_hz * cycles)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eq_3_12_inverts_eq_3_10() {
        let o = Oscillator::coulomb(1.0, 1.5, 0.0591);
        let cycles = 3.5;
        let drop = o.velocity_drop_per_cycle() * cycles;
        assert!((coulomb_force_from_decay(drop, 1.0, 1.5, cycles) - 0.0591).abs() < 1e-15);
    }
}
