//! Output-only identification on simulated records with exact truth: the records of
//! `era simulate shaker` with the forces left out.

use era::identify::oma::{oma, OmaMethod, OmaOptions};
use era::sim::shaker::{simulate_shaker_test, ShakerRecord, ShakerTest};
use era::sim::ModalSpec;

fn record(seed: u64, duration_s: f64) -> ShakerRecord {
    let mut spec = ModalSpec::new(8, 2, 10);
    spec.fmin_hz = 1.0;
    spec.fmax_hz = 20.0;
    spec.seed = seed;
    let mut test = ShakerTest::new(spec, 64.0, duration_s);
    test.noise = 0.02;
    simulate_shaker_test(&test).unwrap()
}

/// For each true mode, the physical mode matched to it (one to one, the closest pairs
/// within 1 % in frequency first), and the physical modes matched to none.
fn matched(found: &era::Oma, truth: &era::sim::ModalStructure) -> (Vec<Option<usize>>, usize) {
    let id = &found.identification;
    let mut pairs = Vec::new();
    for (t, &f) in truth.frequencies_hz.iter().enumerate() {
        for (m, mode) in id.modal.modes.iter().enumerate() {
            let d = (mode.frequency_hz - f).abs() / f;
            if id.quality[m].physical && d < 0.01 {
                pairs.push((d, t, m));
            }
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut pick = vec![None; truth.frequencies_hz.len()];
    let mut used = vec![false; id.modal.modes.len()];
    for (_, t, m) in pairs {
        if pick[t].is_none() && !used[m] {
            pick[t] = Some(m);
            used[m] = true;
        }
    }
    let spurious = (0..used.len())
        .filter(|&m| id.quality[m].physical && !used[m])
        .count();
    (pick, spurious)
}

#[test]
fn ssi_cov_finds_the_modes_of_an_output_only_record_with_no_spurious_one() {
    let rec = record(1, 600.0);
    let outputs: Vec<&[f64]> = rec.outputs.iter().map(Vec::as_slice).collect();
    let found = oma(&[outputs.as_slice()], &OmaOptions::new(64.0)).unwrap();
    let (pick, spurious) = matched(&found, &rec.truth);
    let hits = pick.iter().flatten().count();
    // Two of the ten modes lie 0.06 % apart (13.898 and 13.907 Hz): one mode stands for both.
    assert!(hits >= 9, "found {hits} of 10: {pick:?}");
    assert_eq!(spurious, 0);
    // Every physical mode carries standard deviations, and the truth lies within a
    // few of them.
    for (t, p) in pick.iter().enumerate() {
        let Some(m) = *p else { continue };
        let q = &found.identification.quality[m];
        let mode = &found.identification.modal.modes[m];
        let (fs, zs) = (q.frequency_std_hz.unwrap(), q.damping_ratio_std.unwrap());
        assert!(fs > 0.0 && zs > 0.0);
        let close_pair = (13.8..14.0).contains(&rec.truth.frequencies_hz[t]);
        if !close_pair {
            assert!((mode.frequency_hz - rec.truth.frequencies_hz[t]).abs() < 5.0 * fs);
            assert!((mode.damping_ratio - rec.truth.damping_ratios[t]).abs() < 5.0 * zs);
        }
    }
    assert_eq!(found.references, (0..8).collect::<Vec<_>>());
    assert!(found.lags >= 64);
}

#[test]
fn next_era_and_ssi_cov_agree_on_a_record() {
    let rec = record(4, 300.0);
    let outputs: Vec<&[f64]> = rec.outputs.iter().map(Vec::as_slice).collect();
    let mut options = OmaOptions::new(64.0);
    options.blocks = 1;
    options.era.order = era::Order::Fixed(40);
    let ssi = oma(&[outputs.as_slice()], &options).unwrap();
    options.method = OmaMethod::NextEra;
    let next = oma(&[outputs.as_slice()], &options).unwrap();
    // Without blocks, no standard deviations.
    assert!(ssi.spread.iter().all(Option::is_none));
    // The strongest modes (the lowest) agree to a fraction of their bandwidth.
    for f in [1.0006, 1.4260, 3.4903] {
        let near = |o: &era::Oma| {
            o.identification
                .modal
                .modes
                .iter()
                .min_by(|a, b| {
                    (a.frequency_hz - f)
                        .abs()
                        .total_cmp(&(b.frequency_hz - f).abs())
                })
                .unwrap()
                .clone()
        };
        let (a, b) = (near(&ssi), near(&next));
        assert!(
            (a.frequency_hz - b.frequency_hz).abs() < 0.2 * a.damping_ratio * f,
            "{f}: {} vs {}",
            a.frequency_hz,
            b.frequency_hz
        );
    }
}

#[test]
fn records_are_pooled_and_bad_ones_named() {
    let a = record(7, 200.0);
    let b = record(7, 200.0);
    let ra: Vec<&[f64]> = a.outputs.iter().map(Vec::as_slice).collect();
    let rb: Vec<&[f64]> = b.outputs[..7].iter().map(Vec::as_slice).collect();
    let e = oma(&[ra.as_slice(), rb.as_slice()], &OmaOptions::new(64.0)).unwrap_err();
    assert!(e.to_string().contains("channels of record 2"), "{e}");
    let mut options = OmaOptions::new(64.0);
    options.references = Some(vec![8]);
    let e = oma(&[ra.as_slice()], &options).unwrap_err();
    assert!(e.to_string().contains("not among the 8 outputs"), "{e}");
    let mut options = OmaOptions::new(64.0);
    options.lags = Some(20_000);
    let e = oma(&[ra.as_slice()], &options).unwrap_err();
    assert!(e.to_string().contains("twice the lags"), "{e}");
    let mut options = OmaOptions::new(0.0);
    options.blocks = 2;
    assert!(oma(&[ra.as_slice()], &options).is_err());
}

/// Monte Carlo: eight 600 s records of one structure (one long simulation cut in
/// eight). For each true mode found in at least six records, the scatter of the
/// estimates over the records against the median standard deviation the jackknife
/// reported; the median of that ratio over the modes must lie within a factor 2, for the
/// frequency and for the damping.
#[test]
fn the_reported_standard_deviations_match_the_scatter_over_records() {
    let records = 8;
    let whole = record(1, 600.0 * records as f64);
    let n = 600 * 64;
    let truth = &whole.truth;
    let mut estimates: Vec<Vec<(f64, f64, f64, f64)>> =
        vec![Vec::new(); truth.frequencies_hz.len()];
    for r in 0..records {
        let outputs: Vec<&[f64]> = whole
            .outputs
            .iter()
            .map(|c| &c[r * n..(r + 1) * n])
            .collect();
        let found = oma(&[outputs.as_slice()], &OmaOptions::new(64.0)).unwrap();
        let (pick, spurious) = matched(&found, truth);
        assert!(spurious <= 1, "record {r}: {spurious} spurious");
        for (t, p) in pick.iter().enumerate() {
            let Some(m) = *p else { continue };
            let id = &found.identification;
            let (mode, q) = (&id.modal.modes[m], &id.quality[m]);
            estimates[t].push((
                mode.frequency_hz,
                mode.damping_ratio,
                q.frequency_std_hz.unwrap(),
                q.damping_ratio_std.unwrap(),
            ));
        }
    }
    let ratio = |values: &[(f64, f64)]| {
        let k = values.len() as f64;
        let mean = values.iter().map(|v| v.0).sum::<f64>() / k;
        let scatter = (values.iter().map(|v| (v.0 - mean).powi(2)).sum::<f64>() / (k - 1.0)).sqrt();
        let mut reported: Vec<f64> = values.iter().map(|v| v.1).collect();
        reported.sort_by(f64::total_cmp);
        scatter / reported[reported.len() / 2]
    };
    let (mut f, mut z) = (Vec::new(), Vec::new());
    for e in estimates.iter().filter(|e| e.len() >= 6) {
        f.push(ratio(&e.iter().map(|v| (v.0, v.2)).collect::<Vec<_>>()));
        z.push(ratio(&e.iter().map(|v| (v.1, v.3)).collect::<Vec<_>>()));
    }
    assert!(
        f.len() >= 8,
        "{} modes found in six records or more",
        f.len()
    );
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (mf, mz) = (median(f), median(z));
    assert!(
        (0.5..=2.0).contains(&mf),
        "frequency: scatter / reported = {mf:.2}"
    );
    assert!(
        (0.5..=2.0).contains(&mz),
        "damping: scatter / reported = {mz:.2}"
    );
}

/// A fleet of one structure with a 2 % drift and a 10 % stiffness loss from record 4:
/// each record's modes follow the truth of that record.
#[test]
fn oma_follows_a_fleets_drift_and_damage() {
    use era::sim::fleet::{fleet_record, FleetSpec};
    let mut spec = FleetSpec::new(
        ModalSpec {
            fmin_hz: 1.0,
            fmax_hz: 20.0,
            seed: 3,
            ..ModalSpec::new(8, 2, 6)
        },
        6,
    );
    spec.damage = Some((4, 0.1));
    for index in [0, 3, 5] {
        let r = fleet_record(&spec, index).unwrap();
        let outputs: Vec<&[f64]> = r.record.outputs.iter().map(Vec::as_slice).collect();
        let found = oma(&[outputs.as_slice()], &OmaOptions::new(64.0)).unwrap();
        let (pick, _) = matched(&found, &r.record.truth);
        let hits: Vec<usize> = pick.iter().flatten().copied().collect();
        assert!(hits.len() >= 5, "record {index}: {pick:?}");
        for (t, p) in pick.iter().enumerate() {
            let Some(m) = *p else { continue };
            let (got, want) = (
                found.identification.modal.modes[m].frequency_hz,
                r.record.truth.frequencies_hz[t],
            );
            // Well inside the 2 % drift and the 1-5 % damage shifts.
            assert!(
                (got / want - 1.0).abs() < 0.003,
                "record {index}: {got} vs {want}"
            );
        }
    }
}

/// Few references make a narrow Hankel: the automatic order still runs (its Hankel
/// factor is raised until the columns have room), with one reference and with two.
#[test]
fn few_references_run_at_the_automatic_order() {
    let rec = record(12, 300.0);
    let outputs: Vec<&[f64]> = rec.outputs.iter().map(Vec::as_slice).collect();
    for refs in [vec![0], vec![2, 6]] {
        let mut options = OmaOptions::new(64.0);
        options.references = Some(refs.clone());
        let found = oma(&[outputs.as_slice()], &options)
            .unwrap_or_else(|e| panic!("references {refs:?}: {e}"));
        let physical = found
            .identification
            .quality
            .iter()
            .filter(|q| q.physical)
            .count();
        assert!(
            physical >= 3,
            "references {refs:?}: {physical} physical modes"
        );
        assert_eq!(found.references, refs);
    }
}
