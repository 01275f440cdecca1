//! The automatic path over 16 seeds (issue 38): DTA-like 8 × 8 sets (40 modes in
//! 0.5–14 Hz, collocated, 801 lines at 0.025 Hz, 5 % noise), the measured preset's
//! preprocessing (no integration, padding or zeroed lines; `D = Y0`; a continuous
//! model). Two groups, one function per seed, so that criterion's report gives the
//! median and the worst seed:
//!
//! - `auto_order_5_percent`: `identify` at `Order::Auto` (the probe, the scan's factorization, the
//!   scan, the choice of modes), what `era identify --states auto --no-refine` runs;
//! - `refine_from_auto_5_percent`: the refinement from that start with the CLI's
//!   defaults (pair-noise weights, rank-one residues, missed modes added), what
//!   `--refine` adds.
//!
//! `cargo bench -p era --bench auto_seeds` (about 6 minutes on 2 cores). Setup happens
//! outside the timed closures.

use criterion::{criterion_group, criterion_main, Criterion};
use era::identify::identify;
use era::refine::identification::refine_identification;
use era::refine::{RefineOptions, Weighting};
use era::sim::{add_noise, ModalSpec, ModalStructure};
use era::{FrfData, Quantity};
use std::hint::black_box;

#[path = "support/sets.rs"]
mod sets;

const SEEDS: std::ops::RangeInclusive<u64> = 1001..=1016;

fn set(seed: u64) -> FrfData {
    let spec = ModalSpec {
        seed,
        collocated: true,
        ..ModalSpec::default()
    };
    let s = ModalStructure::random(&spec).unwrap();
    add_noise(
        &s.frf(801, 0.025, Quantity::Acceleration).unwrap(),
        0.05,
        seed,
    )
    .unwrap()
}

fn auto_seeds(c: &mut Criterion) {
    let options = sets::measured_auto();
    let sets: Vec<(u64, FrfData)> = SEEDS.map(|s| (s, set(s))).collect();
    let mut g = c.benchmark_group("auto_order_5_percent");
    g.sample_size(10);
    for (seed, frf) in &sets {
        g.bench_function(format!("seed_{seed}"), |b| {
            b.iter(|| identify(black_box(frf), &options).unwrap())
        });
    }
    g.finish();
    let mut refine = RefineOptions::default();
    refine.weighting = Weighting::PairNoise;
    let mut g = c.benchmark_group("refine_from_auto_5_percent");
    g.sample_size(10);
    for (seed, frf) in &sets {
        let start = identify(frf, &options).unwrap();
        g.bench_function(format!("seed_{seed}"), |b| {
            b.iter_batched(
                || start.clone(),
                |f| {
                    refine_identification(f, black_box(frf), &refine, &mut |_| {}, &mut |_, _| {})
                        .unwrap()
                },
                criterion::BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

criterion_group!(benches, auto_seeds);
criterion_main!(benches);
