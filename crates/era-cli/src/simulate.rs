//! `era simulate truth-model|modal`: synthetic FRF files.

use crate::args::{ModalArgs, SimulateArgs, SimulateCommon, SimulateModel};
use crate::report::{finish_output, Human};
use crate::usage;
use era::sim::{add_noise, truth_model_frf, ModalSpec, ModalStructure};
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
    let max = era::sim::MAX_NOISE_FRACTION;
    if !(noise.is_finite() && (0.0..=max).contains(&noise)) {
        return usage(format!(
            "--noise {noise}: must be a fraction from 0 to {max} (0.15 for 15 %)"
        ));
    }
    Ok(())
}

/// A positive, finite number for `flag`.
fn check_positive(flag: &str, value: f64, what: &str) -> anyhow::Result<()> {
    if !(value.is_finite() && value > 0.0) {
        return usage(format!("{flag} {value}: must be a positive {what}"));
    }
    Ok(())
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
    // Sizes against their limits, under the flag's name, before anything is allocated.
    use era::limits::{CHANNELS, LINES, STATES, VALUES};
    CHANNELS.check("--outputs", a.outputs as u64)?;
    CHANNELS.check("--inputs", a.inputs as u64)?;
    STATES.check_product("--modes (2 states each)", &[a.modes as u64, 2])?;
    LINES.check("--lines", a.lines as u64)?;
    VALUES.check_product(
        "--outputs x --inputs x --lines",
        &[a.outputs as u64, a.inputs as u64, a.lines as u64],
    )?;
    VALUES.check_product(
        "--outputs x --inputs x --lines x --modes (modal FRF terms)",
        &[
            a.outputs as u64,
            a.inputs as u64,
            a.lines as u64,
            a.modes as u64,
        ],
    )?;
    check_positive("--df", a.df, "line spacing in Hz")?;
    check_positive("--fmin", a.fmin, "frequency in Hz")?;
    check_positive("--fmax", a.fmax, "frequency in Hz")?;
    if a.collocated && a.outputs != a.inputs {
        return usage(format!(
            "--collocated needs as many outputs as inputs, got {} x {}",
            a.outputs, a.inputs
        ));
    }
    if a.fmax >= a.df * (a.lines.saturating_sub(1)) as f64 {
        return usage(format!(
            "--fmax {} Hz is not below the last line, {} Hz (--lines {} at --df {})",
            a.fmax,
            a.df * (a.lines.saturating_sub(1)) as f64,
            a.lines,
            a.df
        ));
    }
    let spec = ModalSpec {
        outputs: a.outputs,
        inputs: a.inputs,
        modes: a.modes,
        fmin_hz: a.fmin,
        fmax_hz: a.fmax,
        damping_min,
        damping_max,
        collocated: a.collocated,
        seed: a.sim.seed,
    };
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
