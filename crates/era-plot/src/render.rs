//! Drawing a [`Figure`] with `plotters`, to SVG text or a PNG file.

use crate::figures::{Figure, Panel, SeriesKind, YScale};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};
use std::path::Path;
use std::sync::Once;
use thiserror::Error;

/// A drawing failure.
#[derive(Debug, Error)]
#[error("plotting: {0}")]
pub struct PlotError(pub String);

static FONT: Once = Once::new();

/// Registers DejaVu Sans (embedded) as `sans-serif` once.
pub(crate) fn fonts() {
    FONT.call_once(|| {
        let _ = register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
    });
}

const MEASURED: RGBColor = RGBColor(31, 119, 180);
const MODEL: RGBColor = RGBColor(214, 39, 40);
const GUIDE: RGBColor = RGBColor(120, 120, 120);

fn err(e: impl std::fmt::Display) -> PlotError {
    PlotError(e.to_string())
}

/// An axis range plotters can draw: finite, increasing, not degenerate, within ±1e300
/// (log: within 1e-300 … 1e300, at least a factor 10 and at most
/// [`crate::figures::MAX_LOG_SPAN_DECADES`] decades). Plotters rounds a log range out
/// to decades and searches for tick marks in loops that never end when a bound is
/// infinite, NaN or zero: every panel goes through here first, whatever its figure
/// builder computed.
pub fn safe_range((a, b): (f64, f64), log: bool) -> (f64, f64) {
    const BIG: f64 = 1e300;
    if log {
        let ok = |v: f64| v.is_finite() && v > 0.0;
        let (lo, hi) = match (ok(a), ok(b)) {
            (true, true) => (a.min(b), a.max(b)),
            (true, false) => (a, a * 10.0),
            (false, true) => (b / 10.0, b),
            (false, false) => (0.1, 1.0),
        };
        let hi = hi.clamp(1e-299, BIG);
        let lo = lo.clamp(1e-300, hi / 10.0);
        let span = 10f64.powf(crate::figures::MAX_LOG_SPAN_DECADES);
        let lo = lo.max(hi / span);
        (lo, hi)
    } else {
        let (lo, hi) = match (a.is_finite(), b.is_finite()) {
            (true, true) => (a.min(b).clamp(-BIG, BIG), a.max(b).clamp(-BIG, BIG)),
            (true, false) => (a.clamp(-BIG, BIG), a.clamp(-BIG, BIG)),
            (false, true) => (b.clamp(-BIG, BIG), b.clamp(-BIG, BIG)),
            (false, false) => (0.0, 1.0),
        };
        // Not degenerate: a span of at least 1e-9 of the magnitude (and of 1e-300).
        let min_span = (lo.abs().max(hi.abs()) * 1e-9).max(1e-300);
        if hi - lo < min_span {
            let mid = 0.5 * (lo + hi);
            ((mid - min_span).max(-BIG), (mid + min_span).min(BIG))
        } else {
            (lo, hi)
        }
    }
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &Panel,
    compact: bool,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let font = if compact { 12 } else { 16 };
    let mut builder = ChartBuilder::on(area);
    builder
        .margin(if compact { 4 } else { 10 })
        .x_label_area_size(if compact { 22 } else { 40 })
        .y_label_area_size(if compact { 44 } else { 70 });
    if !panel.title.is_empty() {
        builder.caption(&panel.title, ("sans-serif", font));
    }
    let (x0, x1) = safe_range(panel.x_range, false);
    let (y0, y1) = safe_range(panel.y_range, panel.y_scale == YScale::Log);
    macro_rules! body {
        ($chart:expr) => {{
            let mut chart = $chart;
            let mut mesh = chart.configure_mesh();
            mesh.x_desc(panel.x_label.as_str())
                .y_desc(panel.y_label.as_str())
                .label_style(("sans-serif", font - 2));
            if compact {
                mesh.x_labels(4)
                    .y_labels(4)
                    .disable_x_mesh()
                    .disable_y_mesh();
            }
            let x_span = x1 - x0;
            let x_format = move |v: &f64| {
                if x_span >= 20.0 {
                    format!("{v:.0}")
                } else {
                    format!("{v:.2}")
                }
            };
            mesh.x_label_formatter(&x_format);
            // Linear ticks with as many decimals as the span needs (a ±0.3 V axis
            // is not labelled 0, 0, 0).
            let y_span = y1 - y0;
            let decimals = if y_span >= 20.0 {
                0
            } else {
                (1.0 - y_span.log10().floor()).clamp(1.0, 6.0) as usize
            };
            let y_format = move |v: &f64| match panel.y_scale {
                YScale::Log => format!("{v:.0e}"),
                // A tick at 0 that roundoff put at -1e-17 is "0", not "-0.0".
                YScale::Linear if v.abs() < 0.5 * 10f64.powi(-(decimals as i32)) => {
                    format!("{:.decimals$}", 0.0)
                }
                YScale::Linear => format!("{v:.decimals$}"),
            };
            mesh.y_label_formatter(&y_format);
            mesh.draw().map_err(err)?;
            for s in &panel.series {
                let points: Vec<(f64, f64)> =
                    s.x.iter()
                        .zip(&s.y)
                        .filter(|(x, y)| {
                            x.is_finite()
                                && y.is_finite()
                                && (panel.y_scale == YScale::Linear || **y > 0.0)
                        })
                        // Clamped into the axes, so no coordinate is far outside them.
                        .map(|(x, y)| (x.clamp(x0, x1), y.clamp(y0, y1)))
                        .collect();
                match s.kind {
                    SeriesKind::Measured => {
                        chart
                            .draw_series(LineSeries::new(
                                points,
                                MEASURED.stroke_width(if compact { 1 } else { 2 }),
                            ))
                            .map_err(err)?
                            .label(s.label.as_str())
                            .legend(|(x, y)| {
                                PathElement::new(
                                    vec![(x, y), (x + 20, y)],
                                    MEASURED.stroke_width(2),
                                )
                            });
                    }
                    SeriesKind::Model => {
                        chart
                            .draw_series(DashedLineSeries::new(
                                points,
                                6,
                                4,
                                MODEL.stroke_width(if compact { 1 } else { 2 }),
                            ))
                            .map_err(err)?
                            .label(s.label.as_str())
                            .legend(|(x, y)| {
                                PathElement::new(vec![(x, y), (x + 20, y)], MODEL.stroke_width(2))
                            });
                    }
                    SeriesKind::Values => {
                        chart
                            .draw_series(LineSeries::new(points.clone(), MEASURED.stroke_width(1)))
                            .map_err(err)?;
                        chart
                            .draw_series(
                                points.iter().map(|p| Circle::new(*p, 3, MEASURED.filled())),
                            )
                            .map_err(err)?
                            .label(s.label.as_str())
                            .legend(|(x, y)| Circle::new((x + 10, y), 3, MEASURED.filled()));
                    }
                }
            }
            if let Some((x, label)) = panel.marker_x.as_ref().filter(|(x, _)| x.is_finite()) {
                let x = &x.clamp(x0, x1);
                chart
                    .draw_series(DashedLineSeries::new(
                        vec![(*x, y0), (*x, y1)],
                        5,
                        5,
                        MODEL.stroke_width(1),
                    ))
                    .map_err(err)?
                    .label(label.as_str())
                    .legend(|(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], MODEL.stroke_width(1))
                    });
            }
            if let Some((y, label)) = panel.guide_y.as_ref().filter(|(y, _)| y.is_finite()) {
                let y = &y.clamp(y0, y1);
                chart
                    .draw_series(DashedLineSeries::new(
                        vec![(x0, *y), (x1, *y)],
                        5,
                        5,
                        GUIDE.stroke_width(1),
                    ))
                    .map_err(err)?
                    .label(label.as_str())
                    .legend(|(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], GUIDE.stroke_width(1))
                    });
            }
            if panel.legend || panel.marker_x.is_some() || panel.guide_y.is_some() {
                chart
                    .configure_series_labels()
                    .position(SeriesLabelPosition::UpperRight)
                    .label_font(("sans-serif", font - 2))
                    .border_style(BLACK)
                    .background_style(WHITE.mix(0.9))
                    .draw()
                    .map_err(err)?;
            }
        }};
    }
    match panel.y_scale {
        YScale::Log => body!(builder
            .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
            .map_err(err)?),
        YScale::Linear => body!(builder.build_cartesian_2d(x0..x1, y0..y1).map_err(err)?),
    }
    Ok(())
}

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, figure: &Figure) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    fonts();
    root.fill(&WHITE).map_err(err)?;
    let body = if figure.title.is_empty() {
        root.clone()
    } else {
        root.titled(&figure.title, ("sans-serif", 20))
            .map_err(err)?
    };
    let columns = figure.columns.max(1);
    let rows = figure.panels.len().div_ceil(columns).max(1);
    let compact = figure.panels.len() > 4;
    let areas = body.split_evenly((rows, columns));
    for (panel, area) in figure.panels.iter().zip(areas.iter()) {
        draw_panel(area, panel, compact)?;
    }
    root.present().map_err(err)?;
    Ok(())
}

/// The figure as SVG text.
///
/// # Errors
/// [`PlotError`] when plotters fails.
pub fn render_svg(figure: &Figure) -> Result<String, PlotError> {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, figure.size).into_drawing_area();
        draw(root, figure)?;
    }
    Ok(out)
}

/// The figure as a PNG file.
///
/// # Errors
/// [`PlotError`] when plotters fails or the file cannot be written.
pub fn render_png(figure: &Figure, path: &Path) -> Result<(), PlotError> {
    let root = BitMapBackend::new(path, figure.size).into_drawing_area();
    draw(root, figure)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::figures::singular_value_figure;

    use crate::figures::{frf_grid, frf_overlay};
    use era::frf::uniform_lines;
    use era::{Complex64, FrfData, Quantity};

    #[test]
    fn safe_ranges_are_finite_increasing_and_not_degenerate() {
        let cases = [
            (0.0, 0.0),
            (1.0, 1.0),
            (f64::NAN, f64::NAN),
            (f64::NEG_INFINITY, f64::INFINITY),
            (1e-320, 1.7e308),
            (1.7e308, 1.7e308),
            (-1.7e308, 1.7e308),
            (5.0, -5.0),
            (1e-300, 1e-300),
            (0.0, f64::MAX),
        ];
        for (a, b) in cases {
            for log in [false, true] {
                let (lo, hi) = safe_range((a, b), log);
                assert!(lo.is_finite() && hi.is_finite(), "{a} {b} {log}: {lo} {hi}");
                assert!(hi > lo, "{a} {b} {log}: {lo} {hi}");
                assert!(lo.abs() <= 1e300 && hi.abs() <= 1e300, "{a} {b} {log}");
                if log {
                    assert!(
                        lo > 0.0 && hi / lo >= 10.0 * (1.0 - 1e-12),
                        "{a} {b}: {lo} {hi}"
                    );
                    assert!(hi / lo <= 1.000_001e60, "{a} {b}: {lo} {hi}");
                }
            }
        }
        // Sane ranges pass through untouched (the figures of real data do not change).
        assert_eq!(safe_range((0.01, 10.0), true), (0.01, 10.0));
        assert_eq!(safe_range((-630.0, 0.0), false), (-630.0, 0.0));
    }

    fn frf(lines: usize, value: impl Fn(usize) -> Complex64) -> FrfData {
        FrfData::from_fn(
            uniform_lines(lines, 1.0),
            1,
            1,
            Quantity::Velocity,
            |_, _, k| value(k),
        )
        .unwrap()
    }

    #[test]
    fn hostile_figures_render_without_looping() {
        // A value of 1.7e308 made plotters loop forever (its log range rounded up to
        // 1e309 = inf); all-zero, all-equal, one-line, subnormal and huge-range data and
        // singular values up to 1e308 must all render.
        let sets = [
            frf(8, |k| {
                Complex64::new(if k == 3 { 1.7e308 } else { 1.0 }, 0.0)
            }),
            frf(8, |_| Complex64::new(0.0, 0.0)),
            frf(8, |_| Complex64::new(2.0, 0.0)),
            frf(2, |_| Complex64::new(1.0, 1.0)),
            frf(8, |k| {
                Complex64::new(f64::MAX / (k + 1) as f64, f64::MAX / 2.0)
            }),
            frf(8, |k| Complex64::new(5e-324 * k as f64, 0.0)),
            frf(8, |k| Complex64::new(10f64.powi(300 - 100 * k as i32), 0.0)),
        ];
        for m in &sets {
            let fig = frf_overlay(m, Some(m), 0, 0, true);
            render_svg(&fig).unwrap();
            render_svg(&frf_grid(m, None, false)).unwrap();
        }
        for sv in [
            vec![1e308, 1e307, 1.0, 1e-300],
            vec![f64::MAX, f64::MAX],
            vec![0.0, 0.0, 0.0],
            vec![1.0],
            vec![],
        ] {
            render_svg(&singular_value_figure(&sv, 1)).unwrap();
        }
    }

    #[test]
    fn svg_carries_titles_and_one_path_per_series() {
        let fig = singular_value_figure(&[1.0, 0.5, 0.1, 1e-3, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9], 4);
        let svg = render_svg(&fig).unwrap();
        assert!(svg.starts_with("<svg"));
        assert!(svg.contains("Hankel singular values"));
        assert!(svg.contains("4 states") && svg.contains("noise floor"));
        assert!(svg.contains("Index (states)"));
    }
}
