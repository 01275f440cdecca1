//! The one bundle writer of an identification (model, fit, MAT, UFF, figures, report)
//! that `identify`, `demo` and `refine` share.

use super::{write_output, RunInput};
use era_io::atomic::OutputSet;
use era_io::model_json::{FitJson, ModelJson};
use std::path::Path;

/// What an identification's files show: the identification (refined or not, with
/// the compared data it keeps), its fit.json, what went into the run, the report's
/// title and parameter echo, the states of the singular-value figure, and whether to
/// draw the figures and the report.
pub struct Bundle<'a> {
    /// The identification.
    pub found: &'a era::Identification,
    /// Its fit.json.
    pub fit: &'a FitJson,
    /// What went into the run.
    pub source: &'a RunInput,
    /// The report's title.
    pub title: &'a str,
    /// The report's Parameters.
    pub echo: &'a str,
    /// The order marked in the singular-value figure.
    pub states: usize,
    /// The figures and report.html, or neither.
    pub figures: bool,
}

/// Every output of one identification into the folder `sub` of `set` (`""` for its
/// top): model.json and the rest of the [`Bundle`] ([`write_bundle`]).
pub fn write_identification(
    set: &mut OutputSet,
    sub: &Path,
    model: &ModelJson,
    bundle: &Bundle,
    settings: &crate::config::Settings,
) -> anyhow::Result<()> {
    write_model(set, sub, model)?;
    write_bundle(set, sub, bundle, settings)
}

/// model.json into the folder `sub` of `set`.
pub fn write_model(set: &mut OutputSet, sub: &Path, model: &ModelJson) -> anyhow::Result<()> {
    write_output(set, sub.join("model.json"), |p| Ok(model.write(p)?))
}

/// Every output of one identification but model.json into the folder `sub` of `set`:
/// fit.json, model.mat, model_frf.uff (the model's FRFs on the measurement's lines,
/// after the same integrations), modes.uff, and with `figures` the figures and
/// report.html. All of them show `found.model`, refined or not, and use the compared
/// data kept in `found`.
pub fn write_bundle(
    set: &mut OutputSet,
    sub: &Path,
    bundle: &Bundle,
    settings: &crate::config::Settings,
) -> anyhow::Result<()> {
    let Bundle {
        found,
        fit,
        source,
        title,
        echo,
        states,
        figures,
    } = *bundle;
    write_output(set, sub.join("fit.json"), |p| Ok(fit.write(p)?))?;
    write_output(set, sub.join("model.mat"), |p| {
        Ok(era_io::mat::write_model_mat(p, &found.model, &found.modal)?)
    })?;
    let synthesised = found.model_frf()?;
    let channels = source.channels.as_ref();
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
        Ok(era_io::uff::write_uff55_on(
            p,
            &found.modal,
            channels,
            // The shapes are of the integrated quantity, as the model is.
            found.processed.quantity(),
            source.geometry.as_ref(),
        )?)
    })?;
    if !figures {
        return Ok(());
    }
    let q = found.measured.outputs() * found.measured.inputs();
    let bar = super::progress::bar(settings, q as u64, "figures");
    super::figures::write_all(set, sub, title, echo, found, source, states, &bar)?;
    bar.finish_and_clear();
    Ok(())
}

/// What `write_identification` wrote, for the closing line.
pub fn written_list(dir: &Path, figures: bool) -> String {
    let files = format!(
        "{0}/model.json, {0}/model.mat, {0}/modes.uff, {0}/model_frf.uff, {0}/fit.json",
        dir.display()
    );
    if figures {
        format!("{files}, {}/report.html and figures", dir.display())
    } else if dir.join("report.html").exists() {
        format!(
            "{files} (no figures; {}/report.html and the figures are an earlier run's)",
            dir.display()
        )
    } else {
        format!("{files} (no figures)")
    }
}
