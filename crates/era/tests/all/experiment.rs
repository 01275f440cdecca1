//! The simulated FRF test (`era::sim::experiment`): linear check against the exact FRFs,
//! stick–slip against the exact Coulomb decay (Eqs. 3.3–3.9), determinism, end stops and
//! the compensator's timing.

use era::friction::compensator::ChannelConfig;
use era::friction::simulate::{exact_free_decay, integrate};
use era::friction::Oscillator;
use era::sim::experiment::*;

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
    eprintln!(
        "median relative error {err:.4}, {:?} {:?} in {:?}",
        e.counts,
        e.max_stroke,
        t.elapsed()
    );
    assert!(err < 0.10, "median relative error {err}");
}

/// A rigid, clamped structure: no states, mount accelerations always 0.
fn clamped(mounts: usize) -> Structure {
    use faer::Mat;
    Structure {
        a: Mat::zeros(0, 0),
        b: Mat::zeros(0, mounts),
        c_mount: Mat::zeros(mounts, 0),
        d_mount: Mat::zeros(mounts, mounts),
        c_sensor: Mat::zeros(mounts, 0),
        d_sensor: Mat::zeros(mounts, mounts),
    }
}

/// One actuator on a clamped base, released from `x0`, nothing else.
fn single(act: Actuator, compensation: Option<Compensation>) -> ExperimentSpec {
    ExperimentSpec {
        structure: clamped(1),
        actuators: vec![act],
        compensation,
        excitation_rms_v: 0.0,
        frame: 64,
        averages: 1,
        lines: 33,
        settle_s: 12.0,
        accel_noise_rms: 0.0,
        lvt_noise_rms: 0.0,
        ..ExperimentSpec::thesis(false, 1, 1)
    }
}

#[test]
fn stick_slip_on_a_clamped_base_is_the_exact_coulomb_decay() {
    let act = Actuator {
        viscous_damping_ratio: 0.0,
        coulomb_force: 0.05,
        ..Actuator::thesis(0.05)
    };
    let times: Vec<f64> = (0..1200).map(|k| k as f64 * 0.01).collect();
    let out = simulate_run_with(&single(act, None), &[], 0, {
        let mut o = RunOptions::default();
        o.initial_stroke = Some(vec![0.9]);
        o.probe_times_s = times.clone();
        o
    })
    .unwrap();
    let osc = Oscillator::coulomb(1.0, 1.5, 0.05);
    let exact = exact_free_decay(&osc, 0.9, &times).unwrap();
    let w = osc.omega();
    let worst = out
        .probes
        .iter()
        .zip(&exact)
        .map(|(p, e)| (p[0].0 - e.x).abs().max((p[0].1 - e.v).abs() / w))
        .fold(0.0, f64::max);
    // 0.9 in, F_C/k = 0.05: |x| drops 0.1 per half-cycle and sticks at 0.9 − 0.1·9 = 0.
    // after 9 half-cycles (3 s), then stays.
    assert!(
        worst < 1e-9,
        "largest difference from Eqs. 3.3–3.9: {worst:e}"
    );
    let last = out.probes.last().unwrap()[0];
    assert_eq!(last.1, 0.0, "stuck for good");
    assert!(last.0.abs() <= 0.05 + 1e-12);
}

#[test]
fn compensator_samples_at_200_hz_and_holds_its_output() {
    let act = Actuator {
        viscous_damping_ratio: 0.0,
        ..Actuator::thesis(0.05)
    };
    let comp = Compensation {
        coefficients: vec![0.05],
        ..Compensation::thesis()
    };
    let times: Vec<f64> = (0..1000).map(|k| k as f64 * 0.01).collect();
    let out = simulate_run_with(&single(act, Some(comp.clone())), &[], 0, {
        let mut o = RunOptions::default();
        o.initial_stroke = Some(vec![0.8]);
        o.probe_times_s = times.clone();
        o
    })
    .unwrap();
    // Timing: one sample every 5 ms, each output the channel's map of what it read.
    let trace = &out.compensator;
    assert!(trace.time_s.len() > 1000);
    let channel = {
        let mut o = ChannelConfig::thesis(0.05);
        o.gain = 1.0 / MOTOR_LBF_PER_VOLT;
        o
    };
    for (k, t) in trace.time_s.iter().enumerate() {
        assert!((t - k as f64 / 200.0).abs() < 1e-12, "sample {k} at {t}");
        assert_eq!(trace.output_v[k][0], channel.output(trace.velocity[k][0]));
    }
    assert!(trace.output_v.iter().any(|v| v[0] != 0.0));
    // Held: the motion equals the friction integrator's with the force sampled at 200 Hz
    // and held (zero-order hold) — a different hold (or none) would differ by far more.
    let osc = Oscillator::coulomb(1.0, 1.5, 0.05);
    let force = ChannelConfig::thesis(0.05);
    let reference = integrate(&osc, 0.8, 0.0, 200.0, 2000, |_, s| force.output(s.v)).unwrap();
    let worst = times
        .iter()
        .zip(&out.probes)
        .map(|(t, p)| {
            let r = reference[(t * 200.0).round() as usize];
            (p[0].0 - r.x).abs().max((p[0].1 - r.v).abs() / osc.omega())
        })
        .fold(0.0, f64::max);
    assert!(
        worst < 1e-5,
        "largest difference from the held-force integrator: {worst:e}"
    );
}

#[test]
fn end_stops_bound_the_stroke() {
    let mut spec = single(
        Actuator {
            coulomb_force: 0.0,
            stroke: 0.5,
            ..Actuator::thesis(0.0)
        },
        None,
    );
    spec.excitation_rms_v = 5.0;
    spec.averages = 4;
    let with = simulate_run_with(&spec, &[0], 0, RunOptions::default()).unwrap();
    let max = |r: &RunRecord| r.stroke[0].iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(with.record.counts.impacts > 0);
    assert!(max(&with.record) <= 0.5 + 1e-9, "{}", max(&with.record));
    spec.actuators[0].stroke = f64::INFINITY;
    let without = simulate_run_with(&spec, &[0], 0, RunOptions::default()).unwrap();
    assert_eq!(without.record.counts.impacts, 0);
    assert!(max(&without.record) > 0.6, "{}", max(&without.record));
}

#[test]
fn same_seed_same_result_whatever_the_threads() {
    let mut spec = ExperimentSpec::thesis(true, 1, 5);
    spec.frame = 256;
    spec.lines = 101;
    spec.settle_s = 2.0;
    let a = run_experiment(&spec, false, &|_| {}).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let b = pool.install(|| run_experiment(&spec, false, &|_| {}).unwrap());
    assert_eq!(a.frf.values(), b.frf.values());
    assert_eq!(a.coherence, b.coherence);
    assert_eq!(a.counts, b.counts);
    assert!(a.counts.reversals + a.counts.sticks > 0);
    spec.seed = 6;
    let c = run_experiment(&spec, false, &|_| {}).unwrap();
    assert_ne!(a.frf.values(), c.frf.values());
}

#[test]
#[ignore = "a measurement: run with --ignored --nocapture"]
fn friction_experiment_figures() {
    for comp in [false, true] {
        let t = std::time::Instant::now();
        let e = run_experiment(&ExperimentSpec::thesis(comp, 2, 11), false, &|_| {}).unwrap();
        eprintln!(
            "compensated {comp}: median rel. error vs linear {:.4}, {:?}, strokes {:?}, {:?}",
            median_relative_error(&e, 0.5, 14.0),
            e.counts,
            e.max_stroke,
            t.elapsed()
        );
    }
}
