//! Refinement in the CLI: `era identify … --refine` and `era refine MODEL.json FRF_FILE`
//! (the core is [`era::refine`], wired into the pipeline by
//! [`era::refine::identification::refine_identification`]).

use crate::config::Refine;
use crate::input::{read_frf_with, shape_line};
use crate::output::identification::{write_identification, Bundle};
use crate::output::prepare_out_dir;
use crate::output::report::{identification_summary, print_json, Human};
use anyhow::Context;
use era::identification::Identification;
use era::identify::{assess_model, EraOptions};
use era::pipeline::realize::SvdPath;
use era_io::model_json::{FitJson, ModelJson};

/// A JSON parameter of an older model.json as a count.
fn count(model: &ModelJson, key: &str) -> usize {
    model
        .parameters
        .get(key)
        .and_then(|v| v.as_u64())
        .unwrap_or(0) as usize
}

/// `era refine MODEL.json FRF_FILE`.
pub fn run(a: &Refine) -> anyhow::Result<()> {
    let settings = a.settings;
    let human = Human::new(&settings);
    let ropts = a.options.clone();
    let geometry = crate::output::geometry::read(a.geometry.as_deref(), &human)?;
    let model =
        ModelJson::read(&a.model).with_context(|| format!("reading {}", a.model.display()))?;
    let mut outputs = match &a.out {
        Some(dir) => Some(prepare_out_dir(dir)?),
        None => None,
    };
    let input = read_frf_with(&a.file, &a.read)?;
    let frf = &input.file.frf;
    if a.out.is_some() {
        crate::output::figures::check_pairs(&a.pairs, frf.outputs(), frf.inputs())?;
    }
    check_model_fits(a, &model, frf)?;
    crate::config::identify::check_shape(&ropts, frf)?;
    human.print(&format!(
        "era refine {} {}\n  {}{}\n",
        a.model.display(),
        a.file.display(),
        shape_line(frf),
        input.note
    ));
    let found = start(a, &model, frf, input.file.channels.as_ref())?;
    let before = found.fit.clone();
    let found = crate::work::refine(found, frf, &ropts, None, &settings)
        .with_context(|| format!("refining {} on {}", a.model.display(), a.file.display()))?;
    human.print(&format!(
        "  the model as given: fit collocated {}, non-collocated {}\n",
        before
            .collocated_mean_relative_error
            .map_or("-".into(), |v| format!("{v:.3e}")),
        before
            .noncollocated_mean_relative_error
            .map_or("-".into(), |v| format!("{v:.3e}"))
    ));
    human.print(&crate::output::identify::refinement_summary(&found));
    let states = model
        .states
        .min(found.realization.singular_values.len())
        .max(1);
    human.print(&identification_summary(&found, states));
    let mut params = model.parameters.clone();
    params.refinement = Some(ropts.clone());
    params.refined_from = Some(a.model.clone());
    params.model_states = Some(found.model.states());
    let mut json = ModelJson::from_run(&found, &params);
    if json.singular_values.is_empty() {
        json.singular_values = model.singular_values.clone();
    }
    if let Some(set) = outputs.as_mut() {
        let fit = FitJson::from_report(&found.fit);
        let title = format!("era refine {} {}", a.model.display(), a.file.display());
        let mut source = crate::output::RunInput::from_file(&a.file, &input);
        source.pairs = a.pairs.clone();
        let source = crate::output::geometry::attach(source, geometry, frf.outputs());
        let echo = format!("refined from {}\n", a.model.display());
        let bundle = Bundle {
            found: &found,
            fit: &fit,
            source: &source,
            title: &title,
            echo: &echo,
            states,
            figures: !a.no_figures,
        };
        write_identification(set, std::path::Path::new(""), &json, &bundle, &settings)?;
    }
    if let (Some(dir), Some(set)) = (&a.out, outputs) {
        set.commit()?;
        human.print(&format!(
            "\nwrote {}\n",
            crate::output::identification::written_list(dir, !a.no_figures)
        ));
    }
    if settings.json {
        print_json(&json)?;
    }
    Ok(())
}

/// The model and the FRF file must be of one set: the same outputs and inputs, and
/// the FRF lines the model was identified from when model.json records them.
fn check_model_fits(a: &Refine, model: &ModelJson, frf: &era::FrfData) -> anyhow::Result<()> {
    if (model.outputs, model.inputs) != (frf.outputs(), frf.inputs()) {
        return crate::error::usage(format!(
            "{}: the model has {} outputs x {} inputs, {} has {} x {}",
            a.model.display(),
            model.outputs,
            model.inputs,
            a.file.display(),
            frf.outputs(),
            frf.inputs()
        ));
    }
    if let Some(lines) = &model.frf_lines {
        if let Some(why) = lines.differs_from(frf) {
            return crate::error::usage(format!(
                "{}: not the FRF lines of {}: {why}",
                a.file.display(),
                a.model.display()
            ));
        }
    }
    Ok(())
}

/// The given model assessed on `frf` as an identification would have it: its modes
/// marked physical or not as model.json says, only the physical ones kept for an
/// automatic model, collocation from the channel table.
fn start(
    a: &Refine,
    model: &ModelJson,
    frf: &era::FrfData,
    channels: Option<&era_io::uff::ChannelTable>,
) -> anyhow::Result<Identification> {
    let options = {
        let mut o = EraOptions::new(model.states.max(1), 1);
        o.integrations = count(model, "integrations");
        o.zero_lines = count(model, "zero_lines");
        o.pad_to = count(model, "pad_to");
        o
    };
    let state_space = model
        .state_space()
        .map_err(|e| crate::error::UsageError(format!("{}: {e}", a.model.display())))?;
    // The sample time of the identification: the model's own when discrete, else that
    // of the (padded) lines, as the pipeline computes it.
    let padded_lines = if options.pad_to > 0 {
        options.pad_to + 1
    } else {
        frf.lines()
    };
    let sample_time_s = model.sample_time_s.unwrap_or_else(|| {
        era::sources::frf::preprocess::sample_time_s(frf.spacing_hz(), padded_lines)
    });
    let svd_path = if model.hankel.path == "matrix-free" {
        SvdPath::MatrixFree
    } else {
        SvdPath::Dense
    };
    let mut found = assess_model(
        frf,
        &options,
        state_space,
        model.singular_values.clone(),
        (model.hankel.rows, model.hankel.cols),
        svd_path,
        sample_time_s,
    )
    .with_context(|| format!("evaluating {} on {}", a.model.display(), a.file.display()))?;
    // The modes judged physical in the file start the refinement of an automatic model;
    // every mode starts that of a fixed-order one (as `era identify --refine`).
    let auto = model
        .parameters
        .get("states")
        .is_some_and(|v| v.as_str() == Some("auto"));
    for (q, m) in found.quality.iter_mut().zip(&model.modes) {
        if let Some(physical) = m.physical {
            q.physical = physical;
            q.reason.clone_from(&m.reason);
        }
    }
    if auto {
        // Only the modes marked physical start: `refine_identification` keeps those of a
        // model chosen by a scan.
        let keep: Vec<bool> = found.quality.iter().map(|q| q.physical).collect();
        let mut k = 0;
        found.modal.modes.retain(|_| {
            k += 1;
            keep[k - 1]
        });
        found.quality.retain(|q| q.physical);
    }
    // Collocation from the channel table; the refinement keeps it.
    crate::output::figures::collocate_fit(&mut found.fit, channels, frf.outputs(), frf.inputs());
    Ok(found)
}
