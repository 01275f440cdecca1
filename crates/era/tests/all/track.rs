//! Mode tracking over a fleet (`era::modal::track`): mode rows made from the truth of
//! `era::sim::fleet` plus noise, with a 2 % drift, modes missing from some records,
//! missing channels, spurious modes and a hand-made pair of modes that cross in
//! frequency.

use era::modal::track::{track, TrackMode, TrackOptions, TrackRecord, TrendUnit};
use era::sim::fleet::{fleet_record, FleetSpec};
use era::sim::ModalSpec;
use era::Complex64;
use proptest::prelude::*;
use std::collections::{BTreeMap, BTreeSet};

/// A small generator (xorshift), uniform in −1 … 1.
struct Noise(u64);

impl Noise {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

const RECORDS: usize = 16;
const CHANNELS: usize = 8;

/// The fleet's truth as records of modes, and per record and mode the true label (the
/// structure's mode, 6 and 7 the crossing pair, `None` for a spurious mode) and the true
/// frequency.
#[allow(clippy::type_complexity)]
fn fleet() -> (Vec<TrackRecord>, Vec<Vec<(Option<usize>, f64)>>) {
    let mut spec = FleetSpec::new(
        ModalSpec {
            fmin_hz: 1.0,
            fmax_hz: 20.0,
            seed: 11,
            ..ModalSpec::new(CHANNELS, 2, 6)
        },
        RECORDS,
    );
    spec.record_s = 1.0;
    spec.daily_c = 0.0;
    spec.missing = 0.25;
    let mut noise = Noise(0x2545_f491_4f6c_dd1d);
    let mut records = Vec::new();
    let mut labels = Vec::new();
    // The crossing pair: A rises from 30 to 34 Hz while B falls from 34 to 30, with
    // shapes far apart (MAC about 0.1).
    let shape_a: Vec<f64> = (0..CHANNELS)
        .map(|c| ((c + 1) as f64 * 0.7).sin())
        .collect();
    let shape_b: Vec<f64> = (0..CHANNELS)
        .map(|c| ((c + 1) as f64 * 2.1).cos())
        .collect();
    for i in 0..RECORDS {
        let r = fleet_record(&spec, i).unwrap();
        let truth = &r.record.truth;
        let mut modes = Vec::new();
        let mut label = Vec::new();
        let s = i as f64 / (RECORDS - 1) as f64;
        let mut all: Vec<(usize, f64, f64, Vec<f64>)> = truth
            .frequencies_hz
            .iter()
            .zip(&truth.damping_ratios)
            .zip(&truth.output_shapes)
            .enumerate()
            .map(|(m, ((&f, &z), phi))| (m, f, z, phi.clone()))
            .collect();
        all.push((6, 30.0 + 4.0 * s, 0.01, shape_a.clone()));
        all.push((7, 34.0 - 4.0 * s, 0.015, shape_b.clone()));
        for (m, f, z, phi) in all {
            // Mode 0 is missing from records 5 to 8 (a gap of four), every mode from
            // about one record in six.
            if (m == 0 && (5..=8).contains(&i)) || (i * 7 + m * 3) % 6 == 1 {
                continue;
            }
            let f_noisy = f * (1.0 + 0.001 * noise.next());
            modes.push(TrackMode {
                frequency_hz: f_noisy,
                damping_ratio: z * (1.0 + 0.1 * noise.next()),
                frequency_std_hz: Some(0.001 * f),
                damping_ratio_std: Some(0.1 * z),
                physical: true,
                shape: r
                    .channels
                    .iter()
                    .map(|&c| Complex64::new(phi[c] + 0.03 * noise.next(), 0.01 * noise.next()))
                    .collect(),
                channels: r.channels.iter().map(|c| format!("acc{c}")).collect(),
            });
            label.push((Some(m), f));
        }
        // A spurious mode, not physical, somewhere in the band.
        modes.push(TrackMode {
            frequency_hz: 5.0 + 10.0 * (0.5 + 0.5 * noise.next()),
            damping_ratio: 0.05,
            frequency_std_hz: None,
            damping_ratio_std: None,
            physical: false,
            shape: r
                .channels
                .iter()
                .map(|_| Complex64::new(noise.next(), noise.next()))
                .collect(),
            channels: r.channels.iter().map(|c| format!("acc{c}")).collect(),
        });
        label.push((None, 0.0));
        records.push(TrackRecord {
            id: format!("rec{i}"),
            time_s: Some(1.8e9 + r.time_s),
            modes,
        });
        labels.push(label);
    }
    (records, labels)
}

/// The least-squares slope of `y` against `x`, relative to the mean of `y`.
fn relative_slope(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    sxy / sxx / my
}

#[test]
fn one_track_per_true_mode_following_the_drift_across_gaps_and_a_crossing() {
    let (records, labels) = fleet();
    let found = track(&records, &TrackOptions::default()).unwrap();
    assert_eq!(found.unit, TrendUnit::Day);
    // Every mode of a true label in one track, distinct labels in distinct tracks.
    let mut tracks_of: BTreeMap<usize, BTreeSet<usize>> = BTreeMap::new();
    let mut rows_of: BTreeMap<usize, Vec<(f64, f64)>> = BTreeMap::new();
    for m in &found.members {
        let (label, f_true) = labels[m.record][m.mode];
        let label = label.expect("a spurious (not physical) mode was tracked by default");
        tracks_of.entry(label).or_default().insert(m.track);
        rows_of.entry(label).or_default().push((m.x, f_true));
    }
    assert_eq!(tracks_of.len(), 8);
    let all: BTreeSet<usize> = tracks_of.values().flatten().copied().collect();
    assert_eq!(all.len(), 8, "{tracks_of:?}");
    for (label, set) in &tracks_of {
        assert_eq!(set.len(), 1, "mode {label} split into tracks {set:?}");
    }
    assert_eq!(found.tracks.len(), 8);
    assert!(found.tracks.iter().all(|t| !t.sparse));
    // The gap of mode 0 bridged: one track holding every record that has the mode.
    let present = labels
        .iter()
        .filter(|l| l.iter().any(|m| m.0 == Some(0)))
        .count();
    let t0 = *tracks_of[&0].iter().next().unwrap();
    assert_eq!(found.tracks[t0 - 1].records, present);
    assert!(present <= RECORDS - 4);
    // The crossing pair did cross, and kept its identities.
    let a = *tracks_of[&6].iter().next().unwrap();
    let b = *tracks_of[&7].iter().next().unwrap();
    assert_ne!(a, b);
    // Each slope within 20 % of the truth's (the same regression on the true values).
    for (label, rows) in &rows_of {
        let (x, f): (Vec<f64>, Vec<f64>) = rows.iter().copied().unzip();
        let truth = relative_slope(&x, &f);
        let t = &found.tracks[*tracks_of[label].iter().next().unwrap() - 1];
        let got = t.trend.unwrap();
        assert!(
            (got.relative - truth).abs() <= 0.2 * truth.abs(),
            "mode {label}: slope {} per day, truth {truth}",
            got.relative
        );
        let se = got.relative_std_error.unwrap();
        assert!(se > 0.0 && se < 0.2 * truth.abs(), "mode {label}: {se}");
    }
    // The structure's drift: 2 % down over 15 hours.
    let drift = found.tracks[t0 - 1].trend.unwrap().relative * 15.0 / 24.0;
    assert!((drift + 0.02).abs() < 0.004, "{drift}");
}

#[test]
fn every_mode_tracked_with_all_modes_and_the_spurious_ones_sparse() {
    let (records, labels) = fleet();
    let mut options = TrackOptions::default();
    options.all_modes = true;
    let found = track(&records, &options).unwrap();
    let total: usize = records.iter().map(|r| r.modes.len()).sum();
    assert_eq!(found.members.len(), total);
    let sparse: BTreeSet<usize> = found
        .tracks
        .iter()
        .filter(|t| t.sparse)
        .map(|t| t.id)
        .collect();
    for m in &found.members {
        if labels[m.record][m.mode].0.is_none() {
            assert!(sparse.contains(&m.track), "a spurious mode in a full track");
        }
    }
    assert_eq!(found.tracks.len() - sparse.len(), 8);
}

#[test]
fn without_times_the_trend_is_per_record() {
    let (mut records, _) = fleet();
    records[3].time_s = None;
    let found = track(&records, &TrackOptions::default()).unwrap();
    assert_eq!(found.unit, TrendUnit::Record);
    assert!(found.origin_s.is_none());
    // rec10 comes after rec9 (ids compared as numbers).
    let pos = |id: &str| {
        found
            .order
            .iter()
            .position(|&r| records[r].id == id)
            .unwrap()
    };
    assert_eq!(pos("rec10"), pos("rec9") + 1);
}

#[test]
fn bad_records_are_named() {
    let (mut records, _) = fleet();
    records[2].id = records[1].id.clone();
    let e = track(&records, &TrackOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("rec1") && e.contains("twice"), "{e}");
    let (mut records, _) = fleet();
    records[0].modes[0].frequency_hz = f64::NAN;
    let e = track(&records, &TrackOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("rec0 mode 1"), "{e}");
    let mut options = TrackOptions::default();
    options.mac_min = 1.5;
    let e = track(&records, &options).unwrap_err().to_string();
    assert!(e.contains("mac"), "{e}");
}

/// A small random fleet: `n` records of up to 4 modes with random shapes on 4 channels.
fn random_fleet(n: usize, seed: u64) -> Vec<TrackRecord> {
    let mut g = Noise(seed | 1);
    let shapes: Vec<Vec<f64>> = (0..4).map(|_| (0..4).map(|_| g.next()).collect()).collect();
    (0..n)
        .map(|i| TrackRecord {
            id: format!("r{i}"),
            time_s: seed.is_multiple_of(2).then_some(600.0 * i as f64),
            modes: (0..4)
                .filter(|_| g.next() > -0.5)
                .collect::<Vec<usize>>()
                .into_iter()
                .map(|m| TrackMode {
                    frequency_hz: (2.0 + m as f64 * 1.5) * (1.0 + 0.03 * g.next()),
                    damping_ratio: 0.02,
                    frequency_std_hz: None,
                    damping_ratio_std: None,
                    physical: g.next() > -0.8,
                    shape: shapes[m]
                        .iter()
                        .map(|v| Complex64::new(v + 0.3 * g.next(), 0.0))
                        .collect(),
                    channels: (0..4).map(|c| format!("c{c}")).collect(),
                })
                .collect(),
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn no_mode_in_two_tracks_and_ids_stable_under_record_order(
        n in 1usize..14, seed in 1u64..u64::MAX, all in any::<bool>(), rotate in 0usize..14,
    ) {
        let records = random_fleet(n, seed);
        let mut options = TrackOptions::default();
        options.all_modes = all;
        let found = track(&records, &options).unwrap();
        // Each (record, mode) once; every eligible mode tracked; one mode per record
        // and track.
        let mut seen = BTreeSet::new();
        let mut per_track = BTreeSet::new();
        for m in &found.members {
            prop_assert!(seen.insert((m.record, m.mode)));
            prop_assert!(per_track.insert((m.record, m.track)));
        }
        let eligible: usize = records
            .iter()
            .map(|r| r.modes.iter().filter(|m| all || m.physical).count())
            .sum();
        prop_assert_eq!(seen.len(), eligible);
        for (k, t) in found.tracks.iter().enumerate() {
            prop_assert_eq!(t.id, k + 1);
            let count = found.members.iter().filter(|m| m.track == t.id).count();
            prop_assert_eq!(t.records, count);
        }
        // The same records in another order: the same tracks, by record id.
        let mut shuffled = records.clone();
        shuffled.rotate_left(rotate % n);
        shuffled.reverse();
        let again = track(&shuffled, &options).unwrap();
        let by_id = |f: &era::modal::track::Tracking, rs: &[TrackRecord]| {
            f.members
                .iter()
                .map(|m| ((rs[m.record].id.clone(), m.mode), m.track))
                .collect::<BTreeMap<_, _>>()
        };
        prop_assert_eq!(by_id(&found, &records), by_id(&again, &shuffled));
        prop_assert_eq!(&found.tracks, &again.tracks);
    }
}
