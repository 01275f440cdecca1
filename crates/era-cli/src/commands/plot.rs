//! `era plot FRF_FILE [--model model.json] --out DIR`: any FRF file, overlaid with any
//! model of the same shape.

use crate::config::Plot;
use crate::error::usage;
use crate::input::read_frf_with;
use crate::output::figures::{chosen_pairs, frf_view, write_figure, write_frf_figures};
use crate::output::prepare_out_dir;
use crate::output::report::{print_json, Human};
use anyhow::Context;
use era::pipeline::fit::model_frf;
use era::sources::frf::preprocess::{integrate, zero_leading_lines};
use era_io::model_json::{ModeJson, ModelJson};
use era_plot::{singular_value_figure, FrfUnits};
use serde_json::json;
use std::path::Path;

pub fn run(a: &Plot) -> anyhow::Result<()> {
    let settings = a.settings;
    let human = Human::new(&settings);
    if a.geometry.is_some() && a.model.is_none() {
        return usage("--geometry draws the model's mode shapes: give --model model.json too");
    }
    // Checked before anything is read or written: a bad geometry exits with code 2.
    let geometry = crate::output::geometry::read(a.geometry.as_deref(), &human)?;
    let mut set = prepare_out_dir(&a.out)?;
    let input = read_frf_with(&a.file, &a.read)?;
    let frf = input.file.frf.clone();
    crate::output::figures::check_pairs(&a.pairs, frf.outputs(), frf.inputs())?;
    let (model, integrations, zero_lines) = overlay_model(a, &frf)?;
    let measured = zero_leading_lines(&integrate(&frf, integrations)?, zero_lines);
    let model_frf = match &model {
        Some(m) => {
            let ss = m.state_space().map_err(crate::error::UsageError)?;
            if m.states > 0 {
                write_figure(
                    &mut set,
                    Path::new(""),
                    "singular_values",
                    &singular_value_figure(&m.singular_values, m.states),
                )?;
            }
            Some(model_frf(&ss, &measured)?)
        }
        None => None,
    };
    let mut view = frf_view(
        &FrfUnits::from_metadata(&input.file.metadata),
        frf.quantity(),
        input.file.channels.as_ref(),
        &measured,
        a.phase,
    );
    if model.as_ref().is_some_and(|m| m.refinement.is_some()) {
        view.model = "refined model".into();
    }
    let pairs = chosen_pairs(&a.pairs, &view, measured.outputs(), measured.inputs())?;
    let bar = crate::output::progress::bar(&settings, pairs.len() as u64, "figures");
    let (_, overlays) = write_frf_figures(
        &mut set,
        Path::new(""),
        (&measured, model_frf.as_ref()),
        &view,
        &pairs,
        &bar,
    )?;
    let drawn = match (&geometry, &model) {
        (Some((file, g)), Some(m)) => {
            let view = model_view(g, m, input.file.channels.as_ref());
            for note in
                crate::output::geometry::notes(file, g, input.file.channels.as_ref(), m.outputs)
            {
                human.print(&format!("  {note}\n"));
            }
            bar.inc_length(view.modes.len() as u64);
            crate::output::figures::write_three_views(&mut set, Path::new(""), &view, &bar)?;
            view.modes.len()
        }
        _ => 0,
    };
    bar.finish_and_clear();
    set.commit()?;
    human.print(&format!(
        "wrote {0}/grid.{{svg,png}} and {1} pair overlays in {0}/pairs{2} ({3} FRFs, {4} integration(s), {5} zeroed line(s))\n",
        a.out.display(),
        overlays.len(),
        if model.is_some() { format!(", {}/singular_values.{{svg,png}}", a.out.display()) } else { String::new() },
        measured.quantity(),
        integrations,
        zero_lines
    ));
    if drawn > 0 {
        human.print(&format!(
            "wrote {drawn} mode shapes in three views in {}/shapes (mode_NN.{{svg,png}})\n",
            a.out.display()
        ));
    }
    if settings.json {
        print_json(
            &json!({"out": a.out, "pairs": overlays.len(), "model": a.model, "integrations": integrations, "zero_lines": zero_lines, "geometry": a.geometry, "shapes_drawn": drawn}),
        )?;
    }
    Ok(())
}

/// The modes of model.json `m` on `g`, the outputs placed by the FRF file's channel
/// table (era's numbering without one).
fn model_view(
    g: &era_io::geometry::Geometry,
    m: &ModelJson,
    channels: Option<&era_io::frf_file::ChannelTable>,
) -> era_plot::viewer::ShapeView {
    let (nodes, segments, placed, not_drawn) =
        crate::output::geometry::layout(g, channels, m.outputs);
    let shapes: Vec<Vec<era::Complex64>> = m.modes.iter().map(ModeJson::shape).collect();
    let labelled: Vec<(String, &[era::Complex64])> = m
        .modes
        .iter()
        .zip(&shapes)
        .enumerate()
        .map(|(k, (mode, shape))| {
            let quality = mode
                .indicators
                .as_ref()
                .map(|i| (i.mpc, mode.physical.unwrap_or(true)));
            (
                era_plot::viewer::mode_label(k, mode.frequency_hz, mode.damping_ratio, quality),
                shape.as_slice(),
            )
        })
        .collect();
    era_plot::viewer::ShapeView::from_shapes(nodes, segments, &placed, &labelled, not_drawn)
}

/// The model to overlay (`--model`), refused when its shape is not the FRFs', and the
/// integrations and zeroed lines to plot with: the flags', else the model's, else none.
fn overlay_model(
    a: &Plot,
    frf: &era::FrfData,
) -> anyhow::Result<(Option<ModelJson>, usize, usize)> {
    let model = match &a.model {
        Some(path) => {
            Some(ModelJson::read(path).with_context(|| format!("reading {}", path.display()))?)
        }
        None => None,
    };
    let from_model = |key: &str| {
        model
            .as_ref()
            .and_then(|m| m.parameters.get(key))
            .and_then(|v| v.as_u64())
            .map(|v| v as usize)
    };
    let integrations = a
        .integrations
        .or_else(|| from_model("integrations"))
        .unwrap_or(0);
    let zero_lines = a
        .zero_lines
        .or_else(|| from_model("zero_lines"))
        .unwrap_or(0);
    if let Some(m) = &model {
        if (m.outputs, m.inputs) != (frf.outputs(), frf.inputs()) {
            return usage(format!(
                "--model {}: the model has {} outputs x {} inputs, {} has {} x {}",
                a.model.as_ref().unwrap().display(),
                m.outputs,
                m.inputs,
                a.file.display(),
                frf.outputs(),
                frf.inputs()
            ));
        }
    }
    Ok((model, integrations, zero_lines))
}
