//! What the truncated SVD's noise-floor stop ([`ScanOptions::svd_floor_fraction`]) costs in
//! accuracy: on DTA-like 8 × 8 sets (40 modes, 801 lines, the measured preset, a
//! continuous model), each structure with several noise realizations, the automatic
//! order runs once with the stop off (the tolerance alone, 1e-6 of `σ₁`) and once with it
//! on. For every true mode found by both, the shift of its frequency and damping between
//! the two runs is compared with the spread of that mode over the noise realizations
//! (the run with the stop off), and so is each run's error against the true mode (RMS
//! over the same estimates); the modes found, spurious ones and times are printed.
//!
//! `cargo run --release -p era --example scan_floor -- [STRUCTURES] [REALIZATIONS] [NOISE] [FRACTION]`,
//! e.g. `-- 405,406,407 4 0.05 0.3` (the fraction defaults to the scan's).

use era::identify::{identify, ScanOptions};
use era::sim::{add_noise, ModalSpec, ModalStructure};
use era::Quantity;
use std::time::Instant;

#[path = "../benches/support/sets.rs"]
mod sets;

fn main() -> era::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let structures: Vec<u64> = args
        .first()
        .map(|s| s.split(',').map(|v| v.parse().unwrap()).collect())
        .unwrap_or(vec![201, 202, 203, 204]);
    let realizations: u64 = args.get(1).map_or(8, |v| v.parse().unwrap());
    assert!(
        realizations >= 3,
        "REALIZATIONS: at least 3, for a spread over the noise"
    );
    let noise: f64 = args.get(2).map_or(0.05, |v| v.parse().unwrap());
    let fraction: f64 = args
        .get(3)
        .map_or(ScanOptions::default().svd_floor_fraction, |v| {
            v.parse().unwrap()
        });
    let (mut df_ratios, mut dz_ratios) = (Vec::new(), Vec::new());
    let (mut t_off, mut t_on) = (Vec::new(), Vec::new());
    // Sums of squared errors against the truth over the modes found by both runs, in
    // units of each mode's spread: frequency off, on; damping off, on.
    let mut truth_errors = [0.0f64; 4];
    for &seed in &structures {
        let spec = ModalSpec {
            seed,
            collocated: true,
            ..ModalSpec::default()
        };
        let structure = ModalStructure::random(&spec)?;
        let clean = structure.frf(801, 0.025, Quantity::Acceleration)?;
        let modes = structure.frequencies_hz.len();
        // [realization][mode] -> (f, zeta) for the stop off and on.
        let mut off = vec![vec![None; modes]; realizations as usize];
        let mut on = off.clone();
        for r in 0..realizations {
            let frf = add_noise(&clean, noise, 1000 * seed + r)?;
            for (f, store, times) in [(0.0, &mut off, &mut t_off), (fraction, &mut on, &mut t_on)] {
                let mut options = sets::measured_auto();
                let mut scan = ScanOptions::default();
                scan.svd_floor_fraction = f;
                options.scan = scan;
                let clock = Instant::now();
                let found = identify(&frf, &options)?;
                times.push(clock.elapsed().as_secs_f64());
                let physical = sets::physical(&found);
                for (i, truth) in structure.frequencies_hz.iter().enumerate() {
                    let best = physical
                        .iter()
                        .filter(|(g, _)| (g - truth).abs() <= 0.005 * truth)
                        .min_by(|a, b| (a.0 - truth).abs().total_cmp(&(b.0 - truth).abs()));
                    store[r as usize][i] = best.copied();
                }
                let found_count = store[r as usize].iter().flatten().count();
                println!(
                    "structure {seed} realization {r} fraction {f}: {found_count}/{modes} found, {} physical, {:.3} s",
                    physical.len(),
                    times.last().unwrap()
                );
            }
        }
        for i in 0..modes {
            let both: Vec<((f64, f64), (f64, f64))> = (0..realizations as usize)
                .filter_map(|r| Some((off[r][i]?, on[r][i]?)))
                .collect();
            if both.len() < 3 {
                continue;
            }
            let spread = |pick: fn(&(f64, f64)) -> f64| {
                let v: Vec<f64> = both.iter().map(|(a, _)| pick(a)).collect();
                let mean = v.iter().sum::<f64>() / v.len() as f64;
                (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
            };
            let (sf, sz) = (spread(|m| m.0), spread(|m| m.1));
            if !(sf > 0.0 && sz > 0.0) {
                continue;
            }
            let (tf, tz) = (structure.frequencies_hz[i], structure.damping_ratios[i]);
            for (a, b) in &both {
                df_ratios.push((a.0 - b.0).abs() / sf);
                dz_ratios.push((a.1 - b.1).abs() / sz);
                // Errors against the truth, in units of the mode's noise spread.
                truth_errors[0] += ((a.0 - tf) / sf).powi(2);
                truth_errors[1] += ((b.0 - tf) / sf).powi(2);
                truth_errors[2] += ((a.1 - tz) / sz).powi(2);
                truth_errors[3] += ((b.1 - tz) / sz).powi(2);
            }
        }
    }
    if df_ratios.is_empty() {
        println!("no mode was found in both runs of 3 or more realizations: nothing to compare");
        return Ok(());
    }
    let summary = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        (v[v.len() / 2], v[v.len() * 95 / 100], v[v.len() - 1])
    };
    let (fm, f95, fx) = summary(&mut df_ratios);
    let (zm, z95, zx) = summary(&mut dz_ratios);
    let (om, _, ox) = summary(&mut t_off);
    let (nm, _, nx) = summary(&mut t_on);
    println!(
        "shift / noise spread over {} mode estimates: frequency median {fm:.3} p95 {f95:.3} max {fx:.3}; damping median {zm:.3} p95 {z95:.3} max {zx:.3}",
        df_ratios.len()
    );
    let count = df_ratios.len() as f64;
    let rms = |k: usize| (truth_errors[k] / count).sqrt();
    println!(
        "error against the truth / noise spread, RMS over the same estimates: frequency off {:.3} on {:.3}; damping off {:.3} on {:.3}",
        rms(0),
        rms(1),
        rms(2),
        rms(3)
    );
    println!("identify --states auto: off median {om:.3} s (worst {ox:.3}), on median {nm:.3} s (worst {nx:.3})");
    Ok(())
}
