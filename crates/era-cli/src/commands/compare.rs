//! `era compare A B`: two FRF sets of one structure side by side (thesis Figs. 5.8, 5.9,
//! 5.12): the difference per pair and per band, the modes of their models matched by MAC,
//! and the fit of each model to its own data.

use crate::config::{Compare, Settings};
use crate::error::usage;
use crate::output::report::{finish_output, Human};
use crate::output::write_output;
use era::modal::indicators::mac;
use era::pipeline::fit::model_frf;
use era::pipeline::modes::modal_parameters;
use era::{Complex64, FrfData, StateSpace};
use era_io::atomic::OutputSet;
use era_io::csv::FrfFile;
use era_io::format::{read_frf_file, ReadOptions};
use serde_json::json;
use std::path::Path;
use std::time::Instant;

/// Relative RMS difference `‖A − B‖ / ‖B‖` over the lines `lo ≤ f < hi` (NaN when B has
/// no power there).
pub fn band_difference(a: &[Complex64], b: &[Complex64], f: &[f64], lo: f64, hi: f64) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for k in 0..f.len() {
        if f[k] >= lo && f[k] < hi {
            num += (a[k] - b[k]).norm_sqr();
            den += b[k].norm_sqr();
        }
    }
    if den > 0.0 {
        (num / den).sqrt()
    } else if num == 0.0 {
        0.0
    } else {
        f64::NAN
    }
}

/// `G / (j2πf)^n` on every line above 0 Hz (0 at 0 Hz): what ERA fitted after `n`
/// integrations.
fn integrate(frf: &FrfData, n: usize) -> anyhow::Result<FrfData> {
    let f = frf.frequency_hz().to_vec();
    let lines = f.len();
    let mut v = frf.values().to_vec();
    for (idx, x) in v.iter_mut().enumerate() {
        let k = idx % lines;
        *x = if f[k] > 0.0 {
            *x / Complex64::new(0.0, 2.0 * std::f64::consts::PI * f[k]).powi(n as i32)
        } else {
            Complex64::new(0.0, 0.0)
        };
    }
    Ok(FrfData::new(
        f,
        frf.outputs(),
        frf.inputs(),
        v,
        frf.quantity(),
    )?)
}

/// Mean relative error `‖G − Ĝ‖/‖G‖` over pairs, on the lines in `band`.
fn fit_error(data: &FrfData, model: &FrfData, band: (f64, f64)) -> f64 {
    let f = data.frequency_hz();
    let (q, p) = (data.outputs(), data.inputs());
    let mut total = 0.0;
    for i in 0..q {
        for j in 0..p {
            total += band_difference(model.pair(i, j), data.pair(i, j), f, band.0, band.1 + 1e-9);
        }
    }
    total / (q * p) as f64
}

struct Side {
    model: StateSpace,
    integrations: usize,
}

fn model_from_json(flag: &str, path: &Path) -> anyhow::Result<Side> {
    let m = era_io::model_json::ModelJson::read(path)?;
    let model = m
        .state_space()
        .map_err(|e| crate::error::UsageError(format!("{flag} {}: {e}", path.display())))?;
    let integrations = m
        .parameters
        .get("integrations")
        .and_then(|v| v.as_u64())
        .unwrap_or(0) as usize;
    Ok(Side {
        model,
        integrations,
    })
}

fn identified(flags: &[String], path: &Path, frf: &FrfData) -> anyhow::Result<Side> {
    let opts = crate::config::compare_identify_options(flags, path, frf)?;
    let found = era::identify(frf, &opts)?;
    Ok(Side {
        model: found.model,
        integrations: opts.integrations,
    })
}

/// What `compare` found: the difference of each pair per band, the median and worst
/// over pairs, the matched modes (A's frequency and damping, B's, the MAC) and each
/// model's fit to its own data, percent.
struct Comparison {
    differences: Vec<(String, Vec<f64>)>,
    median_band: Vec<f64>,
    worst: Vec<f64>,
    modes: Vec<(f64, f64, f64, f64, f64)>,
    fit: Option<(f64, f64)>,
}

pub fn run(a: &Compare) -> anyhow::Result<()> {
    let settings = a.settings;
    let human = Human::new(&settings);
    check_bands(a)?;
    let mut set = match &a.out {
        Some(dir) => Some(OutputSet::new(dir)?),
        None => None,
    };
    let (fa, fb) = read_both(a)?;
    let (ga, gb) = (&fa.frf, &fb.frf);
    let clock = Instant::now();
    let (differences, median_band, worst) = band_differences(ga, gb, &a.bands);
    // Models: given or identified.
    let sides = match (&a.model_a, &a.model_b, &a.identify) {
        (Some(ma), Some(mb), _) => Some((
            model_from_json("--model-a", ma)?,
            model_from_json("--model-b", mb)?,
        )),
        (_, _, Some(flags)) => Some((identified(flags, &a.a, ga)?, identified(flags, &a.b, gb)?)),
        _ => None,
    };
    let (modes, fit) = match &sides {
        Some(sides) => compare_models(sides, ga, gb, (a.fit_band[0], a.fit_band[1]))?,
        None => (Vec::new(), None),
    };
    let found = Comparison {
        differences,
        median_band,
        worst,
        modes,
        fit,
    };
    let compare_s = clock.elapsed().as_secs_f64();
    let (la, lb) = (label(&a.a), label(&a.b));
    let text = summary(a, &found, (&la, &lb));
    human.print(&text);
    let json_out = json!({
        "a": a.a, "b": a.b, "bands_hz": a.bands,
        "median_difference_percent": found.median_band, "worst_difference_percent": found.worst,
        "pairs": found.differences.iter().map(|(l, r)| json!({"pair": l, "difference_percent": r})).collect::<Vec<_>>(),
        "fit_percent": found.fit.map(|(x, y)| json!({"a": x, "b": y, "band_hz": a.fit_band})),
        "modes": found.modes.iter().map(|m| json!({"frequency_a_hz": m.0, "damping_a": m.1, "frequency_b_hz": m.2, "damping_b": m.3, "mac": m.4})).collect::<Vec<_>>(),
    });
    if let Some(set) = set.as_mut() {
        write_files(set, a, (&fa, &fb), &found, &text, &json_out, &settings)?;
    }
    if let Some(set) = set {
        set.commit()?;
    }
    finish_output(&human, &settings, json_out, &[("compare", compare_s)])
}

/// `--bands` and `--fit-band` checked before anything is read.
fn check_bands(a: &Compare) -> anyhow::Result<()> {
    if a.bands.len() < 2
        || a.bands.iter().any(|b| !b.is_finite() || *b < 0.0)
        || a.bands.windows(2).any(|w| w[1] <= w[0])
    {
        return usage(format!(
            "--bands {:?}: need at least two increasing frequencies >= 0",
            a.bands
        ));
    }
    if a.fit_band.len() != 2 || !(a.fit_band[0] >= 0.0 && a.fit_band[1] > a.fit_band[0]) {
        return usage(format!(
            "--fit-band {:?}: need LOW,HIGH with LOW < HIGH",
            a.fit_band
        ));
    }
    Ok(())
}

/// Both FRF files, refused unless they hold the same pairs on the same lines.
fn read_both(a: &Compare) -> anyhow::Result<(FrfFile, FrfFile)> {
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

/// A file's name for the tables and figures.
fn label(s: &Path) -> String {
    s.file_name()
        .map_or("?".into(), |n| n.to_string_lossy().into_owned())
}

/// The difference of each pair in each band, percent; the median over pairs and the
/// worst pair per band.
#[allow(clippy::type_complexity)]
fn band_differences(
    ga: &FrfData,
    gb: &FrfData,
    bands: &[f64],
) -> (Vec<(String, Vec<f64>)>, Vec<f64>, Vec<f64>) {
    let (q, p) = (ga.outputs(), ga.inputs());
    let f = ga.frequency_hz();
    let mut differences = Vec::new();
    let mut worst: Vec<f64> = vec![0.0; bands.len() - 1];
    for i in 0..q {
        for j in 0..p {
            let row: Vec<f64> = bands
                .windows(2)
                .map(|w| 100.0 * band_difference(ga.pair(i, j), gb.pair(i, j), f, w[0], w[1]))
                .collect();
            for (w, v) in worst.iter_mut().zip(&row) {
                if v.is_finite() {
                    *w = w.max(*v);
                }
            }
            differences.push((format!("{}/{}", i + 1, j + 1), row));
        }
    }
    let median_band: Vec<f64> = (0..bands.len() - 1)
        .map(|b| {
            let mut v: Vec<f64> = differences
                .iter()
                .map(|d| d.1[b])
                .filter(|x| x.is_finite())
                .collect();
            v.sort_by(f64::total_cmp);
            v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
        })
        .collect();
    (differences, median_band, worst)
}

/// Each model's fit to its own data over `band` (percent), and A's modes matched to
/// B's: among B's modes within 10 % in frequency, the one with the highest MAC.
#[allow(clippy::type_complexity)]
fn compare_models(
    (sa, sb): &(Side, Side),
    ga: &FrfData,
    gb: &FrfData,
    band: (f64, f64),
) -> anyhow::Result<(Vec<(f64, f64, f64, f64, f64)>, Option<(f64, f64)>)> {
    let da = integrate(ga, sa.integrations)?;
    let db = integrate(gb, sb.integrations)?;
    let ma = model_frf(&sa.model, &da)?;
    let mb = model_frf(&sb.model, &db)?;
    let fit = Some((
        100.0 * fit_error(&da, &ma, band),
        100.0 * fit_error(&db, &mb, band),
    ));
    let pa = modal_parameters(&sa.model)?;
    let pb = modal_parameters(&sb.model)?;
    let mut modes = Vec::new();
    for m in &pa.modes {
        let best = pb
            .modes
            .iter()
            .filter(|n| (n.frequency_hz - m.frequency_hz).abs() <= 0.1 * m.frequency_hz)
            .map(|n| (mac(&m.shape, &n.shape), n))
            .max_by(|x, y| x.0.total_cmp(&y.0));
        if let Some((value, n)) = best {
            modes.push((
                m.frequency_hz,
                m.damping_ratio,
                n.frequency_hz,
                n.damping_ratio,
                value,
            ));
        }
    }
    Ok((modes, fit))
}

/// The human summary: the differences by band, the fits and the modes matched.
fn summary(a: &Compare, found: &Comparison, (la, lb): (&str, &str)) -> String {
    let mut text = format!(
        "era compare {} {}\n  differences by band (median over pairs, worst pair), ‖A − B‖/‖B‖:\n",
        a.a.display(),
        a.b.display()
    );
    for (k, w) in a.bands.windows(2).enumerate() {
        text.push_str(&format!(
            "    {:>5}–{:<5} Hz  {:8.2} %  {:8.2} %\n",
            w[0], w[1], found.median_band[k], found.worst[k]
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
fn write_files(
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
        differences: &found.differences,
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
