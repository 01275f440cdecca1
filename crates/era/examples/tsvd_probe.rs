//! Probe of the truncated SVD at the thesis DTA size: passes and time of the defaults
//! (the unrestarted phase first), and of the restarted iteration alone for block widths
//! and Krylov depths, noise-free and noisy
//! (`cargo run --release -p era --example tsvd_probe [DEPTH...]`).

use era::linalg::tsvd::{truncated_svd, TruncatedSvdOptions};
use era::pipeline::hankel::ThesisHankel;
use era::pipeline::hankel_op::HankelOperator;
use era::sim::{add_noise, ModalSpec, ModalStructure};
use era::sources::frf::markov_from_frf;
use era::sources::frf::preprocess::preprocess;
use era::Quantity;
use std::time::Instant;

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
        // Subspace iteration is the library's truncated SVD at depth 1.
        let defaults = TruncatedSvdOptions::new(rank);
        for (label, depth, block) in [
            ("subspace iteration (depth 1)", 1, 0),
            ("restarted block Krylov      ", defaults.depth, 0),
            (
                "defaults (unrestarted first)",
                defaults.depth,
                defaults.block,
            ),
        ] {
            let options = {
                let mut o = defaults;
                o.depth = depth;
                o.block = block;
                o
            };
            let clock = Instant::now();
            let cpu = cpu_seconds();
            let (mut passes, mut columns) = (0, 0);
            for _ in 0..5 {
                let svd = truncated_svd(&op, &options).unwrap();
                (passes, columns) = (svd.iterations, svd.columns);
            }
            let (ms, cpu_ms) = (
                clock.elapsed().as_secs_f64() * 200.0,
                (cpu_seconds() - cpu) * 200.0,
            );
            println!(
                "noise {noise:.2} {label}: {passes:2} passes, {columns:4} columns {ms:7.1} ms wall {cpu_ms:7.1} ms cpu"
            );
        }
        for depth in [1, 2, 3, 4, 6] {
            for oversample in [10, 20, 40] {
                if !args.is_empty() && !(args.contains(&depth)) {
                    continue;
                }
                // The restarted iteration alone, at this depth and block width.
                let options = {
                    let mut o = TruncatedSvdOptions::new(rank);
                    o.depth = depth;
                    o.oversample = oversample;
                    o.block = 0;
                    o
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
