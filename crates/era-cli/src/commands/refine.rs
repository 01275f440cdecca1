//! `era refine MODEL.json FRF_FILE`: a model written earlier, read back and assessed by
//! [`crate::input::model`], refined ([`era::refine`], through [`crate::work::refine`])
//! on the FRFs it came from; [`crate::output::refine`] writes the result.

use crate::config::Refine;
use crate::input::{read_frf_with, shape_line};
use crate::output::identify::fit_errors;
use crate::output::prepare_out_dir;
use crate::output::report::Human;
use anyhow::Context;
use era_io::model_json::ModelJson;

/// `era refine MODEL.json FRF_FILE`.
pub fn run(a: &Refine) -> anyhow::Result<()> {
    let settings = a.settings;
    let human = Human::new(&settings);
    let ropts = a.options.clone();
    let geometry = crate::output::geometry::read(a.geometry.as_deref(), &human)?;
    let model =
        ModelJson::read(&a.model).with_context(|| format!("reading {}", a.model.display()))?;
    let outputs = a.out.as_deref().map(prepare_out_dir).transpose()?;
    let input = read_frf_with(&a.file, &a.read)?;
    let frf = &input.file.frf;
    if a.out.is_some() {
        crate::output::figures::check_pairs(&a.pairs, frf.outputs(), frf.inputs())?;
    }
    crate::input::model::check_model_fits(a, &model, frf)?;
    crate::config::identify::check_shape(&ropts, frf)?;
    human.print(&format!(
        "era refine {} {}\n  {}{}\n",
        a.model.display(),
        a.file.display(),
        shape_line(frf),
        input.note
    ));
    let found = crate::input::model::start(a, &model, frf, input.file.channels.as_ref())?;
    let given = fit_errors(&found.fit);
    let found = crate::work::refine(found, frf, &ropts, None, &settings)
        .with_context(|| format!("refining {} on {}", a.model.display(), a.file.display()))?;
    human.print(&format!("  the model as given: {given}\n"));
    human.print(&crate::output::identify::refinement_summary(&found));
    crate::output::refine::hand_on(a, outputs, &model, &input, geometry, &found, &human)
}
