//! What `era compare` reads: the two FRF sets (on the same pairs and lines) and the
//! models given for them.

use crate::config::Compare;
use crate::error::usage;
use era::StateSpace;
use era_io::csv::FrfFile;
use era_io::format::{read_frf_file, ReadOptions};
use std::path::Path;

/// A model of one set and the integrations ERA applied to the set's FRFs before fitting
/// it.
pub struct Model {
    /// The model.
    pub model: StateSpace,
    /// The integrations (model.json's `integrations`, 0 when it does not say).
    pub integrations: usize,
}

/// Both FRF files, refused unless they hold the same pairs on the same lines.
pub fn read_both(a: &Compare) -> anyhow::Result<(FrfFile, FrfFile)> {
    let opts = ReadOptions::default();
    let (fa, _) = read_frf_file(&a.a, &opts)?;
    let (fb, _) = read_frf_file(&a.b, &opts)?;
    let (ga, gb) = (&fa.frf, &fb.frf);
    if (ga.outputs(), ga.inputs(), ga.lines()) != (gb.outputs(), gb.inputs(), gb.lines())
        || ga
            .frequency_hz()
            .iter()
            .zip(gb.frequency_hz())
            .any(|(x, y)| (x - y).abs() > 1e-9 * (1.0 + x.abs()))
    {
        return usage(format!(
            "{} ({} x {}, {} lines) and {} ({} x {}, {} lines) are not on the same pairs and lines",
            a.a.display(),
            ga.outputs(),
            ga.inputs(),
            ga.lines(),
            a.b.display(),
            gb.outputs(),
            gb.inputs(),
            gb.lines()
        ));
    }
    Ok((fa, fb))
}

/// The model of a model.json given as `flag`.
pub fn model_from_json(flag: &str, path: &Path) -> anyhow::Result<Model> {
    let m = era_io::model_json::ModelJson::read(path)?;
    let model = m
        .state_space()
        .map_err(|e| crate::error::UsageError(format!("{flag} {}: {e}", path.display())))?;
    let integrations = m
        .parameters
        .get("integrations")
        .and_then(|v| v.as_u64())
        .unwrap_or(0) as usize;
    Ok(Model {
        model,
        integrations,
    })
}
