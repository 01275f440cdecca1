//! Figure specifications: series and axis ranges computed from the data.

use era::{Complex64, FrfData};

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SeriesKind {
    /// Measured data: solid.
    Measured,
    /// Model: dashed, contrasting colour.
    Model,
    /// Singular values: points joined by a line.
    Values,
}

/// One curve.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Ordinates (positive for a log axis; non-positive points are skipped there).
    pub y: Vec<f64>,
    /// Style.
    pub kind: SeriesKind,
}

/// Ordinate scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum YScale {
    /// Linear.
    Linear,
    /// Base-10 logarithmic.
    Log,
}

/// One chart.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Title above the chart (may be empty).
    pub title: String,
    /// Abscissa label with unit.
    pub x_label: String,
    /// Ordinate label with unit.
    pub y_label: String,
    /// Ordinate scale.
    pub y_scale: YScale,
    /// Abscissa range.
    pub x_range: (f64, f64),
    /// Ordinate range.
    pub y_range: (f64, f64),
    /// Curves.
    pub series: Vec<Series>,
    /// A vertical marker (e.g. the chosen model order), with its label.
    pub marker_x: Option<(f64, String)>,
    /// A horizontal guide (e.g. the noise floor), with its label.
    pub guide_y: Option<(f64, String)>,
    /// Draw a legend.
    pub legend: bool,
}

/// A figure: panels laid out in a grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// Overall title (may be empty).
    pub title: String,
    /// Panels, row by row.
    pub panels: Vec<Panel>,
    /// Panels per row.
    pub columns: usize,
    /// Size in pixels.
    pub size: (u32, u32),
}

/// Decade-rounded range covering the positive values (at least one decade).
pub fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for v in values.filter(|v| v.is_finite() && *v > 0.0) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if hi.is_nan() || hi <= 0.0 {
        return (0.1, 1.0);
    }
    // Decades clamped to ±MAX_DECADE, so that 1.7e308 cannot round up to 1e309 = inf
    // (plotters then loops forever looking for tick marks), and at most
    // MAX_LOG_SPAN_DECADES of them: values far below the top are clipped, not drawn.
    let b = hi.log10().ceil().clamp(-MAX_DECADE + 1.0, MAX_DECADE);
    let a = lo.log10().floor().clamp(-MAX_DECADE, MAX_DECADE - 1.0);
    let a = a.max(b - MAX_LOG_SPAN_DECADES);
    let b = if b <= a { a + 1.0 } else { b };
    (10f64.powf(a), 10f64.powf(b))
}

/// The largest decade a log axis reaches: `1e300`, well inside `f64` after plotters
/// rounds outwards.
pub const MAX_DECADE: f64 = 300.0;

/// The most decades one log axis spans.
pub const MAX_LOG_SPAN_DECADES: f64 = 60.0;

/// Range rounded outwards to multiples of `step` (at least one step).
pub fn stepped_range(values: impl Iterator<Item = f64>, step: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return (-step, step);
    }
    // Values beyond ±1e300 are clamped, so the rounded range stays finite.
    let (lo, hi) = (lo.clamp(-1e300, 1e300), hi.clamp(-1e300, 1e300));
    let (a, b) = ((lo / step).floor() * step, (hi / step).ceil() * step);
    (a, if b <= a { a + step } else { b })
}

/// `phase` moved, line by line, to the multiple of 360° nearest `reference`: a noisy
/// measured phase shown on the model's branch, where unwrapping the noise on its own
/// would wander off in 360° steps.
pub fn phase_on_branch_of(phase: &[f64], reference: &[f64]) -> Vec<f64> {
    phase
        .iter()
        .zip(reference)
        .map(|(p, r)| p + 360.0 * ((r - p) / 360.0).round())
        .collect()
}

/// Phase in degrees, unwrapped along the lines (jumps over 180° are folded back).
pub fn unwrapped_phase_deg(values: &[Complex64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(values.len());
    let mut offset = 0.0;
    let mut previous: Option<f64> = None;
    for v in values {
        let raw = v.arg().to_degrees();
        if let Some(p) = previous {
            let mut d = raw + offset - p;
            while d > 180.0 {
                offset -= 360.0;
                d -= 360.0;
            }
            while d < -180.0 {
                offset += 360.0;
                d += 360.0;
            }
        }
        let value = raw + offset;
        out.push(value);
        previous = Some(value);
    }
    out
}

/// The unit of an FRF of this quantity in the thesis's units (per lbf).
fn unit(frf: &FrfData) -> &'static str {
    match frf.quantity() {
        era::Quantity::Acceleration => "(in/s²)/lbf",
        era::Quantity::Velocity => "(in/s)/lbf",
        era::Quantity::Displacement => "in/lbf",
    }
}

/// Thesis-style title of a pair (1-based), marked when collocated.
pub fn pair_title(output: usize, input: usize, collocated: bool) -> String {
    let base = format!(
        "Measurement {}, Excitation Actuator {}",
        output + 1,
        input + 1
    );
    if collocated {
        format!("{base} (collocated)")
    } else {
        base
    }
}

/// Measured and model FRF of one pair: log magnitude over frequency, and unwrapped
/// phase in degrees (thesis `plotfrfs.m`), the measured phase on the model's branch
/// ([`phase_on_branch_of`]). `measured` should be the processed
/// measurement (after the same integrations as the model); lines whose measured value is
/// exactly zero (the zeroed low end) are left out.
///
/// # Panics
/// If the two FRF sets differ in shape or the pair is out of range.
#[track_caller]
pub fn frf_overlay(
    measured: &FrfData,
    model: Option<&FrfData>,
    output: usize,
    input: usize,
    collocated: bool,
) -> Figure {
    if let Some(m) = model {
        assert_eq!(
            (measured.outputs(), measured.inputs(), measured.lines()),
            (m.outputs(), m.inputs(), m.lines()),
            "model and measurement shapes"
        );
    }
    let f = measured.frequency_hz();
    let keep: Vec<usize> = (0..f.len())
        .filter(|&k| measured.pair(output, input)[k].norm() > 0.0)
        .collect();
    let pick = |g: &[Complex64]| -> Vec<Complex64> { keep.iter().map(|&k| g[k]).collect() };
    let gm = pick(measured.pair(output, input));
    let gx = model.map(|m| pick(m.pair(output, input)));
    let x: Vec<f64> = keep.iter().map(|&k| f[k]).collect();
    let x_range = (0.0, f[f.len() - 1]);
    let mag = |g: &[Complex64]| g.iter().map(|v| v.norm()).collect::<Vec<f64>>();
    let mm = mag(&gm);
    let mx = gx.as_deref().map(mag);
    let px = gx.as_deref().map(unwrapped_phase_deg);
    let pm = match &px {
        Some(p) => phase_on_branch_of(&unwrapped_phase_deg(&gm), p),
        None => unwrapped_phase_deg(&gm),
    };
    let series = |a: &[f64], b: Option<&Vec<f64>>| {
        let mut out = vec![Series {
            label: "measured".into(),
            x: x.clone(),
            y: a.to_vec(),
            kind: SeriesKind::Measured,
        }];
        if let Some(b) = b {
            out.push(Series {
                label: "ERA model".into(),
                x: x.clone(),
                y: b.clone(),
                kind: SeriesKind::Model,
            });
        }
        out
    };
    let all = |a: &[f64], b: Option<&Vec<f64>>| {
        a.iter()
            .chain(b.into_iter().flatten())
            .copied()
            .collect::<Vec<f64>>()
    };
    let magnitude = Panel {
        title: String::new(),
        x_label: "Frequency (Hz)".into(),
        y_label: format!("|G| {}", unit(measured)),
        y_scale: YScale::Log,
        x_range,
        y_range: log_range(all(&mm, mx.as_ref()).into_iter()),
        series: series(&mm, mx.as_ref()),
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
        y_range: stepped_range(all(&pm, px.as_ref()).into_iter(), 90.0),
        series: series(&pm, px.as_ref()),
        marker_x: None,
        guide_y: None,
        legend: false,
    };
    Figure {
        title: pair_title(output, input, collocated),
        panels: vec![magnitude, phase],
        columns: 1,
        size: (900, 640),
    }
}

/// A q×p overview: magnitude of every pair, measured and (when given) model.
///
/// # Panics
/// As [`frf_overlay`].
#[track_caller]
pub fn frf_grid(measured: &FrfData, model: Option<&FrfData>, collocated: bool) -> Figure {
    let (q, p) = (measured.outputs(), measured.inputs());
    let mut panels = Vec::with_capacity(q * p);
    for i in 0..q {
        for j in 0..p {
            let mut panel = frf_overlay(measured, model, i, j, collocated && i == j)
                .panels
                .swap_remove(0);
            panel.title = format!(
                "Y{} / F{}{}",
                i + 1,
                j + 1,
                if collocated && i == j { " (col.)" } else { "" }
            );
            panel.legend = false;
            panel.x_label = String::new();
            panel.y_label = String::new();
            panels.push(panel);
        }
    }
    let cell = if p <= 3 { 320 } else { 220 };
    let title = if model.is_some() {
        "All pairs: measured (solid) and ERA model (dashed), magnitude"
    } else {
        "All pairs: measured magnitude"
    };
    Figure {
        title: title.into(),
        panels,
        columns: p,
        size: (cell * p as u32 + 40, (cell * 3 / 4) * q as u32 + 60),
    }
}

/// The noise floor of a singular-value tail when one is evident: at least 5 values
/// after the order, spread within one decade (10th to 90th percentile); the median.
pub fn noise_floor(singular_values: &[f64], order: usize) -> Option<f64> {
    let mut tail: Vec<f64> = singular_values
        .iter()
        .skip(order)
        .copied()
        .filter(|v| *v > 0.0)
        .collect();
    if tail.len() < 5 {
        return None;
    }
    tail.sort_by(f64::total_cmp);
    let at = |q: f64| tail[((tail.len() - 1) as f64 * q).round() as usize];
    (at(0.9) / at(0.1) < 10.0).then(|| at(0.5))
}

/// Singular values on a log scale, the chosen order marked, and the noise floor where
/// one is evident ([`noise_floor`]).
pub fn singular_value_figure(singular_values: &[f64], order: usize) -> Figure {
    let x: Vec<f64> = (1..=singular_values.len()).map(|k| k as f64).collect();
    let floor = noise_floor(singular_values, order);
    let panel = Panel {
        title: String::new(),
        x_label: "Index (states)".into(),
        y_label: "Singular value of H0".into(),
        y_scale: YScale::Log,
        x_range: (0.0, singular_values.len().max(1) as f64 + 1.0),
        y_range: log_range(singular_values.iter().copied().chain(floor)),
        series: vec![Series {
            label: "singular values".into(),
            x,
            y: singular_values.to_vec(),
            kind: SeriesKind::Values,
        }],
        marker_x: Some((order as f64 + 0.5, format!("{order} states"))),
        guide_y: floor.map(|v| (v, "noise floor".into())),
        legend: false,
    };
    Figure {
        title: format!(
            "Hankel singular values ({} shown, order {order})",
            singular_values.len()
        ),
        panels: vec![panel],
        columns: 1,
        size: (900, 520),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use era::frf::uniform_lines;
    use era::Quantity;

    fn sample() -> FrfData {
        FrfData::from_fn(
            uniform_lines(50, 1.0),
            2,
            3,
            Quantity::Velocity,
            |i, j, k| {
                if k == 0 {
                    Complex64::new(0.0, 0.0)
                } else {
                    Complex64::from_polar((1 + i + j) as f64 / k as f64, -0.2 * k as f64)
                }
            },
        )
        .unwrap()
    }

    #[test]
    fn overlay_has_two_panels_two_series_and_ranges_from_the_data() {
        let m = sample();
        let fig = frf_overlay(&m, Some(&m), 1, 2, false);
        assert_eq!(fig.title, "Measurement 2, Excitation Actuator 3");
        assert_eq!(fig.panels.len(), 2);
        for p in &fig.panels {
            assert_eq!(p.series.len(), 2);
            assert_eq!(p.series[0].x.len(), 49); // the zero line is left out
            assert_eq!(p.x_range, (0.0, 49.0));
        }
        // |G| runs from 4/49 to 4: decades 0.01 .. 10.
        assert_eq!(fig.panels[0].y_range, (0.01, 10.0));
        assert_eq!(fig.panels[0].y_scale, YScale::Log);
        // Phase −0.2 k rad, unwrapped: −11.5° down to −561°: −630 .. 0 in 90° steps.
        assert_eq!(fig.panels[1].y_range, (-630.0, 0.0));
        assert!(frf_overlay(&m, Some(&m), 0, 0, true)
            .title
            .ends_with("(collocated)"));
    }

    #[test]
    fn measured_phase_follows_the_model_branch() {
        let model = [0.0, -100.0, -200.0, -300.0];
        let noisy = [2.0, -95.0 + 360.0, -210.0 - 720.0, -290.0 + 360.0];
        assert_eq!(
            phase_on_branch_of(&noisy, &model),
            vec![2.0, -95.0, -210.0, -290.0]
        );
    }

    #[test]
    fn phase_unwraps_across_the_branch_cut() {
        let g: Vec<Complex64> = (0..40)
            .map(|k| Complex64::from_polar(1.0, -0.3 * k as f64))
            .collect();
        let p = unwrapped_phase_deg(&g);
        for w in p.windows(2) {
            assert!((w[1] - w[0] + 0.3f64.to_degrees()).abs() < 1e-9);
        }
    }

    #[test]
    fn without_a_model_each_panel_has_the_measurement_only() {
        let m = sample();
        let fig = frf_overlay(&m, None, 0, 1, false);
        assert!(fig.panels.iter().all(|p| p.series.len() == 1));
        assert_eq!(fig.panels[0].y_range, (0.01, 10.0));
        assert_eq!(
            frf_grid(&m, None, false).title,
            "All pairs: measured magnitude"
        );
    }

    #[test]
    fn grid_has_one_panel_per_pair() {
        let m = sample();
        let fig = frf_grid(&m, Some(&m), false);
        assert_eq!((fig.panels.len(), fig.columns), (6, 3));
        assert_eq!(fig.panels[5].title, "Y2 / F3");
    }

    #[test]
    fn singular_values_mark_the_order_and_an_evident_floor() {
        let mut sv: Vec<f64> = (0..8).map(|k| 10f64.powi(-k)).collect();
        sv.extend([2e-9, 1.5e-9, 1.2e-9, 1e-9, 0.9e-9, 0.8e-9]);
        let fig = singular_value_figure(&sv, 8);
        let p = &fig.panels[0];
        assert_eq!(p.series[0].y.len(), 14);
        assert_eq!(p.marker_x.as_ref().unwrap().0, 8.5);
        let floor = p.guide_y.as_ref().unwrap().0;
        assert!((0.9e-9..=1.2e-9).contains(&floor));
        assert_eq!(p.y_range, (1e-10, 1.0));
        // A tail spread over decades has no evident floor.
        let steep: Vec<f64> = (0..20).map(|k| 10f64.powi(-k)).collect();
        assert!(noise_floor(&steep, 8).is_none());
    }
}
