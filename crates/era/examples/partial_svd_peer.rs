//! era's truncated SVD against faer's matrix-free `partial_svd` (Lanczos
//! bidiagonalization with thick restarts) on the same Hankel operator: the thesis
//! DTA-like Hankel (1592², 80 triplets) and the automatic path's (3192², 180 triplets),
//! noise-free and with 5 % and 15 % noise. Each at the tolerance era uses there (1e-12 at
//! a fixed order, 1e-6 in the scan), with the time (best of 3), the products
//! (columns multiplied by `H` and by `Hᵀ`), and the largest relative error of the wanted
//! singular values against the dense SVD.
//!
//! `cargo run --release -p era --example partial_svd_peer`. Knobs for tuning era's
//! iteration: `BLOCK=b` and `DEPTH=d` set its block width and depth, `BIGK=k` the
//! triplets of the larger Hankel, `BIG=1` skips the thesis size, `NOISY=1` the noise-free
//! data, `NOFAER=1` faer's runs, `FLOOR=f` sets era's noise-floor stop
//! (`TruncatedSvdOptions::floor_fraction`), `SPLIT=1` prints where each era run's time went.

use era::linalg::tsvd::{truncated_svd, TruncatedSvdOptions};
use era::linalg::LinearOperator;
use era::pipeline::hankel::{build, HankelShape};
use era::pipeline::hankel_op::HankelOperator;
use era::sim::{add_noise, ModalSpec, ModalStructure};
use era::sources::frf::markov_from_frf;
use era::sources::frf::preprocess::preprocess;
use era::Quantity;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::matrix_free::{BiLinOp, LinOp};
use faer::{Mat, MatMut, MatRef, Par};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// era's Hankel operator as faer sees an operator, counting the columns it multiplies.
struct Faer<'a> {
    op: &'a HankelOperator,
    columns: AtomicUsize,
}

impl std::fmt::Debug for Faer<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Hankel {} x {}",
            LinearOperator::nrows(self.op),
            LinearOperator::ncols(self.op)
        )
    }
}

impl LinOp<f64> for Faer<'_> {
    fn apply_scratch(&self, _: usize, _: Par) -> StackReq {
        StackReq::EMPTY
    }
    fn nrows(&self) -> usize {
        LinearOperator::nrows(self.op)
    }
    fn ncols(&self) -> usize {
        LinearOperator::ncols(self.op)
    }
    fn apply(&self, mut out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, _: Par, _: &mut MemStack) {
        self.columns.fetch_add(rhs.ncols(), Ordering::Relaxed);
        out.copy_from(self.op.apply(rhs));
    }
    fn conj_apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, s: &mut MemStack) {
        LinOp::apply(self, out, rhs, par, s);
    }
}

impl BiLinOp<f64> for Faer<'_> {
    fn transpose_apply_scratch(&self, _: usize, _: Par) -> StackReq {
        StackReq::EMPTY
    }
    fn transpose_apply(
        &self,
        mut out: MatMut<'_, f64>,
        rhs: MatRef<'_, f64>,
        _: Par,
        _: &mut MemStack,
    ) {
        self.columns.fetch_add(rhs.ncols(), Ordering::Relaxed);
        out.copy_from(self.op.apply_transpose(rhs));
    }
    fn adjoint_apply(
        &self,
        out: MatMut<'_, f64>,
        rhs: MatRef<'_, f64>,
        par: Par,
        s: &mut MemStack,
    ) {
        self.transpose_apply(out, rhs, par, s);
    }
}

fn worst(found: &[f64], dense: &[f64], k: usize) -> f64 {
    (0..k)
        .map(|i| (found[i] - dense[i]).abs() / dense[i])
        .fold(0.0, f64::max)
}

fn main() {
    let structure = ModalStructure::random(&ModalSpec::default()).unwrap();
    let clean = structure.frf(801, 0.025, Quantity::Acceleration).unwrap();
    println!("| Hankel | triplets | tolerance | noise | era s | era columns | era worst | faer s | faer columns | faer worst |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let big_k = std::env::var("BIGK")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(180);
    for (blocks, k, tolerance) in [(199usize, 80usize, 1e-12), (399, big_k, 1e-6)] {
        if std::env::var_os("BIG").is_some() && blocks < 300 {
            continue;
        }
        for noise in [0.0, 0.05, 0.15] {
            if std::env::var_os("NOISY").is_some() && noise == 0.0 {
                continue;
            }
            let frf = if noise > 0.0 {
                add_noise(&clean, noise, 42).unwrap()
            } else {
                clean.clone()
            };
            let pre = preprocess(&frf, 0, 0, 0).unwrap();
            let markov = markov_from_frf(&pre.frf).unwrap();
            let shape = HankelShape {
                block_rows: blocks,
                block_cols: blocks,
                first_sample: 1,
            };
            let op = HankelOperator::new(&markov, shape).unwrap();
            let dense = build(&markov, shape).unwrap().singular_values().unwrap();
            let mut era_best = (f64::INFINITY, 0, 0.0);
            for _ in 0..3 {
                let clock = Instant::now();
                let mut options = TruncatedSvdOptions::new(k);
                options.tolerance = tolerance;
                if let Some(b) = std::env::var("BLOCK").ok().and_then(|v| v.parse().ok()) {
                    options.block = b;
                }
                if let Some(d) = std::env::var("DEPTH").ok().and_then(|v| v.parse().ok()) {
                    options.depth = d;
                }
                if let Some(f) = std::env::var("FLOOR").ok().and_then(|v| v.parse().ok()) {
                    options.floor_fraction = f;
                }
                let svd = truncated_svd(&op, &options).unwrap();
                let t = clock.elapsed().as_secs_f64();
                if std::env::var_os("SPLIT").is_some() {
                    let tt = svd.timings;
                    eprintln!(
                        "  era {t:.3} s: products {:.3}, orthogonalisation {:.3}, Rayleigh-Ritz {:.3}; {} passes",
                        tt.products, tt.orthogonalisation, tt.rayleigh_ritz, svd.iterations
                    );
                }
                if t < era_best.0 {
                    era_best = (t, 2 * svd.columns, worst(&svd.s, &dense, k));
                }
            }
            let mut faer_best = (f64::INFINITY, 0, 0.0);
            for _ in 0..if std::env::var_os("NOFAER").is_some() {
                0
            } else {
                3
            } {
                let wrapped = Faer {
                    op: &op,
                    columns: AtomicUsize::new(0),
                };
                let (m, n) = (LinearOperator::nrows(&op), LinearOperator::ncols(&op));
                let mut u = Mat::<f64>::zeros(m, k);
                let mut v = Mat::<f64>::zeros(n, k);
                let mut s = vec![0.0; k];
                let v0 = faer::Col::<f64>::from_fn(n, |i| 1.0 + ((i * 7919) % 101) as f64 / 101.0);
                let v0 = &v0 / v0.norm_l2();
                let par = faer::get_global_parallelism();
                let params = faer::matrix_free::eigen::PartialEigenParams::default();
                let clock = Instant::now();
                let mut buf = MemBuffer::new(faer::matrix_free::eigen::partial_svd_scratch::<f64>(
                    &wrapped, k, par, params,
                ));
                let info = faer::matrix_free::eigen::partial_svd(
                    u.as_mut(),
                    v.as_mut(),
                    &mut s,
                    &wrapped,
                    v0.as_ref(),
                    tolerance,
                    par,
                    MemStack::new(&mut buf),
                    params,
                );
                let t = clock.elapsed().as_secs_f64();
                let mut sorted = s.clone();
                sorted.sort_by(|a, b| b.total_cmp(a));
                let err = if info.n_converged_eigen >= k {
                    worst(&sorted, &dense, k)
                } else {
                    f64::NAN
                };
                if t < faer_best.0 {
                    faer_best = (t, wrapped.columns.load(Ordering::Relaxed), err);
                }
            }
            println!(
                "| {0}² | {k} | {tolerance:.0e} | {1:.0} % | {2:.3} | {3} | {4:.1e} | {5:.3} | {6} | {7:.1e} |",
                LinearOperator::nrows(&op),
                noise * 100.0,
                era_best.0,
                era_best.1,
                era_best.2,
                faer_best.0,
                faer_best.1,
                faer_best.2
            );
        }
    }
}
