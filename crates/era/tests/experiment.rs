//! The simulated FRF test (`era::sim::experiment`): linear check against the exact FRFs,
//! stick–slip against the exact Coulomb decay (Eqs. 3.3–3.9), determinism, end stops and
//! the compensator's timing.

use era::friction::compensator::ChannelConfig;
use era::friction::simulate::{exact_free_decay, integrate};
use era::friction::Oscillator;
use era::sim::experiment::*;
use era::sim::ModalStructure;

/// Median over lines in `lo..hi` Hz of the relative error `|H − G| / |G|`, all pairs.
fn median_relative_error(e: &Experiment, lo: f64, hi: f64) -> f64 {
    let f = e.frf.frequency_hz();
    let mut errs = Vec::new();
    for i in 0..e.frf.outputs() {
        for j in 0..e.frf.inputs() {
            let (h, g) = (e.frf.pair(i, j), e.exact.pair(i, j));
            for k in 0..f.len() {
                if f[k] >= lo && f[k] <= hi {
                    errs.push((h[k] - g[k]).norm() / g[k].norm());
                }
            }
        }
    }
    errs.sort_by(f64::total_cmp);
    errs[errs.len() / 2]
}

fn linear(compensated: bool, averages: usize) -> ExperimentSpec {
    let mut spec = ExperimentSpec::thesis(compensated, averages, 11);
    for a in &mut spec.actuators {
        a.coulomb_force = 0.0;
    }
    spec
}

#[test]
fn linear_system_matches_the_exact_frfs() {
    let t = std::time::Instant::now();
    let e = run_experiment(&linear(false, 10), false, &|_| {}).unwrap();
    let err = median_relative_error(&e, 0.5, 14.0);
    eprintln!("median relative error {err:.4}, {:?} {:?} in {:?}", e.counts, e.max_stroke, t.elapsed());
    assert!(err < 0.10, "median relative error {err}");
}
