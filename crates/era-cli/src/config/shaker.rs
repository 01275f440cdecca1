//! `era simulate shaker`'s settings ([`Shaker`]), checked and turned into the core's
//! [`ShakerTest`].

use crate::args::{ExcitationArg, ShakerArgs};
use crate::config;
use crate::config::Settings;
use crate::error::usage;
use era::sim::shaker::{Excitation as Signal, ShakerTest};
use era::sim::ModalSpec;
use std::path::PathBuf;

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

/// The shakers' signal the flags ask for, `--band` checked against it.
fn excitation(a: &Shaker) -> anyhow::Result<Signal> {
    let band = match a.band.as_deref() {
        None => None,
        Some(text) => Some(config::parse_band(text).ok_or_else(|| {
            crate::error::UsageError(format!("--band {text}: expected LO..HI in Hz, e.g. 1..25"))
        })?),
    };
    if band.is_some()
        && !matches!(
            a.excitation,
            config::Excitation::BandLimited | config::Excitation::Sweep
        )
    {
        return usage(
            "--band sets band-limited noise or a sweep: add --excitation band-limited or sweep",
        );
    }
    let nyquist = a.sample_rate / 2.0;
    let excitation = match a.excitation {
        config::Excitation::White => Signal::White,
        config::Excitation::BandLimited => {
            let (lo_hz, hi_hz) = band.unwrap_or((0.0, nyquist));
            Signal::BandLimited { lo_hz, hi_hz }
        }
        config::Excitation::Burst => Signal::Burst {
            period_s: a.period,
            on_fraction: a.burst_on,
        },
        config::Excitation::Sweep => {
            let (lo_hz, hi_hz) = band.unwrap_or((a.fmin / 2.0, (1.2 * a.fmax).min(nyquist)));
            Signal::Sweep { lo_hz, hi_hz }
        }
        config::Excitation::Impact => Signal::Impact {
            period_s: a.period,
            width_s: a.pulse_width,
        },
    };
    Ok(excitation)
}

/// The shaker test the flags describe: the noise, the damping range and the signal
/// checked (the structure's sizes and ranges are checked against their limits by the
/// simulation, before anything is allocated).
pub fn test(a: &Shaker) -> anyhow::Result<ShakerTest> {
    config::check_noise(a.noise)?;
    let (damping_min, damping_max) = config::parse_range(&a.damping)?;
    let spec = ModalSpec {
        outputs: a.outputs,
        inputs: a.inputs,
        modes: a.modes,
        fmin_hz: a.fmin,
        fmax_hz: a.fmax,
        damping_min,
        damping_max,
        collocated: false,
        seed: a.seed,
    };
    let mut test = ShakerTest::new(spec, a.sample_rate, a.duration);
    test.excitation = excitation(a)?;
    test.quantity = a.quantity;
    test.noise = a.noise;
    Ok(test)
}
