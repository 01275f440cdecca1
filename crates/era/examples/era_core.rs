//! The ERA core alone, Markov data in, A, B, C out: what `bench/peers.sh` times against
//! python-control's `eigensys_realization` on the same data.
//!
//! ```text
//! era_core generate FILE OUTPUTS INPUTS MODES SAMPLES SEED
//!     writes lightly damped Markov data (era::sim::lightly_damped_markov) as raw
//!     little-endian f64 in [sample][output][input] order (numpy: reshape(K, q, p))
//! era_core dta FILE NOISE
//!     writes the Markov data of the DTA-like 8x8 set (40 modes, 801 lines at 0.025 Hz,
//!     acceleration, seed 987654321) at the thesis settings (ni 1, nz 3, ndpts 1024), with
//!     NOISE (0.05 for 5 %, seed 42) added to the FRFs first; same layout, 2048 samples
//! era_core realize FILE OUTPUTS INPUTS SAMPLES STATES M dense|matrix-free|auto
//!     H0 = m × m blocks from Y_1 (as python-control builds it); prints one JSON line
//! ```

use era::pipeline::hankel::HankelShape;
use era::pipeline::realize::{realize_general, RealizeOptions, SvdPath};
use era::sim::lightly_damped_markov;
use era::sim::{add_noise, ModalSpec, ModalStructure};
use era::sources::frf::preprocess::preprocess;
use era::sources::frf::{markov_from_frf, MarkovSequence};
use era::Quantity;
use std::io::Write;
use std::time::Instant;

fn arg<T: std::str::FromStr>(args: &[String], k: usize, name: &str) -> T {
    args.get(k).and_then(|a| a.parse().ok()).unwrap_or_else(|| {
        eprintln!("era_core: missing or bad {name} (see the header of examples/era_core.rs)");
        std::process::exit(2)
    })
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    match args.get(1).map(String::as_str) {
        Some("generate") => {
            let (file, q, p, modes, samples, seed): (String, usize, usize, usize, usize, u64) = (
                arg(&args, 2, "FILE"),
                arg(&args, 3, "OUTPUTS"),
                arg(&args, 4, "INPUTS"),
                arg(&args, 5, "MODES"),
                arg(&args, 6, "SAMPLES"),
                arg(&args, 7, "SEED"),
            );
            let m = lightly_damped_markov(q, p, modes, samples, seed);
            let mut bytes = Vec::with_capacity(samples * q * p * 8);
            for k in 0..samples {
                for i in 0..q {
                    for j in 0..p {
                        bytes.extend_from_slice(&m.get(k, i, j).to_le_bytes());
                    }
                }
            }
            std::fs::File::create(&file)
                .and_then(|mut f| f.write_all(&bytes))
                .unwrap_or_else(|e| {
                    eprintln!("era_core: {file}: {e}");
                    std::process::exit(2)
                });
        }
        Some("dta") => {
            let (file, noise): (String, f64) = (arg(&args, 2, "FILE"), arg(&args, 3, "NOISE"));
            let structure = ModalStructure::random(&ModalSpec::default()).unwrap();
            let clean = structure.frf(801, 0.025, Quantity::Acceleration).unwrap();
            let frf = if noise > 0.0 {
                add_noise(&clean, noise, 42).unwrap()
            } else {
                clean
            };
            let pre = preprocess(&frf, 1, 1024, 3).unwrap();
            let m = markov_from_frf(&pre.frf).unwrap();
            let mut bytes = Vec::with_capacity(m.samples() * 64 * 8);
            for k in 0..m.samples() {
                for i in 0..m.outputs() {
                    for j in 0..m.inputs() {
                        bytes.extend_from_slice(&m.get(k, i, j).to_le_bytes());
                    }
                }
            }
            std::fs::write(&file, &bytes).unwrap_or_else(|e| {
                eprintln!("era_core: {file}: {e}");
                std::process::exit(2)
            });
        }
        Some("realize") => {
            let (file, q, p, samples, states, m): (String, usize, usize, usize, usize, usize) = (
                arg(&args, 2, "FILE"),
                arg(&args, 3, "OUTPUTS"),
                arg(&args, 4, "INPUTS"),
                arg(&args, 5, "SAMPLES"),
                arg(&args, 6, "STATES"),
                arg(&args, 7, "M"),
            );
            let svd = match args.get(8).map(String::as_str) {
                Some("dense") => SvdPath::Dense,
                Some("matrix-free") => SvdPath::MatrixFree,
                _ => SvdPath::Auto,
            };
            let bytes = std::fs::read(&file).unwrap_or_else(|e| {
                eprintln!("era_core: {file}: {e}");
                std::process::exit(2)
            });
            if bytes.len() != samples * q * p * 8 {
                eprintln!(
                    "era_core: {file} has {} bytes, expected {}",
                    bytes.len(),
                    samples * q * p * 8
                );
                std::process::exit(2);
            }
            let value = |k: usize, i: usize, j: usize| {
                let at = ((k * q + i) * p + j) * 8;
                f64::from_le_bytes(bytes[at..at + 8].try_into().unwrap())
            };
            let markov = MarkovSequence::from_fn(q, p, samples, value);
            drop(bytes);
            let shape = HankelShape {
                block_rows: m,
                block_cols: m,
                first_sample: 1,
            };
            let options = {
                let mut o = RealizeOptions::new(states, 1);
                o.svd = svd;
                o
            };
            let clock = Instant::now();
            let r = realize_general(&markov, 1.0, &options, shape).unwrap_or_else(|e| {
                eprintln!("era_core: {e}");
                std::process::exit(2)
            });
            let seconds = clock.elapsed().as_secs_f64();
            let poles = r.model.poles().map(|p| p.len()).unwrap_or(0);
            println!(
                "{{\"seconds\": {seconds}, \"hankel_svd_s\": {}, \"path\": \"{}\", \"iterations\": {}, \"rows\": {}, \"cols\": {}, \"states\": {poles}}}",
                r.hankel_svd_seconds,
                r.svd_path.name(),
                r.svd_iterations.unwrap_or(0),
                r.hankel_size.0,
                r.hankel_size.1
            );
        }
        _ => {
            eprintln!("usage: see the header of crates/era/examples/era_core.rs");
            std::process::exit(2);
        }
    }
}
