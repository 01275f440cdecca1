//! What an FRF file holds, for `era info`: per format, the lines to print and the
//! summary JSON (a UFF file's datasets, a MAT file's variables, a CSV file's FRFs).

use crate::config::Info;
use crate::input::{describe_input, read_frf_bytes, shape_line, FrfFlags};
use era_io::format::FrfFormat;
use era_io::uff::{function_type_name, listed, quantity_of, FrfLayout};
use serde_json::json;
use std::collections::BTreeMap;

/// The lines and the summary of the file `bytes` (read from `a.file`) in `format`.
pub fn describe(
    a: &Info,
    bytes: &[u8],
    format: FrfFormat,
) -> anyhow::Result<(String, serde_json::Value)> {
    match format {
        FrfFormat::Uff => uff_info(a, bytes),
        FrfFormat::Mat => mat_info(a, bytes),
        FrfFormat::Csv => csv_info(a, bytes),
    }
}

fn uff_info(a: &Info, bytes: &[u8]) -> anyhow::Result<(String, serde_json::Value)> {
    let contents = era_io::uff::parse_uff(bytes, &a.file, false)?;
    let mut text = format!("{}: UFF\n", a.file.display());
    let mut by_type: BTreeMap<String, usize> = BTreeMap::new();
    for (f, _) in &contents.functions {
        let name = function_type_name(f.function_type).map_or_else(
            || format!("unknown type {}", f.function_type),
            str::to_string,
        );
        *by_type.entry(name).or_insert(0) += 1;
    }
    let binary = contents
        .functions
        .iter()
        .filter(|(f, _)| f.binary.is_some())
        .count();
    text.push_str(&format!(
        "  dataset 58: {} records ({} binary 58b, {} ASCII): {}\n",
        contents.functions.len(),
        binary,
        contents.functions.len() - binary,
        by_type
            .iter()
            .map(|(k, n)| format!("{n} {k}"))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    for (d, n) in &contents.skipped {
        let records = if *n == 1 { "record" } else { "records" };
        text.push_str(&format!("  dataset {d}: {n} {records} (skipped)\n"));
    }
    let frfs: Vec<_> = contents
        .functions
        .iter()
        .map(|(f, _)| f)
        .filter(|f| f.function_type == era_io::uff::FUNCTION_FRF)
        .collect();
    let layout = FrfLayout::of(frfs.iter().copied());
    let mut summary = json!({
        "file": a.file, "format": "UFF",
        "records_58": contents.functions.len(), "binary_58b": binary,
        "function_types": by_type, "skipped_datasets": contents.skipped,
        "notes": contents.notes,
    });
    if let Some(first) = frfs.first() {
        let (q, p) = (layout.table.outputs.len(), layout.table.inputs.len());
        let same_axis = frfs.iter().all(|f| {
            f.points == first.points
                && f.even == first.even
                && f.abscissa_min == first.abscissa_min
                && f.abscissa_inc == first.abscissa_inc
        });
        let ordinates: Vec<&str> = {
            let mut v: Vec<&str> = frfs.iter().map(|f| f.ordinate.name()).collect();
            v.sort_unstable();
            v.dedup();
            v
        };
        let quantity = quantity_of(first.axes[1].data_type).map(|q| q.name());
        let unit = |u: &str| {
            if u.is_empty() {
                "NONE".to_string()
            } else {
                u.to_string()
            }
        };
        text.push_str(&format!(
            "  FRF matrix: {q} outputs x {p} inputs ({} records)\n",
            frfs.len()
        ));
        if first.even {
            let last = first.abscissa_min + (first.points - 1) as f64 * first.abscissa_inc;
            text.push_str(&format!(
                "  lines: {} from {} to {last} Hz, spacing {} Hz{}\n",
                first.points,
                first.abscissa_min,
                first.abscissa_inc,
                if same_axis {
                    ""
                } else {
                    " (other records differ)"
                }
            ));
        } else {
            text.push_str(&format!(
                "  lines: {} at uneven abscissa (ERA needs uniform lines){}\n",
                first.points,
                if same_axis {
                    ""
                } else {
                    " (other records differ)"
                }
            ));
        }
        text.push_str(&format!(
            "  values: {}\n  quantity: {} per {}\n  units: {} / {}\n",
            ordinates.join(", "),
            quantity.unwrap_or("not stated"),
            if first.axes[2].data_type == 13 {
                "force"
            } else {
                "reference"
            },
            unit(&first.axes[1].units),
            unit(&first.axes[2].units)
        ));
        text.push_str("  channels:\n");
        for line in layout.table.describe() {
            text.push_str(&format!("    {line}\n"));
        }
        if !layout.missing.is_empty() {
            text.push_str(&format!(
                "  missing pairs ({}): {}\n",
                layout.missing.len(),
                listed(&layout.missing)
            ));
        }
        if !layout.duplicates.is_empty() {
            text.push_str(&format!(
                "  duplicate pairs: {}\n",
                listed(&layout.duplicates)
            ));
        }
        summary["outputs"] = json!(q);
        summary["inputs"] = json!(p);
        summary["lines"] = json!(first.points);
        summary["even"] = json!(first.even);
        summary["first_hz"] = json!(first.abscissa_min);
        summary["spacing_hz"] = json!(first.abscissa_inc);
        summary["quantity"] = json!(quantity);
        summary["response_unit"] = json!(first.axes[1].units);
        summary["force_unit"] = json!(first.axes[2].units);
        summary["channels"] = json!(layout.table.describe());
        summary["missing_pairs"] = json!(layout.missing);
        summary["duplicate_pairs"] = json!(layout.duplicates);
    } else {
        text.push_str("  no FRF records (function type 4)\n");
    }
    for n in &contents.notes {
        text.push_str(&format!("  note: {n}\n"));
    }
    Ok((text, summary))
}

fn mat_info(a: &Info, bytes: &[u8]) -> anyhow::Result<(String, serde_json::Value)> {
    let vars = era_io::mat::list_variables_in(bytes, &a.file)?;
    let mut text = format!("{}: MAT v5\n  variables:\n", a.file.display());
    for (name, what) in &vars {
        text.push_str(&format!("    {name}: {what}\n"));
    }
    let mut summary = json!({"file": a.file, "format": "MAT",
        "variables": vars.iter().map(|(n, w)| json!({"name": n, "what": w})).collect::<Vec<_>>()});
    match read_frf_bytes(bytes, &a.file, &info_flags(a)) {
        Ok(input) => {
            let frf = &input.file.frf;
            text.push_str(&format!(
                "  FRFs: {} outputs x {} inputs, {} lines at {} Hz, {}{}\n",
                frf.outputs(),
                frf.inputs(),
                frf.lines(),
                frf.spacing_hz(),
                frf.quantity(),
                input.note
            ));
            text.push_str(&describe_input(&input));
            summary["quantity"] = json!(frf.quantity().name());
            summary["metadata"] = json!(input.file.metadata);
            if let Some(t) = &input.file.channels {
                summary["channels"] = json!(t.describe());
            }
            summary["outputs"] = json!(frf.outputs());
            summary["inputs"] = json!(frf.inputs());
            summary["lines"] = json!(frf.lines());
            summary["spacing_hz"] = json!(frf.spacing_hz());
        }
        Err(e) => text.push_str(&format!("  not an FRF layout: {}\n", root(&e))),
    }
    Ok((text, summary))
}

fn root(e: &anyhow::Error) -> String {
    e.root_cause().to_string()
}

fn info_flags(a: &Info) -> FrfFlags<'_> {
    FrfFlags {
        frequency_variable: a.freq_variable.as_deref(),
        ..FrfFlags::default()
    }
}

fn csv_info(a: &Info, bytes: &[u8]) -> anyhow::Result<(String, serde_json::Value)> {
    let input = read_frf_bytes(bytes, &a.file, &info_flags(a))?;
    let frf = &input.file.frf;
    let meta = &input.file.metadata;
    let mut text = format!(
        "{}: CSV\n  {}{}\n",
        a.file.display(),
        shape_line(frf),
        input.note,
    );
    text.push_str(&describe_input(&input));
    Ok((
        text,
        json!({"file": a.file, "format": "CSV", "outputs": frf.outputs(), "inputs": frf.inputs(),
               "lines": frf.lines(), "spacing_hz": frf.spacing_hz(), "quantity": frf.quantity().name(),
               "metadata": meta}),
    ))
}
