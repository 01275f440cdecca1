//! `--geometry FILE`: read and checked before a run (a bad file exits with code 2), then
//! described in the run's notes with the channels it cannot draw, and written into
//! modes.uff with the shapes ([`super::identification::write_bundle`]).

use era_io::frf_file::{direction_name, ChannelTable};
use era_io::geometry::{map_channels, read_geometry, Geometry};
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
        let list: Vec<String> = map
            .not_drawn
            .iter()
            .map(|u| {
                let c = &table.outputs[u.channel];
                format!(
                    "output {} (node {} {}): {}",
                    u.channel + 1,
                    c.dof.node,
                    direction_name(c.dof.direction),
                    u.reason
                )
            })
            .collect();
        notes.push(format!(
            "geometry: not drawn: {}",
            era_io::frf_file::listed(&list)
        ));
    }
    notes
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
