//! Writing mode shapes as dataset 55.

use super::*;
use crate::IoError;
use era::{Complex64, Quantity};
use std::io::Write;
use std::path::Path;

use super::write58::{fortran_e, header_text, write_streamed};
use era::pipeline::modes::ModalParameters;
/// Writes the mode shapes of an identified model as UFF dataset 55, one record per
/// mode: complex eigenvalue analysis (type 3), the continuous pole `s` (rad/s) as the
/// eigenvalue, modal A and B written as 0, and at each output node the complex shape
/// `Cφ` in its direction (a negative direction flips the sign). Translations only give
/// 3 values per node; any rotation gives 6.
///
/// # Errors
/// [`IoError`] naming the file; a channel table whose size differs from the shapes.
pub fn write_uff55(
    path: &Path,
    modal: &ModalParameters,
    channels: Option<&ChannelTable>,
    quantity: Quantity,
) -> Result<(), IoError> {
    write_uff55_on(path, modal, channels, quantity, None)
}

/// [`write_uff55`], with the geometry's datasets 18, 15 and 82 ahead of the shapes
/// when one is given ([`super::write_geometry_records`]), so that a viewer opens the
/// shapes on their structure from the one file.
///
/// # Errors
/// As [`write_uff55`].
pub fn write_uff55_on(
    path: &Path,
    modal: &ModalParameters,
    channels: Option<&ChannelTable>,
    quantity: Quantity,
    geometry: Option<&crate::geometry::Geometry>,
) -> Result<(), IoError> {
    let q = modal.modes.first().map_or(0, |m| m.shape.len());
    let numbered = ChannelTable::numbered(q, 0);
    let outputs = channels.map_or(&numbered.outputs, |t| &t.outputs);
    if modal.modes.iter().any(|m| m.shape.len() != outputs.len()) {
        return Err(IoError::format(
            path,
            "",
            format!(
                "the channel table has {} outputs, the mode shapes {q}",
                outputs.len()
            ),
        ));
    }
    let rotations = outputs.iter().any(|c| c.dof.direction.abs() > 3);
    let per_node = if rotations { 6 } else { 3 };
    // Nodes in order of first appearance; each output lands in one slot.
    let mut nodes: Vec<i64> = Vec::new();
    let mut slots = Vec::with_capacity(outputs.len());
    for c in outputs {
        let n = match nodes.iter().position(|&x| x == c.dof.node) {
            Some(n) => n,
            None => {
                nodes.push(c.dof.node);
                nodes.len() - 1
            }
        };
        let d = c.dof.direction;
        let component = if d == 0 {
            2
        } else {
            (d.unsigned_abs() - 1) as usize
        };
        let sign = if d < 0 { -1.0 } else { 1.0 };
        slots.push((n, component.min(per_node - 1), sign));
    }
    write_streamed(path, |w| {
        if let Some(g) = geometry {
            super::write_geometry_records(w, g)?;
        }
        for (number, mode) in modal.modes.iter().enumerate() {
            writeln!(w, "{:>6}", -1)?;
            writeln!(w, "{:>6}{:74}", 55, "")?;
            let title = format!(
                "era: mode {} at {:.6} Hz, damping ratio {:.6}",
                number + 1,
                mode.frequency_hz,
                mode.damping_ratio
            );
            for id in [title.as_str(), "NONE", "NONE", "NONE", "NONE"] {
                writeln!(w, "{}", header_text(id, 80).trim_end())?;
            }
            writeln!(
                w,
                "{:>10}{:>10}{:>10}{:>10}{:>10}{:>10}",
                1,
                3,
                if rotations { 3 } else { 2 },
                quantity_code(quantity),
                5,
                per_node
            )?;
            writeln!(w, "{:>10}{:>10}{:>10}{:>10}", 2, 6, 0, number + 1)?;
            let s = mode.continuous_pole;
            let mut r8 = String::new();
            for x in [s.re, s.im, 0.0, 0.0, 0.0, 0.0] {
                r8.push_str(&fortran_e(x, 13, 5));
            }
            writeln!(w, "{r8}")?;
            let mut values = vec![Complex64::new(0.0, 0.0); nodes.len() * per_node];
            for (k, &(n, component, sign)) in slots.iter().enumerate() {
                values[n * per_node + component] = mode.shape[k] * sign;
            }
            for (n, node) in nodes.iter().enumerate() {
                writeln!(w, "{node:>10}")?;
                let mut line = String::new();
                for (k, v) in values[n * per_node..(n + 1) * per_node]
                    .iter()
                    .flat_map(|v| [v.re, v.im])
                    .enumerate()
                {
                    line.push_str(&fortran_e(v, 13, 5));
                    if (k + 1) % 6 == 0 {
                        line.push('\n');
                    }
                }
                w.write_all(line.as_bytes())?;
            }
            writeln!(w, "{:>6}", -1)?;
        }
        Ok(())
    })
}
