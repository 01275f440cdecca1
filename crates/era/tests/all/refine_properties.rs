//! `era::refine` on small systems: exact recovery (a property test), the naive
//! reference, reciprocity and stability, the state-space model of every quantity, the
//! Monte Carlo check of the standard deviations, and bad input.

use era::linalg::rng::Minstd;
use era::pipeline::fit::frequency_response;
use era::refine::{refine, refine_naive, RefineOptions, Refinement, Residuals, Weighting};
use era::sim::{add_noise, ModalSpec, ModalStructure};
use era::{Complex64, EraError, FrfData, Quantity};
use era_testkit::{assert_matches_naive, Scale};
use proptest::prelude::*;
use std::f64::consts::PI;

fn pole(f_hz: f64, zeta: f64) -> Complex64 {
    let w = 2.0 * PI * f_hz;
    Complex64::new(-zeta * w, w * (1.0 - zeta * zeta).sqrt())
}

fn kappa(q: Quantity) -> i32 {
    match q {
        Quantity::Displacement => 0,
        Quantity::Velocity => 1,
        Quantity::Acceleration => 2,
    }
}

/// A pole–residue system written out here, independently of the module:
/// `Σ s^κ R/(jω − s) + c.c. + U + L (jω)^(κ−2)`.
struct System {
    poles: Vec<Complex64>,
    residues: Vec<Vec<Complex64>>,
    upper: Vec<f64>,
    lower: Vec<f64>,
    q: usize,
    p: usize,
}

impl System {
    fn frf(&self, lines: usize, df: f64, quantity: Quantity) -> FrfData {
        let k = kappa(quantity);
        let freq: Vec<f64> = (0..lines).map(|i| i as f64 * df).collect();
        FrfData::from_fn(freq.clone(), self.q, self.p, quantity, |i, j, l| {
            let w = 2.0 * PI * freq[l];
            if w == 0.0 {
                return Complex64::new(0.0, 0.0);
            }
            let jw = Complex64::new(0.0, w);
            let pair = i * self.p + j;
            let mut g = Complex64::new(self.upper[pair], 0.0) + self.lower[pair] * jw.powi(k - 2);
            for (s, r) in self.poles.iter().zip(&self.residues) {
                g += s.powi(k) * r[pair] / (jw - s)
                    + s.conj().powi(k) * r[pair].conj() / (jw - s.conj());
            }
            g
        })
        .unwrap()
    }
}

fn quantity_of(index: usize) -> Quantity {
    [
        Quantity::Displacement,
        Quantity::Velocity,
        Quantity::Acceleration,
    ][index]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 8, .. ProptestConfig::default() })]

    /// Random stable systems, noise-free, are recovered to round-off from poles 0.5 % off
    /// in frequency and 20 % off in damping: with rank-one residues (a structure's, the
    /// default fit) and with free ones (`rank_one` false).
    #[test]
    fn random_stable_systems_are_recovered(seed in 1u64..1_000_000, modes in 1usize..4, qi in 0usize..3, rank_one in any::<bool>()) {
        let quantity = quantity_of(qi);
        let mut rng = Minstd::new(seed);
        let (q, p) = (2, 3);
        let poles: Vec<Complex64> = (0..modes)
            .map(|r| pole(2.0 + 3.0 * r as f64 + rng.uniform(), 0.01 + 0.04 * rng.uniform()))
            .collect();
        let residues: Vec<Vec<Complex64>> = (0..modes)
            .map(|_| {
                if rank_one {
                    let u: Vec<Complex64> = (0..q).map(|_| rng.complex_normal()).collect();
                    let v: Vec<Complex64> = (0..p).map(|_| rng.complex_normal()).collect();
                    (0..q * p).map(|k| u[k / p] * v[k % p]).collect()
                } else {
                    (0..q * p).map(|_| rng.complex_normal()).collect()
                }
            })
            .collect();
        let system = System {
            poles: poles.clone(),
            residues: residues.clone(),
            upper: (0..q * p).map(|_| 1e-3 * rng.normal()).collect(),
            lower: (0..q * p).map(|_| rng.normal()).collect(),
            q,
            p,
        };
        let frf = system.frf(300, 0.05, quantity);
        let start: Vec<Complex64> = poles
            .iter()
            .enumerate()
            .map(|(r, s)| {
                let sign = if r % 2 == 0 { 1.0 } else { -1.0 };
                let f = s.norm() / (2.0 * PI) * (1.0 + 0.005 * sign);
                pole(f, -s.re / s.norm() * (1.0 - 0.2 * sign))
            })
            .collect();
        let mut options = {
        let mut o = RefineOptions::default();
        o.weighting = era::refine::Weighting::Uniform;
        o
    };
        options.rank_one = rank_one;
        let r = refine(&frf, &start, &options, &mut |_, _| {}).unwrap();
        prop_assert_eq!(r.modes.len(), modes);
        prop_assert_eq!(r.rank_one, rank_one);
        for (s, res) in poles.iter().zip(&residues) {
            let m = r.modes.iter().min_by(|a, b| (a.pole - s).norm().total_cmp(&(b.pole - s).norm())).unwrap();
            prop_assert!((m.pole - s).norm() <= 1e-9 * s.norm(), "{} vs {}", m.pole, s);
            let scale = res.iter().map(|x| x.norm()).fold(0.0, f64::max);
            for (a, b) in m.residue.iter().zip(res) {
                prop_assert!((a - b).norm() <= 1e-7 * scale, "{} vs {}", a, b);
            }
        }
        prop_assert!(r.fit_after <= 1e-10, "{}", r.fit_after);
        if rank_one {
            // Two states per mode, and the lower residual's double integrator per input.
            let model = r.to_state_space(quantity).unwrap();
            let chains: usize = r
                .residual_terms(quantity)
                .iter()
                .filter(|(e, _)| *e < 0)
                .map(|(e, _)| e.unsigned_abs() as usize * p)
                .sum();
            prop_assert_eq!(model.states(), 2 * modes + chains);
        }
    }
}

/// A small noisy structure: 2×2, 3 modes in 2–8 Hz, 401 lines at 0.025 Hz.
fn small(quantity: Quantity, noise: f64, seed: u64) -> (ModalStructure, FrfData) {
    let spec = ModalSpec {
        fmin_hz: 2.0,
        fmax_hz: 8.0,
        collocated: false,
        damping_min: 0.01,
        damping_max: 0.03,
        ..ModalSpec::new(2, 2, 3)
    };
    let s = ModalStructure::random(&spec).unwrap();
    let mut frf = s.frf(401, 0.025, quantity).unwrap();
    if noise > 0.0 {
        frf = add_noise(&frf, noise, seed).unwrap();
    }
    (s, frf)
}

fn start_of(s: &ModalStructure) -> Vec<Complex64> {
    s.poles()
        .iter()
        .map(|p| pole(p.norm() / (2.0 * PI) * 1.004, -p.re / p.norm() * 1.2))
        .collect()
}

#[test]
fn naive_and_fast_paths_agree() {
    let (s, frf) = small(Quantity::Acceleration, 0.05, 3);
    let mut options = {
        let mut o = RefineOptions::default();
        o.weighting = era::refine::Weighting::Uniform;
        o
    };
    options.residuals = Residuals::Upper;
    // The variable-projection fit itself (the rank-one stage after it is shared).
    options.rank_one = false;
    let fast = refine(&frf, &start_of(&s), &options, &mut |_, _| {}).unwrap();
    let naive = refine_naive(&frf, &start_of(&s), &options, &mut |_, _| {}).unwrap();
    assert_eq!(fast.modes.len(), 3);
    assert_eq!(naive.modes.len(), 3);
    // Two iterative fits that stop at their own tolerances: fixed bounds, not rounding.
    let entry = Scale::Entry;
    let (before, after) = ([fast.cost_before], [fast.cost_after]);
    assert_matches_naive("cost before", &before, &[naive.cost_before], entry, 1e-10);
    assert_matches_naive("cost after", &after, &[naive.cost_after], entry, 1e-7);
    let poles = |r: &Refinement| r.modes.iter().map(|m| m.pole).collect::<Vec<_>>();
    assert_matches_naive("poles", &poles(&fast), &poles(&naive), entry, 1e-6);
    for (a, b) in fast.modes.iter().zip(&naive.modes) {
        // Kaufman's normal matrix and the full one differ by a term of the noise's order.
        assert!((a.frequency_std_hz / b.frequency_std_hz - 1.0).abs() < 0.1);
        assert!((a.damping_ratio_std / b.damping_ratio_std - 1.0).abs() < 0.1);
    }
}

#[test]
fn reciprocal_fit_is_symmetric_and_stable() {
    let spec = ModalSpec {
        fmin_hz: 2.0,
        fmax_hz: 8.0,
        ..ModalSpec::new(3, 3, 4)
    };
    let s = ModalStructure::random(&spec).unwrap();
    let frf = add_noise(&s.frf(401, 0.025, Quantity::Velocity).unwrap(), 0.05, 5).unwrap();
    let mut start = start_of(&s);
    // An unstable start pole is reflected into the left half-plane.
    start[1].re = -start[1].re;
    let mut options = {
        let mut o = RefineOptions::default();
        o.weighting = era::refine::Weighting::Uniform;
        o
    };
    options.reciprocal = true;
    let r = refine(&frf, &start, &options, &mut |_, _| {}).unwrap();
    assert_eq!(r.modes.len(), 4);
    assert!(r.rank_one);
    for m in &r.modes {
        assert!(m.pole.re < 0.0 && m.pole.im > 0.0);
        for i in 0..3 {
            for j in 0..3 {
                assert_eq!(m.residue[i * 3 + j], m.residue[j * 3 + i]);
            }
        }
        // ψψᵀ: rank one, R_ii R_jj = R_ij², with noise.
        for i in 0..3 {
            for j in 0..3 {
                let (a, b) = (
                    m.residue[i * 4] * m.residue[j * 4],
                    m.residue[i * 3 + j].powi(2),
                );
                assert!((a - b).norm() <= 1e-10 * a.norm().max(b.norm()));
            }
        }
    }
    // Free residues (reciprocal too) are not rank one with noise.
    options.rank_one = false;
    let free = refine(&frf, &start, &options, &mut |_, _| {}).unwrap();
    let m = &free.modes[0];
    let (a, b) = (m.residue[0] * m.residue[4], m.residue[1].powi(2));
    assert!((a - b).norm() > 1e-6 * a.norm());
    for term in [&r.lower, &r.upper] {
        let t = term.as_ref().unwrap();
        for i in 0..3 {
            for j in 0..3 {
                assert_eq!(t[(i, j)], t[(j, i)]);
            }
        }
    }
    for (true_pole, m) in s.poles().iter().zip(&r.modes) {
        assert!((m.pole - true_pole).norm() < 1e-2 * true_pole.norm());
    }
    // The same fit without reciprocity has non-symmetric residues.
    let free = refine(
        &frf,
        &start,
        &{
            let mut o = RefineOptions::default();
            o.weighting = era::refine::Weighting::Uniform;
            o
        },
        &mut |_, _| {},
    )
    .unwrap();
    assert!(free.modes[0].residue[1] != free.modes[0].residue[3]);
}

/// `‖a − b‖/‖b‖`.
fn relative(a: &[Complex64], b: &[Complex64]) -> f64 {
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y).norm_sqr()).sum();
    let den: f64 = b.iter().map(|y| y.norm_sqr()).sum();
    (num / den).sqrt()
}

#[test]
fn state_space_model_reproduces_the_response_in_every_quantity() {
    let freq: Vec<f64> = (1..200).map(|k| k as f64 * 0.05).collect();
    for data_quantity in [
        Quantity::Displacement,
        Quantity::Velocity,
        Quantity::Acceleration,
    ] {
        let (s, frf) = small(data_quantity, 0.05, 9);
        for residuals in [
            Residuals::None,
            Residuals::Lower,
            Residuals::Upper,
            Residuals::Both,
        ] {
            let mut options = {
                let mut o = RefineOptions::default();
                o.weighting = era::refine::Weighting::Uniform;
                o
            };
            options.residuals = residuals;
            let r = refine(&frf, &start_of(&s), &options, &mut |_, _| {}).unwrap();
            for out in [
                Quantity::Displacement,
                Quantity::Velocity,
                Quantity::Acceleration,
            ] {
                let has_upper = r.upper.is_some();
                match r.to_state_space(out) {
                    Ok(ss) => {
                        let g = frequency_response(&ss, &freq).unwrap();
                        let want = r.response(&freq, out);
                        let e = relative(&g, &want);
                        assert!(
                            e <= 1e-10,
                            "{data_quantity} data, {residuals:?}, {out} out: {e:e}"
                        );
                    }
                    Err(EraError::InvalidParameter {
                        name: "quantity", ..
                    }) => {
                        assert!(has_upper && kappa(out) > kappa(data_quantity));
                    }
                    Err(e) => panic!("{e}"),
                }
            }
            // The data's own quantity always works and is the fit.
            let own = r.response(&frf.frequency_hz()[r.band.0..r.band.1], data_quantity);
            assert!(own.iter().all(|v| v.re.is_finite() && v.im.is_finite()));
        }
    }
}

#[test]
fn z_domain_model_is_the_zero_order_hold_of_its_state_space() {
    // A sampled system: the ZOH model of a small structure, its discrete FRF.
    let (s, _) = small(Quantity::Displacement, 0.0, 1);
    let ts = 1.0 / 40.0;
    let discrete = s.state_space(Quantity::Displacement).c2d(ts).unwrap();
    let freq: Vec<f64> = (0..401).map(|k| k as f64 * 0.05).collect();
    let values = frequency_response(&discrete, &freq).unwrap();
    let frf = FrfData::new(freq.clone(), 2, 2, values, Quantity::Displacement).unwrap();
    let mut options = {
        let mut o = RefineOptions::default();
        o.weighting = era::refine::Weighting::Uniform;
        o
    };
    options.sample_time_s = Some(ts);
    options.residuals = Residuals::Upper;
    let r = refine(&frf, &start_of(&s), &options, &mut |_, _| {}).unwrap();
    for (p, m) in s.poles().iter().zip(&r.modes) {
        assert!((m.pole - p).norm() <= 1e-9 * p.norm(), "{} vs {p}", m.pole);
    }
    let ss = r
        .to_state_space(Quantity::Displacement)
        .unwrap()
        .c2d(ts)
        .unwrap();
    let g = frequency_response(&ss, &freq[1..]).unwrap();
    assert!(relative(&g, &r.response(&freq[1..], Quantity::Displacement)) <= 1e-10);
    assert!(matches!(
        r.to_state_space(Quantity::Velocity),
        Err(EraError::InvalidParameter { .. })
    ));
}

fn std_of(v: &[f64]) -> f64 {
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

#[test]
fn monte_carlo_spread_matches_the_predicted_standard_deviations() {
    // Complex Gaussian noise of one variance on every value (the model of the
    // estimator), 60 re-fits.
    let (s, clean) = small(Quantity::Displacement, 0.0, 0);
    let sigma = 0.02 * clean.values().iter().map(|v| v.norm()).fold(0.0, f64::max);
    let runs = 60;
    let modes = 3;
    let mut freqs = vec![Vec::new(); modes];
    let mut zetas = vec![Vec::new(); modes];
    let mut predicted_f = vec![0.0; modes];
    let mut predicted_z = vec![0.0; modes];
    let mut options = {
        let mut o = RefineOptions::default();
        o.weighting = era::refine::Weighting::Uniform;
        o
    };
    options.residuals = Residuals::None;
    for run in 0..runs {
        let mut rng = Minstd::new(1000 + run as u64);
        let values: Vec<Complex64> = clean
            .values()
            .iter()
            .map(|v| v + rng.complex_normal() * sigma)
            .collect();
        let frf = FrfData::new(
            clean.frequency_hz().to_vec(),
            2,
            2,
            values,
            clean.quantity(),
        )
        .unwrap();
        let r = refine(&frf, &s.poles(), &options, &mut |_, _| {}).unwrap();
        assert_eq!(r.modes.len(), modes);
        // σ² per real observation is half the complex variance.
        assert!((r.noise_variance / (sigma * sigma / 2.0) - 1.0).abs() < 0.1);
        for (m, mode) in r.modes.iter().enumerate() {
            freqs[m].push(mode.frequency_hz);
            zetas[m].push(mode.damping_ratio);
            predicted_f[m] += mode.frequency_std_hz / runs as f64;
            predicted_z[m] += mode.damping_ratio_std / runs as f64;
        }
    }
    for m in 0..modes {
        let rf = std_of(&freqs[m]) / predicted_f[m];
        let rz = std_of(&zetas[m]) / predicted_z[m];
        assert!(
            (rf - 1.0).abs() <= 0.3,
            "mode {m}: frequency spread / predicted = {rf}"
        );
        assert!(
            (rz - 1.0).abs() <= 0.3,
            "mode {m}: damping spread / predicted = {rz}"
        );
    }
}

#[test]
fn coherence_of_one_is_the_uniform_fit() {
    let (s, frf) = small(Quantity::Acceleration, 0.05, 4);
    let uniform = refine(
        &frf,
        &start_of(&s),
        &{
            let mut o = RefineOptions::default();
            o.weighting = era::refine::Weighting::Uniform;
            o
        },
        &mut |_, _| {},
    )
    .unwrap();
    let mut options = {
        let mut o = RefineOptions::default();
        o.weighting = era::refine::Weighting::Uniform;
        o
    };
    options.weighting = Weighting::Coherence(vec![1.0; frf.values().len()]);
    let weighted = refine(&frf, &start_of(&s), &options, &mut |_, _| {}).unwrap();
    for (a, b) in uniform.modes.iter().zip(&weighted.modes) {
        assert!((a.pole - b.pole).norm() <= 1e-9 * a.pole.norm());
    }
    // Down-weighting one pair changes the fit.
    let mut w = vec![1.0; frf.values().len()];
    w[..frf.lines()].iter_mut().for_each(|x| *x = 0.01);
    options.weighting = Weighting::Coherence(w);
    let other = refine(&frf, &start_of(&s), &options, &mut |_, _| {}).unwrap();
    assert!(
        (other.modes[0].pole - uniform.modes[0].pole).norm() > 1e-9 * uniform.modes[0].pole.norm()
    );
}

fn expect_invalid(r: era::Result<Refinement>, name: &str) {
    match r {
        Err(EraError::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
        Err(e) => panic!("expected invalid {name}, got {e}"),
        Ok(_) => panic!("expected invalid {name}, got a fit"),
    }
}

#[test]
fn bad_input_is_an_error_that_names_it() {
    let (s, frf) = small(Quantity::Acceleration, 0.0, 0);
    let start = start_of(&s);
    let run =
        |start: &[Complex64], options: &RefineOptions| refine(&frf, start, options, &mut |_, _| {});
    let o = {
        let mut o = RefineOptions::default();
        o.weighting = era::refine::Weighting::Uniform;
        o
    };
    expect_invalid(run(&[], &o), "start poles");
    expect_invalid(run(&[Complex64::new(f64::NAN, 1.0)], &o), "start poles");
    expect_invalid(run(&[Complex64::new(-1.0, 0.0)], &o), "start poles");
    let mut b = o.clone();
    b.band = Some((0, 10));
    expect_invalid(run(&start, &b), "band");
    b.band = Some((5, 5000));
    expect_invalid(run(&start, &b), "band");
    b.band = Some((1, 4));
    expect_invalid(run(&start, &b), "band");
    let mut t = o.clone();
    t.tolerance = f64::NAN;
    expect_invalid(run(&start, &t), "tolerance");
    let mut z = o.clone();
    z.sample_time_s = Some(0.0);
    expect_invalid(run(&start, &z), "sample time");
    z.sample_time_s = Some(1.0);
    expect_invalid(run(&start, &z), "band");
    z.sample_time_s = Some(0.01);
    z.real_modes = true;
    expect_invalid(run(&start, &z), "real_modes");
    let mut w = o.clone();
    w.weighting = Weighting::Coherence(vec![1.0; 3]);
    assert!(matches!(
        run(&start, &w),
        Err(EraError::ShapeMismatch { .. })
    ));
    w.weighting = Weighting::Coherence(vec![1.5; frf.values().len()]);
    expect_invalid(run(&start, &w), "coherence");
    w.weighting = Weighting::InverseVariance(vec![0.0; frf.values().len()]);
    expect_invalid(run(&start, &w), "variance");
    w.weighting = Weighting::Coherence(vec![0.0; frf.values().len()]);
    expect_invalid(run(&start, &w), "weighting");
    let rect = ModalStructure::random(&ModalSpec {
        collocated: false,
        ..ModalSpec::new(2, 1, 2)
    })
    .unwrap()
    .frf(100, 0.1, Quantity::Velocity)
    .unwrap();
    let mut rc = o.clone();
    rc.reciprocal = true;
    expect_invalid(refine(&rect, &start, &rc, &mut |_, _| {}), "reciprocal");
}

#[test]
fn weights_constant_per_pair_share_one_basis_and_fit_as_per_line_weights() {
    // Constant weights per pair are fitted through each unit's weighted mean with one
    // basis; weights that vary by one part in 1e9 on one line are fitted pair by pair.
    // The two must give the same fit, plain and reciprocal.
    let spec = ModalSpec {
        fmin_hz: 2.0,
        fmax_hz: 8.0,
        damping_min: 0.01,
        damping_max: 0.03,
        ..ModalSpec::new(2, 2, 3)
    };
    let s = ModalStructure::random(&spec).unwrap();
    let frf = add_noise(&s.frf(401, 0.025, Quantity::Acceleration).unwrap(), 0.05, 9).unwrap();
    let nl = frf.lines();
    let variance: Vec<f64> = (0..frf.values().len())
        .map(|k| [1.0, 4.0, 0.25, 9.0][k / nl])
        .collect();
    let mut nudged = variance.clone();
    nudged[nl + 7] *= 1.0 + 1e-9;
    for reciprocal in [false, true] {
        let fit = |v: &Vec<f64>| {
            let mut options = {
                let mut o = RefineOptions::default();
                o.weighting = era::refine::Weighting::Uniform;
                o
            };
            options.residuals = Residuals::Upper;
            options.reciprocal = reciprocal;
            options.weighting = Weighting::InverseVariance(v.clone());
            // The free fit: rank-one residues need weights constant per pair.
            options.rank_one = false;
            refine(&frf, &start_of(&s), &options, &mut |_, _| {}).unwrap()
        };
        let (shared, separate) = (fit(&variance), fit(&nudged));
        assert_eq!(shared.modes.len(), 3);
        assert_eq!(separate.modes.len(), 3);
        assert!(
            (shared.cost_after - separate.cost_after).abs() <= 1e-7 * shared.cost_after,
            "reciprocal {reciprocal}: {} vs {}",
            shared.cost_after,
            separate.cost_after
        );
        for (a, b) in shared.modes.iter().zip(&separate.modes) {
            assert!((a.pole - b.pole).norm() <= 1e-7 * a.pole.norm());
            for (x, y) in a.residue.iter().zip(&b.residue) {
                assert!((x - y).norm() <= 1e-6 * x.norm().max(1e-3));
            }
            assert!((a.frequency_std_hz / b.frequency_std_hz - 1.0).abs() < 1e-5);
        }
    }
}

#[test]
fn pair_noise_weighting_of_exact_data_still_gives_rank_one_residues() {
    // An exact fit has no noise to weight by and skips the weighted pass; the residues
    // are still the rank-one ones asked for.
    let (s, frf) = small(Quantity::Acceleration, 0.0, 1);
    let mut options = {
        let mut o = RefineOptions::default();
        o.weighting = era::refine::Weighting::Uniform;
        o
    };
    options.weighting = Weighting::PairNoise;
    let r = refine(&frf, &start_of(&s), &options, &mut |_, _| {}).unwrap();
    assert!(r.rank_one);
    assert!(r.fit_after <= 1e-10, "{}", r.fit_after);
    // `before` is at the caller's start poles, not at the first pass's optimum.
    assert!(r.cost_after < r.cost_before && r.fit_before > 1e-3);
    assert_eq!(
        r.to_state_space(Quantity::Acceleration).unwrap().states(),
        2 * 3
    );
    options.rank_one = false;
    assert!(
        !refine(&frf, &start_of(&s), &options, &mut |_, _| {})
            .unwrap()
            .rank_one
    );
}
