//! `era plot FRF_FILE [--model model.json] --out DIR`: any FRF file, overlaid with any
//! model of the same shape.

use crate::config::Plot;
use crate::error::usage;
use crate::input::read_frf_with;
use crate::output::prepare_out_dir;
use crate::output::report::{print_json, Human};
use era::pipeline::fit::model_frf;
use era::sources::frf::preprocess::{integrate, zero_leading_lines};
use serde_json::json;

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
    let (model, integrations, zero_lines) = crate::input::model::overlay_model(a, &frf)?;
    let measured = zero_leading_lines(&integrate(&frf, integrations)?, zero_lines);
    let model_frf = match &model {
        Some(m) => {
            let ss = m.state_space().map_err(crate::error::UsageError)?;
            Some(model_frf(&ss, &measured)?)
        }
        None => None,
    };
    let (overlays, drawn) = crate::output::plot::write_figures(
        &mut set,
        a,
        &input,
        (&measured, model_frf.as_ref()),
        model.as_ref(),
        geometry.as_ref(),
        &human,
    )?;
    set.commit()?;
    human.print(&format!(
        "wrote {0}/grid.{{svg,png}} and {1} pair overlays in {0}/pairs{2} ({3} FRFs, {4} integration(s), {5} zeroed line(s))\n",
        a.out.display(),
        overlays,
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
            &json!({"out": a.out, "pairs": overlays, "model": a.model, "integrations": integrations, "zero_lines": zero_lines, "geometry": a.geometry, "shapes_drawn": drawn}),
        )?;
    }
    Ok(())
}
