//! `era identify`'s settings that depend on the data read ([`Plan`]): the route for
//! the data's quantity, the window correction, the band and its lines, the scan's
//! options and the coherence weighting of the refinement.

use crate::config::{apply_route, era_options, Identify, WeightingGiven};
use crate::input::InputFrf;
use crate::output::report::Human;
use crate::output::InputCoherence;
use anyhow::Context;
use era::identify::route::Route;
use era::identify::{EraOptions, ScanOptions};
use era::refine::RefineOptions;

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
