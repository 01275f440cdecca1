//! `era simulate fleet`'s flags checked and turned into the core's [`FleetSpec`].

use crate::args::FleetArgs;
use crate::config::Settings;
use crate::error::UsageError;
use era::sim::fleet::FleetSpec;
use era::sim::ModalSpec;
use std::path::PathBuf;

/// `era simulate fleet`: the fleet, its first record's time, and where it goes.
pub struct Fleet {
    /// The fleet.
    pub spec: FleetSpec,
    /// The first record's time, µs since the epoch (`--start`).
    pub start_us: i64,
    /// The folder written.
    pub out: PathBuf,
    /// The output switches.
    pub settings: Settings,
}

impl Fleet {
    /// The flags checked, each value under its flag's name.
    pub fn new(a: &FleetArgs) -> anyhow::Result<Self> {
        let spec = spec(a)?;
        let start_us =
            era_io::fleet::parse_time(&a.start).map_err(|m| UsageError(format!("--start: {m}")))?;
        Ok(Fleet {
            spec,
            start_us,
            out: a.out.clone(),
            settings: (&a.common).into(),
        })
    }
}

/// The core's spec from the flags; an out-of-range value names its flag.
fn spec(a: &FleetArgs) -> anyhow::Result<FleetSpec> {
    let (damping_min, damping_max) = crate::config::parse_range(&a.damping)?;
    for (flag, v) in [
        ("--record-length", a.record_length),
        ("--interval", a.interval),
        ("--sample-rate", a.sample_rate),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return crate::error::usage(format!("{flag} {v}: must be a positive number"));
        }
    }
    if a.record_length * a.sample_rate < 16.0 {
        return crate::error::usage(format!(
            "--record-length {} at --sample-rate {}: a record needs at least 16 samples",
            a.record_length, a.sample_rate
        ));
    }
    crate::config::check_noise(a.noise)?;
    let structure = ModalSpec {
        outputs: a.outputs,
        inputs: a.forces,
        modes: a.modes,
        fmin_hz: a.fmin,
        fmax_hz: a.fmax,
        damping_min,
        damping_max,
        collocated: false,
        seed: a.seed,
    };
    let mut s = FleetSpec::new(structure, a.records);
    s.record_s = a.record_length;
    s.interval_s = a.interval;
    s.sample_rate_hz = a.sample_rate;
    s.noise = a.noise;
    s.drift = a.drift;
    s.daily_c = a.daily;
    s.missing = a.missing;
    if let Some(text) = &a.damage {
        let parsed = text.split_once(':').and_then(|(r, l)| {
            Some((
                r.trim().parse::<usize>().ok()?,
                l.trim().parse::<f64>().ok()?,
            ))
        });
        match parsed {
            Some((r, loss)) if (1..=a.records).contains(&r) && (0.0..0.9).contains(&loss) => {
                s.damage = Some((r - 1, loss));
            }
            _ => {
                return crate::error::usage(format!(
                    "--damage {text}: expected R:LOSS, the first damaged record (1 to --records) and the stiffness loss (0 to 0.9), e.g. 7:0.05"
                ))
            }
        }
    }
    Ok(s)
}
