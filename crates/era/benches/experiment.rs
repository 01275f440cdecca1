//! The simulated FRF test (`era::sim::experiment`): the full 8×8 experiment at a few
//! averages, with and without friction and compensation. The target is 8 × 20
//! frames of 40 s (6400 s simulated) in 30 s on 2 cores; the time scales linearly with the
//! averages, so the 2-average figure times 10 (plus the settling) gives it.

use criterion::{criterion_group, criterion_main, Criterion};
use era::sim::experiment::{run_experiment, ExperimentSpec};

fn experiment(c: &mut Criterion) {
    let mut group = c.benchmark_group("experiment_8x8_2_averages");
    group.sample_size(10);
    for (name, compensated, friction) in [
        ("linear", false, false),
        ("friction", false, true),
        ("friction_compensated", true, true),
    ] {
        let mut spec = ExperimentSpec::thesis(compensated, 2, 1);
        if !friction {
            spec.actuators
                .iter_mut()
                .for_each(|a| a.coulomb_force = 0.0);
        }
        group.bench_function(name, |b| {
            b.iter(|| run_experiment(&spec, false, &|_| {}).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, experiment);
criterion_main!(benches);
