//! Stage timings of `identify` at the thesis DTA size, the median of 15 runs, noise-free
//! and with 5 % and 15 % noise (`cargo run --release -p era --example pipeline_probe`).

use era::identify::{identify, EraOptions};
use era::pipeline::realize::SvdPath;
use era::sim::{add_noise, ModalSpec, ModalStructure};
use era::Quantity;

fn main() {
    let structure = ModalStructure::random(&ModalSpec::default()).unwrap();
    let clean = structure.frf(801, 0.025, Quantity::Acceleration).unwrap();
    for noise in [0.0, 0.05, 0.15] {
        let frf = if noise > 0.0 {
            add_noise(&clean, noise, 42).unwrap()
        } else {
            clean.clone()
        };
        let options = {
            let mut o = EraOptions::thesis_dta();
            o.svd = SvdPath::MatrixFree;
            o
        };
        let mut runs: Vec<[f64; 6]> = (0..15)
            .map(|_| {
                let t = identify(&frf, &options).unwrap().timings;
                [
                    t.preprocess,
                    t.markov,
                    t.hankel_svd,
                    t.realize,
                    t.modes,
                    t.fit,
                ]
            })
            .collect();
        let median = |k: usize| {
            runs.sort_by(|a, b| a[k].total_cmp(&b[k]));
            runs[runs.len() / 2][k] * 1e3
        };
        let m: Vec<f64> = (0..6).map(median).collect();
        println!(
            "noise {noise:.2}: preprocess {:.2} markov {:.2} hankel_svd {:.1} realize {:.2} modes {:.2} fit {:.2} ms",
            m[0], m[1], m[2], m[3], m[4], m[5]
        );
    }
}
