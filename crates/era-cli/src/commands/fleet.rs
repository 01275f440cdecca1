//! `era simulate fleet --out DIR`: a fleet of output-only records of one structure
//! ([`era::sim::fleet`]), written as `era batch` takes it: `DIR/records/rNNNN.csv`,
//! the manifest `DIR/fleet.toml` and the truth `DIR/truth.json`.
//!
//! A record's CSV names its channels by the structure's (`acc1` … `acc8`), so a record
//! that lacks `acc3` still calls `acc4` by its name; such a record gets its own
//! `--outputs` in the manifest.

use crate::args::FleetArgs;
use crate::error::UsageError;
use crate::output::report::Human;
use era::sim::fleet::{fleet_record, FleetRecord, FleetSpec};
use era::sim::ModalSpec;
use rayon::prelude::*;
use serde_json::json;
use std::fmt::Write as _;

/// The core's spec from the flags; an out-of-range value names its flag.
fn spec(a: &FleetArgs) -> anyhow::Result<FleetSpec> {
    let (damping_min, damping_max) = crate::config::parse_range(&a.damping)?;
    for (flag, v) in [
        ("--record-length", a.record_length),
        ("--interval", a.interval),
        ("--sample-rate", a.sample_rate),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return crate::error::usage(format!("{flag} {v}: must be a positive number"));
        }
    }
    if a.record_length * a.sample_rate < 16.0 {
        return crate::error::usage(format!(
            "--record-length {} at --sample-rate {}: a record needs at least 16 samples",
            a.record_length, a.sample_rate
        ));
    }
    crate::config::check_noise(a.noise)?;
    let structure = ModalSpec {
        outputs: a.outputs,
        inputs: a.forces,
        modes: a.modes,
        fmin_hz: a.fmin,
        fmax_hz: a.fmax,
        damping_min,
        damping_max,
        collocated: false,
        seed: a.seed,
    };
    let mut s = FleetSpec::new(structure, a.records);
    s.record_s = a.record_length;
    s.interval_s = a.interval;
    s.sample_rate_hz = a.sample_rate;
    s.noise = a.noise;
    s.drift = a.drift;
    s.daily_c = a.daily;
    s.missing = a.missing;
    if let Some(text) = &a.damage {
        let parsed = text.split_once(':').and_then(|(r, l)| {
            Some((
                r.trim().parse::<usize>().ok()?,
                l.trim().parse::<f64>().ok()?,
            ))
        });
        match parsed {
            Some((r, loss)) if (1..=a.records).contains(&r) && (0.0..0.9).contains(&loss) => {
                s.damage = Some((r - 1, loss));
            }
            _ => {
                return crate::error::usage(format!(
                    "--damage {text}: expected R:LOSS, the first damaged record (1 to --records) and the stiffness loss (0 to 0.9), e.g. 7:0.05"
                ))
            }
        }
    }
    Ok(s)
}

/// A core error on a parameter, under its flag's name.
fn flagged(e: era::EraError) -> anyhow::Error {
    match e {
        era::EraError::InvalidParameter {
            name,
            value,
            reason,
        } => {
            let flag = match name {
                "index" => "records".to_string(),
                "inputs" => "forces".to_string(),
                _ => name.replace('_', "-"),
            };
            UsageError(format!(
                "--{flag} {value}: {}",
                reason.message(era::params::Naming::Flag)
            ))
            .into()
        }
        other => other.into(),
    }
}

/// The record's name: `r0001` …, wide enough for the fleet.
fn name(index: usize, records: usize) -> String {
    let width = records.to_string().len().max(4);
    format!("r{:0width$}", index + 1)
}

/// A record as a time-history CSV: `time_s` and the channels it holds.
fn record_csv(r: &FleetRecord, header: &str) -> String {
    let outputs = &r.record.outputs;
    let n = outputs.first().map_or(0, Vec::len);
    let mut out = String::with_capacity(n * 14 * (outputs.len() + 1));
    let _ = writeln!(out, "# {header}");
    let _ = writeln!(out, "# temperature_c: {:.3}", r.temperature_c);
    out.push_str("time_s");
    for c in &r.channels {
        let _ = write!(out, ",acc{}", c + 1);
    }
    out.push('\n');
    for k in 0..n {
        let _ = write!(out, "{}", k as f64 / r.record.sample_rate_hz);
        for ch in outputs {
            let _ = write!(out, ",{:.7e}", ch[k]);
        }
        out.push('\n');
    }
    out
}

/// `era simulate fleet`.
pub fn run(a: &FleetArgs) -> anyhow::Result<()> {
    let settings: crate::config::Settings = (&a.common).into();
    let human = Human::new(&settings);
    let spec = spec(a)?;
    let start_us =
        era_io::fleet::parse_time(&a.start).map_err(|m| UsageError(format!("--start: {m}")))?;
    // The spec is checked (and the first record made) before anything is written.
    let first = fleet_record(&spec, 0).map_err(flagged)?;
    let mut set = crate::output::prepare_out_dir(&a.out)?;
    let names: Vec<String> = (0..a.records).map(|k| name(k, a.records)).collect();
    let mut staged = Vec::with_capacity(a.records);
    for n in &names {
        staged.push(set.stage(format!("records/{n}.csv"))?);
    }
    let header = format!(
        "era simulate fleet: {} modes {}..{} Hz, {} unmeasured forces, {} % sensor noise, seed {}",
        a.modes,
        a.fmin,
        a.fmax,
        a.forces,
        100.0 * a.noise,
        a.seed
    );
    let bar = crate::output::progress::bar(&settings, a.records as u64, "records");
    let truths = (0..a.records)
        .into_par_iter()
        .map(|k| -> anyhow::Result<serde_json::Value> {
            let r = if k == 0 {
                first.clone()
            } else {
                fleet_record(&spec, k).map_err(flagged)?
            };
            std::fs::write(&staged[k], record_csv(&r, &header)).map_err(|e| {
                anyhow::anyhow!(
                    "writing {}: {e}",
                    a.out.join("records").join(&names[k]).display()
                )
            })?;
            bar.inc(1);
            let t = &r.record.truth;
            Ok(json!({
                "id": names[k],
                "time": era_io::fleet::format_time(start_us + (r.time_s * 1e6).round() as i64),
                "temperature_c": r.temperature_c,
                "channels": r.channels.iter().map(|c| format!("acc{}", c + 1)).collect::<Vec<_>>(),
                "frequencies_hz": t.frequencies_hz,
                "damping_ratios": t.damping_ratios,
            }))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    bar.finish_and_clear();
    let mut manifest = String::new();
    let _ = writeln!(manifest, "# {header}");
    let _ = writeln!(manifest, "verb = \"oma\"");
    let _ = writeln!(manifest, "args = [\"--outputs\", \"1-{}\"]", a.outputs);
    for t in &truths {
        let held = t["channels"].as_array().map_or(0, Vec::len);
        let _ = write!(
            manifest,
            "\n[[record]]\nid = \"{}\"\npath = \"records/{}.csv\"\ntime = {}\n",
            t["id"].as_str().unwrap_or_default(),
            t["id"].as_str().unwrap_or_default(),
            t["time"].as_str().unwrap_or_default()
        );
        if held != a.outputs {
            let _ = writeln!(manifest, "args = [\"--outputs\", \"1-{held}\"]");
        }
    }
    let truth = json!({
        "model": "fleet",
        "outputs": a.outputs,
        "forces": a.forces,
        "sample_rate_hz": a.sample_rate,
        "record_s": a.record_length,
        "interval_s": a.interval,
        "noise": a.noise,
        "drift": a.drift,
        "daily_c": a.daily,
        "damage": spec.damage.map(|(r, loss)| json!({"from_record": r + 1, "loss": loss})),
        "missing": a.missing,
        "seed": a.seed,
        "records": truths,
    });
    crate::output::write_output(&mut set, "fleet.toml", |p| {
        Ok(era_io::atomic::write_atomic(p, manifest.as_bytes())?)
    })?;
    crate::output::write_output(&mut set, "truth.json", |p| {
        Ok(era_io::atomic::write_atomic(
            p,
            serde_json::to_string_pretty(&truth)?.as_bytes(),
        )?)
    })?;
    set.commit()?;
    human.print(&format!(
        "wrote {} records of {} s at {} Hz in {}, the manifest {} and the truth {}\n",
        a.records,
        a.record_length,
        a.sample_rate,
        a.out.join("records").display(),
        a.out.join("fleet.toml").display(),
        a.out.join("truth.json").display()
    ));
    if settings.json {
        crate::output::report::print_json(&truth)?;
    }
    Ok(())
}
