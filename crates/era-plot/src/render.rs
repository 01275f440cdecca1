//! Drawing a [`Figure`] with `plotters`, to SVG text or a PNG file.
//!
//! Two things are done here by hand, because neither plotters nor a well-kept small
//! crate does them for us:
//!
//! - **Thinning a curve to what the pixels show** ([`visible_points`]). A curve of `N`
//!   lines drawn `W` pixels wide needs at most four points per pixel column (the
//!   first, lowest, highest and last, "M4" aggregation: Jugel et al., *M4: a
//!   visualization-oriented time series data aggregation*, VLDB 2014), which keeps
//!   every peak and notch exactly; then the Ramer–Douglas–Peucker simplification
//!   (Douglas & Peucker, *Cartographica* 10(2), 1973) drops the points within
//!   [`SIMPLIFY_TOLERANCE_PX`] of the chord between their kept neighbours. Both are a
//!   few lines; the geometry crates that have RDP bring a large dependency tree for it.
//! - **Sharing styles in SVG** ([`compact_svg`]). Plotters writes each element's fill,
//!   stroke, width, opacity and font as attributes, and a dashed line as one element
//!   per dash. The SVG is rewritten line by line: the drawing attributes become a
//!   class (named by a hash of them, so that figures in one page agree), a polyline
//!   becomes a path of relative steps, and the model's curve is one path dashed by
//!   `stroke-dasharray`. A bitmap draws the dashes itself.
//!
//! A series is cut where a point is not drawable (NaN marks a gap, such as a wrapped
//! phase passing ±180°); a piece of one point is drawn as a dot.

use crate::figures::{log_tick_label, typeset_units, Figure, Panel, Series, SeriesKind, YScale};
use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::types::RangedCoordf64;
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

/// A figure that cannot be drawn is the program's failure, not the caller's.
impl era::error::InputError for PlotError {
    fn is_input_error(&self) -> bool {
        false
    }
}

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

/// A drawing backend's error as ours (every figure module maps plotters' errors
/// through it).
pub(crate) fn err(e: impl std::fmt::Display) -> PlotError {
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

/// The indices of the points of a polyline to draw, given their pixel positions:
/// per pixel column the first, lowest, highest and last point (so every peak and
/// notch survives, whatever the number of lines), then, of those, the ones that
/// deviate more than [`SIMPLIFY_TOLERANCE_PX`] from the straight line between their
/// kept neighbours (Ramer–Douglas–Peucker). The drawn curve differs from the full one
/// by under a pixel; a report of 64 overlays of 801 lines shrinks by about three.
pub fn visible_points(pixels: &[(i32, i32)]) -> Vec<usize> {
    let n = pixels.len();
    if n <= 2 {
        return (0..n).collect();
    }
    // Per pixel column: first, min, max, last, in order.
    let mut column_kept = Vec::with_capacity(n.min(4096));
    let mut start = 0;
    while start < n {
        let mut end = start + 1;
        while end < n && pixels[end].0 == pixels[start].0 {
            end += 1;
        }
        let run = start..end;
        let lo = run.clone().min_by_key(|&k| pixels[k].1).unwrap_or(start);
        let hi = run.clone().max_by_key(|&k| pixels[k].1).unwrap_or(start);
        let mut four = [start, lo, hi, end - 1];
        four.sort_unstable();
        for k in four {
            if column_kept.last() != Some(&k) {
                column_kept.push(k);
            }
        }
        start = end;
    }
    // Ramer–Douglas–Peucker on the kept points, with an explicit stack.
    let m = column_kept.len();
    let mut keep = vec![false; m];
    keep[0] = true;
    keep[m - 1] = true;
    let mut stack = vec![(0usize, m - 1)];
    while let Some((a, b)) = stack.pop() {
        if b <= a + 1 {
            continue;
        }
        let (pa, pb) = (pixels[column_kept[a]], pixels[column_kept[b]]);
        let (dx, dy) = ((pb.0 - pa.0) as f64, (pb.1 - pa.1) as f64);
        let length = dx.hypot(dy);
        let mut worst = (0.0f64, a);
        for (k, &index) in column_kept.iter().enumerate().take(b).skip(a + 1) {
            let p = pixels[index];
            let (ex, ey) = ((p.0 - pa.0) as f64, (p.1 - pa.1) as f64);
            let distance = if length > 0.0 {
                (ex * dy - ey * dx).abs() / length
            } else {
                ex.hypot(ey)
            };
            if distance > worst.0 {
                worst = (distance, k);
            }
        }
        if worst.0 > SIMPLIFY_TOLERANCE_PX {
            keep[worst.1] = true;
            stack.push((a, worst.1));
            stack.push((worst.1, b));
        }
    }
    column_kept
        .into_iter()
        .zip(keep)
        .filter_map(|(k, kept)| kept.then_some(k))
        .collect()
}

/// How far (pixels) a dropped point may lie from the drawn polyline.
pub const SIMPLIFY_TOLERANCE_PX: f64 = 0.5;

/// The legend mark of a dashed series: two short strokes, at `(x, y)`.
macro_rules! dashed_mark {
    ($x:expr, $y:expr, $style:expr) => {
        EmptyElement::at(($x, $y))
            + PathElement::new(vec![(0, 0), (8, 0)], $style)
            + PathElement::new(vec![(12, 0), (20, 0)], $style)
    };
}

/// A panel's chart: x linear, y linear or logarithmic.
type PanelChart<'a, DB, Y> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, Y>>;

/// How a panel is drawn: its axes' ranges (already through [`safe_range`]), the font
/// size, and the medium.
#[derive(Clone, Copy)]
struct Frame {
    x: (f64, f64),
    y: (f64, f64),
    font: i32,
    compact: bool,
    svg: bool,
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &Panel,
    compact: bool,
    svg: bool,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let font = if compact { 17 } else { 16 };
    let mut builder = ChartBuilder::on(area);
    builder
        .margin(if compact { 4 } else { 10 })
        .x_label_area_size(match (compact, panel.x_label.is_empty()) {
            (true, true) => 26,
            (true, false) => 44,
            (false, _) => 40,
        })
        .y_label_area_size(match (compact, panel.y_label.is_empty()) {
            (true, true) => 56,
            (true, false) => 76,
            (false, _) => 70,
        });
    // Room on the right for the last abscissa tick, centred on the axis's end.
    if compact {
        builder.margin_right(14);
    }
    if !panel.title.is_empty() {
        builder.caption(typeset_units(&panel.title), ("sans-serif", font));
    }
    let frame = Frame {
        x: safe_range(panel.x_range, false),
        y: safe_range(panel.y_range, panel.y_scale == YScale::Log),
        font,
        compact,
        svg,
    };
    let ((x0, x1), (y0, y1)) = (frame.x, frame.y);
    match panel.y_scale {
        YScale::Log => draw_chart(
            builder
                .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
                .map_err(err)?,
            panel,
            frame,
        ),
        YScale::Linear => draw_chart(
            builder.build_cartesian_2d(x0..x1, y0..y1).map_err(err)?,
            panel,
            frame,
        ),
    }
}

/// A panel's content on its chart: the mesh, each series, the marker and guide lines,
/// and the legend.
fn draw_chart<'a, DB, Y>(
    mut chart: PanelChart<'a, DB, Y>,
    panel: &Panel,
    frame: Frame,
) -> Result<(), PlotError>
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    draw_mesh(&mut chart, panel, frame)?;
    for s in &panel.series {
        if s.kind == SeriesKind::Values {
            draw_values(&mut chart, s, panel.y_scale, frame)?;
        } else {
            draw_curve(&mut chart, s, panel.y_scale, frame)?;
        }
    }
    draw_guides(&mut chart, panel, frame)?;
    if panel.legend || panel.marker_x.is_some() || panel.guide_y.is_some() {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font(("sans-serif", frame.font - 2))
            .border_style(BLACK)
            .background_style(WHITE.mix(0.9))
            .draw()
            .map_err(err)?;
    }
    Ok(())
}

/// The axes, their names and tick labels, and the grid (none when compact).
fn draw_mesh<'a, DB, Y>(
    chart: &mut PanelChart<'a, DB, Y>,
    panel: &Panel,
    frame: Frame,
) -> Result<(), PlotError>
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let ((x0, x1), (y0, y1)) = (frame.x, frame.y);
    let mut mesh = chart.configure_mesh();
    let (x_desc, y_desc) = (typeset_units(&panel.x_label), typeset_units(&panel.y_label));
    mesh.x_desc(x_desc.as_str())
        .y_desc(y_desc.as_str())
        .label_style(("sans-serif", frame.font - 2));
    if frame.compact {
        mesh.x_labels(4)
            .y_labels(4)
            .disable_x_mesh()
            .disable_y_mesh();
    } else {
        // One light line between labelled ones: the minor grid of every
        // overlay was most of a report's bytes.
        mesh.max_light_lines(1);
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
        YScale::Log => log_tick_label(*v),
        // A tick at 0 that roundoff put at -1e-17 is "0", not "-0.0".
        YScale::Linear if v.abs() < 0.5 * 10f64.powi(-(decimals as i32)) => {
            format!("{:.decimals$}", 0.0)
        }
        YScale::Linear => format!("{v:.decimals$}"),
    };
    mesh.y_label_formatter(&y_format);
    mesh.draw().map_err(err)
}

/// Whether a point can be drawn on a `scale` axis: finite, and positive on a log axis.
fn usable(x: f64, y: f64, scale: YScale) -> bool {
    x.is_finite() && y.is_finite() && (scale == YScale::Linear || y > 0.0)
}

/// A series of values: each drawable point a dot, joined by a thin line.
fn draw_values<'a, DB, Y>(
    chart: &mut PanelChart<'a, DB, Y>,
    s: &Series,
    scale: YScale,
    frame: Frame,
) -> Result<(), PlotError>
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let ((x0, x1), (y0, y1)) = (frame.x, frame.y);
    let points: Vec<(f64, f64)> =
        s.x.iter()
            .zip(&s.y)
            .filter(|(x, y)| usable(**x, **y, scale))
            .map(|(x, y)| (x.clamp(x0, x1), y.clamp(y0, y1)))
            .collect();
    chart
        .draw_series(LineSeries::new(points.clone(), MEASURED.stroke_width(1)))
        .map_err(err)?;
    chart
        .draw_series(points.iter().map(|p| Circle::new(*p, 3, MEASURED.filled())))
        .map_err(err)?
        .label(s.label.as_str())
        .legend(|(x, y)| Circle::new((x + 10, y), 3, MEASURED.filled()));
    Ok(())
}

/// A measured or model curve, cut where a point is not drawable (NaN marks a gap, e.g. a
/// wrapped phase's jump), each piece thinned to what the pixels show.
fn draw_curve<'a, DB, Y>(
    chart: &mut PanelChart<'a, DB, Y>,
    s: &Series,
    scale: YScale,
    frame: Frame,
) -> Result<(), PlotError>
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let ((x0, x1), (y0, y1)) = (frame.x, frame.y);
    let mut pieces: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
    for (x, y) in s.x.iter().zip(&s.y) {
        if usable(*x, *y, scale) {
            // Clamped into the axes, so no coordinate is far outside them.
            if let Some(p) = pieces.last_mut() {
                p.push((x.clamp(x0, x1), y.clamp(y0, y1)));
            }
        } else if pieces.last().is_some_and(|p| !p.is_empty()) {
            pieces.push(Vec::new());
        }
    }
    for (k, piece) in pieces.into_iter().enumerate() {
        let pixels: Vec<(i32, i32)> = piece.iter().map(|p| chart.backend_coord(p)).collect();
        let points: Vec<(f64, f64)> = visible_points(&pixels)
            .into_iter()
            .map(|k| piece[k])
            .collect();
        draw_piece(chart, s, points, k == 0, frame)?;
    }
    Ok(())
}

/// One piece of a curve (a dot when it is one point), with the series' legend entry
/// when it is the first.
fn draw_piece<'a, DB, Y>(
    chart: &mut PanelChart<'a, DB, Y>,
    s: &Series,
    points: Vec<(f64, f64)>,
    first: bool,
    frame: Frame,
) -> Result<(), PlotError>
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let (compact, svg) = (frame.compact, frame.svg);
    // A bitmap strokes a wide polyline as a polygon with mitred joins, and a
    // noisy measurement turning back within a pixel makes miters that shoot
    // far past its points (and the panel): measured curves are one pixel
    // wide there, drawn without joins. SVG viewers limit the miter.
    let width = if compact || (!svg && s.kind != SeriesKind::Model) {
        1
    } else {
        2
    };
    let colour = if s.kind == SeriesKind::Model {
        MODEL
    } else {
        MEASURED
    };
    let drawn = match s.kind {
        // A piece of one point (a noisy phase flipping across ±180°
        // line by line) is a dot, not an invisible one-point line.
        _ if points.len() == 1 => chart.draw_series(std::iter::once(Circle::new(
            points[0],
            width,
            colour.filled(),
        ))),
        SeriesKind::Model if !svg => chart.draw_series(DashedLineSeries::new(
            points,
            6,
            4,
            MODEL.stroke_width(width),
        )),
        // In SVG one polyline, dashed by the style sheet `compact_svg`
        // adds.
        SeriesKind::Model => chart.draw_series(LineSeries::new(points, MODEL.stroke_width(width))),
        _ => chart.draw_series(LineSeries::new(points, MEASURED.stroke_width(width))),
    }
    .map_err(err)?;
    // The legend entry once per series.
    if first {
        if s.kind == SeriesKind::Model {
            drawn
                .label(s.label.as_str())
                .legend(|(x, y)| dashed_mark!(x, y, MODEL.stroke_width(2)));
        } else {
            drawn.label(s.label.as_str()).legend(|(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], MEASURED.stroke_width(2))
            });
        }
    }
    Ok(())
}

/// The panel's vertical marker and horizontal guide, dashed across the axes, when set.
fn draw_guides<'a, DB, Y>(
    chart: &mut PanelChart<'a, DB, Y>,
    panel: &Panel,
    frame: Frame,
) -> Result<(), PlotError>
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let ((x0, x1), (y0, y1)) = (frame.x, frame.y);
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
            .legend(|(x, y)| dashed_mark!(x, y, MODEL.stroke_width(1)));
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
            .legend(|(x, y)| dashed_mark!(x, y, GUIDE.stroke_width(1)));
    }
    Ok(())
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    figure: &Figure,
    svg: bool,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    fonts();
    root.fill(&WHITE).map_err(err)?;
    let body = if figure.title.is_empty() {
        root.clone()
    } else {
        // A wide grid gets a title to match (20 px at 900 px wide, up to 32).
        root.titled(
            &typeset_units(&figure.title),
            ("sans-serif", (figure.size.0 / 60).clamp(20, 32)),
        )
        .map_err(err)?
    };
    let columns = figure.columns.max(1);
    let rows = figure.panels.len().div_ceil(columns).max(1);
    let compact = figure.panels.len() > 4;
    let areas = body.split_evenly((rows, columns));
    for (panel, area) in figure.panels.iter().zip(areas.iter()) {
        draw_panel(area, panel, compact, svg)?;
    }
    root.present().map_err(err)?;
    Ok(())
}

/// The drawing attributes [`compact_svg`] moves into a style sheet.
const STYLE_ATTRIBUTES: [&str; 8] = [
    "fill",
    "fill-opacity",
    "opacity",
    "stroke",
    "stroke-opacity",
    "stroke-width",
    "font-family",
    "font-size",
];

/// The dash pattern of the model's curve (drawn in red, #D62728), in the style sheet:
/// one polyline dashed by the browser instead of one polyline per dash.
pub const MODEL_DASHES: &str = "stroke-dasharray:6 4";

/// Plotters' SVG with shared styles: each element's drawing attributes (fill, stroke,
/// width, opacity, font) become a class named by a hash of their values, with one
/// rule per class in a `<style>` at the top. Figures inlined together in one page
/// then share their rules (the same style has the same class in every figure, so the
/// repeated rules agree), and each of thousands of elements carries one short class
/// instead of five attributes. Polylines of the model's colour are dashed there
/// ([`MODEL_DASHES`]). Font sizes are rounded to 0.1 px; nothing else changes.
pub fn compact_svg(svg: &str) -> String {
    let mut rules: Vec<(String, String)> = Vec::new();
    let mut body = String::with_capacity(svg.len());
    let mut head = String::new();
    for line in svg.split_inclusive('\n') {
        if line.starts_with("<svg") {
            head.push_str(line);
            continue;
        }
        match restyle(line) {
            Some((element, class, rule)) => {
                if !rules.iter().any(|(c, _)| *c == class) {
                    rules.push((class, rule));
                }
                body.push_str(&element);
            }
            None => body.push_str(line),
        }
    }
    let mut out = String::with_capacity(head.len() + body.len() + 64 * rules.len());
    out.push_str(&head);
    if !rules.is_empty() {
        out.push_str("<style>");
        for (class, rule) in &rules {
            out.push_str(&format!(".{class}{{{rule}}}"));
        }
        out.push_str("</style>\n");
    }
    out.push_str(&body);
    out
}

/// One element line with its drawing attributes replaced by a class: the new line,
/// the class and its CSS rule; `None` for a line that is not a single element tag.
fn restyle(line: &str) -> Option<(String, String, String)> {
    let rest = line.strip_prefix('<')?;
    let name_end = rest.find(' ')?;
    let name = &rest[..name_end];
    if !name.chars().all(|c| c.is_ascii_alphabetic()) {
        return None;
    }
    let mut attrs = &rest[name_end..];
    let mut geometry = String::new();
    let mut style: Vec<(&str, String)> = Vec::new();
    loop {
        attrs = attrs.trim_start();
        if attrs.is_empty() || attrs.starts_with('/') || attrs.starts_with('>') {
            break;
        }
        let eq = attrs.find("=\"")?;
        let key = &attrs[..eq];
        let value_start = eq + 2;
        let value_len = attrs[value_start..].find('"')?;
        let value = &attrs[value_start..value_start + value_len];
        if STYLE_ATTRIBUTES.contains(&key) {
            let value = match key {
                "font-size" => format!(
                    "{}px",
                    value
                        .parse::<f64>()
                        .map_or(value.to_string(), |v| format!("{v:.1}"))
                ),
                "stroke-width" => format!("{value}px"),
                _ => value.to_string(),
            };
            style.push((key, value));
        } else {
            geometry.push(' ');
            geometry.push_str(&attrs[..value_start + value_len + 1]);
        }
        attrs = &attrs[value_start + value_len + 1..];
    }
    if style.is_empty() {
        return None;
    }
    let mut rule: String = style
        .iter()
        .map(|(k, v)| format!("{k}:{v}"))
        .collect::<Vec<_>>()
        .join(";");
    let model_stroke = format!("#{:02X}{:02X}{:02X}", MODEL.0, MODEL.1, MODEL.2);
    if name == "polyline"
        && style
            .iter()
            .any(|(k, v)| *k == "stroke" && *v == model_stroke)
    {
        rule.push(';');
        rule.push_str(MODEL_DASHES);
    }
    // FNV-1a of the rule: the same style, the same class, in every figure.
    let hash = rule.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    });
    let class = format!("s{:08x}", hash as u32 ^ (hash >> 32) as u32);
    // A polyline becomes a path of relative moves: `M83 160l6 0 1-1` instead of
    // `83,160 89,160 90,159`, half the bytes for the same points.
    if name == "polyline" {
        if let Some(d) = geometry
            .strip_prefix(" points=\"")
            .and_then(|g| g.strip_suffix('"'))
            .and_then(relative_path)
        {
            return Some((
                format!("<path class=\"{class}\" d=\"{d}\"{attrs}"),
                class,
                rule,
            ));
        }
    }
    Some((
        format!("<{name} class=\"{class}\"{geometry}{attrs}"),
        class,
        rule,
    ))
}

/// SVG path data of a polyline's integer points (`x,y x,y …`): an absolute move to
/// the first, then relative line steps; `None` unless every coordinate is an integer.
fn relative_path(points: &str) -> Option<String> {
    let mut out = String::with_capacity(points.len() / 2 + 8);
    let mut previous: Option<(i64, i64)> = None;
    for pair in points.split_whitespace() {
        let (x, y) = pair.split_once(',')?;
        let (x, y) = (x.parse::<i64>().ok()?, y.parse::<i64>().ok()?);
        match previous {
            None => out.push_str(&format!("M{x} {y}l")),
            Some((px, py)) => {
                for (k, v) in [x - px, y - py].into_iter().enumerate() {
                    // No separator before a minus sign, nor before the first step.
                    if v >= 0 && !(k == 0 && out.ends_with('l')) {
                        out.push(' ');
                    }
                    out.push_str(&v.to_string());
                }
            }
        }
        previous = Some((x, y));
    }
    if out.ends_with('l') {
        out.pop();
    }
    (!out.is_empty()).then_some(out)
}

/// The figure as SVG text.
///
/// # Errors
/// [`PlotError`] when plotters fails.
pub fn render_svg(figure: &Figure) -> Result<String, PlotError> {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, figure.size).into_drawing_area();
        draw(root, figure, true)?;
    }
    Ok(compact_svg(&out))
}

/// The figure as a PNG file.
///
/// # Errors
/// [`PlotError`] when plotters fails or the file cannot be written.
pub fn render_png(figure: &Figure, path: &Path) -> Result<(), PlotError> {
    let root = BitMapBackend::new(path, figure.size).into_drawing_area();
    draw(root, figure, false)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::figures::singular_value_figure;

    use crate::figures::{frf_grid, frf_overlay};
    use era::data::frf::uniform_lines;
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
            let view = crate::figures::FrfView::by_index(1, 1);
            let fig = frf_overlay(m, Some(m), 0, 0, &view);
            render_svg(&fig).unwrap();
            render_svg(&frf_grid(m, None, &view)).unwrap();
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

    #[test]
    fn thinning_keeps_every_peak_and_drops_what_a_pixel_hides() {
        // 4000 points over 400 pixel columns, a one-point spike and a one-point notch.
        let pixels: Vec<(i32, i32)> = (0..4000)
            .map(|k| {
                let y = match k {
                    1234 => 5,
                    3001 => 395,
                    _ => 200 + ((k as f64 * 0.01).sin() * 50.0) as i32,
                };
                (k / 10, y)
            })
            .collect();
        let kept = visible_points(&pixels);
        assert!(kept.contains(&1234) && kept.contains(&3001));
        assert!(kept.contains(&0) && kept.contains(&3999));
        assert!(kept.windows(2).all(|w| w[0] < w[1]));
        assert!(kept.len() < 4000 / 3, "{} kept", kept.len());
        // A straight line keeps its two ends only.
        let line: Vec<(i32, i32)> = (0..500).map(|k| (k, 2 * k)).collect();
        assert_eq!(visible_points(&line), vec![0, 499]);
        // Every dropped point lies within the tolerance of the drawn polyline.
        for w in kept.windows(2) {
            let (a, b) = (pixels[w[0]], pixels[w[1]]);
            for p in &pixels[w[0]..w[1]] {
                let (dx, dy) = ((b.0 - a.0) as f64, (b.1 - a.1) as f64);
                let (ex, ey) = ((p.0 - a.0) as f64, (p.1 - a.1) as f64);
                let len = dx.hypot(dy);
                let d = if len > 0.0 {
                    (ex * dy - ey * dx).abs() / len
                } else {
                    ex.hypot(ey)
                };
                // Within a column the first/min/max/last are kept, so the rest lie
                // between them; across columns RDP bounds the distance.
                assert!(d <= SIMPLIFY_TOLERANCE_PX + 1.0 || a.0 == b.0, "{d}");
            }
        }
    }

    #[test]
    fn svg_shares_styles_and_the_legend_draws_the_model_dashed() {
        let m = frf(200, |k| Complex64::new(1.0 + k as f64, 1.0));
        let view = crate::figures::FrfView::by_index(1, 1);
        let svg = render_svg(&frf_overlay(&m, Some(&m), 0, 0, &view)).unwrap();
        assert!(svg.contains("<style>") && svg.contains(MODEL_DASHES));
        // The model: one polyline per panel plus the legend's two strokes, all of the
        // dashed class; no drawing attribute is left on an element.
        let dashed = svg
            .split("<style>")
            .nth(1)
            .and_then(|s| s.split("</style>").next())
            .unwrap_or("")
            .split('.')
            .filter(|rule| rule.contains(MODEL_DASHES))
            .map(|rule| rule.split('{').next().unwrap_or("").to_string())
            .collect::<Vec<_>>();
        assert_eq!(dashed.len(), 1, "{dashed:?}");
        let marker = format!(r#"<path class="{}""#, dashed[0]);
        let model: Vec<&str> = svg.lines().filter(|l| l.starts_with(&marker)).collect();
        assert_eq!(model.len(), 2 + 2, "{} dashed paths", model.len());
        assert!(!svg.contains(r#" stroke=""#) && !svg.contains(r#" font-family=""#));
        // The legend's model mark: two 8 px strokes with a gap, beside "ERA model".
        let short = model.iter().filter(|l| l.contains("l8 0\"")).count();
        assert_eq!(short, 2);
        assert!(svg.contains("ERA model"));
        // The same figure as PNG draws too.
        let dir = std::env::temp_dir().join(format!("era-plot-legend-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        render_png(&frf_overlay(&m, Some(&m), 0, 0, &view), &dir.join("a.png")).unwrap();
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn figure_labels_carry_the_data_units() {
        let m = frf(50, |k| Complex64::new(1.0 + k as f64, 1.0));
        let mut view = crate::figures::FrfView::by_index(1, 1);
        view.unit = crate::figures::FrfUnits {
            response: Some("m/s^2".into()),
            force: Some("N".into()),
        }
        .label();
        let svg = render_svg(&frf_overlay(&m, Some(&m), 0, 0, &view)).unwrap();
        assert!(svg.contains("|G| (m/s²)/N"), "units typeset");
        assert!(!svg.contains("lbf") && !svg.contains("in/s") && !svg.contains("s^2"));
        let grid = render_svg(&frf_grid(&m, Some(&m), &view)).unwrap();
        assert!(grid.contains("|G| (m/s²)/N") && grid.contains("Frequency (Hz)"));
        // Log ticks in superscripts, never `1e-2`.
        assert!(
            svg.contains("10⁰") || svg.contains("10¹"),
            "superscript ticks"
        );
        assert!(!svg.contains(">1e"), "an e-notation tick");
    }

    #[test]
    fn polylines_become_relative_paths_with_the_same_points() {
        assert_eq!(
            relative_path("83,160 89,160 90,159 90,170").as_deref(),
            Some("M83 160l6 0 1-1 0 11")
        );
        assert_eq!(relative_path("5,5").as_deref(), Some("M5 5"));
        assert_eq!(relative_path("1.5,2 3,4"), None);
        let (element, _, rule) =
            restyle(r##"<polyline fill="none" opacity="1" stroke="#1F77B4" stroke-width="2" points="1,2 3,1 "/>"##)
                .unwrap();
        assert!(
            element.starts_with("<path class=\"s") && element.ends_with(r#" d="M1 2l2-1"/>"#),
            "{element}"
        );
        assert_eq!(rule, "fill:none;opacity:1;stroke:#1F77B4;stroke-width:2px");
    }
}
