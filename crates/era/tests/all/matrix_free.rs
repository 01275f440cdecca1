//! The matrix-free path (FFT Hankel products + truncated SVD) gives the dense path's
//! eigenvalues: 1e-8 on noise-free data, 1e-6 with 15 % noise, on the DTA-like set and
//! on random stable systems; and the truncated SVD recovers known spectra on each of its
//! routes.

use crate::common;

use common::{assert_eigenvalues_match, eigenvalue_difference};
use era::identify::{identify, EraOptions};
use era::linalg::rng::Minstd;
use era::pipeline::realize::{realize, realize_naive, RealizeOptions, SvdPath};
use era::sim::{add_noise, ModalSpec, ModalStructure};
use era::sources::frf::MarkovSequence;
use era::Quantity;
use era_testkit::{difference, tol, Scale};
use faer::Mat;
use proptest::prelude::*;

/// Checks the matrix-free path's eigenvalues against the dense path's within `tol`, and
/// returns its passes.
#[track_caller]
fn both_paths(frf: &era::FrfData, what: &str, tol: f64) -> usize {
    let run = |svd| {
        identify(frf, &{
            let mut o = EraOptions::thesis_dta();
            o.svd = svd;
            o
        })
        .unwrap()
    };
    let (dense, free) = (run(SvdPath::Dense), run(SvdPath::MatrixFree));
    assert_eq!(free.realization.svd_path, SvdPath::MatrixFree);
    assert_eq!(free.realization.singular_values.len(), 80);
    let (dense_poles, free_poles) = (dense.model.poles().unwrap(), free.model.poles().unwrap());
    assert_eigenvalues_match(what, &free_poles, &dense_poles, tol);
    free.realization.svd_iterations.unwrap()
}

#[test]
fn dta_like_set_without_and_with_noise() {
    let structure = ModalStructure::random(&ModalSpec::default()).unwrap();
    let clean = structure.frf(801, 0.025, Quantity::Acceleration).unwrap();
    both_paths(&clean, "noise-free", 1e-8);
    let noisy = add_noise(&clean, 0.15, 42).unwrap();
    let passes = both_paths(&noisy, "15 % noise", 1e-6);
    // σ81/σ80 = 0.995: subspace iteration needed 24 passes of 120 columns each way here,
    // the restarted block Krylov iteration 7–8. The unrestarted phase (era::linalg::tsvd) in
    // blocks of 13 finishes within 480 columns each way, without a restart (its room is
    // 784 columns).
    let block = era::linalg::tsvd::default_block(80);
    assert_eq!(block, 13);
    assert!(
        passes * block <= 480,
        "15 % noise: {passes} passes of {block} columns"
    );
}

#[test]
fn the_figure_sees_past_a_fixed_order_on_the_same_hankel() {
    // A matrix-free run keeps its 80 values; hankel_singular_values gives more of the
    // same H0, which the dense path computes all of.
    let structure = ModalStructure::random(&ModalSpec::default()).unwrap();
    let clean = structure.frf(801, 0.025, Quantity::Acceleration).unwrap();
    let noisy = add_noise(&clean, 0.15, 42).unwrap();
    let options = |svd| {
        let mut o = EraOptions::thesis_dta();
        o.svd = svd;
        o
    };
    let dense = identify(&noisy, &options(SvdPath::Dense)).unwrap();
    let more = era::identify::hankel_singular_values(&noisy, &options(SvdPath::MatrixFree), 180)
        .unwrap()
        .expect("ERA factors the thesis Hankel");
    assert_eq!(more.len(), 180);
    let all = &dense.realization.singular_values;
    let largest = all[0];
    for (k, (a, b)) in more.iter().zip(all).enumerate() {
        assert!((a - b).abs() <= 1e-5 * largest, "σ{}: {a} vs {b}", k + 1);
    }
    // The run itself is the run: its model and values do not depend on the figure.
    let free = identify(&noisy, &options(SvdPath::MatrixFree)).unwrap();
    assert_eq!(free.realization.singular_values.len(), 80);
    // ERA/DC factors another matrix: nothing to show.
    let mut dc = options(SvdPath::MatrixFree);
    dc.realizer = era::identify::Realizer::EraDc;
    assert!(era::identify::hankel_singular_values(&noisy, &dc, 180)
        .unwrap()
        .is_none());
}

/// Markov blocks `C A^(k−1) B` of a random stable discrete system (modal blocks with
/// radius 0.6–0.97, hidden by a similarity), plus noise of `noise` × each pair's RMS.
fn markov_of_random_system(
    seed: u64,
    modes: usize,
    q: usize,
    p: usize,
    samples: usize,
    noise: f64,
) -> MarkovSequence {
    let mut rng = Minstd::new(seed);
    let n = 2 * modes;
    let mut a = Mat::<f64>::zeros(n, n);
    for k in 0..modes {
        let radius = 0.6 + 0.37 * rng.uniform();
        let theta = 0.1 + (2.9 / modes as f64) * (k as f64 + 0.2 + 0.6 * rng.uniform());
        let (re, im) = (radius * theta.cos(), radius * theta.sin());
        a[(2 * k, 2 * k)] = re;
        a[(2 * k, 2 * k + 1)] = -im;
        a[(2 * k + 1, 2 * k)] = im;
        a[(2 * k + 1, 2 * k + 1)] = re;
    }
    let b = Mat::from_fn(n, p, |_, _| rng.normal());
    let c = Mat::from_fn(q, n, |_, _| rng.normal());
    let mut markov = MarkovSequence::zeros(q, p, samples);
    let mut power = Mat::<f64>::identity(n, n);
    for k in 1..samples {
        let y = &c * &power * &b;
        for i in 0..q {
            for j in 0..p {
                markov.set(k, i, j, y[(i, j)]);
            }
        }
        power = &power * &a;
    }
    if noise > 0.0 {
        for i in 0..q {
            for j in 0..p {
                let rms = ((1..samples)
                    .map(|k| markov.get(k, i, j).powi(2))
                    .sum::<f64>()
                    / samples as f64)
                    .sqrt();
                for k in 1..samples {
                    let v = markov.get(k, i, j) + noise * rms * rng.normal();
                    markov.set(k, i, j, v);
                }
            }
        }
    }
    markov
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn random_stable_systems_agree(seed in 1u64..1_000_000, modes in 1usize..8, q in 1usize..4, p in 1usize..4, noisy in any::<bool>()) {
        let states = 2 * modes;
        let hankel_factor = 6 + 12 / q.min(p);
        let noise = if noisy { 0.15 } else { 0.0 };
        let markov = markov_of_random_system(seed, modes, q, p, states * hankel_factor + 2, noise);
        let run = |svd| realize(&markov, 1.0, &{
            let mut o = RealizeOptions::new(states, hankel_factor);
            o.svd = svd;
            o
        });
        let dense = run(SvdPath::Dense).unwrap();
        let free = run(SvdPath::MatrixFree).unwrap();
        let dense_poles = dense.model.poles().unwrap();
        let diff = eigenvalue_difference(&dense_poles, &free.model.poles().unwrap());
        let bound = if noisy { 1e-6 } else { 1e-8 };
        prop_assert!(diff.within(bound), "seed {}, {}x{}, {} states, noise {}: {}, tolerance {:e}", seed, q, p, states, noise, diff, bound);
        // The dense path against its naive reference (element-wise Hankels, the full SVD,
        // plain loops): singular values to rounding (Weyl: c · ε · n · σ₁ for n rows),
        // poles within the bound above.
        let naive = realize_naive(&markov, 1.0, &RealizeOptions::new(states, hankel_factor)).unwrap();
        let (sv, naive_sv) = (&dense.singular_values, &naive.singular_values);
        let rows = dense.hankel_size.0;
        let diff = difference(&sv[..], &naive_sv[..], Scale::Largest);
        prop_assert!(diff.within(tol(2.0, rows, 1.0)), "seed {}: singular values {}", seed, diff);
        let diff = eigenvalue_difference(&naive.model.poles().unwrap(), &dense_poles);
        prop_assert!(diff.within(bound), "seed {}: poles against the naive reference {}", seed, diff);
    }
}

/// `Q1 diag(d) Q2ᵀ` with random orthonormal `Q1` (`m × r`) and `Q2` (`n × r`).
fn with_spectrum(m: usize, n: usize, d: &[f64], seed: u64) -> Mat<f64> {
    let mut rng = Minstd::new(seed);
    let r = d.len();
    let q1 = Mat::from_fn(m, r, |_, _| rng.normal())
        .qr()
        .compute_thin_Q();
    let q2 = Mat::from_fn(n, r, |_, _| rng.normal())
        .qr()
        .compute_thin_Q();
    let scaled = Mat::from_fn(m, r, |i, j| q1[(i, j)] * d[j]);
    &scaled * q2.transpose()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    /// The truncated SVD on every route (the unrestarted phase first, the opening then
    /// the phase, the restarted iteration alone; any depth) against the known spectrum:
    /// slow or fast decay, a cluster of equal values up to the block floor, exact low
    /// rank. The singular values to 1e-10 σ₁, and the triplets satisfy both
    /// `A v = σ u` and `Aᵀ u = σ v` to 1e-10 σ₁ (vectors within a cluster are any basis
    /// of it, so they are checked through the residuals).
    #[test]
    fn truncated_svd_recovers_known_spectra(
        seed in 1u64..1_000_000,
        m in 60usize..220,
        n in 60usize..220,
        rank in 1usize..24,
        decay in 0.80f64..0.995,
        cluster in 1usize..7,
        low_rank in any::<bool>(),
        block in prop::sample::select(vec![0usize, 8, 12]),
        depth in 1usize..5,
    ) {
        let limit = m.min(n);
        let rank = rank.min(limit / 3);
        prop_assume!(rank >= 1);
        // A cluster of `cluster` equal values after the first, then geometric decay; exact
        // low rank stops the spectrum at `rank + 3` values.
        let len = if low_rank { (rank + 3).min(limit) } else { limit };
        let d: Vec<f64> = (0..len)
            .map(|i| {
                let j = if i >= 1 && i <= cluster { 1 } else { i };
                decay.powi(j as i32)
            })
            .collect();
        let a = with_spectrum(m, n, &d, seed);
        let options = {
            let mut o = era::linalg::tsvd::TruncatedSvdOptions::new(rank);
            o.block = block;
            o.depth = depth;
            o
        };
        let t = era::linalg::tsvd::truncated_svd(&a, &options).unwrap();
        prop_assert!(t.residual <= options.tolerance);
        let (av, atu) = (&a * &t.v, a.transpose() * &t.u);
        for i in 0..rank {
            prop_assert!((t.s[i] - d[i]).abs() <= 1e-10 * d[0], "σ{}: {} against {}", i, t.s[i], d[i]);
            let left: f64 = (0..m).map(|k| (av[(k, i)] - t.s[i] * t.u[(k, i)]).powi(2)).sum::<f64>().sqrt();
            let right: f64 = (0..n).map(|k| (atu[(k, i)] - t.s[i] * t.v[(k, i)]).powi(2)).sum::<f64>().sqrt();
            prop_assert!(left <= 1e-10 * d[0] && right <= 1e-10 * d[0], "triplet {}: {:e} {:e}", i, left, right);
        }
    }
}
