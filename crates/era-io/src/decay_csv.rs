//! Free-decay records: `time_s` plus `velocity` and/or `displacement`, with optional
//! `# key: value` lines first (units and provenance, e.g. `# velocity_unit: in/s`).
//!
//! ```text
//! # velocity_unit: in/s
//! # displacement_unit: in
//! time_s,velocity,displacement
//! 0,0.0012,1.5003
//! ```
//!
//! Other columns are ignored. Errors name the file, the line and the column: a missing
//! column, a non-numeric cell, NaN or infinity, and time that does not increase.

use crate::atomic::write_atomic;
use crate::text::metadata_line;
use crate::IoError;
use era::friction::estimate::DecayEstimate;
use era::friction::simulate::DecayRecord;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// A record read from a file.
#[derive(Debug, Clone, PartialEq)]
pub struct DecayFile {
    /// Sample times, s.
    pub time_s: Vec<f64>,
    /// The velocity column, if present.
    pub velocity: Option<Vec<f64>>,
    /// The displacement column, if present.
    pub displacement: Option<Vec<f64>>,
    /// `# key: value` lines, keys lower-case.
    pub metadata: BTreeMap<String, String>,
}

/// One record's friction estimate as `era friction estimate --json` prints it (its
/// `records` entries, less `file`), and as Python's `era.friction.estimate` returns it.
pub fn estimate_json(
    e: &DecayEstimate,
    signal: &str,
) -> serde_json::Map<String, serde_json::Value> {
    use serde_json::json;
    let fields = [
        ("signal", json!(signal)),
        ("natural_frequency_hz", json!(e.natural_frequency_hz)),
        (
            "natural_frequency_hz_from_peaks",
            json!(e.natural_frequency_hz_from_peaks),
        ),
        ("cycles", json!(e.cycles)),
        ("velocity_drop_per_cycle", json!(e.velocity_drop_per_cycle)),
        ("coulomb_force", json!(e.coulomb_force)),
        ("viscous_damping_ratio", json!(e.viscous_damping_ratio)),
        ("better_model", json!(e.better_model.name())),
        ("coulomb_residual", json!(e.coulomb_residual)),
        ("viscous_residual", json!(e.viscous_residual)),
        ("combined_coulomb_force", json!(e.combined.coulomb_force)),
        (
            "combined_viscous_damping_ratio",
            json!(e.combined.viscous_damping_ratio),
        ),
        ("combined_residual", json!(e.combined.residual)),
        ("half_cycles_fitted", json!(e.half_cycles.len())),
        (
            "fit_start_s",
            json!(e.half_cycles.first().map(|h| h.start_s)),
        ),
        ("fit_end_s", json!(e.half_cycles.last().map(|h| h.end_s))),
        ("noise_rms", json!(e.noise_rms)),
    ];
    fields
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
}

/// Reads a free-decay CSV.
///
/// # Errors
/// [`IoError`] naming the file, line and column.
pub fn read_decay_csv(path: &Path) -> Result<DecayFile, IoError> {
    let bytes = crate::input::read_input(path)?;
    let text = crate::input::utf8(&bytes, path)?;
    parse_decay_csv(text, path)
}

/// [`read_decay_csv`] on text already read; `path` names it in messages.
///
/// # Errors
/// As [`read_decay_csv`].
pub fn parse_decay_csv(text: &str, path: &Path) -> Result<DecayFile, IoError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let fail =
        |line: usize, column: &str, message: String| IoError::at(path, line, column, message);
    let mut metadata = BTreeMap::new();
    let mut header: Option<(usize, Vec<String>)> = None;
    let (mut time_s, mut velocity, mut displacement) = (Vec::new(), Vec::new(), Vec::new());
    let (mut col_t, mut col_v, mut col_x) = (None, None, None);
    for (index, raw) in text.lines().enumerate() {
        let line = index + 1;
        let trimmed = raw.trim();
        if trimmed.is_empty() {
            continue;
        }
        if trimmed.starts_with('#') {
            if let Some((key, value)) = metadata_line(trimmed) {
                metadata.insert(key, value);
            }
            continue;
        }
        let cells: Vec<&str> = trimmed.split(',').map(str::trim).collect();
        let Some((_, names)) = &header else {
            let names: Vec<String> = cells.iter().map(|c| c.to_ascii_lowercase()).collect();
            let find = |name: &str| names.iter().position(|n| n == name);
            col_t = find("time_s");
            col_v = find("velocity");
            col_x = find("displacement");
            if col_t.is_none() {
                return Err(fail(
                    line,
                    "time_s",
                    "missing column (the header needs time_s and velocity or displacement)".into(),
                ));
            }
            if col_v.is_none() && col_x.is_none() {
                return Err(fail(
                    line,
                    "velocity",
                    "missing column: the header needs velocity or displacement".into(),
                ));
            }
            header = Some((line, names));
            continue;
        };
        if cells.len() != names.len() {
            return Err(fail(
                line,
                "",
                format!("{} cells, the header has {}", cells.len(), names.len()),
            ));
        }
        let number = |col: usize| -> Result<f64, IoError> {
            let cell = cells[col];
            let v: f64 = cell
                .parse()
                .map_err(|_| fail(line, &names[col], format!("'{cell}' is not a number")))?;
            if !v.is_finite() {
                return Err(fail(
                    line,
                    &names[col],
                    format!("{cell} is not a finite number"),
                ));
            }
            Ok(v)
        };
        let t = number(col_t.unwrap())?;
        if let Some(&prev) = time_s.last() {
            if t <= prev {
                return Err(fail(
                    line,
                    "time_s",
                    format!("time does not increase ({prev} s, then {t} s)"),
                ));
            }
        }
        time_s.push(t);
        if let Some(c) = col_v {
            velocity.push(number(c)?);
        }
        if let Some(c) = col_x {
            displacement.push(number(c)?);
        }
    }
    if header.is_none() {
        return Err(IoError::format(
            path,
            "",
            "no header line (expected time_s,velocity[,displacement])",
        ));
    }
    if time_s.is_empty() {
        return Err(IoError::format(path, "", "no data rows"));
    }
    Ok(DecayFile {
        time_s,
        velocity: col_v.map(|_| velocity),
        displacement: col_x.map(|_| displacement),
        metadata,
    })
}

/// Writes a record (`time_s,velocity,displacement`) atomically, metadata lines first.
///
/// # Errors
/// [`IoError::Io`] naming the file.
pub fn write_decay_csv(
    path: &Path,
    record: &DecayRecord,
    metadata: &[(&str, String)],
) -> Result<(), IoError> {
    let mut out = String::with_capacity(record.time_s.len() * 64);
    for (k, v) in metadata {
        let _ = writeln!(out, "# {k}: {v}");
    }
    out.push_str("time_s,velocity,displacement\n");
    for ((t, v), x) in record
        .time_s
        .iter()
        .zip(&record.velocity)
        .zip(&record.displacement)
    {
        let _ = writeln!(out, "{t},{v:e},{x:e}");
    }
    write_atomic(path, out.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_errors() {
        let dir = tempfile::tempdir().unwrap();
        let rec = DecayRecord {
            time_s: vec![0.0, 0.005, 0.01],
            velocity: vec![0.1, -1.0 / 3.0, 2e-9],
            displacement: vec![1.5, 1.4, 1.3],
        };
        let p = dir.path().join("d.csv");
        write_decay_csv(&p, &rec, &[("velocity_unit", "in/s".into())]).unwrap();
        let back = read_decay_csv(&p).unwrap();
        assert_eq!(back.time_s, rec.time_s);
        assert_eq!(back.velocity.as_deref(), Some(&rec.velocity[..]));
        assert_eq!(back.metadata["velocity_unit"], "in/s");

        let cases = [
            (
                "a.csv",
                "time_s,force\n0,1\n",
                "column velocity: missing column",
            ),
            ("b.csv", "velocity\n1\n", "column time_s: missing column"),
            (
                "c.csv",
                "time_s,velocity\n0,1\n0.1,abc\n",
                "line 3, column velocity: 'abc' is not a number",
            ),
            (
                "d.csv",
                "time_s,velocity\n0,1\n0.1,nan\n",
                "line 3, column velocity: nan is not a finite number",
            ),
            (
                "e.csv",
                "time_s,velocity\n0,1\n0.2,1\n0.1,1\n",
                "line 4, column time_s: time does not increase",
            ),
        ];
        for (name, text, needle) in cases {
            let p = dir.path().join(name);
            std::fs::write(&p, text).unwrap();
            let err = read_decay_csv(&p).unwrap_err().to_string();
            assert!(err.contains(name) && err.contains(needle), "{name}: {err}");
        }
    }
}
