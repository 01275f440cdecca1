//! Figures and page of `era compare`: two FRF sets of one structure overlaid pair by pair
//! (in the manner of the thesis's Figs. 5.8, 5.9 and 5.12: with and without friction
//! compensation, and against an earlier test), the difference table per band and the
//! modes matched side by side.

use crate::figures::{
    log_range, phase_curves, phase_series, Figure, FrfView, Panel, Series, SeriesKind, YScale,
};
use era::{Complex64, FrfData};
use std::fmt::Write as _;

/// Magnitude and phase of one pair of two sets, `a` solid and `b` dashed, with their
/// labels, in the units and phase view of `view`; lines where either is exactly zero
/// are left out.
///
/// # Panics
/// If the sets differ in shape or the pair is out of range.
#[track_caller]
pub fn compare_overlay(
    a: &FrfData,
    b: &FrfData,
    labels: (&str, &str),
    output: usize,
    input: usize,
    view: &FrfView,
) -> Figure {
    assert_eq!(
        (a.outputs(), a.inputs(), a.lines()),
        (b.outputs(), b.inputs(), b.lines()),
        "compared shapes"
    );
    let f = a.frequency_hz();
    let (ga, gb) = (a.pair(output, input), b.pair(output, input));
    let keep: Vec<usize> = (0..f.len())
        .filter(|&k| ga[k].norm() > 0.0 && gb[k].norm() > 0.0)
        .collect();
    let pick = |g: &[Complex64]| -> Vec<Complex64> { keep.iter().map(|&k| g[k]).collect() };
    let (pa, pb) = (pick(ga), pick(gb));
    let x: Vec<f64> = keep.iter().map(|&k| f[k]).collect();
    let x_range = (0.0, f[f.len() - 1]);
    let mag = |g: &[Complex64]| g.iter().map(|v| v.norm()).collect::<Vec<f64>>();
    let (ma, mb) = (mag(&pa), mag(&pb));
    let (pha, phb, phase_range) = phase_curves(&pa, Some(&pb), view.phase);
    let phb = phb.unwrap_or_default();
    let two = |ya: &[f64], yb: &[f64]| {
        vec![
            Series {
                label: labels.0.into(),
                x: x.clone(),
                y: ya.to_vec(),
                kind: SeriesKind::Measured,
            },
            Series {
                label: labels.1.into(),
                x: x.clone(),
                y: yb.to_vec(),
                kind: SeriesKind::Model,
            },
        ]
    };
    let magnitude = Panel {
        title: String::new(),
        x_label: "Frequency (Hz)".into(),
        y_label: format!("|G| {}", view.unit),
        y_scale: YScale::Log,
        x_range,
        y_range: log_range(ma.iter().chain(&mb).copied()),
        series: two(&ma, &mb),
        marker_x: None,
        guide_y: None,
        legend: true,
    };
    let phase = Panel {
        title: String::new(),
        x_label: "Frequency (Hz)".into(),
        y_label: "Phase (deg)".into(),
        y_scale: YScale::Linear,
        x_range,
        y_range: phase_range,
        series: vec![
            phase_series(&x, &pha, labels.0, SeriesKind::Measured, view.phase),
            phase_series(&x, &phb, labels.1, SeriesKind::Model, view.phase),
        ],
        marker_x: None,
        guide_y: None,
        legend: false,
    };
    Figure {
        title: view.pair_title(output, input),
        panels: vec![magnitude, phase],
        columns: 1,
        size: (900, 640),
    }
}

/// What the comparison page shows.
pub struct ComparePage<'a> {
    /// Page title.
    pub title: &'a str,
    /// The two sets' names.
    pub labels: (&'a str, &'a str),
    /// Band edges, Hz (`bands[k]..bands[k+1]`).
    pub bands: &'a [f64],
    /// Rows of the difference table: pair label, then one relative RMS difference (%)
    /// per band.
    pub differences: &'a [(String, Vec<f64>)],
    /// Matched modes: `(f_a, ζ_a, f_b, ζ_b, MAC)` (Hz, fraction).
    pub modes: &'a [(f64, f64, f64, f64, f64)],
    /// Fit error of each model against its own data (mean relative error, %), when
    /// there are models.
    pub fit: Option<(f64, f64)>,
    /// Free text above the tables (what was compared, how).
    pub notes: &'a str,
    /// One (title, SVG) per pair.
    pub overlays: &'a [(String, String)],
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The comparison page: one self-contained HTML file (inline CSS and SVG, no script),
/// in the style of `report.html`.
pub fn compare_html(p: &ComparePage<'_>) -> String {
    let mut h = String::with_capacity(1 << 20);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\n<style>\
body{{font-family:sans-serif;margin:2em;max-width:1100px;color:#222}} h1{{font-size:1.6em}} h2{{margin-top:2em;border-bottom:1px solid #ccc}}\
table{{border-collapse:collapse;margin:1em 0}} td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}} th{{background:#f3f3f3}}\
pre{{background:#f7f7f7;padding:1em}} figure{{margin:1em 0}} svg{{max-width:100%;height:auto}} .big{{background:#fde8e8}}\
</style></head><body>\n<h1>{}</h1>\n<pre>{}</pre>\n",
        escape(p.title),
        escape(p.title),
        escape(p.notes)
    );
    let _ = write!(
        h,
        "<h2 id=\"differences\">Differences by band</h2>\n<p>Relative RMS difference ‖A − B‖ / ‖B‖ over the lines of each band, %, with A = {} and B = {}; cells above 10 % are shaded.</p>\n<table><tr><th>pair</th>",
        escape(p.labels.0),
        escape(p.labels.1)
    );
    for w in p.bands.windows(2) {
        let _ = write!(h, "<th>{}–{} Hz</th>", w[0], w[1]);
    }
    h.push_str("</tr>\n");
    for (label, row) in p.differences {
        let _ = write!(h, "<tr><td>{}</td>", escape(label));
        for v in row {
            let class = if *v > 10.0 { " class=\"big\"" } else { "" };
            if v.is_finite() {
                let _ = write!(h, "<td{class}>{v:.2}</td>");
            } else {
                h.push_str("<td>–</td>");
            }
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table>\n");
    if !p.modes.is_empty() {
        let _ = write!(
            h,
            "<h2 id=\"modes\">Modes side by side</h2>\n<table><tr><th>f {0} (Hz)</th><th>ζ {0} (%)</th><th>f {1} (Hz)</th><th>ζ {1} (%)</th><th>Δf (Hz)</th><th>Δζ (%)</th><th>MAC</th></tr>\n",
            escape(p.labels.0),
            escape(p.labels.1)
        );
        for &(fa, za, fb, zb, mac) in p.modes {
            let _ = writeln!(
                h,
                "<tr><td>{fa:.4}</td><td>{:.3}</td><td>{fb:.4}</td><td>{:.3}</td><td>{:.4}</td><td>{:.3}</td><td>{mac:.4}</td></tr>",
                100.0 * za,
                100.0 * zb,
                fb - fa,
                100.0 * (zb - za)
            );
        }
        h.push_str("</table>\n");
    }
    if let Some((fa, fb)) = p.fit {
        let _ = write!(
            h,
            "<h2 id=\"fit\">Fit of each model to its own data</h2>\n<table><tr><th>{}</th><th>{}</th></tr><tr><td>{fa:.2} %</td><td>{fb:.2} %</td></tr></table>\n",
            escape(p.labels.0),
            escape(p.labels.1)
        );
    }
    h.push_str("<h2 id=\"pairs\">Pairs</h2>\n");
    for (title, svg) in p.overlays {
        let _ = write!(
            h,
            "<h3>{}</h3>\n<figure class=\"plot\">{svg}</figure>\n",
            escape(title)
        );
    }
    h.push_str("</body></html>\n");
    h
}
