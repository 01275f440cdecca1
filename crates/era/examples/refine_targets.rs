//! The targets of the refinement (issue 14), measured.
//!
//! `cargo run --release -p era --example refine_targets -- dta [SEEDS] [NOISES]`: DTA-like
//! 8 × 8 sets with 40 modes (the order issue's recipe), `--states auto` with the thesis
//! preprocessing and a continuous model, then the refinement: modes found within 0.5 %
//! of the truth, spurious physical modes, median relative frequency and damping errors,
//! the refined model's own FRF (from its A, B, C, D) against the data over the band, the
//! noise floor `‖noise‖/‖data‖` over the same lines and quantity, and the time.
//!
//! `cargo run --release -p era --example refine_targets -- table52 [SEEDS]`: the truth
//! model with 15 % noise, thesis settings (Table 5.2), ERA and ERA + refinement (the
//! z-domain fit at the model's sample time): the median |Δf| per mode over the seeds
//! (default 1..=100), and the median of the fit's own predicted standard deviation.
//!
//! Environment: `PAIRNOISE=1` weights each pair by its estimated noise (the CLI's
//! default, `--weighting pair-noise`); `FREE=1` keeps free residues (`--free-residues`); `NOADD=1` does not look for missed modes (`--no-added-modes`); `NORES=1` fits without residual terms and
//! `RECIP=1` with reciprocity (Table 5.2 only); `DEBUG=1` lists every refined mode of a
//! DTA-like set with its start, truth and standard deviations.

use era::identify::{identify, EraOptions, ModelDomain, Order};

use era::refine::identification::refine_identification;

use era::data::identification::Identification;
use era::refine::RefineOptions;
use era::sim::{add_noise, truth_model, truth_model_frf, ModalSpec, ModalStructure};
use era::sources::frf::preprocess::integrate;
use era::{FrfData, Quantity};
use std::time::Instant;

#[path = "../benches/support/sets.rs"]
mod sets;

fn list<T: std::str::FromStr>(arg: Option<&String>, default: Vec<T>) -> Vec<T>
where
    T::Err: std::fmt::Debug,
{
    match arg {
        None => default,
        Some(s) if s.contains("..") => {
            let (a, b) = s.split_once("..").unwrap();
            let (a, b): (usize, usize) = (a.parse().unwrap(), b.parse().unwrap());
            (a..=b).map(|k| k.to_string().parse().unwrap()).collect()
        }
        Some(s) => s.split(',').map(|v| v.parse().unwrap()).collect(),
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// `‖a − b‖/‖a‖` over lines `first..` of every pair.
fn relative(a: &FrfData, b: &[era::Complex64], first: usize) -> f64 {
    let lines = a.lines();
    let (mut num, mut den) = (0.0, 0.0);
    for pair in 0..a.outputs() * a.inputs() {
        for k in first..lines {
            let g = a.values()[pair * lines + k];
            num += (g - b[pair * lines + k]).norm_sqr();
            den += g.norm_sqr();
        }
    }
    (num / den).sqrt()
}

/// One-to-one matching within 0.5 %, nearest first: (truth index, found index) pairs.
fn matching(truth: &[f64], found: &[f64]) -> Vec<(usize, usize)> {
    let mut pairs = Vec::new();
    for (i, t) in truth.iter().enumerate() {
        for (j, f) in found.iter().enumerate() {
            let rel = (f - t).abs() / t;
            if rel <= 0.005 {
                pairs.push((rel, i, j));
            }
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut ti, mut fj) = (vec![false; truth.len()], vec![false; found.len()]);
    let mut out = Vec::new();
    for (_, i, j) in pairs {
        if !ti[i] && !fj[j] {
            ti[i] = true;
            fj[j] = true;
            out.push((i, j));
        }
    }
    out
}

fn dta(seeds: &[u64], noises: &[f64]) -> era::Result<()> {
    println!("seed noise | found spurious | median |df|/f  median |dz|/z | model-vs-data  noise floor  ratio | ERA fit | iterations converged dropped | refine s");
    for &seed in seeds {
        for &noise in noises {
            let spec = ModalSpec {
                seed,
                // The DTA-like set: 8×8, 40 modes in 0.5–14 Hz, ζ 0.5–2 %, collocated.
                ..ModalSpec::default()
            };
            let structure = ModalStructure::random(&spec)?;
            let clean = structure.frf(801, 0.025, Quantity::Acceleration)?;
            let frf = if noise > 0.0 {
                add_noise(&clean, noise, seed)?
            } else {
                clean.clone()
            };
            let options = {
                let mut o = EraOptions::thesis_dta();
                o.domain = ModelDomain::Continuous;
                o.order = Order::Auto;
                o
            };
            let found = identify(&frf, &options)?;
            let era_fit = relative(&found.measured, &found.model_response, found.first_line);
            let clock = Instant::now();
            let mut ropts = {
                let mut o = RefineOptions::default();
                o.weighting = era::refine::Weighting::Uniform;
                o
            };
            ropts.add_missed = std::env::var("NOADD").is_err();
            if std::env::var("PAIRNOISE").is_ok() {
                ropts.weighting = era::refine::Weighting::PairNoise;
            }
            if std::env::var("FREE").is_ok() {
                ropts.rank_one = false;
            }
            let found = refine_identification(found, &frf, &ropts, &mut |_| {}, &mut |_, _| {})?;
            let seconds = clock.elapsed().as_secs_f64();
            report_dta(
                seed, noise, &structure, &clean, &frf, &found, era_fit, seconds,
            )?;
        }
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn report_dta(
    seed: u64,
    noise: f64,
    structure: &ModalStructure,
    clean: &FrfData,
    frf: &FrfData,
    found: &Identification,
    era_fit: f64,
    seconds: f64,
) -> era::Result<()> {
    let physical = sets::physical(found);
    let freqs: Vec<f64> = physical.iter().map(|p| p.0).collect();
    let m = matching(&structure.frequencies_hz, &freqs);
    let ferr: Vec<f64> = m
        .iter()
        .map(|&(i, j)| (freqs[j] - structure.frequencies_hz[i]).abs() / structure.frequencies_hz[i])
        .collect();
    let zerr: Vec<f64> = m
        .iter()
        .map(|&(i, j)| {
            (physical[j].1 - structure.damping_ratios[i]).abs() / structure.damping_ratios[i]
        })
        .collect();
    if std::env::var("DEBUG").is_ok() {
        let r = found.refinement.as_ref().unwrap();
        let matched: Vec<usize> = m.iter().map(|&(_, j)| j).collect();
        let mut j = 0;
        for (rm, q) in r.refinement.modes.iter().zip(&found.quality) {
            if !q.physical {
                println!(
                    "    not physical {:.4} start {:.4} ({:?})",
                    rm.frequency_hz, r.start_frequency_hz[rm.start], q.reason
                );
                continue;
            }
            let start = r.start_frequency_hz[rm.start];
            let added = if rm.start >= r.start_modes() {
                "+"
            } else {
                " "
            };
            let truth = structure
                .frequencies_hz
                .iter()
                .copied()
                .min_by(|a, b| {
                    (a - rm.frequency_hz)
                        .abs()
                        .total_cmp(&(b - rm.frequency_hz).abs())
                })
                .unwrap();
            let (q, p) = (r.refinement.outputs, r.refinement.inputs);
            let residue = faer::Mat::from_fn(q, p, |i, j| {
                let z = rm.residue[i * p + j];
                faer::c64::new(z.re, z.im)
            });
            let sv = residue.singular_values().unwrap();
            println!(
                "  {}{added}start {:.4} -> {:.4} (truth {:.4}) zeta {:.4} ± {:.1e} share {:.2e} sig {:.1} f-std {:.1e} rank ratio {:.3}",
                if matched.contains(&j) { "  " } else { "!!" },
                start,
                rm.frequency_hz,
                truth,
                rm.damping_ratio,
                rm.damping_ratio_std,
                rm.contribution,
                rm.significance,
                rm.frequency_std_hz,
                sv.get(1).copied().unwrap_or(0.0) / sv[0]
            );
            j += 1;
        }
        let hit: Vec<usize> = m.iter().map(|&(i, _)| i).collect();
        for (i, f) in structure.frequencies_hz.iter().enumerate() {
            if !hit.contains(&i) {
                println!(
                    "  -- missed truth {f:.4} Hz, zeta {:.4}",
                    structure.damping_ratios[i]
                );
            }
        }
    }
    let first = found.first_line;
    let fit = relative(&found.measured, &found.model_response, first);
    // The noise over the same lines and quantity as the fit.
    let ni = EraOptions::thesis_dta().integrations;
    let (pc, pn) = (integrate(clean, ni)?, integrate(frf, ni)?);
    let floor = relative(&pn, pc.values(), first);
    let ratio = if floor > 0.0 {
        format!("{:>6.3}", fit / floor)
    } else {
        format!("{:>6}", "-")
    };
    let r = found.refinement.as_ref().unwrap();
    println!(
        "{seed:>4} {noise:>5} | {:>5} {:>8} | {:>13.3e} {:>13.3e} | {:>13.3e} {:>12.3e} {ratio} | {era_fit:.3} | {:>10} {:>9} {:>7} | {seconds:.2}",
        m.len(),
        physical.len() - m.len(),
        median(ferr),
        median(zerr),
        fit,
        floor,
        r.refinement.iterations,
        r.refinement.converged,
        r.refinement.dropped.len()
    );
    Ok(())
}

fn table52(seeds: &[u64]) -> era::Result<()> {
    let truth: Vec<f64> = era::pipeline::modes::modal_parameters(&truth_model())?
        .modes
        .iter()
        .map(|m| m.frequency_hz)
        .collect();
    let options = EraOptions::thesis_truth_model();
    let nearest = |found: &Identification, f: f64| {
        found
            .modal
            .modes
            .iter()
            .map(|m| (m.frequency_hz - f).abs())
            .fold(f64::INFINITY, f64::min)
    };
    let (mut era_err, mut ref_err) = (vec![Vec::new(); 4], vec![Vec::new(); 4]);
    let mut predicted = vec![Vec::new(); 4];
    let mut failures = 0;
    let mut seconds = 0.0;
    for &seed in seeds {
        let frf = truth_model_frf(Some((0.15, seed)))?;
        let found = identify(&frf, &options)?;
        for (k, &f) in truth.iter().enumerate() {
            era_err[k].push(nearest(&found, f));
        }
        let clock = Instant::now();
        let mut ropts = {
            let mut o = RefineOptions::default();
            o.weighting = era::refine::Weighting::Uniform;
            o
        };
        ropts.add_missed = std::env::var("NOADD").is_err();
        if std::env::var("NORES").is_ok() {
            ropts.residuals = era::refine::Residuals::None;
        }
        if std::env::var("RECIP").is_ok() {
            ropts.reciprocal = true;
        }
        if std::env::var("PAIRNOISE").is_ok() {
            ropts.weighting = era::refine::Weighting::PairNoise;
        }
        if std::env::var("FREE").is_ok() {
            ropts.rank_one = false;
        }
        match refine_identification(found, &frf, &ropts, &mut |_| {}, &mut |_, _| {}) {
            Ok(refined) => {
                for (k, &f) in truth.iter().enumerate() {
                    ref_err[k].push(nearest(&refined, f));
                    let j = (0..refined.modal.modes.len())
                        .min_by(|&a, &b| {
                            (refined.modal.modes[a].frequency_hz - f)
                                .abs()
                                .total_cmp(&(refined.modal.modes[b].frequency_hz - f).abs())
                        })
                        .unwrap();
                    if let Some(sd) = refined.quality[j].frequency_std_hz {
                        predicted[k].push(sd);
                    }
                }
            }
            Err(e) => {
                failures += 1;
                eprintln!("seed {seed}: {e}");
            }
        }
        seconds += clock.elapsed().as_secs_f64();
    }
    println!(
        "Table 5.2, 15 % noise, {} seeds ({failures} refinements failed), refinement {:.3} s per seed",
        seeds.len(),
        seconds / seeds.len() as f64
    );
    println!("mode  truth Hz | ERA median |df| Hz | refined median |df| Hz | ratio | predicted std Hz (median) | 0.674 x std");
    for k in 0..4 {
        let (a, b) = (median(era_err[k].clone()), median(ref_err[k].clone()));
        println!(
            "{:>4} {:>9.2} | {:>18.3} | {:>22.3} | {:.3} | {:>25.3} | {:.3}",
            k + 1,
            truth[k],
            a,
            b,
            b / a,
            median(predicted[k].clone()),
            0.674 * median(predicted[k].clone())
        );
    }
    Ok(())
}

fn main() -> era::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("table52") => table52(&list(args.get(1), (1..=100).collect())),
        _ => dta(
            &list(args.get(1), vec![11, 12, 13]),
            &list(args.get(2), vec![0.0, 0.05]),
        ),
    }
}
