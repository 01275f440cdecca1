//! The refinement as a step of the pipeline: an ERA identification in, the refined one
//! out, with its modes judged again ([`refine_identification`]), and the check of its
//! modes against a second estimate of the same test ([`confirm_modes`]).

use crate::data::frf::FrfData;
use crate::data::identification::{FitDomain, Identification, ModeQuality, Refined, Stage};
use crate::error::{EraError, Result};
use crate::identify::ModelDomain;
use crate::modal::indicators::{mpc, ModeIndicators};
use crate::modal::stabilization::{hard_rejection, SelectionCriteria};
use crate::pipeline::fit::fit_metrics;
use crate::pipeline::modes::ModalParameters;
use crate::Complex64;
use std::time::Instant;

/// A refined mode whose share of the band's FRF norm exceeds this is not physical: it is
/// larger than the data, so it cancels other modes (the fit has gone degenerate there,
/// typically where modes the start missed are absorbed by others).
pub const MAX_REFINED_SHARE: f64 = 1.0;

/// A refined mode whose frequency's standard deviation exceeds this fraction of `ζ f`
/// (half its half-power bandwidth) is not physical: the data does not pin it down. On
/// the DTA-like sets with 5 % noise the real modes stay below 0.09 and the poles that
/// ended up fitting noise or the leftovers of other modes are at 0.11–0.8.
pub const MAX_FREQUENCY_SPREAD: f64 = 0.15;

/// Replaces the model of `found` by its refinement against the processed FRFs
/// ([`crate::refine`]): the model that is the fit.
///
/// - **Start poles**: with `--states auto` (a scan chose the modes) the modes judged
///   physical; at a fixed order every mode.
/// - **Domain**: a continuous model is refined as a continuous pole–residue model; a
///   discrete one as the zero-order-hold image at its sample time (the `z`-domain fit of
///   [`crate::refine`]), so that either way the model returned *is* the fitted one.
/// - **Data**: a continuous model is fitted to `frf` *as measured* (the data `found`
///   was identified from), and realised in the quantity of the processed data: the
///   integrations of docs/src/design.md §1.1 help ERA's Markov parameters decay, but they
///   colour the noise (its variance grows as `1/ω²` per integration), so a fit of the
///   integrated data would weight the noisy low lines most. The `z`-domain model has
///   only the quantity it was fitted in, so a discrete model is fitted to the processed
///   data.
/// - **Band**: the identification's fitted lines (from `found.first_line`, never the
///   0 Hz line), unless `options.band` says otherwise.
/// - **The model** is [`crate::refine::Refinement::to_state_space`] of the data's
///   quantity, discretised by `c2d` at the sample time when `found.model` is discrete;
///   its FRF, the fit and the plots are evaluated from its (A, B, C, D).
/// - **Modes** come from the refinement: each pole, its shape and participation the
///   rank-one part `u σ vᴴ` of its residue in the model's variable (shape `u` scaled to
///   a largest entry of 1), with the standard deviations of frequency and damping. The
///   lower residual's integrator states are the model's real poles at `s = 0`.
/// - **Judgement**: a mode is physical when it passes the hard criteria of
///   docs/src/design.md §10 with its refined frequency and damping, its share is at least
///   the minimum and at most [`MAX_REFINED_SHARE`], its significance is at least
///   [`crate::refine::Refinement::significance_minimum`] (not judged when the weights
///   vary by line), its frequency's standard deviation is at most
///   [`MAX_FREQUENCY_SPREAD`] of `ζ f`, and (when a scan ran) its start mode was
///   physical. A mode whose pole the
///   refinement added for one the start missed has no start mode: the residual and its
///   significance vouch for it, even where the stabilization scan had judged a pole
///   there not physical, when its refined shape's MPC reaches the scan's minimum. Last, a weaker mode inside a stronger one's half-power band
///   with its shape is not resolved from it (`mark_unresolved`).
///
/// # Errors
/// [`EraError::InvalidParameter`] when there is no mode to start from, and every error
/// of [`crate::refine::refine`] and [`crate::refine::Refinement::to_state_space`].
pub fn refine_identification(
    found: Identification,
    frf: &FrfData,
    options: &crate::refine::RefineOptions,
    observer: &mut dyn FnMut(Stage),
    progress: &mut dyn FnMut(usize, f64),
) -> Result<Identification> {
    refine_identification_in(found, frf, options, None, observer, progress)
}

/// Largest share of its host's that a pole inside the host's half-power band, with the
/// host's shape, may have to be called unresolved from it (see [`refine_identification`]).
pub(crate) const UNRESOLVED_SHARE: f64 = 0.3;

/// Shape MAC from which two shapes are one at the measured outputs
/// (see [`refine_identification`]).
pub(crate) const UNRESOLVED_MAC: f64 = 0.9;

/// The refinement's last judgement: a physical mode inside the half-power band of a
/// stronger physical one (`|f₁ − f₂| < ζ₁f₁ + ζ₂f₂`), with the stronger one's shape at the
/// outputs (MAC at least [`UNRESOLVED_MAC`]) and less than [`UNRESOLVED_SHARE`] of its
/// share (`shares`, per mode), is not physical
/// ([`crate::modal::stabilization::Rejection::Unresolved`]). A pole the refinement
/// added (`added`: no start mode, so no order of a scan supports it) is unresolved from
/// a start mode it is weaker than, whatever the ratio. Two modes that close are told
/// apart by their shapes or not at all: a weaker pole with the same shape is how a fit
/// bends to a distorted peak (a Welch window's leakage, noise), and a refinement, free
/// to add poles, finds such poles significant on estimated FRFs. With one output every
/// shape has MAC 1, and a weak pole inside a stronger one's band is always unresolved.
fn mark_unresolved(
    modes: &[crate::pipeline::modes::Mode],
    shares: &[f64],
    added: &[bool],
    quality: &mut [ModeQuality],
) {
    use crate::modal::stabilization::Rejection;
    let mut verdicts = Vec::new();
    for (k, m) in modes.iter().enumerate() {
        if !quality.get(k).is_some_and(|q| q.physical) {
            continue;
        }
        let host = modes
            .iter()
            .enumerate()
            .filter(|&(j, h)| {
                j != k
                    && quality.get(j).is_some_and(|q| q.physical)
                    && (h.frequency_hz - m.frequency_hz).abs()
                        < h.damping_ratio.abs() * h.frequency_hz
                            + m.damping_ratio.abs() * m.frequency_hz
                    && shares[k]
                        < if added[k] && !added[j] {
                            shares[j]
                        } else {
                            UNRESOLVED_SHARE * shares[j]
                        }
            })
            .map(|(j, h)| (j, crate::modal::indicators::mac(&m.shape, &h.shape)))
            .filter(|&(_, mac)| mac >= UNRESOLVED_MAC)
            .max_by(|a, b| shares[a.0].total_cmp(&shares[b.0]));
        if let Some((j, mac)) = host {
            verdicts.push((
                k,
                Rejection::Unresolved {
                    host_hz: modes[j].frequency_hz,
                    share: shares[k] / shares[j],
                    mac,
                },
            ));
        }
    }
    for (k, why) in verdicts {
        quality[k].physical = false;
        quality[k].reason = Some(why.to_string());
    }
}

/// Checks `found`'s physical modes against `check`, the identification of a second
/// estimate of the same test (the same records through frames of `frame` samples, a
/// length other than `found`'s): each physical mode must have a counterpart
/// among `check`'s modes with `0 < ζ ≤ 20 %`, matched one to one by increasing
/// frequency distance within the larger of its half-power half-width `ζ f` and two
/// lines of the coarser of the two estimates (a short frame's leakage moves a mode's
/// estimate by about a line). A mode without one is not physical
/// ([`crate::modal::stabilization::Rejection::Unconfirmed`]). Returns how many were
/// unconfirmed.
///
/// A structure's mode is where it is whatever the frame; the poles a fit adds for a
/// window's leakage, for the bias of a short frame or for one estimate's noise move
/// or vanish when the frame changes.
pub fn confirm_modes(found: &mut Identification, check: &Identification, frame: usize) -> usize {
    use crate::modal::stabilization::Rejection;
    let spacing = 2.0
        * found
            .processed
            .spacing_hz()
            .max(check.processed.spacing_hz());
    let candidates: Vec<f64> = check
        .modal
        .modes
        .iter()
        .filter(|m| m.damping_ratio > 0.0 && m.damping_ratio <= 0.2)
        .map(|m| m.frequency_hz)
        .collect();
    let physical: Vec<usize> = (0..found.modal.modes.len())
        .filter(|&k| found.quality.get(k).is_some_and(|q| q.physical))
        .collect();
    let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
    for &k in &physical {
        let m = &found.modal.modes[k];
        let tolerance = (m.damping_ratio.abs() * m.frequency_hz).max(spacing);
        for (j, &f) in candidates.iter().enumerate() {
            let d = (f - m.frequency_hz).abs();
            if d <= tolerance {
                pairs.push((d, k, j));
            }
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut matched, mut used) = (Vec::new(), Vec::new());
    for (_, k, j) in pairs {
        if !matched.contains(&k) && !used.contains(&j) {
            matched.push(k);
            used.push(j);
        }
    }
    let mut count = 0;
    for k in physical {
        if matched.contains(&k) {
            continue;
        }
        let f = found.modal.modes[k].frequency_hz;
        let nearest_hz = candidates
            .iter()
            .copied()
            .min_by(|a, b| (a - f).abs().total_cmp(&(b - f).abs()));
        found.quality[k].physical = false;
        found.quality[k].reason = Some(Rejection::Unconfirmed { frame, nearest_hz }.to_string());
        count += 1;
    }
    count
}

/// [`refine_identification`] with the refined model returned in `domain` (`None`: the
/// domain of `found.model`). A route that wants a continuous-time model keeps ERA's
/// start discrete (a discrete realization with a negative real pole has no
/// continuous image) and asks for the continuous model here.
///
/// # Errors
/// As [`refine_identification`].
pub fn refine_identification_in(
    mut found: Identification,
    frf: &FrfData,
    options: &crate::refine::RefineOptions,
    domain: Option<ModelDomain>,
    observer: &mut dyn FnMut(Stage),
    progress: &mut dyn FnMut(usize, f64),
) -> Result<Identification> {
    Stage::Refine.enter(observer)?;
    let clock = Instant::now();
    let start = Start::of(&found)?;
    // The domain the user asked the model in, and the domain of the fit, chosen for the
    // data (`FitDomain`).
    let discrete_ts = requested_sample_time(&found, domain);
    let (ropts, fit_domain) = fit_setup(&found, options, &start.poles, discrete_ts);
    // The domain probe treats a failure as "keep the asked domain"; an interrupt is not one.
    crate::cancel::check()?;
    let fitted = fitted_data(&found, frf, &fit_domain)?;
    let (refinement, round_seconds) =
        crate::refine::refine_rounds(fitted, &start.poles, &ropts, progress)?;
    let quantity = found.processed.quantity();
    let continuous = refinement.to_state_space(quantity)?;
    let model = match discrete_ts {
        Some(ts) => continuous.c2d(ts)?,
        None => continuous,
    };
    let residual_states = integrator_states(&refinement, quantity);
    let modes = refined_modes(&refinement, quantity, discrete_ts)?;
    let real_poles = (0..residual_states)
        .map(|_| crate::pipeline::modes::RealPole {
            eigenvalue: if discrete_ts.is_some() { 1.0 } else { 0.0 },
            continuous_pole: Complex64::new(0.0, 0.0),
            frequency_hz: 0.0,
        })
        .collect();
    let freq = found.processed.frequency_hz();
    let (first, end) = refinement.band;
    let band_hz = (freq[first], freq[end - 1]);
    let mut quality = refined_quality(&found, &refinement, &modes, &start, band_hz);
    let shares: Vec<f64> = refinement.modes.iter().map(|rm| rm.contribution).collect();
    let added: Vec<bool> = refinement
        .modes
        .iter()
        .map(|rm| start.modes.get(rm.start).is_none())
        .collect();
    mark_unresolved(&modes, &shares, &added, &mut quality);
    refit(&mut found, &model, first);
    found.band_hz = band_hz;
    found.model = model;
    found.modal = ModalParameters { modes, real_poles };
    found.quality = quality;
    found.suspects = crate::identify::suspect::check_identification(&found);
    found.timings.refine = clock.elapsed().as_secs_f64();
    found.refinement = Some(Refined {
        start_frequency_hz: start
            .poles
            .iter()
            .chain(&refinement.added)
            .map(|s| s.norm() / (2.0 * std::f64::consts::PI))
            .collect(),
        refinement,
        residual_states,
        fit_domain,
        round_seconds,
    });
    Ok(found)
}

/// What a refinement starts from: the modes of `found` it refines (with `--states auto`
/// the physical ones, at a fixed order all), their continuous poles, and whether a scan
/// judged them.
struct Start {
    modes: Vec<usize>,
    poles: Vec<Complex64>,
    scanned: bool,
}

impl Start {
    fn of(found: &Identification) -> Result<Start> {
        let scanned = found.stabilization.is_some();
        let auto = found
            .stabilization
            .as_ref()
            .is_some_and(|s| s.model_note.is_some());
        let modes: Vec<usize> = (0..found.modal.modes.len())
            .filter(|&k| !auto || found.quality.get(k).is_none_or(|q| q.physical))
            .collect();
        if modes.is_empty() {
            return Err(EraError::InvalidParameter {
                name: "refine",
                value: "true".into(),
                reason: "the model has no mode to start the refinement from".into(),
            });
        }
        let poles = modes
            .iter()
            .map(|&k| found.modal.modes[k].continuous_pole)
            .collect();
        Ok(Start {
            modes,
            poles,
            scanned,
        })
    }
}

/// The sample time of the model asked for: `domain`'s, or `found.model`'s own when
/// `domain` is `None`; `None` for a continuous model.
fn requested_sample_time(found: &Identification, domain: Option<ModelDomain>) -> Option<f64> {
    match (domain, found.model.domain) {
        (Some(ModelDomain::Discrete), _) => Some(found.sample_time_s),
        (Some(ModelDomain::Continuous), _) => None,
        (None, crate::TimeDomain::Discrete { sample_time_s }) => Some(sample_time_s),
        (None, crate::TimeDomain::Continuous) => None,
    }
}

/// The refinement's options for `found`: the fitted lines (the identification's, never
/// the 0 Hz line, unless `options.band` says otherwise) and the domain of the fit
/// ([`choose_fit_domain`]; a probe that fails, on a basis the data cannot support, leaves
/// the domain asked for).
fn fit_setup(
    found: &Identification,
    options: &crate::refine::RefineOptions,
    start_poles: &[Complex64],
    discrete_ts: Option<f64>,
) -> (crate::refine::RefineOptions, FitDomain) {
    let mut ropts = options.clone();
    let freq = found.processed.frequency_hz();
    let lines = freq.len();
    if ropts.band.is_none() {
        let positive = freq.iter().position(|&f| f > 0.0).unwrap_or(lines);
        ropts.band = Some((found.first_line.max(positive), lines));
    }
    let fit_domain =
        choose_fit_domain(found, start_poles, &ropts, discrete_ts).unwrap_or_else(|e| FitDomain {
            sample_time_s: discrete_ts.map(|_| found.sample_time_s),
            probe_fit: (f64::NAN, f64::NAN),
            reason: format!(
                "the model's own time domain (the comparison of the two could not be made: {e})"
            ),
        });
    ropts.sample_time_s = fit_domain.sample_time_s;
    (ropts, fit_domain)
}

/// The data the refinement fits: the processed FRFs in the `z` domain, `frf` as measured
/// in the continuous one; refused when `frf` is not the data `found` came from.
fn fitted_data<'a>(
    found: &'a Identification,
    frf: &'a FrfData,
    fit_domain: &FitDomain,
) -> Result<&'a FrfData> {
    let fitted = match fit_domain.sample_time_s {
        Some(_) => &found.processed,
        None => frf,
    };
    if (fitted.outputs(), fitted.inputs(), fitted.lines())
        != (
            found.processed.outputs(),
            found.processed.inputs(),
            found.processed.lines(),
        )
    {
        return Err(EraError::InvalidParameter {
            name: "frf",
            value: format!("{}x{}x{}", frf.outputs(), frf.inputs(), frf.lines()),
            reason: "not the data the identification was made from".into(),
        });
    }
    Ok(fitted)
}

/// Integrator states of the residual terms `K (jω)^e`, `e < 0`.
fn integrator_states(refinement: &crate::refine::Refinement, quantity: crate::Quantity) -> usize {
    refinement
        .residual_terms(quantity)
        .iter()
        .filter(|(e, _)| *e < 0)
        .map(|(e, _)| e.unsigned_abs() as usize * refinement.inputs)
        .sum()
}

/// The refined modes in the domain asked for: each pole, and the rank-one part of its
/// residue as shape and participation.
fn refined_modes(
    refinement: &crate::refine::Refinement,
    quantity: crate::Quantity,
    discrete_ts: Option<f64>,
) -> Result<Vec<crate::pipeline::modes::Mode>> {
    let (q, p) = (refinement.outputs, refinement.inputs);
    let mut modes = Vec::with_capacity(refinement.modes.len());
    for rm in &refinement.modes {
        let mut residue = refinement.model_residue(rm, quantity);
        // A residue of the fitted domain in the domain asked for: the zero-order hold
        // takes a continuous term `R/(s − p)` to `R (e^(pTs) − 1)/p / (z − e^(pTs))`.
        let hold = |ts: f64| ((rm.pole * ts).exp() - 1.0) / rm.pole;
        let factor = match (refinement.sample_time_s, discrete_ts) {
            (None, Some(ts)) => hold(ts),
            (Some(ts), None) => 1.0 / hold(ts),
            _ => Complex64::new(1.0, 0.0),
        };
        residue.iter_mut().for_each(|r| *r *= factor);
        let (shape, participation) = rank_one(&residue, q, p)?;
        modes.push(crate::pipeline::modes::Mode {
            frequency_hz: rm.frequency_hz,
            damping_ratio: rm.damping_ratio,
            eigenvalue: match discrete_ts {
                Some(ts) => (rm.pole * ts).exp(),
                None => rm.pole,
            },
            continuous_pole: rm.pole,
            shape,
            participation,
        });
    }
    Ok(modes)
}

/// The judgement of each refined mode (see [`refine_identification`]), before
/// [`mark_unresolved`].
fn refined_quality(
    found: &Identification,
    refinement: &crate::refine::Refinement,
    modes: &[crate::pipeline::modes::Mode],
    start: &Start,
    band_hz: (f64, f64),
) -> Vec<ModeQuality> {
    let criteria = SelectionCriteria::default();
    refinement
        .modes
        .iter()
        .zip(modes)
        .map(|(rm, m)| {
            // A mode added for one the start missed has no judgement from before.
            let before = start
                .modes
                .get(rm.start)
                .and_then(|&k| found.quality.get(k))
                .cloned();
            let reason = refined_rejection(
                refinement,
                rm,
                m,
                before.as_ref(),
                start.scanned,
                band_hz,
                &criteria,
            );
            let emac = before.as_ref().and_then(|b| b.indicators.emac);
            let m_pc = mpc(&m.shape);
            let finite = |v: f64| v.is_finite().then_some(v);
            ModeQuality {
                physical: reason.is_none(),
                reason,
                indicators: ModeIndicators {
                    mpc: m_pc,
                    emac,
                    cmi: emac.map(|e| e * m_pc),
                    contribution: Some(rm.contribution),
                },
                stable_orders: before.and_then(|b| b.stable_orders),
                frequency_std_hz: finite(rm.frequency_std_hz),
                damping_ratio_std: finite(rm.damping_ratio_std),
            }
        })
        .collect()
}

/// Why a refined mode is not physical, if it is not: the first of the rules of
/// [`refine_identification`] it fails.
fn refined_rejection(
    refinement: &crate::refine::Refinement,
    rm: &crate::refine::RefinedMode,
    m: &crate::pipeline::modes::Mode,
    before: Option<&ModeQuality>,
    scanned: bool,
    band_hz: (f64, f64),
    criteria: &SelectionCriteria,
) -> Option<String> {
    let mut reason = hard_rejection(m.frequency_hz, m.damping_ratio, None, band_hz, criteria)
        .map(|r| r.to_string());
    if reason.is_none() && rm.contribution < criteria.contribution_minimum {
        reason = Some(
            crate::modal::stabilization::Rejection::NoContribution(rm.contribution).to_string(),
        );
    }
    let least = refinement.significance_minimum();
    if reason.is_none() && rm.significance < least {
        reason = Some(format!(
            "it explains {:.2} noise variances per parameter, fewer than the {least:.2} that tell a mode from noise",
            rm.significance,
        ));
    }
    let half_width = rm.damping_ratio * rm.frequency_hz;
    if reason.is_none() && rm.frequency_std_hz > MAX_FREQUENCY_SPREAD * half_width {
        reason = Some(format!(
            "its frequency is uncertain by ±{:.2e} Hz, more than {MAX_FREQUENCY_SPREAD} of ζf = {half_width:.2e} Hz: the data does not pin it down",
            rm.frequency_std_hz
        ));
    }
    if reason.is_none() && rm.contribution > MAX_REFINED_SHARE {
        reason = Some(format!(
            "its share of the data is {:.2}: it cancels other modes (a degenerate fit there)",
            rm.contribution
        ));
    }
    if reason.is_none() && scanned {
        if let Some(b) = before.filter(|b| !b.physical) {
            reason = b
                .reason
                .clone()
                .or(Some("not physical before refinement".into()));
        }
    }
    // The scan's rule on an added pole's refined shape (a start mode passed it over the
    // scan's orders): a structure's normal mode has a near-real shape; a pole the fit
    // bent to noise need not.
    let m_pc = mpc(&m.shape);
    if reason.is_none() && before.is_none() && m_pc < criteria.mpc_minimum {
        reason = Some(format!(
            "its refined shape is complex (MPC {m_pc:.2}, under {:.2}): not a normal mode of the structure",
            criteria.mpc_minimum
        ));
    }
    reason
}

/// `found`'s model response and fit anew from `model`, from line `first`. Below the band
/// the lower residual's integrators are infinite at 0 Hz: those lines were not fitted
/// (like the zeroed measured lines) and are written as 0. The pairs keep the collocation
/// the caller gave the start's fit (a channel table's, `FitReport::set_collocation`);
/// `fit_metrics` alone goes by index.
fn refit(found: &mut Identification, model: &crate::StateSpace, first: usize) {
    let mut response =
        crate::pipeline::fit::frequency_response_blocks(model, found.measured.frequency_hz());
    let nl = found.measured.lines();
    for (i, v) in response.iter_mut().enumerate() {
        if i % nl < first && !(v.re.is_finite() && v.im.is_finite()) {
            *v = Complex64::new(0.0, 0.0);
        }
    }
    let collocated: Vec<bool> = found.fit.pairs.iter().map(|f| f.collocated).collect();
    found.fit = fit_metrics(&found.measured, &response, first);
    let p = found.measured.inputs();
    found.fit.set_collocation(|i, j| collocated[i * p + j]);
    found.model_response = response;
    found.first_line = first;
}

/// How many standard deviations of the noise's part of the difference of the two
/// probe costs (chosen by the refinement in the pipeline) the zero-order-hold image must win by.
const ZOH_SIGNIFICANCE: f64 = 8.0;

/// Chooses the domain of the refinement's fit for the data, not for the model asked
/// for. FRFs measured on a structure are those of a continuous system; FRFs computed
/// from a zero-order-hold discrete model (the thesis's truth model) are not those of
/// any continuous pole–residue model. Fitting data with the wrong one leaves a
/// systematic residual that the scan for missed modes reads as modes, and junk poles
/// are added. Both are fitted at the start poles with free residues (a linear least
/// squares each, no iteration, uniform weights) to the processed data. They have the
/// same `k` parameters, so on data that suits either, their costs differ by noise
/// alone, about `σ²√k` (each projects the noise on a `k`-dimensional subspace); the
/// ZOH image is taken when the continuous cost exceeds its own by more than
/// [`ZOH_SIGNIFICANCE`] of that, with `σ²` the ZOH fit's residual variance, and the
/// continuous model when its cost is lower by as much. When neither wins (noise, or a
/// start that misses modes and leaves both far from the data), the fit is in the domain
/// of the model asked for (`requested_ts`). The model returned is then converted to the
/// domain asked for.
fn choose_fit_domain(
    found: &Identification,
    start_poles: &[crate::Complex64],
    ropts: &crate::refine::RefineOptions,
    requested_ts: Option<f64>,
) -> Result<FitDomain> {
    let mut probe = ropts.clone();
    probe.max_iterations = 0;
    probe.add_missed = false;
    probe.rank_one = false;
    probe.weighting = crate::refine::Weighting::Uniform;
    // Only the two costs and the noise variance are read: no standard deviations.
    probe.standard_deviations = false;
    let (continuous, zoh) = crate::refine::refine_in_both_domains(
        &found.processed,
        start_poles,
        &probe,
        found.sample_time_s,
    );
    let (continuous, zoh) = (continuous?, zoh?);
    let (c, z) = (continuous.fit_before, zoh.fit_before);
    let (band_lines, pairs) = (zoh.band.1 - zoh.band.0, zoh.outputs * zoh.inputs);
    let observations = (2 * band_lines * pairs) as f64;
    // Unknowns from the residual variance's definition, `cost/(observations − unknowns)`.
    let unknowns = if zoh.noise_variance > 0.0 && zoh.noise_variance.is_finite() {
        (observations - zoh.cost_before / zoh.noise_variance).max(1.0)
    } else {
        observations
    };
    let noise_part = zoh.noise_variance.max(0.0) * unknowns.sqrt();
    let gain = continuous.cost_before - zoh.cost_before;
    let (take_zoh, reason) = if gain > ZOH_SIGNIFICANCE * noise_part {
        (true, format!(
            "the zero-order-hold image fits the data better than a continuous model (relative error {z:.2e} against {c:.2e} at the start poles, beyond the noise): the FRFs are those of a sampled system"
        ))
    } else if -gain > ZOH_SIGNIFICANCE * noise_part {
        (false, format!(
            "a continuous model fits the data better than the zero-order-hold image (relative error {c:.2e} against {z:.2e} at the start poles, beyond the noise): FRFs measured on a structure are continuous-time data"
        ))
    } else {
        let zoh = requested_ts.is_some();
        (zoh, format!(
            "the data does not tell a continuous model from the zero-order-hold image at the start poles (relative error {c:.2e} against {z:.2e}): the {} model, as the model's time domain asks",
            if zoh { "zero-order-hold" } else { "continuous" }
        ))
    };
    Ok(FitDomain {
        sample_time_s: take_zoh.then_some(found.sample_time_s),
        probe_fit: (c, z),
        reason,
    })
}

/// The dominant rank-one part `u σ vᴴ` of a q × p residue as (shape, participation):
/// shape `u/u_max` (largest entry 1), participation `u_max σ v̄`, so that
/// `shape · participationᵀ` is that part.
fn rank_one(
    residue: &[crate::Complex64],
    q: usize,
    p: usize,
) -> Result<(Vec<crate::Complex64>, Vec<crate::Complex64>)> {
    let r = faer::Mat::from_fn(q, p, |i, j| residue[i * p + j]);
    let svd = r
        .thin_svd()
        .map_err(|e| EraError::Numerical(format!("SVD of a residue: {e:?}")))?;
    let sigma = svd.S()[0].re;
    let u: Vec<crate::Complex64> = (0..q).map(|i| svd.U()[(i, 0)]).collect();
    let k = (0..q)
        .max_by(|&a, &b| u[a].norm().total_cmp(&u[b].norm()))
        .unwrap_or(0);
    let top = u[k];
    let shape = u.iter().map(|x| x / top).collect();
    let participation = (0..p)
        .map(|j| top * sigma * svd.V()[(j, 0)].conj())
        .collect();
    Ok((shape, participation))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::{identify, EraOptions};

    #[test]
    fn a_physical_mode_not_found_again_in_a_second_estimate_is_not_physical() {
        use crate::test_support::receptance;
        let options = EraOptions::new(4, 20);
        let mut found = identify(
            &receptance(&[(6.0, 0.02), (13.0, 0.01)], 0.1, 401),
            &options,
        )
        .unwrap();
        assert!(found.quality.iter().all(|q| q.physical));
        // The same 6 Hz mode, and a 14 Hz one in place of 13 Hz: 13 Hz moved.
        let check = identify(
            &receptance(&[(6.01, 0.02), (14.0, 0.01)], 0.05, 801),
            &options,
        )
        .unwrap();
        assert_eq!(confirm_modes(&mut found, &check, 4096), 1);
        assert!(found.quality[0].physical && !found.quality[1].physical);
        let why = found.quality[1].reason.clone().unwrap();
        assert!(
            why.contains("frames of 4096 samples") && why.contains("nearest mode is at 14.0"),
            "{why}"
        );
        // Found again within ζf or two lines: confirmed.
        let mut again = identify(
            &receptance(&[(6.0, 0.02), (13.0, 0.01)], 0.1, 401),
            &options,
        )
        .unwrap();
        let near = identify(
            &receptance(&[(6.05, 0.02), (13.1, 0.01)], 0.05, 801),
            &options,
        )
        .unwrap();
        assert_eq!(confirm_modes(&mut again, &near, 4096), 0);
    }

    #[test]
    fn a_weak_pole_with_a_stronger_ones_shape_inside_its_band_is_unresolved() {
        use crate::modal::stabilization::Rejection;
        use crate::pipeline::modes::Mode;
        use crate::Complex64;
        let mode = |f: f64, z: f64, shape: &[f64]| Mode {
            frequency_hz: f,
            damping_ratio: z,
            eigenvalue: Complex64::new(0.0, 0.0),
            continuous_pole: Complex64::new(0.0, 0.0),
            shape: shape.iter().map(|&x| Complex64::new(x, 0.0)).collect(),
            participation: vec![Complex64::new(1.0, 0.0)],
        };
        let fresh = |n: usize| {
            vec![
                ModeQuality {
                    physical: true,
                    reason: None,
                    indicators: ModeIndicators {
                        mpc: 1.0,
                        emac: None,
                        cmi: None,
                        contribution: None,
                    },
                    stable_orders: None,
                    frequency_std_hz: None,
                    damping_ratio_std: None,
                };
                n
            ]
        };
        // 10 Hz at 1 %: its half-power band is ±0.1 Hz. A pole at 10.05 Hz with its
        // shape and a fifth of its share is unresolved; one at 10.05 Hz with another
        // shape is a close mode; one at 10.5 Hz is outside the band.
        let host = mode(10.0, 0.01, &[1.0, 0.5, -0.2]);
        let same = mode(10.05, 0.005, &[1.0, 0.49, -0.21]);
        let other = mode(10.05, 0.005, &[0.1, -1.0, 0.6]);
        let far = mode(10.5, 0.005, &[1.0, 0.5, -0.2]);
        let mut q = fresh(2);
        mark_unresolved(
            &[host.clone(), same.clone()],
            &[1.0, 0.2],
            &[false, false],
            &mut q,
        );
        assert!(q[0].physical && !q[1].physical);
        let text = q[1].reason.clone().unwrap();
        assert_eq!(
            text,
            Rejection::Unresolved {
                host_hz: 10.0,
                share: 0.2,
                mac: crate::modal::indicators::mac(&same.shape, &host.shape)
            }
            .to_string()
        );
        for (second, shares) in [
            (&other, [1.0, 0.2]),
            (&far, [1.0, 0.2]),
            (&same, [1.0, 0.5]),
        ] {
            let mut q = fresh(2);
            mark_unresolved(
                &[host.clone(), second.clone()],
                &shares,
                &[false, false],
                &mut q,
            );
            assert!(q.iter().all(|q| q.physical), "{shares:?}");
        }
        // A pole the refinement added, weaker than a start mode: unresolved at half
        // its share too; a start mode is not judged against an added pole that way.
        let mut q = fresh(2);
        mark_unresolved(
            &[host.clone(), same.clone()],
            &[1.0, 0.5],
            &[false, true],
            &mut q,
        );
        assert!(q[0].physical && !q[1].physical);
        let mut q = fresh(2);
        mark_unresolved(&[host, same], &[1.0, 0.5], &[true, false], &mut q);
        assert!(q.iter().all(|q| q.physical));
    }
}
