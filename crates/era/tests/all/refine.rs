//! `era::refine` on the DTA-like synthetic set and the thesis truth model.

use era::identify::{identify, EraOptions};
use era::pipeline::fit::frequency_response;
use era::refine::{refine, RefineOptions, Refinement, Residuals};
use era::sim::{
    add_noise, truth_model, truth_model_frf, ModalSpec, ModalStructure, TRUTH_SAMPLE_RATE_HZ,
};
use era::{Complex64, FrfData, Quantity};
use std::f64::consts::PI;

fn pole(f_hz: f64, zeta: f64) -> Complex64 {
    let w = 2.0 * PI * f_hz;
    Complex64::new(-zeta * w, w * (1.0 - zeta * zeta).sqrt())
}

/// The DTA-like set of `era simulate modal` (defaults: 8×8, 40 modes, 801 lines at
/// 0.025 Hz, acceleration, collocated), with `noise` added as the CLI does.
fn dta(noise: f64) -> (ModalStructure, FrfData) {
    let spec = ModalSpec::default();
    let s = ModalStructure::random(&spec).unwrap();
    let mut frf = s.frf(801, 0.025, Quantity::Acceleration).unwrap();
    if noise > 0.0 {
        frf = add_noise(&frf, noise, spec.seed).unwrap();
    }
    (s, frf)
}

/// True poles with the frequency off by ±0.3 % and the damping by ±20 % (alternating),
/// mode `missing` left out, and two computational poles: one near the missing mode, one
/// in a gap.
fn perturbed_start(s: &ModalStructure, missing: usize) -> Vec<Complex64> {
    let mut start = Vec::new();
    for (r, (f, z)) in s.frequencies_hz.iter().zip(&s.damping_ratios).enumerate() {
        if r == missing {
            continue;
        }
        let sign = if r % 2 == 0 { 1.0 } else { -1.0 };
        start.push(pole(f * (1.0 + 0.003 * sign), z * (1.0 - 0.2 * sign)));
    }
    start.push(pole(s.frequencies_hz[missing] * 1.01, 0.03));
    start.push(pole(17.0, 0.05));
    start
}

/// Every true pole, the frequency off by the fraction `df` and the damping by `dz`,
/// alternately up and down.
fn alternating_start(s: &ModalStructure, df: f64, dz: f64) -> Vec<Complex64> {
    (0..s.frequencies_hz.len())
        .map(|r| {
            let sign = if r % 2 == 0 { 1.0 } else { -1.0 };
            pole(
                s.frequencies_hz[r] * (1.0 + df * sign),
                s.damping_ratios[r] * (1.0 - dz * sign),
            )
        })
        .collect()
}

/// The refined mode nearest in frequency to `f_hz`.
fn nearest(r: &Refinement, f_hz: f64) -> &era::refine::RefinedMode {
    r.modes
        .iter()
        .min_by(|a, b| {
            (a.frequency_hz - f_hz)
                .abs()
                .total_cmp(&(b.frequency_hz - f_hz).abs())
        })
        .unwrap()
}

/// Relative errors of the found frequencies and damping ratios against the nearest true
/// mode, and how many true modes have a found mode within 1e-3 relative.
fn errors(s: &ModalStructure, r: &Refinement) -> (Vec<f64>, Vec<f64>, usize) {
    let mut fe = Vec::new();
    let mut ze = Vec::new();
    let mut found = 0;
    for (f, z) in s.frequencies_hz.iter().zip(&s.damping_ratios) {
        let best = nearest(r, *f);
        let e = (best.frequency_hz - f).abs() / f;
        if e < 1e-3 {
            found += 1;
        }
        fe.push(e);
        ze.push((best.damping_ratio - z).abs() / z);
    }
    (fe, ze, found)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// `‖G − Ĝ‖/‖G‖` over lines `band` of the model's own (A, B, C, D) response: the
/// continuous model, or its zero-order-hold image for a z-domain fit.
fn state_space_error(frf: &FrfData, r: &Refinement) -> f64 {
    let mut ss = r.to_state_space(frf.quantity()).unwrap();
    if let Some(ts) = r.sample_time_s {
        ss = ss.c2d(ts).unwrap();
    }
    let f = &frf.frequency_hz()[r.band.0..r.band.1];
    let g = frequency_response(&ss, f).unwrap();
    let nl = frf.lines();
    let nb = f.len();
    let (mut num, mut den) = (0.0, 0.0);
    for pair in 0..frf.outputs() * frf.inputs() {
        for k in 0..nb {
            let data = frf.values()[pair * nl + r.band.0 + k];
            num += (data - g[pair * nb + k]).norm_sqr();
            den += data.norm_sqr();
        }
    }
    (num / den).sqrt()
}

#[test]
fn dta_noise_free_is_recovered_to_round_off() {
    // 39 of the 40 poles perturbed, one left out with a computational pole near it, and
    // one computational pole in a gap above the modes.
    let (s, frf) = dta(0.0);
    let start = perturbed_start(&s, 17);
    let mut options = {
        let mut o = RefineOptions::default();
        o.weighting = era::refine::Weighting::Uniform;
        o
    };
    options.residuals = Residuals::Upper;
    let r = refine(&frf, &start, &options, &mut |_, _| {}).unwrap();
    let (fe, ze, found) = errors(&s, &r);
    assert_eq!(found, 40);
    assert_eq!(r.modes.len(), 40, "dropped {:?}", r.dropped);
    // The computational pole in the gap has nothing to fit and is said to be dropped.
    assert_eq!(r.dropped.len(), 1);
    assert_eq!(r.dropped[0].0, 40);
    assert!(
        r.dropped[0].1.contains("contribution"),
        "{}",
        r.dropped[0].1
    );
    assert!(median(fe.clone()) <= 1e-9, "{:e}", median(fe));
    assert!(median(ze.clone()) <= 1e-7, "{:e}", median(ze));
    assert!(r.fit_after <= 1e-10 && r.fit_before > 1e-2);
    let sse = state_space_error(&frf, &r);
    assert!(sse <= 1e-8, "{sse:e}");
    assert!(r.converged);
}

#[test]
fn dta_with_5_percent_noise_reaches_the_noise_floor() {
    let (s, frf) = dta(0.05);
    let start = perturbed_start(&s, 17);
    let mut options = {
        let mut o = RefineOptions::default();
        o.weighting = era::refine::Weighting::Uniform;
        o
    };
    options.residuals = Residuals::Upper;
    let r = refine(&frf, &start, &options, &mut |_, _| {}).unwrap();
    let (_, ze, found) = errors(&s, &r);
    assert!(found >= 37, "found {found}");
    // The noise floor: the noise RMS is 5 % of each pair's RMS.
    assert!(r.fit_after <= 1.1 * 0.05, "{}", r.fit_after);
    assert!(median(ze.clone()) <= 0.015, "{}", median(ze));
    assert!(r.modes.iter().all(|m| m.pole.re < 0.0));
    // Rank-one residues: two states per mode (free ones gave up to 16 here).
    assert!(r.rank_one);
    let model = r.to_state_space(Quantity::Acceleration).unwrap();
    assert_eq!(model.states(), 2 * r.modes.len());
    // Each mode's phase in (B, C) is its own, not the SVD's: its largest output entry is
    // real and positive, so round-off in the fit cannot turn a mode's states around.
    let c = &model.c;
    for x in (0..model.states()).step_by(2) {
        let entry = |i: usize| Complex64::new(c[(i, x)], c[(i, x + 1)]);
        let largest = (0..c.nrows()).map(|i| entry(i).norm()).fold(0.0, f64::max);
        let first = (0..c.nrows())
            .find(|&i| entry(i).norm() >= (1.0 - 1e-9) * largest)
            .unwrap();
        let z = entry(first);
        assert!(z.re > 0.0 && z.im == 0.0, "states {x}: {z}");
    }
    let sse = state_space_error(&frf, &r);
    assert!(
        (sse - r.fit_after).abs() <= 1e-9,
        "{sse} vs {}",
        r.fit_after
    );
}

fn exact_truth_poles() -> Vec<Complex64> {
    truth_model()
        .poles()
        .unwrap()
        .into_iter()
        .filter(|s| s.im > 0.0)
        .collect()
}

/// `add_noise` gives each pair noise of 15 % of its RMS: weights of the inverse of each
/// pair's mean square make the least-squares fit the maximum-likelihood one.
fn pair_variance_weights(frf: &FrfData) -> era::refine::Weighting {
    let nl = frf.lines();
    let mut w = Vec::with_capacity(frf.values().len());
    for v in frf.values().chunks(nl) {
        let mean_square = v.iter().map(|x| x.norm_sqr()).sum::<f64>() / nl as f64;
        w.extend(std::iter::repeat_n(mean_square, nl));
    }
    era::refine::Weighting::InverseVariance(w)
}

fn truth_options() -> RefineOptions {
    let mut options = {
        let mut o = RefineOptions::default();
        o.weighting = era::refine::Weighting::Uniform;
        o
    };
    options.residuals = Residuals::Upper;
    options.reciprocal = true;
    options.sample_time_s = Some(1.0 / TRUTH_SAMPLE_RATE_HZ);
    options
}

#[test]
fn truth_model_refined_from_the_thesis_era_poles() {
    // The truth-model FRFs are those of the zero-order-hold model: the z-domain fit
    // contains them exactly.
    let frf = truth_model_frf(None).unwrap();
    let era = identify(&frf, &EraOptions::thesis_truth_model()).unwrap();
    let mut start: Vec<Complex64> = era.modal.modes.iter().map(|m| m.continuous_pole).collect();
    // A repeated start pole is dropped, named by its frequency.
    start.push(start[0]);
    let r = refine(&frf, &start, &truth_options(), &mut |_, _| {}).unwrap();
    assert_eq!(r.dropped.len(), 1, "{:?}", r.dropped);
    let expected = format!(
        "a duplicate of the start pole at {:.6} Hz",
        start[0].norm() / (2.0 * PI)
    );
    assert_eq!(r.dropped[0], (start.len() - 1, expected));
    assert_eq!(r.modes.len(), 4);
    for e in exact_truth_poles() {
        let d = r
            .modes
            .iter()
            .map(|m| (m.pole - e).norm())
            .fold(f64::INFINITY, f64::min);
        assert!(d <= 1e-9 * e.norm(), "{e}: {d:e}");
    }
    assert!(r.fit_after <= 1e-9, "{}", r.fit_after);
    // Its continuous model, discretised again, is the data.
    assert!(state_space_error(&frf, &r) <= 1e-8);
    // Displacement residues of a collocated chain are symmetric.
    for m in &r.modes {
        for i in 0..3 {
            for j in 0..3 {
                assert_eq!(m.residue[i * 3 + j], m.residue[j * 3 + i]);
            }
        }
    }
}

#[test]
fn truth_model_with_15_percent_noise_improves_on_era() {
    let exact = exact_truth_poles();
    let (mut era_err, mut refined_err) = (0.0, 0.0);
    for seed in [11u64, 12, 13] {
        let frf = truth_model_frf(Some((0.15, seed))).unwrap();
        let era = identify(&frf, &EraOptions::thesis_truth_model()).unwrap();
        let start: Vec<Complex64> = era.modal.modes.iter().map(|m| m.continuous_pole).collect();
        let mut options = truth_options();
        options.weighting = pair_variance_weights(&frf);
        let r = refine(&frf, &start, &options, &mut |_, _| {}).unwrap();
        assert_eq!(r.modes.len(), 4);
        assert!(r.fit_after <= r.fit_before);
        for e in &exact {
            let f = e.norm() / (2.0 * PI);
            let nearest = |fs: &mut dyn Iterator<Item = f64>| {
                fs.map(|x| (x - f).abs()).fold(f64::INFINITY, f64::min)
            };
            era_err += nearest(&mut era.modal.modes.iter().map(|m| m.frequency_hz));
            refined_err += nearest(&mut r.modes.iter().map(|m| m.frequency_hz));
        }
    }
    assert!(
        refined_err < era_err,
        "refined {refined_err} Hz, ERA {era_err} Hz"
    );
}

/// The two modes farthest from their neighbours, in half-power bandwidths.
fn isolated_modes(s: &ModalStructure) -> Vec<usize> {
    let f = &s.frequencies_hz;
    let mut gaps: Vec<(f64, usize)> = (0..f.len())
        .map(|r| {
            let nearest = (0..f.len())
                .filter(|&k| k != r)
                .map(|k| (f[k] - f[r]).abs())
                .fold(f64::INFINITY, f64::min);
            (nearest / (s.damping_ratios[r] * f[r]), r)
        })
        .collect();
    gaps.sort_by(|a, b| b.0.total_cmp(&a.0));
    gaps.iter().take(2).map(|g| g.1).collect()
}

#[test]
fn modes_the_start_missed_are_found_in_the_residual() {
    let (s, frf) = dta(0.05);
    let missing = isolated_modes(&s);
    let start: Vec<Complex64> = (0..s.frequencies_hz.len())
        .filter(|r| !missing.contains(r))
        .map(|r| pole(s.frequencies_hz[r] * 1.001, s.damping_ratios[r]))
        .collect();
    let mut options = {
        let mut o = RefineOptions::default();
        o.weighting = era::refine::Weighting::Uniform;
        o
    };
    options.residuals = Residuals::Upper;
    let r = refine(&frf, &start, &options, &mut |_, _| {}).unwrap();
    assert!(!r.added.is_empty(), "nothing added");
    for &m in &missing {
        let f = s.frequencies_hz[m];
        let best = nearest(&r, f);
        assert!(
            (best.frequency_hz - f).abs() <= 1e-3 * f,
            "missed {f} Hz: nearest {} Hz, added {:?}",
            best.frequency_hz,
            r.added
        );
        assert!(best.significance >= r.significance_minimum());
    }
    // Without the scan the fit cannot find them.
    options.add_missed = false;
    let without = refine(&frf, &start, &options, &mut |_, _| {}).unwrap();
    assert!(without.added.is_empty());
    assert!(without.fit_after > r.fit_after);
    let (_, _, found) = errors(&s, &without);
    let (_, _, found_with) = errors(&s, &r);
    assert!(found < found_with, "{found} vs {found_with}");
}

#[test]
fn noise_alone_adds_no_mode_and_every_true_mode_is_significant() {
    let (s, frf) = dta(0.05);
    // Every true pole, the frequency off by ±0.3 % and the damping by ±20 %.
    let start = alternating_start(&s, 0.003, 0.2);
    let mut options = {
        let mut o = RefineOptions::default();
        o.weighting = era::refine::Weighting::Uniform;
        o
    };
    options.residuals = Residuals::Upper;
    let r = refine(&frf, &start, &options, &mut |_, _| {}).unwrap();
    assert!(r.added.is_empty(), "added {:?}", r.added);
    let least = r.significance_minimum();
    assert!(least > 10.0 && least < 13.0, "{least}");
    for m in &r.modes {
        assert!(
            m.significance >= least,
            "{} Hz: {}",
            m.frequency_hz,
            m.significance
        );
    }
}

/// Where the rank-one stage steps aside (too many joint parameters: 40 outputs, 1 input
/// and 50 modes give 4140), the free fit is the result and runs to the caller's
/// tolerance, exactly as with `rank_one = false`; it does not stop at the looser
/// tolerance of a fit that only starts the joint stage.
#[test]
fn a_free_fit_the_rank_one_stage_steps_aside_from_runs_to_the_tolerance() {
    let spec = ModalSpec {
        fmin_hz: 1.0,
        fmax_hz: 9.0,
        collocated: false,
        ..ModalSpec::new(40, 1, 50)
    };
    let s = ModalStructure::random(&spec).unwrap();
    let frf = add_noise(&s.frf(401, 0.025, Quantity::Acceleration).unwrap(), 0.05, 7).unwrap();
    let start: Vec<Complex64> = s
        .frequencies_hz
        .iter()
        .zip(&s.damping_ratios)
        .enumerate()
        .map(|(r, (f, z))| {
            let sign = if r % 2 == 0 { 1.0 } else { -1.0 };
            pole(f * (1.0 + 0.002 * sign), z * (1.0 - 0.2 * sign))
        })
        .collect();
    let mut options = {
        let mut o = RefineOptions::default();
        o.weighting = era::refine::Weighting::Uniform;
        o
    };
    options.weighting = era::refine::Weighting::Uniform;
    options.tolerance = 1e-8;
    options.add_missed = false;
    let stepped_aside = refine(&frf, &start, &options, &mut |_, _| {}).unwrap();
    assert!(!stepped_aside.rank_one);
    options.rank_one = false;
    let free = refine(&frf, &start, &options, &mut |_, _| {}).unwrap();
    assert_eq!(stepped_aside.iterations, free.iterations);
    assert_eq!(stepped_aside.cost_after, free.cost_after);
}

/// A fit that the scan for missed modes follows stops after `LOOK_AFTER` iterations; one
/// the scan then finds nothing in runs on from there. From a start far enough off to
/// need more iterations than that, the default fit (scan on) still ends converged, with
/// the same modes as the fit that runs without a scan and so without a stop.
#[test]
fn a_fit_cut_short_for_the_look_runs_on_to_its_tolerance() {
    let (s, frf) = dta(0.05);
    let start = alternating_start(&s, 0.006, 0.4);
    let options = RefineOptions::default();
    let r = refine(&frf, &start, &options, &mut |_, _| {}).unwrap();
    let mut no_scan = options.clone();
    no_scan.add_missed = false;
    let without = refine(&frf, &start, &no_scan, &mut |_, _| {}).unwrap();
    // The start is far enough off that the final fit, stopped at the look's limit,
    // has not converged: the default fit was cut short and ran on.
    let mut capped = no_scan.clone();
    capped.max_iterations = era::refine::LOOK_AFTER;
    let capped = refine(&frf, &start, &capped, &mut |_, _| {}).unwrap();
    assert!(!capped.converged, "{} iterations", capped.iterations);
    assert!(
        r.converged && without.converged,
        "converged {} (iterations {}), without the scan {}",
        r.converged,
        r.iterations,
        without.converged
    );
    assert!(r.added.is_empty(), "{:?}", r.added);
    assert_eq!(r.modes.len(), without.modes.len());
    for m in &without.modes {
        let other = nearest(&r, m.frequency_hz);
        let sigma = m.pole.re.abs();
        assert!(
            (other.pole - m.pole).norm() <= 0.01 * sigma,
            "{} vs {}",
            other.pole,
            m.pole
        );
    }
}
