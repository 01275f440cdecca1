//! The frame check of `era identify --from-time` with the automatic order: the records
//! estimated again at another frame and identified on the same route; the modes not
//! found again are not physical.

use crate::config::identify::Plan;
use crate::config::{Identify, Settings};
use era::sources::MarkovSequence;
use std::time::Instant;

/// Fewest averages the frame check's second estimate needs.
const CHECK_AVERAGES: u64 = crate::config::JUDGING_AVERAGES as u64;

/// What the frame check repeats of the first identification.
pub struct Check<'a> {
    /// The first run's settings.
    pub plan: &'a Plan,
    /// OKID's Markov parameters, which the second identification realizes again.
    pub supplied: Option<&'a MarkovSequence>,
    /// Samples per frame of the first estimate.
    pub frame: usize,
}

/// With `--from-time`: the records are estimated again through frames twice as long
/// (half as long when the records are too short for that) and identified on the same
/// route, and `found`'s physical modes that are not found
/// again there are not physical ([`era::refine::identification::confirm_modes`]): a structure's
/// modes stay where they are, the poles a fit adds for leakage, a short frame's bias
/// or one estimate's noise do not. Skipped, and said, when the records give fewer than
/// [`CHECK_AVERAGES`] averages at either frame. Returns the lines to print and the
/// check's seconds (a stage of `--timings`).
pub fn frame_check(
    a: &Identify,
    found: &mut era::Identification,
    check: &Check,
) -> anyhow::Result<(String, f64)> {
    let quiet = Settings::silent();
    let clock = Instant::now();
    // Twice the frame (finer lines, the modes better resolved); half of it when the
    // records are too short for that.
    let frame = check.frame;
    let mut second = None;
    let mut tried = Vec::new();
    for other in [frame.saturating_mul(2), frame / 2] {
        if other < 64 {
            continue;
        }
        let mut welch = a.welch.clone();
        welch.frame = Some(other);
        // Too few frames for the inputs is one way for these records to be too short
        // at that frame: the check then tries the other.
        let Ok(estimate) = crate::input::time::estimate_from_time(
            &a.record_paths(),
            a.inputs.as_deref().unwrap_or_default(),
            a.outputs.as_deref().unwrap_or_default(),
            &welch,
            a.quantity.unwrap_or(era::Quantity::Acceleration),
            false,
            &quiet,
        ) else {
            tried.push(format!("{other} samples give no estimate"));
            continue;
        };
        let averages = estimate.facts.averages as u64;
        if averages >= CHECK_AVERAGES {
            second = Some((estimate, other, averages));
            break;
        }
        tried.push(format!("{other} samples give {averages}"));
    }
    let Some((second, other, averages)) = second else {
        let lines = format!(
            "  frame check: skipped: at frames of {}, these records give no estimate with at least {CHECK_AVERAGES} averages (--no-frame-check: off)\n",
            if tried.is_empty() { "twice or half the frame".to_string() } else { tried.join(" and ") }
        );
        return Ok((lines, clock.elapsed().as_secs_f64()));
    };
    let lines = match second_identification(a, second, other, check, &quiet) {
        Ok(again) => {
            let unconfirmed = era::refine::identification::confirm_modes(found, &again, other);
            format!(
                "  frame check: identified again from frames of {other} samples ({averages} averages, {:.2} s): {unconfirmed} physical mode(s) not found again, so not physical (--no-frame-check: off)\n",
                clock.elapsed().as_secs_f64()
            )
        }
        // The check vouches for modes; when it cannot be made, the run stands as it is.
        Err(e) => format!(
            "  frame check: skipped: the second estimate (frames of {other} samples) could not be identified: {e:#}\n"
        ),
    };
    Ok((lines, clock.elapsed().as_secs_f64()))
}

/// The frame check's second identification: the estimate at `other` samples per frame,
/// window-corrected as the first, identified and refined on the same route.
fn second_identification(
    a: &Identify,
    second: crate::input::time::FromTime,
    other: usize,
    check: &Check,
    quiet: &Settings,
) -> anyhow::Result<era::Identification> {
    let mut frf = second.input.file.frf;
    if check.plan.route.window_correction {
        if let Some((corrected, _)) =
            crate::config::window_corrected(&frf, &second.input.file.metadata)?
        {
            frf = corrected;
        }
    }
    let mut refine_options = check.plan.refine.clone();
    refine_options.band = check.plan.fit.band_hz.and_then(|b| {
        let (first, end) = era::data::frf::band_lines(frf.frequency_hz(), b, 0);
        (end > first).then_some((first, end))
    });
    // Zeroed lines are a count of lines: the same Hz at the other frame.
    let mut era_opts = check.plan.era.clone();
    era_opts.zero_lines = (era_opts.zero_lines * other).div_ceil(check.frame.max(1));
    let again = crate::work::identify(
        &a.file,
        &frf,
        check.supplied,
        &era_opts,
        &check.plan.scan,
        true,
        quiet,
    )?;
    crate::work::refine(
        again,
        &frf,
        &refine_options,
        Some(check.plan.route.domain),
        quiet,
    )
}
