//! A `model.json` read back: for `era refine`, checked against the FRFs it is refined on
//! and assessed on them as an identification would have it; for `era plot`, the model
//! to overlay.

use crate::config::{Plot, Refine};
use crate::error::usage;
use anyhow::Context;
use era::data::identification::Identification;
use era::identify::{assess_model, EraOptions};
use era::pipeline::realize::SvdPath;
use era_io::model_json::ModelJson;

/// A JSON parameter of an older model.json as a count.
fn count(model: &ModelJson, key: &str) -> usize {
    model
        .parameters
        .get(key)
        .and_then(|v| v.as_u64())
        .unwrap_or(0) as usize
}

/// The model and the FRF file must be of one set: the same outputs and inputs, and
/// the FRF lines the model was identified from when model.json records them.
pub fn check_model_fits(a: &Refine, model: &ModelJson, frf: &era::FrfData) -> anyhow::Result<()> {
    if (model.outputs, model.inputs) != (frf.outputs(), frf.inputs()) {
        return crate::error::usage(format!(
            "{}: the model has {} outputs x {} inputs, {} has {} x {}",
            a.model.display(),
            model.outputs,
            model.inputs,
            a.file.display(),
            frf.outputs(),
            frf.inputs()
        ));
    }
    if let Some(lines) = &model.frf_lines {
        if let Some(why) = lines.differs_from(frf) {
            return crate::error::usage(format!(
                "{}: not the FRF lines of {}: {why}",
                a.file.display(),
                a.model.display()
            ));
        }
    }
    Ok(())
}

/// The given model assessed on `frf` as an identification would have it: its modes
/// marked physical or not as model.json says, only the physical ones kept for an
/// automatic model, collocation from the channel table.
pub fn start(
    a: &Refine,
    model: &ModelJson,
    frf: &era::FrfData,
    channels: Option<&era_io::uff::ChannelTable>,
) -> anyhow::Result<Identification> {
    let options = {
        let mut o = EraOptions::new(model.states.max(1), 1);
        o.integrations = count(model, "integrations");
        o.zero_lines = count(model, "zero_lines");
        o.pad_to = count(model, "pad_to");
        o
    };
    let state_space = model
        .state_space()
        .map_err(|e| crate::error::UsageError(format!("{}: {e}", a.model.display())))?;
    // The sample time of the identification: the model's own when discrete, else that
    // of the (padded) lines, as the pipeline computes it.
    let padded_lines = if options.pad_to > 0 {
        options.pad_to + 1
    } else {
        frf.lines()
    };
    let sample_time_s = model.sample_time_s.unwrap_or_else(|| {
        era::sources::frf::preprocess::sample_time_s(frf.spacing_hz(), padded_lines)
    });
    let svd_path = if model.hankel.path == "matrix-free" {
        SvdPath::MatrixFree
    } else {
        SvdPath::Dense
    };
    let mut found = assess_model(
        frf,
        &options,
        state_space,
        model.singular_values.clone(),
        (model.hankel.rows, model.hankel.cols),
        svd_path,
        sample_time_s,
    )
    .with_context(|| format!("evaluating {} on {}", a.model.display(), a.file.display()))?;
    // The modes judged physical in the file start the refinement of an automatic model;
    // every mode starts that of a fixed-order one (as `era identify --refine`).
    let auto = model
        .parameters
        .get("states")
        .is_some_and(|v| v.as_str() == Some("auto"));
    for (q, m) in found.quality.iter_mut().zip(&model.modes) {
        if let Some(physical) = m.physical {
            q.physical = physical;
            q.reason.clone_from(&m.reason);
        }
    }
    if auto {
        // Only the modes marked physical start: `refine_identification` keeps those of a
        // model chosen by a scan.
        let keep: Vec<bool> = found.quality.iter().map(|q| q.physical).collect();
        let mut k = 0;
        found.modal.modes.retain(|_| {
            k += 1;
            keep[k - 1]
        });
        found.quality.retain(|q| q.physical);
    }
    // Collocation from the channel table; the refinement keeps it.
    crate::output::figures::collocate_fit(&mut found.fit, channels, frf.outputs(), frf.inputs());
    Ok(found)
}

/// The model to overlay (`--model`), refused when its shape is not the FRFs', and the
/// integrations and zeroed lines to plot with: the flags', else the model's, else none.
pub fn overlay_model(
    a: &Plot,
    frf: &era::FrfData,
) -> anyhow::Result<(Option<ModelJson>, usize, usize)> {
    let model = match &a.model {
        Some(path) => {
            Some(ModelJson::read(path).with_context(|| format!("reading {}", path.display()))?)
        }
        None => None,
    };
    let from_model = |key: &str| {
        model
            .as_ref()
            .and_then(|m| m.parameters.get(key))
            .and_then(|v| v.as_u64())
            .map(|v| v as usize)
    };
    let integrations = a
        .integrations
        .or_else(|| from_model("integrations"))
        .unwrap_or(0);
    let zero_lines = a
        .zero_lines
        .or_else(|| from_model("zero_lines"))
        .unwrap_or(0);
    if let Some(m) = &model {
        if (m.outputs, m.inputs) != (frf.outputs(), frf.inputs()) {
            return usage(format!(
                "--model {}: the model has {} outputs x {} inputs, {} has {} x {}",
                a.model.as_ref().unwrap().display(),
                m.outputs,
                m.inputs,
                a.file.display(),
                frf.outputs(),
                frf.inputs()
            ));
        }
    }
    Ok((model, integrations, zero_lines))
}
