//! What `era demo` hands on: the table of the truth's modes beside those identified,
//! the files of each run, and the JSON.

use crate::config::{Demo, Settings};
use crate::output::identification::{write_identification, Bundle};
use crate::output::report::parameter_echo;
use crate::output::{write_output, RunInput};
use era::data::identification::Identification;
use era::identify::EraOptions;
use era::pipeline::modes::Mode;
use era::sim::TABLE_5_2_ERA_NOISY;
use era_io::atomic::OutputSet;
use era_io::csv::write_frf_csv;
use era_io::model_json::{FitJson, ModeJson, ModelJson, ModelParameters};
use era_plot::FrfUnits;
use serde_json::json;
use std::fmt::Write as _;
use std::path::Path;

/// The three identifications of the demo: ERA without noise, ERA with noise, and that
/// noisy model refined.
pub struct Runs {
    /// ERA on the noise-free FRFs.
    pub clean: Identification,
    /// ERA on the noisy FRFs.
    pub noisy: Identification,
    /// The noisy run refined.
    pub refined: Identification,
}

pub fn max_errors(truth: &[Mode], found: &[Mode]) -> serde_json::Value {
    if truth.len() != found.len() {
        return json!({"modes_found": found.len(), "modes_expected": truth.len()});
    }
    let df = truth
        .iter()
        .zip(found)
        .map(|(t, f)| (t.frequency_hz - f.frequency_hz).abs())
        .fold(0.0, f64::max);
    let dz = truth
        .iter()
        .zip(found)
        .map(|(t, f)| (t.damping_ratio - f.damping_ratio).abs())
        .fold(0.0, f64::max);
    json!({"max_frequency_error_hz": df, "max_damping_ratio_error": dz})
}

pub fn cell(mode: Option<&Mode>) -> String {
    mode.map_or(format!("{:>10} {:>7}", "-", "-"), |m| {
        format!("{:>10.2} {:>7.2}", m.frequency_hz, 100.0 * m.damping_ratio)
    })
}

/// Table 5.2 beside the truth, and the largest errors of each run.
pub fn table(a: &Demo, truth: &[Mode], runs: &Runs, errors: &[serde_json::Value; 3]) -> String {
    let pct = 100.0 * a.noise;
    let mut t = String::new();
    let _ = writeln!(t, "\nTable 5.2: f in Hz, zeta in %");
    let _ = writeln!(
        t,
        "{:>4} | {:^18} | {:^18} | {:^18} | {:^16} || {:^18} | {:^16}",
        "mode",
        "truth",
        "ERA, no noise",
        format!("ERA, {pct:.0} % noise"),
        "noisy - truth",
        "ERA + refined",
        "refined - truth"
    );
    let _ = writeln!(
        t,
        "{:>4} | {:>10} {:>7} | {:>10} {:>7} | {:>10} {:>7} | {:>8} {:>7} || {:>10} {:>7} | {:>8} {:>7}",
        "", "f", "zeta", "f", "zeta", "f", "zeta", "df", "dzeta", "f", "zeta", "df", "dzeta"
    );
    for (k, m) in truth.iter().enumerate() {
        let n = runs.noisy.modal.modes.get(k);
        let difference = |n: Option<&Mode>| {
            n.map_or(format!("{:>8} {:>7}", "-", "-"), |n| {
                format!(
                    "{:>8.2} {:>7.2}",
                    n.frequency_hz - m.frequency_hz,
                    100.0 * (n.damping_ratio - m.damping_ratio)
                )
            })
        };
        let diff = difference(n).trim_end().to_string();
        let diff = if n.is_none() { String::from("-") } else { diff };
        // The refined mode nearest the truth (a refinement may drop a mode).
        let r = runs.refined.modal.modes.iter().min_by(|a, b| {
            (a.frequency_hz - m.frequency_hz)
                .abs()
                .total_cmp(&(b.frequency_hz - m.frequency_hz).abs())
        });
        let _ = writeln!(
            t,
            "{:>4} | {} | {} | {} | {:<16} || {} | {}",
            k + 1,
            cell(Some(m)),
            cell(runs.clean.modal.modes.get(k)),
            cell(n),
            diff,
            cell(r),
            difference(r)
        );
    }
    let show = |e: &serde_json::Value| match (
        e["max_frequency_error_hz"].as_f64(),
        e["max_damping_ratio_error"].as_f64(),
    ) {
        (Some(f), Some(z)) => format!("max |df| = {f:.3e} Hz, max |dzeta| = {z:.3e}"),
        _ => format!("{e}"),
    };
    let _ = writeln!(t, "\nno noise: {}", show(&errors[0]));
    let _ = writeln!(
        t,
        "{pct:.0} % noise (seed {}): {}",
        a.seed,
        show(&errors[1])
    );
    let _ = writeln!(
        t,
        "{pct:.0} % noise, ERA + refinement (z-domain, weighted by each pair's noise): {}",
        show(&errors[2])
    );
    let _ = write!(t, "thesis (1994), ERA with 15 % noise:");
    for (f, z) in TABLE_5_2_ERA_NOISY {
        let _ = write!(t, "  {f:.2} / {z:.2}");
    }
    let _ = writeln!(t, "\n(the noisy column depends on the noise draw; scripts/octave_peer.sh compare SEED runs the thesis routines on the same draw)");
    t
}

/// The FRFs (CSV) and both runs' bundles (no_noise/, noisy/) into `set`, committed
/// together: both take their place, or none does.
pub fn write_files(
    a: &Demo,
    mut set: OutputSet,
    options: &EraOptions,
    [clean_frf, noisy_frf]: [&era::FrfData; 2],
    runs: &Runs,
    settings: &Settings,
) -> anyhow::Result<()> {
    let seed = a.seed.to_string();
    let noise = a.noise.to_string();
    write_output(&mut set, "truth_frf.csv", |p| {
        Ok(write_frf_csv(
            p,
            clean_frf,
            &[
                ("source", "era demo"),
                ("noise_fraction", "0"),
                ("response_unit", "in"),
                ("force_unit", "lbf"),
            ],
        )?)
    })?;
    write_output(&mut set, "truth_frf_noisy.csv", |p| {
        Ok(write_frf_csv(
            p,
            noisy_frf,
            &[
                ("source", "era demo"),
                ("noise_fraction", &noise),
                ("seed", &seed),
                ("response_unit", "in"),
                ("force_unit", "lbf"),
            ],
        )?)
    })?;
    for (label, found) in [("no_noise", &runs.clean), ("noisy", &runs.noisy)] {
        let title = format!("era demo: the truth model, {}", label.replace('_', " "));
        let model = ModelJson::from_run(found, &ModelParameters::new(options));
        // The truth model is in inches and pounds-force (thesis section 4.2).
        let source = RunInput::synthetic(
            &format!(
                "the thesis's truth model (Table 5.2), {}",
                if label == "noisy" {
                    format!("{} % noise, seed {}", 100.0 * a.noise, a.seed)
                } else {
                    "no noise".into()
                }
            ),
            clean_frf.quantity(),
            FrfUnits {
                response: Some("in".into()),
                force: Some("lbf".into()),
            },
        );
        let fit = FitJson::from_report(&found.fit);
        let echo = parameter_echo(options);
        let states = options.order.states().unwrap_or(0);
        let bundle = Bundle {
            found,
            fit: &fit,
            source: &source,
            title: &title,
            echo: &echo,
            states,
            figures: false,
        };
        // modes.uff keeps era's numbering; the figures and the report draw the modes on
        // the chain drawn as a shear frame.
        write_identification(&mut set, Path::new(label), &model, &bundle, settings)?;
        let source = on_shear_frame(source, found.measured.outputs(), found.measured.inputs());
        let pairs = found.measured.outputs() * found.measured.inputs();
        let bar = crate::output::progress::bar(settings, pairs as u64, "figures");
        crate::output::figures::write_all(
            &mut set,
            Path::new(label),
            &title,
            &echo,
            found,
            &source,
            states,
            &bar,
        )?;
        bar.finish_and_clear();
    }
    set.commit()?;
    Ok(())
}

/// `source` with the truth model's chain drawn as a 4-storey shear frame
/// ([`era_io::geometry::layouts::shear_frame`]): output `i` and input `j` at masses `i`
/// and `j`, along x (the chain's direction), for the report's shapes.
pub fn on_shear_frame(source: RunInput, outputs: usize, inputs: usize) -> RunInput {
    let along_x = |node: usize| era_io::frf_file::Channel {
        dof: era_io::frf_file::Dof {
            node: node as i64,
            direction: 1,
        },
        entity: "NONE".into(),
    };
    let mut source = source;
    source.channels = Some(era_io::frf_file::ChannelTable {
        outputs: (1..=outputs).map(along_x).collect(),
        inputs: (1..=inputs).map(along_x).collect(),
    });
    let frame = era_io::geometry::layouts::shear_frame(4);
    crate::output::geometry::attach(
        source,
        Some((
            "the truth model's chain drawn by era demo as a 4-storey shear frame, masses along x"
                .into(),
            frame,
        )),
        outputs,
    )
}

/// The demo's JSON: the truth, each run's modes, the refinement, the errors and the
/// parameters.
pub fn demo_json(
    a: &Demo,
    options: &EraOptions,
    truth: &[Mode],
    runs: &Runs,
    [e0, e1, e2]: [serde_json::Value; 3],
) -> serde_json::Value {
    let modes = |v: &[Mode]| v.iter().map(ModeJson::from_mode).collect::<Vec<_>>();
    let refined = &runs.refined;
    json!({
        "truth": modes(truth),
        "no_noise": modes(&runs.clean.modal.modes),
        "noisy": modes(&runs.noisy.modal.modes),
        "refined": refined
            .modal
            .modes
            .iter()
            .zip(&refined.quality)
            .map(|(m, q)| ModeJson::from_mode_quality(m, q))
            .collect::<Vec<_>>(),
        "refinement": refined.refinement.as_ref().map(era_io::model_json::RefinementJson::of),
        "noise": {"fraction": a.noise, "seed": a.seed},
        "errors": {"no_noise": e0, "noisy": e1, "refined": e2},
        "parameters": ModelParameters::new(options).to_map(),
    })
}
