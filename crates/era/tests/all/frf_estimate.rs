//! FRF estimation on simulated systems with known FRFs: seeded random inputs through a
//! discrete model (`sim::time_response`), then `frf::estimate`, compared with the model's
//! exact discrete FRF.

use era::estimate::{estimate, Detrend, Estimator, WelchOptions, Window};
use era::linalg::rng::Minstd;
use era::pipeline::fit::frequency_response;
use era::sim::{time_response, truth_model, ModalSpec, ModalStructure};
use era::{Complex64, EraError, Quantity};

fn noise(seed: u64, samples: usize, rms: f64) -> Vec<f64> {
    let mut rng = Minstd::new(seed);
    (0..samples).map(|_| rms * rng.normal()).collect()
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
}

fn hann(frame: usize, fs: f64) -> WelchOptions {
    let o = WelchOptions::new(fs, frame);
    assert_eq!(
        (o.overlap, o.window, o.detrend),
        (0.5, Window::Hann, Detrend::Mean)
    );
    o
}

/// Simulates `model` (discrete) driven by independent unit Gaussian inputs, drops the
/// first `settle` samples, adds output noise of `snr_fraction` of each output's RMS.
fn simulate(
    model: &era::StateSpace,
    samples: usize,
    settle: usize,
    snr_fraction: f64,
    seed: u64,
) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let p = model.inputs();
    let u: Vec<Vec<f64>> = (0..p)
        .map(|j| noise(seed + j as u64, samples + settle, 1.0))
        .collect();
    let y = time_response(model, &u).unwrap();
    let u: Vec<Vec<f64>> = u.into_iter().map(|c| c[settle..].to_vec()).collect();
    let y: Vec<Vec<f64>> = y
        .into_iter()
        .enumerate()
        .map(|(i, c)| {
            let c = &c[settle..];
            let n = noise(seed + 100 + i as u64, c.len(), snr_fraction * rms(c));
            c.iter().zip(n).map(|(a, b)| a + b).collect()
        })
        .collect();
    (u, y)
}

fn slices(v: &[Vec<f64>]) -> Vec<&[f64]> {
    v.iter().map(Vec::as_slice).collect()
}

/// Largest relative H1 error over the lines of every pair that are more than `bands`
/// half-power bandwidths (2ζf) from every resonance. So that a relative error means
/// something, lines are left out where the exact FRF is below `floor` of the pair's peak
/// (antiresonance notches), or where the pair carries less than `SHARE` of its output's
/// power (inputs of equal power: `|H_ij|² / Σ_j |H_ij|²`, from the exact FRFs). There the
/// other inputs' paths dominate the output, and the frame-edge (leakage) error they bring
/// is large relative to this pair's small part. Returns (worst error, lines checked).
const SHARE: f64 = 0.1;

fn h1_error(
    est: &era::estimate::FrfEstimate,
    exact: &[Complex64],
    modes: &[(f64, f64)],
    bands: f64,
    floor: f64,
) -> (f64, usize) {
    let f = est.frf.frequency_hz();
    let (q, p, l) = (est.frf.outputs(), est.frf.inputs(), est.frf.lines());
    let mut worst = 0.0f64;
    let mut checked = 0;
    for pair in 0..q * p {
        let h = &exact[pair * l..(pair + 1) * l];
        let peak = h.iter().map(|v| v.norm()).fold(0.0, f64::max);
        let got = est.frf.pair(pair / p, pair % p);
        for k in 1..l {
            let near = modes
                .iter()
                .any(|(fr, z)| (f[k] - fr).abs() < bands * 2.0 * z * fr);
            let i = pair / p;
            let total: f64 = (0..p).map(|j| exact[(i * p + j) * l + k].norm_sqr()).sum();
            if near || h[k].norm() < floor * peak || h[k].norm_sqr() < SHARE * total {
                continue;
            }
            let e = (got[k] - h[k]).norm() / h[k].norm();
            if e > worst && std::env::var_os("FRF_VERBOSE").is_some() {
                println!("  pair {pair} line {k} ({} Hz): |H| {:.3e} (peak {peak:.3e}) error {e:.3e} coherence {:.6}", f[k], h[k].norm(), est.coherence(pair / p, pair % p)[k]);
            }
            worst = worst.max(e);
            checked += 1;
        }
    }
    (worst, checked)
}

#[test]
fn h1_of_the_truth_model_is_within_one_percent_away_from_resonances() {
    // 3 x 3, ZOH at 25.6 kHz, independent white forces, output noise 0.1 % RMS.
    let fs = 25_600.0;
    let model = truth_model().c2d(1.0 / fs).unwrap();
    let (u, y) = simulate(&model, 2048 * 200, 4096, 1e-5, 11);
    let est = estimate(
        &slices(&u),
        &slices(&y),
        &hann(2048, fs),
        Estimator::H1,
        Quantity::Displacement,
    )
    .unwrap();
    let exact = frequency_response(&model, est.frf.frequency_hz()).unwrap();
    let modes: Vec<(f64, f64)> = era::pipeline::modes::modal_parameters(&truth_model())
        .unwrap()
        .modes
        .iter()
        .map(|m| (m.frequency_hz, m.damping_ratio))
        .collect();
    assert_eq!(modes.len(), 4);
    let (worst, checked) = h1_error(&est, &exact, &modes, 3.0, 1e-3);
    println!("truth model: H1 worst relative error {worst:.3e} over {checked} lines");
    assert!(checked > 1000, "{checked} lines checked");
    assert!(worst < 0.01, "H1 error {worst}");
    // The multiple coherence is high where the outputs have power.
    let m = est.multiple(0);
    let median = {
        let mut v = m[1..800].to_vec();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    assert!(median > 0.999, "median multiple coherence {median}");
}

#[test]
fn h1_of_a_lightly_damped_mimo_structure_is_within_one_percent_away_from_resonances() {
    // 4 outputs x 2 inputs, 6 modes in 20..200 Hz, zeta 1..3 %, acceleration, fs 1024 Hz;
    // frames of 8192 samples (0.125 Hz lines, 8 s) so that leakage stays near the peaks.
    let spec = ModalSpec {
        outputs: 4,
        inputs: 2,
        modes: 6,
        fmin_hz: 20.0,
        fmax_hz: 200.0,
        damping_min: 0.01,
        damping_max: 0.03,
        collocated: false,
        seed: 7,
    };
    let structure = ModalStructure::random(&spec).unwrap();
    let fs = 1024.0;
    let model = structure
        .state_space(Quantity::Acceleration)
        .c2d(1.0 / fs)
        .unwrap();
    let (u, y) = simulate(&model, 8192 * 100, 8192, 1e-5, 5);
    let est = estimate(
        &slices(&u),
        &slices(&y),
        &hann(8192, fs),
        Estimator::H1,
        Quantity::Acceleration,
    )
    .unwrap();
    let exact = frequency_response(&model, est.frf.frequency_hz()).unwrap();
    let modes: Vec<(f64, f64)> = structure
        .frequencies_hz
        .iter()
        .copied()
        .zip(structure.damping_ratios.iter().copied())
        .collect();
    let (worst, checked) = h1_error(&est, &exact, &modes, 3.0, 1e-3);
    println!("modal 4x2: H1 worst relative error {worst:.3e} over {checked} lines");
    assert!(checked > 8000, "{checked} lines checked");
    println!("modes: {modes:?}");
    assert!(worst < 0.01, "H1 error {worst}");
}

/// Median of |estimate / exact| over the lines from 2 % to 45 % of the sample rate.
fn median_gain(est: &era::estimate::FrfEstimate, exact: &[Complex64]) -> f64 {
    let l = est.frf.lines();
    let got = est.frf.pair(0, 0);
    let mut r: Vec<f64> = (l / 25..l * 9 / 10)
        .map(|k| got[k].norm() / exact[k].norm())
        .collect();
    r.sort_by(f64::total_cmp);
    r[r.len() / 2]
}

#[test]
fn h1_h2_and_hv_are_biased_as_theory_says() {
    // SISO truth-model pair (force 1 -> displacement 1), with noise on the measured input
    // (variance 0.25 of the force's): H1 = H·Gxx/(Gxx + Gnn) = 0.8 H, H2 unbiased.
    let fs = 25_600.0;
    let full = truth_model().c2d(1.0 / fs).unwrap();
    let mut model = full.clone();
    model.b = full.b.subcols(0, 1).to_owned();
    model.c = full.c.subrows(0, 1).to_owned();
    model.d = faer::Mat::zeros(1, 1);
    let (u, y) = simulate(&model, 2048 * 60, 4096, 1e-4, 21);
    let measured: Vec<f64> = u[0]
        .iter()
        .zip(noise(99, u[0].len(), 0.5))
        .map(|(a, b)| a + b)
        .collect();
    let opts = hann(2048, fs);
    let f = |e: Estimator| {
        estimate(&[&measured], &slices(&y), &opts, e, Quantity::Displacement).unwrap()
    };
    let (h1, h2, hv) = (f(Estimator::H1), f(Estimator::H2), f(Estimator::Hv));
    let exact = frequency_response(&model, h1.frf.frequency_hz()).unwrap();
    let (g1, g2) = (median_gain(&h1, &exact), median_gain(&h2, &exact));
    println!("input noise: median |H1/H| {g1:.4}, |H2/H| {g2:.4}");
    assert!((g1 - 0.8).abs() < 0.02, "H1 gain {g1}");
    assert!((g2 - 1.0).abs() < 0.02, "H2 gain {g2}");
    // SISO: |H1| <= |Hv| <= |H2| at every line.
    for k in 1..h1.frf.lines() {
        let (a, b, c) = (
            h1.frf.pair(0, 0)[k].norm(),
            hv.frf.pair(0, 0)[k].norm(),
            h2.frf.pair(0, 0)[k].norm(),
        );
        assert!(
            a <= b * (1.0 + 1e-9) && b <= c * (1.0 + 1e-9),
            "line {k}: {a} {b} {c}"
        );
    }
    // Coherence is the same whatever the estimator, and H1/H2 = coherence.
    for k in 1..h1.frf.lines() {
        let ratio = h1.frf.pair(0, 0)[k].norm() / h2.frf.pair(0, 0)[k].norm();
        assert!((ratio - h1.coherence(0, 0)[k]).abs() < 1e-9, "line {k}");
    }
}

#[test]
fn bad_time_data_is_refused_with_a_reason() {
    let x = noise(1, 4096, 1.0);
    let y = noise(2, 4096, 1.0);
    let opts = hann(512, 1000.0);
    let run = |i: &[&[f64]], o: &[&[f64]], opts: &WelchOptions| {
        estimate(i, o, opts, Estimator::H1, Quantity::Acceleration).unwrap_err()
    };
    // Two identical inputs.
    let e = run(&[&x, &x], &[&y], &opts);
    assert!(matches!(e, EraError::SingularInputSpectrum { .. }), "{e}");
    assert!(
        e.to_string().contains("inputs 1 and 2 are fully coherent"),
        "{e}"
    );
    // Proportional inputs too.
    let x2: Vec<f64> = x.iter().map(|v| -3.0 * v).collect();
    assert!(matches!(
        run(&[&x, &x2], &[&y], &opts),
        EraError::SingularInputSpectrum { .. }
    ));
    // One frame, two inputs.
    let e = run(&[&x, &y], &[&y], &hann(4096, 1000.0));
    assert!(e.to_string().contains("fewer than the 2 inputs"), "{e}");
    // NaN.
    let mut bad = y.clone();
    bad[1234] = f64::NAN;
    assert_eq!(
        run(&[&x], &[&y, &bad], &opts),
        EraError::NonFiniteSample {
            role: "output",
            channel: 2,
            sample: 1234
        }
    );
    // Unequal lengths.
    assert!(matches!(
        run(&[&x], &[&y[..4000]], &opts),
        EraError::ShapeMismatch { .. }
    ));
    // Fewer samples than a frame.
    let e = run(&[&x], &[&y], &hann(8192, 1000.0));
    assert!(e.to_string().contains("fewer than one frame"), "{e}");
    // A silent input.
    let flat = vec![2.5; 4096];
    let e = run(&[&x, &flat], &[&y], &opts);
    assert!(e.to_string().contains("input 2 has no power"), "{e}");
    // Parameters.
    let mut o = opts;
    o.overlap = 1.0;
    assert!(matches!(
        run(&[&x], &[&y], &o),
        EraError::InvalidParameter {
            name: "overlap",
            ..
        }
    ));
    o = opts;
    o.sample_rate_hz = 0.0;
    assert!(matches!(
        run(&[&x], &[&y], &o),
        EraError::InvalidParameter {
            name: "sample_rate",
            ..
        }
    ));
    // H2 with fewer outputs than inputs.
    let e = estimate(
        &[&x, &y],
        &[&y],
        &opts,
        Estimator::H2,
        Quantity::Acceleration,
    )
    .unwrap_err();
    assert!(matches!(
        e,
        EraError::InvalidParameter {
            name: "estimator",
            ..
        }
    ));
}

#[test]
fn pooling_records_equals_welch_over_all_their_frames() {
    // Without overlap, a record cut at a frame boundary gives the same frames in two
    // records as in one: pooled spectra and FRFs equal the whole record's.
    let x = noise(3, 8192, 1.0);
    let y: Vec<f64> = x
        .windows(3)
        .map(|w| w[0] - 0.5 * w[1] + 0.25 * w[2])
        .chain([0.0, 0.0])
        .collect();
    let mut opts = hann(1024, 500.0);
    opts.overlap = 0.0;
    let whole = era::estimate::spectra(&[&x], &[&y], &opts, true).unwrap();
    let a = era::estimate::spectra(&[&x[..3072]], &[&y[..3072]], &opts, true).unwrap();
    let b = era::estimate::spectra(&[&x[3072..]], &[&y[3072..]], &opts, true).unwrap();
    let pooled = era::estimate::Spectra::pool(&[a, b]).unwrap();
    assert_eq!(pooled.frames(), whole.frames());
    for (u, v) in pooled.gyx(0, 0).iter().zip(whole.gyx(0, 0)) {
        assert!((u - v).norm() <= 1e-12 * v.norm().max(1e-300), "{u} vs {v}");
    }
    let e = era::estimate::estimate_from_spectra(pooled, Estimator::H2, Quantity::Acceleration)
        .unwrap();
    let w =
        era::estimate::estimate_from_spectra(whole, Estimator::H2, Quantity::Acceleration).unwrap();
    for (u, v) in e.frf.values().iter().zip(w.frf.values()) {
        assert!((u - v).norm() <= 1e-10 * v.norm(), "{u} vs {v}");
    }
    // Records of different settings are refused.
    let c = era::estimate::spectra(&[&x], &[&y], &hann(512, 500.0), true).unwrap();
    let d = era::estimate::spectra(&[&x], &[&y], &hann(1024, 500.0), true).unwrap();
    assert!(era::estimate::Spectra::pool(&[d, c]).is_err());
}
