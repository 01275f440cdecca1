//! `era identify`'s settings: its flags checked into an [`Identify`] (ERA's options, the
//! route asked for, the refinement's options) before anything is read, and what the
//! data decides once it is ([`Plan`]): the route for the data's quantity, the window
//! correction, the band and its lines, the scan's options and the coherence weighting
//! of the refinement.

use crate::args::{IdentifyArgs, StatesArg};
use crate::config::{parse_band, refine_given, refine_options, Settings, Welch};
use crate::input::InputFrf;
use crate::output::report::Human;
use crate::output::InputCoherence;
use anyhow::Context;
use era::identify::route::Route;
use era::identify::route::RouteRequest;
use era::identify::ModelDomain;
use era::identify::{EraOptions, ScanOptions};
use era::modal::stabilization::OrderRange;
use era::params::Naming;
use era::pipeline::realize::DirectTerm;
use era::refine::RefineOptions;
use std::path::PathBuf;

/// The refinement's weighting asked for by name: one of the core's (set in
/// [`Identify::refine`]), or the estimate's coherence, whose values come with the data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WeightingGiven {
    /// `uniform` or `pair-noise`.
    Named,
    /// `coherence`.
    Coherence,
}

/// `era identify`: the data and how to read or estimate it, ERA's options, the route
/// asked for, the refinement and where the files go; checked under the flags' names
/// before anything is read.
#[derive(Debug, Clone)]
pub struct Identify<'a> {
    /// The FRF file, or the first time-history file.
    pub file: PathBuf,
    /// More time-history files (records of one test).
    pub more: Vec<PathBuf>,
    /// ERA's options ([`options`]); the route's domain and direct term are set once the
    /// data is read ([`apply_route`]).
    pub options: EraOptions,
    /// The route asked for ([`route_request`]).
    pub request: RouteRequest,
    /// The refinement's options, checked ([`refine_options`]).
    pub refine: RefineOptions,
    /// The weighting asked for by name, when given.
    pub weighting: Option<WeightingGiven>,
    /// The scan's orders (`--orders`), when given.
    pub orders: Option<OrderRange>,
    /// What the FRFs (or the outputs) measure, when given.
    pub quantity: Option<era::Quantity>,
    /// `--outputs`: the FRF file's output count, or the time files' output channels.
    pub outputs: Option<String>,
    /// Input channels of the time files.
    pub inputs: Option<String>,
    /// Units of the FRFs, when given.
    pub units: Option<&'a crate::args::UnitsArg>,
    /// A MAT file's frequency variable, when not `FreqV`.
    pub freq_variable: Option<String>,
    /// `--band`, as given.
    pub band: Option<String>,
    /// The data are time histories.
    pub from_time: bool,
    /// No check of the model against a second frame.
    pub no_frame_check: bool,
    /// Where the Markov parameters come from.
    pub markov: era::sources::MarkovSource,
    /// OKID's observer order.
    pub observer_order: era::sources::okid::ObserverOrder,
    /// Markov blocks OKID returns, when given.
    pub markov_samples: Option<usize>,
    /// How FRFs are estimated from the time histories.
    pub welch: Welch,
    /// File for the estimated FRFs.
    pub save_frf: Option<PathBuf>,
    /// How the figures draw the phase.
    pub phase: era_plot::PhaseView,
    /// The pairs overlaid one by one (`--pairs`).
    pub pairs: era_plot::PairSelection,
    /// Folder for the files, when asked for.
    pub out: Option<PathBuf>,
    /// Model files but no figures and no report.
    pub no_figures: bool,
    /// The output switches.
    pub settings: Settings,
    /// `--geometry`, when given.
    pub geometry: Option<PathBuf>,
}

impl<'a> Identify<'a> {
    /// The time files: the first and any more records of the test.
    pub fn record_paths(&self) -> Vec<PathBuf> {
        std::iter::once(self.file.clone())
            .chain(self.more.iter().cloned())
            .collect()
    }

    /// The settings of the flags, checked in the order the flags' errors are reported.
    pub fn new(a: &'a IdentifyArgs) -> anyhow::Result<Self> {
        use crate::args::{ObserverOrderArg, WeightingArg};
        use era::sources::okid::ObserverOrder;
        let options = options(a)?;
        let orders = scan_orders(a)?;
        let request = route_request(a);
        let refine = identify_refine_options(a, &request)?;
        Ok(Identify {
            file: a.file.clone(),
            more: a.more.clone(),
            options,
            request,
            refine,
            weighting: a.refine_fit.weighting.as_ref().map(|w| match w {
                WeightingArg::Named(_) => WeightingGiven::Named,
                WeightingArg::Coherence => WeightingGiven::Coherence,
            }),
            orders,
            quantity: a.quantity,
            outputs: a.outputs.clone(),
            inputs: a.inputs.clone(),
            units: a.facts.units.as_ref(),
            freq_variable: a.facts.freq_variable.clone(),
            band: a.band.clone(),
            from_time: a.from_time,
            no_frame_check: a.no_frame_check,
            markov: a.markov,
            observer_order: match a.observer_order {
                Some(ObserverOrderArg::Fixed(p)) => ObserverOrder::Fixed(p),
                Some(ObserverOrderArg::Auto) | None => ObserverOrder::Auto { max: None },
            },
            markov_samples: a.markov_samples,
            welch: Welch::from(&a.welch),
            save_frf: a.save_frf.clone(),
            phase: a.phase.into(),
            pairs: a.pairs.pairs.clone(),
            out: a.out.clone(),
            no_figures: a.no_figures,
            settings: Settings::from(&a.common),
            geometry: a.geometry.geometry.clone(),
        })
    }
}

/// The refinement's options, refused when given while the route asked for does not
/// refine: whether it refines depends on the preset, not on the data's quantity, so it
/// is known before anything is read.
fn identify_refine_options(
    a: &IdentifyArgs,
    request: &RouteRequest,
) -> anyhow::Result<RefineOptions> {
    let refine = request.resolve(era::Quantity::Acceleration, 0).refine;
    if !refine && refine_given(&a.refine_fit) {
        return crate::error::usage(
            "--residuals, --reciprocal, --free-residues, --no-added-modes, --weighting and --max-iterations set the refinement, which is off (--no-refine, --preset thesis or --markov okid): add --refine",
        );
    }
    refine_options(&a.refine_fit)
}

/// The route the flags ask for: the preset, and every choice given explicitly
/// (era::identify::route resolves the rest once the data's quantity is known).
pub fn route_request(a: &IdentifyArgs) -> RouteRequest {
    let mut r = RouteRequest::new(a.preset);
    r.states = match a.states {
        Some(StatesArg::Fixed(n)) => Some(n),
        Some(StatesArg::Auto) | None => None,
    };
    r.refine = if a.refine {
        Some(true)
    } else if a.no_refine {
        Some(false)
    } else {
        None
    };
    r.domain = a.time_domain;
    r.direct_term = a.direct_term;
    match a.band.as_deref().map(str::trim) {
        Some(t) if t.eq_ignore_ascii_case("all") => r.coherence_band = Some(false),
        // Parsed and checked against the data by the identification; the route only
        // says it is given.
        Some(t) => r.band_hz = parse_band(t),
        None => {}
    }
    r.window_correction = a.no_window_correction.then_some(false);
    r.markov = a.markov;
    r
}

/// The flags of the time-history route that only some routes take, refused elsewhere
/// before anything is read.
fn check_time_flags(a: &IdentifyArgs) -> anyhow::Result<()> {
    use era::sources::MarkovSource;
    if !a.from_time && !a.more.is_empty() {
        return crate::error::usage(format!(
            "{}: identify takes one FRF file; several files are records of one test with --from-time",
            a.more[0].display()
        ));
    }
    let okid = a.markov == MarkovSource::Okid;
    if !okid {
        for (given, flag) in [
            (a.observer_order.is_some(), "--observer-order"),
            (a.markov_samples.is_some(), "--markov-samples"),
        ] {
            if given {
                return crate::error::usage(format!(
                    "{flag} sets OKID's observer, which runs with --markov okid only"
                ));
            }
        }
        return Ok(());
    }
    for (value, flag) in [
        (a.integrations, "--integrations"),
        (a.pad_to, "--pad-to"),
        (a.zero_lines, "--zero-lines"),
    ] {
        if value != 0 {
            return crate::error::usage(format!(
                "{flag} {value}: it shapes the FRFs' inverse transform, and with --markov okid the Markov parameters come from the observer: leave it out"
            ));
        }
    }
    if let Some(n) = a.markov_samples {
        if n < 2 {
            return crate::error::usage(format!(
                "--markov-samples {n}: OKID returns at least 2 Markov blocks (the direct term and one more)"
            ));
        }
        era::params::limits::SAMPLES.check("--markov-samples", n as u64)?;
    }
    Ok(())
}

/// The route's domain and direct term in `options` (the rest of the route is the
/// front end's: refinement, band, window correction).
pub fn apply_route(options: &mut EraOptions, route: &Route) {
    options.domain = route.domain;
    options.direct_term = route.direct_term;
}

/// The options ERA runs with on `route` ([`Route::realization_domain`]).
pub fn era_options(options: &EraOptions, route: &Route) -> EraOptions {
    let mut o = options.clone();
    o.domain = route.realization_domain();
    o
}

/// Options from flags, with the checks clap cannot do (those of the library call are
/// [`EraOptions::check`], shared with the Python package; `--orders` is the CLI's own).
/// The domain and direct term are those given, or the thesis's until
/// [`apply_route`] sets the route's.
pub fn options(a: &IdentifyArgs) -> anyhow::Result<EraOptions> {
    let auto = !matches!(a.states, Some(StatesArg::Fixed(_)));
    let states = match a.states {
        Some(StatesArg::Fixed(n)) => n,
        // The scan sets its own orders; this is only echoed.
        _ => 0,
    };
    let mut opts = EraOptions::new(states, a.hankel_factor);
    opts.integrations = a.integrations;
    opts.lowpass = a.lowpass_hz.map(|hz| (a.lowpass_order, hz));
    opts.zero_lines = a.zero_lines;
    opts.pad_to = a.pad_to;
    opts.domain = a.time_domain.unwrap_or(ModelDomain::Discrete);
    opts.direct_term = a.direct_term.unwrap_or(DirectTerm::Zero);
    opts.svd = a.svd;
    if a.era_dc {
        opts.realizer = era::identify::Realizer::EraDc;
    }
    check_time_flags(a)?;
    // Sizes are checked against their limits here, under the flag's name, before anything
    // is read or allocated (the core checks them again for library users). With
    // --states auto every other parameter is checked as for one state.
    let checked = {
        let mut o = opts.clone();
        o.order = era::Order::Fixed(states.max(usize::from(auto)));
        o
    };
    checked.check(Naming::Flag)?;
    use era::params::limits::SAMPLES;
    if let Some(range) = scan_orders(a)? {
        SAMPLES.check_product(
            format!("--orders {} x --hankel-factor (Markov samples)", range.max),
            &[range.max as u64, a.hankel_factor as u64],
        )?;
    }
    Ok(opts)
}

/// `--orders` parsed, naming the flag in errors.
pub fn scan_orders(a: &IdentifyArgs) -> anyhow::Result<Option<OrderRange>> {
    match &a.orders {
        None => Ok(None),
        Some(text) => OrderRange::parse(text).map(Some).map_err(|e| {
            crate::error::UsageError(format!("--orders {text}: {}", reason_of(&e))).into()
        }),
    }
}

pub fn reason_of(e: &era::EraError) -> String {
    match e {
        era::EraError::InvalidParameter { reason, .. } => reason.message(Naming::Flag),
        other => other.message(Naming::Flag),
    }
}

/// `frf` with the lag window of the Welch estimate it came from divided out (see
/// [`lag_window`]), and the reason to echo; `None` when `metadata` names no such
/// window. Leading lines that are zero in every pair (a padded late start) stay zero:
/// the correction works on the impulse responses and would spread values into them.
pub fn window_corrected(
    frf: &era::FrfData,
    metadata: &std::collections::BTreeMap<String, String>,
) -> anyhow::Result<Option<(era::FrfData, String)>> {
    let Some((lag, why)) = lag_window(metadata) else {
        return Ok(None);
    };
    Ok(Some((lag.correct_frf(frf)?, why)))
}

/// The lag window of the Welch estimate an FRF file came from, when its metadata (an
/// `era frf` CSV, or `--from-time`) names the H1 estimator, a tapered window, the frame
/// and the sample rate; `None` for a rectangular window (transients need no
/// correction), another estimator, or when the file does not say. The reason goes to
/// the echo.
pub fn lag_window(
    metadata: &std::collections::BTreeMap<String, String>,
) -> Option<(era::sources::frf::LagWindow, String)> {
    use era::estimate::{Estimator, Window};
    // The words `era frf` writes; a file that says anything else is not corrected.
    let estimator = match metadata.get("estimator")?.trim() {
        "h1" => Estimator::H1,
        _ => return None,
    };
    let window = match metadata.get("window")?.trim() {
        "hann" => Window::Hann,
        "flattop" | "flat-top" => Window::FlatTop,
        _ => return None,
    };
    let frame: usize = metadata.get("frame")?.trim().parse().ok()?;
    let rate: f64 = metadata.get("sample_rate_hz")?.trim().parse().ok()?;
    let lag = era::sources::frf::LagWindow::of_estimate(estimator, window, frame, rate).ok()??;
    Some((
        lag,
        format!(
            "the Welch estimate's {} lag window (frames of {frame} samples at {rate} Hz) divided out of the FRFs (their impulse responses)",
            window.name()
        ),
    ))
}

/// What `era identify` runs with once the data is read.
pub struct Plan {
    /// The route the request resolves to for the data.
    pub route: Route,
    /// The order is chosen from the stabilization diagram.
    pub auto: bool,
    /// ERA's options on the route, as echoed and recorded in model.json.
    pub options: EraOptions,
    /// The options ERA realizes with (the route's realization domain).
    pub era: EraOptions,
    /// The scan's options: `--orders` and the band it judges poles in.
    pub scan: ScanOptions,
    /// The refinement's options: the lines it fits and its weighting.
    pub refine: RefineOptions,
    /// The lines fitted and the band, Hz.
    pub fit: era::data::frf::FitLines,
}

impl Plan {
    /// The route for `input`'s quantity, its window correction applied to `input` (and
    /// said), the flags checked against the data; then the band (said) and the
    /// weighting. `coherence` is the estimate's when the FRFs were estimated here.
    /// `describe` prints what was read and the echo between the two, in the order the
    /// terminal shows them.
    pub fn new(
        a: &Identify,
        input: &mut InputFrf,
        coherence: Option<&InputCoherence>,
        human: &Human,
        describe: impl FnOnce(&Route, &EraOptions, &InputFrf),
    ) -> anyhow::Result<Plan> {
        let route = a
            .request
            .resolve(input.file.frf.quantity(), a.options.integrations);
        let mut options = a.options.clone();
        apply_route(&mut options, &route);
        correct_window(a, &route, input, human)?;
        let frf = &input.file.frf;
        if a.out.is_some() {
            crate::output::figures::check_pairs(&a.pairs, frf.outputs(), frf.inputs())?;
        }
        if route.refine {
            check_shape(&a.refine, frf)?;
        }
        describe(&route, &options, input);
        let fit = fit_lines(a, frf, coherence, &route, human)?;
        let mut refine = a.refine.clone();
        refine.band = fit.lines;
        coherence_weighting(a, &route, coherence, frf, &mut refine)?;
        let mut scan = ScanOptions::default();
        scan.orders = a.orders.clone();
        scan.band_hz = fit.band_hz;
        Ok(Plan {
            auto: route.states.is_none(),
            era: era_options(&options, &route),
            route,
            options,
            scan,
            refine,
            fit,
        })
    }
}

/// `--reciprocal` needs a square set: said before the identification runs.
pub fn check_shape(options: &RefineOptions, frf: &era::FrfData) -> anyhow::Result<()> {
    if options.reciprocal && frf.outputs() != frf.inputs() {
        return crate::error::usage(format!(
            "--reciprocal: the set has {} outputs x {} inputs; reciprocity needs a square (collocated) set",
            frf.outputs(),
            frf.inputs()
        ));
    }
    Ok(())
}

/// The route's window correction of `input` (a Welch estimate's lag window divided
/// out), said on the terminal.
pub fn correct_window(
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
pub fn fit_lines(
    a: &Identify,
    frf: &era::FrfData,
    coherence: Option<&InputCoherence>,
    route: &Route,
    human: &Human,
) -> anyhow::Result<era::data::frf::FitLines> {
    let band = identify_band(a, frf, coherence, route.coherence_band)?;
    let fit = era::data::frf::fit_lines(
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

/// The band to identify over: `--band LO..HI`, or (when the route takes the band from
/// the coherence) where the coherence is at least [`era::data::frf::BAND_COHERENCE`]
/// (`era::data::frf::coherence_band`), with the reason to echo; `Err(why)` inside the `Ok`
/// for every line, with the reason.
pub fn identify_band(
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
        // Checked against the data by era::data::frf::fit_lines.
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
        match era::data::frf::coherence_band(&curves.frequency_hz, &values) {
            Some((lo, hi)) => Ok((
                lo,
                hi,
                format!(
                    "where the coherence ({source}) is at least {} (--band LO..HI to set it)",
                    era::data::frf::BAND_COHERENCE
                ),
            )),
            None => Err(format!(
                "every line: the coherence ({source}) marks no narrower band where it is at least {} (--band LO..HI to set it)",
                era::data::frf::BAND_COHERENCE
            )),
        },
    )
}

/// `--weighting coherence`, and the refinement's default when it refines OKID's model:
/// each line of a pair weighted by its output's multiple coherence from the estimate
/// (the lines where the test carried information count, the rest hardly).
pub fn coherence_weighting(
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
