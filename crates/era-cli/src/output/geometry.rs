//! `--geometry FILE`: read and checked before a run (a bad file exits with code 2), then
//! described in the run's notes with the channels it cannot draw, written into
//! modes.uff with the shapes ([`super::identification::write_bundle`]), and drawn in
//! the report's mode-shape viewer ([`shape_view`]). And the geometry the simulators
//! write beside their FRFs ([`write_dta_like`]).

use era::data::identification::Identification;
use era_io::frf_file::ChannelTable;
use era_io::geometry::{map_channels, read_geometry, Geometry};
use era_plot::viewer::{Placement, ShapeView};
use std::path::Path;

/// The geometry of `path`, when given, its summary printed.
///
/// # Errors
/// The reader's error (it names the file and line: an input error, exit code 2).
pub fn read(
    path: Option<&Path>,
    human: &super::report::Human,
) -> anyhow::Result<Option<(String, Geometry)>> {
    let Some(path) = path else {
        return Ok(None);
    };
    let g = read_geometry(path)?;
    human.print(&format!("  geometry {}: {}\n", path.display(), g.summary()));
    Ok(Some((path.display().to_string(), g)))
}

/// The notes of a run on `geometry`: what it holds, then which output channels it
/// draws and which it does not, and why (a channel without a node is listed, never
/// guessed). Without a channel table the outputs are `era`'s numbering (nodes 1..q, +Z).
pub fn notes(
    file: &str,
    geometry: &Geometry,
    channels: Option<&ChannelTable>,
    outputs: usize,
) -> Vec<String> {
    let numbered = ChannelTable::numbered(outputs, 0);
    let table = channels.unwrap_or(&numbered);
    let map = map_channels(geometry, &table.outputs);
    let mut notes = vec![format!("geometry {file}: {}", geometry.summary())];
    notes.extend(geometry.notes.iter().map(|n| format!("geometry: {n}")));
    notes.push(format!(
        "geometry: {} of {} output channels on its nodes",
        map.placed.len(),
        table.outputs.len()
    ));
    if !map.not_drawn.is_empty() {
        let list = map.not_drawn_sentences(&table.outputs);
        notes.push(format!(
            "geometry: not drawn: {}",
            era_io::frf_file::listed(&list)
        ));
    }
    notes
}

/// The modes of `found` on the run's geometry, for the report's viewer; `None` without
/// a geometry. The outputs are placed as in [`notes`].
pub fn shape_view(run: &super::RunInput, found: &Identification) -> Option<ShapeView> {
    let geometry = run.geometry.as_ref()?;
    let (nodes, segments, placed, not_drawn) =
        layout(geometry, run.channels.as_ref(), found.measured.outputs());
    Some(ShapeView::new(nodes, segments, &placed, found, not_drawn))
}

/// What a shape view of `outputs` channels on `geometry` needs: the node positions,
/// the segments as node indices, each channel placed (as in [`notes`]: the channel
/// table, or era's numbering without one) and the channels not drawn.
#[allow(clippy::type_complexity)]
pub fn layout(
    geometry: &Geometry,
    channels: Option<&ChannelTable>,
    outputs: usize,
) -> (
    Vec<[f64; 3]>,
    Vec<(usize, usize)>,
    Vec<Placement>,
    Vec<String>,
) {
    let numbered = ChannelTable::numbered(outputs, 0);
    let table = channels.unwrap_or(&numbered);
    let map = map_channels(geometry, &table.outputs);
    let index = geometry.node_index();
    let segments = geometry
        .segments()
        .into_iter()
        .filter_map(|(a, b)| Some((*index.get(&a)?, *index.get(&b)?)))
        .collect();
    let placed: Vec<Placement> = map
        .placed
        .iter()
        .map(|p| Placement {
            channel: p.channel,
            node: p.node,
            direction: p.direction,
        })
        .collect();
    (
        geometry.nodes.iter().map(|n| n.xyz).collect(),
        segments,
        placed,
        map.not_drawn_sentences(&table.outputs),
    )
}

/// `run` with the geometry and its notes.
pub fn attach(
    mut run: super::RunInput,
    geometry: Option<(String, Geometry)>,
    outputs: usize,
) -> super::RunInput {
    if let Some((file, g)) = geometry {
        let notes = notes(&file, &g, run.channels.as_ref(), outputs);
        run.section.notes.extend(notes);
        run.geometry = Some(g);
    }
    run
}

/// `dir/STEM_geometry.csv` beside `out` (`dta.csv` → `dta_geometry.csv`).
pub fn beside(out: &std::path::Path) -> std::path::PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "frf".into());
    out.with_file_name(format!("{stem}_geometry.csv"))
}

/// The DTA-like ring truss with its tripod ([`era_io::geometry::layouts::dta_like`]),
/// the outputs on its ring, as our geometry CSV at `path`, so that `--geometry` draws
/// the simulated shapes.
pub fn write_dta_like(
    human: &super::report::Human,
    path: &std::path::Path,
    outputs: usize,
) -> anyhow::Result<()> {
    let g = era_io::geometry::layouts::dta_like(outputs);
    let text = era_io::geometry::csv::geometry_csv_text(
        &g,
        &[
            "the DTA-like structure of era simulate (thesis chapter II): a ring truss, its tripod,",
            "two solar-array masts and three mass simulators. Outputs 1..q are nodes 1..q (+Z) on the",
            "ring's upper chord. A layout to draw on, not a finite-element model: the simulated",
            "shapes are random vectors placed on it.",
        ],
    );
    era_io::atomic::write_atomic(path, text.as_bytes())?;
    human.print(&format!(
        "wrote {}: {} (give it to identify/refine/oma with --geometry)\n",
        path.display(),
        g.summary()
    ));
    Ok(())
}
