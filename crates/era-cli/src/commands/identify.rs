//! `era identify FILE`: the pipeline of docs/src/design.md §1 on an FRF file. Flags become
//! options in [`crate::config`], the file is read by [`crate::input`] (or estimated
//! from time histories by [`crate::input::time`]), and the outputs are written by
//! [`crate::output`].

use crate::config::{apply_route, era_options, Identify, Settings, WeightingGiven};
use crate::input::InputFrf;
use crate::input::{describe_input, read_frf_with, set_units, shape_line, FrfFlags};
use crate::output::identification::{write_bundle, write_model, Bundle};
use crate::output::report::PART;
use crate::output::report::{
    identification_summary, parameter_echo_states, print_json, stabilization_summary,
    svd_path_line, timings_table, Human,
};
use crate::output::{pair_fit_table, prepare_out_dir, InputCoherence, RunInput};
use anyhow::Context;
use era::identify::route::Route;
use era::identify::{identify_observed, identify_supplied, Order, ScanOptions};
use era::sources::MarkovSequence;
use era_io::atomic::OutputSet;
use era_io::model_json::{timings_map, FitJson, ModelJson, ModelParameters};
use std::time::Instant;

/// What `identify` read: the FRFs (from a file, or estimated from time histories), and
/// with `--from-time` the estimate's seconds, coherence and description.
struct Source {
    input: InputFrf,
    estimate_s: Option<f64>,
    coherence: Option<InputCoherence>,
    time_format: Option<String>,
    records: Option<crate::input::time::TimeRecords>,
    /// Samples per frame of the estimate (with `--from-time`).
    frame: usize,
}

/// The Markov parameters OKID found in the records, and its seconds.
struct Observed {
    okid: era::sources::okid::Okid,
    seconds: f64,
}

impl Observed {
    fn supplied(&self) -> &MarkovSequence {
        &self.okid.markov
    }
}

pub fn run(a: &Identify) -> anyhow::Result<super::Done> {
    let settings = a.settings;
    let human = Human::new(&settings);
    let mut opts = a.options.clone();
    let request = &a.request;
    let refine_options = a.refine.clone();
    let geometry = crate::output::geometry::read(a.geometry.as_deref(), &human)?;
    let mut outputs = match &a.out {
        Some(dir) => Some(prepare_out_dir(dir)?),
        None => None,
    };
    let frf_outputs = match &a.save_frf {
        Some(path) if a.from_time => Some(crate::output::estimate::prepare_estimate(path, false)?),
        _ => None,
    };
    let clock = Instant::now();
    let mut source = read_source(a, frf_outputs, &human, &settings)?;
    let read_s = clock.elapsed().as_secs_f64() - source.estimate_s.unwrap_or(0.0);
    let frame_run = source.frame;
    // The records' copies are OKID's alone: they go once it has run.
    let observed = match source.records.take() {
        Some(records) => Some(observe(a, &records, &settings)?),
        None => None,
    };
    let supplied = observed.as_ref().map(Observed::supplied);
    let mut input = source.input;
    let route = request.resolve(input.file.frf.quantity(), a.options.integrations);
    apply_route(&mut opts, &route);
    correct_window(a, &route, &mut input, &human)?;
    let frf = &input.file.frf;
    if a.out.is_some() {
        crate::output::figures::check_pairs(&a.pairs, frf.outputs(), frf.inputs())?;
    }
    let names: Vec<String> = (1..=frf.outputs()).map(|o| o.to_string()).collect();
    if route.refine {
        crate::commands::refine::check_shape(&refine_options, frf)?;
    }
    human.print(&format!("  {}{}\n", shape_line(frf), input.note));
    human.print(&describe_input(&input));
    let auto = route.states.is_none();
    // The route and the parameters: printed here, and the report's Parameters.
    let echo = format!(
        "{}{}{}",
        route_echo(&route),
        observed.as_ref().map(okid_echo).unwrap_or_default(),
        parameter_echo_states(
            &opts,
            auto.then_some("auto (from the stabilization diagram)")
        )
    );
    human.print(&echo);
    let fit = fit_lines(a, frf, source.coherence.as_ref(), &route, &human)?;
    let mut refine_options = refine_options;
    refine_options.band = fit.lines;
    coherence_weighting(
        a,
        &route,
        source.coherence.as_ref(),
        frf,
        &mut refine_options,
    )?;
    let scan_options = {
        let mut o = ScanOptions::default();
        o.orders = a.orders.clone();
        o.band_hz = fit.band_hz;
        o
    };
    let era_opts = era_options(&opts, &route);
    let mut found = realize(a, frf, supplied, &era_opts, &scan_options, auto, &settings)?;
    let channels = input.file.channels.as_ref();
    crate::output::figures::collocate_fit(&mut found.fit, channels, frf.outputs(), frf.inputs());
    let states = found.model.states();
    if auto {
        opts.order = era::Order::Fixed(states);
    }
    // What the data's zeroed start does to ERA's modes, measured on this model (two
    // identifications of its own FRF: a stage of its own in --timings).
    let clock = std::time::Instant::now();
    let zero_start = era::identify::zero_start(&found, &era_opts, route.refine);
    let zero_start_s = clock.elapsed().as_secs_f64();
    if route.refine {
        let check = Check {
            band_hz: fit.band_hz,
            era_opts: &era_opts,
            scan_options: &scan_options,
            refine_options: &refine_options,
            route: &route,
            supplied,
            frame: frame_run,
        };
        found = refine_route(a, found, frf, &check, auto, &human, &settings)?;
    }
    found.suspects.extend(zero_start);
    found
        .suspects
        .extend(era::suspect::band_edges(&found, fit.fitted_hz));
    print_found(&found, frf, states, &human);
    let mut model = model_json(&found, &opts, &route, &refine_options, auto, states);
    let mut timings = timings(&found, read_s, source.estimate_s, route.refine);
    timings.insert("zero_start".into(), zero_start_s);
    if let Some(o) = &observed {
        okid_json(o, &mut model);
        timings.insert("okid".into(), o.seconds);
    }
    let written = Written {
        model,
        timings,
        echo,
        states,
    };
    let (time_format, coherence) = (source.time_format, source.coherence);
    let run_input = outputs
        .as_ref()
        .map(|_| run_input(a, &input, time_format, coherence))
        .map(|mut r| {
            // The singular-value figure of a fixed order looks past it.
            if !auto && supplied.is_none() && a.orders.is_none() && !a.no_figures {
                let mut options = era_opts.clone();
                options.order = Order::Fixed(states);
                r.hankel = Some((input.file.frf.clone(), options));
            }
            r
        })
        .map(|r| crate::output::geometry::attach(r, geometry, input.file.frf.outputs()));
    let model = write(
        a,
        outputs.as_mut().zip(run_input.as_ref()),
        &found,
        written,
        &human,
        &settings,
    )?;
    if let (Some(dir), Some(set)) = (&a.out, outputs) {
        // Every output is in the staging folder: they all take their place now, or none.
        set.commit()?;
        human.print(&written_line(a, dir));
    }
    if settings.json {
        print_json(&model)?;
    }
    Ok(super::Done {
        json: serde_json::to_value(&model)?,
        channels: names,
    })
}

/// The summary of the identification, the fit per pair and the scan.
fn print_found(found: &era::Identification, frf: &era::FrfData, states: usize, human: &Human) {
    human.print(&identification_summary(found, states));
    human.print(&pair_fit_table(&found.fit, frf.outputs(), frf.inputs()));
    if let Some(st) = &found.stabilization {
        human.print(&stabilization_summary(st));
    }
}

/// The stages' seconds: the pipeline's, reading, the estimate and the refinement.
fn timings(
    found: &era::Identification,
    read_s: f64,
    estimate_s: Option<f64>,
    refined: bool,
) -> std::collections::BTreeMap<String, f64> {
    let mut timings = timings_map(&found.timings);
    timings.insert("read".into(), read_s);
    if let Some(t) = estimate_s {
        timings.insert("frf_estimate".into(), t);
    }
    if refined {
        timings.insert("refine".into(), found.timings.refine);
        if let Some(r) = &found.refinement {
            for (k, t) in r.round_seconds.iter().enumerate() {
                timings.insert(format!("refine{PART}round {}", k + 1), *t);
            }
        }
    }
    timings
}

/// What went into the run, for the report: the file (or the time histories and how
/// their FRFs were estimated), the coherence when there is one, the phase view.
fn run_input(
    a: &Identify,
    input: &InputFrf,
    time_format: Option<String>,
    coherence: Option<InputCoherence>,
) -> RunInput {
    let mut run_input = RunInput::from_file(&a.file, input);
    if a.from_time {
        run_input.section.format = time_format.unwrap_or_default();
    }
    if coherence.is_some() {
        run_input.coherence = coherence;
    }
    run_input.phase = a.phase;
    run_input.pairs = a.pairs.clone();
    run_input
}

/// The closing line: what the run wrote in `dir`.
fn written_line(a: &Identify, dir: &std::path::Path) -> String {
    let figures = if a.geometry.is_some() {
        " (singular_values, grid, pairs/, automac, complexity, shapes/)"
    } else {
        " (singular_values, grid, pairs/, automac, complexity)"
    };
    format!(
        "\nwrote {}{}\n",
        crate::output::identification::written_list(dir, !a.no_figures),
        if a.no_figures { "" } else { figures }
    )
}

/// The FRFs to identify: estimated from time histories with `--from-time` (and saved
/// with `--save-frf`), read from the FRF file otherwise.
fn read_source(
    a: &Identify,
    frf_outputs: Option<OutputSet>,
    human: &Human,
    settings: &Settings,
) -> anyhow::Result<Source> {
    if !a.from_time {
        let outputs = match a.outputs.as_deref() {
            None => None,
            Some(text) => Some(text.trim().parse::<usize>().map_err(|_| {
                crate::error::UsageError(format!(
                    "--outputs {text}: expected the number of outputs of a MAT FRF matrix (channel lists apply with --from-time)"
                ))
            })?),
        };
        let input = read_frf_with(
            &a.file,
            &FrfFlags {
                quantity: a.quantity,
                outputs,
                units: a.units,
                frequency_variable: a.freq_variable.as_deref(),
            },
        )?;
        human.print(&format!("era identify {}\n", a.file.display()));
        return Ok(Source {
            input,
            estimate_s: None,
            coherence: None,
            time_format: None,
            records: None,
            frame: a.welch.frame_or_default(),
        });
    }
    let inputs = a.inputs.as_deref().unwrap_or_default();
    let Some(outputs) = a.outputs.as_deref() else {
        return crate::error::usage("--from-time needs --outputs CHANNELS (e.g. --outputs 3-30)");
    };
    let quantity = a.quantity.unwrap_or(era::Quantity::Acceleration);
    let mut found = crate::input::time::estimate_from_time(
        &record_paths(a),
        inputs,
        outputs,
        &a.welch,
        quantity,
        a.markov == era::sources::MarkovSource::Okid,
        settings,
    )?;
    set_units(&mut found.input, a.units);
    human.print(&format!(
        "era identify --from-time {}\n{}",
        record_paths(a)
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(" "),
        found.summary
    ));
    if let (Some(path), Some(set)) = (&a.save_frf, frf_outputs) {
        let coherence = crate::output::estimate::write_estimate(
            set,
            path,
            &found.input.file,
            &found.estimate,
            false,
        )?;
        human.print(&format!(
            "  wrote {} and {}\n",
            path.display(),
            coherence.display()
        ));
    }
    let facts = &found.facts;
    let time_format = format!(
        "time histories ({}); FRFs estimated here: {} estimator, {} window, frame {}, {} averages",
        facts.format, facts.estimator, facts.window, facts.frame, facts.averages
    );
    Ok(Source {
        estimate_s: Some(found.timings.1),
        coherence: Some(InputCoherence::multiple(&found.estimate)),
        time_format: Some(time_format),
        frame: found.facts.frame,
        input: found.input,
        records: found.records,
    })
}

/// The route's window correction of `input` (a Welch estimate's lag window divided
/// out), said on the terminal.
fn correct_window(
    a: &Identify,
    route: &Route,
    input: &mut InputFrf,
    human: &Human,
) -> anyhow::Result<()> {
    if !route.window_correction {
        return Ok(());
    }
    if let Some((corrected, why)) =
        crate::config::window_corrected(&input.file.frf, &input.file.metadata)
            .with_context(|| format!("correcting the window of {}", a.file.display()))?
    {
        input.file.frf = corrected;
        human.print(&format!(
            "  window correction: {why} (--no-window-correction: off)\n"
        ));
    }
    Ok(())
}

/// The lines the refinement fits and the scan judges: measured lines only (never the
/// zero lines a late start was padded with, or --zero-lines zeroed), inside the band
/// when there is one; the band said on the terminal.
fn fit_lines(
    a: &Identify,
    frf: &era::FrfData,
    coherence: Option<&InputCoherence>,
    route: &Route,
    human: &Human,
) -> anyhow::Result<era::frf::FitLines> {
    let band = identify_band(a, frf, coherence, route.coherence_band)?;
    let fit = era::frf::fit_lines(
        frf,
        a.options.zero_lines,
        band.as_ref().ok().map(|b| (b.0, b.1)),
    )
    .map_err(|why| {
        let text = a.band.clone().unwrap_or_else(|| match &band {
            Ok((lo, hi, _)) => format!("{lo}..{hi}"),
            Err(_) => String::new(),
        });
        crate::error::UsageError(format!("--band {text}: {why}"))
    })?;
    match (&band, fit.band_hz) {
        (Ok((_, _, why)), Some((lo, hi))) => {
            human.print(&format!("  band: {lo}..{hi} Hz, {why}\n"))
        }
        (Err(why), _) | (Ok((_, _, why)), None) => human.print(&format!("  band: {why}\n")),
    }
    Ok(fit)
}

/// The refinement of ERA's model on the route, and with `--from-time` and the automatic
/// order the frame check.
fn refine_route(
    a: &Identify,
    found: era::Identification,
    frf: &era::FrfData,
    check: &Check,
    auto: bool,
    human: &Human,
    settings: &Settings,
) -> anyhow::Result<era::Identification> {
    let era_fit = &found.fit;
    human.print(&format!(
        "\nERA model: {} states, {} modes; fit collocated {}, non-collocated {}\n",
        found.model.states(),
        found.modal.modes.len(),
        era_fit
            .collocated_mean_relative_error
            .map_or("-".into(), |v| format!("{v:.3e}")),
        era_fit
            .noncollocated_mean_relative_error
            .map_or("-".into(), |v| format!("{v:.3e}"))
    ));
    let mut found = crate::commands::refine::refine_found(
        found,
        frf,
        check.refine_options,
        Some(check.route.domain),
        settings,
    )
    .with_context(|| format!("refining the model of {}", a.file.display()))?;
    human.print(&crate::commands::refine::summary(&found));
    if a.from_time && auto && !a.no_frame_check {
        human.print(&frame_check(a, &mut found, check)?);
    }
    Ok(found)
}

/// model.json of the run: the identification, the parameters as run (the automatic
/// order, the scan's orders, the preset, the refinement's), and the route's cautions
/// before the warnings, as they led the echo.
fn model_json(
    found: &era::Identification,
    opts: &era::EraOptions,
    route: &Route,
    refine_options: &era::refine::RefineOptions,
    auto: bool,
    states: usize,
) -> ModelJson {
    let mut params = ModelParameters::new(opts);
    if auto {
        params.automatic_order = true;
        params.model_states = Some(states);
    }
    params.orders = found.stabilization.as_ref().map(|st| st.range.to_string());
    params.preset = Some(route.preset.name().to_string());
    if route.refine {
        params.refinement = Some(refine_options.clone());
        params.model_states = Some(found.model.states());
    }
    let mut model = ModelJson::from_run(found, &params);
    model.warnings.splice(0..0, route.cautions.iter().cloned());
    model
}

/// What a run hands to its outputs besides the identification.
struct Written {
    model: ModelJson,
    timings: std::collections::BTreeMap<String, f64>,
    echo: String,
    states: usize,
}

/// The run's files into `out` (staged, not yet committed), model.json last and once
/// (with the timings when asked for, the write's among them); returns model.json.
fn write(
    a: &Identify,
    mut out: Option<(&mut OutputSet, &RunInput)>,
    found: &era::Identification,
    written: Written,
    human: &Human,
    settings: &Settings,
) -> anyhow::Result<ModelJson> {
    let Written {
        mut model,
        mut timings,
        echo,
        states,
    } = written;
    let fit = FitJson::from_report(&found.fit);
    if let Some((set, source)) = out.as_mut() {
        let clock = Instant::now();
        let title = format!("era identify {}", a.file.display());
        let bundle = Bundle {
            found,
            fit: &fit,
            source,
            title: &title,
            echo: &echo,
            states,
            figures: !a.no_figures,
        };
        write_bundle(set, std::path::Path::new(""), &bundle, settings)?;
        timings.insert("write".into(), clock.elapsed().as_secs_f64());
    }
    if settings.timings {
        if let Some(wall) = crate::output::report::process_seconds() {
            timings.insert(crate::output::report::WALL.into(), wall);
        }
        human.print(&timings_table(&timings));
        human.print(&svd_path_line(&found.realization));
        model.timings_s = Some(timings);
    }
    // model.json once, with the timings when they were asked for.
    if let Some((set, _)) = out.as_mut() {
        write_model(set, std::path::Path::new(""), &model)?;
    }
    Ok(model)
}

/// ERA on `frf` as the flags ask: the automatic order, a fixed order judged against a
/// scan, or a fixed order alone; a spinner on stderr meanwhile.
fn realize(
    a: &Identify,
    frf: &era::FrfData,
    supplied: Option<&MarkovSequence>,
    era_opts: &era::EraOptions,
    scan_options: &ScanOptions,
    auto: bool,
    settings: &Settings,
) -> anyhow::Result<era::Identification> {
    let spinner = crate::output::progress::spinner(settings);
    let mut on_stage = |stage: era::Stage| spinner.set_message(stage.name());
    let mut on_order = |done: usize, total: usize| {
        spinner.set_message(format!("stabilization: order {done} of {total}"));
    };
    let (stage, order) = (&mut on_stage, &mut on_order);
    let mut options = era_opts.clone();
    options.scan = scan_options.clone();
    let states = era_opts.order.states().unwrap_or(0);
    options.order = match (auto, scan_options.orders.is_some()) {
        (true, _) => Order::Auto,
        (false, true) => Order::Scan { states },
        (false, false) => Order::Fixed(states),
    };
    let found = match supplied {
        None => identify_observed(frf, &options, stage, order),
        Some(m) => identify_supplied(frf, m, &options, stage, order),
    }
    .map_err(|e| match e {
        era::EraError::InvalidParameter {
            name,
            value,
            reason,
        } if name == "orders" || (name == "states" && value == "auto") => anyhow::Error::from(
            crate::error::UsageError(format!(
                "--{name} {value}: {}",
                reason.message(era::params::Naming::Flag)
            )),
        ),
        era::EraError::NotEnoughMarkovSamples {
            needed, available, ..
        } if supplied.is_some() => anyhow::Error::from(crate::error::UsageError(format!(
            "--markov-samples {available}: the Hankel matrix needs {needed} Markov samples (states x hankel factor, plus the direct term): raise --markov-samples, or lower --states or --hankel-factor"
        ))),
        other => anyhow::Error::from(other),
    })
    .with_context(|| format!("identifying {}", a.file.display()));
    spinner.finish_and_clear();
    found
}

/// Fewest averages the frame check's second estimate needs.
const CHECK_AVERAGES: u64 = crate::config::JUDGING_AVERAGES as u64;

/// What the frame check repeats of the first identification.
struct Check<'a> {
    band_hz: Option<(f64, f64)>,
    era_opts: &'a era::EraOptions,
    scan_options: &'a ScanOptions,
    refine_options: &'a era::refine::RefineOptions,
    route: &'a era::identify::route::Route,
    /// OKID's Markov parameters, which the second identification realizes again.
    supplied: Option<&'a MarkovSequence>,
    /// Samples per frame of the first estimate.
    frame: usize,
}

/// With `--from-time`: the records are estimated again through frames twice as long
/// (half as long when the records are too short for that) and identified on the same
/// route, and `found`'s physical modes that are not found
/// again there are not physical ([`era::refine::identification::confirm_modes`]): a structure's
/// modes stay where they are, the poles a fit adds for leakage, a short frame's bias
/// or one estimate's noise do not. Skipped, and said, when the records give fewer than
/// [`CHECK_AVERAGES`] averages at either frame. Returns the lines to print.
fn frame_check(
    a: &Identify,
    found: &mut era::Identification,
    check: &Check,
) -> anyhow::Result<String> {
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
            &record_paths(a),
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
        return Ok(format!(
            "  frame check: skipped: at frames of {}, these records give no estimate with at least {CHECK_AVERAGES} averages (--no-frame-check: off)\n",
            if tried.is_empty() { "twice or half the frame".to_string() } else { tried.join(" and ") }
        ));
    };
    match second_identification(a, second, other, check, &quiet) {
        Ok(again) => {
            let unconfirmed = era::refine::identification::confirm_modes(found, &again, other);
            Ok(format!(
                "  frame check: identified again from frames of {other} samples ({averages} averages, {:.2} s): {unconfirmed} physical mode(s) not found again, so not physical (--no-frame-check: off)\n",
                clock.elapsed().as_secs_f64()
            ))
        }
        // The check vouches for modes; when it cannot be made, the run stands as it is.
        Err(e) => Ok(format!(
            "  frame check: skipped: the second estimate (frames of {other} samples) could not be identified: {e:#}\n"
        )),
    }
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
    if check.route.window_correction {
        if let Some((corrected, _)) =
            crate::config::window_corrected(&frf, &second.input.file.metadata)?
        {
            frf = corrected;
        }
    }
    let mut refine_options = check.refine_options.clone();
    refine_options.band = check.band_hz.and_then(|b| {
        let (first, end) = era::frf::band_lines(frf.frequency_hz(), b, 0);
        (end > first).then_some((first, end))
    });
    // Zeroed lines are a count of lines: the same Hz at the other frame.
    let mut era_opts = check.era_opts.clone();
    era_opts.zero_lines = (era_opts.zero_lines * other).div_ceil(check.frame.max(1));
    let again = realize(
        a,
        &frf,
        check.supplied,
        &era_opts,
        check.scan_options,
        true,
        quiet,
    )?;
    crate::commands::refine::refine_found(
        again,
        &frf,
        &refine_options,
        Some(check.route.domain),
        quiet,
    )
}

/// The route's choices, one line each, with their reasons; then its cautions.
fn route_echo(route: &era::identify::route::Route) -> String {
    let mut text = format!("route (--preset {})\n", route.preset.name());
    for line in route.echo() {
        text.push_str(&format!("  {line}\n"));
    }
    for caution in &route.cautions {
        text.push_str(&format!("  warning: {caution}\n"));
    }
    text
}

/// The band to identify over: `--band LO..HI`, or (when the route takes the band from
/// the coherence) where the coherence is at least [`era::frf::BAND_COHERENCE`]
/// (`era::frf::coherence_band`), with the reason to echo; `Err(why)` inside the `Ok`
/// for every line, with the reason.
fn identify_band(
    a: &Identify,
    frf: &era::FrfData,
    estimated: Option<&crate::output::InputCoherence>,
    from_coherence: bool,
) -> anyhow::Result<Result<(f64, f64, String), String>> {
    if let Some(text) = a
        .band
        .as_ref()
        .filter(|t| !t.trim().eq_ignore_ascii_case("all"))
    {
        // Checked against the data by era::frf::fit_lines.
        let Some((lo, hi)) = crate::config::parse_band(text) else {
            return crate::error::usage(format!(
                "--band {text}: expected LO..HI in Hz, e.g. 60..500, or all"
            ));
        };
        return Ok(Ok((lo, hi, "as --band says".into())));
    }
    if !from_coherence {
        return Ok(Err("every line, as the route asks".into()));
    }
    let companion;
    let (curves, source) = match estimated {
        Some(c) => (c, "estimated here".to_string()),
        None => match crate::output::InputCoherence::companion(&a.file, frf) {
            Ok(Some(c)) => {
                companion = c;
                (
                    &companion,
                    crate::output::coherence_path(&a.file).display().to_string(),
                )
            }
            _ => {
                return Ok(Err(format!(
                "every line: no coherence (no {} beside the file; --band LO..HI to set the band)",
                crate::output::coherence_path(&a.file).display()
            )))
            }
        },
    };
    let values: Vec<Vec<f64>> = curves.curves.iter().map(|(_, v)| v.clone()).collect();
    Ok(
        match era::frf::coherence_band(&curves.frequency_hz, &values) {
            Some((lo, hi)) => Ok((
                lo,
                hi,
                format!(
                    "where the coherence ({source}) is at least {} (--band LO..HI to set it)",
                    era::frf::BAND_COHERENCE
                ),
            )),
            None => Err(format!(
                "every line: the coherence ({source}) marks no narrower band where it is at least {} (--band LO..HI to set it)",
                era::frf::BAND_COHERENCE
            )),
        },
    )
}

/// The time files: the first and any more records of the test.
fn record_paths(a: &Identify) -> Vec<std::path::PathBuf> {
    std::iter::once(a.file.clone())
        .chain(a.more.iter().cloned())
        .collect()
}

/// The channels of a record as slices.
fn channels(set: &[Vec<f64>]) -> Vec<&[f64]> {
    set.iter().map(Vec::as_slice).collect()
}

/// OKID on the records (`--markov okid`), a spinner meanwhile; an input it cannot use
/// is named by its channel.
fn observe(
    a: &Identify,
    records: &crate::input::time::TimeRecords,
    settings: &Settings,
) -> anyhow::Result<Observed> {
    use era::sources::okid::{okid, OkidOptions, Record};
    let mut options = OkidOptions::default();
    options.observer_order = a.observer_order;
    let longest = records
        .records
        .iter()
        .filter_map(|r| r.inputs.first().map(|c| c.len()))
        .max()
        .unwrap_or(0);
    options.markov_samples = a
        .markov_samples
        .unwrap_or_else(|| era::sources::okid::default_markov_samples(longest));
    options.sample_time_s = 1.0 / records.rate;
    let inputs: Vec<Vec<&[f64]>> = records
        .records
        .iter()
        .map(|r| channels(&r.inputs))
        .collect();
    let outputs: Vec<Vec<&[f64]>> = records
        .records
        .iter()
        .map(|r| channels(&r.outputs))
        .collect();
    let recs: Vec<Record> = inputs
        .iter()
        .zip(&outputs)
        .map(|(ins, outs)| Record {
            inputs: ins,
            outputs: outs,
        })
        .collect();
    let spinner = crate::output::progress::spinner(settings);
    spinner.set_message("OKID: the observer's least squares");
    let clock = Instant::now();
    let found = okid(&recs, &options);
    spinner.finish_and_clear();
    let found = found.map_err(|e| {
        let named = match &e {
            era::EraError::DeficientInput { input, .. } => Some(format!(
                "--inputs: channel {} cannot drive OKID",
                records.input_labels[input - 1]
            )),
            _ => None,
        };
        let files = records
            .records
            .iter()
            .map(|r| r.path.display().to_string())
            .collect::<Vec<_>>()
            .join(", ");
        let err = anyhow::Error::new(e).context(format!("OKID on {files}"));
        match named {
            Some(text) => err.context(text),
            None => err,
        }
    })?;
    Ok(Observed {
        okid: found,
        seconds: clock.elapsed().as_secs_f64(),
    })
}

/// The echo's OKID section: the observer, how the system's Markov parameters came from
/// it, and the residual.
fn okid_echo(o: &Observed) -> String {
    use era::sources::okid::MarkovRoute;
    let k = &o.okid;
    let how = if k.criterion.is_empty() {
        "as --observer-order says".to_string()
    } else {
        format!(
            "the least BIC of orders 1..{}",
            k.criterion.last().map_or(0, |c| c.0)
        )
    };
    let route = match k.route {
        MarkovRoute::Recursion => format!(
            "from the recursion (observer roots within {:.3} of the origin)",
            k.observer_radius
        ),
        MarkovRoute::UnitCircle { points } => format!(
            "from the unit circle ({points} points): the least-squares observer has roots out to {:.2}, where the recursion would grow",
            k.observer_radius
        ),
        _ => "other".into(),
    };
    let mut res = k.residual.clone();
    res.sort_by(f64::total_cmp);
    let median = res.get(res.len() / 2).copied().unwrap_or(f64::NAN);
    format!(
        "Markov parameters (--markov okid)\n  observer order          {} ({how})\n  equations               {} samples x {} unknowns per output (rank {})\n  Markov blocks           {}, {route}\n  one-step residual       {:.3} of the output RMS (median over outputs)\n",
        k.observer_order,
        k.equations,
        k.regressors,
        k.rank,
        k.markov.samples(),
        median
    )
}

/// model.json's record of OKID: `markov: "okid"` and the observer's facts.
fn okid_json(o: &Observed, model: &mut ModelJson) {
    model.parameters.markov = Some(era::sources::MarkovSource::Okid);
    model.parameters.okid = Some(era_io::model_json::okid_json(&o.okid));
}

/// `--weighting coherence`, and the refinement's default when it refines OKID's model:
/// each line of a pair weighted by its output's multiple coherence from the estimate
/// (the lines where the test carried information count, the rest hardly).
fn coherence_weighting(
    a: &Identify,
    route: &Route,
    coherence: Option<&InputCoherence>,
    frf: &era::FrfData,
    options: &mut era::refine::RefineOptions,
) -> anyhow::Result<()> {
    let asked = a.weighting == Some(WeightingGiven::Coherence);
    let okid_default =
        a.weighting.is_none() && a.markov == era::sources::MarkovSource::Okid && route.refine;
    if !(asked || okid_default) {
        return Ok(());
    }
    // Estimated here, or the coherence file `era frf` wrote beside the FRFs.
    let companion;
    let c = match coherence {
        Some(c) => c,
        None => match InputCoherence::companion(&a.file, frf) {
            Ok(Some(found)) => {
                companion = found;
                &companion
            }
            Ok(None) => {
                return crate::error::usage(format!(
                    "--weighting coherence weights by the estimate's coherence: use it with --from-time, or keep {} beside the FRFs",
                    crate::output::coherence_path(&a.file).display()
                ))
            }
            Err(why) => return crate::error::usage(format!("--weighting coherence: {why}")),
        },
    };
    let (q, p, lines) = (frf.outputs(), frf.inputs(), frf.lines());
    let curves: Vec<&[f64]> = c.curves.iter().map(|(_, v)| v.as_slice()).collect();
    // One curve per output (multiple coherence, for every input) or per pair.
    let weighting = era::refine::Weighting::coherence_of(&curves, q, p)
        .filter(|_| curves.iter().all(|v| v.len() == lines));
    let Some(weighting) = weighting else {
        return crate::error::usage(format!(
            "--weighting coherence: the coherence ({} curves) does not match the FRFs ({q} outputs x {p} inputs x {lines} lines)",
            c.curves.len()
        ));
    };
    options.weighting = weighting;
    Ok(())
}
