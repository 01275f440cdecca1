//! What the automatic path's benches and examples share: the options `era identify FILE
//! --states auto` runs with on a measured-FRF file, and the physical modes of a result.
//! Included by path (`#[path = "../benches/support/sets.rs"]` from an example).

#![allow(dead_code)]

use era::data::identification::Identification;
use era::identify::{EraOptions, ModelDomain, Order};
use era::pipeline::realize::DirectTerm;

/// The measured preset's preprocessing on a CSV of accelerances (no integration, padding
/// or zeroed lines; `D = Y0`; a continuous model) at the automatic order.
pub fn measured_auto() -> EraOptions {
    let mut o = EraOptions::thesis_dta();
    o.integrations = 0;
    o.zero_lines = 0;
    o.pad_to = 0;
    o.direct_term = DirectTerm::FirstMarkov;
    o.domain = ModelDomain::Continuous;
    o.order = Order::Auto;
    o
}

/// `(frequency Hz, damping ratio)` of the modes `found` calls physical, in its order.
pub fn physical(found: &Identification) -> Vec<(f64, f64)> {
    found
        .modal
        .modes
        .iter()
        .zip(&found.quality)
        .filter(|(_, q)| q.physical)
        .map(|(m, _)| (m.frequency_hz, m.damping_ratio))
        .collect()
}
