//! The stabilization diagram: every pole of every scanned order against frequency, marked
//! by how it compares with the previous order, over the CMIF (the singular values of the
//! FRF matrix at each line) on a second, logarithmic axis. Physical modes show as
//! vertical columns of stable poles; the modes the automatic choice kept are marked by
//! dashed lines.

use crate::render::{safe_range, PlotError};
use era::data::identification::Stabilization;
use era::modal::stabilization::PoleStatus;
use plotters::chart::DualCoordChartContext;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

const NEW: RGBColor = RGBColor(170, 170, 170);
const FREQ: RGBColor = RGBColor(31, 119, 180);
const FREQ_DAMP: RGBColor = RGBColor(255, 127, 14);
const STABLE: RGBColor = RGBColor(44, 160, 44);
const CHOSEN: RGBColor = RGBColor(214, 39, 40);
const CMIF: RGBColor = RGBColor(90, 90, 90);

/// What the diagram shows, computed from a scan.
#[derive(Debug, Clone, PartialEq)]
pub struct StabilizationPlot {
    /// Title.
    pub title: String,
    /// Frequency axis, Hz.
    pub frequency_range: (f64, f64),
    /// Order axis.
    pub order_range: (f64, f64),
    /// (frequency Hz, order, status) of every pole in the frequency range.
    pub poles: Vec<(f64, f64, PoleStatus)>,
    /// Frequencies of the modes judged physical, Hz.
    pub physical_hz: Vec<f64>,
    /// CMIF: line frequencies and, per singular value index, its values.
    pub cmif: (Vec<f64>, Vec<Vec<f64>>),
    /// Size in pixels.
    pub size: (u32, u32),
}

impl StabilizationPlot {
    /// From a scan, over the fitted band of the identification; `lines_hz` are the
    /// frequencies of the CMIF's lines.
    pub fn new(
        title: &str,
        st: &Stabilization,
        band_hz: (f64, f64),
        lines_hz: &[f64],
        physical_hz: Vec<f64>,
    ) -> Self {
        let (lo, hi) = band_hz;
        let poles = st
            .scan
            .poles
            .iter()
            .filter(|p| p.frequency_hz >= lo && p.frequency_hz <= hi)
            .map(|p| (p.frequency_hz, p.order as f64, p.status))
            .collect();
        let k = st.cmif.first().map_or(0, Vec::len);
        let mut curves = vec![Vec::with_capacity(lines_hz.len()); k];
        for line in &st.cmif {
            for (c, v) in curves.iter_mut().zip(line) {
                c.push(*v);
            }
        }
        let first = *st.scan.orders.first().unwrap_or(&0) as f64;
        let last = *st.scan.orders.last().unwrap_or(&1) as f64;
        let pad = ((last - first) * 0.03).max(1.0);
        StabilizationPlot {
            title: title.to_string(),
            frequency_range: (lo, hi),
            order_range: (first - pad, last + pad),
            poles,
            physical_hz,
            cmif: (lines_hz.to_vec(), curves),
            size: (1200, 700),
        }
    }
}

use crate::render::err;

/// The diagram's chart: poles on (frequency, order), the CMIF on a secondary log axis.
type Diagram<'a, DB> = DualCoordChartContext<
    'a,
    DB,
    Cartesian2d<RangedCoordf64, RangedCoordf64>,
    Cartesian2d<RangedCoordf64, LogCoord<f64>>,
>;

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    plot: &StabilizationPlot,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    crate::render::fonts();
    root.fill(&WHITE).map_err(err)?;
    let (x0, x1) = safe_range(plot.frequency_range, false);
    let (y0, y1) = safe_range(plot.order_range, false);
    let positive = plot
        .cmif
        .1
        .iter()
        .flatten()
        .copied()
        .filter(|v| v.is_finite() && *v > 0.0);
    let (c0, c1) = crate::figures::log_range(positive);
    let (c0, c1) = safe_range((c0, c1), true);
    let mut chart = ChartBuilder::on(&root)
        .caption(&plot.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(65)
        .right_y_label_area_size(75)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?
        .set_secondary_coord(x0..x1, (c0..c1).log_scale());
    draw_axes(&mut chart)?;
    draw_cmif(&mut chart, plot, (x0, x1), (c0, c1))?;
    draw_physical(&mut chart, plot, (x0, x1), (y0, y1))?;
    draw_poles(&mut chart, plot, (x0, x1), (y0, y1))?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .label_font(("sans-serif", 13))
        .border_style(BLACK)
        // See-through enough that poles under the legend still show.
        .background_style(WHITE.mix(0.65))
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

/// Frequency and order on the primary axes, the CMIF's decades on the right.
fn draw_axes<'a, DB: DrawingBackend + 'a>(chart: &mut Diagram<'a, DB>) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    chart
        .configure_mesh()
        .x_desc("Frequency (Hz)")
        .y_desc("Model order (states)")
        .label_style(("sans-serif", 14))
        .y_label_formatter(&|v: &f64| format!("{v:.0}"))
        .x_label_formatter(&|v: &f64| format!("{v}"))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(err)?;
    chart
        .configure_secondary_axes()
        .y_desc("CMIF: singular values of the FRF matrix")
        .label_style(("sans-serif", 14))
        .y_label_formatter(&|v: &f64| crate::figures::log_tick_label(*v))
        .draw()
        .map_err(err)
}

/// The CMIF curves on the right axis, the first one darker and in the legend.
fn draw_cmif<'a, DB: DrawingBackend + 'a>(
    chart: &mut Diagram<'a, DB>,
    plot: &StabilizationPlot,
    (x0, x1): (f64, f64),
    (c0, c1): (f64, f64),
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    for (k, curve) in plot.cmif.1.iter().enumerate() {
        let points: Vec<(f64, f64)> = plot
            .cmif
            .0
            .iter()
            .zip(curve)
            .filter(|(f, v)| **f >= x0 && **f <= x1 && v.is_finite() && **v > 0.0)
            .map(|(f, v)| (*f, v.clamp(c0, c1)))
            .collect();
        let style = if k == 0 {
            CMIF.stroke_width(1)
        } else {
            CMIF.mix(0.45).stroke_width(1)
        };
        let series = chart
            .draw_secondary_series(LineSeries::new(points, style))
            .map_err(err)?;
        if k == 0 {
            series
                .label("CMIF (right axis)")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], CMIF.stroke_width(1)));
        }
    }
    Ok(())
}

/// A dashed vertical line at each physical mode in the band, and its legend entry.
fn draw_physical<'a, DB: DrawingBackend + 'a>(
    chart: &mut Diagram<'a, DB>,
    plot: &StabilizationPlot,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    for &f in &plot.physical_hz {
        if f >= x0 && f <= x1 {
            chart
                .draw_series(DashedLineSeries::new(
                    vec![(f, y0), (f, y1)],
                    4,
                    4,
                    CHOSEN.mix(0.6).stroke_width(1),
                ))
                .map_err(err)?;
        }
    }
    chart
        .draw_series(std::iter::once(PathElement::new(
            vec![(x0, y0), (x0, y0)],
            CHOSEN.mix(0.6).stroke_width(1),
        )))
        .map_err(err)?
        .label("physical mode (automatic choice)")
        // Dashed, as the lines are drawn.
        .legend(|(x, y)| {
            EmptyElement::at((x, y))
                + PathElement::new(vec![(0, 0), (8, 0)], CHOSEN.stroke_width(1))
                + PathElement::new(vec![(12, 0), (20, 0)], CHOSEN.stroke_width(1))
        });
    Ok(())
}

/// The poles, one marker per status (new, stable in frequency, … and damping, … and
/// shape), each status one legend entry.
fn draw_poles<'a, DB: DrawingBackend + 'a>(
    chart: &mut Diagram<'a, DB>,
    plot: &StabilizationPlot,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let groups = [
        (PoleStatus::New, "new", NEW),
        (PoleStatus::Frequency, "stable in frequency", FREQ),
        (PoleStatus::FrequencyDamping, "... and damping", FREQ_DAMP),
        (PoleStatus::Stable, "... and shape (stable)", STABLE),
    ];
    for (status, label, colour) in groups {
        let points: Vec<(f64, f64)> = plot
            .poles
            .iter()
            .filter(|p| p.2 == status)
            .map(|p| (p.0.clamp(x0, x1), p.1.clamp(y0, y1)))
            .collect();
        let series = match status {
            PoleStatus::New => chart.draw_series(
                points
                    .iter()
                    .map(|p| Cross::new(*p, 3, colour.stroke_width(1)).into_dyn()),
            ),
            PoleStatus::Frequency => chart.draw_series(
                points
                    .iter()
                    .map(|p| Circle::new(*p, 3, colour.stroke_width(1)).into_dyn()),
            ),
            PoleStatus::FrequencyDamping => chart.draw_series(
                points
                    .iter()
                    .map(|p| TriangleMarker::new(*p, 4, colour.filled()).into_dyn()),
            ),
            PoleStatus::Stable => chart.draw_series(
                points
                    .iter()
                    .map(|p| Circle::new(*p, 3, colour.filled()).into_dyn()),
            ),
        }
        .map_err(err)?;
        series.label(label).legend(move |(x, y)| match status {
            PoleStatus::New => Cross::new((x + 10, y), 3, colour.stroke_width(1)).into_dyn(),
            PoleStatus::Frequency => Circle::new((x + 10, y), 3, colour.stroke_width(1)).into_dyn(),
            PoleStatus::FrequencyDamping => {
                TriangleMarker::new((x + 10, y), 4, colour.filled()).into_dyn()
            }
            PoleStatus::Stable => Circle::new((x + 10, y), 3, colour.filled()).into_dyn(),
        });
    }
    Ok(())
}

/// The diagram as SVG text.
///
/// # Errors
/// [`PlotError`] when plotters fails.
pub fn stabilization_svg(plot: &StabilizationPlot) -> Result<String, PlotError> {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, plot.size).into_drawing_area();
        draw(root, plot)?;
    }
    Ok(crate::render::compact_svg(&out))
}

/// The diagram as a PNG file.
///
/// # Errors
/// [`PlotError`] when plotters fails or the file cannot be written.
pub fn stabilization_png(plot: &StabilizationPlot, path: &Path) -> Result<(), PlotError> {
    let root = BitMapBackend::new(path, plot.size).into_drawing_area();
    draw(root, plot)
}
