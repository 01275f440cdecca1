//! What `era friction estimate|simulate|tune` print and hand on: the estimates' table,
//! the record written, the compensator's coefficients, and their JSON.

use crate::config::{FrictionEstimate, FrictionSimulate, FrictionTune};
use crate::output::report::fixed;
use era::friction::estimate::{summarize, DecayEstimate};
use era::friction::show;
use era::friction::Oscillator;
use era_io::decay_csv::estimate_json;
use serde_json::json;
use std::fmt::Write as _;
use std::path::Path;

fn record_json(path: &Path, e: &DecayEstimate, signal: &str) -> serde_json::Value {
    let mut record = estimate_json(e, signal);
    record.insert("file".into(), json!(path));
    serde_json::Value::Object(record)
}

/// `era friction estimate`'s table (one row per record, then the means) and JSON:
/// `estimates[k]` is of `a.files[k]`, read from its `signals[k]` column.
pub fn estimate_table(
    a: &FrictionEstimate,
    estimates: &[DecayEstimate],
    signals: &[&str],
) -> (String, serde_json::Value) {
    let mut table = format!(
        "era friction estimate (k = {}; Eq. 3.12: F_C = dy k / (8 pi f_n cycles); combined: friction and viscous damping fitted together)\n{:<28} {:>9} {:>7} {:>12} {:>11} {:>9} {:>9} {:>11} {:>9}\n",
        show(a.stiffness), "record", "f_n (Hz)", "cycles", "drop/cycle", "F_C", "zeta", "model", "F_C comb.", "zeta comb."
    );
    let mut records = Vec::new();
    for ((path, e), signal) in a.files.iter().zip(estimates).zip(signals) {
        let name = path.file_name().map_or_else(
            || path.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        let _ = writeln!(
            table,
            "{:<28} {:>9} {:>7} {:>12} {:>11} {:>9} {:>9} {:>11} {:>10}",
            name,
            fixed(e.natural_frequency_hz, 4),
            fixed(e.cycles, 1),
            fixed(e.velocity_drop_per_cycle, 5),
            fixed(e.coulomb_force, 5),
            fixed(e.viscous_damping_ratio, 5),
            e.better_model.name(),
            fixed(e.combined.coulomb_force, 5),
            fixed(e.combined.viscous_damping_ratio, 5)
        );
        records.push(record_json(path, e, signal));
    }
    let s = summarize(estimates);
    let _ = writeln!(
        table,
        "\nF_C mean {}, std {} over {} record(s); f_n mean {} Hz",
        fixed(s.coulomb_force_mean, 5),
        fixed(s.coulomb_force_std, 5),
        estimates.len(),
        fixed(s.natural_frequency_hz_mean, 4)
    );
    let _ = writeln!(
        table,
        "combined law: F_C mean {}, zeta mean {} (Eq. 3.12 reads any viscous damping as friction; the combined fit does not)",
        fixed(s.combined_coulomb_force_mean, 5),
        fixed(s.combined_viscous_damping_ratio_mean, 5)
    );
    let out = json!({
        "records": records,
        "coulomb_force_mean": s.coulomb_force_mean,
        "coulomb_force_std": s.coulomb_force_std,
        "natural_frequency_hz_mean": s.natural_frequency_hz_mean,
        "combined_coulomb_force_mean": s.combined_coulomb_force_mean,
        "combined_viscous_damping_ratio_mean": s.combined_viscous_damping_ratio_mean,
        "stiffness": a.stiffness,
    });
    (table, out)
}

/// The facts `era friction simulate` writes into the record's header.
pub fn decay_metadata(a: &FrictionSimulate) -> [(&'static str, String); 9] {
    [
        ("source", "era friction simulate".to_string()),
        ("stiffness", a.model.stiffness.to_string()),
        (
            "natural_frequency_hz",
            a.model.natural_frequency_hz.to_string(),
        ),
        ("coulomb_force", a.coulomb_force.to_string()),
        (
            "viscous_damping_ratio",
            a.model.viscous_damping_ratio.to_string(),
        ),
        ("x0", a.model.x0.to_string()),
        ("release_time_s", a.hold.to_string()),
        ("noise_fraction", a.noise.to_string()),
        ("seed", a.seed.to_string()),
    ]
}

/// The line `era friction simulate` closes with.
pub fn decay_written(a: &FrictionSimulate, samples: usize) -> String {
    format!(
        "wrote {}: {} samples at {} Hz, release at {} s, F_C {} (k {}, f_n {} Hz){}\n",
        a.out.display(),
        samples,
        a.model.sample_rate,
        a.hold,
        a.coulomb_force,
        a.model.stiffness,
        a.model.natural_frequency_hz,
        if a.noise > 0.0 {
            format!(", {} % noise (seed {})", 100.0 * a.noise, a.seed)
        } else {
            String::new()
        }
    )
}

/// `era friction tune`'s lines and JSON: the coefficients for `osc`, and with records
/// the margin their raw estimate `raw` would have.
pub fn tune_report(
    a: &FrictionTune,
    osc: &Oscillator,
    t: &era::friction::tune::TuneResult,
    raw: Option<f64>,
) -> (String, serde_json::Value) {
    let mut text = format!(
        "era friction tune: k {}, f_n {} Hz, F_C {}, zeta {}, dead zone {}, {} Hz compensator\n",
        show(osc.stiffness),
        fixed(osc.natural_frequency_hz, 4),
        fixed(osc.coulomb_force, 5),
        show(osc.viscous_damping_ratio),
        show(a.dead_zone),
        show(a.model.sample_rate)
    );
    let _ = writeln!(
        text,
        "neutral coefficient      {}  (compensated free decay neither decays nor grows)",
        fixed(t.neutral_coefficient, 5)
    );
    let _ = writeln!(
        text,
        "applied at {:>4.0} %       {}  (stability margin {:.1} %)",
        100.0 * a.fraction,
        fixed(t.applied_coefficient, 5),
        100.0 * t.stability_margin
    );
    let mut out = json!({
        "neutral_coefficient": t.neutral_coefficient,
        "applied_coefficient": t.applied_coefficient,
        "fraction": a.fraction,
        "stability_margin": t.stability_margin,
        "bisection_iterations": t.iterations,
        "model": {"stiffness": osc.stiffness, "natural_frequency_hz": osc.natural_frequency_hz,
                  "coulomb_force": osc.coulomb_force, "viscous_damping_ratio": osc.viscous_damping_ratio},
        "dead_zone": a.dead_zone,
    });
    if let Some(raw) = raw {
        let margin = era::friction::tune::stability_margin(raw, a.fraction, t.neutral_coefficient);
        let _ = writeln!(
            text,
            "the free-decay estimate {} at {:.0} %: margin {:.1} %{}",
            fixed(raw, 5),
            100.0 * a.fraction,
            100.0 * margin,
            if margin < 0.0 {
                " -- it would make the actuator oscillate"
            } else {
                ""
            }
        );
        out["free_decay_estimate"] = json!(raw);
        out["free_decay_estimate_margin"] = json!(margin);
    }
    (text, out)
}
