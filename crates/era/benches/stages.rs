//! Stages of the pipeline at the thesis's DTA size: 8×8 FRFs, 40 modes, 801 lines at
//! 0.025 Hz (acceleration), ns 80, lh 5, so H0 is 1592 × 1592.
//!
//! `cargo bench -p era --bench stages`. Setup happens outside the timed closures; the
//! naive Hankel is there as the baseline of the fast one. The group `tsvd_dta_1592` times
//! the truncated SVD of H0 on the same set as measured FRFs come (continuous-time,
//! leaking through the 40 s window) without noise and with 5 % and 15 %, with the
//! defaults (the unrestarted phase first) and with the restarted iteration alone; and the
//! whole `identify` at 5 % noise.

use criterion::{criterion_group, criterion_main, Criterion};
use era::identify::{identify, EraOptions};
use era::linalg::tsvd::{truncated_svd, TruncatedSvdOptions};
use era::pipeline::fit::{frequency_response, HessenbergForm};
use era::pipeline::hankel::{self, ThesisHankel};
use era::pipeline::hankel_op::HankelOperator;
use era::pipeline::modes::modal_parameters;
use era::pipeline::realize::{realize, RealizeOptions};
use era::sim::{add_noise, ModalSpec, ModalStructure};
use era::sources::frf::markov_from_frf;
use era::sources::frf::preprocess::preprocess;
use era::Quantity;
use std::hint::black_box;

fn stages(c: &mut Criterion) {
    let structure = ModalStructure::random(&ModalSpec::default()).unwrap();
    let frf = structure.frf(801, 0.025, Quantity::Acceleration).unwrap();
    let options = EraOptions::thesis_dta();
    let pre = preprocess(&frf, 1, 1024, 3).unwrap();
    let markov = markov_from_frf(&pre.frf).unwrap();
    let shapes = ThesisHankel::new(80, 5).unwrap();
    let realization = realize(&markov, pre.sample_time_s, &RealizeOptions::new(80, 5)).unwrap();
    let model = realization.model.clone();
    let h0 = hankel::build(&markov, shapes.h0).unwrap();

    let mut g = c.benchmark_group("dta_8x8_ns80_lh5");
    g.sample_size(10);
    g.bench_function("preprocess", |b| {
        b.iter(|| preprocess(black_box(&frf), 1, 1024, 3).unwrap())
    });
    g.bench_function("markov_realfft", |b| {
        b.iter(|| markov_from_frf(black_box(&pre.frf)).unwrap())
    });
    g.bench_function("hankel_build", |b| {
        b.iter(|| hankel::build(black_box(&markov), shapes.h0).unwrap())
    });
    g.bench_function("hankel_build_naive", |b| {
        b.iter(|| hankel::build_naive(black_box(&markov), shapes.h0).unwrap())
    });
    g.bench_function("thin_svd_1592", |b| {
        b.iter(|| black_box(&h0).thin_svd().unwrap())
    });
    g.bench_function("singular_values_only_1592", |b| {
        b.iter(|| black_box(&h0).singular_values().unwrap())
    });
    g.bench_function("realize_total", |b| {
        b.iter(|| {
            realize(
                black_box(&markov),
                pre.sample_time_s,
                &RealizeOptions::new(80, 5),
            )
            .unwrap()
        })
    });
    g.bench_function("modes", |b| {
        b.iter(|| modal_parameters(black_box(&model)).unwrap())
    });
    g.bench_function("model_frf_801_lines", |b| {
        b.iter(|| HessenbergForm::new(black_box(&model)).response(frf.frequency_hz()))
    });
    g.bench_function("model_frf_801_lines_dispatch", |b| {
        b.iter(|| frequency_response(black_box(&model), frf.frequency_hz()).unwrap())
    });
    g.bench_function("identify_end_to_end", |b| {
        b.iter(|| identify(black_box(&frf), &options).unwrap())
    });
    g.finish();

    let mut g = c.benchmark_group("tsvd_dta_1592");
    g.sample_size(10);
    for noise in [0.0, 0.05, 0.15] {
        let noisy = if noise > 0.0 {
            add_noise(&frf, noise, 42).unwrap()
        } else {
            frf.clone()
        };
        let pre = preprocess(&noisy, 1, 1024, 3).unwrap();
        let markov = markov_from_frf(&pre.frf).unwrap();
        let op = HankelOperator::new(&markov, shapes.h0).unwrap();
        let percent = (noise * 100.0).round();
        for (name, block) in [
            ("defaults", TruncatedSvdOptions::new(80).block),
            ("restarted", 0),
        ] {
            let options = {
                let mut o = TruncatedSvdOptions::new(80);
                o.block = block;
                o
            };
            g.bench_function(format!("{name}_noise_{percent}pc"), |b| {
                b.iter(|| truncated_svd(black_box(&op), &options).unwrap())
            });
        }
        if noise == 0.05 {
            g.bench_function("identify_end_to_end_noise_5pc", |b| {
                b.iter(|| identify(black_box(&noisy), &options).unwrap())
            });
        }
    }
    g.finish();
}

criterion_group!(benches, stages);
criterion_main!(benches);
