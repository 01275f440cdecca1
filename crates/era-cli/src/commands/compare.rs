//! `era compare A B`: two FRF sets of one structure side by side (thesis Figs. 5.8, 5.9,
//! 5.12): the difference per pair and per band, the modes of their models matched by MAC,
//! and the fit of each model to its own data.

use crate::config::Compare;
use crate::input::compare::{model_from_json, read_both, Model};
use crate::output::compare::{label, summary, summary_json, write_files, Comparison};
use crate::output::report::{finish_output, Human};
use era::modal::compare::{band_differences, compare_models, Side};
use era::FrfData;
use era_io::atomic::OutputSet;
use std::path::Path;
use std::time::Instant;

/// `set` (read from `path`) identified with `--identify FLAGS`.
fn identified(flags: &[String], path: &Path, frf: &FrfData) -> anyhow::Result<Model> {
    let opts = crate::config::compare::compare_identify_options(flags, path, frf)?;
    let found = era::identify(frf, &opts)?;
    Ok(Model {
        model: found.model,
        integrations: opts.integrations,
    })
}

/// The core's side of a comparison: `frf` and its model.
fn side<'a>(frf: &'a FrfData, m: &'a Model) -> Side<'a> {
    Side {
        frf,
        model: &m.model,
        integrations: m.integrations,
    }
}

pub fn run(a: &Compare) -> anyhow::Result<()> {
    let settings = a.settings;
    let human = Human::new(&settings);
    crate::config::compare::check_bands(a)?;
    let mut set = a.out.as_deref().map(OutputSet::new).transpose()?;
    let (fa, fb) = read_both(a)?;
    let (ga, gb) = (&fa.frf, &fb.frf);
    let clock = Instant::now();
    let differences = band_differences(ga, gb, &a.bands);
    // Models: given or identified.
    let models = match (&a.model_a, &a.model_b, &a.identify) {
        (Some(ma), Some(mb), _) => Some((
            model_from_json("--model-a", ma)?,
            model_from_json("--model-b", mb)?,
        )),
        (_, _, Some(flags)) => Some((identified(flags, &a.a, ga)?, identified(flags, &a.b, gb)?)),
        _ => None,
    };
    let compared = match &models {
        Some((ma, mb)) => {
            let band = (a.fit_band[0], a.fit_band[1]);
            Some(compare_models((&side(ga, ma), &side(gb, mb)), band)?)
        }
        None => None,
    };
    let found = Comparison {
        differences,
        modes: compared
            .as_ref()
            .map(|c| c.modes.clone())
            .unwrap_or_default(),
        fit: compared.map(|c| c.fit),
    };
    let compare_s = clock.elapsed().as_secs_f64();
    let (la, lb) = (label(&a.a), label(&a.b));
    let text = summary(a, &found, (&la, &lb));
    human.print(&text);
    let json_out = summary_json(a, &found);
    if let Some(set) = set.as_mut() {
        write_files(set, a, (&fa, &fb), &found, &text, &json_out, &settings)?;
    }
    if let Some(set) = set {
        set.commit()?;
    }
    finish_output(&human, &settings, json_out, &[("compare", compare_s)])
}
