//! `era friction estimate|simulate|tune`: the actuators' Coulomb friction from free-decay
//! records, a free decay simulated, and the compensator tuned.

use crate::config::friction::{check_stiffness, check_tune_source, decay_spec, tune_spec};
use crate::config::{Friction, FrictionEstimate, FrictionSimulate, FrictionTune};
use crate::input::friction::estimate_file;
use crate::output::friction::{decay_metadata, decay_written, estimate_table, tune_report};
use crate::output::report::{finish_output, Human};
use era::friction::estimate::summarize;
use serde_json::json;
use std::time::Instant;

pub fn run(a: &Friction) -> anyhow::Result<()> {
    match a {
        Friction::Estimate(e) => estimate(e),
        Friction::Simulate(s) => simulate(s),
        Friction::Tune(t) => tune(t),
    }
}

fn estimate(a: &FrictionEstimate) -> anyhow::Result<()> {
    let human = Human::new(&a.settings);
    check_stiffness(a.stiffness)?;
    let clock = Instant::now();
    let mut estimates = Vec::new();
    let mut signals = Vec::new();
    for path in &a.files {
        let (e, signal) = estimate_file(path, a.stiffness)?;
        estimates.push(e);
        signals.push(signal);
    }
    let (table, out) = estimate_table(a, &estimates, &signals);
    human.print(&table);
    let seconds = clock.elapsed().as_secs_f64();
    finish_output(&human, &a.settings, out, &[("estimate", seconds)])
}

fn simulate(a: &FrictionSimulate) -> anyhow::Result<()> {
    let human = Human::new(&a.settings);
    let clock = Instant::now();
    let spec = decay_spec(a)?;
    let record = era::friction::simulate::free_decay_record(&spec)?;
    let simulate_s = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    era_io::decay_csv::write_decay_csv(&a.out, &record, &decay_metadata(a))?;
    human.print(&decay_written(a, record.time_s.len()));
    let method = format!("{:?}", spec.method).to_lowercase();
    let out = json!({"file": a.out, "samples": record.time_s.len(), "method": method});
    let write_s = clock.elapsed().as_secs_f64();
    finish_output(
        &human,
        &a.settings,
        out,
        &[("simulate", simulate_s), ("write", write_s)],
    )
}

fn tune(a: &FrictionTune) -> anyhow::Result<()> {
    let human = Human::new(&a.settings);
    let clock = Instant::now();
    check_tune_source(a)?;
    // The actuator: from records, or from the flags.
    let (coulomb_force, natural_frequency_hz, raw) = match a.coulomb_force {
        Some(fc) => (fc, a.model.natural_frequency_hz, None),
        None => {
            let estimates = a
                .files
                .iter()
                .map(|p| estimate_file(p, a.model.stiffness).map(|(e, _)| e))
                .collect::<anyhow::Result<Vec<_>>>()?;
            let s = summarize(&estimates);
            let fc = s.coulomb_force_mean;
            (fc, s.natural_frequency_hz_mean, Some(fc))
        }
    };
    let spec = tune_spec(a, coulomb_force, natural_frequency_hz)?;
    let t = era::friction::tune::tune(&spec)?;
    let (text, out) = tune_report(a, &spec.oscillator, &t, raw);
    human.print(&text);
    let seconds = clock.elapsed().as_secs_f64();
    finish_output(&human, &a.settings, out, &[("tune", seconds)])
}
