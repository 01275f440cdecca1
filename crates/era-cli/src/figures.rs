//! Writing the figures and `report.html` of one identification into an [`OutputSet`].

use crate::output::write_output;
use era::identify::Identification;
use era::FrfData;
use era_io::atomic::{write_atomic, write_via, OutputSet};
use era_io::IoError;
use era_plot::report::{report_html, ReportInput};
use era_plot::stabilization::{stabilization_png, stabilization_svg, StabilizationPlot};
use era_plot::{frf_grid, frf_overlay, render_png, render_svg, singular_value_figure, Figure};
use std::path::Path;

/// The last 12 bytes of every complete PNG: the empty IEND chunk and its CRC.
const PNG_END: [u8; 12] = [0, 0, 0, 0, b'I', b'E', b'N', b'D', 0xAE, 0x42, 0x60, 0x82];

/// Renders `figure` as PNG into `path` and checks that the file is complete: the
/// encoder's buffered writer may drop a failed last write (a full disk) silently.
fn write_png(figure: &Figure, path: &Path) -> Result<(), IoError> {
    write_png_with(path, |tmp| render_png(figure, tmp))
}

/// [`write_png`] for any renderer.
fn write_png_with(
    path: &Path,
    render: impl FnOnce(&Path) -> Result<(), era_plot::PlotError>,
) -> Result<(), IoError> {
    let failed = |message: String| IoError::Format {
        path: path.to_path_buf(),
        location: String::new(),
        message,
    };
    write_via(path, |tmp| {
        // The SVG of the same figure has just been drawn: a failure here is the file's.
        render(tmp).map_err(|e| failed(format!("cannot write the PNG: {e}")))?;
        // Only the closing chunk is read back, not the whole image.
        let (len, tail) = (|| {
            use std::io::{Read, Seek, SeekFrom};
            let mut file = std::fs::File::open(tmp)?;
            let len = file.metadata()?.len();
            let mut tail = [0u8; PNG_END.len()];
            if len >= PNG_END.len() as u64 {
                file.seek(SeekFrom::End(-(PNG_END.len() as i64)))?;
                file.read_exact(&mut tail)?;
            }
            Ok((len, tail))
        })()
        .map_err(|e| IoError::Io {
            path: path.to_path_buf(),
            error: e,
        })?;
        if tail != PNG_END {
            return Err(failed(format!(
                "the PNG encoder stopped after {len} bytes (disk full?)"
            )));
        }
        Ok(())
    })
}

/// Writes `folder/stem.svg` and `folder/stem.png` of a figure into `set`; returns the
/// SVG text.
pub fn write_figure(
    set: &mut OutputSet,
    folder: &Path,
    stem: &str,
    figure: &Figure,
) -> anyhow::Result<String> {
    let svg = render_svg(figure)?;
    write_output(set, folder.join(format!("{stem}.svg")), |p| {
        Ok(write_atomic(p, svg.as_bytes())?)
    })?;
    write_output(set, folder.join(format!("{stem}.png")), |p| {
        Ok(write_png(figure, p)?)
    })?;
    Ok(svg)
}

/// The overview grid and every pair's overlay of `measured` (and `model` when given)
/// into `folder` and `folder/pairs` of `set`; returns the grid SVG and the (title, SVG)
/// per pair.
pub fn write_frf_figures(
    set: &mut OutputSet,
    folder: &Path,
    measured: &FrfData,
    model: Option<&FrfData>,
    progress: &indicatif::ProgressBar,
) -> anyhow::Result<(String, Vec<(String, String)>)> {
    let square = measured.outputs() == measured.inputs();
    let grid_svg = write_figure(set, folder, "grid", &frf_grid(measured, model, square))?;
    let pairs = folder.join("pairs");
    let mut overlays = Vec::new();
    for i in 0..measured.outputs() {
        for j in 0..measured.inputs() {
            let figure = frf_overlay(measured, model, i, j, square && i == j);
            let svg = write_figure(set, &pairs, &format!("pair_{}_{}", i + 1, j + 1), &figure)?;
            overlays.push((figure.title.clone(), svg));
            progress.inc(1);
        }
    }
    Ok((grid_svg, overlays))
}

/// Figures and report of `found` into `folder` of `set`: `singular_values`, `grid`,
/// `pairs/pair_I_J` (SVG and PNG) and `report.html`.
#[allow(clippy::too_many_arguments)]
pub fn write_all(
    set: &mut OutputSet,
    folder: &Path,
    title: &str,
    parameters: &str,
    found: &Identification,
    states: usize,
    progress: &indicatif::ProgressBar,
) -> anyhow::Result<()> {
    // What the fit compared, kept in the identification: the measurement and the
    // model's FRF on its lines.
    let measured = &found.measured;
    let model = found.model_frf()?;
    // With a scan, the factored H0's values: on the matrix-free path they run past the
    // largest order, so the gap after the physical modes shows.
    let singular_values = match &found.stabilization {
        Some(st) => &st.singular_values,
        None => &found.realization.singular_values,
    };
    let sv_svg = write_figure(
        set,
        folder,
        "singular_values",
        &singular_value_figure(singular_values, states),
    )?;
    let stabilization_svg = match &found.stabilization {
        Some(st) => {
            let physical: Vec<f64> = found
                .modal
                .modes
                .iter()
                .zip(&found.quality)
                .filter(|(_, q)| q.physical)
                .map(|(m, _)| m.frequency_hz)
                .collect();
            let plot = StabilizationPlot::new(
                &format!("Stabilization diagram, orders {}", st.range),
                st,
                (0.0, found.band_hz.1),
                measured.frequency_hz(),
                physical,
            );
            let svg = stabilization_svg(&plot)?;
            write_output(set, folder.join("stabilization.svg"), |p| {
                Ok(write_atomic(p, svg.as_bytes())?)
            })?;
            write_output(set, folder.join("stabilization.png"), |p| {
                Ok(write_png_with(p, |tmp| stabilization_png(&plot, tmp))?)
            })?;
            Some(svg)
        }
        None => None,
    };
    let (grid_svg, overlays) = write_frf_figures(set, folder, measured, Some(&model), progress)?;
    let html = report_html(&ReportInput {
        title,
        parameters,
        found,
        singular_values_svg: &sv_svg,
        stabilization_svg: stabilization_svg.as_deref(),
        grid_svg: &grid_svg,
        overlays: &overlays,
    });
    write_output(set, folder.join("report.html"), |p| {
        Ok(write_atomic(p, html.as_bytes())?)
    })?;
    Ok(())
}
