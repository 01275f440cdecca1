//! What `era compare` hands on: the summary, `compare.json`, and with `--out` one
//! overlay per pair and `compare.html`.

use crate::config::{Compare, Settings};
use crate::output::write_output;
use era::modal::compare::BandDifferences;
use era_io::atomic::OutputSet;
use era_io::csv::FrfFile;
use serde_json::json;
use std::path::Path;

/// What `compare` found: the differences per pair and band, and with models the modes
/// matched and each model's fit to its own data, percent.
pub struct Comparison {
    /// The differences per pair and band.
    pub differences: BandDifferences,
    /// A's modes matched to B's (frequency, damping, frequency, damping, MAC).
    pub modes: Vec<(f64, f64, f64, f64, f64)>,
    /// Each model's fit to its own data, percent.
    pub fit: Option<(f64, f64)>,
}

/// `compare.json`, printed with `--json`.
pub fn summary_json(a: &Compare, found: &Comparison) -> serde_json::Value {
    let d = &found.differences;
    json!({
        "a": a.a, "b": a.b, "bands_hz": a.bands,
        "median_difference_percent": d.median, "worst_difference_percent": d.worst,
        "pairs": d.pairs.iter().map(|(l, r)| json!({"pair": l, "difference_percent": r})).collect::<Vec<_>>(),
        "fit_percent": found.fit.map(|(x, y)| json!({"a": x, "b": y, "band_hz": a.fit_band})),
        "modes": found.modes.iter().map(|m| json!({"frequency_a_hz": m.0, "damping_a": m.1, "frequency_b_hz": m.2, "damping_b": m.3, "mac": m.4})).collect::<Vec<_>>(),
    })
}

/// A file's name for the tables and figures.
pub fn label(s: &Path) -> String {
    s.file_name()
        .map_or("?".into(), |n| n.to_string_lossy().into_owned())
}

/// The human summary: the differences by band, the fits and the modes matched.
pub fn summary(a: &Compare, found: &Comparison, (la, lb): (&str, &str)) -> String {
    let mut text = format!(
        "era compare {} {}\n  differences by band (median over pairs, worst pair), ‖A − B‖/‖B‖:\n",
        a.a.display(),
        a.b.display()
    );
    for (k, w) in a.bands.windows(2).enumerate() {
        text.push_str(&format!(
            "    {:>5}–{:<5} Hz  {:8.2} %  {:8.2} %\n",
            w[0], w[1], found.differences.median[k], found.differences.worst[k]
        ));
    }
    if let Some((x, y)) = found.fit {
        text.push_str(&format!(
            "  fit of each model to its own data, {}–{} Hz (mean relative error): {la} {x:.2} %, {lb} {y:.2} %\n",
            a.fit_band[0], a.fit_band[1]
        ));
    }
    if !found.modes.is_empty() {
        let modes = &found.modes;
        let mean_mac = modes.iter().map(|m| m.4).sum::<f64>() / modes.len() as f64;
        text.push_str(&format!(
            "  modes matched: {} of the first model's, mean MAC {mean_mac:.4}\n",
            modes.len()
        ));
    }
    text
}

/// One PNG per pair, compare.html and compare.json into `set`.
pub fn write_files(
    set: &mut OutputSet,
    a: &Compare,
    (fa, fb): (&FrfFile, &FrfFile),
    found: &Comparison,
    notes: &str,
    json_out: &serde_json::Value,
    settings: &Settings,
) -> anyhow::Result<()> {
    let (ga, gb) = (&fa.frf, &fb.frf);
    let (q, p) = (ga.outputs(), ga.inputs());
    let (la, lb) = (label(&a.a), label(&a.b));
    let bar = crate::output::progress::bar(settings, (q * p) as u64, "figures");
    let mut overlays = Vec::new();
    // The first set's units and channel table; the phase wrapped.
    let view = crate::output::figures::frf_view(
        &era_plot::FrfUnits::from_metadata(&fa.metadata),
        ga.quantity(),
        fa.channels.as_ref(),
        ga,
        era_plot::PhaseView::Wrapped,
    );
    for i in 0..q {
        for j in 0..p {
            let fig = era_plot::compare::compare_overlay(ga, gb, (&la, &lb), i, j, &view);
            overlays.push((fig.title.clone(), era_plot::render_svg(&fig)?));
            let name = format!("pair_{}_{}.png", i + 1, j + 1);
            write_output(set, &name, |staged| {
                era_plot::render_png(&fig, staged)?;
                Ok(())
            })?;
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    let page = era_plot::compare::compare_html(&era_plot::compare::ComparePage {
        title: &format!("era compare: {la} and {lb}"),
        labels: (&la, &lb),
        bands: &a.bands,
        differences: &found.differences.pairs,
        modes: &found.modes,
        fit: found.fit,
        notes,
        overlays: &overlays,
    });
    write_output(set, "compare.html", |staged| {
        era_io::atomic::write_atomic(staged, page.as_bytes())?;
        Ok(())
    })?;
    let js = serde_json::to_string_pretty(json_out)?;
    write_output(set, "compare.json", |staged| {
        era_io::atomic::write_atomic(staged, js.as_bytes())?;
        Ok(())
    })?;
    Ok(())
}
