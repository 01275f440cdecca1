//! What `era identify` hands on: the terminal's summaries and echoes, the stages'
//! seconds, `model.json` and the run's files (staged in its folder).

use crate::config::identify::Plan;
use crate::config::{Identify, Settings};
use crate::input::source::Source;
use crate::input::{describe_input, shape_line, InputFrf};
use crate::output::identification::{write_bundle, write_model, Bundle};
use crate::output::report::PART;
use crate::output::report::{
    identification_summary, parameter_echo_states, print_json, stabilization_summary,
    svd_path_line, timings_table, Human,
};
use crate::output::{pair_fit_table, InputCoherence, RunInput};
use crate::work::Observed;
use era::identify::route::Route;
use era::identify::Order;
use era_io::atomic::OutputSet;
use era_io::geometry::Geometry;
use era_io::model_json::{timings_map, FitJson, ModelJson, ModelParameters};
use std::fmt::Write as _;
use std::time::Instant;

/// What `era identify` found, and how, for its outputs.
pub struct Found<'a> {
    /// The identification (refined when the route refines).
    pub found: era::Identification,
    /// ERA's states (before any refinement).
    pub states: usize,
    /// The settings it ran with.
    pub plan: &'a Plan,
    /// The route and parameters echoed (the report's Parameters).
    pub echo: String,
    /// Seconds reading the data (without an estimate's).
    pub read_s: f64,
    /// Seconds of the zero-start check.
    pub zero_start_s: f64,
    /// Seconds of the frame check, when it ran.
    pub frame_check_s: Option<f64>,
    /// OKID's Markov parameters, when they were the source.
    pub observed: Option<&'a Observed>,
}

/// The terminal's summary, model.json (on stdout too with `--json`) and, with `--out`,
/// the run's files, which take their place together; the verb's result for `era batch`.
pub fn hand_on(
    a: &Identify,
    mut outputs: Option<OutputSet>,
    geometry: Option<(String, Geometry)>,
    source: Source,
    f: Found,
    human: &Human,
) -> anyhow::Result<super::Done> {
    let Found {
        found,
        states,
        plan,
        echo,
        read_s,
        zero_start_s,
        frame_check_s,
        observed,
    } = f;
    let input = &source.input;
    let frf = &input.file.frf;
    print_found(&found, frf, states, human);
    let mut model = model_json(
        &found,
        &plan.options,
        &plan.route,
        &plan.refine,
        plan.auto,
        states,
    );
    let mut timings = timings(&found, read_s, source.estimate_s, plan.route.refine);
    timings.insert("zero_start".into(), zero_start_s);
    if let Some(seconds) = frame_check_s {
        timings.insert("frame_check".into(), seconds);
    }
    if let Some(o) = observed {
        okid_json(o, &mut model);
        timings.insert("okid".into(), o.seconds);
    }
    let written = Written {
        model,
        timings,
        echo,
        states,
    };
    let run_input = outputs
        .as_ref()
        .map(|_| run_input(a, input, source.time_format, source.coherence))
        .map(|mut r| {
            // The singular-value figure of a fixed order looks past it.
            if !plan.auto && observed.is_none() && a.orders.is_none() && !a.no_figures {
                let mut options = plan.era.clone();
                options.order = Order::Fixed(states);
                r.hankel = Some((frf.clone(), options));
            }
            r
        })
        .map(|r| crate::output::geometry::attach(r, geometry, frf.outputs()));
    let out = outputs.as_mut().zip(run_input.as_ref());
    let model = write(a, out, &found, written, human, &a.settings)?;
    if let (Some(dir), Some(set)) = (&a.out, outputs) {
        // Every output is in the staging folder: they all take their place now, or none.
        set.commit()?;
        human.print(&written_line(a, dir));
    }
    if a.settings.json {
        print_json(&model)?;
    }
    Ok(super::Done {
        model,
        channels: (1..=frf.outputs()).map(|o| o.to_string()).collect(),
    })
}

/// The summary of the identification, the fit per pair and the scan.
pub fn print_found(found: &era::Identification, frf: &era::FrfData, states: usize, human: &Human) {
    human.print(&identification_summary(found, states));
    human.print(&pair_fit_table(&found.fit, frf.outputs(), frf.inputs()));
    if let Some(st) = &found.stabilization {
        human.print(&stabilization_summary(st));
    }
}

/// The stages' seconds: the pipeline's, reading, the estimate and the refinement.
pub fn timings(
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
pub fn run_input(
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
pub fn written_line(a: &Identify, dir: &std::path::Path) -> String {
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

/// model.json of the run: the identification, the parameters as run (the automatic
/// order, the scan's orders, the preset, the refinement's), and the route's cautions
/// before the warnings, as they led the echo.
pub fn model_json(
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
pub struct Written {
    /// model.json as it stands before the write.
    pub model: ModelJson,
    /// The stages' seconds so far.
    pub timings: std::collections::BTreeMap<String, f64>,
    /// The route and parameters echoed (the report's Parameters).
    pub echo: String,
    /// The model's states.
    pub states: usize,
}

/// The run's files into `out` (staged, not yet committed), model.json last and once
/// (with the timings when asked for, the write's among them); returns model.json.
pub fn write(
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

/// `fit collocated X, non-collocated Y`: `fit`'s mean relative errors over the
/// collocated and the other pairs (`-` where there are none), as the lines around a
/// refinement say them.
pub fn fit_errors(fit: &era::pipeline::fit::FitReport) -> String {
    let error = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.3e}"));
    format!(
        "fit collocated {}, non-collocated {}",
        error(fit.collocated_mean_relative_error),
        error(fit.noncollocated_mean_relative_error)
    )
}

/// What was read: the FRFs' shape and notes, and the file's description.
pub fn read_lines(input: &InputFrf) -> String {
    format!(
        "  {}{}\n{}",
        shape_line(&input.file.frf),
        input.note,
        describe_input(input)
    )
}

/// The echo of the run: the route, OKID's observer when it was the source, and the
/// parameters (the automatic order said as such).
pub fn echo(route: &Route, options: &era::EraOptions, observed: Option<&Observed>) -> String {
    let auto = route.states.is_none();
    format!(
        "{}{}{}",
        route_echo(route),
        observed.map(okid_echo).unwrap_or_default(),
        parameter_echo_states(
            options,
            auto.then_some("auto (from the stabilization diagram)")
        )
    )
}

/// The route's choices, one line each, with their reasons; then its cautions.
pub fn route_echo(route: &era::identify::route::Route) -> String {
    let mut text = format!("route (--preset {})\n", route.preset.name());
    for line in route.echo() {
        text.push_str(&format!("  {line}\n"));
    }
    for caution in &route.cautions {
        text.push_str(&format!("  warning: {caution}\n"));
    }
    text
}

/// The echo's OKID section: the observer, how the system's Markov parameters came from
/// it, and the residual.
pub fn okid_echo(o: &Observed) -> String {
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
pub fn okid_json(o: &Observed, model: &mut ModelJson) {
    model.parameters.markov = Some(era::sources::MarkovSource::Okid);
    model.parameters.okid = Some(era_io::model_json::okid_json(&o.okid));
}

/// How the refinement went, in lines for the human summary.
pub fn refinement_summary(found: &era::Identification) -> String {
    let Some(r) = &found.refinement else {
        return String::new();
    };
    let f = &r.refinement;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\nrefinement ({} model of the {} data, residuals {}): {} start modes, {} kept; {} iterations, {}; fit over the band {:.3e} -> {:.3e} (weighted cost: free residues at the start {:.3e}, the model {:.3e}), {:.2} s",
        if f.sample_time_s.is_some() {
            "z-domain"
        } else {
            "continuous"
        },
        f.quantity,
        match (&f.lower, &f.upper) {
            (Some(_), Some(_)) => "lower+upper",
            (Some(_), None) => "lower",
            (None, Some(_)) => "upper",
            (None, None) => "none",
        },
        r.start_modes(),
        f.modes.len(),
        f.iterations,
        if f.converged {
            "converged"
        } else {
            "NOT converged (the iterations ran out: raise --max-iterations)"
        },
        f.fit_before,
        f.fit_after,
        f.cost_before,
        f.cost_after,
        found.timings.refine
    );
    let _ = writeln!(s, "  fitted domain: {}", r.fit_domain.reason);
    for line in r.start_lines() {
        let _ = writeln!(s, "  {line}");
    }
    let _ = writeln!(
        s,
        "  (± is one standard deviation from the Gauss-Newton covariance at the optimum, the noise taken from the residual)"
    );
    s
}
