//! Static pictures of the mode shapes, for a test report: each mode on the test
//! geometry in three orthographic views ([`ThreeView`]: front x–z, side y–z, top x–y,
//! the undeformed structure in grey under the deformed one in colour), and the
//! complexity of each shape as small polar plots ([`ComplexityPlot`]: each entry a
//! vector in the complex plane, MPC in the panel's title).
//!
//! Both are drawn with `plotters`, as the other figures are, to SVG text and PNG files.
//! The three views take the viewer's data ([`crate::viewer::ShapeView`]), so the
//! pictures and the animated viewer show the same displacements.

use crate::render::{safe_range, PlotError};
use crate::viewer::ShapeView;
use era::Complex64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

const DEFORMED: RGBColor = RGBColor(31, 78, 156);
const UNDEFORMED: RGBColor = RGBColor(175, 175, 175);
const UNMEASURED: RGBColor = RGBColor(140, 140, 140);

use crate::render::err;

/// The three views: their names and the global axes they show (horizontal, vertical).
pub const VIEWS: [(&str, usize, usize); 3] = [
    ("front (x–z)", 0, 2),
    ("side (y–z)", 1, 2),
    ("top (x–y)", 0, 1),
];

/// One mode on the geometry, seen from the front, the side and the top.
#[derive(Debug, Clone, PartialEq)]
pub struct ThreeView {
    /// Title (the mode's label).
    pub title: String,
    /// Undeformed node positions.
    pub nodes: Vec<[f64; 3]>,
    /// Deformed node positions: `nodes + amplitude · size · Re(u)` at the largest
    /// deflection (the phase the viewer starts at).
    pub deformed: Vec<[f64; 3]>,
    /// Segments, as node index pairs.
    pub segments: Vec<(usize, usize)>,
    /// Whether a channel sits on each node (a node without one is a hollow dot).
    pub measured: Vec<bool>,
    /// Size in pixels.
    pub size: (u32, u32),
}

/// The diagonal of the box around `nodes` (1 when they are all at one point).
fn extent(nodes: &[[f64; 3]]) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in nodes {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let d = (0..3).map(|a| (hi[a] - lo[a]).powi(2)).sum::<f64>().sqrt();
    if d.is_finite() && d > 0.0 {
        d
    } else {
        1.0
    }
}

impl ThreeView {
    /// Mode `mode` of `view`, its largest displacement `amplitude` (a share, e.g. 0.1)
    /// of the structure's size; `None` when there is no such mode.
    pub fn new(view: &ShapeView, mode: usize, amplitude: f64) -> Option<Self> {
        let m = view.modes.get(mode)?;
        let scale = amplitude * extent(&view.nodes);
        let deformed = view
            .nodes
            .iter()
            .zip(&m.displacement)
            .map(|(p, u)| match u {
                Some(u) => [
                    p[0] + scale * u[0].re,
                    p[1] + scale * u[1].re,
                    p[2] + scale * u[2].re,
                ],
                None => *p,
            })
            .collect();
        Some(ThreeView {
            title: m.label.clone(),
            nodes: view.nodes.clone(),
            deformed,
            segments: view.segments.clone(),
            measured: m.displacement.iter().map(Option::is_some).collect(),
            size: (1200, 460),
        })
    }

    /// The range of each view's axes: both positions (undeformed and deformed) inside,
    /// padded, and widened to the panel's aspect so that a metre is as long across as
    /// up (`aspect` = width / height of the plotting area).
    fn ranges(&self, h: usize, v: usize, aspect: f64) -> ((f64, f64), (f64, f64)) {
        let span = |a: usize| {
            let all = self.nodes.iter().chain(&self.deformed).map(|p| p[a]);
            let lo = all.clone().fold(f64::INFINITY, f64::min);
            let hi = all.fold(f64::NEG_INFINITY, f64::max);
            (lo, hi)
        };
        let ((x0, x1), (y0, y1)) = (span(h), span(v));
        let pad = 0.06 * extent(&self.nodes);
        let (mut w, mut t) = (x1 - x0 + 2.0 * pad, y1 - y0 + 2.0 * pad);
        if w / t < aspect {
            w = t * aspect;
        } else {
            t = w / aspect;
        }
        let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        (
            safe_range((cx - w / 2.0, cx + w / 2.0), false),
            safe_range((cy - t / 2.0, cy + t / 2.0), false),
        )
    }
}

const AXES: [&str; 3] = ["x", "y", "z"];

fn draw_three<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    plot: &ThreeView,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    crate::render::fonts();
    root.fill(&WHITE).map_err(err)?;
    let root = root.titled(&plot.title, ("sans-serif", 18)).map_err(err)?;
    let panels = root.split_evenly((1, 3));
    for (area, &(name, h, v)) in panels.iter().zip(VIEWS.iter()) {
        let (w, t) = area.dim_in_pixel();
        // The plotting area: the panel less its caption, labels and margins.
        let aspect = (f64::from(w) - 70.0).max(10.0) / (f64::from(t) - 75.0).max(10.0);
        let ((x0, x1), (y0, y1)) = plot.ranges(h, v, aspect);
        let mut chart = ChartBuilder::on(area)
            .caption(name, ("sans-serif", 15))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(40)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_labels(5)
            .y_labels(5)
            .x_desc(AXES[h])
            .y_desc(AXES[v])
            .label_style(("sans-serif", 11))
            .draw()
            .map_err(err)?;
        let at = |p: &[f64; 3]| (p[h], p[v]);
        for (positions, colour, width) in
            [(&plot.nodes, UNDEFORMED, 1), (&plot.deformed, DEFORMED, 2)]
        {
            chart
                .draw_series(plot.segments.iter().filter_map(|&(a, b)| {
                    let (pa, pb) = (positions.get(a)?, positions.get(b)?);
                    Some(PathElement::new(
                        vec![at(pa), at(pb)],
                        colour.stroke_width(width),
                    ))
                }))
                .map_err(err)?;
        }
        chart
            .draw_series(plot.deformed.iter().zip(&plot.measured).map(|(p, &m)| {
                if m {
                    Circle::new(at(p), 3, DEFORMED.filled())
                } else {
                    Circle::new(at(p), 2, UNMEASURED.stroke_width(1))
                }
            }))
            .map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}

/// The three views as SVG text.
///
/// # Errors
/// [`PlotError`] when plotters fails.
pub fn three_view_svg(plot: &ThreeView) -> Result<String, PlotError> {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, plot.size).into_drawing_area();
        draw_three(root, plot)?;
    }
    Ok(crate::render::compact_svg(&out))
}

/// The three views as a PNG file.
///
/// # Errors
/// [`PlotError`] when plotters fails or the file cannot be written.
pub fn three_view_png(plot: &ThreeView, path: &Path) -> Result<(), PlotError> {
    let root = BitMapBackend::new(path, plot.size).into_drawing_area();
    draw_three(root, plot)
}

/// One shape in the complex plane.
#[derive(Debug, Clone, PartialEq)]
pub struct ComplexityPanel {
    /// Title (`12.35 Hz`).
    pub label: String,
    /// The modal phase collinearity shown in the title, as the identification's
    /// indicator gives it.
    pub mpc: f64,
    /// Each entry of the shape divided by its largest entry (so that one is 1 and
    /// none is longer): `(re, im)`.
    pub points: Vec<(f64, f64)>,
}

/// The complexity of several shapes: one polar panel each, in rows.
#[derive(Debug, Clone, PartialEq)]
pub struct ComplexityPlot {
    /// Title.
    pub title: String,
    /// The panels, in order.
    pub panels: Vec<ComplexityPanel>,
    /// Panels per row.
    pub columns: usize,
    /// Size in pixels.
    pub size: (u32, u32),
}

/// The most panels drawn (the rest are left out, and the title says so).
pub const MAX_PANELS: usize = 48;

impl ComplexityPanel {
    /// The panel of `shape`, titled `label`, with the indicator's `mpc`.
    pub fn new(label: &str, shape: &[Complex64], mpc: f64) -> Self {
        let top = shape
            .iter()
            .copied()
            .filter(|c| c.is_finite())
            .max_by(|a, b| a.norm().total_cmp(&b.norm()))
            .unwrap_or_default();
        let points = shape
            .iter()
            .map(|c| {
                if top.norm() > 0.0 && c.is_finite() {
                    let v = c / top;
                    (v.re, v.im)
                } else {
                    (0.0, 0.0)
                }
            })
            .collect();
        ComplexityPanel {
            label: label.to_string(),
            mpc,
            points,
        }
    }
}

impl ComplexityPlot {
    /// The plot of `panels` (at most [`MAX_PANELS`]), six to a row.
    pub fn new(title: &str, mut panels: Vec<ComplexityPanel>) -> Self {
        let mut title = title.to_string();
        if panels.len() > MAX_PANELS {
            title.push_str(&format!(" (the first {MAX_PANELS} of {})", panels.len()));
            panels.truncate(MAX_PANELS);
        }
        let columns = panels.len().clamp(1, 6);
        let rows = panels.len().div_ceil(columns).max(1);
        ComplexityPlot {
            title,
            panels,
            columns,
            size: (200 * columns as u32 + 20, 210 * rows as u32 + 40),
        }
    }
}

fn draw_complexity<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    plot: &ComplexityPlot,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    crate::render::fonts();
    root.fill(&WHITE).map_err(err)?;
    let root = root.titled(&plot.title, ("sans-serif", 17)).map_err(err)?;
    let rows = plot.panels.len().div_ceil(plot.columns).max(1);
    let areas = root.split_evenly((rows, plot.columns));
    let circle: Vec<(f64, f64)> = (0..=72)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / 72.0;
            (t.cos(), t.sin())
        })
        .collect();
    for (area, panel) in areas.iter().zip(&plot.panels) {
        // A circle drawn round: the ranges widened to the plotting area's aspect (the
        // panel less its margins and caption).
        let (w, h) = area.dim_in_pixel();
        let aspect = (f64::from(w) - 12.0).max(10.0) / (f64::from(h) - 32.0).max(10.0);
        let (rx, ry) = (1.1 * aspect.max(1.0), 1.1 * (1.0 / aspect).max(1.0));
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!("{}, MPC {:.3}", panel.label, panel.mpc),
                ("sans-serif", 12),
            )
            .margin(6)
            .build_cartesian_2d(-rx..rx, -ry..ry)
            .map_err(err)?;
        let guide = UNDEFORMED.stroke_width(1);
        chart
            .draw_series(std::iter::once(PathElement::new(circle.clone(), guide)))
            .map_err(err)?;
        chart
            .draw_series([
                PathElement::new(vec![(-1.0, 0.0), (1.0, 0.0)], guide),
                PathElement::new(vec![(0.0, -1.0), (0.0, 1.0)], guide),
            ])
            .map_err(err)?;
        chart
            .draw_series(panel.points.iter().map(|&(re, im)| {
                PathElement::new(vec![(0.0, 0.0), (re, im)], DEFORMED.stroke_width(2))
            }))
            .map_err(err)?;
        chart
            .draw_series(
                panel
                    .points
                    .iter()
                    .map(|&p| Circle::new(p, 2, DEFORMED.filled())),
            )
            .map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}

/// The complexity plot as SVG text.
///
/// # Errors
/// [`PlotError`] when plotters fails.
pub fn complexity_svg(plot: &ComplexityPlot) -> Result<String, PlotError> {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, plot.size).into_drawing_area();
        draw_complexity(root, plot)?;
    }
    Ok(crate::render::compact_svg(&out))
}

/// The complexity plot as a PNG file.
///
/// # Errors
/// [`PlotError`] when plotters fails or the file cannot be written.
pub fn complexity_png(plot: &ComplexityPlot, path: &Path) -> Result<(), PlotError> {
    let root = BitMapBackend::new(path, plot.size).into_drawing_area();
    draw_complexity(root, plot)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viewer::ShapeMode;

    fn c(re: f64, im: f64) -> Complex64 {
        Complex64::new(re, im)
    }

    /// A square frame of four nodes; node 3 has no channel.
    fn view(z: f64) -> ShapeView {
        let u = |v: f64| Some([c(0.0, 0.0), c(0.0, 0.0), c(v, 0.0)]);
        ShapeView {
            nodes: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            segments: vec![(0, 1), (1, 2), (2, 3), (3, 0)],
            modes: vec![ShapeMode {
                label: "Mode 1: test".into(),
                displacement: vec![u(z), u(-z), u(1.0), None],
            }],
            not_drawn: Vec::new(),
        }
    }

    #[test]
    fn the_three_views_have_three_panels_and_move_with_the_shape() {
        let a = ThreeView::new(&view(0.5), 0, 0.1).unwrap();
        // The deflection is along z, scaled to a tenth of the diagonal √2.
        let d = 0.1 * 2f64.sqrt();
        assert!((a.deformed[2][2] - d).abs() < 1e-12);
        assert!((a.deformed[0][2] - 0.5 * d).abs() < 1e-12);
        assert_eq!(a.deformed[3], a.nodes[3]);
        assert_eq!(a.measured, vec![true, true, true, false]);
        let svg = three_view_svg(&a).unwrap();
        for (name, _, _) in VIEWS {
            assert!(svg.contains(name), "no panel {name}");
        }
        assert!(svg.contains("Mode 1: test"));
        let b = three_view_svg(&ThreeView::new(&view(-0.5), 0, 0.1).unwrap()).unwrap();
        assert_ne!(svg, b, "another shape, the same picture");
        assert!(ThreeView::new(&view(0.5), 1, 0.1).is_none());
    }

    #[test]
    fn the_complexity_panel_scales_to_the_largest_entry_and_keeps_the_mpc() {
        let shape = [c(0.0, 2.0), c(0.0, -1.0), c(0.1, 0.5)];
        let mpc = era::modal::indicators::mpc(&shape);
        let panel = ComplexityPanel::new("5.00 Hz", &shape, mpc);
        assert_eq!(panel.points[0], (1.0, 0.0));
        assert!((panel.points[1].0 + 0.5).abs() < 1e-12);
        assert_eq!(panel.mpc, mpc);
        let plot = ComplexityPlot::new("t", vec![panel; 8]);
        assert_eq!((plot.columns, plot.panels.len()), (6, 8));
        let svg = complexity_svg(&plot).unwrap();
        assert!(svg.contains(&format!("MPC {mpc:.3}")));
        let many = ComplexityPlot::new("t", vec![plot.panels[0].clone(); MAX_PANELS + 2]);
        assert_eq!(many.panels.len(), MAX_PANELS);
        assert!(many.title.contains("of 50"));
    }
}
