//! The zero-start check: how much the zeroed (or padded) leading lines of an FRF shift
//! ERA's modes, found by identifying the model's own FRF twice, whole and with the same
//! lines zeroed ([`crate::identify::suspect`] words the result).

use crate::data::frf::leading_zero_lines;
use crate::data::identification::{Identification, SuspectResult};

/// Relative shifts below which zeroed lines are not worth a warning: 5 % in damping,
/// 0.1 % in frequency.
const ZERO_START_QUIET: (f64, f64) = (0.05, 1e-3);

/// The effect of zeroed leading lines on `found` (an ERA identification at its final
/// order, run with `options`), when its data have leading lines that are zero beyond
/// the 0 Hz line (see the module documentation); `None` when there are none, when the
/// effect is below 5 % in damping and 0.1 % in frequency, or when the model's own FRF
/// cannot be identified at its order. `refined` says whether the model reported is
/// refined (the wording only).
pub fn zero_start(
    found: &Identification,
    options: &crate::EraOptions,
    refined: bool,
) -> Option<SuspectResult> {
    let zeroed = leading_zero_lines(&found.processed).max(options.zero_lines);
    let freq = found.processed.frequency_hz();
    if zeroed < 2 || zeroed >= freq.len() {
        return None;
    }
    let physical: Vec<&crate::pipeline::modes::Mode> = found
        .modal
        .modes
        .iter()
        .zip(&found.quality)
        .filter(|(_, q)| q.physical)
        .map(|(m, _)| m)
        .collect();
    if physical.is_empty() {
        return None;
    }
    // The model's own FRF on every line (its response at the zeroed lines included),
    // already in the quantity ERA fitted: identified on every line, then with the same
    // lines zeroed, at the model's order.
    let own = crate::FrfData::new(
        freq.to_vec(),
        found.processed.outputs(),
        found.processed.inputs(),
        found.model_response.clone(),
        found.processed.quantity(),
    )
    .ok()?;
    let mut plain = options.clone();
    plain.order = crate::Order::Fixed(found.realization.model.states());
    plain.integrations = 0;
    plain.zero_lines = 0;
    plain.lowpass = None;
    plain.domain = crate::ModelDomain::Discrete;
    let mut cut = plain.clone();
    cut.zero_lines = zeroed;
    let whole = crate::identify(&own, &plain).ok()?;
    let zeroed_fit = crate::identify(&own, &cut).ok()?;
    let nearest = |f: f64, modes: &[crate::pipeline::modes::Mode]| {
        modes
            .iter()
            .min_by(|a, b| {
                (a.frequency_hz - f)
                    .abs()
                    .total_cmp(&(b.frequency_hz - f).abs())
            })
            .cloned()
    };
    let mut worst: Option<(f64, f64, f64)> = None;
    for m in physical {
        let (Some(a), Some(b)) = (
            nearest(m.frequency_hz, &whole.modal.modes),
            nearest(m.frequency_hz, &zeroed_fit.modal.modes),
        ) else {
            continue;
        };
        if a.damping_ratio <= 0.0 || (a.frequency_hz - m.frequency_hz).abs() > 0.02 * m.frequency_hz
        {
            continue;
        }
        let dz = b.damping_ratio / a.damping_ratio - 1.0;
        let df = b.frequency_hz / a.frequency_hz - 1.0;
        if worst.is_none_or(|(_, z, f)| {
            dz.abs() / ZERO_START_QUIET.0 + df.abs() / ZERO_START_QUIET.1
                > z.abs() / ZERO_START_QUIET.0 + f.abs() / ZERO_START_QUIET.1
        }) {
            worst = Some((m.frequency_hz, dz, df));
        }
    }
    let (mode_hz, damping_shift, frequency_shift) = worst?;
    (damping_shift.abs() >= ZERO_START_QUIET.0 || frequency_shift.abs() >= ZERO_START_QUIET.1)
        .then_some(SuspectResult::ZeroStart {
            first_hz: freq[zeroed],
            mode_hz,
            damping_shift,
            frequency_shift,
            refined,
        })
}
