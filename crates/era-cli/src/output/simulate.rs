//! What the simulators write: an FRF file in the format its name asks for, and a
//! shaker test's time histories with the truth beside them.

use crate::config::{Shaker, SimOutput};
use crate::output::report::{finish_output, Human};
use era::{FrfData, Quantity};
use era_io::csv::{write_frf_csv, FrfFile};
use era_io::format::{FrfFormat, FrfWriter};
use era_io::uff::UffWriteOptions;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

/// Writes `frf` where `sim.out` says, then runs `after` (a file beside it, written only
/// once the FRFs are), prints what was written and the summary.
pub fn finish(
    sim: &SimOutput,
    frf: &FrfData,
    extra: &[(&str, &str)],
    summary: serde_json::Value,
    simulate_s: f64,
    after: impl FnOnce() -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let settings = sim.settings;
    let human = Human::new(&settings);
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
    after()?;
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
        &settings,
        summary,
        &[
            ("simulate", simulate_s),
            ("write", clock.elapsed().as_secs_f64()),
        ],
    )
}

/// The record as a time-history CSV: `time_s,force1..,acc1..` (names by quantity).
pub fn shaker_csv(r: &era::sim::shaker::ShakerRecord, quantity: Quantity, header: &str) -> String {
    use std::fmt::Write as _;
    let prefix = match quantity {
        Quantity::Acceleration => "acc",
        Quantity::Velocity => "vel",
        Quantity::Displacement => "disp",
    };
    let n = r.outputs.first().map_or(0, Vec::len);
    let mut out = String::with_capacity(n * 20 * (r.inputs.len() + r.outputs.len() + 1));
    let _ = writeln!(out, "# {header}");
    out.push_str("time_s");
    for j in 1..=r.inputs.len() {
        let _ = write!(out, ",force{j}");
    }
    for i in 1..=r.outputs.len() {
        let _ = write!(out, ",{prefix}{i}");
    }
    out.push('\n');
    for k in 0..n {
        let _ = write!(out, "{}", k as f64 / r.sample_rate_hz);
        for v in r.inputs.iter().chain(&r.outputs) {
            let _ = write!(out, ",{:e}", v[k]);
        }
        out.push('\n');
    }
    out
}

/// The truth beside a shaker test's CSV (and its JSON summary): the settings, the
/// columns, and each mode's frequency, damping and shape.
pub fn shaker_truth(
    a: &Shaker,
    record: &era::sim::shaker::ShakerRecord,
    excitation: era::sim::shaker::Excitation,
    quantity: Quantity,
    outputs_columns: &str,
) -> serde_json::Value {
    let truth = &record.truth;
    let modes: Vec<_> = truth
        .frequencies_hz
        .iter()
        .zip(&truth.damping_ratios)
        .zip(&truth.output_shapes)
        .map(|((f, z), shape)| json!({"frequency_hz": f, "damping_ratio": z, "shape": shape}))
        .collect();
    json!({"file": a.out, "model": "shaker", "outputs": a.outputs, "inputs": a.inputs,
        "sample_rate_hz": a.sample_rate, "duration_s": a.duration, "samples": record.outputs[0].len(),
        "excitation": excitation.name(), "quantity": quantity.name(), "noise": a.noise, "seed": a.seed,
        "inputs_columns": format!("1-{}", a.inputs), "outputs_columns": outputs_columns,
        "modes": modes})
}

/// The record (`--out`, a time-history CSV) and the truth beside it (`STEM.truth.json`),
/// committed together. Returns the truth's path.
pub fn write_shaker(
    a: &Shaker,
    record: &era::sim::shaker::ShakerRecord,
    test: &era::sim::shaker::ShakerTest,
    summary: &serde_json::Value,
) -> anyhow::Result<PathBuf> {
    let header = format!(
        "era simulate shaker: {} modes {}..{} Hz, {} excitation, {} % sensor noise, seed {}",
        a.modes,
        a.fmin,
        a.fmax,
        test.excitation.name(),
        100.0 * a.noise,
        a.seed
    );
    let truth_path = {
        let stem = a
            .out
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        a.out.with_file_name(format!("{stem}.truth.json"))
    };
    let mut set = era_io::atomic::OutputSet::beside(&a.out)?;
    let staged = set.stage(crate::output::output_name("--out", &a.out)?)?;
    std::fs::write(
        &staged,
        shaker_csv(record, test.quantity, &header).as_bytes(),
    )?;
    let staged = set.stage(crate::output::output_name("--out", &truth_path)?)?;
    std::fs::write(&staged, serde_json::to_string_pretty(summary)?.as_bytes())?;
    set.commit()?;
    Ok(truth_path)
}
