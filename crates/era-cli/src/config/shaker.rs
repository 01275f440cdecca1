//! `era simulate shaker`'s flags checked and turned into the core's [`ShakerTest`].

use crate::config::{self, Shaker};
use crate::error::usage;
use era::sim::shaker::{Excitation, ShakerTest};
use era::sim::ModalSpec;

/// The shakers' signal the flags ask for, `--band` checked against it.
fn excitation(a: &Shaker) -> anyhow::Result<Excitation> {
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
        config::Excitation::White => Excitation::White,
        config::Excitation::BandLimited => {
            let (lo_hz, hi_hz) = band.unwrap_or((0.0, nyquist));
            Excitation::BandLimited { lo_hz, hi_hz }
        }
        config::Excitation::Burst => Excitation::Burst {
            period_s: a.period,
            on_fraction: a.burst_on,
        },
        config::Excitation::Sweep => {
            let (lo_hz, hi_hz) = band.unwrap_or((a.fmin / 2.0, (1.2 * a.fmax).min(nyquist)));
            Excitation::Sweep { lo_hz, hi_hz }
        }
        config::Excitation::Impact => Excitation::Impact {
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
