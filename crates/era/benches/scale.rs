//! The ERA core (Markov data → A, B, C) over a size grid, dense and matrix-free.
//!
//! `cargo bench -p era --bench scale`. Lightly damped 8×8 data
//! ([`era::sim::lightly_damped_markov`]), `H0` of `m × m` blocks; the dense path only
//! where it takes seconds, not minutes. `bench/peers.sh` runs python-control on the same
//! data.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use era::linalg::LinearOperator;
use era::pipeline::hankel::HankelShape;
use era::pipeline::hankel_op::HankelOperator;
use era::pipeline::realize::{realize_general, RealizeOptions, SvdPath};
use era::sim::lightly_damped_markov;
use faer::Mat;
use std::hint::black_box;
use std::time::Duration;

fn grid(c: &mut Criterion) {
    // (outputs, inputs, modes, m): the cases.
    let cases = [
        (8, 8, 40, 200),
        (8, 8, 120, 600),
        (8, 8, 200, 1000),
        (8, 8, 200, 2000),
        (151, 8, 40, 400),
    ];
    let mut g = c.benchmark_group("era_core");
    g.sample_size(10).warm_up_time(Duration::from_millis(500));
    for (q, p, modes, m) in cases {
        let markov = lightly_damped_markov(q, p, modes, 2 * m + 2, 7);
        let shape = HankelShape {
            block_rows: m,
            block_cols: m,
            first_sample: 1,
        };
        let label = format!("{q}x{p}_m{m}_n{}", 2 * modes);
        let mut paths = vec![SvdPath::MatrixFree];
        if m * q.max(p) <= 1600 {
            paths.push(SvdPath::Dense);
        }
        for svd in paths {
            let options = {
                let mut o = RealizeOptions::new(2 * modes, 1);
                o.svd = svd;
                o
            };
            g.bench_with_input(BenchmarkId::new(svd.name(), &label), &options, |b, o| {
                b.iter(|| realize_general(black_box(&markov), 1.0, o, shape).unwrap())
            });
        }
    }
    g.finish();

    // One product at the thesis size: FFT correlations against a dense GEMM.
    let markov = lightly_damped_markov(8, 8, 40, 402, 7);
    let shape = HankelShape {
        block_rows: 200,
        block_cols: 200,
        first_sample: 1,
    };
    let op = HankelOperator::new(&markov, shape).unwrap();
    let dense = era::pipeline::hankel::build(&markov, shape).unwrap();
    let x = Mat::from_fn(1600, 120, |i, j| ((i * 7 + j * 3) as f64).sin());
    let mut g = c.benchmark_group("product_1600x1600_by_120");
    g.sample_size(20);
    g.bench_function("fft", |b| b.iter(|| op.apply(black_box(x.as_ref()))));
    g.bench_function("dense_gemm", |b| {
        b.iter(|| black_box(&dense) * black_box(&x))
    });
    g.finish();
}

criterion_group!(benches, grid);
criterion_main!(benches);
