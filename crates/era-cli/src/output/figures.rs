//! Writing the figures and `report.html` of one identification into an [`OutputSet`].

use crate::output::{write_output, RunInput};
use era::data::identification::Identification;
use era::{FrfData, Quantity};
use era_io::atomic::{write_atomic, write_via, OutputSet};
use era_io::uff::ChannelTable;
use era_io::IoError;
use era_plot::oma::{mac_png, mac_svg};
use era_plot::report::{report_html, CoherenceInput, PairFigure, ReportInput, ReportSection};
use era_plot::shapes::{complexity_png, complexity_svg, three_view_png, three_view_svg, ThreeView};
use era_plot::stabilization::{stabilization_png, stabilization_svg, StabilizationPlot};
use era_plot::viewer::ShapeView;
use era_plot::{
    coherence_grid, frf_grid, frf_overlay, render_png, render_svg, singular_value_figure, Figure,
    FrfUnits, FrfView, PairSelection, PhaseView,
};
use std::path::Path;

/// How many times a quantity is integrated to become another (acceleration → velocity
/// is 1); 0 when it is not reached by integration.
fn integrations_between(read: Quantity, shown: Quantity) -> usize {
    let mut q = Some(read);
    for n in 0..3 {
        if q == Some(shown) {
            return n;
        }
        q = q.and_then(Quantity::integrated);
    }
    0
}

/// Whether output `i` and input `j` of `table` are at the same node and direction.
pub fn collocated_in(table: &ChannelTable, i: usize, j: usize) -> bool {
    matches!((table.outputs.get(i), table.inputs.get(j)), (Some(o), Some(n)) if o.dof == n.dof)
}

/// Marks the fit's collocated pairs from the channel table when it fits the set (same
/// node and direction), as the figures and report do ([`frf_view`]): the summary,
/// fit.json, model.json and the report then agree. Without a table, by index.
pub fn collocate_fit(
    fit: &mut era::pipeline::fit::FitReport,
    channels: Option<&ChannelTable>,
    q: usize,
    p: usize,
) {
    if let Some(t) = channels.filter(|t| (t.outputs.len(), t.inputs.len()) == (q, p)) {
        fit.set_collocation(|i, j| collocated_in(t, i, j));
    }
}

/// The figures' view of `shown` (the FRFs as plotted, after any integrations) of an
/// input read as `read` in `units`: the unit label integrated along, the phase view,
/// and collocation from the channel table when it fits the set (same node and
/// direction), by index otherwise.
pub fn frf_view(
    units: &FrfUnits,
    read: Quantity,
    channels: Option<&ChannelTable>,
    shown: &FrfData,
    phase: PhaseView,
) -> FrfView {
    let (q, p) = (shown.outputs(), shown.inputs());
    let mut view = FrfView::by_index(q, p);
    view.unit = units
        .integrated(integrations_between(read, shown.quantity()))
        .label();
    view.phase = phase;
    if let Some(t) = channels.filter(|t| (t.outputs.len(), t.inputs.len()) == (q, p)) {
        view.collocated = (0..q * p).map(|k| collocated_in(t, k / p, k % p)).collect();
        let names = |side: &[era_io::uff::Channel]| {
            side.iter()
                .map(|c| {
                    format!(
                        "node {} {}",
                        c.dof.node,
                        era_io::frf_file::direction_name(c.dof.direction)
                    )
                })
                .collect()
        };
        view.output_names = names(&t.outputs);
        view.input_names = names(&t.inputs);
    }
    view
}

/// The pairs `selection` (`--pairs`) picks from a `q × p` set, 0-based; a pair
/// outside the set is the flag's error.
///
/// # Errors
/// A usage error naming `--pairs` and its value.
pub fn chosen_pairs(
    selection: &PairSelection,
    view: &FrfView,
    q: usize,
    p: usize,
) -> anyhow::Result<Vec<(usize, usize)>> {
    selection
        .pairs(q, p, view)
        .or_else(|e| crate::error::usage(format!("--pairs {selection}: {e}")))
}

/// Refuses a `--pairs` list that names a pair outside a `q × p` set, before any work.
///
/// # Errors
/// As [`chosen_pairs`].
pub fn check_pairs(selection: &PairSelection, q: usize, p: usize) -> anyhow::Result<()> {
    chosen_pairs(selection, &FrfView::by_index(q, p), q, p).map(|_| ())
}

/// The last 12 bytes of every complete PNG: the empty IEND chunk and its CRC.
const PNG_END: [u8; 12] = [0, 0, 0, 0, b'I', b'E', b'N', b'D', 0xAE, 0x42, 0x60, 0x82];

/// Renders `figure` as PNG into `path` and checks that the file is complete: the
/// encoder's buffered writer may drop a failed last write (a full disk) silently.
fn write_png(figure: &Figure, path: &Path) -> Result<(), IoError> {
    write_png_with(path, |tmp| render_png(figure, tmp))
}

/// [`write_png`] for any renderer.
pub(crate) fn write_png_with(
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

/// Writes `folder/stem.svg` (the text `svg`) and `folder/stem.png` (drawn by `png`,
/// which gets the staged path) into `set`.
pub fn write_svg_png(
    set: &mut OutputSet,
    folder: &Path,
    stem: &str,
    svg: &str,
    png: impl FnOnce(&Path) -> Result<(), IoError>,
) -> anyhow::Result<()> {
    write_output(set, folder.join(format!("{stem}.svg")), |p| {
        Ok(write_atomic(p, svg.as_bytes())?)
    })?;
    write_output(set, folder.join(format!("{stem}.png")), |p| Ok(png(p)?))
}

/// Writes `automac` (with `automac`), `complexity` and, with a geometry, each mode's
/// three views into `folder` of `set`; returns the report's sections (the AutoMAC and
/// the complexity). The three views count on `progress`.
pub fn write_shape_figures(
    set: &mut OutputSet,
    folder: &Path,
    found: &Identification,
    view: Option<&ShapeView>,
    automac: bool,
    progress: &indicatif::ProgressBar,
) -> anyhow::Result<Vec<super::shapes::Section>> {
    let mut sections = Vec::new();
    if let Some(mac) = automac
        .then(|| super::shapes::automac_plot(found))
        .flatten()
    {
        let svg = mac_svg(&mac)?;
        write_svg_png(set, folder, "automac", &svg, |p| {
            write_png_with(p, |tmp| mac_png(&mac, tmp))
        })?;
        sections.push(super::shapes::Section {
            id: "automac",
            heading: mac.title.clone(),
            caption: "The modal assurance criterion between the modes' shapes (AutoMAC): 1 on the diagonal; an entry near 1 off it says two modes look alike at these sensors (too few sensors to tell them apart, or one mode found twice).".into(),
            svg,
        });
    }
    if let Some(plot) = super::shapes::complexity_plot(found) {
        let svg = complexity_svg(&plot)?;
        write_svg_png(set, folder, "complexity", &svg, |p| {
            write_png_with(p, |tmp| complexity_png(&plot, tmp))
        })?;
        sections.push(super::shapes::Section {
            id: "complexity",
            heading: "Complexity of the shapes".into(),
            caption: "Each entry of a shape as a vector in the complex plane, divided by the largest entry (which lies on the positive real axis, the circle is 1). A real normal mode's entries lie on one line through 0 (MPC 1); entries spread round the circle are a complex shape: close modes mixed, non-proportional damping, or noise.".into(),
            svg,
        });
    }
    if let Some(v) = view {
        progress.inc_length(v.modes.len() as u64);
        write_three_views(set, folder, v, progress)?;
    }
    Ok(sections)
}

/// Each mode of `view` in three views ([`ThreeView`]), `folder/shapes/mode_NN.svg/png`,
/// one step of `progress` each.
pub fn write_three_views(
    set: &mut OutputSet,
    folder: &Path,
    view: &ShapeView,
    progress: &indicatif::ProgressBar,
) -> anyhow::Result<()> {
    let dir = folder.join("shapes");
    for k in 0..view.modes.len() {
        let Some(plot) = ThreeView::new(view, k, super::shapes::AMPLITUDE) else {
            continue;
        };
        let svg = three_view_svg(&plot)?;
        write_svg_png(set, &dir, &format!("mode_{:02}", k + 1), &svg, |p| {
            write_png_with(p, |tmp| three_view_png(&plot, tmp))
        })?;
        progress.inc(1);
    }
    Ok(())
}

/// The overview grid (every pair) and the overlay of each of `pairs` (0-based) of
/// `measured` (and `model` when given) into `folder` and `folder/pairs` of `set`;
/// returns the grid SVG and the overlays.
pub fn write_frf_figures(
    set: &mut OutputSet,
    folder: &Path,
    frfs: (&FrfData, Option<&FrfData>),
    view: &FrfView,
    pairs: &[(usize, usize)],
    progress: &indicatif::ProgressBar,
) -> anyhow::Result<(String, Vec<PairFigure>)> {
    let (measured, model) = frfs;
    let grid_svg = write_figure(set, folder, "grid", &frf_grid(measured, model, view))?;
    let folder = folder.join("pairs");
    let mut overlays = Vec::with_capacity(pairs.len());
    for &(i, j) in pairs {
        let figure = frf_overlay(measured, model, i, j, view);
        let svg = write_figure(set, &folder, &format!("pair_{}_{}", i + 1, j + 1), &figure)?;
        overlays.push(PairFigure {
            output: i,
            input: j,
            title: figure.title.clone(),
            svg,
        });
        progress.inc(1);
    }
    Ok((grid_svg, overlays))
}

/// The stabilization diagram of `found`'s scan into `folder` of `set` (SVG and PNG);
/// returns the SVG, or `None` when no scan ran.
pub fn write_stabilization(
    set: &mut OutputSet,
    folder: &Path,
    found: &Identification,
) -> anyhow::Result<Option<String>> {
    Ok(match &found.stabilization {
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
                found.measured.frequency_hz(),
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
    })
}

/// The singular values the figure shows. With a scan, the factored H0's: on the
/// matrix-free path they run past the largest order, so the gap after the physical
/// modes shows. At a fixed order on the matrix-free path the run computed its `states`
/// values only: more of the same H0 are computed here for the figure (up to
/// `2·states + 20`, at most [`FIGURE_SINGULAR_VALUES`]); the model is not touched.
fn figure_singular_values(found: &Identification, source: &RunInput, states: usize) -> Vec<f64> {
    let computed = match &found.stabilization {
        Some(st) => &st.singular_values,
        None => &found.realization.singular_values,
    };
    let short = computed.len() <= states + 1
        && found.stabilization.is_none()
        && found.realization.svd_path == era::pipeline::factor::SvdPath::MatrixFree;
    if let (true, Some((frf, options))) = (short, &source.hankel) {
        let count = (2 * states + 20).min(FIGURE_SINGULAR_VALUES.max(states + 20));
        // For the figure only: should it fail, the figure shows what the run computed.
        if let Ok(Some(more)) = era::identify::hankel_singular_values(frf, options, count) {
            if more.len() > computed.len() {
                return more;
            }
        }
    }
    computed.clone()
}

/// The most singular values a fixed-order figure computes past what the run did.
pub const FIGURE_SINGULAR_VALUES: usize = 400;

/// Figures and report of `found` into `folder` of `set`: `singular_values`, `grid`,
/// `pairs/pair_I_J`, `coherence` when `source` carries it, `automac`, `complexity` and
/// with a geometry `shapes/mode_NN` ([`super::shapes`]) (SVG and PNG) and
/// `report.html`, in the units and with the collocation `source` gives.
#[allow(clippy::too_many_arguments)]
pub fn write_all(
    set: &mut OutputSet,
    folder: &Path,
    title: &str,
    parameters: &str,
    found: &Identification,
    source: &RunInput,
    states: usize,
    progress: &indicatif::ProgressBar,
) -> anyhow::Result<()> {
    // What the fit compared, kept in the identification: the measurement and the
    // model's FRF on its lines.
    let measured = &found.measured;
    let model = found.model_frf()?;
    let singular_values = figure_singular_values(found, source, states);
    let sv_svg = write_figure(
        set,
        folder,
        "singular_values",
        &singular_value_figure(&singular_values, states),
    )?;
    let stabilization_svg = write_stabilization(set, folder, found)?;
    let mut view = frf_view(
        &source.units,
        source.quantity,
        source.channels.as_ref(),
        measured,
        source.phase,
    );
    if found.refinement.is_some() {
        view.model = "refined model".into();
    }
    let pairs = chosen_pairs(&source.pairs, &view, measured.outputs(), measured.inputs())?;
    let coherence_svg = match &source.coherence {
        Some(c) => Some(write_figure(
            set,
            folder,
            "coherence",
            &coherence_grid(&c.title, &c.frequency_hz, &c.curves),
        )?),
        None => None,
    };
    let (grid_svg, overlays) = write_frf_figures(
        set,
        folder,
        (measured, Some(&model)),
        &view,
        &pairs,
        progress,
    )?;
    let shapes = super::geometry::shape_view(source, found);
    let own = write_shape_figures(set, folder, found, shapes.as_ref(), true, progress)?;
    let sections: Vec<ReportSection> = own.iter().map(super::shapes::Section::view).collect();
    let html = report_html(&ReportInput {
        title,
        source: &source.section,
        view: &view,
        coherence: source
            .coherence
            .as_ref()
            .zip(coherence_svg.as_deref())
            .map(|(c, svg)| CoherenceInput {
                caption: &c.caption,
                svg,
            }),
        parameters,
        found,
        singular_values_svg: &sv_svg,
        stabilization_svg: stabilization_svg.as_deref(),
        sections: &sections,
        grid_svg: Some(&grid_svg),
        overlays: &overlays,
        shapes: shapes.as_ref(),
        output_only: false,
    });
    write_output(set, folder.join("report.html"), |p| {
        Ok(write_atomic(p, html.as_bytes())?)
    })?;
    Ok(())
}
