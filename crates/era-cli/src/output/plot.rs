//! What `era plot` writes: the grid and one overlay per pair of the FRFs (with the
//! model's FRF when there is one), its singular values, and with a geometry the
//! model's mode shapes in three views.

use crate::config::Plot;
use crate::input::InputFrf;
use crate::output::figures::{chosen_pairs, frf_view, write_figure, write_frf_figures};
use crate::output::report::Human;
use era_io::atomic::OutputSet;
use era_io::geometry::Geometry;
use era_io::model_json::{ModeJson, ModelJson};
use era_plot::{singular_value_figure, FrfUnits};
use std::path::Path;

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

/// The figures into `set`: the model's singular values, the grid and the chosen pairs'
/// overlays of `measured` (and the model's FRF), and with a geometry the model's mode
/// shapes (the geometry's notes said). Returns the overlays' count and the shapes drawn.
pub fn write_figures(
    set: &mut OutputSet,
    a: &Plot,
    input: &InputFrf,
    (measured, model_frf): (&era::FrfData, Option<&era::FrfData>),
    model: Option<&ModelJson>,
    geometry: Option<&(String, Geometry)>,
    human: &Human,
) -> anyhow::Result<(usize, usize)> {
    if let Some(m) = model.filter(|m| m.states > 0) {
        let figure = singular_value_figure(&m.singular_values, m.states);
        write_figure(set, Path::new(""), "singular_values", &figure)?;
    }
    let frf = &input.file.frf;
    let mut view = frf_view(
        &FrfUnits::from_metadata(&input.file.metadata),
        frf.quantity(),
        input.file.channels.as_ref(),
        measured,
        a.phase,
    );
    if model.is_some_and(|m| m.refinement.is_some()) {
        view.model = "refined model".into();
    }
    let pairs = chosen_pairs(&a.pairs, &view, measured.outputs(), measured.inputs())?;
    let bar = crate::output::progress::bar(&a.settings, pairs.len() as u64, "figures");
    let (_, overlays) = write_frf_figures(
        set,
        Path::new(""),
        (measured, model_frf),
        &view,
        &pairs,
        &bar,
    )?;
    let drawn = match (geometry, model) {
        (Some((file, g)), Some(m)) => {
            let view = model_view(g, m, input.file.channels.as_ref());
            for note in
                crate::output::geometry::notes(file, g, input.file.channels.as_ref(), m.outputs)
            {
                human.print(&format!("  {note}\n"));
            }
            bar.inc_length(view.modes.len() as u64);
            crate::output::figures::write_three_views(set, Path::new(""), &view, &bar)?;
            view.modes.len()
        }
        _ => 0,
    };
    bar.finish_and_clear();
    Ok((overlays.len(), drawn))
}
