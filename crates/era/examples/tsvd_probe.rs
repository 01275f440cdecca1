//! Probe of the truncated SVD at the thesis DTA size: passes and time for block widths and
//! Krylov depths, noise-free and noisy (`cargo run --release -p era --example tsvd_probe`).

use era::hankel::ThesisHankel;
use era::hankel_op::HankelOperator;
use era::hankel_op::LinearOperator;
use era::markov::markov_from_frf;
use era::preprocess::preprocess;
use era::sim::Minstd;
use era::sim::{add_noise, ModalSpec, ModalStructure};
use era::tsvd::{truncated_svd, TruncatedSvdOptions};
use era::EraError;
use era::Quantity;
use faer::Mat;
use std::time::Instant;

fn orthonormal(m: &Mat<f64>) -> Mat<f64> {
    m.qr().compute_thin_Q()
}

/// The leading `options.rank` singular triplets of `op`.
///
/// # Errors
/// [`EraError::InvalidParameter`] for a rank of 0 or above `min(rows, cols)`;
/// [`EraError::Numerical`] when the small SVD fails or the residual does not reach the
/// tolerance within `max_iterations`.
pub fn old_truncated_svd(
    op: &dyn LinearOperator,
    options: &TruncatedSvdOptions,
) -> Result<era::tsvd::TruncatedSvd, EraError> {
    let (rows, cols) = (op.nrows(), op.ncols());
    let limit = rows.min(cols);
    if options.rank == 0 || options.rank > limit {
        return Err(EraError::InvalidParameter {
            name: "states",
            value: options.rank.to_string(),
            reason: format!(
                "a truncated SVD of a {rows} x {cols} operator needs 1 to {limit} triplets"
            ),
        });
    }
    let k = (options.rank + options.oversample).min(limit);
    let mut rng = Minstd::new(options.seed);
    // At most three k-wide blocks are alive at once (memory is what limits large cases).
    // The start is uniform on [-1, 1] (any full-rank random test matrix finds the range;
    // Halko et al. §4) and is not orthonormalised: the first pass only finds the range,
    // its residual is not tested, and from the second pass on W = orth(Hᵀ U).
    let mut w = Mat::from_fn(cols, k, |_, _| 2.0 * rng.uniform() - 1.0);
    let mut residual = f64::INFINITY;
    for iteration in 1..=options.max_iterations {
        // Rayleigh–Ritz on span(H W): H W = Q R, R = U_R Σ V_Rᵀ.
        let qr = op.apply(w.as_ref()).qr(); // Y itself is gone once factored
        let (q, r) = (qr.compute_thin_Q(), qr.thin_R().to_owned());
        drop(qr);
        let small = r
            .thin_svd()
            .map_err(|e| EraError::Numerical(format!("small SVD: {e:?}")))?;
        let s: Vec<f64> = (0..small.S().dim()).map(|i| small.S()[i]).collect();
        let u = &q * small.U();
        drop(q);
        let v = &w * small.V();
        drop(w);
        let z = op.apply_transpose(u.as_ref());
        if iteration == 1 {
            drop((u, v));
            w = orthonormal(&z);
            continue;
        }
        let s1 = s[0].max(f64::MIN_POSITIVE);
        residual = (0..options.rank)
            .map(|i| {
                (0..cols)
                    .map(|row| (z[(row, i)] - s[i] * v[(row, i)]).powi(2))
                    .sum::<f64>()
                    .sqrt()
                    / s1
            })
            .fold(0.0, f64::max);
        if residual <= options.tolerance {
            return Ok(era::tsvd::TruncatedSvd {
                u,
                s,
                v,
                iterations: iteration,
                residual,
                timings: Default::default(),
            });
        }
        drop((u, v));
        w = orthonormal(&z);
    }
    Err(EraError::Numerical(format!(
        "the truncated SVD did not converge in {} iterations (residual {residual:.2e}, tolerance {:.0e}): use --svd dense",
        options.max_iterations, options.tolerance
    )))
}

/// CPU seconds of this process (utime + stime from /proc/self/stat, 10 ms ticks).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit(')')
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect();
    let tick = |k: usize| {
        fields
            .get(k)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (tick(11) + tick(12)) / 100.0
}

fn main() {
    if std::env::var_os("SEQ").is_some() {
        faer::set_global_parallelism(faer::Par::Seq);
    }
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    // RANK=306 probes the order scan's factorization (306 triplets + 64) at 15 % noise.
    let rank: usize = std::env::var("RANK")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(80);
    let structure = ModalStructure::random(&ModalSpec::default()).unwrap();
    let clean = structure.frf(801, 0.025, Quantity::Acceleration).unwrap();
    for noise in [0.0, 0.05, 0.15] {
        if rank != 80 && noise < 0.15 {
            continue;
        }
        let frf = if noise > 0.0 {
            add_noise(&clean, noise, 42).unwrap()
        } else {
            clean.clone()
        };
        let pre = preprocess(&frf, 1, 1024, 3).unwrap();
        let markov = markov_from_frf(&pre.frf).unwrap();
        let shapes = ThesisHankel::new(80, 5).unwrap();
        let op = HankelOperator::new(&markov, shapes.h0).unwrap();
        let clock = Instant::now();
        let cpu = cpu_seconds();
        let mut passes = 0;
        for _ in 0..5 {
            passes = old_truncated_svd(&op, &TruncatedSvdOptions::new(rank))
                .unwrap()
                .iterations;
        }
        let (ms, cpu_ms) = (
            clock.elapsed().as_secs_f64() * 200.0,
            (cpu_seconds() - cpu) * 200.0,
        );
        println!("noise {noise:.2} old subspace iteration:    {passes:2} passes {ms:7.1} ms wall {cpu_ms:7.1} ms cpu");
        let clock = Instant::now();
        let cpu = cpu_seconds();
        for _ in 0..5 {
            passes = truncated_svd(&op, &TruncatedSvdOptions::new(rank))
                .unwrap()
                .iterations;
        }
        let (ms, cpu_ms) = (
            clock.elapsed().as_secs_f64() * 200.0,
            (cpu_seconds() - cpu) * 200.0,
        );
        println!("noise {noise:.2} block Krylov (defaults):   {passes:2} passes {ms:7.1} ms wall {cpu_ms:7.1} ms cpu");
        for depth in [1, 2, 3, 4, 6] {
            for oversample in [10, 20, 40] {
                if !args.is_empty() && !(args.contains(&depth)) {
                    continue;
                }
                let options = TruncatedSvdOptions {
                    depth,
                    oversample,
                    ..TruncatedSvdOptions::new(rank)
                };
                let clock = Instant::now();
                let cpu = cpu_seconds();
                let reps = if rank == 80 { 5 } else { 1 };
                let mut passes = 0;
                for _ in 0..reps {
                    passes = truncated_svd(&op, &options).unwrap().iterations;
                }
                let ms = clock.elapsed().as_secs_f64() * 1e3 / reps as f64;
                let cpu_ms = (cpu_seconds() - cpu) * 1e3 / reps as f64;
                println!("noise {noise:.2} depth {depth} oversample {oversample:2}: {passes:2} passes {ms:7.1} ms wall {cpu_ms:7.1} ms cpu");
            }
        }
    }
}
