//! The figures and page of `era track`: one small panel per track of a quantity
//! (frequency or damping) against time, each record's value with its standard deviation
//! as an error bar and, for the frequency, the least-squares trend line; and
//! [`track_html`], the page with the table of tracks and the figures.
//!
//! Each track has a panel of its own so that a drift of a percent is visible: on one
//! axis shared by modes from 2 to 30 Hz it would be a flat line. Times are drawn as
//! dates (UTC) when the records have them, else the record's position in the fleet.

use crate::render::{safe_range, PlotError};
use era::modal::track::{Track, TrendUnit};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::fmt::Write as _;
use std::path::Path;

const POINT: RGBColor = RGBColor(31, 119, 180);
const TREND: RGBColor = RGBColor(214, 39, 40);

use crate::render::err;

/// One track's points in a figure.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackPanel {
    /// The panel's title (the track, its mean, its trend).
    pub title: String,
    /// Abscissae: days since the first record, or record positions.
    pub x: Vec<f64>,
    /// Values, in the figure's unit.
    pub y: Vec<f64>,
    /// Standard deviation of each value (same unit), when known.
    pub std: Vec<Option<f64>>,
    /// The trend line `(intercept, slope)` in the figure's unit, if drawn.
    pub line: Option<(f64, f64)>,
    /// A fitted curve `(x, y)` drawn instead of the line (the model of a change).
    pub curve: Option<Vec<(f64, f64)>>,
}

/// A figure of tracks: one panel per track.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackPlot {
    /// The figure's title.
    pub title: String,
    /// The ordinate's label.
    pub y_label: String,
    /// The first record's time, s since 1970 (UTC): abscissae are days from it and drawn
    /// as dates; `None`: abscissae are record positions.
    pub origin_s: Option<f64>,
    /// The panels.
    pub panels: Vec<TrackPanel>,
    /// Panels per row.
    pub columns: usize,
    /// Size in pixels.
    pub size: (u32, u32),
    /// The abscissa of a change, drawn as a dashed vertical line in every panel.
    pub change: Option<f64>,
}

impl TrackPlot {
    /// A figure of `panels`, two columns when there are more than two, each panel about
    /// 260 pixels high.
    pub fn new(title: &str, y_label: &str, origin_s: Option<f64>, panels: Vec<TrackPanel>) -> Self {
        let columns = if panels.len() > 2 { 2 } else { 1 };
        let rows = panels.len().div_ceil(columns).max(1) as u32;
        TrackPlot {
            title: title.to_string(),
            y_label: y_label.to_string(),
            origin_s,
            panels,
            columns,
            size: (1200, 60 + 270 * rows),
            change: None,
        }
    }

    /// Abscissa units per day on the drawn axis: hours (24) when the records span at
    /// most four days, so that ticks fall on round hours; days (1) otherwise; 1 for
    /// record positions.
    fn per_day(&self, span_days: f64) -> f64 {
        if self.origin_s.is_some() && span_days <= 4.0 {
            24.0
        } else {
            1.0
        }
    }

    /// The tick label of drawn abscissa `v` (in units of [`Self::per_day`]): a date and
    /// time (or a date, over long spans) when there are times, else the record's number.
    fn tick(&self, v: f64, span_days: f64) -> String {
        match self.origin_s {
            Some(t0) => {
                let t = t0 + v / self.per_day(span_days) * 86_400.0;
                let Some(d) = chrono::DateTime::from_timestamp(t.round() as i64, 0) else {
                    return format!("{v:.1}");
                };
                if span_days > 4.0 {
                    d.format("%Y-%m-%d").to_string()
                } else {
                    d.format("%m-%d %H:%M").to_string()
                }
            }
            None => format!("{}", v.round() as i64 + 1),
        }
    }
}

/// The common abscissa range of every panel.
fn x_range(plot: &TrackPlot) -> (f64, f64) {
    let xs = plot.panels.iter().flat_map(|p| p.x.iter().copied());
    let (lo, hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.03).max(if plot.origin_s.is_some() { 0.01 } else { 0.5 });
    (lo - pad, hi + pad)
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    plot: &TrackPlot,
    panel: &TrackPanel,
    (x0, x1): (f64, f64),
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let spread = |k: usize| panel.std.get(k).copied().flatten().unwrap_or(0.0);
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (k, &y) in panel.y.iter().enumerate() {
        lo = lo.min(y - spread(k));
        hi = hi.max(y + spread(k));
    }
    let pad = ((hi - lo) * 0.08).max(1e-6 * hi.abs().max(1e-12));
    let (y0, y1) = safe_range((lo - pad, hi + pad), false);
    // Days (or positions) as read, drawn in hours over short spans.
    let span = x1 - x0;
    let k = plot.per_day(span);
    let (x0, x1) = safe_range((x0 * k, x1 * k), false);
    // Enough decimals to tell the ticks apart, and no more.
    let digits = (2.0 - (y1 - y0).log10().floor()).clamp(0.0, 8.0) as usize;
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, ("sans-serif", 15))
        .margin(8)
        .x_label_area_size(32)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    let x_desc = if plot.origin_s.is_some() {
        "Record start (UTC)"
    } else {
        "Record"
    };
    chart
        .configure_mesh()
        .x_labels(6)
        .y_labels(5)
        .x_label_formatter(&|v: &f64| plot.tick(*v, span))
        .y_label_formatter(&|v: &f64| format!("{v:.digits$}"))
        .x_desc(x_desc)
        .y_desc(plot.y_label.as_str())
        .label_style(("sans-serif", 12))
        .light_line_style(RGBColor(246, 246, 246))
        .draw()
        .map_err(err)?;
    if let Some(curve) = &panel.curve {
        chart
            .draw_series(LineSeries::new(
                curve.iter().map(|&(x, y)| (x * k, y)),
                TREND.stroke_width(2),
            ))
            .map_err(err)?;
    } else if let Some((a, b)) = panel.line {
        chart
            .draw_series(LineSeries::new(
                [x0, x1].map(|x| (x, a + b * x / k)),
                TREND.stroke_width(2),
            ))
            .map_err(err)?;
    }
    if let Some(c) = plot.change {
        // A dashed vertical line: short strokes from the bottom to the top.
        let (xc, dash) = (c * k, (y1 - y0) / 40.0);
        let style = RGBColor(90, 90, 90).stroke_width(1);
        chart
            .draw_series((0..20).map(|j| {
                let a = y0 + 2.0 * j as f64 * dash;
                PathElement::new(vec![(xc, a), (xc, a + dash)], style)
            }))
            .map_err(err)?;
    }
    // Error bars: a vertical stroke of ± one standard deviation with short caps.
    let cap = 0.004 * (x1 - x0);
    let xs: Vec<f64> = panel.x.iter().map(|x| x * k).collect();
    let style = POINT.mix(0.6).stroke_width(1);
    for (j, (&x, &y)) in xs.iter().zip(&panel.y).enumerate() {
        let s = spread(j);
        if s > 0.0 {
            let (a, b) = (y - s, y + s);
            chart
                .draw_series([
                    PathElement::new(vec![(x, a), (x, b)], style),
                    PathElement::new(vec![(x - cap, a), (x + cap, a)], style),
                    PathElement::new(vec![(x - cap, b), (x + cap, b)], style),
                ])
                .map_err(err)?;
        }
    }
    chart
        .draw_series(
            xs.iter()
                .zip(&panel.y)
                .map(|(&x, &y)| Circle::new((x, y), 3, POINT.filled())),
        )
        .map_err(err)?;
    Ok(())
}

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, plot: &TrackPlot) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    crate::render::fonts();
    root.fill(&WHITE).map_err(err)?;
    let root = root.titled(&plot.title, ("sans-serif", 20)).map_err(err)?;
    if plot.panels.is_empty() {
        root.draw(&Text::new(
            "no track to draw",
            (40, 40),
            ("sans-serif", 16).into_font(),
        ))
        .map_err(err)?;
        root.present().map_err(err)?;
        return Ok(());
    }
    let rows = plot.panels.len().div_ceil(plot.columns);
    let areas = root.split_evenly((rows, plot.columns));
    let range = x_range(plot);
    for (panel, area) in plot.panels.iter().zip(&areas) {
        draw_panel(area, plot, panel, range)?;
    }
    root.present().map_err(err)?;
    Ok(())
}

/// The figure as SVG text.
///
/// # Errors
/// [`PlotError`] when plotters fails.
pub fn track_svg(plot: &TrackPlot) -> Result<String, PlotError> {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, plot.size).into_drawing_area();
        draw(root, plot)?;
    }
    Ok(crate::render::compact_svg(&out))
}

/// The figure as a PNG file.
///
/// # Errors
/// [`PlotError`] when plotters fails or the file cannot be written.
pub fn track_png(plot: &TrackPlot, path: &Path) -> Result<(), PlotError> {
    let root = BitMapBackend::new(path, plot.size).into_drawing_area();
    draw(root, plot)
}

/// A change in a track page: its first record, and each track's step (relative) and t.
pub type ChangeSteps<'a> = (&'a str, Vec<Option<(f64, f64)>>);

/// What the page of `era track` shows.
pub struct TrackPage<'a> {
    /// Page title.
    pub title: &'a str,
    /// Free text above the table (what was read, the options).
    pub notes: &'a str,
    /// The tracks.
    pub tracks: &'a [Track],
    /// What the trends are per.
    pub unit: TrendUnit,
    /// The figures: (id, heading, caption, SVG).
    pub figures: &'a [(String, String, String, String)],
    /// When a change was found: its first record, and each track's step (relative) and
    /// t statistic, in the order of `tracks`.
    pub change: Option<ChangeSteps<'a>>,
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The trend of `t` in % per unit with its standard error, as text.
pub fn trend_text(t: &Track) -> String {
    match t.trend {
        Some(tr) => match tr.relative_std_error {
            Some(se) => format!("{:+.4} ± {:.4}", 100.0 * tr.relative, 100.0 * se),
            None => format!("{:+.4}", 100.0 * tr.relative),
        },
        None => "–".into(),
    }
}

/// The page: one self-contained HTML file (inline CSS and SVG, no script), in the
/// style of `report.html`.
pub fn track_html(p: &TrackPage<'_>) -> String {
    let mut h = String::with_capacity(1 << 20);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\n<style>\
body{{font-family:sans-serif;margin:2em;max-width:1200px;color:#222}} h1{{font-size:1.6em}} h2{{margin-top:2em;border-bottom:1px solid #ccc}}\
table{{border-collapse:collapse;margin:1em 0}} td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}} th{{background:#f3f3f3}}\
pre{{background:#f7f7f7;padding:1em;white-space:pre-wrap}} figure{{margin:1em 0}} svg{{max-width:100%;height:auto}} .sparse{{color:#888}}\
</style></head><body>\n<h1>{}</h1>\n<pre>{}</pre>\n",
        escape(p.title),
        escape(p.title),
        escape(p.notes)
    );
    let unit = p.unit.name();
    let _ = write!(
        h,
        "<h2 id=\"tracks\">Tracks</h2>\n<p>One row per track: the records it appears in, the mean and standard deviation of its frequency and damping over those records, and the trend of its frequency (least-squares slope relative to the mean, % per {unit}, ± its standard error). Sparse tracks (grey) appear in too few records to be a mode followed through the fleet.</p>\n\
<table><tr><th>track</th><th>records</th><th>f mean (Hz)</th><th>f std (Hz)</th><th>ζ mean (%)</th><th>ζ std (%)</th><th>trend (%/{unit})</th>{}<th></th></tr>\n",
        match &p.change {
            Some((first, _)) => format!("<th>step from {} (%)</th><th>t</th>", escape(first)),
            None => String::new(),
        }
    );
    for (k, t) in p.tracks.iter().enumerate() {
        let class = if t.sparse { " class=\"sparse\"" } else { "" };
        let step = match &p.change {
            Some((_, steps)) => match steps.get(k).copied().flatten() {
                Some((r, tt)) => format!("<td>{:+.2}</td><td>{tt:.1}</td>", 100.0 * r),
                None => "<td>–</td><td>–</td>".to_string(),
            },
            None => String::new(),
        };
        let _ = writeln!(
            h,
            "<tr{class}><td>{}</td><td>{}</td><td>{:.4}</td><td>{:.4}</td><td>{:.3}</td><td>{:.3}</td><td>{}</td>{step}<td>{}</td></tr>",
            t.id,
            t.records,
            t.frequency_mean_hz,
            t.frequency_std_hz,
            100.0 * t.damping_mean,
            100.0 * t.damping_std,
            trend_text(t),
            if t.sparse { "sparse" } else { "" }
        );
    }
    h.push_str("</table>\n");
    for (id, heading, caption, svg) in p.figures {
        let _ = write!(
            h,
            "<h2 id=\"{}\">{}</h2>\n<p>{}</p>\n<figure class=\"plot\">{svg}</figure>\n",
            escape(id),
            escape(heading),
            escape(caption)
        );
    }
    h.push_str("</body></html>\n");
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    fn panel(n: usize) -> TrackPanel {
        let x: Vec<f64> = (0..n).map(|k| k as f64 / 24.0).collect();
        TrackPanel {
            title: "Track 1".into(),
            y: x.iter().map(|v| 5.0 - 0.1 * v).collect(),
            std: vec![Some(0.002); n],
            x,
            line: Some((5.0, -0.1)),
            curve: None,
        }
    }

    #[test]
    fn dates_on_the_axis_with_times_and_record_numbers_without() {
        let mut plot = TrackPlot::new("f", "Hz", Some(1.8e9), vec![panel(12), panel(3)]);
        assert_eq!(plot.tick(12.0, 1.0), "01-15 20:00");
        assert_eq!(plot.per_day(1.0), 24.0);
        assert_eq!(plot.tick(0.0, 10.0), "2027-01-15");
        let svg = track_svg(&plot).unwrap();
        assert!(svg.contains("<svg") && svg.contains("01-15"));
        plot.origin_s = None;
        assert_eq!(plot.tick(2.0, 10.0), "3");
        assert_eq!(plot.columns, 1);
        assert_eq!(
            TrackPlot::new("f", "Hz", None, vec![panel(2); 3]).columns,
            2
        );
        assert!(track_svg(&TrackPlot::new("f", "Hz", None, vec![]))
            .unwrap()
            .contains("no track"));
    }
}
