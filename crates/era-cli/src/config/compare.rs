//! `era compare`'s checks before anything is read, and the options `--identify FLAGS`
//! realizes each set with.

use crate::config::{apply_route, options, route_request, Compare};
use crate::error::usage;
use era::identify::EraOptions;

/// `--bands` and `--fit-band` checked before anything is read.
pub fn check_bands(a: &Compare) -> anyhow::Result<()> {
    if a.bands.len() < 2
        || a.bands.iter().any(|b| !b.is_finite() || *b < 0.0)
        || a.bands.windows(2).any(|w| w[1] <= w[0])
    {
        return usage(format!(
            "--bands {:?}: need at least two increasing frequencies >= 0",
            a.bands
        ));
    }
    if a.fit_band.len() != 2 || !(a.fit_band[0] >= 0.0 && a.fit_band[1] > a.fit_band[0]) {
        return usage(format!(
            "--fit-band {:?}: need LOW,HIGH with LOW < HIGH",
            a.fit_band
        ));
    }
    Ok(())
}

/// The options `era compare --identify FLAGS` realizes the set at `path` with: plain
/// ERA at one order, on the route of an unrefined run. The flags are parsed when the
/// set is read, so that the files' errors come first.
pub fn compare_identify_options(
    flags: &[String],
    path: &std::path::Path,
    frf: &era::FrfData,
) -> anyhow::Result<EraOptions> {
    use clap::Parser;
    let mut argv = vec![path.display().to_string()];
    argv.extend(flags.iter().cloned());
    let parsed = crate::args::IdentifyFlags::try_parse_from(&argv)
        .map_err(|e| crate::error::UsageError(format!("--identify: {e}")))?;
    if parsed.args.refine || parsed.args.band.is_some() || parsed.args.from_time {
        return crate::error::usage(
            "--identify: compare realizes each set with plain ERA at one order; --refine, --band and --from-time do not apply (identify each set with era identify, then --model-a/--model-b)",
        );
    }
    let a = &parsed.args;
    if a.out.is_some()
        || a.no_figures
        || a.geometry.geometry.is_some()
        || !matches!(a.pairs.pairs, era_plot::PairSelection::All)
    {
        return crate::error::usage(
            "--identify: compare writes its own outputs; --out, --no-figures, --geometry and --pairs of identify do not apply (compare's --out holds compare.html and one PNG per pair)",
        );
    }
    let mut opts = options(&parsed.args)?;
    if opts.order.states().unwrap_or(0) == 0 {
        return crate::error::usage(
            "--identify needs --states N: compare realizes each set at one order",
        );
    }
    // Compare realizes with ERA alone: the route's refinement does not apply, and its
    // domain and direct term are those of an unrefined run.
    let mut request = route_request(&parsed.args);
    request.refine = Some(false);
    let route = request.resolve(frf.quantity(), opts.integrations);
    apply_route(&mut opts, &route);
    Ok(opts)
}
