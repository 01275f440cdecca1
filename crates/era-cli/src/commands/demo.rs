//! `era demo`: the embedded default. The thesis's truth model (Table 5.2) identified
//! with the thesis settings, without and with noise, beside the exact truth.

use crate::config::Demo;
use crate::output::demo::{demo_json, max_errors, table, write_files, Runs};
use crate::output::prepare_out_dir;
use crate::output::report::{parameter_echo, print_json, timings_table, Human};
use anyhow::Context;
use era::data::identification::Identification;
use era::identify::{identify, EraOptions};
use era::pipeline::modes::modal_parameters;
use era::sim::{truth_model, truth_model_frf};
use era_io::model_json::timings_map;
use serde_json::json;
use std::time::Instant;

pub fn run(a: &Demo) -> anyhow::Result<()> {
    let settings = a.settings;
    let human = Human::new(&settings);
    crate::config::check_noise(a.noise)?;
    let mut outputs = match &a.out {
        Some(dir) => Some(prepare_out_dir(dir)?),
        None => None,
    };
    let options = EraOptions::thesis_truth_model();
    human.print("era demo: the thesis's truth model (Woods 1994, section 4.2, Table 5.2)\n");
    human.print("  4 masses, 3 force inputs, 3 displacement outputs; ZOH at 25 600 Hz, 1025 lines 0..12 800 Hz\n");
    human.print(&parameter_echo(&options));

    let truth = modal_parameters(&truth_model())?.modes;
    let clean_frf = truth_model_frf(None)?;
    let noisy_frf = truth_model_frf(Some((a.noise, a.seed)))?;
    let runs = identify_both(&options, &clean_frf, &noisy_frf)?;
    let err = |found: &Identification| max_errors(&truth, &found.modal.modes);
    let errors = [err(&runs.clean), err(&runs.noisy), err(&runs.refined)];
    human.print(&table(a, &truth, &runs, &errors));

    let mut timing_json = serde_json::Map::new();
    if settings.timings {
        for (label, found) in [("no_noise", &runs.clean), ("noisy", &runs.noisy)] {
            let map = timings_map(&found.timings);
            human.print(&format!("\n{label}:"));
            human.print(&timings_table(&map));
            timing_json.insert(label.into(), json!(map));
        }
    }
    if let (Some(dir), Some(set)) = (&a.out, outputs.take()) {
        let clock = Instant::now();
        let frfs = [&clean_frf, &noisy_frf];
        write_files(a, set, &options, frfs, &runs, &settings)?;
        human.print(&format!(
            "\nwrote {0}/truth_frf.csv, {0}/truth_frf_noisy.csv, and in {0}/no_noise and {0}/noisy: model.json, fit.json, model.mat, modes.uff, model_frf.uff, report.html and figures ({1:.3} s)\n",
            dir.display(),
            clock.elapsed().as_secs_f64()
        ));
    }
    if settings.json {
        let mut out = demo_json(a, &options, &truth, &runs, errors);
        if settings.timings {
            out["timings_s"] = serde_json::Value::Object(timing_json);
        }
        print_json(&out)?;
    }
    Ok(())
}

/// ERA on the clean and the noisy FRFs, and ERA's noisy model refined against the same
/// noisy FRFs (the z-domain fit, each pair weighted by its noise): the thesis's closing
/// recommendation, carried out. The thesis columns are untouched by it.
fn identify_both(
    options: &EraOptions,
    clean_frf: &era::FrfData,
    noisy_frf: &era::FrfData,
) -> anyhow::Result<Runs> {
    let run_one = |frf: &era::FrfData, label: &str| -> anyhow::Result<Identification> {
        identify(frf, options).with_context(|| format!("identifying the truth model ({label})"))
    };
    let clean = run_one(clean_frf, "no noise")?;
    let noisy = run_one(noisy_frf, "noisy")?;
    let refine_options = era::refine::RefineOptions::default();
    let refined = era::refine::identification::refine_identification(
        noisy.clone(),
        noisy_frf,
        &refine_options,
        &mut |_| {},
        &mut |_, _| {},
    )
    .context("refining the noisy truth-model fit")?;
    Ok(Runs {
        clean,
        noisy,
        refined,
    })
}
