//! Writing FRFs as dataset 58 (ASCII) or 58b (binary).

use super::*;
use crate::IoError;
use era::FrfData;
use std::io::Write;
use std::path::Path;

use crate::atomic::write_via;
/// How [`write_uff58`] stores values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct UffWriteOptions {
    /// Binary 58b (little-endian IEEE) rather than ASCII.
    pub binary: bool,
    /// Single precision rather than double.
    pub single: bool,
}

/// Fortran-style `E` format: `width` columns, `digits` after the point, an exponent
/// of at least two digits (`-1.234567890123e+00`).
pub(super) fn fortran_e(x: f64, width: usize, digits: usize) -> String {
    let s = format!("{x:.digits$e}");
    let (mantissa, exponent) = s.split_once('e').expect("exponent form");
    let e: i32 = exponent.parse().expect("integer exponent");
    let sign = if e < 0 { '-' } else { '+' };
    format!(
        "{:>width$}",
        format!("{mantissa}e{sign}{:02}", e.unsigned_abs())
    )
}

pub(super) fn header_text(s: &str, width: usize) -> String {
    let t: String = s.chars().filter(|c| !c.is_control()).take(width).collect();
    let t = if t.trim().is_empty() {
        "NONE".into()
    } else {
        t
    };
    format!("{t:<width$}")
}

/// The ASCII part of one dataset-58 record (opening `-1` to record 11).
#[allow(clippy::too_many_arguments)]
pub(super) fn write_header58(
    w: &mut impl Write,
    opts: UffWriteOptions,
    data_bytes: usize,
    ids: [&str; 5],
    response: &Channel,
    reference: &Channel,
    points: usize,
    spacing: f64,
    axes: [(i64, i64, i64, &str); 4],
) -> std::io::Result<()> {
    writeln!(w, "{:>6}", -1)?;
    if opts.binary {
        writeln!(
            w,
            "{:>6}b{:>6}{:>6}{:>12}{:>12}{:>6}{:>6}{:>12}{:>12}",
            58, 1, 2, 11, data_bytes, 0, 0, 0, 0
        )?;
    } else {
        writeln!(w, "{:>6}{:74}", 58, "")?;
    }
    for id in ids {
        writeln!(w, "{}", header_text(id, 80).trim_end())?;
    }
    writeln!(
        w,
        "{:>5}{:>10}{:>5}{:>10} {}{:>10}{:>4} {}{:>10}{:>4}",
        FUNCTION_FRF,
        0,
        0,
        0,
        header_text(&response.entity, 10),
        response.dof.node,
        response.dof.direction,
        header_text(&reference.entity, 10),
        reference.dof.node,
        reference.dof.direction
    )?;
    let ordinate = if opts.single {
        Ordinate::ComplexSingle
    } else {
        Ordinate::ComplexDouble
    };
    writeln!(
        w,
        "{:>10}{:>10}{:>10}{}{}{}",
        ordinate.code(),
        points,
        1,
        fortran_e(0.0, 13, 6),
        fortran_e(spacing, 13, 6),
        fortran_e(0.0, 13, 5)
    )?;
    for (data_type, length, force, units) in axes {
        writeln!(
            w,
            "{:>10}{:>5}{:>5}{:>5} {} {}",
            data_type,
            length,
            force,
            0,
            header_text("NONE", 20),
            header_text(units, 20)
        )?;
    }
    Ok(())
}

/// Writes FRFs as UFF dataset 58, one record per pair (output-major), through a
/// temporary file and a rename. `channels` gives the node and direction of each output
/// and input (else [`ChannelTable::numbered`]); `units` (response, force) go in the
/// axis labels.
///
/// # Errors
/// [`IoError`] naming the file; a channel table whose size differs from the FRFs.
pub fn write_uff58(
    path: &Path,
    frf: &FrfData,
    channels: Option<&ChannelTable>,
    units: (Option<&str>, Option<&str>),
    opts: UffWriteOptions,
) -> Result<(), IoError> {
    let (q, p, lines) = (frf.outputs(), frf.inputs(), frf.lines());
    let numbered = ChannelTable::numbered(q, p);
    let table = channels.unwrap_or(&numbered);
    if table.outputs.len() != q || table.inputs.len() != p {
        return Err(IoError::format(
            path,
            "",
            format!(
                "the channel table has {} outputs and {} inputs, the FRFs {q} and {p}",
                table.outputs.len(),
                table.inputs.len()
            ),
        ));
    }
    let quantity = frf.quantity();
    let (response_unit, force_unit) = (units.0.unwrap_or("NONE"), units.1.unwrap_or("NONE"));
    write_streamed(path, |w| {
        for i in 0..q {
            for j in 0..p {
                let size = if opts.single { 4 } else { 8 };
                let title = format!("era: H{}_{} ({quantity} / force)", i + 1, j + 1);
                write_header58(
                    w,
                    opts,
                    lines * 2 * size,
                    [&title, "NONE", "NONE", "NONE", "NONE"],
                    &table.outputs[i],
                    &table.inputs[j],
                    lines,
                    frf.spacing_hz(),
                    [
                        (18, 0, 0, "Hz"),
                        (quantity_code(quantity), 1, 0, response_unit),
                        (13, 0, 1, force_unit),
                        (0, 0, 0, "NONE"),
                    ],
                )?;
                let values = frf.pair(i, j);
                if opts.binary {
                    let mut buf = Vec::with_capacity(lines * 2 * size);
                    for v in values {
                        if opts.single {
                            buf.extend_from_slice(&(v.re as f32).to_le_bytes());
                            buf.extend_from_slice(&(v.im as f32).to_le_bytes());
                        } else {
                            buf.extend_from_slice(&v.re.to_le_bytes());
                            buf.extend_from_slice(&v.im.to_le_bytes());
                        }
                    }
                    w.write_all(&buf)?;
                } else {
                    let (width, digits, per_line) =
                        if opts.single { (13, 5, 6) } else { (20, 12, 4) };
                    let mut line = String::with_capacity(80);
                    let parts = values.iter().flat_map(|v| [v.re, v.im]);
                    for (k, x) in parts.enumerate() {
                        let digits = if x != 0.0 && x.abs().log10().abs() >= 99.0 {
                            digits - 1
                        } else {
                            digits
                        };
                        line.push_str(&fortran_e(x, width, digits));
                        if (k + 1) % per_line == 0 {
                            line.push('\n');
                            w.write_all(line.as_bytes())?;
                            line.clear();
                        }
                    }
                    if !line.is_empty() {
                        line.push('\n');
                        w.write_all(line.as_bytes())?;
                    }
                }
                // In 58b the closing -1 follows the data directly.
                writeln!(w, "{:>6}", -1)?;
            }
        }
        Ok(())
    })
}

/// Runs `body` on a buffered temporary file, then flushes, syncs and renames it.
pub(super) fn write_streamed(
    path: &Path,
    body: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
) -> Result<(), IoError> {
    write_via(path, |tmp| {
        (|| {
            let file = std::fs::File::create(tmp)?;
            let mut w = std::io::BufWriter::with_capacity(1 << 20, file);
            body(&mut w)?;
            w.flush()?;
            w.get_ref().sync_all()
        })()
        .map_err(|e| IoError::io(path, e))
    })
}
