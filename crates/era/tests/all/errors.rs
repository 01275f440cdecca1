//! Impossible requests give typed errors, never panics.

use era::identify::{identify, EraOptions};
use era::sim::truth_model_frf;
use era::{Complex64, EraError, FrfData, Quantity};

#[test]
fn more_states_than_the_data_supports() {
    let frf = truth_model_frf(None).unwrap();
    let err = identify(&frf, &{
        let mut o = EraOptions::thesis_truth_model();
        o.order = era::Order::Fixed(12);
        o
    })
    .unwrap_err();
    assert!(
        matches!(
            err,
            EraError::RankDeficient {
                rank: 8,
                states: 12,
                ..
            }
        ),
        "{err}"
    );
}

#[test]
fn hankel_factor_too_large_for_the_data() {
    let frf = truth_model_frf(None).unwrap();
    let err = identify(&frf, &{
        let mut o = EraOptions::thesis_truth_model();
        o.hankel_factor = 400;
        o
    })
    .unwrap_err();
    assert!(
        matches!(
            err,
            EraError::NotEnoughMarkovSamples {
                needed: 3201,
                available: 2048,
                ..
            }
        ),
        "{err}"
    );
}

#[test]
fn hankel_smaller_than_the_order() {
    let frf = truth_model_frf(None).unwrap();
    let err = identify(&frf, &EraOptions::new(10, 1)).unwrap_err();
    assert!(
        matches!(
            err,
            EraError::HankelTooSmall {
                rows: 9,
                cols: 9,
                available: 9,
                states: 10
            }
        ),
        "{err}"
    );
}

#[test]
fn all_zero_frf() {
    let frf = FrfData::from_fn(
        era::data::frf::uniform_lines(64, 1.0),
        2,
        2,
        Quantity::Velocity,
        |_, _, _| Complex64::new(0.0, 0.0),
    )
    .unwrap();
    assert_eq!(
        identify(&frf, &EraOptions::new(2, 4)).unwrap_err(),
        EraError::AllZero
    );
}

#[test]
fn integrating_displacement_is_refused() {
    let frf = truth_model_frf(None).unwrap();
    let err = identify(&frf, &{
        let mut o = EraOptions::thesis_truth_model();
        o.integrations = 1;
        o
    })
    .unwrap_err();
    assert!(
        matches!(
            err,
            EraError::InvalidParameter {
                name: "integrations",
                ..
            }
        ),
        "{err}"
    );
}
