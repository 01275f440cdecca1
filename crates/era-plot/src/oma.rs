//! The two figures of an output-only identification besides the stabilization diagram:
//! the singular values of the output spectrum at each line with the identified modes
//! marked (the quick look of frequency-domain decomposition, FDD), and the MAC matrix
//! of the physical modes' shapes (AutoMAC: 1 on the diagonal, near 0 off it for
//! well-separated, well-observed modes).

use crate::render::{safe_range, PlotError};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

const FIRST: RGBColor = RGBColor(31, 119, 180);
const OTHER: RGBColor = RGBColor(120, 150, 190);
const PHYSICAL: RGBColor = RGBColor(214, 39, 40);
const OTHER_MODE: RGBColor = RGBColor(255, 127, 14);

use crate::render::err;

/// The spectral singular values and the modes to mark.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralPlot {
    /// Title.
    pub title: String,
    /// Ordinate label.
    pub y_label: String,
    /// The lines, Hz.
    pub lines_hz: Vec<f64>,
    /// Per singular value index (largest first), its value at each line.
    pub curves: Vec<Vec<f64>>,
    /// The modes: frequency (Hz) and whether judged physical.
    pub modes: Vec<(f64, bool)>,
    /// Size in pixels.
    pub size: (u32, u32),
}

impl SpectralPlot {
    /// From the singular values of each line (`per_line[k]`, largest first) at
    /// `lines_hz`; at most `max_curves` of them are drawn.
    pub fn new(
        title: &str,
        lines_hz: &[f64],
        per_line: &[Vec<f64>],
        modes: Vec<(f64, bool)>,
        max_curves: usize,
    ) -> Self {
        let k = per_line.first().map_or(0, Vec::len).min(max_curves);
        let curves = (0..k)
            .map(|c| {
                per_line
                    .iter()
                    .map(|v| v.get(c).copied().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect();
        SpectralPlot {
            title: title.to_string(),
            y_label: "Singular values of the output spectrum".into(),
            lines_hz: lines_hz.to_vec(),
            curves,
            modes,
            size: (1200, 560),
        }
    }
}

fn draw_spectral<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    plot: &SpectralPlot,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    crate::render::fonts();
    root.fill(&WHITE).map_err(err)?;
    let top = plot.lines_hz.iter().copied().fold(0.0, f64::max);
    let (x0, x1) = safe_range((0.0, top), false);
    let positive = plot.curves.iter().flatten().copied();
    let (y0, y1) = safe_range(crate::figures::log_range(positive), true);
    let mut chart = ChartBuilder::on(&root)
        .caption(&plot.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(75)
        .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("Frequency (Hz)")
        .y_desc(crate::figures::typeset_units(&plot.y_label))
        .label_style(("sans-serif", 14))
        .y_label_formatter(&|v: &f64| crate::figures::log_tick_label(*v))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(err)?;
    // The first curve (in the legend first), the others, then the first again on top.
    let n = plot.curves.len();
    let order: Vec<(usize, bool)> = (0..n.min(1))
        .map(|k| (k, true))
        .chain((1..n).map(|k| (k, k == 1)))
        .chain((0..n.min(1)).map(|k| (k, false)))
        .collect();
    for (k, labelled) in order {
        let curve = &plot.curves[k];
        let points: Vec<(f64, f64)> = plot
            .lines_hz
            .iter()
            .zip(curve)
            .filter(|(f, v)| f.is_finite() && v.is_finite() && **v > 0.0)
            .map(|(f, v)| (*f, v.clamp(y0, y1)))
            .collect();
        let (colour, width) = if k == 0 { (FIRST, 2) } else { (OTHER, 1) };
        let series = chart
            .draw_series(LineSeries::new(points, colour.stroke_width(width)))
            .map_err(err)?;
        match (k, labelled) {
            (0, true) => {
                series.label("first singular value").legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], FIRST.stroke_width(2))
                });
            }
            (_, true) => {
                series.label("the others").legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], OTHER.stroke_width(1))
                });
            }
            _ => {}
        }
    }
    for (physical, colour, label) in [
        (true, PHYSICAL, "physical mode"),
        (false, OTHER_MODE, "mode not judged physical"),
    ] {
        let at: Vec<f64> = plot
            .modes
            .iter()
            .filter(|m| m.1 == physical && m.0 >= x0 && m.0 <= x1)
            .map(|m| m.0)
            .collect();
        if at.is_empty() {
            continue;
        }
        for &f in &at {
            chart
                .draw_series(DashedLineSeries::new(
                    vec![(f, y0), (f, y1)],
                    4,
                    4,
                    colour.mix(0.7).stroke_width(1),
                ))
                .map_err(err)?;
        }
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(x0, y0), (x0, y0)],
                colour.stroke_width(1),
            )))
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| {
                EmptyElement::at((x, y))
                    + PathElement::new(vec![(0, 0), (8, 0)], colour.stroke_width(1))
                    + PathElement::new(vec![(12, 0), (20, 0)], colour.stroke_width(1))
            });
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font(("sans-serif", 13))
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

/// The spectral singular values as SVG text.
///
/// # Errors
/// [`PlotError`] when plotters fails.
pub fn spectral_svg(plot: &SpectralPlot) -> Result<String, PlotError> {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, plot.size).into_drawing_area();
        draw_spectral(root, plot)?;
    }
    Ok(crate::render::compact_svg(&out))
}

/// The spectral singular values as a PNG file.
///
/// # Errors
/// [`PlotError`] when plotters fails or the file cannot be written.
pub fn spectral_png(plot: &SpectralPlot, path: &Path) -> Result<(), PlotError> {
    let root = BitMapBackend::new(path, plot.size).into_drawing_area();
    draw_spectral(root, plot)
}

/// A MAC matrix: one row and column per mode, values from 0 to 1.
#[derive(Debug, Clone, PartialEq)]
pub struct MacPlot {
    /// Title.
    pub title: String,
    /// One label per mode (e.g. its frequency).
    pub labels: Vec<String>,
    /// `values[i][j]`, from 0 to 1.
    pub values: Vec<Vec<f64>>,
    /// Size in pixels.
    pub size: (u32, u32),
}

impl MacPlot {
    /// The AutoMAC of `shapes` (one complex vector per mode), labelled by `labels`.
    pub fn auto(title: &str, labels: Vec<String>, shapes: &[Vec<era::Complex64>]) -> Self {
        let values = shapes
            .iter()
            .map(|a| {
                shapes
                    .iter()
                    .map(|b| era::modal::indicators::mac(a, b))
                    .collect()
            })
            .collect();
        let side = (160 + 42 * labels.len() as u32).clamp(420, 1100);
        MacPlot {
            title: title.to_string(),
            labels,
            values,
            size: (side + 60, side),
        }
    }
}

/// White at 0 to dark blue at 1.
fn shade(v: f64) -> RGBColor {
    let t = v.clamp(0.0, 1.0);
    let mix = |lo: f64, hi: f64| (lo + (hi - lo) * t).round() as u8;
    RGBColor(mix(255.0, 8.0), mix(255.0, 48.0), mix(255.0, 107.0))
}

fn draw_mac<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    plot: &MacPlot,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    crate::render::fonts();
    root.fill(&WHITE).map_err(err)?;
    let n = plot.labels.len().max(1);
    let mut chart = ChartBuilder::on(&root)
        .caption(&plot.title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(70)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..n as f64, 0.0..n as f64)
        .map_err(err)?;
    let label = |v: &f64| {
        let k = (v - 0.5).round();
        if (v - 0.5 - k).abs() < 1e-6 && k >= 0.0 && (k as usize) < plot.labels.len() {
            plot.labels[k as usize].clone()
        } else {
            String::new()
        }
    };
    // Rows from the top: mode 1 at the top left.
    let y_label = |v: &f64| label(&(n as f64 - v));
    chart
        .configure_mesh()
        .disable_mesh()
        .x_labels(2 * n + 1)
        .y_labels(2 * n + 1)
        .x_label_formatter(&label)
        .y_label_formatter(&y_label)
        .x_desc("Mode (Hz)")
        .y_desc("Mode (Hz)")
        .label_style(("sans-serif", 12))
        .draw()
        .map_err(err)?;
    let text = n <= 20;
    for (i, row) in plot.values.iter().enumerate() {
        for (j, &v) in row.iter().enumerate() {
            let (x, y) = (j as f64, (n - 1 - i) as f64);
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(x, y), (x + 1.0, y + 1.0)],
                    shade(v).filled(),
                )))
                .map_err(err)?;
            if text {
                let colour = if v > 0.5 { WHITE } else { BLACK };
                chart
                    .draw_series(std::iter::once(Text::new(
                        format!("{v:.2}"),
                        (x + 0.5, y + 0.5),
                        ("sans-serif", 11).into_font().color(&colour).pos(
                            plotters::style::text_anchor::Pos::new(
                                plotters::style::text_anchor::HPos::Center,
                                plotters::style::text_anchor::VPos::Center,
                            ),
                        ),
                    )))
                    .map_err(err)?;
            }
        }
    }
    root.present().map_err(err)?;
    Ok(())
}

/// The MAC matrix as SVG text.
///
/// # Errors
/// [`PlotError`] when plotters fails.
pub fn mac_svg(plot: &MacPlot) -> Result<String, PlotError> {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, plot.size).into_drawing_area();
        draw_mac(root, plot)?;
    }
    Ok(crate::render::compact_svg(&out))
}

/// The MAC matrix as a PNG file.
///
/// # Errors
/// [`PlotError`] when plotters fails or the file cannot be written.
pub fn mac_png(plot: &MacPlot, path: &Path) -> Result<(), PlotError> {
    let root = BitMapBackend::new(path, plot.size).into_drawing_area();
    draw_mac(root, plot)
}

#[cfg(test)]
mod tests {
    use super::*;
    use era::Complex64;

    #[test]
    fn the_automac_is_one_on_its_diagonal_and_symmetric() {
        let c = |re: f64, im: f64| Complex64::new(re, im);
        let shapes = vec![
            vec![c(1.0, 0.0), c(0.5, 0.1), c(-0.2, 0.0)],
            vec![c(0.1, 0.0), c(-1.0, 0.0), c(0.4, 0.2)],
            vec![c(0.3, 0.0), c(0.3, 0.0), c(1.0, 0.0)],
        ];
        let plot = MacPlot::auto("t", vec!["a".into(), "b".into(), "c".into()], &shapes);
        for i in 0..3 {
            assert!((plot.values[i][i] - 1.0).abs() < 1e-12);
            for j in 0..3 {
                assert!((plot.values[i][j] - plot.values[j][i]).abs() < 1e-12);
                assert!(plot.values[i][j] <= 1.0 + 1e-12);
            }
        }
        assert!(plot.values[0][1] < 0.5);
        let svg = mac_svg(&plot).unwrap();
        assert!(svg.contains("<svg"));
    }

    #[test]
    fn the_spectral_plot_keeps_the_curves_asked_for_in_order() {
        let lines: Vec<f64> = (0..50).map(|k| k as f64).collect();
        let per_line: Vec<Vec<f64>> = lines.iter().map(|f| vec![3.0 + f, 2.0, 1.0]).collect();
        let plot = SpectralPlot::new("t", &lines, &per_line, vec![(10.0, true), (20.0, false)], 2);
        assert_eq!(plot.curves.len(), 2);
        assert_eq!(plot.curves[0][4], 7.0);
        assert_eq!(plot.curves[1], vec![2.0; 50]);
        assert!(spectral_svg(&plot).unwrap().contains("<svg"));
    }
}
