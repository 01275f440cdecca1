//! `era friction estimate|simulate|tune`.

use crate::config::{Actuator, Friction, FrictionEstimate, FrictionSimulate, FrictionTune};
use crate::error::usage;
use crate::output::report::{finish_output, fixed, Human};
use anyhow::Context;
use era::friction::estimate::{estimate_displacement, estimate_velocity, summarize, DecayEstimate};
use era::friction::show;
use era::friction::simulate::{free_decay_record, DecaySpec, Method};
use era::friction::tune::{stability_margin, tune, TuneSpec};
use era::friction::Oscillator;
use era::params::Naming;
use era_io::decay_csv::{estimate_json, read_decay_csv, write_decay_csv};
use serde_json::json;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

fn estimate_file(path: &Path, stiffness: f64) -> anyhow::Result<(DecayEstimate, &'static str)> {
    let file = read_decay_csv(path)?;
    let result = match (&file.velocity, &file.displacement) {
        (Some(v), _) => estimate_velocity(&file.time_s, v, stiffness).map(|e| (e, "velocity")),
        (None, Some(x)) => {
            estimate_displacement(&file.time_s, x, stiffness).map(|e| (e, "displacement"))
        }
        (None, None) => unreachable!("the reader requires one of the columns"),
    };
    result.with_context(|| format!("{}", path.display()))
}

fn record_json(path: &Path, e: &DecayEstimate, signal: &str) -> serde_json::Value {
    let mut record = estimate_json(e, signal);
    record.insert("file".into(), json!(path));
    serde_json::Value::Object(record)
}

fn check_stiffness(k: f64) -> anyhow::Result<()> {
    Ok(era::friction::check_stiffness(Naming::Flag, k)?)
}

fn estimate(a: &FrictionEstimate) -> anyhow::Result<()> {
    let settings = a.settings;
    let human = Human::new(&settings);
    check_stiffness(a.stiffness)?;
    let clock = Instant::now();
    let mut estimates = Vec::new();
    let mut records = Vec::new();
    let mut table = format!(
        "era friction estimate (k = {}; Eq. 3.12: F_C = dy k / (8 pi f_n cycles); combined: friction and viscous damping fitted together)\n{:<28} {:>9} {:>7} {:>12} {:>11} {:>9} {:>9} {:>11} {:>9}\n",
        show(a.stiffness), "record", "f_n (Hz)", "cycles", "drop/cycle", "F_C", "zeta", "model", "F_C comb.", "zeta comb."
    );
    for path in &a.files {
        let (e, signal) = estimate_file(path, a.stiffness)?;
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
        records.push(record_json(path, &e, signal));
        estimates.push(e);
    }
    let s = summarize(&estimates);
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
    human.print(&table);
    let out = json!({
        "records": records,
        "coulomb_force_mean": s.coulomb_force_mean,
        "coulomb_force_std": s.coulomb_force_std,
        "natural_frequency_hz_mean": s.natural_frequency_hz_mean,
        "combined_coulomb_force_mean": s.combined_coulomb_force_mean,
        "combined_viscous_damping_ratio_mean": s.combined_viscous_damping_ratio_mean,
        "stiffness": a.stiffness,
    });
    finish_output(
        &human,
        &settings,
        out,
        &[("estimate", clock.elapsed().as_secs_f64())],
    )
}

fn oscillator(m: &Actuator, coulomb_force: f64) -> anyhow::Result<Oscillator> {
    check_stiffness(m.stiffness)?;
    let o = Oscillator {
        stiffness: m.stiffness,
        natural_frequency_hz: m.natural_frequency_hz,
        coulomb_force,
        viscous_damping_ratio: m.viscous_damping_ratio,
    };
    o.validate()?;
    Ok(o)
}

fn simulate(a: &FrictionSimulate) -> anyhow::Result<()> {
    let settings = a.settings;
    let human = Human::new(&settings);
    let clock = Instant::now();
    let osc = oscillator(&a.model, a.coulomb_force)?;
    let method = match a.method {
        Some(Method::Exact) if osc.viscous_damping_ratio != 0.0 => {
            return usage("--method exact is for Coulomb friction alone: drop --viscous-damping-ratio or use --method integrate");
        }
        Some(method) => method,
        None if osc.viscous_damping_ratio != 0.0 => Method::Integrate,
        None => Method::Exact,
    };
    let spec = DecaySpec {
        oscillator: osc,
        x0: a.model.x0,
        sample_rate_hz: a.model.sample_rate,
        hold_s: a.hold,
        duration_s: a.duration,
        noise_fraction: a.noise,
        seed: a.seed,
        method,
    };
    let record = free_decay_record(&spec)?;
    let simulate_s = clock.elapsed().as_secs_f64();
    let meta = [
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
    ];
    let clock = Instant::now();
    write_decay_csv(&a.out, &record, &meta)?;
    human.print(&format!(
        "wrote {}: {} samples at {} Hz, release at {} s, F_C {} (k {}, f_n {} Hz){}\n",
        a.out.display(),
        record.time_s.len(),
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
    ));
    let out = json!({"file": a.out, "samples": record.time_s.len(), "method": format!("{method:?}").to_lowercase()});
    finish_output(
        &human,
        &settings,
        out,
        &[
            ("simulate", simulate_s),
            ("write", clock.elapsed().as_secs_f64()),
        ],
    )
}

fn tune_cmd(a: &FrictionTune) -> anyhow::Result<()> {
    let settings = a.settings;
    let human = Human::new(&settings);
    let clock = Instant::now();
    check_stiffness(a.model.stiffness)?;
    // The actuator: from records, or from the flags.
    let (coulomb_force, natural_frequency_hz, raw) = match (a.files.is_empty(), a.coulomb_force) {
        (true, None) => return usage("give free-decay record file(s) or --coulomb-force"),
        (false, Some(_)) => {
            return usage("give either record file(s) or --coulomb-force, not both")
        }
        (true, Some(fc)) => (fc, a.model.natural_frequency_hz, None),
        (false, None) => {
            let estimates: Vec<DecayEstimate> = a
                .files
                .iter()
                .map(|p| estimate_file(p, a.model.stiffness).map(|(e, _)| e))
                .collect::<anyhow::Result<_>>()?;
            let s = summarize(&estimates);
            (
                s.coulomb_force_mean,
                s.natural_frequency_hz_mean,
                Some(s.coulomb_force_mean),
            )
        }
    };
    let osc = Oscillator {
        natural_frequency_hz,
        ..oscillator(&a.model, coulomb_force)?
    };
    let spec = TuneSpec {
        oscillator: osc,
        x0: a.model.x0,
        dead_zone: a.dead_zone,
        sample_rate_hz: a.model.sample_rate,
        cycles: a.cycles,
        fraction: a.fraction,
    };
    let t = tune(&spec)?;
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
        let margin = stability_margin(raw, a.fraction, t.neutral_coefficient);
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
    human.print(&text);
    finish_output(
        &human,
        &settings,
        out,
        &[("tune", clock.elapsed().as_secs_f64())],
    )
}

pub fn run(a: &Friction) -> anyhow::Result<()> {
    match a {
        Friction::Estimate(e) => estimate(e),
        Friction::Simulate(s) => simulate(s),
        Friction::Tune(t) => tune_cmd(t),
    }
}
