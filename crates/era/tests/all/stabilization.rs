//! The scan's core promises (docs/src/design.md §10): a realization from the kept factors is
//! the fresh identification at that order, on both SVD paths; the indicators do not
//! depend on the state basis.

use era::linalg::rng::Minstd;
use era::modal::indicators::{emac, mpc};
use era::pipeline::hankel::HankelShape;
use era::pipeline::modes::ModalForm;
use era::pipeline::realize::{
    realize_general, DirectTerm, FactorOptions, Factorization, RealizeOptions, SvdPath,
};
use era::sim::lightly_damped_markov;
use era::sources::frf::MarkovSequence;
use era::Complex64;
use faer::linalg::solvers::DenseSolveCore;
use faer::Mat;
use proptest::prelude::*;

fn sorted_eigenvalues(model: &era::StateSpace) -> Vec<Complex64> {
    let mut e = model.poles().unwrap();
    e.sort_by(|a, b| a.im.total_cmp(&b.im).then(a.re.total_cmp(&b.re)));
    e
}

fn noisy_markov(seed: u64) -> MarkovSequence {
    // A lightly damped 3 x 2 system with 12 modes, plus a little noise so every order
    // has a distinct realization.
    let mut m = lightly_damped_markov(3, 2, 12, 400, seed);
    let mut rng = Minstd::new(seed + 7);
    for k in 0..m.samples() {
        for i in 0..3 {
            for j in 0..2 {
                let v = m.get(k, i, j);
                m.set(k, i, j, v + 1e-4 * rng.normal());
            }
        }
    }
    m
}

#[test]
fn a_realization_from_the_factors_is_a_fresh_identification_on_both_paths() {
    let markov = noisy_markov(3);
    let _ = FactorOptions::new(1, 1);
    let shape = HankelShape {
        block_rows: 90,
        block_cols: 120,
        first_sample: 1,
    };
    for path in [SvdPath::Dense, SvdPath::MatrixFree] {
        let factors = Factorization::general(&markov, 0.01, 60, path, shape).unwrap();
        assert_eq!(factors.svd_path(), path);
        // The dense SVD is exact at every order. The truncated SVD meets its residual
        // tolerance, which fixes the singular vectors only where a gap separates them from
        // the rest: at the orders where the data's modes end (12 modes), not inside the
        // noise.
        let orders: &[usize] = match path {
            SvdPath::Dense => &[12, 24, 36, 60],
            _ => &[12, 24],
        };
        for &n in orders {
            let from_factors = factors.realize(n, DirectTerm::Zero).unwrap();
            let options = {
                let mut o = RealizeOptions::new(n, 1);
                o.svd = path;
                o
            };
            let fresh = realize_general(&markov, 0.01, &options, shape).unwrap();
            let (a, b) = (
                sorted_eigenvalues(&from_factors.model),
                sorted_eigenvalues(&fresh.model),
            );
            assert_eq!(a.len(), b.len());
            let worst = a
                .iter()
                .zip(&b)
                .map(|(x, y)| (x - y).norm())
                .fold(0.0, f64::max);
            assert!(worst < 1e-10, "{path:?} at {n} states: {worst:e}");
        }
        // The matrix-free path keeps singular values past the largest order.
        assert!(
            factors.singular_values().len() >= 60 + era::pipeline::realize::EXTRA_SINGULAR_VALUES
        );
    }
}

#[test]
fn thesis_factorization_refuses_orders_above_what_it_kept() {
    let markov = noisy_markov(5);
    let f = Factorization::thesis(&markov, 0.01, &{
        let mut o = FactorOptions::new(30, 5);
        o.max_states = 30;
        o
    })
    .unwrap();
    assert!(f.realize(31, DirectTerm::Zero).is_err());
    assert!(f.realize(0, DirectTerm::Zero).is_err());
    assert_eq!(f.realize(30, DirectTerm::Zero).unwrap().model.states(), 30);
}

/// A random well-conditioned similarity transform of size n: `2I + E` with `E`'s
/// entries of standard deviation `0.6/√n`, so that `‖E‖₂ ≈ 1.2` and the condition
/// number stays near 4 (entries of 0.3 at n = 30 gave `‖E‖₂ ≈ 3.3 > 2`: seed 6855
/// drew a transform that made one eigenvector's condition number 1600, and its MPC
/// moved by 2e-7 through rounding alone).
fn transform(n: usize, seed: u64) -> Mat<f64> {
    let mut rng = Minstd::new(seed);
    let scale = 0.6 / (n as f64).sqrt();
    Mat::from_fn(n, n, |i, j| {
        (if i == j { 2.0 } else { 0.0 }) + scale * rng.normal()
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(8))]
    #[test]
    fn indicators_do_not_depend_on_the_state_basis(seed in 1u64..10_000) {
        let markov = noisy_markov(seed);
        let shape = HankelShape { block_rows: 60, block_cols: 80, first_sample: 1 };
        let f = Factorization::general(&markov, 0.01, 30, SvdPath::Dense, shape).unwrap();
        let r = f.realize(30, DirectTerm::Zero).unwrap();
        let t = transform(30, seed);
        let t_inv = t.partial_piv_lu().inverse();
        let mut other = r.clone();
        other.model.a = &t_inv * &r.model.a * &t;
        other.model.b = &t_inv * &r.model.b;
        other.model.c = &r.model.c * &t;
        other.tails.observability = &r.tails.observability * &t;
        other.tails.controllability = &t_inv * &r.tails.controllability;
        let (fa, fb) = (ModalForm::new(&r.model).unwrap(), ModalForm::new(&other.model).unwrap());
        let (ea, eb) = (emac(&fa, &r.tails), emac(&fb, &other.tails));
        for (k, z) in fa.eigenvalues.iter().enumerate() {
            let j = (0..fb.eigenvalues.len())
                .min_by(|&x, &y| (fb.eigenvalues[x] - z).norm().total_cmp(&(fb.eigenvalues[y] - z).norm()))
                .unwrap();
            prop_assert!((fb.eigenvalues[j] - z).norm() < 1e-8);
            prop_assert!((mpc(&fa.shapes[k]) - mpc(&fb.shapes[j])).abs() < 1e-8);
            prop_assert!((ea[k].0 - eb[j].0).abs() < 1e-6, "{} vs {}", ea[k].0, eb[j].0);
            prop_assert!((ea[k].1 - eb[j].1).abs() < 1e-6, "{} vs {}", ea[k].1, eb[j].1);
        }
    }
}
