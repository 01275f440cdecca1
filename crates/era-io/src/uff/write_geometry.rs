//! Writing a geometry as UFF: dataset 18 (its coordinate systems, by origin, +x point
//! and +xz point in the global frame), 15 (the nodes, global, with their displacement
//! systems) and 82 (the trace lines, at most 250 node entries each, as the definition
//! allows: longer ones are split into several trace lines).

use super::write58::{fortran_e, header_text};
use crate::geometry::Geometry;
use std::io::Write;

/// Node entries of one dataset-82 record.
const TRACE_ENTRIES: usize = 250;

/// The `0, n1, n2, …` entry lists of the dataset-82 records of `g`: every stroke
/// starts with a 0 (a move), strokes too long for one record are cut into pieces that
/// share their end node, and pieces are packed in order up to 250 entries.
fn trace_records(g: &Geometry) -> Vec<(String, Vec<i64>)> {
    let mut out: Vec<(String, Vec<i64>)> = Vec::new();
    for t in &g.trace_lines {
        let name = if t.name.trim().is_empty() {
            format!("era trace line {}", t.id)
        } else {
            t.name.clone()
        };
        let mut current: Vec<i64> = Vec::new();
        for stroke in t.strokes.iter().filter(|s| s.len() >= 2) {
            let mut start = 0;
            while start + 1 < stroke.len() {
                let end = (start + TRACE_ENTRIES - 1).min(stroke.len());
                let piece = &stroke[start..end];
                if current.len() + piece.len() + 1 > TRACE_ENTRIES {
                    out.push((name.clone(), std::mem::take(&mut current)));
                }
                current.push(0);
                current.extend_from_slice(piece);
                start = end - 1;
            }
        }
        if !current.is_empty() {
            out.push((name, current));
        }
    }
    out
}

/// Writes datasets 18 (when there are coordinate systems), 15 and 82 (when there are
/// trace lines) for `g`.
pub fn write_geometry_records(w: &mut impl Write, g: &Geometry) -> std::io::Result<()> {
    let e = |x: f64| fortran_e(x, 13, 5);
    if !g.coordinate_systems.is_empty() {
        writeln!(w, "{:>6}\n{:>6}{:74}", -1, 18, "")?;
        for c in &g.coordinate_systems {
            writeln!(
                w,
                "{:>10}{:>10}{:>10}{:>10}{:>10}",
                c.id,
                c.kind.code(),
                0,
                0,
                1
            )?;
            writeln!(w, "{}", header_text(&c.name, 40).trim_end())?;
            let at = |axis: usize| -> [f64; 3] { [0, 1, 2].map(|i| c.origin[i] + c.axes[axis][i]) };
            let mut line: String = c.origin.iter().chain(&at(0)).map(|v| e(*v)).collect();
            writeln!(w, "{line}")?;
            line = at(2).iter().map(|v| e(*v)).collect();
            writeln!(w, "{line}")?;
        }
        writeln!(w, "{:>6}", -1)?;
    }
    writeln!(w, "{:>6}\n{:>6}{:74}", -1, 15, "")?;
    for n in &g.nodes {
        writeln!(
            w,
            "{:>10}{:>10}{:>10}{:>10}{}{}{}",
            n.id,
            0,
            n.displacement_system,
            0,
            e(n.xyz[0]),
            e(n.xyz[1]),
            e(n.xyz[2])
        )?;
    }
    writeln!(w, "{:>6}", -1)?;
    for (k, (name, entries)) in trace_records(g).iter().enumerate() {
        writeln!(w, "{:>6}\n{:>6}{:74}", -1, 82, "")?;
        writeln!(w, "{:>10}{:>10}{:>10}", k + 1, entries.len(), 0)?;
        writeln!(w, "{}", header_text(name, 80).trim_end())?;
        for chunk in entries.chunks(8) {
            let line: String = chunk.iter().map(|v| format!("{v:>10}")).collect();
            writeln!(w, "{line}")?;
        }
        writeln!(w, "{:>6}", -1)?;
    }
    Ok(())
}
