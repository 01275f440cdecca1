//! `era::refine` at the DTA size: 8×8 acceleration FRFs, 40 modes in 0.5–14 Hz, 801
//! lines at 0.025 Hz (`era simulate modal` defaults) with 5 % noise, refined from the true
//! poles perturbed by ±0.3 % in frequency and ±20 % in damping. The target is ≤ 1 s on
//! 2 cores, for the uniform weighting and for the CLI's default, `PairNoise`, with
//! rank-one residues (the default) and with free ones (`--free-residues`). The naive reference (finite differences, a dense solve per pair) is timed
//! on a 2×2, 4-mode set beside the fast path on the same set.
//!
//! The group `refine_dta_from_era_auto` starts where the pipeline does (`era identify
//! --states auto --refine --time-domain continuous` with the thesis preprocessing):
//! from the physical modes of the automatic order, refining the whole identification
//! (`refine_identification`: the fit, its residual scan, the model and its FRF).
//!
//! The group `refine_iteration_floor` times the dense kernels one iteration of the
//! rank-one stage cannot do without at that size (faer alone, on matrices of the
//! problem's shapes): what an iteration would cost if nothing but those kernels ran.
//!
//! `cargo bench -p era --bench refine`. Setup happens outside the timed closures.

use criterion::{criterion_group, criterion_main, Criterion};
use era::refine::{refine, refine_naive, RefineOptions, Residuals, Weighting};
use era::sim::{add_noise, ModalSpec, ModalStructure};
use era::{Complex64, Quantity};
use std::f64::consts::PI;
use std::hint::black_box;

fn perturbed(s: &ModalStructure) -> Vec<Complex64> {
    s.frequencies_hz
        .iter()
        .zip(&s.damping_ratios)
        .enumerate()
        .map(|(r, (f, z))| {
            let sign = if r % 2 == 0 { 1.0 } else { -1.0 };
            let w = 2.0 * PI * f * (1.0 + 0.003 * sign);
            let z = z * (1.0 - 0.2 * sign);
            Complex64::new(-z * w, w * (1.0 - z * z).sqrt())
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let spec = ModalSpec::default();
    let s = ModalStructure::random(&spec).unwrap();
    let clean = s.frf(801, 0.025, Quantity::Acceleration).unwrap();
    let noisy = add_noise(&clean, 0.05, spec.seed).unwrap();
    let start = perturbed(&s);
    let mut options = {
        let mut o = RefineOptions::default();
        o.weighting = era::refine::Weighting::Uniform;
        o
    };
    options.residuals = Residuals::Upper;

    let mut g = c.benchmark_group("refine_dta_8x8_40modes_801lines");
    g.sample_size(10);
    g.bench_function("noise_free", |b| {
        b.iter(|| refine(black_box(&clean), &start, &options, &mut |_, _| {}).unwrap())
    });
    g.bench_function("noise_5_percent", |b| {
        b.iter(|| refine(black_box(&noisy), &start, &options, &mut |_, _| {}).unwrap())
    });
    // The CLI's default weighting: a uniform first pass, then each pair by its noise.
    let mut pair_noise = options.clone();
    pair_noise.weighting = Weighting::PairNoise;
    g.bench_function("noise_5_percent_pair_noise", |b| {
        b.iter(|| refine(black_box(&noisy), &start, &pair_noise, &mut |_, _| {}).unwrap())
    });
    // `--free-residues`: the variable-projection stage alone.
    let mut free = pair_noise.clone();
    free.rank_one = false;
    g.bench_function("noise_5_percent_pair_noise_free_residues", |b| {
        b.iter(|| refine(black_box(&noisy), &start, &free, &mut |_, _| {}).unwrap())
    });
    g.finish();

    let small_spec = ModalSpec {
        fmin_hz: 2.0,
        fmax_hz: 8.0,
        ..ModalSpec::new(2, 2, 4)
    };
    let small = ModalStructure::random(&small_spec).unwrap();
    let small_frf = add_noise(
        &small.frf(401, 0.025, Quantity::Acceleration).unwrap(),
        0.05,
        1,
    )
    .unwrap();
    let small_start = perturbed(&small);
    let mut g = c.benchmark_group("refine_2x2_4modes_401lines");
    g.sample_size(10);
    g.bench_function("fast", |b| {
        b.iter(|| {
            refine(
                black_box(&small_frf),
                &small_start,
                &options,
                &mut |_, _| {},
            )
            .unwrap()
        })
    });
    g.bench_function("naive", |b| {
        b.iter(|| {
            refine_naive(
                black_box(&small_frf),
                &small_start,
                &options,
                &mut |_, _| {},
            )
            .unwrap()
        })
    });
    g.finish();
}

/// From ERA's automatic order, as the CLI refines (setup: one automatic identification
/// per set).
fn bench_from_era(c: &mut Criterion) {
    use era::identify::{identify, EraOptions, ModelDomain, Order};
    use era::refine::identification::refine_identification;
    let spec = ModalSpec::default();
    let s = ModalStructure::random(&spec).unwrap();
    let clean = s.frf(801, 0.025, Quantity::Acceleration).unwrap();
    let noisy = add_noise(&clean, 0.05, spec.seed).unwrap();
    let era_options = {
        let mut o = EraOptions::thesis_dta();
        o.domain = ModelDomain::Continuous;
        o.order = Order::Auto;
        o
    };
    let mut options = {
        let mut o = RefineOptions::default();
        o.weighting = era::refine::Weighting::Uniform;
        o
    };
    options.weighting = Weighting::PairNoise;
    let mut g = c.benchmark_group("refine_dta_from_era_auto");
    g.sample_size(10);
    for (name, frf) in [
        ("noise_free", &clean),
        ("noise_5_percent_pair_noise", &noisy),
    ] {
        let found = identify(frf, &era_options).unwrap();
        g.bench_function(name, |b| {
            b.iter_batched(
                || found.clone(),
                |f| {
                    refine_identification(f, black_box(frf), &options, &mut |_| {}, &mut |_, _| {})
                        .unwrap()
                },
                criterion::BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

/// The dense kernels of one rank-one iteration at the DTA size (8 × 8, 40 modes, 801
/// lines, the upper residual): the Gram products of the basis `Φ` (1602 × 81) and its
/// pole derivatives `D` (1602 × 160) with each other and with the residuals (64 pairs);
/// the elimination of each output's own parameters (8 blocks of 88²: its 80 shape
/// entries and 8 residual terms), each solved for the 640 shared unknowns (the poles
/// and participations) and the gradient; the Schur complement `S = N_zz − N_Izᵀ X` (the
/// lower half of a 640 × 704 × 640 product); and the Cholesky factorisation of `S` that
/// each trial step takes.
fn bench_iteration_floor(c: &mut Criterion) {
    use faer::linalg::matmul::triangular::{matmul, BlockStructure};
    use faer::prelude::Solve;
    use faer::{Accum, Mat, Side};
    let (modes, outputs, inputs, lines) = (40, 8, 8, 801);
    let (rows, pairs) = (2 * lines, outputs * inputs);
    // Two columns per mode and the upper residual; two derivatives per column pair.
    let (basis, derivatives) = (2 * modes + 1, 4 * modes);
    // Per mode: its pole (2) and participation (2p, one complex entry held).
    let shared = modes * (2 + 2 * inputs - 2);
    // Per output: its shapes (2 per mode) and one residual term per input.
    let own = 2 * modes + inputs;
    let local = outputs * own;
    let filled = |r: usize, c: usize, k: usize| {
        Mat::<f64>::from_fn(r, c, |i, j| {
            (((i * 7 + j * 13 + k) % 29) as f64 - 14.0) / 29.0
        })
    };
    let phi = filled(rows, basis, 1);
    let d = filled(rows, derivatives, 2);
    let residual = filled(rows, pairs, 3);
    // A symmetric positive definite block and the shared system, as the fit has them.
    let spd = |n: usize, k: usize| {
        let a = filled(n, n, k);
        let mut g = a.transpose() * &a;
        for i in 0..n {
            g[(i, i)] += n as f64;
        }
        g
    };
    let block = spd(own, 4);
    let coupling = filled(own, shared + 1, 5);
    let n_iz = filled(local, shared, 6);
    let x = filled(local, shared, 7);
    let s = spd(shared, 8);
    let mut g = c.benchmark_group("refine_iteration_floor");
    g.sample_size(30);
    g.bench_function("gram_products", |b| {
        b.iter(|| {
            (
                phi.transpose() * &d,
                d.transpose() * &d,
                phi.transpose() * &residual,
                d.transpose() * &residual,
            )
        })
    });
    g.bench_function("shape_blocks_solved", |b| {
        b.iter(|| {
            (0..outputs)
                .map(|_| block.llt(Side::Lower).unwrap().solve(&coupling))
                .collect::<Vec<_>>()
        })
    });
    g.bench_function("schur_complement", |b| {
        b.iter(|| {
            let mut out = s.clone();
            matmul(
                out.as_mut(),
                BlockStructure::TriangularLower,
                Accum::Add,
                n_iz.transpose(),
                BlockStructure::Rectangular,
                x.as_ref(),
                BlockStructure::Rectangular,
                -1.0,
                faer::get_global_parallelism(),
            );
            out
        })
    });
    g.bench_function("step_cholesky", |b| {
        b.iter(|| black_box(&s).llt(Side::Lower).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench, bench_from_era, bench_iteration_floor);
criterion_main!(benches);
