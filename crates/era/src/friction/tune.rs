//! Automatic tuning of the compensation coefficient (replaces the thesis's "tweak"
//! routine of Appendix K.2, where the coefficient was adjusted by eye until the
//! compensated free decay neither decayed nor grew).
//!
//! With the compensator applying `c·sgn(v)` outside its dead zone (fraction 1), the
//! compensated free decay is simulated ([`super::simulate::integrate`], sampled
//! compensator, zero-order hold) and its velocity amplitude measured over the cycles.
//! The trend is monotone in `c`: below the neutral coefficient the motion decays, above
//! it it grows. Bisection finds the neutral `c*`. Without viscous damping and with a
//! negligible dead zone `c* = F_C`; viscous damping and the dead zone raise it.
//!
//! At the applied fraction `φ` the **stability margin** is `1 − φ·c/c*` for a coefficient
//! `c`: positive means the compensated actuator still decays, negative means it
//! oscillates — as the thesis's raw free-decay coefficients did.

use super::compensator::ChannelConfig;
use super::simulate::integrate;
use super::{FrictionError, Oscillator, Result};

/// Settings of a tuning run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TuneSpec {
    /// The actuator model.
    pub oscillator: Oscillator,
    /// Release displacement of the simulated free decays.
    pub x0: f64,
    /// Compensator dead zone (velocity).
    pub dead_zone: f64,
    /// Compensator sample rate, Hz (thesis: 200).
    pub sample_rate_hz: f64,
    /// Cycles simulated per trial.
    pub cycles: usize,
    /// Fraction of the coefficient to apply in service (thesis: 0.85–0.9).
    pub fraction: f64,
}

/// Result of a tuning run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TuneResult {
    /// Coefficient at which the compensated free decay is neutral.
    pub neutral_coefficient: f64,
    /// `fraction × neutral`: the coefficient to program.
    pub applied_coefficient: f64,
    /// `1 − fraction` at the neutral coefficient.
    pub stability_margin: f64,
    /// Bisection iterations.
    pub iterations: usize,
}

/// Doublings of the upper bracket at most.
const BRACKET_DOUBLINGS: usize = 20;
/// Bisection steps at most.
const BISECTIONS: usize = 60;
/// Trials of one tuning run at most: the bracket's first try, its doublings, the
/// bisections.
pub(crate) const MAX_TRIALS: usize = 1 + BRACKET_DOUBLINGS + BISECTIONS;

/// Velocity amplitude trend of the compensated free decay with coefficient `c`:
/// (last peak − first peak) / first peak over the simulated cycles.
///
/// # Errors
/// From the integrator.
pub(crate) fn amplitude_trend(spec: &TuneSpec, coefficient: f64) -> Result<f64> {
    let channel = ChannelConfig {
        coefficient,
        dead_zone: spec.dead_zone,
        fraction: 1.0,
        ..ChannelConfig::thesis(coefficient)
    };
    let samples = (spec.cycles as f64 * spec.sample_rate_hz / spec.oscillator.natural_frequency_hz)
        .ceil() as usize;
    let states = integrate(
        &spec.oscillator,
        spec.x0,
        0.0,
        spec.sample_rate_hz,
        samples,
        |_, s| channel.output(s.v),
    )?;
    // Peak |v| in the first and the last cycle.
    let per_cycle = (spec.sample_rate_hz / spec.oscillator.natural_frequency_hz).ceil() as usize;
    let peak =
        |range: &[super::simulate::State]| range.iter().fold(0.0f64, |m, s| m.max(s.v.abs()));
    let first = peak(&states[..per_cycle.min(states.len())]);
    let last = peak(&states[states.len().saturating_sub(per_cycle)..]);
    Ok((last - first) / first.max(f64::MIN_POSITIVE))
}

/// Bisection for the neutral coefficient between 0 and `4·F_C + drop` of the model.
///
/// # Errors
/// [`FrictionError::InvalidParameter`] for invalid settings; [`FrictionError::Limit`]
/// when the trials together would take more than [`crate::params::limits::STEPS`] integrator
/// steps (checked before the first trial); [`FrictionError::NonFiniteResult`] when the
/// neutral coefficient is not a positive finite number.
pub fn tune(spec: &TuneSpec) -> Result<TuneResult> {
    spec.oscillator.validate()?;
    let bad = |name, value: f64, reason: &str| Err(FrictionError::invalid(name, value, reason));
    if !(spec.x0 != 0.0 && super::physical(spec.x0)) {
        return bad("x0", spec.x0, &super::range_reason("non-zero"));
    }
    if !(spec.fraction.is_finite() && spec.fraction > 0.0 && spec.fraction <= 1.0) {
        return bad("fraction", spec.fraction, "must be in (0, 1]");
    }
    if !(spec.dead_zone == 0.0 || (spec.dead_zone > 0.0 && super::physical(spec.dead_zone))) {
        return bad(
            "dead_zone",
            spec.dead_zone,
            &super::range_reason("0, or positive"),
        );
    }
    if spec.cycles < 2 {
        return bad(
            "cycles",
            spec.cycles as f64,
            "need at least 2 cycles per trial",
        );
    }
    if !(spec.sample_rate_hz.is_finite()
        && spec.sample_rate_hz > 4.0 * spec.oscillator.natural_frequency_hz)
    {
        return Err(FrictionError::invalid(
            "sample_rate",
            spec.sample_rate_hz,
            format!(
                "must exceed 4 x the natural frequency (natural-frequency-hz {})",
                spec.oscillator.natural_frequency_hz
            ),
        ));
    }
    let o = &spec.oscillator;
    // Both are finite and positive (validated), so the product is never NaN.
    if o.stiffness * spec.x0.abs() <= o.coulomb_force {
        return Err(FrictionError::invalid(
            "coulomb_force",
            o.coulomb_force,
            format!(
                "the mass never moves: the spring force at release, stiffness {} x x0 {}, does not exceed the friction force, so no coefficient is neutral",
                super::show(o.stiffness),
                super::show(spec.x0)
            ),
        ));
    }
    // Bound the work before any trial runs: every trial integrates
    // cycles x sample-rate / f_n samples of `substeps` steps each.
    let substeps = super::simulate::substeps_per_sample(o, spec.sample_rate_hz)?;
    let samples = crate::params::limits::saturating_count(
        spec.cycles as f64 * spec.sample_rate_hz / o.natural_frequency_hz,
    );
    crate::params::limits::STEPS.check_product(
        format!(
            "--cycles {} at sample-rate {} and natural-frequency-hz {} ({MAX_TRIALS} bisection trials x samples x steps per sample)",
            spec.cycles,
            super::show(spec.sample_rate_hz),
            super::show(o.natural_frequency_hz)
        ),
        &[MAX_TRIALS as u64, samples, substeps as u64],
    )?;
    // Upper bracket: enough force to beat friction and the viscous loss at x0.
    let viscous = o.viscous_coefficient() * o.omega() * spec.x0.abs();
    let (mut lo, mut hi) = (
        0.0,
        2.0 * (o.coulomb_force + viscous).max(1e-12 * o.stiffness * spec.x0.abs()),
    );
    let mut guard = 0;
    while amplitude_trend(spec, hi)? < 0.0 && guard < BRACKET_DOUBLINGS {
        hi *= 2.0;
        guard += 1;
    }
    let mut iterations = 0;
    while hi - lo > 1e-5 * hi && iterations < BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if amplitude_trend(spec, mid)? < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
        iterations += 1;
    }
    let neutral = 0.5 * (lo + hi);
    if !(neutral.is_finite() && neutral > 0.0) {
        return Err(FrictionError::NonFiniteResult {
            what: "the neutral coefficient",
            parameters: format!(
                "{}, x0 {}, dead-zone {}, sample-rate {}",
                o.describe(),
                super::show(spec.x0),
                super::show(spec.dead_zone),
                super::show(spec.sample_rate_hz)
            ),
        });
    }
    Ok(TuneResult {
        neutral_coefficient: neutral,
        applied_coefficient: spec.fraction * neutral,
        stability_margin: 1.0 - spec.fraction,
        iterations,
    })
}

/// Stability margin `1 − fraction·coefficient/neutral` of a coefficient against the
/// neutral one: negative means the compensated actuator oscillates.
pub fn stability_margin(coefficient: f64, fraction: f64, neutral: f64) -> f64 {
    1.0 - fraction * coefficient / neutral
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> TuneSpec {
        TuneSpec {
            oscillator: Oscillator::coulomb(1.0, 1.5, 0.05),
            x0: 1.5,
            dead_zone: 0.2,
            sample_rate_hz: 200.0,
            cycles: 6,
            fraction: 0.85,
        }
    }

    #[test]
    fn the_work_is_bounded_before_the_first_trial() {
        // 100 000 cycles ran for minutes; a tiny natural frequency asked for more
        // samples than usize holds (a capacity-overflow panic).
        for s in [
            TuneSpec {
                cycles: 100_000,
                ..spec()
            },
            TuneSpec {
                cycles: usize::MAX,
                ..spec()
            },
            TuneSpec {
                oscillator: Oscillator::coulomb(1.0, 1e-9, 0.05),
                ..spec()
            },
        ] {
            match tune(&s) {
                Err(FrictionError::Limit(e)) => assert_eq!(e.env, "ERA_MAX_STEPS", "{e}"),
                other => panic!("{s:?}: {other:?}"),
            }
        }
    }

    #[test]
    fn values_outside_any_actuator_and_a_meaningless_coefficient_are_errors() {
        // k·x0 overflowed to an infinite bracket ("neutral coefficient inf"), and 1e300
        // ran for 15 s: such values are refused before anything runs, by name.
        for (s, name) in [
            (
                TuneSpec {
                    oscillator: Oscillator::coulomb(1e300, 1.5, 0.05),
                    ..spec()
                },
                "stiffness",
            ),
            (
                TuneSpec {
                    x0: 1e308,
                    ..spec()
                },
                "x0",
            ),
            (
                TuneSpec {
                    dead_zone: 1e308,
                    ..spec()
                },
                "dead_zone",
            ),
        ] {
            match tune(&s) {
                Err(e @ FrictionError::InvalidParameter { .. }) => {
                    let text = e.to_string();
                    assert!(text.contains(name) && text.contains("1e12"), "{text}")
                }
                other => panic!("{name}: {other:?}"),
            }
        }
        // Friction above the spring force: the mass never moves, any coefficient is
        // "neutral" (a bisection to nowhere gave 8.7e281).
        let s = TuneSpec {
            oscillator: Oscillator::coulomb(1.0, 1.5, 100.0),
            ..spec()
        };
        match tune(&s) {
            Err(e @ FrictionError::InvalidParameter { .. }) => {
                assert!(e.to_string().contains("never moves"), "{e}")
            }
            other => panic!("{other:?}"),
        }
    }
}
