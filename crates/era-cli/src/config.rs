//! Flags to validated options: `identify`'s (and `compare`'s) arguments become an
//! [`EraOptions`] and an [`OrderRange`], checked under the flags' names before anything is
//! read. The core names option fields ([`Naming`]); this module adds the flag names, so
//! other front ends (Python) can word the same checks their own way.

use crate::args::{CommonArgs, IdentifyArgs, RefineFitArgs, StatesArg};
use era::identify::route::{Route, RouteRequest};
use era::identify::{EraOptions, ModelDomain};
use era::modal::stabilization::OrderRange;
use era::params::Naming;
use era::pipeline::realize::DirectTerm;
use era::refine::RefineOptions;

/// How much a verb says on the terminal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verbosity {
    /// Nothing but errors (and the JSON with `--json`).
    Quiet,
    /// The human summary.
    Normal,
}

/// What every verb's output switches say: how much to print, whether to draw progress
/// on stderr, whether JSON owns stdout, and whether to time the stages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Settings {
    /// Human text or none.
    pub verbosity: Verbosity,
    /// Spinners and bars on stderr (indicatif hides them when stderr is no terminal).
    pub progress: bool,
    /// JSON on stdout, human text on stderr.
    pub json: bool,
    /// The wall time of each stage.
    pub timings: bool,
}

impl Settings {
    /// Nothing printed, nothing drawn: for a run inside a run (the frame check).
    pub fn silent() -> Self {
        Settings {
            verbosity: Verbosity::Quiet,
            progress: false,
            json: false,
            timings: false,
        }
    }
}

impl From<&CommonArgs> for Settings {
    fn from(a: &CommonArgs) -> Self {
        Settings {
            verbosity: if a.quiet {
                Verbosity::Quiet
            } else {
                Verbosity::Normal
            },
            progress: !a.quiet,
            json: a.json,
            timings: a.timings,
        }
    }
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
        era::limits::SAMPLES.check("--markov-samples", n as u64)?;
    }
    Ok(())
}

/// `LO..HI` as two numbers, or `None`.
pub fn parse_band(text: &str) -> Option<(f64, f64)> {
    let (lo, hi) = text.split_once("..")?;
    Some((lo.trim().parse().ok()?, hi.trim().parse().ok()?))
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
    use era::limits::SAMPLES;
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

fn reason_of(e: &era::EraError) -> String {
    match e {
        era::EraError::InvalidParameter { reason, .. } => reason.clone(),
        other => other.to_string(),
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
    use era::frf::estimate::{Estimator, Window};
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

/// The refinement options of the flags, checked before anything is read: at least one
/// iteration, and no more than [`era::limits::ITERATIONS`].
pub fn refine_options(fit: &RefineFitArgs) -> anyhow::Result<RefineOptions> {
    let mut o = RefineOptions::default();
    if let Some(r) = fit.residuals {
        o.residuals = r;
    }
    o.reciprocal = fit.reciprocal;
    o.rank_one = !fit.free_residues;
    o.add_missed = !fit.no_added_modes;
    // The coherence's values come with time histories: `identify` sets them.
    if let Some(crate::args::WeightingArg::Named(w)) = fit.weighting.clone() {
        o.weighting = w;
    }
    if let Some(n) = fit.max_iterations {
        if n == 0 {
            return crate::error::usage(
                "--max-iterations 0: the refinement needs at least one iteration",
            );
        }
        era::limits::ITERATIONS.check("--max-iterations", n as u64)?;
        o.max_iterations = n;
    }
    Ok(o)
}

/// Whether any refinement flag was given (they need `--refine` on `era identify`).
pub fn refine_given(fit: &RefineFitArgs) -> bool {
    fit.residuals.is_some()
        || fit.reciprocal
        || fit.free_residues
        || fit.no_added_modes
        || fit.max_iterations.is_some()
        || fit.weighting.is_some()
}

pub fn parse_range(text: &str) -> anyhow::Result<(f64, f64)> {
    let Some((lo, hi)) = text.split_once("..") else {
        return crate::error::usage(format!(
            "--damping {text}: expected MIN..MAX, e.g. 0.005..0.02"
        ));
    };
    match (lo.trim().parse::<f64>(), hi.trim().parse::<f64>()) {
        (Ok(lo), Ok(hi)) => Ok((lo, hi)),
        _ => crate::error::usage(format!("--damping {text}: MIN and MAX must be numbers")),
    }
}

/// `--noise`, checked by the simulator's rule.
pub fn check_noise(noise: f64) -> anyhow::Result<()> {
    Ok(era::sim::check_noise(era::params::Naming::Flag, noise)?)
}
