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
fn fonts() {
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
    let (x0, x1) = panel.x_range;
    let (y0, y1) = panel.y_range;
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
            let y_format = |v: &f64| match panel.y_scale {
                YScale::Log => format!("{v:.0e}"),
                YScale::Linear => format!("{v:.0}"),
            };
            mesh.y_label_formatter(&y_format);
            mesh.draw().map_err(err)?;
            for s in &panel.series {
                let points: Vec<(f64, f64)> =
                    s.x.iter()
                        .zip(&s.y)
                        .filter(|(_, y)| {
                            y.is_finite() && (panel.y_scale == YScale::Linear || **y > 0.0)
                        })
                        .map(|(x, y)| (*x, *y))
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
            if let Some((x, label)) = &panel.marker_x {
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
            if let Some((y, label)) = &panel.guide_y {
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
