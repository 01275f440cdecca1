//! Figures for `era`: FRF overlays (thesis Figs. 5.1–5.11 and Appendices A–I) in the
//! data's units with wrapped phase by default, the singular-value plot of the thesis's
//! `cut` option, a q×p overview grid (wrapped when tall), coherence, and a
//! self-contained HTML report that says what went in; and the tracks of a fleet's modes
//! over time ([`track`]).
//!
//! Plotting stays out of the numeric core. A figure is first a [`Figure`]: panels with
//! their series and axis ranges, computed from the data by pure functions that tests can
//! check. [`render_svg`] and [`render_png`] then draw it with `plotters`. Text is drawn
//! with DejaVu Sans embedded from the `dejavu` crate, so no system font is needed.
//! [`report::report_html`] puts everything into one file with inline SVG.

pub mod compare;
pub mod figures;
pub mod oma;
pub mod render;
pub mod report;
pub mod shapes;
pub mod stabilization;
pub mod track;
pub mod viewer;

pub use figures::{
    coherence_grid, frf_grid, frf_overlay, singular_value_figure, Figure, FrfUnits, FrfView,
    PairSelection, Panel, PhaseView, Series, SeriesKind, YScale,
};
pub use render::{render_png, render_svg, PlotError};
