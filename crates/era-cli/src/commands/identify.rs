//! `era identify FILE`: the pipeline of docs/src/design.md §1 on an FRF file, or on
//! FRFs estimated from time histories. The flags are settings from [`crate::config`],
//! the data is read by [`crate::input::source`] and planned for by
//! [`crate::config::identify::Plan`]; ERA, OKID and the refinement run through
//! [`crate::work`], and [`crate::output::identify`] writes what they found.

mod frame_check;

use crate::config::identify::Plan;
use crate::config::{Identify, Settings};
use crate::input::InputFrf;
use crate::output::identify::{fit_errors, read_lines, refinement_summary, Found};
use crate::output::report::Human;
use anyhow::Context;
use era::identify::route::Route;
use era::sources::MarkovSequence;
use std::time::Instant;

pub fn run(a: &Identify) -> anyhow::Result<super::Done> {
    let settings = a.settings;
    let human = Human::new(&settings);
    let geometry = crate::output::geometry::read(a.geometry.as_deref(), &human)?;
    let outputs = a
        .out
        .as_deref()
        .map(crate::output::prepare_out_dir)
        .transpose()?;
    let frf_outputs = match &a.save_frf {
        Some(path) if a.from_time => Some(crate::output::estimate::prepare_estimate(path, false)?),
        _ => None,
    };
    let clock = Instant::now();
    let mut source = crate::input::source::read(a, frf_outputs, &human, &settings)?;
    let read_s = clock.elapsed().as_secs_f64() - source.estimate_s.unwrap_or(0.0);
    // The records' copies are OKID's alone: they go once it has run.
    let observed = match source.records.take() {
        Some(records) => Some(crate::work::observe(a, &records, &settings)?),
        None => None,
    };
    let mut echo = String::new();
    let describe = |route: &Route, options: &era::EraOptions, input: &InputFrf| {
        human.print(&read_lines(input));
        // The route and the parameters: printed here, and the report's Parameters.
        echo = crate::output::identify::echo(route, options, observed.as_ref());
        human.print(&echo);
    };
    let coherence = source.coherence.as_ref();
    let mut plan = Plan::new(a, &mut source.input, coherence, &human, describe)?;
    let supplied = observed.as_ref().map(|o| o.supplied());
    let (found, states, checks) =
        identified(a, &source.input, source.frame, supplied, &mut plan, &human)?;
    let found = Found {
        found,
        states,
        plan: &plan,
        echo,
        read_s,
        zero_start_s: checks.zero_start_s,
        frame_check_s: checks.frame_check_s,
        observed: observed.as_ref(),
    };
    crate::output::identify::hand_on(a, outputs, geometry, source, found, &human)
}

/// ERA on the plan (the automatic order's states set in `plan.options`), the zero-start
/// check, the refinement when the route refines (with the frame check), and the
/// suspects of the zeroed start and the band's edges. Returns the identification,
/// ERA's states and the checks' seconds.
fn identified(
    a: &Identify,
    input: &InputFrf,
    frame: usize,
    supplied: Option<&MarkovSequence>,
    plan: &mut Plan,
    human: &Human,
) -> anyhow::Result<(era::Identification, usize, Checks)> {
    let frf = &input.file.frf;
    let mut found = crate::work::identify(
        &a.file,
        frf,
        supplied,
        &plan.era,
        &plan.scan,
        plan.auto,
        &a.settings,
    )?;
    let channels = input.file.channels.as_ref();
    crate::output::figures::collocate_fit(&mut found.fit, channels, frf.outputs(), frf.inputs());
    let states = found.model.states();
    if plan.auto {
        plan.options.order = era::Order::Fixed(states);
    }
    // What the data's zeroed start does to ERA's modes, measured on this model (two
    // identifications of its own FRF: a stage of its own in --timings).
    let clock = Instant::now();
    let zero_start = era::identify::zero_start(&found, &plan.era, plan.route.refine);
    let zero_start_s = clock.elapsed().as_secs_f64();
    let mut frame_check_s = None;
    if plan.route.refine {
        let check = frame_check::Check {
            plan,
            supplied,
            frame,
        };
        (found, frame_check_s) = refine_route(a, found, frf, &check, human, &a.settings)?;
    }
    found.suspects.extend(zero_start);
    found.suspects.extend(era::identify::suspect::band_edges(
        &found,
        plan.fit.fitted_hz,
    ));
    Ok((
        found,
        states,
        Checks {
            zero_start_s,
            frame_check_s,
        },
    ))
}

/// Seconds of the checks that are stages of their own in `--timings`.
struct Checks {
    zero_start_s: f64,
    /// The frame check's, when it ran.
    frame_check_s: Option<f64>,
}

/// The refinement of ERA's model on the route, and with `--from-time` and the automatic
/// order the frame check (and its seconds: a second identification, a stage of its
/// own).
fn refine_route(
    a: &Identify,
    found: era::Identification,
    frf: &era::FrfData,
    check: &frame_check::Check,
    human: &Human,
    settings: &Settings,
) -> anyhow::Result<(era::Identification, Option<f64>)> {
    human.print(&format!(
        "\nERA model: {} states, {} modes; {}\n",
        found.model.states(),
        found.modal.modes.len(),
        fit_errors(&found.fit)
    ));
    let plan = check.plan;
    let mut found =
        crate::work::refine(found, frf, &plan.refine, Some(plan.route.domain), settings)
            .with_context(|| format!("refining the model of {}", a.file.display()))?;
    human.print(&refinement_summary(&found));
    let mut seconds = None;
    if a.from_time && plan.auto && !a.no_frame_check {
        let (lines, spent) = frame_check::frame_check(a, &mut found, check)?;
        human.print(&lines);
        seconds = Some(spent);
    }
    Ok((found, seconds))
}
