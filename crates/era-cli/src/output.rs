//! Writing a run's outputs: the `--out` folder as one [`OutputSet`] (every file staged
//! and committed together, `era_io::atomic`), and the one bundle writer of an
//! identification (model, fit, MAT, UFF, figures, report) that `identify`, `demo` and
//! `refine` share.

use anyhow::Context;
use era_io::atomic::OutputSet;
use era_io::model_json::{FitJson, ModelJson};
use std::path::Path;

/// Creates `--out DIR` and opens the run's [`OutputSet`] there (a private staging
/// folder), before any long work: a folder that cannot take files is refused now.
pub fn prepare_out_dir(dir: &Path) -> anyhow::Result<OutputSet> {
    std::fs::create_dir_all(dir).map_err(|e| {
        crate::UsageError(format!(
            "--out {}: cannot create the folder: {e}",
            dir.display()
        ))
    })?;
    OutputSet::new(dir).map_err(|e| {
        crate::UsageError(format!("--out {}: cannot write there: {e}", dir.display())).into()
    })
}

/// Stages the output `name` of `set` and runs `write` on its staged path; an error
/// names the output's final place.
pub fn write_output(
    set: &mut OutputSet,
    name: impl AsRef<Path>,
    write: impl FnOnce(&Path) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let name = name.as_ref();
    let staged = set.stage(name)?;
    write(&staged).with_context(|| format!("writing {}", set.target(name).display()))
}

/// The file name of an output file given on the command line, for [`OutputSet::stage`].
pub fn output_name<'a>(flag: &str, path: &'a Path) -> anyhow::Result<&'a std::ffi::OsStr> {
    path.file_name().ok_or_else(|| {
        crate::UsageError(format!("{flag} {}: not a file name", path.display())).into()
    })
}

/// Every output of one identification into the folder `sub` of `set` (`""` for its
/// top): model.json, fit.json, model.mat,
/// model_frf.uff (the model's FRFs on the measurement's lines, after the same
/// integrations), modes.uff, the figures and report.html. All of them show
/// `found.model`, refined or not, and use the compared data kept in `found`.
#[allow(clippy::too_many_arguments)]
pub fn write_identification(
    set: &mut OutputSet,
    sub: &Path,
    found: &era::Identification,
    model: &ModelJson,
    fit: &FitJson,
    channels: Option<&era_io::uff::ChannelTable>,
    title: &str,
    echo: &str,
    states: usize,
    common: &crate::args::CommonArgs,
) -> anyhow::Result<()> {
    write_output(set, sub.join("model.json"), |p| Ok(model.write(p)?))?;
    write_output(set, sub.join("fit.json"), |p| Ok(fit.write(p)?))?;
    write_output(set, sub.join("model.mat"), |p| {
        Ok(era_io::mat::write_model_mat(p, &found.model, &found.modal)?)
    })?;
    let synthesised = found.model_frf()?;
    write_output(set, sub.join("model_frf.uff"), |p| {
        Ok(era_io::uff::write_uff58(
            p,
            &synthesised,
            channels,
            (None, None),
            era_io::uff::UffWriteOptions {
                binary: true,
                single: false,
            },
        )?)
    })?;
    write_output(set, sub.join("modes.uff"), |p| {
        Ok(era_io::uff::write_uff55(
            p,
            &found.modal,
            channels,
            // The shapes are of the integrated quantity, as the model is.
            found.processed.quantity(),
        )?)
    })?;
    let q = found.measured.outputs() * found.measured.inputs();
    let bar = crate::progress::bar(common, q as u64, "figures");
    crate::figures::write_all(set, sub, title, echo, found, states, &bar)?;
    bar.finish_and_clear();
    Ok(())
}

/// Per-pair relative fit error as an outputs × inputs grid (up to 64 pairs).
pub fn pair_fit_table(fit: &era::response::FitReport, q: usize, p: usize) -> String {
    use std::fmt::Write as _;
    if q * p > 64 {
        return format!("  per-pair fit: {} pairs, see fit.json (--out)\n", q * p);
    }
    let mut s = String::from(
        "relative fit error per pair (rows: outputs, columns: inputs; * collocated)\n",
    );
    let _ = write!(s, "{:>8}", "");
    for j in 1..=p {
        let _ = write!(s, " {:>10}", format!("in {j}"));
    }
    s.push('\n');
    for i in 0..q {
        let _ = write!(s, "{:>8}", format!("out {}", i + 1));
        for j in 0..p {
            match fit.pairs.iter().find(|f| f.output == i && f.input == j) {
                Some(f) => {
                    let mark = if f.collocated { "*" } else { " " };
                    let _ = write!(s, " {:>9.3e}{mark}", f.relative_error);
                }
                None => {
                    let _ = write!(s, " {:>10}", "-");
                }
            }
        }
        s.push('\n');
    }
    s
}
