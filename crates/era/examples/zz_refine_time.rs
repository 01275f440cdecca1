use era::refine::{refine, RefineOptions, Residuals, Weighting};
use era::sim::{add_noise, ModalSpec, ModalStructure};
use era::{Complex64, Quantity};
use std::f64::consts::PI;
use std::time::Instant;
fn main() {
    if std::env::var("SEQ").is_ok() {
        faer::set_global_parallelism(faer::Par::Seq);
    }
    let spec = ModalSpec::default();
    let s = ModalStructure::random(&spec).unwrap();
    let clean = s.frf(801, 0.025, Quantity::Acceleration).unwrap();
    let noisy = add_noise(&clean, 0.05, spec.seed).unwrap();
    let start: Vec<Complex64> = s
        .frequencies_hz
        .iter()
        .zip(&s.damping_ratios)
        .enumerate()
        .map(|(r, (f, z))| {
            let sign = if r % 2 == 0 { 1.0 } else { -1.0 };
            let w = 2.0 * PI * f * (1.0 + 0.003 * sign);
            let z = z * (1.0 - 0.2 * sign);
            Complex64::new(-z * w, w * (1.0 - z * z).sqrt())
        })
        .collect();
    for (name, data) in [("clean", &clean), ("noisy", &noisy)] {
        for w in [Weighting::Uniform, Weighting::PairNoise] {
            let mut o = RefineOptions::default();
            o.residuals = Residuals::Upper;
            o.weighting = w.clone();
            let t = Instant::now();
            let mut n = 0;
            let r = refine(data, &start, &o, &mut |i, c| {
                n += 1;
                if std::env::var("V").is_ok() {
                    eprintln!("  it {i} cost {c:.6e} t {:.3}", t.elapsed().as_secs_f64());
                }
            })
            .unwrap();
            println!(
                "{name} {:?}: {:.3} s, {} iterations, progress calls {n}, fit {:.3e}",
                w,
                t.elapsed().as_secs_f64(),
                r.iterations,
                r.fit_after
            );
        }
    }
}
