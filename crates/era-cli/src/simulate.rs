//! `era simulate truth-model|modal`: synthetic FRF files.

use crate::args::{ModalArgs, SimulateArgs, SimulateCommon, SimulateModel};
use crate::report::{finish_output, Human};
use crate::usage;
use era::params::Naming;
use era::sim::{add_noise, truth_model_frf, ModalRequest, ModalSpec, ModalStructure};
use era::{FrfData, Quantity};
use era_io::csv::{write_frf_csv, FrfFile};
use era_io::format::{FrfFormat, FrfWriter};
use era_io::uff::UffWriteOptions;
use serde_json::json;
use std::time::Instant;

pub fn parse_range(text: &str) -> anyhow::Result<(f64, f64)> {
    let Some((lo, hi)) = text.split_once("..") else {
        return usage(format!(
            "--damping {text}: expected MIN..MAX, e.g. 0.005..0.02"
        ));
    };
    match (lo.trim().parse::<f64>(), hi.trim().parse::<f64>()) {
        (Ok(lo), Ok(hi)) => Ok((lo, hi)),
        _ => usage(format!("--damping {text}: MIN and MAX must be numbers")),
    }
}

pub fn check_noise(noise: f64) -> anyhow::Result<()> {
    Ok(era::sim::check_noise(Naming::Flag, noise)?)
}

fn finish(
    sim: &SimulateCommon,
    frf: &FrfData,
    extra: &[(&str, &str)],
    summary: serde_json::Value,
    simulate_s: f64,
) -> anyhow::Result<()> {
    let human = Human::new(&sim.common);
    let clock = Instant::now();
    let seed = sim.seed.to_string();
    let noise = sim.noise.to_string();
    let mut meta: Vec<(&str, &str)> = extra.to_vec();
    meta.push(("noise_fraction", &noise));
    meta.push(("seed", &seed));
    match FrfFormat::from_extension(&sim.out) {
        Some(format @ (FrfFormat::Uff | FrfFormat::Mat)) => {
            let file = FrfFile {
                frf: frf.clone(),
                quantity_given: true,
                metadata: meta
                    .iter()
                    .map(|(k, v)| (k.to_string(), v.to_string()))
                    .collect(),
                channels: None,
            };
            format.write_frf(&sim.out, &file, UffWriteOptions::default())?;
        }
        _ => write_frf_csv(&sim.out, frf, &meta)?,
    }
    human.print(&format!(
        "wrote {}: {} outputs x {} inputs, {} lines at {} Hz, {}{}\n",
        sim.out.display(),
        frf.outputs(),
        frf.inputs(),
        frf.lines(),
        frf.spacing_hz(),
        frf.quantity(),
        if sim.noise > 0.0 {
            format!(", {} % noise (seed {})", 100.0 * sim.noise, sim.seed)
        } else {
            String::new()
        },
    ));
    finish_output(
        &human,
        &sim.common,
        summary,
        &[
            ("simulate", simulate_s),
            ("write", clock.elapsed().as_secs_f64()),
        ],
    )
}

fn truth(sim: &SimulateCommon) -> anyhow::Result<()> {
    check_noise(sim.noise)?;
    let clock = Instant::now();
    let noise = (sim.noise > 0.0).then_some((sim.noise, sim.seed));
    let frf = truth_model_frf(noise)?;
    let modal = era::modal::modal_parameters(&era::sim::truth_model())?;
    let modes: Vec<_> = modal
        .modes
        .iter()
        .map(|m| json!({"frequency_hz": m.frequency_hz, "damping_ratio": m.damping_ratio}))
        .collect();
    let summary = json!({"file": sim.out, "model": "truth-model", "outputs": 3, "inputs": 3, "lines": frf.lines(),
        "spacing_hz": frf.spacing_hz(), "quantity": "displacement", "noise": sim.noise, "seed": sim.seed, "modes": modes});
    finish(
        sim,
        &frf,
        &[
            ("force_unit", "lbf"),
            ("response_unit", "in"),
            ("source", "era simulate truth-model"),
        ],
        summary,
        clock.elapsed().as_secs_f64(),
    )
}

fn modal(a: &ModalArgs) -> anyhow::Result<()> {
    check_noise(a.sim.noise)?;
    let (damping_min, damping_max) = parse_range(&a.damping)?;
    let request = ModalRequest {
        spec: ModalSpec {
            outputs: a.outputs,
            inputs: a.inputs,
            modes: a.modes,
            fmin_hz: a.fmin,
            fmax_hz: a.fmax,
            damping_min,
            damping_max,
            collocated: a.collocated,
            seed: a.sim.seed,
        },
        lines: a.lines,
        df_hz: a.df,
    };
    // Sizes against their limits, under the flag's name, before anything is allocated.
    request.check(Naming::Flag)?;
    let spec = request.spec;
    let clock = Instant::now();
    let structure = ModalStructure::random(&spec)?;
    let quantity: Quantity = a.quantity.into();
    let mut frf = structure.frf(a.lines, a.df, quantity)?;
    if a.sim.noise > 0.0 {
        frf = add_noise(&frf, a.sim.noise, a.sim.seed)?;
    }
    let modes: Vec<_> = structure
        .frequencies_hz
        .iter()
        .zip(&structure.damping_ratios)
        .map(|(f, z)| json!({"frequency_hz": f, "damping_ratio": z}))
        .collect();
    let summary = json!({"file": a.sim.out, "model": "modal", "outputs": a.outputs, "inputs": a.inputs, "lines": a.lines,
        "spacing_hz": a.df, "quantity": quantity.name(), "collocated": a.collocated, "noise": a.sim.noise, "seed": a.sim.seed, "modes": modes});
    let simulate_s = clock.elapsed().as_secs_f64();
    finish(
        &a.sim,
        &frf,
        &[("source", "era simulate modal")],
        summary,
        simulate_s,
    )
}

pub fn run(a: &SimulateArgs) -> anyhow::Result<()> {
    match &a.model {
        SimulateModel::TruthModel(sim) => truth(sim),
        SimulateModel::Modal(m) => modal(m),
        SimulateModel::Experiment(e) => crate::experiment::run(e),
    }
}
