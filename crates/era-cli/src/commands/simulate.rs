//! `era simulate truth-model|modal`: synthetic FRF files.

use crate::config::{self, Modal, Shaker, SimOutput, Simulate};
use crate::error::usage;
use crate::output::report::{finish_output, Human};
use era::params::Naming;
use era::sim::{add_noise, truth_model_frf, ModalRequest, ModalSpec, ModalStructure};
use era::{FrfData, Quantity};
use era_io::csv::{write_frf_csv, FrfFile};
use era_io::format::{FrfFormat, FrfWriter};
use era_io::uff::UffWriteOptions;
use serde_json::json;
use std::time::Instant;

/// Writes `frf` where `sim.out` says, then runs `after` (a file beside it, written only
/// once the FRFs are), prints what was written and the summary.
fn finish(
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
    crate::config::check_noise(a.sim.noise)?;
    let (damping_min, damping_max) = crate::config::parse_range(&a.damping)?;
    let request = ModalRequest::new(
        ModalSpec {
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
        a.lines,
        a.df,
    );
    // Sizes against their limits, under the flag's name, before anything is allocated.
    request.check(Naming::Flag)?;
    let spec = request.spec;
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
        Simulate::Shaker(s) => shaker(s),
        Simulate::Fleet(f) => super::fleet::run(f),
    }
}

/// `LO..HI` of `--band`.
fn parse_band(text: &str) -> anyhow::Result<(f64, f64)> {
    let parsed = text.split_once("..").and_then(|(lo, hi)| {
        Some((
            lo.trim().parse::<f64>().ok()?,
            hi.trim().parse::<f64>().ok()?,
        ))
    });
    match parsed {
        Some(band) => Ok(band),
        None => usage(format!("--band {text}: expected LO..HI in Hz, e.g. 1..25")),
    }
}

/// The record as a time-history CSV: `time_s,force1..,acc1..` (names by quantity).
fn shaker_csv(r: &era::sim::shaker::ShakerRecord, quantity: Quantity, header: &str) -> String {
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

/// The shakers' signal the flags ask for, `--band` checked against it.
fn shaker_excitation(a: &Shaker) -> anyhow::Result<era::sim::shaker::Excitation> {
    use era::sim::shaker::Excitation;
    let band = a.band.as_deref().map(parse_band).transpose()?;
    if band.is_some()
        && !matches!(
            a.excitation,
            config::Excitation::BandLimited | config::Excitation::Sweep
        )
    {
        return usage(
            "--band sets band-limited noise or a sweep: add --excitation band-limited or sweep",
        );
    }
    let nyquist = a.sample_rate / 2.0;
    let excitation = match a.excitation {
        config::Excitation::White => Excitation::White,
        config::Excitation::BandLimited => {
            let (lo_hz, hi_hz) = band.unwrap_or((0.0, nyquist));
            Excitation::BandLimited { lo_hz, hi_hz }
        }
        config::Excitation::Burst => Excitation::Burst {
            period_s: a.period,
            on_fraction: a.burst_on,
        },
        config::Excitation::Sweep => {
            let (lo_hz, hi_hz) = band.unwrap_or((a.fmin / 2.0, (1.2 * a.fmax).min(nyquist)));
            Excitation::Sweep { lo_hz, hi_hz }
        }
        config::Excitation::Impact => Excitation::Impact {
            period_s: a.period,
            width_s: a.pulse_width,
        },
    };
    Ok(excitation)
}

/// The truth beside a shaker test's CSV (and its JSON summary): the settings, the
/// columns, and each mode's frequency, damping and shape.
fn shaker_truth(
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

fn shaker(a: &Shaker) -> anyhow::Result<()> {
    use era::sim::shaker::{simulate_shaker_test, ShakerTest};
    let settings = a.settings;
    let human = Human::new(&settings);
    crate::config::check_noise(a.noise)?;
    let (damping_min, damping_max) = crate::config::parse_range(&a.damping)?;
    let excitation = shaker_excitation(a)?;
    // The structure's sizes and ranges are checked, against their limits, before
    // anything is allocated (ModalStructure::random, inside the simulation).
    let spec = ModalSpec {
        outputs: a.outputs,
        inputs: a.inputs,
        modes: a.modes,
        fmin_hz: a.fmin,
        fmax_hz: a.fmax,
        damping_min,
        damping_max,
        collocated: false,
        seed: a.seed,
    };
    let quantity: Quantity = a.quantity;
    let mut test = ShakerTest::new(spec, a.sample_rate, a.duration);
    test.excitation = excitation;
    test.quantity = quantity;
    test.noise = a.noise;
    let clock = Instant::now();
    let record = simulate_shaker_test(&test).map_err(|e| match e {
        era::EraError::InvalidParameter {
            name,
            value,
            reason,
        } => anyhow::Error::from(crate::error::UsageError(format!(
            "--{name} {value}: {}",
            reason.message(era::params::Naming::Flag)
        ))),
        other => anyhow::Error::from(other),
    })?;
    let simulate_s = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    let outputs_columns = format!("{}-{}", a.inputs + 1, a.inputs + a.outputs);
    let summary = shaker_truth(a, &record, excitation, quantity, &outputs_columns);
    let header = format!(
        "era simulate shaker: {} modes {}..{} Hz, {} excitation, {} % sensor noise, seed {}",
        a.modes,
        a.fmin,
        a.fmax,
        excitation.name(),
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
    std::fs::write(&staged, shaker_csv(&record, quantity, &header).as_bytes())?;
    let staged = set.stage(crate::output::output_name("--out", &truth_path)?)?;
    std::fs::write(&staged, serde_json::to_string_pretty(&summary)?.as_bytes())?;
    set.commit()?;
    human.print(&format!(
        "wrote {} ({} samples at {} Hz: force1-{} then {} outputs, columns {}) and {}\n",
        a.out.display(),
        record.outputs[0].len(),
        a.sample_rate,
        a.inputs,
        a.outputs,
        outputs_columns,
        truth_path.display()
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
