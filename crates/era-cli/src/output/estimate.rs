//! The FRFs estimated from time histories and their coherence, written together
//! (`era frf`, `era identify --from-time --save-frf`).

use super::{coherence_path, output_name, write_output};
use era::estimate::FrfEstimate;
use era_io::atomic::OutputSet;
use era_io::csv::FrfFile;
use era_io::format::FrfFormat;
use era_io::uff::UffWriteOptions;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A coherence file's text: the `# coherence of SOURCE` and `# NOTE` lines, then
/// `frequency_hz`, `coh{i}_{j}` (`ordinary(i, j, line)`) for every pair and, when
/// `multiple` is given, `mcoh{i}` (`multiple(i, line)`) for every output. `era frf`'s
/// estimate and `era simulate experiment` write it.
pub fn coherence_csv(
    source: &str,
    note: &str,
    frequency_hz: &[f64],
    (q, p): (usize, usize),
    ordinary: impl Fn(usize, usize, usize) -> f64,
    multiple: Option<&dyn Fn(usize, usize) -> f64>,
) -> String {
    let lines = frequency_hz.len();
    let mut out = String::with_capacity(lines * (q * p + q + 1) * 24);
    let _ = writeln!(out, "# coherence of {source}");
    let _ = writeln!(out, "# {note}");
    out.push_str("frequency_hz");
    for i in 1..=q {
        for j in 1..=p {
            let _ = write!(out, ",coh{i}_{j}");
        }
    }
    if multiple.is_some() {
        for i in 1..=q {
            let _ = write!(out, ",mcoh{i}");
        }
    }
    out.push('\n');
    for (k, f) in frequency_hz.iter().enumerate() {
        let _ = write!(out, "{f}");
        for i in 0..q {
            for j in 0..p {
                let _ = write!(out, ",{}", ordinary(i, j, k));
            }
        }
        if let Some(multiple) = multiple {
            for i in 0..q {
                let _ = write!(out, ",{}", multiple(i, k));
            }
        }
        out.push('\n');
    }
    out
}

/// The estimate's coherence as CSV ([`coherence_csv`]): ordinary and multiple.
pub fn write_coherence(path: &Path, est: &FrfEstimate, source: &str) -> anyhow::Result<()> {
    let shape = (est.frf.outputs(), est.frf.inputs());
    let text = coherence_csv(
        source,
        "coh<i>_<j>: ordinary coherence of output i with input j; mcoh<i>: multiple coherence of output i",
        est.frf.frequency_hz(),
        shape,
        |i, j, k| est.coherence(i, j)[k],
        Some(&|i, k| est.multiple(i)[k]),
    );
    era_io::atomic::write_atomic(path, text.as_bytes())?;
    Ok(())
}

/// Checks `--out` (its format, and that it and its coherence file beside it can be
/// written) and opens the [`OutputSet`] that [`write_estimate`] fills, before the work.
pub fn prepare_estimate(out: &Path, binary: bool) -> anyhow::Result<OutputSet> {
    let format = FrfFormat::from_extension(out).ok_or_else(|| {
        crate::error::UsageError(format!(
            "--out {}: cannot tell the format from the extension: use .csv, .uff (or .unv) or .mat",
            out.display()
        ))
    })?;
    if binary && format != FrfFormat::Uff {
        return crate::error::usage(format!(
            "--binary applies to UFF output, not to {}",
            out.display()
        ));
    }
    let mut set = OutputSet::beside(out)?;
    set.stage(output_name("--out", out)?)?;
    set.stage(output_name("--out", &coherence_path(out))?)?;
    Ok(set)
}

/// Writes the FRFs (the estimation settings kept as CSV metadata) and the coherence
/// into `set` (from [`prepare_estimate`]) and puts both in place together: when either
/// cannot be written, neither changes.
pub fn write_estimate(
    mut set: OutputSet,
    out: &Path,
    file: &FrfFile,
    estimate: &FrfEstimate,
    binary: bool,
) -> anyhow::Result<PathBuf> {
    let format = FrfFormat::from_extension(out)
        .ok_or_else(|| crate::error::UsageError(format!("--out {}: no format", out.display())))?;
    write_output(&mut set, output_name("--out", out)?, |staged| {
        match format {
            // The estimation settings stay with the FRFs as `# key: value` lines.
            FrfFormat::Csv => era_io::format::write_frf_csv_keeping(staged, file, |_| true)?,
            _ => era_io::format::write_frf_file(
                staged,
                file,
                UffWriteOptions {
                    binary,
                    single: false,
                },
            )?,
        }
        Ok(())
    })?;
    let coherence = coherence_path(out);
    write_output(&mut set, output_name("--out", &coherence)?, |staged| {
        write_coherence(staged, estimate, &out.display().to_string())
    })?;
    set.commit()?;
    Ok(coherence)
}
