//! `era simulate truth-model|modal`: synthetic FRF files; `experiment`, `shaker` and
//! `fleet` have files of their own.

use crate::config::{Modal, SimOutput, Simulate};
use crate::output::report::Human;
use crate::output::simulate::finish;
use era::sim::{add_noise, truth_model_frf, ModalStructure};
use era::Quantity;
use serde_json::json;
use std::time::Instant;

fn truth(sim: &SimOutput) -> anyhow::Result<()> {
    crate::config::check_noise(sim.noise)?;
    let clock = Instant::now();
    let noise = (sim.noise > 0.0).then_some((sim.noise, sim.seed));
    let frf = truth_model_frf(noise)?;
    let modal = era::pipeline::modes::modal_parameters(&era::sim::truth_model())?;
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
        || Ok(()),
    )
}

fn modal(a: &Modal) -> anyhow::Result<()> {
    let spec = a.spec()?;
    let clock = Instant::now();
    let structure = ModalStructure::random(&spec)?;
    let quantity: Quantity = a.quantity;
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
    let geometry_path = crate::output::geometry::beside(&a.sim.out);
    let summary = json!({"file": a.sim.out, "model": "modal", "outputs": a.outputs, "inputs": a.inputs, "lines": a.lines,
        "spacing_hz": a.df, "quantity": quantity.name(), "collocated": a.collocated, "noise": a.sim.noise, "seed": a.sim.seed, "modes": modes,
        "geometry": geometry_path});
    let simulate_s = clock.elapsed().as_secs_f64();
    let human = Human::new(&a.sim.settings);
    finish(
        &a.sim,
        &frf,
        &[("source", "era simulate modal")],
        summary,
        simulate_s,
        || crate::output::geometry::write_dta_like(&human, &geometry_path, a.outputs),
    )
}

pub fn run(a: &Simulate) -> anyhow::Result<()> {
    match a {
        Simulate::TruthModel(sim) => truth(sim),
        Simulate::Modal(m) => modal(m),
        Simulate::Experiment(e) => super::experiment::run(e),
        Simulate::Shaker(s) => super::shaker::run(s),
        Simulate::Fleet(f) => super::fleet::run(&crate::config::fleet::Fleet::new(f)?),
    }
}
