//! Property tests (proptest): Hankel block structure, `d2c(c2d(·)) = id`, and ERA on
//! exact Markov data of random stable systems.

use crate::common;

use common::worst_match;
use era::data::statespace::{relative_difference, StateSpace, TimeDomain};
use era::pipeline::hankel::{build, build_naive, HankelShape};
use era::pipeline::realize::{realize, RealizeOptions};
use era::sources::frf::MarkovSequence;
use era::Complex64;
use era_testkit::{difference, Scale};
use faer::Mat;
use proptest::prelude::*;

/// A random stable system in modal coordinates (2×2 blocks `r[[cos θ, −sin θ],
/// [sin θ, cos θ]]` in discrete time, or `[[σ, ω], [−ω, σ]]` in continuous time), every mode
/// well coupled to the inputs and outputs, then hidden by a well-conditioned similarity.
#[derive(Debug, Clone)]
struct RandomSystem {
    /// (radius or decay, angle or frequency) per mode.
    modes: Vec<(f64, f64)>,
    b: Vec<f64>,
    c: Vec<f64>,
    mix: Vec<f64>,
    outputs: usize,
    inputs: usize,
}

fn random_system(max_modes: usize) -> impl Strategy<Value = RandomSystem> {
    (1..=max_modes, 1usize..=3, 1usize..=3).prop_flat_map(|(modes, outputs, inputs)| {
        let n = 2 * modes;
        (
            prop::collection::vec((0.5f64..0.95, 0.0f64..1.0), modes),
            prop::collection::vec(prop_oneof![-1.5f64..-0.5, 0.5f64..1.5], n * inputs),
            prop::collection::vec(prop_oneof![-1.5f64..-0.5, 0.5f64..1.5], outputs * n),
            prop::collection::vec(-0.2f64..0.2, n * n),
        )
            .prop_map(move |(modes, b, c, mix)| RandomSystem {
                modes,
                b,
                c,
                mix,
                outputs,
                inputs,
            })
    })
}

impl RandomSystem {
    fn states(&self) -> usize {
        2 * self.modes.len()
    }

    /// Angles spread over (0.1, 3.0) with gaps, so the poles are distinct.
    fn angle(&self, k: usize, fraction: f64) -> f64 {
        let slot = 2.9 / self.modes.len() as f64;
        0.1 + slot * (k as f64 + 0.2 + 0.6 * fraction)
    }

    fn model(&self, domain: TimeDomain) -> StateSpace {
        let n = self.states();
        let mut a = Mat::<f64>::zeros(n, n);
        for (k, (radius, fraction)) in self.modes.iter().enumerate() {
            let theta = self.angle(k, *fraction);
            let (re, im) = match domain {
                TimeDomain::Discrete { .. } => (radius * theta.cos(), radius * theta.sin()),
                // Continuous: s = −(1 − radius)·θ·… lightly to moderately damped.
                TimeDomain::Continuous => (-(1.0 - radius) * theta, theta),
            };
            a[(2 * k, 2 * k)] = re;
            a[(2 * k, 2 * k + 1)] = -im;
            a[(2 * k + 1, 2 * k)] = im;
            a[(2 * k + 1, 2 * k + 1)] = re;
        }
        let t = Mat::from_fn(n, n, |i, j| {
            f64::from(u8::from(i == j)) + self.mix[i * n + j]
        });
        let t_inv = faer::linalg::solvers::DenseSolveCore::inverse(&t.partial_piv_lu());
        let b0 = Mat::from_fn(n, self.inputs, |i, j| self.b[i * self.inputs + j]);
        let c0 = Mat::from_fn(self.outputs, n, |i, j| self.c[i * n + j]);
        StateSpace::new(
            &t * &a * &t_inv,
            &t * &b0,
            &c0 * &t_inv,
            Mat::zeros(self.outputs, self.inputs),
            domain,
        )
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn hankel_has_block_structure(
        outputs in 1usize..4, inputs in 1usize..4,
        rows in 1usize..6, cols in 1usize..6, first in 0usize..4, extra in 0usize..3,
        seed in any::<u64>(),
    ) {
        let samples = first + rows + cols - 1 + extra;
        let markov = MarkovSequence::from_fn(outputs, inputs, samples, |k, i, j| {
            ((seed.wrapping_add((k * 131 + i * 17 + j * 7) as u64) % 1000) as f64) - 500.0
        });
        let shape = HankelShape { block_rows: rows, block_cols: cols, first_sample: first };
        let h = build(&markov, shape).unwrap();
        // A copy of the same numbers: equal to the bit.
        let diff = difference(&h, &build_naive(&markov, shape).unwrap(), Scale::Absolute);
        prop_assert!(diff.within(0.0), "block Hankel: {}", diff);
        prop_assert_eq!((h.nrows(), h.ncols()), (rows * outputs, cols * inputs));
        for r in 0..rows {
            for c in 0..cols {
                for i in 0..outputs {
                    for j in 0..inputs {
                        // Block (r, c) is Y_(first + r + c), constant along anti-diagonals.
                        prop_assert_eq!(h[(r * outputs + i, c * inputs + j)], markov.get(first + r + c, i, j));
                        if r > 0 && c + 1 < cols {
                            prop_assert_eq!(
                                h[(r * outputs + i, c * inputs + j)],
                                h[((r - 1) * outputs + i, (c + 1) * inputs + j)]
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn d2c_inverts_c2d(system in random_system(4), sample_time_s in 0.05f64..0.9) {
        let continuous = system.model(TimeDomain::Continuous);
        let discrete = continuous.c2d(sample_time_s).unwrap();
        let back = discrete.d2c().unwrap();
        prop_assert!(relative_difference(&back.a, &continuous.a) < 1e-9);
        prop_assert!(relative_difference(&back.b, &continuous.b) < 1e-9);
        prop_assert_eq!(back.domain, TimeDomain::Continuous);
    }

    #[test]
    fn era_on_exact_markov_data_reproduces_the_poles(system in random_system(5)) {
        let model = system.model(TimeDomain::Discrete { sample_time_s: 1.0 });
        let n = model.states();
        // Hankel large enough for the order whatever the numbers of channels.
        let hankel_factor = 4 + 8 / system.outputs.min(system.inputs);
        let samples = n * hankel_factor + 2;
        let mut power = Mat::<f64>::identity(n, n);
        let mut markov = MarkovSequence::zeros(system.outputs, system.inputs, samples);
        for k in 1..samples {
            let y = &model.c * &power * &model.b; // C A^(k−1) B
            for i in 0..system.outputs {
                for j in 0..system.inputs {
                    markov.set(k, i, j, y[(i, j)]);
                }
            }
            power = &power * &model.a;
        }
        let found = realize(&markov, 1.0, &RealizeOptions::new(n, hankel_factor)).unwrap();
        let expected: Vec<Complex64> = model.poles().unwrap();
        let err = worst_match(&expected, &found.model.poles().unwrap());
        prop_assert!(err < 1e-7, "relative pole error {:e}", err);
    }
}
