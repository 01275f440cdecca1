//! The sampled Coulomb-friction compensator (thesis §4.4; the logic of Appendix K's
//! `couldamp.c`, written anew).
//!
//! Each sample, per channel, with the measured relative velocity `v`:
//!
//! ```text
//! f = +fraction·coefficient   if v >  dead_zone
//! f = −fraction·coefficient   if v < −dead_zone
//! f = 0                       otherwise (inside the dead zone, or v not finite)
//! out = clamp(gain·f, output_min, output_max)
//! ```
//!
//! The force aids the motion, cancelling the friction that opposes it. The thesis used a
//! ±0.2 in/s dead zone (below it the LVT voltage is noise) and 85–90 % of the tuned
//! coefficient (more makes the actuators oscillate); `gain` converts force to the output
//! unit (the thesis's lbf → volts), 1 for force. [`FrictionCompensator::step`] allocates
//! nothing and is O(channels), so it can run inside a 200 Hz real-time loop.

use super::{FrictionError, Result};

/// One actuator's compensation settings.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct ChannelConfig {
    /// Coulomb coefficient (force).
    pub coefficient: f64,
    /// Velocities with `|v| ≤ dead_zone` get no compensation (thesis: 0.2 in/s).
    pub dead_zone: f64,
    /// Fraction of the coefficient applied (thesis: 0.85–0.9).
    pub fraction: f64,
    /// Output per unit force (thesis: volts per lbf); 1 for force output.
    pub gain: f64,
    /// Lowest output.
    pub output_min: f64,
    /// Highest output.
    pub output_max: f64,
}

impl ChannelConfig {
    /// The thesis's compensator sample rate, Hz (§4.4; its LVTs are sampled with it).
    pub const THESIS_RATE_HZ: f64 = 200.0;
    /// The thesis's dead zone, in/s (§4.4).
    pub const THESIS_DEAD_ZONE: f64 = 0.2;
    /// The fraction of the coefficient the thesis applied (§4.4: 0.85–0.9).
    pub const THESIS_FRACTION: f64 = 0.85;

    /// The thesis's settings for a coefficient: dead zone 0.2, fraction 0.85, force
    /// output, no limits.
    pub fn thesis(coefficient: f64) -> Self {
        ChannelConfig {
            coefficient,
            dead_zone: Self::THESIS_DEAD_ZONE,
            fraction: Self::THESIS_FRACTION,
            gain: 1.0,
            output_min: f64::NEG_INFINITY,
            output_max: f64::INFINITY,
        }
    }

    fn validate(&self, channel: usize) -> Result<()> {
        let bad =
            |name, value: f64, reason: String| Err(FrictionError::invalid(name, value, reason));
        if !(self.coefficient.is_finite() && self.coefficient >= 0.0) {
            return bad(
                "coefficient",
                self.coefficient,
                format!("channel {}: must be >= 0", channel + 1),
            );
        }
        if !(self.dead_zone.is_finite() && self.dead_zone >= 0.0) {
            return bad(
                "dead_zone",
                self.dead_zone,
                format!("channel {}: must be >= 0", channel + 1),
            );
        }
        if !(self.fraction.is_finite() && (0.0..=1.0).contains(&self.fraction)) {
            return bad(
                "fraction",
                self.fraction,
                format!("channel {}: must be in [0, 1]", channel + 1),
            );
        }
        if !self.gain.is_finite() {
            return bad(
                "gain",
                self.gain,
                format!("channel {}: must be finite", channel + 1),
            );
        }
        if self.output_min.is_nan() || self.output_max.is_nan() || self.output_min > self.output_max
        {
            return bad(
                "output limits",
                self.output_min,
                format!("channel {}: need min <= max", channel + 1),
            );
        }
        Ok(())
    }

    /// The compensation output for one velocity.
    #[inline]
    pub fn output(&self, velocity: f64) -> f64 {
        let force = if velocity > self.dead_zone {
            self.fraction * self.coefficient
        } else if velocity < -self.dead_zone {
            -self.fraction * self.coefficient
        } else {
            0.0 // inside the dead zone, or NaN: apply nothing
        };
        (self.gain * force).clamp(self.output_min, self.output_max)
    }
}

/// Per-sample map from measured relative velocities to compensation outputs.
#[derive(Debug, Clone, PartialEq)]
pub struct FrictionCompensator {
    channels: Vec<ChannelConfig>,
}

impl FrictionCompensator {
    /// Validates the channel settings.
    ///
    /// # Errors
    /// [`FrictionError::InvalidParameter`] naming the channel and setting.
    pub fn new(channels: Vec<ChannelConfig>) -> Result<Self> {
        for (k, c) in channels.iter().enumerate() {
            c.validate(k)?;
        }
        Ok(FrictionCompensator { channels })
    }

    /// The channels.
    pub fn channels(&self) -> &[ChannelConfig] {
        &self.channels
    }

    /// One sample: `outputs[k] = channel k's output for velocities[k]`. Allocates nothing.
    ///
    /// # Errors
    /// [`FrictionError::Expected`] when a buffer's length differs from the number of
    /// channels (nothing is written then).
    #[inline]
    pub fn step(&self, velocities: &[f64], outputs: &mut [f64]) -> Result<()> {
        let n = self.channels.len();
        if velocities.len() != n {
            return Err(FrictionError::Expected {
                expected: n,
                got: velocities.len(),
            });
        }
        if outputs.len() != n {
            return Err(FrictionError::Expected {
                expected: n,
                got: outputs.len(),
            });
        }
        for ((out, v), c) in outputs.iter_mut().zip(velocities).zip(&self.channels) {
            *out = c.output(*v);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dead_zone_boundaries_signs_and_limits() {
        let c = ChannelConfig {
            coefficient: 0.05,
            dead_zone: 0.2,
            fraction: 0.9,
            gain: 5.0,
            output_min: -0.2,
            output_max: 0.2,
        };
        assert_eq!(c.output(0.2), 0.0); // the boundary itself is inside (strict, as Appendix K)
        assert_eq!(c.output(-0.2), 0.0);
        assert_eq!(c.output(0.0), 0.0);
        assert!((c.output(0.2000001) - 0.2).abs() < 1e-15); // 5 × 0.9 × 0.05 = 0.225, clamped
        assert!((c.output(-3.0) + 0.2).abs() < 1e-15);
        assert_eq!(c.output(f64::NAN), 0.0);
        let unclamped = ChannelConfig {
            output_min: -1.0,
            output_max: 1.0,
            ..c
        };
        assert!((unclamped.output(1.0) - 0.225).abs() < 1e-15);
        assert!((unclamped.output(-1.0) + 0.225).abs() < 1e-15);
        assert!((unclamped.output(f64::INFINITY) - 0.225).abs() < 1e-15);
    }

    #[test]
    fn step_checks_lengths_and_settings() {
        let comp = FrictionCompensator::new(vec![
            ChannelConfig::thesis(0.0325),
            ChannelConfig::thesis(0.05),
        ])
        .unwrap();
        let mut out = [9.0; 2];
        comp.step(&[1.0, -1.0], &mut out).unwrap();
        assert!((out[0] - 0.85 * 0.0325).abs() < 1e-15 && (out[1] + 0.85 * 0.05).abs() < 1e-15);
        assert_eq!(
            comp.step(&[1.0], &mut out),
            Err(FrictionError::Expected {
                expected: 2,
                got: 1
            })
        );
        assert_eq!(
            comp.step(&[1.0, 1.0], &mut [0.0; 3]),
            Err(FrictionError::Expected {
                expected: 2,
                got: 3
            })
        );
        assert!(FrictionCompensator::new(vec![ChannelConfig {
            fraction: 1.5,
            ..ChannelConfig::thesis(0.1)
        }])
        .is_err());
        assert!(FrictionCompensator::new(vec![ChannelConfig {
            output_min: 1.0,
            output_max: -1.0,
            ..ChannelConfig::thesis(0.1)
        }])
        .is_err());
    }
}
