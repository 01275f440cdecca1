//! Flags to validated options: `identify`'s (and `compare`'s) arguments become an
//! [`EraOptions`] and an [`OrderRange`], checked under the flags' names before anything is
//! read. The core names option fields ([`Naming`]); this module adds the flag names, so
//! other front ends (Python) can word the same checks their own way.

use crate::args::{DirectTermArg, IdentifyArgs, StatesArg, SvdArg, TimeDomainArg};
use era::identify::{EraOptions, ModelDomain};
use era::modal::stabilization::OrderRange;
use era::params::Naming;
use era::realize::{DirectTerm, SvdPath};

/// Options from flags, with the checks clap cannot do (those of the library call are
/// [`EraOptions::check`], shared with the Python package; `--orders` is the CLI's own).
pub fn options(a: &IdentifyArgs) -> anyhow::Result<EraOptions> {
    let states = match a.states {
        StatesArg::Fixed(n) => n,
        // The scan sets its own orders; this is only echoed.
        StatesArg::Auto => 0,
    };
    let opts = EraOptions {
        states,
        hankel_factor: a.hankel_factor,
        integrations: a.integrations,
        lowpass: a.lowpass_hz.map(|hz| (a.lowpass_order, hz)),
        zero_lines: a.zero_lines,
        pad_to: a.pad_to,
        domain: match a.time_domain {
            TimeDomainArg::Discrete => ModelDomain::Discrete,
            TimeDomainArg::Continuous => ModelDomain::Continuous,
        },
        direct_term: match a.direct_term {
            DirectTermArg::Zero => DirectTerm::Zero,
            DirectTermArg::Markov0 => DirectTerm::FirstMarkov,
        },
        svd: match a.svd {
            SvdArg::Dense => SvdPath::Dense,
            SvdArg::MatrixFree => SvdPath::MatrixFree,
            SvdArg::Auto => SvdPath::Auto,
        },
    };
    // Sizes are checked against their limits here, under the flag's name, before anything
    // is read or allocated (the core checks them again for library users). With
    // --states auto every other parameter is checked as for one state.
    let checked = EraOptions {
        states: states.max(usize::from(a.states == StatesArg::Auto)),
        ..opts.clone()
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
        Some(text) => OrderRange::parse(text)
            .map(Some)
            .map_err(|e| crate::UsageError(format!("--orders {text}: {}", reason_of(&e))).into()),
    }
}

fn reason_of(e: &era::EraError) -> String {
    match e {
        era::EraError::InvalidParameter { reason, .. } => reason.clone(),
        other => other.to_string(),
    }
}

/// The lag window of the Welch estimate an FRF file came from, when its metadata (an
/// `era frf` CSV, or `--from-time`) names the H1 estimator, a tapered window, the frame
/// and the sample rate; `None` for a rectangular window (transients need no
/// correction), another estimator, or when the file does not say. The reason goes to
/// the echo.
pub fn lag_window(
    metadata: &std::collections::BTreeMap<String, String>,
) -> Option<(era::markov::LagWindow, String)> {
    use era::frf::estimate::Window;
    // The lag window is H1's bias (an output-noise estimator); H2 and Hv differ.
    if metadata.get("estimator").map(|e| e.trim()) != Some("h1") {
        return None;
    }
    let window = match metadata.get("window")?.trim() {
        "hann" => Window::Hann,
        "flattop" | "flat-top" => Window::FlatTop,
        _ => return None,
    };
    let frame: usize = metadata.get("frame")?.trim().parse().ok()?;
    let rate: f64 = metadata.get("sample_rate_hz")?.trim().parse().ok()?;
    let lag = era::markov::LagWindow::new(window, frame, rate).ok()?;
    Some((
        lag,
        format!(
            "the Welch estimate's {} lag window (frames of {frame} samples at {rate} Hz) divided out of the FRFs (their impulse responses)",
            window.name()
        ),
    ))
}
