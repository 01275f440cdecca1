//! What the shape figures of an identification's report show: the AutoMAC heat map and
//! the complexity of each shape as polar plots, of the physical modes (every mode when
//! none is judged physical). [`super::figures::write_shape_figures`] writes them, and
//! with a geometry each mode in three views (`shapes/mode_NN.svg/png`, not inlined in
//! the report: its viewer draws the same three views from its own data).

use era::data::identification::Identification;
use era::Complex64;
use era_plot::oma::MacPlot;
use era_plot::shapes::{ComplexityPanel, ComplexityPlot};

/// The deflection of the three views: a tenth of the structure's size, as the viewer's
/// default amplitude.
pub const AMPLITUDE: f64 = 0.1;

/// A figure of the report's own: anchor, heading, caption and SVG.
pub struct Section {
    pub id: &'static str,
    pub heading: String,
    pub caption: String,
    pub svg: String,
}

impl Section {
    /// The report's view of it.
    pub fn view(&self) -> era_plot::report::ReportSection<'_> {
        era_plot::report::ReportSection {
            id: self.id,
            heading: &self.heading,
            caption: &self.caption,
            svg: &self.svg,
        }
    }
}

/// The modes the MAC and complexity figures show, by index: the physical ones, or every
/// mode when none is judged physical; and whether they are the physical ones.
pub fn shown_modes(found: &Identification) -> (Vec<usize>, bool) {
    let physical: Vec<usize> = (0..found.modal.modes.len())
        .filter(|&k| found.quality.get(k).is_some_and(|q| q.physical))
        .collect();
    if physical.is_empty() {
        ((0..found.modal.modes.len()).collect(), false)
    } else {
        (physical, true)
    }
}

/// Each shown mode's complexity panel, its MPC the identification's indicator (or the
/// shape's own when the mode has no quality entry).
pub fn complexity_plot(found: &Identification) -> Option<ComplexityPlot> {
    let (shown, physical) = shown_modes(found);
    if shown.is_empty() {
        return None;
    }
    let panels = shown
        .iter()
        .map(|&k| {
            let m = &found.modal.modes[k];
            let mpc = found.quality.get(k).map_or_else(
                || era::modal::indicators::mpc(&m.shape),
                |q| q.indicators.mpc,
            );
            ComplexityPanel::new(
                &format!("Mode {}: {:.4} Hz", k + 1, m.frequency_hz),
                &m.shape,
                mpc,
            )
        })
        .collect();
    let title = if physical {
        "Complexity of the physical modes' shapes (each entry / the largest)"
    } else {
        "Complexity of the shapes (each entry / the largest)"
    };
    Some(ComplexityPlot::new(title, panels))
}

/// The AutoMAC of the shown modes, when there are two or more.
pub fn automac_plot(found: &Identification) -> Option<MacPlot> {
    let (shown, physical) = shown_modes(found);
    let (labels, shapes): (Vec<String>, Vec<Vec<Complex64>>) = shown
        .iter()
        .map(|&k| {
            let m = &found.modal.modes[k];
            (format!("{:.1}", m.frequency_hz), m.shape.clone())
        })
        .unzip();
    let title = if physical {
        "AutoMAC of the physical modes"
    } else {
        "AutoMAC of the modes"
    };
    (labels.len() >= 2).then(|| MacPlot::auto(title, labels, &shapes))
}
