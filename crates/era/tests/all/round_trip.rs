//! Simulate → identify → compare poles, on exact discrete FRFs of seeded structures.
//!
//! The FRF of a discrete model sampled on 0 … Nyquist inverse-transforms to its
//! circularly aliased impulse response, `C A^(k−1) (I − A^n)⁻¹ B`, which has the same `A`:
//! so ERA must return the poles to round-off, whatever the damping.

use crate::common;

use common::worst_match;
use era::data::frf::uniform_lines;
use era::identify::{identify, EraOptions, ModelDomain};
use era::pipeline::fit::frequency_response;
use era::sim::{ModalSpec, ModalStructure};
use era::{Complex64, FrfData, Quantity};

fn round_trip(outputs: usize, inputs: usize, modes: usize, seed: u64, domain: ModelDomain) -> f64 {
    let spec = ModalSpec {
        outputs,
        inputs,
        modes,
        fmin_hz: 20.0,
        fmax_hz: 200.0,
        damping_min: 0.005,
        damping_max: 0.05,
        collocated: outputs == inputs,
        seed,
    };
    let structure = ModalStructure::random(&spec).unwrap();
    let lines = 513;
    let spacing = 1.0; // Nyquist 512 Hz: Ts = 1/1024 s
    let ts = 1.0 / (2.0 * spacing * (lines - 1) as f64);
    let discrete = structure
        .state_space(Quantity::Displacement)
        .c2d(ts)
        .unwrap();
    let freq = uniform_lines(lines, spacing);
    let values = frequency_response(&discrete, &freq).unwrap();
    let frf = FrfData::new(freq, outputs, inputs, values, Quantity::Displacement).unwrap();
    let hankel_factor = if outputs.min(inputs) == 1 { 8 } else { 4 };
    let options = {
        let mut o = EraOptions::new(2 * modes, hankel_factor);
        o.domain = domain;
        o
    };
    let found = identify(&frf, &options).unwrap();
    assert_eq!(
        found.modal.modes.len(),
        modes,
        "{outputs}x{inputs} seed {seed}"
    );
    let expected: Vec<Complex64> = structure.poles();
    let got: Vec<Complex64> = found
        .modal
        .modes
        .iter()
        .map(|m| m.continuous_pole)
        .collect();
    worst_match(&expected, &got)
}

#[test]
fn poles_come_back_for_several_shapes_and_seeds() {
    for (q, p, r) in [(1, 1, 3), (3, 2, 5), (3, 3, 6), (8, 8, 12)] {
        for seed in [11, 2024, 987_654_321] {
            let err = round_trip(q, p, r, seed, ModelDomain::Discrete);
            assert!(
                err < 1e-8,
                "{q}x{p}, {r} modes, seed {seed}: relative pole error {err:e}"
            );
        }
    }
}

#[test]
fn continuous_models_give_the_same_poles() {
    for seed in [5, 6] {
        let err = round_trip(3, 3, 4, seed, ModelDomain::Continuous);
        assert!(err < 1e-7, "seed {seed}: relative pole error {err:e}");
    }
}
