//! A simulated shaker test with exact truth: a seeded [`ModalStructure`] driven at its
//! inputs by shakers, its outputs sampled with sensor noise. It is the measured-like
//! data of the reliability study: the time histories go through era's own analyzer
//! (`era frf`, or `era identify --from-time`) exactly as a test's would.
//!
//! - **The structure** is [`ModalStructure::random`] (real normal modes, proportional
//!   damping), its acceleration (or velocity, displacement) response realised as a
//!   state-space model and held between samples (zero-order hold): the sampled outputs
//!   are exact samples of the continuous structure driven by a staircase force, so the
//!   discrete poles are exactly `e^(s_r T)` of the truth's.
//! - **The excitation** ([`Excitation`]) of each input, independent between inputs
//!   (uncorrelated forces, as a MIMO test needs): white or band-limited random, burst
//!   random, a linear sine sweep, or impacts (half-sine pulses). Sweeps and impacts
//!   are deterministic, so with several inputs each input is driven in its own segment
//!   of the record while the others rest (one shaker at a time, a roving hammer).
//! - **Sensor noise**: independent Gaussian noise on every channel, its RMS a fraction
//!   of that channel's RMS (inputs too: force gauges are sensors).
//!
//! The random numbers come from [`Minstd`] (seeded by the spec), so a seed gives the
//! same record everywhere.

use super::{Minstd, ModalSpec, ModalStructure};
use crate::data::frf::Quantity;
use crate::error::{EraError, Result};
use std::f64::consts::PI;

/// How a shaker drives its input.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Excitation {
    /// Gaussian white noise up to the Nyquist frequency.
    White,
    /// Gaussian noise with a flat spectrum from `lo` to `hi` Hz and nothing elsewhere.
    BandLimited {
        /// Lowest frequency, Hz.
        lo_hz: f64,
        /// Highest frequency, Hz.
        hi_hz: f64,
    },
    /// White noise switched on for `on_fraction` of each period of `period_s`, off for
    /// the rest, so that the response decays within the period.
    Burst {
        /// Length of one burst and its quiet tail, s.
        period_s: f64,
        /// Fraction of the period with noise on (0 < f ≤ 1).
        on_fraction: f64,
    },
    /// A linear sine sweep from `lo` to `hi` Hz over the input's segment.
    Sweep {
        /// Start frequency, Hz.
        lo_hz: f64,
        /// End frequency, Hz.
        hi_hz: f64,
    },
    /// Half-sine force pulses of `width_s`, one every `period_s` within the input's
    /// segment (their heights vary by ±20 %, as a hand's do).
    Impact {
        /// Time between hits, s.
        period_s: f64,
        /// Duration of one pulse, s (its spectrum reaches about 1.5/width Hz).
        width_s: f64,
    },
}

impl Excitation {
    /// The name used in files and messages.
    pub fn name(&self) -> &'static str {
        match self {
            Excitation::White => "white",
            Excitation::BandLimited { .. } => "band-limited",
            Excitation::Burst { .. } => "burst",
            Excitation::Sweep { .. } => "sweep",
            Excitation::Impact { .. } => "impact",
        }
    }
}

/// A shaker test to simulate.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct ShakerTest {
    /// The structure (its seed also seeds the excitation and the noise).
    pub structure: ModalSpec,
    /// What the outputs measure.
    pub quantity: Quantity,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Record length, s.
    pub duration_s: f64,
    /// The shakers' signal.
    pub excitation: Excitation,
    /// Sensor noise RMS as a fraction of each channel's RMS.
    pub noise: f64,
}

impl ShakerTest {
    /// A white-noise test of `structure`: acceleration, `sample_rate_hz`, `duration_s`,
    /// no noise.
    pub fn new(structure: ModalSpec, sample_rate_hz: f64, duration_s: f64) -> Self {
        ShakerTest {
            structure,
            quantity: Quantity::Acceleration,
            sample_rate_hz,
            duration_s,
            excitation: Excitation::White,
            noise: 0.0,
        }
    }
}

/// The record of a simulated test and its truth.
#[derive(Debug, Clone, PartialEq)]
pub struct ShakerRecord {
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Input (force) channels, one vector of samples each.
    pub inputs: Vec<Vec<f64>>,
    /// Output (response) channels.
    pub outputs: Vec<Vec<f64>>,
    /// The structure: the exact modes.
    pub truth: ModalStructure,
}

/// The most samples per channel a simulation writes (about 2.3 days at 2 kHz).
pub const MAX_SHAKER_SAMPLES: usize = 400_000_000;

/// Simulates `test`.
///
/// # Errors
/// [`EraError::InvalidParameter`] naming the parameter for a non-positive sample rate or
/// duration, a record of fewer than 16 samples or more than [`MAX_SHAKER_SAMPLES`], a
/// band or sweep outside `0 … fs/2`, a burst fraction outside `(0, 1]`, a period or pulse
/// width that does not fit, modes at or above the Nyquist frequency, or a noise
/// fraction outside [`super::check_noise`]'s range; the structure's own errors.
pub fn simulate_shaker_test(test: &ShakerTest) -> Result<ShakerRecord> {
    let bad = |name: &'static str, value: String, reason: &str| EraError::InvalidParameter {
        name,
        value,
        reason: reason.into(),
    };
    let fs = test.sample_rate_hz;
    if !(fs.is_finite() && fs > 0.0) {
        return Err(bad(
            "sample_rate",
            fs.to_string(),
            "must be a positive rate in Hz",
        ));
    }
    if !(test.duration_s.is_finite() && test.duration_s > 0.0) {
        return Err(bad(
            "duration",
            test.duration_s.to_string(),
            "must be a positive time in s",
        ));
    }
    let samples_f = (test.duration_s * fs).round();
    if !(16.0..=MAX_SHAKER_SAMPLES as f64).contains(&samples_f) {
        return Err(bad(
            "duration",
            test.duration_s.to_string(),
            &format!(
                "{samples_f} samples at {fs} Hz: a record needs 16 to {MAX_SHAKER_SAMPLES} samples"
            ),
        ));
    }
    let n = samples_f as usize;
    super::check_noise(crate::params::Naming::Flag, test.noise)?;
    let nyquist = fs / 2.0;
    if test.structure.fmax_hz >= nyquist {
        return Err(bad(
            "fmax",
            test.structure.fmax_hz.to_string(),
            &format!("the modes must lie below the Nyquist frequency {nyquist} Hz"),
        ));
    }
    let period_check = |period_s: f64, what: &str| -> Result<()> {
        if !(period_s.is_finite() && period_s * fs >= 2.0 && period_s <= test.duration_s) {
            return Err(bad(
                "period",
                period_s.to_string(),
                &format!("the {what} period must span at least 2 samples and fit in the record"),
            ));
        }
        Ok(())
    };
    match test.excitation {
        Excitation::White => {}
        Excitation::BandLimited { lo_hz, hi_hz } | Excitation::Sweep { lo_hz, hi_hz } => {
            if !(lo_hz.is_finite()
                && hi_hz.is_finite()
                && 0.0 <= lo_hz
                && lo_hz < hi_hz
                && hi_hz <= nyquist)
            {
                return Err(bad(
                    "band",
                    format!("{lo_hz}..{hi_hz}"),
                    &format!("need 0 <= LO < HI <= {nyquist} Hz (the Nyquist frequency)"),
                ));
            }
        }
        Excitation::Burst {
            period_s,
            on_fraction,
        } => {
            period_check(period_s, "burst")?;
            if !(on_fraction > 0.0 && on_fraction <= 1.0) {
                return Err(bad(
                    "burst_on",
                    on_fraction.to_string(),
                    "the fraction of each period with noise on must be in (0, 1]",
                ));
            }
        }
        Excitation::Impact { period_s, width_s } => {
            period_check(period_s, "impact")?;
            if !(width_s.is_finite() && width_s * fs >= 1.0 && width_s < period_s) {
                return Err(bad(
                    "pulse_width",
                    width_s.to_string(),
                    "a pulse must span at least one sample and be shorter than the period",
                ));
            }
        }
    }
    let truth = ModalStructure::random(&test.structure)?;
    let seed = test.structure.seed.wrapping_mul(7919).wrapping_add(17);
    drive(test, truth, n, seed)
}

/// `test` on the structure `truth` (already checked against `test`'s rate): `n`
/// samples of each output, the excitation and the noise drawn from `seed`.
pub(crate) fn drive(
    test: &ShakerTest,
    truth: ModalStructure,
    n: usize,
    seed: u64,
) -> Result<ShakerRecord> {
    let fs = test.sample_rate_hz;
    let p = truth.inputs();
    crate::params::limits::VALUES.check_product(
        "samples x channels",
        &[n as u64, (p + truth.outputs()) as u64],
    )?;
    let model = truth.state_space(test.quantity).c2d(1.0 / fs)?;
    // The excitation draws from a stream of its own, so that a seed gives the same
    // structure whatever the excitation.
    let mut rng = Minstd::new(seed);
    let mut inputs: Vec<Vec<f64>> = (0..p)
        .map(|j| excite(&test.excitation, j, p, n, fs, &mut rng))
        .collect();
    let mut outputs = super::time_response(&model, &inputs)?;
    if test.noise > 0.0 {
        for channel in inputs.iter_mut().chain(outputs.iter_mut()) {
            let rms = (channel.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
            for v in channel.iter_mut() {
                *v += test.noise * rms * rng.normal();
            }
        }
    }
    Ok(ShakerRecord {
        sample_rate_hz: fs,
        inputs,
        outputs,
        truth,
    })
}

/// Input `j` of `p`: `n` samples of the excitation.
fn excite(
    excitation: &Excitation,
    j: usize,
    p: usize,
    n: usize,
    fs: f64,
    rng: &mut Minstd,
) -> Vec<f64> {
    // Deterministic signals drive one input at a time: input j owns the j-th segment.
    let segment = (n * j / p)..(n * (j + 1) / p);
    match *excitation {
        Excitation::White => (0..n).map(|_| rng.normal()).collect(),
        Excitation::BandLimited { lo_hz, hi_hz } => band_limited(n, fs, lo_hz, hi_hz, rng),
        Excitation::Burst {
            period_s,
            on_fraction,
        } => {
            let period = (period_s * fs).round().max(2.0) as usize;
            let on = ((on_fraction * period as f64).round() as usize).clamp(1, period);
            (0..n)
                .map(|k| {
                    let v = rng.normal();
                    if k % period < on {
                        v
                    } else {
                        0.0
                    }
                })
                .collect()
        }
        Excitation::Sweep { lo_hz, hi_hz } => {
            let mut u = vec![0.0; n];
            let length = (segment.end - segment.start) as f64 / fs;
            for k in segment.clone() {
                let t = (k - segment.start) as f64 / fs;
                // Phase of a linear chirp: 2π (f0 t + (f1 − f0) t²/(2T)).
                let phase = 2.0 * PI * (lo_hz * t + (hi_hz - lo_hz) * t * t / (2.0 * length));
                u[k] = phase.sin();
            }
            u
        }
        Excitation::Impact { period_s, width_s } => {
            let mut u = vec![0.0; n];
            let period = (period_s * fs).round() as usize;
            let width = width_s * fs;
            let mut start = segment.start;
            while start + width.ceil() as usize <= segment.end {
                let height = 1.0 + 0.2 * (2.0 * rng.uniform() - 1.0);
                let mut k = 0usize;
                while (k as f64) < width && start + k < segment.end {
                    u[start + k] = height * (PI * (k as f64 + 0.5) / width).sin();
                    k += 1;
                }
                start += period.max(1);
            }
            u
        }
    }
}

/// Gaussian noise with a flat spectrum from `lo` to `hi` Hz: white noise, its FFT zeroed
/// outside the band, scaled back to unit RMS.
fn band_limited(n: usize, fs: f64, lo_hz: f64, hi_hz: f64, rng: &mut Minstd) -> Vec<f64> {
    let (forward, inverse) = crate::linalg::fft::real_fft_plans(n);
    let mut u: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
    let mut spectrum = forward.make_output_vec();
    forward
        .process(&mut u, &mut spectrum)
        .expect("buffers sized by the plan");
    let df = fs / n as f64;
    for (k, v) in spectrum.iter_mut().enumerate() {
        let f = k as f64 * df;
        if f < lo_hz || f > hi_hz {
            *v = num_complex::Complex64::new(0.0, 0.0);
        }
    }
    // A real inverse needs real 0 Hz and Nyquist lines.
    spectrum[0].im = 0.0;
    if n.is_multiple_of(2) {
        if let Some(last) = spectrum.last_mut() {
            last.im = 0.0;
        }
    }
    inverse
        .process(&mut spectrum, &mut u)
        .expect("buffers sized by the plan");
    let rms = (u.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
    if rms > 0.0 {
        for v in &mut u {
            *v /= rms;
        }
    }
    u
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> ModalSpec {
        ModalSpec {
            collocated: false,
            fmin_hz: 1.9,
            fmax_hz: 20.0,
            ..ModalSpec::new(3, 2, 4)
        }
    }

    /// Noise-free white noise through the ZOH model: the outputs are the structure's
    /// discrete response, so an output sample equals the convolution of the inputs with
    /// the model's Markov parameters.
    #[test]
    fn the_record_is_the_discrete_response_of_the_truth() {
        let test = ShakerTest::new(spec(), 64.0, 4.0);
        let r = simulate_shaker_test(&test).unwrap();
        assert_eq!(r.inputs.len(), 2);
        assert_eq!(r.outputs.len(), 3);
        assert_eq!(r.outputs[0].len(), 256);
        let model = r
            .truth
            .state_space(Quantity::Acceleration)
            .c2d(1.0 / 64.0)
            .unwrap();
        // y_k = D u_k + Σ_{m≥1} C A^(m−1) B u_(k−m), checked at k = 40.
        let k = 40;
        let mut expected = [0.0; 3];
        for (i, e) in expected.iter_mut().enumerate() {
            for j in 0..2 {
                *e += model.d[(i, j)] * r.inputs[j][k];
            }
        }
        let mut x = faer::Mat::<f64>::zeros(model.states(), 2);
        for j in 0..2 {
            for s in 0..model.states() {
                x[(s, j)] = model.b[(s, j)];
            }
        }
        for m in 1..=k {
            let cx = &model.c * &x;
            for (i, e) in expected.iter_mut().enumerate() {
                for j in 0..2 {
                    *e += cx[(i, j)] * r.inputs[j][k - m];
                }
            }
            x = &model.a * &x;
        }
        for (i, (output, e)) in r.outputs.iter().zip(expected).enumerate() {
            let scale = output.iter().map(|v| v.abs()).fold(0.0, f64::max);
            assert!(
                (output[k] - e).abs() <= 1e-10 * scale,
                "{i}: {} vs {e}",
                output[k]
            );
        }
    }

    #[test]
    fn band_limited_noise_has_no_power_outside_its_band() {
        let mut rng = Minstd::new(3);
        let u = band_limited(4096, 64.0, 5.0, 10.0, &mut rng);
        let rms = (u.iter().map(|v| v * v).sum::<f64>() / 4096.0).sqrt();
        assert!((rms - 1.0).abs() < 1e-12);
        let mut planner = realfft::RealFftPlanner::<f64>::new();
        let fft = planner.plan_fft_forward(4096);
        let mut x = u.clone();
        let mut s = fft.make_output_vec();
        fft.process(&mut x, &mut s).unwrap();
        let df = 64.0 / 4096.0;
        let (mut inside, mut outside) = (0.0, 0.0);
        for (k, v) in s.iter().enumerate() {
            let f = k as f64 * df;
            if (5.0..=10.0).contains(&f) {
                inside += v.norm_sqr();
            } else {
                outside += v.norm_sqr();
            }
        }
        assert!(outside <= 1e-20 * inside, "{outside} vs {inside}");
    }

    #[test]
    fn sweeps_and_impacts_drive_one_input_at_a_time() {
        for excitation in [
            Excitation::Sweep {
                lo_hz: 1.0,
                hi_hz: 25.0,
            },
            Excitation::Impact {
                period_s: 2.0,
                width_s: 0.05,
            },
        ] {
            let test = ShakerTest {
                excitation,
                ..ShakerTest::new(spec(), 64.0, 20.0)
            };
            let r = simulate_shaker_test(&test).unwrap();
            let n = r.inputs[0].len();
            assert!(
                r.inputs[0][n / 2..].iter().all(|v| *v == 0.0),
                "{excitation:?}"
            );
            assert!(
                r.inputs[1][..n / 2].iter().all(|v| *v == 0.0),
                "{excitation:?}"
            );
            assert!(r.inputs[0][..n / 2].iter().any(|v| *v != 0.0));
            assert!(r.inputs[1][n / 2..].iter().any(|v| *v != 0.0));
        }
    }

    #[test]
    fn bad_parameters_are_named() {
        let cases: Vec<(ShakerTest, &str)> = vec![
            (ShakerTest::new(spec(), 0.0, 10.0), "sample_rate"),
            (ShakerTest::new(spec(), 64.0, -1.0), "duration"),
            (ShakerTest::new(spec(), 64.0, 1e12), "duration"),
            (ShakerTest::new(spec(), 30.0, 10.0), "fmax"),
            (
                ShakerTest {
                    excitation: Excitation::BandLimited {
                        lo_hz: 10.0,
                        hi_hz: 40.0,
                    },
                    ..ShakerTest::new(spec(), 64.0, 10.0)
                },
                "band",
            ),
            (
                ShakerTest {
                    excitation: Excitation::Burst {
                        period_s: 2.0,
                        on_fraction: 0.0,
                    },
                    ..ShakerTest::new(spec(), 64.0, 10.0)
                },
                "burst_on",
            ),
        ];
        for (test, name) in cases {
            let e = simulate_shaker_test(&test).unwrap_err().to_string();
            assert!(e.contains(name), "{name}: {e}");
        }
    }
}
