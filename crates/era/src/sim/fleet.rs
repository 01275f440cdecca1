//! A fleet of output-only records of one monitored structure, with exact truth: what a
//! bridge or a wind turbine gives a monitoring system, one record every interval.
//!
//! - **One structure** ([`ModalStructure::random`] of the spec's seed), its forces
//!   unmeasured white noise ([`super::shaker`]), each record driven and noised by a seed
//!   of its own.
//! - **Temperature**: a linear trend over the fleet plus a daily cycle of ±`daily_c`
//!   (°C); every natural frequency follows it, `f = f₀ (1 − α (T − T₀))`, with `α` set so
//!   that the trend alone moves the frequencies by `drift` over the fleet (stiffness
//!   falls as the structure warms: a trend up in temperature is a drift down in
//!   frequency).
//! - **Damage**: from record `damage_from` on, a stiffness loss lowers each mode's
//!   frequency by `√(1 − loss·w_r)`, with a weight `w_r` in 0.2 … 1 drawn per mode (a
//!   local loss touches the modes unequally).
//! - **Missing channels**: in a record, each output is missing with probability
//!   `missing`; such a record lists the channels it holds (at least two).
//!
//! Records are made one at a time ([`fleet_record`]), so a fleet of thousands never sits
//! in memory.

use super::shaker::{ShakerRecord, ShakerTest};
use super::{Minstd, ModalSpec, ModalStructure};
use crate::error::{EraError, Result};

/// How to draw a fleet.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct FleetSpec {
    /// The structure (its seed seeds everything else too) and its unmeasured forces.
    pub structure: ModalSpec,
    /// Records in the fleet.
    pub records: usize,
    /// Length of a record, s.
    pub record_s: f64,
    /// Time from one record's start to the next's, s.
    pub interval_s: f64,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Sensor noise RMS as a fraction of each channel's RMS.
    pub noise: f64,
    /// Relative fall of every frequency over the fleet from the temperature trend.
    pub drift: f64,
    /// Amplitude of the daily temperature cycle, °C (the trend spans 10 °C).
    pub daily_c: f64,
    /// The first damaged record and the stiffness loss (a fraction), if any.
    pub damage: Option<(usize, f64)>,
    /// Probability that a record lacks a given output channel.
    pub missing: f64,
}

impl FleetSpec {
    /// `records` records of 10 minutes an hour apart at 64 Hz of `structure`: 2 %
    /// noise, a 2 % drift, a daily cycle of ±3 °C, no damage, no missing channel.
    pub fn new(structure: ModalSpec, records: usize) -> Self {
        FleetSpec {
            structure,
            records,
            record_s: 600.0,
            interval_s: 3600.0,
            sample_rate_hz: 64.0,
            noise: 0.02,
            drift: 0.02,
            daily_c: 3.0,
            damage: None,
            missing: 0.0,
        }
    }

    fn check(&self) -> Result<()> {
        let bad = |name: &'static str, value: String, reason: &str| {
            Err(EraError::InvalidParameter {
                name,
                value,
                reason: reason.into(),
            })
        };
        if self.records == 0 || self.records > MAX_FLEET_RECORDS {
            return bad(
                "records",
                self.records.to_string(),
                &format!("must be from 1 to {MAX_FLEET_RECORDS}"),
            );
        }
        if !(self.interval_s.is_finite() && self.interval_s >= self.record_s) {
            return bad(
                "interval",
                self.interval_s.to_string(),
                "must be at least the record's length",
            );
        }
        if !(self.drift.is_finite() && (0.0..0.5).contains(&self.drift.abs())) {
            return bad(
                "drift",
                self.drift.to_string(),
                "must be a fraction below 0.5",
            );
        }
        if !(self.daily_c.is_finite() && self.daily_c.abs() <= 50.0) {
            return bad("daily", self.daily_c.to_string(), "must be within ±50 °C");
        }
        if let Some((from, loss)) = self.damage {
            if from >= self.records || !(0.0..0.9).contains(&loss) {
                return bad(
                    "damage",
                    format!("{from}:{loss}"),
                    "needs a record of the fleet and a loss from 0 to 0.9",
                );
            }
        }
        if !(0.0..=1.0).contains(&self.missing) {
            return bad(
                "missing",
                self.missing.to_string(),
                "must be a probability from 0 to 1",
            );
        }
        Ok(())
    }
}

/// The most records a fleet may have.
pub(crate) const MAX_FLEET_RECORDS: usize = 1_000_000;

/// Temperature span of the trend over the fleet, °C.
const TREND_C: f64 = 10.0;

/// One record of a fleet and its truth.
#[derive(Debug, Clone, PartialEq)]
pub struct FleetRecord {
    /// Index in the fleet.
    pub index: usize,
    /// Start time from the fleet's start, s.
    pub time_s: f64,
    /// Temperature during the record, °C.
    pub temperature_c: f64,
    /// The output channels the record holds (0-based among the structure's).
    pub channels: Vec<usize>,
    /// The record, its outputs only those of `channels`; its inputs are the unmeasured
    /// forces (for checks), its truth the structure as it was during the record.
    pub record: ShakerRecord,
}

/// Record `index` of the fleet `spec`.
///
/// # Errors
/// [`EraError::InvalidParameter`] for a spec out of range or an index past the fleet,
/// and the shaker simulation's errors.
pub fn fleet_record(spec: &FleetSpec, index: usize) -> Result<FleetRecord> {
    spec.check()?;
    if index >= spec.records {
        return Err(EraError::InvalidParameter {
            name: "index",
            value: index.to_string(),
            reason: format!("the fleet has {} records", spec.records).into(),
        });
    }
    let base = ModalStructure::random(&spec.structure)?;
    let mut g = Minstd::new(spec.structure.seed.wrapping_mul(104_729).wrapping_add(7));
    let weights: Vec<f64> = (0..base.frequencies_hz.len())
        .map(|_| 0.2 + 0.8 * g.uniform())
        .collect();
    let time_s = index as f64 * spec.interval_s;
    let fraction = if spec.records > 1 {
        index as f64 / (spec.records - 1) as f64
    } else {
        0.0
    };
    let day = 2.0 * std::f64::consts::PI * (time_s + 0.5 * spec.record_s) / 86_400.0;
    let temperature_c = 10.0 + TREND_C * fraction + spec.daily_c * day.sin();
    // The trend alone moves the frequencies by `drift`: α = drift / TREND_C.
    let factor = 1.0 - spec.drift / TREND_C * (temperature_c - 10.0);
    let mut truth = base.clone();
    for (m, f) in truth.frequencies_hz.iter_mut().enumerate() {
        *f *= factor;
        if let Some((from, loss)) = spec.damage {
            if index >= from {
                *f *= (1.0 - loss * weights[m]).sqrt();
            }
        }
    }
    let mut test = ShakerTest::new(spec.structure.clone(), spec.sample_rate_hz, spec.record_s);
    test.noise = spec.noise;
    let n = (spec.record_s * spec.sample_rate_hz).round() as usize;
    if truth
        .frequencies_hz
        .iter()
        .any(|&f| f >= spec.sample_rate_hz / 2.0)
        || n < 16
    {
        return Err(EraError::InvalidParameter {
            name: "sample_rate",
            value: spec.sample_rate_hz.to_string(),
            reason: "the modes must lie below the Nyquist frequency and a record hold 16 samples"
                .into(),
        });
    }
    let seed = spec
        .structure
        .seed
        .wrapping_mul(7919)
        .wrapping_add(17 + 1_000_003 * index as u64);
    let mut record = super::shaker::drive(&test, truth, n, seed)?;
    let q = record.outputs.len();
    let mut pick = Minstd::new(seed ^ 0x9e37_79b9);
    let mut channels: Vec<usize> = (0..q).filter(|_| pick.uniform() >= spec.missing).collect();
    if channels.len() < 2.min(q) {
        channels = (0..2.min(q)).collect();
    }
    let mut kept = Vec::with_capacity(channels.len());
    for (c, out) in std::mem::take(&mut record.outputs).into_iter().enumerate() {
        if channels.contains(&c) {
            kept.push(out);
        }
    }
    record.outputs = kept;
    Ok(FleetRecord {
        index,
        time_s,
        temperature_c,
        channels,
        record,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> FleetSpec {
        let mut s = FleetSpec::new(
            ModalSpec {
                fmin_hz: 1.0,
                fmax_hz: 20.0,
                seed: 11,
                ..ModalSpec::new(8, 2, 6)
            },
            12,
        );
        s.record_s = 60.0;
        s
    }

    #[test]
    fn the_frequencies_follow_the_trend_and_fall_after_the_damage() {
        let mut s = spec();
        s.daily_c = 0.0;
        let first = fleet_record(&s, 0).unwrap();
        let last = fleet_record(&s, 11).unwrap();
        for (a, b) in first
            .record
            .truth
            .frequencies_hz
            .iter()
            .zip(&last.record.truth.frequencies_hz)
        {
            assert!((b / a - (1.0 - s.drift)).abs() < 1e-12);
        }
        s.damage = Some((6, 0.1));
        let before = fleet_record(&s, 5).unwrap();
        let after = fleet_record(&s, 6).unwrap();
        let undamaged = fleet_record(
            &FleetSpec {
                damage: None,
                ..s.clone()
            },
            6,
        )
        .unwrap();
        assert_eq!(
            before.record.truth,
            fleet_record(&spec_no_daily(), 5).unwrap().record.truth
        );
        for (d, u) in after
            .record
            .truth
            .frequencies_hz
            .iter()
            .zip(&undamaged.record.truth.frequencies_hz)
        {
            let ratio = d / u;
            assert!(
                ratio < (1.0 - 0.1 * 0.2f64).sqrt() + 1e-12 && ratio >= (0.9f64).sqrt() - 1e-12
            );
        }
        // The same index gives the same record; another index, another draw.
        assert_eq!(fleet_record(&s, 3).unwrap(), fleet_record(&s, 3).unwrap());
        assert_ne!(
            fleet_record(&s, 3).unwrap().record.outputs[0][..10],
            fleet_record(&s, 4).unwrap().record.outputs[0][..10]
        );
    }

    fn spec_no_daily() -> FleetSpec {
        let mut s = spec();
        s.daily_c = 0.0;
        s
    }

    #[test]
    fn missing_channels_are_left_out_and_listed() {
        let mut s = spec();
        s.missing = 0.3;
        let mut short = 0;
        for i in 0..12 {
            let r = fleet_record(&s, i).unwrap();
            assert_eq!(r.channels.len(), r.record.outputs.len());
            assert!(r.channels.len() >= 2 && r.channels.windows(2).all(|w| w[0] < w[1]));
            short += usize::from(r.channels.len() < 8);
        }
        assert!(short >= 6, "{short} of 12 records lack a channel");
    }

    #[test]
    fn a_bad_spec_is_named() {
        let mut s = spec();
        s.damage = Some((12, 0.1));
        assert!(fleet_record(&s, 0)
            .unwrap_err()
            .to_string()
            .contains("damage"));
        let s = spec();
        assert!(fleet_record(&s, 12)
            .unwrap_err()
            .to_string()
            .contains("index"));
        let mut s = spec();
        s.interval_s = 10.0;
        assert!(fleet_record(&s, 0)
            .unwrap_err()
            .to_string()
            .contains("interval"));
    }
}
