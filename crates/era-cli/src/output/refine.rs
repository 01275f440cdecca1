//! What `era refine` hands on: the refined identification's summary, `model.json` (on
//! stdout too with `--json`) and, with `--out`, the run's files.

use crate::config::Refine;
use crate::input::InputFrf;
use crate::output::identification::{write_identification, Bundle};
use crate::output::report::{identification_summary, print_json, Human};
use era::data::identification::Identification;
use era_io::atomic::OutputSet;
use era_io::geometry::Geometry;
use era_io::model_json::{FitJson, ModelJson};

/// The summary, model.json and the files of `found`, refined from `model` on `input`.
pub fn hand_on(
    a: &Refine,
    mut outputs: Option<OutputSet>,
    model: &ModelJson,
    input: &InputFrf,
    geometry: Option<(String, Geometry)>,
    found: &Identification,
    human: &Human,
) -> anyhow::Result<()> {
    let settings = &a.settings;
    let frf = &input.file.frf;
    let ropts = &a.options;
    let states = model
        .states
        .min(found.realization.singular_values.len())
        .max(1);
    human.print(&identification_summary(found, states));
    let mut params = model.parameters.clone();
    params.refinement = Some(ropts.clone());
    params.refined_from = Some(a.model.clone());
    params.model_states = Some(found.model.states());
    let mut json = ModelJson::from_run(found, &params);
    if json.singular_values.is_empty() {
        json.singular_values = model.singular_values.clone();
    }
    if let Some(set) = outputs.as_mut() {
        let fit = FitJson::from_report(&found.fit);
        let title = format!("era refine {} {}", a.model.display(), a.file.display());
        let mut source = super::RunInput::from_file(&a.file, input);
        source.pairs = a.pairs.clone();
        let source = super::geometry::attach(source, geometry, frf.outputs());
        let echo = format!("refined from {}\n", a.model.display());
        let bundle = Bundle {
            found,
            fit: &fit,
            source: &source,
            title: &title,
            echo: &echo,
            states,
            figures: !a.no_figures,
        };
        write_identification(set, std::path::Path::new(""), &json, &bundle, settings)?;
    }
    if let (Some(dir), Some(set)) = (&a.out, outputs) {
        set.commit()?;
        human.print(&format!(
            "\nwrote {}\n",
            super::identification::written_list(dir, !a.no_figures)
        ));
    }
    if settings.json {
        print_json(&json)?;
    }
    Ok(())
}
