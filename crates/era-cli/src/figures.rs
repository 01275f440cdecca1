//! Writing the figures and `report.html` of one identification into a folder.

use era::identify::Identification;
use era::preprocess::zero_leading_lines;
use era::FrfData;
use era_io::atomic::{write_atomic, write_via};
use era_plot::report::{report_html, ReportInput};
use era_plot::{frf_grid, frf_overlay, render_png, render_svg, singular_value_figure, Figure};
use std::path::Path;

/// Writes `stem.svg` and `stem.png` for a figure; returns the SVG text.
pub fn write_figure(dir: &Path, stem: &str, figure: &Figure) -> anyhow::Result<String> {
    let svg = render_svg(figure)?;
    write_atomic(&dir.join(format!("{stem}.svg")), svg.as_bytes())?;
    write_via(&dir.join(format!("{stem}.png")), |tmp| {
        render_png(figure, tmp).map_err(anyhow::Error::from)
    })?;
    Ok(svg)
}

/// The overview grid and every pair's overlay of `measured` (and `model` when given)
/// into `dir` and `dir/pairs`; returns the grid SVG and the (title, SVG) per pair.
pub fn write_frf_figures(
    dir: &Path,
    measured: &FrfData,
    model: Option<&FrfData>,
    progress: &indicatif::ProgressBar,
) -> anyhow::Result<(String, Vec<(String, String)>)> {
    let square = measured.outputs() == measured.inputs();
    let grid_svg = write_figure(dir, "grid", &frf_grid(measured, model, square))?;
    let pairs = dir.join("pairs");
    std::fs::create_dir_all(&pairs)
        .map_err(|e| crate::UsageError(format!("{}: {e}", pairs.display())))?;
    let mut overlays = Vec::new();
    for i in 0..measured.outputs() {
        for j in 0..measured.inputs() {
            let figure = frf_overlay(measured, model, i, j, square && i == j);
            let svg = write_figure(&pairs, &format!("pair_{}_{}", i + 1, j + 1), &figure)?;
            overlays.push((figure.title.clone(), svg));
            progress.inc(1);
        }
    }
    Ok((grid_svg, overlays))
}

/// Figures and report of `found` into `dir`: `singular_values`, `grid`,
/// `pairs/pair_I_J` (SVG and PNG) and `report.html`.
pub fn write_all(
    dir: &Path,
    title: &str,
    parameters: &str,
    found: &Identification,
    zero_lines: usize,
    states: usize,
    progress: &indicatif::ProgressBar,
) -> anyhow::Result<()> {
    let measured = zero_leading_lines(&found.processed, zero_lines);
    // The fit already evaluated the model on these lines.
    let model = FrfData::new(
        measured.frequency_hz().to_vec(),
        measured.outputs(),
        measured.inputs(),
        found.model_response.clone(),
        measured.quantity(),
    )?;
    let sv_svg = write_figure(
        dir,
        "singular_values",
        &singular_value_figure(&found.realization.singular_values, states),
    )?;
    let (grid_svg, overlays) = write_frf_figures(dir, &measured, Some(&model), progress)?;
    let html = report_html(&ReportInput {
        title,
        parameters,
        found,
        singular_values_svg: &sv_svg,
        grid_svg: &grid_svg,
        overlays: &overlays,
    });
    write_atomic(&dir.join("report.html"), html.as_bytes())?;
    Ok(())
}
