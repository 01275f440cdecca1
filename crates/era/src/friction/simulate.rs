//! Free-decay and forced simulation of an actuator with Coulomb friction.
//!
//! [`exact_free_decay`] is the thesis's piecewise solution (Eqs. 3.3–3.9), any number of
//! half-cycles: from rest at `x_i`, the mass moves with velocity sign `s = −sgn(x_i)`
//! about the centre `c = −s·F_C/k`, `x = c + (x_i − c) cos ω_n τ`, and stops after half
//! a period at `x_(i+1) = 2c − x_i`; it sticks for good once `k|x_i| ≤ F_C`.
//!
//! [`integrate`] is a general event-driven integrator for forced, viscous and
//! compensated motion. No ODE crate handles the switching and sticking of dry friction
//! (a discontinuous right-hand side), so it is written here: classical RK4 on each smooth
//! stretch (fixed friction sign), the velocity zero located by bisection on the step
//! fraction, then a stick-or-reverse decision from the net force against `F_C` (static
//! friction equal to kinetic, as in Eq. 3.1). The applied force is sampled once per
//! sample period and held (zero-order hold), as the thesis's 200 Hz compensator did.

use super::{FrictionError, Oscillator, Result};
use crate::linalg::rng::Minstd;
use std::f64::consts::PI;

/// Position and velocity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct State {
    /// Displacement.
    pub x: f64,
    /// Velocity.
    pub v: f64,
}

/// Exact Coulomb free decay released from rest at `x0` at `t = 0`, evaluated at `times`
/// (before 0 the mass is held at `x0`).
///
/// # Errors
/// [`FrictionError::InvalidParameter`] for invalid oscillator parameters or a viscous
/// damping ratio other than 0 (the closed form is for dry friction only).
pub fn exact_free_decay(osc: &Oscillator, x0: f64, times: &[f64]) -> Result<Vec<State>> {
    osc.validate()?;
    if osc.viscous_damping_ratio != 0.0 {
        return Err(FrictionError::InvalidParameter {
            name: "viscous_damping_ratio",
            value: osc.viscous_damping_ratio.to_string(),
            reason: "the exact solution is for Coulomb friction alone; use the integrator".into(),
        });
    }
    let w = osc.omega();
    let half = PI / w;
    let fk = osc.coulomb_force / osc.stiffness;
    // Turning points x_0, x_1, … until the mass sticks.
    let mut turning = vec![x0];
    loop {
        let xi = *turning.last().unwrap();
        if xi.abs() <= fk || turning.len() > 1_000_000 {
            break;
        }
        let centre = fk * xi.signum();
        turning.push(2.0 * centre - xi);
    }
    let moving_segments = turning.len() - 1;
    Ok(times
        .iter()
        .map(|&t| {
            if t <= 0.0 {
                return State { x: x0, v: 0.0 };
            }
            let segment = (t / half).floor() as usize;
            if segment >= moving_segments {
                return State {
                    x: *turning.last().unwrap(),
                    v: 0.0,
                };
            }
            let xi = turning[segment];
            let centre = fk * xi.signum();
            let tau = t - segment as f64 * half;
            State {
                x: centre + (xi - centre) * (w * tau).cos(),
                v: -(xi - centre) * w * (w * tau).sin(),
            }
        })
        .collect())
}

/// Acceleration on a smooth stretch with friction sign `sign`.
fn acceleration(osc: &Oscillator, mass: f64, c: f64, force: f64, s: State, sign: f64) -> f64 {
    (force - osc.stiffness * s.x - c * s.v - osc.coulomb_force * sign) / mass
}

fn rk4(osc: &Oscillator, mass: f64, c: f64, force: f64, s: State, sign: f64, h: f64) -> State {
    let f = |st: State| (st.v, acceleration(osc, mass, c, force, st, sign));
    let (k1x, k1v) = f(s);
    let (k2x, k2v) = f(State {
        x: s.x + 0.5 * h * k1x,
        v: s.v + 0.5 * h * k1v,
    });
    let (k3x, k3v) = f(State {
        x: s.x + 0.5 * h * k2x,
        v: s.v + 0.5 * h * k2v,
    });
    let (k4x, k4v) = f(State {
        x: s.x + h * k3x,
        v: s.v + h * k3v,
    });
    State {
        x: s.x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
        v: s.v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
    }
}

/// Advances `state` by `h` under a constant applied force, handling velocity zeros
/// (stick or reverse) inside the step.
fn advance(osc: &Oscillator, mass: f64, c: f64, force: f64, mut state: State, mut h: f64) -> State {
    for _ in 0..8 {
        if h <= 0.0 {
            break;
        }
        if state.v == 0.0 {
            let net = force - osc.stiffness * state.x;
            if net.abs() <= osc.coulomb_force {
                return state; // stuck for the rest of the step (force and x are constant)
            }
        }
        let sign = if state.v != 0.0 {
            state.v.signum()
        } else {
            (force - osc.stiffness * state.x).signum()
        };
        let next = rk4(osc, mass, c, force, state, sign, h);
        if next.v * sign > 0.0 {
            return next;
        }
        // The velocity reaches zero inside the step: bisect on the step fraction.
        let (mut lo, mut hi) = (0.0f64, h);
        for _ in 0..64 {
            let mid = 0.5 * (lo + hi);
            if rk4(osc, mass, c, force, state, sign, mid).v * sign > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let at_zero = rk4(osc, mass, c, force, state, sign, hi);
        state = State {
            x: at_zero.x,
            v: 0.0,
        };
        h -= hi;
    }
    state
}

/// Internal integrator steps per sample period: the step is at most `1/(2000 f_n)`.
///
/// # Errors
/// [`FrictionError::Limit`] when one sample period would need more steps than
/// [`crate::params::limits::STEPS`] allows (a natural frequency far above the sample rate).
pub(crate) fn substeps_per_sample(osc: &Oscillator, sample_rate_hz: f64) -> Result<usize> {
    let ratio = 2000.0 * osc.natural_frequency_hz / sample_rate_hz;
    let n = crate::params::limits::STEPS.check(
        format!(
            "steps per sample: 2000 x natural-frequency-hz {} / sample-rate {}",
            super::show(osc.natural_frequency_hz),
            super::show(sample_rate_hz)
        ),
        crate::params::limits::saturating_count(ratio).max(1),
    )?;
    Ok(usize::try_from(n).unwrap_or(usize::MAX))
}

/// Integrates from `(x0, v0)` at `t = 0` and returns the state at `samples` instants
/// `k / sample_rate_hz`. Before each sample period `applied_force(t, state)` is called
/// once and its value held for the period. Internal steps are at most
/// `1/(2000 f_n)`.
///
/// # Errors
/// [`FrictionError::InvalidParameter`] for invalid parameters or a non-positive sample
/// rate; [`FrictionError::Limit`] when `samples` exceeds [`crate::params::limits::SAMPLES`] or
/// the steps exceed [`crate::params::limits::STEPS`] (checked before anything is allocated).
pub fn integrate(
    osc: &Oscillator,
    x0: f64,
    v0: f64,
    sample_rate_hz: f64,
    samples: usize,
    mut applied_force: impl FnMut(f64, State) -> f64,
) -> Result<Vec<State>> {
    osc.validate()?;
    if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
        return Err(FrictionError::InvalidParameter {
            name: "sample_rate",
            value: sample_rate_hz.to_string(),
            reason: "must be positive".into(),
        });
    }
    let (mass, c) = (osc.mass(), osc.viscous_coefficient());
    let period = 1.0 / sample_rate_hz;
    let substeps = substeps_per_sample(osc, sample_rate_hz)?;
    crate::params::limits::SAMPLES.check("samples", samples as u64)?;
    crate::params::limits::STEPS.check_product(
        "integration (samples x steps per sample)",
        &[samples as u64, substeps as u64],
    )?;
    let h = period / substeps as f64;
    let mut state = State { x: x0, v: v0 };
    let mut out = Vec::with_capacity(samples);
    for k in 0..samples {
        out.push(state);
        let force = applied_force(k as f64 * period, state);
        for _ in 0..substeps {
            state = advance(osc, mass, c, force, state, h);
        }
    }
    Ok(out)
}

/// How a free-decay record is made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// [`exact_free_decay`] (Coulomb only).
    Exact,
    /// [`integrate`] (any damping).
    Integrate,
}

/// A free-decay test as the thesis ran it: the mass held at `x0`, released, and
/// recorded by the LVT until well after it stops.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DecaySpec {
    /// The actuator.
    pub oscillator: Oscillator,
    /// Initial displacement.
    pub x0: f64,
    /// Samples per second (thesis compensator: 200).
    pub sample_rate_hz: f64,
    /// Time at rest before the release, s.
    pub hold_s: f64,
    /// Time recorded after the release, s; `None`: until the mass sticks (at most 40
    /// cycles) plus 1 s.
    pub duration_s: Option<f64>,
    /// Sensor noise RMS as a fraction of the first half-cycle's velocity amplitude
    /// `(x0 − F_C/k)·ω_n` (velocity) and of `x0` (displacement).
    pub noise_fraction: f64,
    /// Seed of the noise ([`Minstd`]).
    pub seed: u64,
    /// Exact or integrated.
    pub method: Method,
}

/// A sampled record: time, velocity and displacement.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DecayRecord {
    /// Sample times, s.
    pub time_s: Vec<f64>,
    /// Velocity (the LVT signal).
    pub velocity: Vec<f64>,
    /// Displacement.
    pub displacement: Vec<f64>,
}

/// Simulates a free-decay record.
///
/// # Errors
/// [`FrictionError::InvalidParameter`] for invalid parameters,
/// [`FrictionError::Limit`] when the record would exceed [`crate::params::limits::SAMPLES`] or
/// the integration [`crate::params::limits::STEPS`], [`FrictionError::NonFiniteResult`] when the
/// parameters are beyond double precision (the record is never returned with NaN or
/// infinite samples).
pub fn free_decay_record(spec: &DecaySpec) -> Result<DecayRecord> {
    let osc = &spec.oscillator;
    osc.validate()?;
    let bad = |name, value: f64, reason: &str| Err(FrictionError::invalid(name, value, reason));
    if !(spec.x0.is_finite() && spec.x0 != 0.0) {
        return bad("x0", spec.x0, "the initial displacement must be non-zero");
    }
    if !(spec.sample_rate_hz.is_finite() && spec.sample_rate_hz > 4.0 * osc.natural_frequency_hz) {
        return Err(FrictionError::invalid(
            "sample_rate",
            spec.sample_rate_hz,
            format!(
                "must exceed 4 x the natural frequency (natural-frequency-hz {})",
                osc.natural_frequency_hz
            ),
        ));
    }
    if !(spec.hold_s.is_finite() && spec.hold_s >= 0.0) {
        return bad("hold", spec.hold_s, "must be >= 0");
    }
    if !(spec.noise_fraction.is_finite() && spec.noise_fraction >= 0.0) {
        return bad("noise", spec.noise_fraction, "must be a fraction >= 0");
    }
    let period = 1.0 / osc.natural_frequency_hz;
    let duration = match spec.duration_s {
        Some(d) if !(d.is_finite() && d > 0.0) => return bad("duration", d, "must be positive"),
        Some(d) => d,
        None => {
            let fk = osc.coulomb_force / osc.stiffness;
            let half_cycles = if fk > 0.0 {
                ((spec.x0.abs() - fk) / (2.0 * fk)).max(0.0).ceil() + 1.0
            } else {
                f64::INFINITY
            };
            (half_cycles * 0.5 * period).min(40.0 * period) + 1.0
        }
    };
    // rate x (hold + duration) + 1, saturating: 1e9 s at 1e9 Hz is refused, not wrapped.
    let duration_from = match spec.duration_s {
        Some(_) => "--duration".to_string(),
        None => format!(
            "until the mass sticks at natural-frequency-hz {}",
            super::show(osc.natural_frequency_hz)
        ),
    };
    let samples = crate::params::limits::SAMPLES.check_product(
        format!(
            "samples: sample-rate {} x (hold {} + duration {} s, {duration_from}) + 1",
            super::show(spec.sample_rate_hz),
            super::show(spec.hold_s),
            super::show(duration)
        ),
        &[crate::params::limits::saturating_count(
            ((spec.hold_s + duration) * spec.sample_rate_hz).round() + 1.0,
        )],
    )?;
    let time_s: Vec<f64> = (0..samples)
        .map(|k| k as f64 / spec.sample_rate_hz)
        .collect();
    let states = match spec.method {
        Method::Exact => {
            let shifted: Vec<f64> = time_s.iter().map(|t| t - spec.hold_s).collect();
            exact_free_decay(osc, spec.x0, &shifted)?
        }
        Method::Integrate => {
            let held = (spec.hold_s * spec.sample_rate_hz).round() as usize;
            let mut s = vec![State { x: spec.x0, v: 0.0 }; held.min(samples)];
            s.extend(integrate(
                osc,
                spec.x0,
                0.0,
                spec.sample_rate_hz,
                samples - s.len(),
                |_, _| 0.0,
            )?);
            s
        }
    };
    if states.iter().any(|s| !(s.x.is_finite() && s.v.is_finite())) {
        return Err(non_finite(spec, "the simulated motion"));
    }
    let mut rng = Minstd::new(spec.seed);
    let v_amp = (spec.x0.abs() - osc.coulomb_force / osc.stiffness).max(0.0) * osc.omega();
    let (nv, nx) = (
        spec.noise_fraction * v_amp,
        spec.noise_fraction * spec.x0.abs(),
    );
    let mut record = DecayRecord {
        time_s,
        ..Default::default()
    };
    for s in &states {
        let (ev, ex) = if spec.noise_fraction > 0.0 {
            (rng.normal(), rng.normal())
        } else {
            (0.0, 0.0)
        };
        record.velocity.push(s.v + nv * ev);
        record.displacement.push(s.x + nx * ex);
    }
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    if record.time_s.is_empty()
        || !finite(&record.time_s)
        || !finite(&record.velocity)
        || !finite(&record.displacement)
    {
        return Err(non_finite(spec, "the simulated record (with its noise)"));
    }
    Ok(record)
}

/// [`FrictionError::NonFiniteResult`] naming every parameter of `spec`.
fn non_finite(spec: &DecaySpec, what: &'static str) -> FrictionError {
    FrictionError::NonFiniteResult {
        what,
        parameters: format!(
            "{}, x0 {}, sample-rate {}, hold {}, noise {}",
            spec.oscillator.describe(),
            super::show(spec.x0),
            super::show(spec.sample_rate_hz),
            super::show(spec.hold_s),
            super::show(spec.noise_fraction)
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decay() -> DecaySpec {
        DecaySpec {
            oscillator: Oscillator::coulomb(1.0, 1.5, 0.05),
            x0: 1.5,
            sample_rate_hz: 200.0,
            hold_s: 0.5,
            duration_s: None,
            noise_fraction: 0.0,
            seed: 1,
            method: Method::Exact,
        }
    }

    #[test]
    fn huge_records_are_refused_before_allocating() {
        for (rate, hold, duration) in [
            (1e9, 0.5, None),
            (200.0, 0.5, Some(1e9)),
            (200.0, 1e300, None),
            (1e300, 0.5, Some(1e300)),
        ] {
            for method in [Method::Exact, Method::Integrate] {
                let s = DecaySpec {
                    sample_rate_hz: rate,
                    hold_s: hold,
                    duration_s: duration,
                    method,
                    ..decay()
                };
                match free_decay_record(&s) {
                    Err(FrictionError::Limit(e)) => assert!(e.asked > e.allowed, "{e}"),
                    other => panic!("{rate} {hold} {duration:?}: {other:?}"),
                }
            }
        }
    }

    #[test]
    fn non_finite_motion_is_an_error_not_a_record() {
        // x0 near the largest double: the velocity x0·ω overflows.
        let s = DecaySpec {
            x0: 1e308,
            oscillator: Oscillator::coulomb(1.0, 100.0, 0.0),
            sample_rate_hz: 1000.0,
            duration_s: Some(1.0),
            ..decay()
        };
        match free_decay_record(&s) {
            Err(e @ FrictionError::NonFiniteResult { .. }) => {
                assert!(e.to_string().contains("x0 1e308"), "{e}")
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn exact_solution_follows_eqs_3_6_and_3_9() {
        let o = Oscillator::coulomb(1.0, 1.5, 0.05);
        let half = PI / o.omega();
        let s = exact_free_decay(&o, 1.0, &[half, 2.0 * half]).unwrap();
        assert!((s[0].x - (2.0 * 0.05 - 1.0)).abs() < 1e-14); // Eq. 3.6a
        assert!((s[1].x - (1.0 - 4.0 * 0.05)).abs() < 1e-14); // Eq. 3.9a
        assert!(s[0].v.abs() < 1e-14 && s[1].v.abs() < 1e-14);
        // It sticks once k|x| <= F_C: |x| = 1 - 2n·0.05 reaches 0 after 10 half-cycles.
        let late = exact_free_decay(&o, 1.0, &[100.0]).unwrap()[0];
        assert_eq!(late.v, 0.0);
        assert!(late.x.abs() <= 0.05 + 1e-12);
    }

    #[test]
    fn integrator_agrees_with_the_exact_solution_over_ten_cycles() {
        let o = Oscillator::coulomb(1.0, 1.5, 0.0591);
        let rate = 200.0;
        let samples = (10.0 / 1.5 * rate) as usize; // 10 cycles
        let numeric = integrate(&o, 3.0, 0.0, rate, samples, |_, _| 0.0).unwrap();
        let times: Vec<f64> = (0..samples).map(|k| k as f64 / rate).collect();
        let exact = exact_free_decay(&o, 3.0, &times).unwrap();
        let worst = numeric
            .iter()
            .zip(&exact)
            .map(|(a, b)| (a.x - b.x).abs().max((a.v - b.v).abs() / o.omega()))
            .fold(0.0, f64::max);
        assert!(worst < 1e-6, "largest difference {worst:e}");
    }

    #[test]
    fn integrator_sticks_and_breaks_away_under_force() {
        let o = Oscillator::coulomb(1.0, 1.5, 0.1);
        // Held at rest by friction: a force below F_C does nothing.
        let s = integrate(&o, 0.0, 0.0, 100.0, 50, |_, _| 0.09).unwrap();
        assert!(s.iter().all(|st| st.v == 0.0 && st.x == 0.0));
        // Above it, the mass moves to the new equilibrium side.
        let s = integrate(&o, 0.0, 0.0, 100.0, 50, |_, _| 0.5).unwrap();
        assert!(s[10].v > 0.0 && s[10].x > 0.0);
    }
}
