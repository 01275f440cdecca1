//! `era::refine` on the DTA-like synthetic set and the thesis truth model.

use era::refine::{refine, RefineOptions, Refinement, Residuals};
use era::response::frequency_response;
use era::sim::{add_noise, ModalSpec, ModalStructure};
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

/// Relative errors of the found frequencies and damping ratios against the nearest true
/// mode, and how many true modes have a found mode within 1e-3 relative.
fn errors(s: &ModalStructure, r: &Refinement) -> (Vec<f64>, Vec<f64>, usize) {
    let mut fe = Vec::new();
    let mut ze = Vec::new();
    let mut found = 0;
    for (f, z) in s.frequencies_hz.iter().zip(&s.damping_ratios) {
        let best = r
            .modes
            .iter()
            .min_by(|a, b| (a.frequency_hz - f).abs().total_cmp(&(b.frequency_hz - f).abs()))
            .unwrap();
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

/// `‖G − Ĝ‖/‖G‖` over lines `band` of the model's own (A, B, C, D) response.
fn state_space_error(frf: &FrfData, r: &Refinement) -> f64 {
    let ss = r.to_state_space(frf.quantity()).unwrap();
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
    let (s, frf) = dta(0.0);
    let start = perturbed_start(&s, 17);
    let mut options = RefineOptions::default();
    options.residuals = Residuals::Upper;
    let clock = std::time::Instant::now();
    let r = refine(&frf, &start, &options, &mut |i, c| eprintln!("iter {i} cost {c:e}")).unwrap();
    eprintln!("{:?} s, {} modes, dropped {:?}", clock.elapsed(), r.modes.len(), r.dropped);
    let (fe, ze, found) = errors(&s, &r);
    eprintln!("found {found} median f {:e} z {:e} fit {:e} -> {:e}", median(fe.clone()), median(ze.clone()), r.fit_before, r.fit_after);
    let sse = state_space_error(&frf, &r);
    eprintln!("ss error {sse:e}");
    assert_eq!(found, 40);
    assert_eq!(r.modes.len(), 40, "dropped {:?}", r.dropped);
    assert!(median(fe) <= 1e-9);
    assert!(median(ze) <= 1e-7);
    assert!(sse <= 1e-8, "{sse:e}");
    assert!(r.converged);
}

#[test]
fn dta_with_5_percent_noise_reaches_the_noise_floor() {
    let (s, frf) = dta(0.05);
    let start = perturbed_start(&s, 17);
    let mut options = RefineOptions::default();
    options.residuals = Residuals::Upper;
    let clock = std::time::Instant::now();
    let r = refine(&frf, &start, &options, &mut |i, c| eprintln!("iter {i} cost {c:e}")).unwrap();
    eprintln!("{:?} s, {} modes, dropped {:?}", clock.elapsed(), r.modes.len(), r.dropped);
    let (fe, ze, found) = errors(&s, &r);
    eprintln!("found {found} median f {:e} z {:e} fit {:e} -> {:e}", median(fe.clone()), median(ze.clone()), r.fit_before, r.fit_after);
    let sse = state_space_error(&frf, &r);
    eprintln!("ss error {sse:e}");
}

#[test]
#[ignore]
fn dbg_bench_case() {
    let (s, frf) = dta(0.05);
    let mut start = perturbed_start(&s, 17);
    start.truncate(39);
    start.insert(17, pole(s.frequencies_hz[17], s.damping_ratios[17]));
    let mut options = RefineOptions::default();
    options.residuals = Residuals::Upper;
    let env = |k: &str| std::env::var(k).ok();
    if let Some(t) = env("TOL") { options.tolerance = t.parse().unwrap(); }
    options.real_modes = env("REAL").is_some();
    options.reciprocal = env("RECIP").is_some();
    let clock = std::time::Instant::now();
    let r = refine(&frf, &start, &options, &mut |_, _| {}).unwrap();
    eprintln!("{:?} s, {} modes, it {} dropped {:?}", clock.elapsed(), r.modes.len(), r.iterations, r.dropped);
    let (fe, ze, found) = errors(&s, &r);
    eprintln!("found {found} median f {:e} z {:e} fit {:e} -> {:e}", median(fe.clone()), median(ze.clone()), r.fit_before, r.fit_after);
    if env("MODES").is_some() { for m in &r.modes { eprintln!("{:.5} {:.3e} ± {:.2e} {:.2e}  c {:.2e}", m.frequency_hz, m.damping_ratio, m.frequency_std_hz, m.damping_ratio_std, m.contribution); } }
}

#[test]
#[ignore]
fn dbg_truth() {
    use era::identify::{identify, EraOptions};
    use era::sim::{truth_model, truth_model_frf};
    let exact: Vec<Complex64> = truth_model().poles().unwrap().into_iter().filter(|s| s.im > 0.0).collect();
    let mut fe = [0.0f64; 4];
    for seed in 1..=5u64 {
        let frf = truth_model_frf(Some((0.15, seed))).unwrap();
        let found = identify(&frf, &EraOptions::thesis_truth_model()).unwrap();
        let start: Vec<Complex64> = found.modal.modes.iter().map(|m| m.continuous_pole).collect();
        let mut options = RefineOptions::default();
        options.residuals = Residuals::Upper;
        options.sample_time_s = Some(1.0 / era::sim::TRUTH_SAMPLE_RATE_HZ);
        if std::env::var("REAL").is_ok() { options.real_modes = true; }
        if std::env::var("RECIP").is_ok() { options.reciprocal = true; }
        if std::env::var("IV").is_ok() {
            let nl = frf.lines();
            let mut w = Vec::new();
            for pair in 0..9 {
                let v = &frf.values()[pair * nl..(pair + 1) * nl];
                let ms = v.iter().map(|x| x.norm_sqr()).sum::<f64>() / nl as f64;
                w.extend(std::iter::repeat(ms).take(nl));
            }
            options.weighting = era::refine::Weighting::InverseVariance(w);
        }
        let r = refine(&frf, &start, &options, &mut |_, _| {}).unwrap();
        for (k, e) in exact.iter().enumerate() {
            let fe_true = e.norm() / (2.0 * PI);
            let era = found.modal.modes.iter().map(|m| (m.frequency_hz - fe_true).abs()).fold(f64::INFINITY, f64::min);
            let refd = r.modes.iter().map(|m| (m.frequency_hz - fe_true).abs()).fold(f64::INFINITY, f64::min);
            eprint!("[{k}: era {era:.2} ref {refd:.2}] ");
            fe[k] += refd;
        }
        eprintln!(" it {} fit {:.3}->{:.3} dropped {:?}", r.iterations, r.fit_before, r.fit_after, r.dropped);
    }
}
