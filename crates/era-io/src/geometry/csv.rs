//! Our geometry CSV: two sections, each opened by its header line.
//!
//! ```text
//! # era geometry: a square plate on four legs
//! node,x,y,z
//! 1,0,0,0
//! 2,1.2,0,0
//! 3,1.2,0.8,0
//! from,to
//! 1,2
//! 2,3
//! ```
//!
//! - `node,x,y,z` opens the nodes: an integer id and three global coordinates a row;
//! - `from,to` opens the lines: two node ids a row, one segment each;
//! - either section may come first, each at most once; the lines may be left out;
//! - blank lines and lines starting with `#` are skipped anywhere; cells are trimmed,
//!   headers read without regard to case.
//!
//! Directions are global: a channel at node 3 in +Y is measured along global y.

use super::{Geometry, Node, Origins, TraceLine};
use crate::IoError;
use std::path::Path;

#[derive(Clone, Copy, PartialEq)]
enum Section {
    None,
    Nodes,
    Lines,
}

fn header(cells: &[&str]) -> Option<Section> {
    let lower: Vec<String> = cells.iter().map(|c| c.to_ascii_lowercase()).collect();
    let names: Vec<&str> = lower.iter().map(String::as_str).collect();
    match names.as_slice() {
        ["node", "x", "y", "z"] => Some(Section::Nodes),
        ["from", "to"] => Some(Section::Lines),
        _ => None,
    }
}

/// Parses a geometry CSV (see the module doc); `path` names it in messages.
///
/// # Errors
/// [`IoError`] naming the file and line: an unknown header, a row before any header,
/// a cell that is not a number, a row of the wrong length, a section given twice, and
/// what [`Geometry::validate`] refuses.
pub fn parse_geometry_csv(bytes: &[u8], path: &Path) -> Result<Geometry, IoError> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| IoError::format(path, "", format!("not UTF-8 text ({e})")))?;
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut g = Geometry::default();
    let mut origins = Origins::default();
    let mut lines = TraceLine {
        id: 1,
        name: String::new(),
        strokes: Vec::new(),
    };
    let mut section = Section::None;
    let mut seen = (false, false);
    for (k, raw) in text.lines().enumerate() {
        let number = k + 1;
        let trimmed = raw.trim();
        if trimmed.is_empty() || trimmed.starts_with('#') {
            continue;
        }
        let cells: Vec<&str> = trimmed.split(',').map(str::trim).collect();
        if let Some(s) = header(&cells) {
            let twice = match s {
                Section::Nodes => std::mem::replace(&mut seen.0, true),
                _ => std::mem::replace(&mut seen.1, true),
            };
            if twice {
                return Err(IoError::at(
                    path,
                    number,
                    "",
                    format!("a second '{trimmed}' section; each section comes once"),
                ));
            }
            section = s;
            continue;
        }
        let bad = |column: &str, message: String| IoError::at(path, number, column, message);
        match section {
            Section::None => {
                return Err(bad(
                    "",
                    format!(
                        "expected the header 'node,x,y,z' (or 'from,to'), found '{}'",
                        super::shortened(trimmed)
                    ),
                ))
            }
            Section::Nodes => {
                if cells.len() != 4 {
                    return Err(bad(
                        "",
                        format!(
                            "a node row has 4 cells (node,x,y,z), this one {}",
                            cells.len()
                        ),
                    ));
                }
                let id = int_cell(cells[0]).ok_or_else(|| {
                    bad("node", format!("'{}' is not an integer node id", cells[0]))
                })?;
                let mut xyz = [0.0; 3];
                for (c, name) in ["x", "y", "z"].into_iter().enumerate() {
                    xyz[c] = cells[c + 1]
                        .parse::<f64>()
                        .map_err(|_| bad(name, format!("'{}' is not a number", cells[c + 1])))?;
                }
                g.nodes.push(Node {
                    id,
                    xyz,
                    displacement_system: 0,
                });
                origins.nodes.push(number);
            }
            Section::Lines => {
                if cells.len() != 2 {
                    return Err(bad(
                        "",
                        format!("a line row has 2 cells (from,to), this one {}", cells.len()),
                    ));
                }
                let mut pair = [0; 2];
                for (c, name) in ["from", "to"].into_iter().enumerate() {
                    pair[c] = int_cell(cells[c]).ok_or_else(|| {
                        bad(name, format!("'{}' is not an integer node id", cells[c]))
                    })?;
                }
                if pair[0] == pair[1] {
                    return Err(bad("", format!("a line from node {} to itself", pair[0])));
                }
                // Every segment is checked against the nodes with its own line number.
                origins.trace_lines.push(number);
                g.trace_lines.push(TraceLine {
                    id: lines.strokes.len() as i64 + 1,
                    name: String::new(),
                    strokes: vec![pair.to_vec()],
                });
            }
        }
    }
    if !seen.0 {
        return Err(IoError::format(
            path,
            "",
            "no 'node,x,y,z' section: a geometry CSV lists its nodes under that header",
        ));
    }
    g.check(&origins)
        .map_err(|m| IoError::format(path, "", m))?;
    // One trace line holds every segment, as dataset 82 would.
    if !g.trace_lines.is_empty() {
        lines.strokes = g.trace_lines.drain(..).flat_map(|t| t.strokes).collect();
        g.trace_lines.push(lines);
    }
    Ok(g)
}

fn int_cell(cell: &str) -> Option<i64> {
    cell.parse::<i64>().ok()
}

/// Writes a geometry as our CSV: the nodes (global), then every segment as a node pair.
/// Displacement coordinate systems are not kept (the CSV's directions are global).
///
/// # Errors
/// [`IoError`] naming the file.
pub fn write_geometry_csv(path: &Path, g: &Geometry) -> Result<(), IoError> {
    crate::atomic::write_atomic(path, geometry_csv_text(g, &[]).as_bytes())
}

/// The geometry CSV text of `g`: `# era geometry: SUMMARY`, then each line of
/// `comments` as a `#` line, the nodes and the segments.
pub fn geometry_csv_text(g: &Geometry, comments: &[&str]) -> String {
    use std::fmt::Write;
    let mut w = String::new();
    // Writing to a String cannot fail.
    let _ = writeln!(w, "# era geometry: {}", g.summary());
    for c in comments {
        let _ = writeln!(w, "# {c}");
    }
    let _ = writeln!(w, "node,x,y,z");
    for n in &g.nodes {
        let _ = writeln!(w, "{},{},{},{}", n.id, n.xyz[0], n.xyz[1], n.xyz[2]);
    }
    let segments = g.segments();
    if !segments.is_empty() {
        let _ = writeln!(w, "from,to");
        for (a, b) in segments {
            let _ = writeln!(w, "{a},{b}");
        }
    }
    w
}
