//! Refinement in the CLI: `era identify … --refine` and `era refine MODEL.json FRF_FILE`
//! (the core is [`era::refine`], wired into the pipeline by
//! [`era::refine::identification::refine_identification`]).

use crate::config::Refine;
use crate::config::Settings;
use crate::input::{read_frf_with, shape_line};
use crate::output::identification::{write_identification, Bundle};
use crate::output::prepare_out_dir;
use crate::output::report::{identification_summary, print_json, Human};
use anyhow::Context;
use era::identification::Identification;
use era::identify::{assess_model, EraOptions};
use era::pipeline::realize::SvdPath;
use era::refine::identification::refine_identification_in;
use era::refine::RefineOptions;
use era_io::model_json::{FitJson, ModelJson};
use std::fmt::Write as _;

/// `--reciprocal` needs a square set: said before the identification runs.
pub fn check_shape(options: &RefineOptions, frf: &era::FrfData) -> anyhow::Result<()> {
    if options.reciprocal && frf.outputs() != frf.inputs() {
        return crate::error::usage(format!(
            "--reciprocal: the set has {} outputs x {} inputs; reciprocity needs a square (collocated) set",
            frf.outputs(),
            frf.inputs()
        ));
    }
    Ok(())
}

/// Runs the refinement of `found` with a spinner that counts the iterations.
pub fn refine_found(
    found: Identification,
    frf: &era::FrfData,
    options: &RefineOptions,
    domain: Option<era::ModelDomain>,
    settings: &Settings,
) -> anyhow::Result<Identification> {
    let spinner = crate::output::progress::spinner(settings);
    spinner.set_message("refinement");
    let mut on_stage = |_: era::Stage| {};
    let mut on_step = |iteration: usize, cost: f64| {
        spinner.set_message(format!(
            "refinement: iteration {iteration}, cost {cost:.3e}"
        ));
    };
    let refined =
        refine_identification_in(found, frf, options, domain, &mut on_stage, &mut on_step)
            .map_err(|e| match e {
                era::EraError::InvalidParameter {
                    name: "max-iterations",
                    value,
                    reason,
                } => anyhow::Error::from(crate::error::UsageError(format!(
                    "--max-iterations {value}: {}",
                    reason.message(era::params::Naming::Flag)
                ))),
                other => anyhow::Error::from(other),
            })
            .context("refining the model");
    spinner.finish_and_clear();
    refined
}

/// How the refinement went, in lines for the human summary.
pub fn summary(found: &Identification) -> String {
    let Some(r) = &found.refinement else {
        return String::new();
    };
    let f = &r.refinement;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\nrefinement ({} model of the {} data, residuals {}): {} start modes, {} kept; {} iterations, {}; fit over the band {:.3e} -> {:.3e} (weighted cost: free residues at the start {:.3e}, the model {:.3e}), {:.2} s",
        if f.sample_time_s.is_some() {
            "z-domain"
        } else {
            "continuous"
        },
        f.quantity,
        match (&f.lower, &f.upper) {
            (Some(_), Some(_)) => "lower+upper",
            (Some(_), None) => "lower",
            (None, Some(_)) => "upper",
            (None, None) => "none",
        },
        r.start_modes(),
        f.modes.len(),
        f.iterations,
        if f.converged {
            "converged"
        } else {
            "NOT converged (the iterations ran out: raise --max-iterations)"
        },
        f.fit_before,
        f.fit_after,
        f.cost_before,
        f.cost_after,
        found.timings.refine
    );
    let _ = writeln!(s, "  fitted domain: {}", r.fit_domain.reason);
    for line in r.start_lines() {
        let _ = writeln!(s, "  {line}");
    }
    let _ = writeln!(
        s,
        "  (± is one standard deviation from the Gauss-Newton covariance at the optimum, the noise taken from the residual)"
    );
    s
}

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
    check_shape(&ropts, frf)?;
    human.print(&format!(
        "era refine {} {}\n  {}{}\n",
        a.model.display(),
        a.file.display(),
        shape_line(frf),
        input.note
    ));
    let found = start(a, &model, frf, input.file.channels.as_ref())?;
    let before = found.fit.clone();
    let found = refine_found(found, frf, &ropts, None, &settings)
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
    human.print(&summary(&found));
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
