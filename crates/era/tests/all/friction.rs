//! Free-decay estimation, simulation and tuning against the thesis's Table 5.1.

use era::friction::estimate::{estimate_displacement, estimate_velocity, DampingModel};
use era::friction::simulate::{free_decay_record, DecaySpec, Method};
use era::friction::tune::{stability_margin, tune, TuneSpec};
use era::friction::{FrictionError, Oscillator};

/// Table 5.1, calculated coefficients (lbf) of actuators 1–6.
const TABLE_5_1: [f64; 6] = [0.0591, 0.0565, 0.0549, 0.0353, 0.0574, 0.0518];

fn spec(coulomb_force: f64, noise_fraction: f64, seed: u64) -> DecaySpec {
    DecaySpec {
        oscillator: Oscillator::coulomb(1.0, 1.5, coulomb_force),
        x0: 1.5,
        sample_rate_hz: 200.0,
        hold_s: 0.5,
        duration_s: None,
        noise_fraction,
        seed,
        method: Method::Exact,
    }
}

#[test]
fn table_5_1_recovered_within_2_percent_without_noise() {
    for fc in TABLE_5_1 {
        let r = free_decay_record(&spec(fc, 0.0, 1)).unwrap();
        let e = estimate_velocity(&r.time_s, &r.velocity, 1.0).unwrap();
        let err = (e.coulomb_force - fc).abs() / fc;
        assert!(
            err < 0.02,
            "F_C {fc}: estimated {} ({:.2} %)",
            e.coulomb_force,
            100.0 * err
        );
        assert!(
            (e.natural_frequency_hz - 1.5).abs() < 0.01 * 1.5,
            "{}",
            e.natural_frequency_hz
        );
        assert!((e.natural_frequency_hz_from_peaks - 1.5).abs() < 0.01 * 1.5);
        assert_eq!(e.better_model, DampingModel::Coulomb);
        // The displacement channel gives the same answer.
        let d = estimate_displacement(&r.time_s, &r.displacement, 1.0).unwrap();
        assert!(
            (d.coulomb_force - fc).abs() / fc < 0.02,
            "displacement: {}",
            d.coulomb_force
        );
    }
}

#[test]
fn table_5_1_recovered_within_5_percent_with_5_percent_noise() {
    for fc in TABLE_5_1 {
        let mut estimates: Vec<f64> = (1..=10)
            .map(|seed| {
                let r = free_decay_record(&spec(fc, 0.05, seed * 7919)).unwrap();
                estimate_velocity(&r.time_s, &r.velocity, 1.0)
                    .unwrap()
                    .coulomb_force
            })
            .collect();
        estimates.sort_by(f64::total_cmp);
        let median = 0.5 * (estimates[4] + estimates[5]);
        let err = (median - fc).abs() / fc;
        assert!(
            err < 0.05,
            "F_C {fc}: median {median} ({:.2} %)",
            100.0 * err
        );
    }
}

#[test]
fn the_decay_law_is_recognised() {
    let viscous = DecaySpec {
        oscillator: Oscillator {
            viscous_damping_ratio: 0.02,
            ..Oscillator::coulomb(1.0, 1.5, 0.0)
        },
        duration_s: Some(12.0),
        method: Method::Integrate,
        ..spec(0.0, 0.0, 1)
    };
    let r = free_decay_record(&viscous).unwrap();
    let e = estimate_velocity(&r.time_s, &r.velocity, 1.0).unwrap();
    assert_eq!(e.better_model, DampingModel::Viscous, "{e:?}");
    assert!(
        (e.viscous_damping_ratio - 0.02).abs() < 0.002,
        "{}",
        e.viscous_damping_ratio
    );

    let r = free_decay_record(&spec(0.0591, 0.0, 1)).unwrap();
    let e = estimate_velocity(&r.time_s, &r.velocity, 1.0).unwrap();
    assert_eq!(e.better_model, DampingModel::Coulomb);
    assert!(e.coulomb_residual < 0.1 * e.viscous_residual);
}

/// Friction and viscous damping together: Eq. 3.12 reads the viscous share as friction,
/// the combined law separates them.
#[test]
fn the_combined_law_separates_friction_from_viscous_damping() {
    for (fc, zeta) in [(0.0591, 0.02), (0.0353, 0.01), (0.0175, 0.03), (0.05, 0.0)] {
        let mixed = DecaySpec {
            oscillator: Oscillator {
                viscous_damping_ratio: zeta,
                ..Oscillator::coulomb(1.0, 1.5, fc)
            },
            method: Method::Integrate,
            ..spec(fc, 0.0, 1)
        };
        let r = free_decay_record(&mixed).unwrap();
        let e = estimate_velocity(&r.time_s, &r.velocity, 1.0).unwrap();
        let c = e.combined;
        assert!(
            (c.coulomb_force - fc).abs() < 0.03 * fc,
            "F_C {fc}, zeta {zeta}: combined {c:?}, Eq. 3.12 {}",
            e.coulomb_force
        );
        assert!(
            (c.viscous_damping_ratio - zeta).abs() < 0.002,
            "F_C {fc}, zeta {zeta}: combined {c:?}"
        );
        assert!(c.residual <= e.coulomb_residual.min(e.viscous_residual) * (1.0 + 1e-9));
        if zeta > 0.0 {
            // Eq. 3.12 alone over-estimates: the bias the combined law removes.
            assert!(e.coulomb_force > fc * 1.1, "{}", e.coulomb_force);
        }
    }
    // With 1 % sensor noise, one record each: the median over seeds within 3 %.
    let mut found: Vec<f64> = (1..=7)
        .map(|seed| {
            let noisy = DecaySpec {
                oscillator: Oscillator {
                    viscous_damping_ratio: 0.02,
                    ..Oscillator::coulomb(1.0, 1.5, 0.0591)
                },
                method: Method::Integrate,
                x0: 1.0,
                ..spec(0.0591, 0.01, seed)
            };
            let r = free_decay_record(&noisy).unwrap();
            estimate_velocity(&r.time_s, &r.velocity, 1.0)
                .unwrap()
                .combined
                .coulomb_force
        })
        .collect();
    found.sort_by(f64::total_cmp);
    assert!((found[3] - 0.0591).abs() < 0.03 * 0.0591, "{found:?}");
}

#[test]
fn bad_records_are_refused_with_the_reason() {
    let r = free_decay_record(&spec(0.0591, 0.0, 1)).unwrap();
    let (t, v) = (r.time_s.clone(), r.velocity.clone());

    let mut nan = v.clone();
    nan[100] = f64::NAN;
    assert_eq!(
        estimate_velocity(&t, &nan, 1.0),
        Err(FrictionError::NonFinite {
            column: "velocity",
            index: 100
        })
    );

    let mut back = t.clone();
    back[50] = back[49];
    assert!(matches!(
        estimate_velocity(&back, &v, 1.0),
        Err(FrictionError::NonMonotonicTime { index: 50, .. })
    ));

    // Actuator 9's 0.2824 lbf from a small release: motion dies within a cycle.
    let stuck = free_decay_record(&DecaySpec {
        x0: 0.9,
        ..spec(0.2824, 0.0, 1)
    })
    .unwrap();
    assert!(matches!(
        estimate_velocity(&stuck.time_s, &stuck.velocity, 1.0),
        Err(FrictionError::NeverOscillates { .. })
    ));

    // Four half-cycles: it oscillates, but too little is left once the release
    // transient and the stuck tail are dropped.
    let short = free_decay_record(&DecaySpec {
        x0: 0.45,
        ..spec(0.0591, 0.0, 1)
    })
    .unwrap();
    assert!(matches!(
        estimate_velocity(&short.time_s, &short.velocity, 1.0),
        Err(FrictionError::TooFewCycles { .. })
    ));

    assert!(matches!(
        estimate_velocity(&t[..10], &v[..10], 1.0),
        Err(FrictionError::TooFewSamples { .. })
    ));
    assert!(matches!(
        estimate_velocity(&t, &v, 0.0),
        Err(FrictionError::InvalidParameter {
            name: "stiffness",
            ..
        })
    ));
}

#[test]
fn tune_recovers_the_true_coefficient() {
    for fc in [0.0591, 0.0353] {
        let spec = TuneSpec {
            oscillator: Oscillator::coulomb(1.0, 1.5, fc),
            x0: 1.5,
            dead_zone: 0.2,
            sample_rate_hz: 200.0,
            cycles: 6,
            fraction: 0.85,
        };
        let t = tune(&spec).unwrap();
        let err = (t.neutral_coefficient - fc).abs() / fc;
        assert!(
            err < 0.02,
            "F_C {fc}: neutral {} ({:.2} %)",
            t.neutral_coefficient,
            100.0 * err
        );
        assert!((t.applied_coefficient - 0.85 * t.neutral_coefficient).abs() < 1e-15);
        assert!((t.stability_margin - 0.15).abs() < 1e-12);
        // A coefficient 30 % too large, applied at 85 %, makes the actuator oscillate.
        assert!(stability_margin(1.3 * fc, 0.85, t.neutral_coefficient) < 0.0);
    }
}
