//! `report.html`: one self-contained file (inline SVG, inline CSS, no network), laid out
//! for a reader who starts at the top ([`report_html`]): a table of contents and a
//! summary (modes, model, fit in %, warnings), the modal table, the stabilization
//! diagram, the modes on the geometry when one is given ([`crate::viewer`]), the
//! warnings, the fit as an outputs × inputs matrix, the singular values, the coherence
//! when the input carries it, the overview grid, the pairs' overlays in a grid with a
//! picker (a few lines of inline script), and last what went in (file, format, units,
//! channel table, command line, version, date) and the parameters.
//!
//! Size: each figure appears once, its elements share style rules
//! ([`crate::render::compact_svg`]) and its curves are thinned to what a pixel shows
//! ([`crate::render::visible_points`], which keeps every peak), so an 8 × 8 set of 801
//! lines stays well under 2 MB.

use crate::figures::{typeset_units, FrfView};
use era::data::identification::Identification;
use std::fmt::Write as _;

/// One row of the channel table: which DOF an output or input is.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelRow {
    /// `output` or `input`.
    pub role: &'static str,
    /// 1-based index in the FRF matrix.
    pub index: usize,
    /// Node number.
    pub node: i64,
    /// Direction (`+Z`, `-X`, …).
    pub direction: String,
    /// Entity name, when the file gives one.
    pub entity: Option<String>,
}

/// What went into the run: the report's first section.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct InputSection {
    /// The input file (or a description of a synthetic set).
    pub file: String,
    /// Its format (`CSV`, `UFF 58`, `MAT v5`, time histories …).
    pub format: String,
    /// The FRFs' quantity as read (acceleration, velocity, displacement), with where
    /// it came from.
    pub quantity: String,
    /// The FRFs' units as read (`(m/s^2)/N`; `unit/unit` when the file does not say).
    pub units: String,
    /// The channel table, when there is one.
    pub channels: Vec<ChannelRow>,
    /// Notes on the input (padding, layout, estimation settings).
    pub notes: Vec<String>,
    /// The command line.
    pub command_line: String,
    /// `era` version.
    pub version: String,
    /// Date and time of the run (UTC).
    pub date: String,
}

/// Coherence of the input: a figure, and what it shows.
pub struct CoherenceInput<'a> {
    /// What the curves are (e.g. multiple coherence of each output).
    pub caption: &'a str,
    /// The figure, SVG.
    pub svg: &'a str,
}

/// What goes into a report besides the identification itself.
pub struct ReportInput<'a> {
    /// Page title.
    pub title: &'a str,
    /// What went in.
    pub source: &'a InputSection,
    /// Units and collocation of the pairs (from the channel table when there is one).
    pub view: &'a FrfView,
    /// The parameter echo, as printed before the run.
    pub parameters: &'a str,
    /// The identification.
    pub found: &'a Identification,
    /// Coherence, when the input carries it.
    pub coherence: Option<CoherenceInput<'a>>,
    /// Singular-value figure, SVG.
    pub singular_values_svg: &'a str,
    /// Stabilization diagram, SVG, when a scan ran.
    pub stabilization_svg: Option<&'a str>,
    /// Figures of their own after the stabilization diagram (an output-only run's
    /// spectral singular values and MAC matrix).
    pub sections: &'a [ReportSection<'a>],
    /// Overview grid, SVG (none for an output-only run, whose pairs are correlations).
    pub grid_svg: Option<&'a str>,
    /// The overlay of each pair shown ([`PairFigure`]).
    pub overlays: &'a [PairFigure],
    /// The modes on the test geometry, when one was given ([`crate::viewer`]).
    pub shapes: Option<&'a crate::viewer::ShapeView>,
    /// Responses alone (`era oma`): the model is fitted to the half spectrum of the
    /// output correlations, its columns are references, and nothing is collocated.
    pub output_only: bool,
}

/// A figure of its own in the report: its anchor, heading, caption and SVG.
pub struct ReportSection<'a> {
    /// The id of the heading (`fig-` + it for the figure).
    pub id: &'a str,
    /// The heading.
    pub heading: &'a str,
    /// What the figure shows (plain text).
    pub caption: &'a str,
    /// The figure, SVG.
    pub svg: &'a str,
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("–".into(), |x| format!("{x:.digits$}"))
}

/// The input section: a definition list and the channel table.
fn input_html(s: &InputSection) -> String {
    let mut h = String::from("<h2 id=\"input\">Input</h2>\n<dl id=\"input-facts\">");
    for (term, value) in [
        ("File", &s.file),
        ("Format", &s.format),
        ("Quantity", &s.quantity),
        ("Units", &typeset_units(&s.units)),
        ("Command", &s.command_line),
        ("era version", &s.version),
        ("Date", &s.date),
    ] {
        let _ = write!(h, "<dt>{term}</dt><dd>{}</dd>", escape(value));
    }
    h.push_str("</dl>\n");
    if !s.notes.is_empty() {
        h.push_str("<ul id=\"input-notes\">");
        for n in &s.notes {
            let _ = write!(h, "<li>{}</li>", escape(n));
        }
        h.push_str("</ul>\n");
    }
    if s.channels.is_empty() {
        h.push_str("<p id=\"channel-table\">The file has no channel table: the channels are known by their index only (with inputs, collocation is by index: output i with input i).</p>\n");
    } else {
        // A long table folds away (still in the page, one click to open).
        let _ = writeln!(
            h,
            "<details{}><summary>Channel table: {} outputs, {} inputs</summary>",
            if s.channels.len() <= 16 { " open" } else { "" },
            s.channels.iter().filter(|c| c.role == "output").count(),
            s.channels.iter().filter(|c| c.role == "input").count()
        );
        h.push_str("<table id=\"channel-table\"><tr><th>channel</th><th>node</th><th>direction</th><th>entity</th></tr>\n");
        for c in &s.channels {
            let _ = writeln!(
                h,
                "<tr><td>{} {}</td><td>{}</td><td>{}</td><td style=\"text-align:left\">{}</td></tr>",
                c.role,
                c.index,
                c.node,
                escape(&c.direction),
                escape(c.entity.as_deref().unwrap_or(""))
            );
        }
        h.push_str("</table></details>\n<p>Collocated pairs (same node and direction) are shaded in the fit table.</p>\n");
    }
    h
}

/// The fit as an outputs × inputs matrix: each cell the pair's relative error and its
/// RMS log-magnitude error (dB); collocated pairs shaded.
fn fit_matrix_html(
    fit: &era::pipeline::fit::FitReport,
    view: &FrfView,
    (q, p): (usize, usize),
    columns: &str,
) -> String {
    let mut h =
        format!("<table id=\"fit-table\" class=\"matrix\"><tr><th>output \\ {columns}</th>");
    for j in 1..=p {
        let _ = write!(h, "<th>{j}</th>");
    }
    h.push_str("</tr>\n");
    for i in 0..q {
        let _ = write!(h, "<tr><th>{}</th>", i + 1);
        for j in 0..p {
            match fit.pairs.iter().find(|f| f.output == i && f.input == j) {
                Some(f) => {
                    let _ = write!(
                        h,
                        "<td{}>{}<br><small>{:.2} dB</small></td>",
                        if view.is_collocated(i, j) {
                            " class=\"col\""
                        } else {
                            ""
                        },
                        percent(f.relative_error),
                        f.rms_log_magnitude_db
                    );
                }
                None => h.push_str("<td>–</td>"),
            }
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table>\n");
    h
}

/// Mean relative error and mean RMS log-magnitude error (dB) of the pairs whose
/// collocation is `collocated`.
fn fit_means(
    fit: &era::pipeline::fit::FitReport,
    view: &FrfView,
    collocated: bool,
) -> (Option<f64>, Option<f64>) {
    pairs_mean(fit, |f| view.is_collocated(f.output, f.input) == collocated).unzip()
}

/// Mean relative error and mean RMS log-magnitude error (dB) of the pairs `keep` keeps;
/// `None` when it keeps none.
fn pairs_mean(
    fit: &era::pipeline::fit::FitReport,
    keep: impl Fn(&era::pipeline::fit::PairFit) -> bool,
) -> Option<(f64, f64)> {
    let chosen: Vec<_> = fit.pairs.iter().filter(|f| keep(f)).collect();
    let n = chosen.len() as f64;
    (!chosen.is_empty()).then(|| {
        (
            chosen.iter().map(|f| f.relative_error).sum::<f64>() / n,
            chosen.iter().map(|f| f.rms_log_magnitude_db).sum::<f64>() / n,
        )
    })
}

/// The report's figures of their own, each a heading, a caption and the figure.
fn sections_html(sections: &[ReportSection<'_>]) -> String {
    let mut h = String::new();
    for section in sections {
        let _ = write!(
            h,
            "<h2 id=\"{0}\">{1}</h2>\n<p>{2}</p>\n<figure class=\"plot\" id=\"fig-{0}\">{3}</figure>\n",
            escape(section.id),
            escape(section.heading),
            escape(section.caption),
            section.svg
        );
    }
    h
}

/// One pair's overlay in the report: which pair (0-based), its title and its SVG.
#[derive(Debug, Clone, PartialEq)]
pub struct PairFigure {
    /// Output (row of the FRF matrix), 0-based.
    pub output: usize,
    /// Input (column), 0-based.
    pub input: usize,
    /// The title drawn in the figure.
    pub title: String,
    /// The figure, SVG.
    pub svg: String,
}

/// The overview grid.
fn grid_html(input: &ReportInput<'_>) -> String {
    input.grid_svg.map_or(String::new(), |grid| {
        format!(
            "<h2 id=\"grid\">All pairs</h2>\n<p>|G| in {}.</p>\n<figure class=\"plot wide\" id=\"fig-grid\">{}</figure>\n",
            escape(&typeset_units(&input.view.unit)),
            grid
        )
    })
}

/// The pair picker's script: shows the overlays of the chosen output, input, or the
/// collocated pairs only, and says how many are shown. No network, no library.
const PAIR_PICKER_JS: &str = "(function(){\
var o=document.getElementById('pair-output'),i=document.getElementById('pair-input'),\
c=document.getElementById('pair-collocated'),n=document.getElementById('pair-count'),\
f=document.querySelectorAll('#pairs figure');\
function show(){var k=0;f.forEach(function(e){var v=(o.value===''||e.dataset.output===o.value)&&\
(i.value===''||e.dataset.input===i.value)&&(!c.checked||e.dataset.collocated==='1');\
e.hidden=!v;if(v)k++;});n.textContent=k+' of '+f.length+' shown';}\
[o,i,c].forEach(function(e){e.addEventListener('change',show);});show();})();";

/// Every pair's overlay in a grid of as many columns as the page holds, with a picker
/// (output, input, collocated only) above it.
fn overlays_html(input: &ReportInput<'_>) -> String {
    let mut h = String::from("<h2 id=\"overlays\">Each pair</h2>\n");
    let (q, p) = (
        input.found.measured.outputs(),
        input.found.measured.inputs(),
    );
    let overlays = input.overlays;
    if overlays.len() < q * p {
        let _ = writeln!(
            h,
            "<p>{} of the {} pairs, as chosen with --pairs (every pair is in the grid above).</p>",
            overlays.len(),
            q * p
        );
    }
    let options = |role: &str, id: &str, pick: fn(&PairFigure) -> usize| {
        let mut chosen: Vec<usize> = overlays.iter().map(pick).collect();
        chosen.sort_unstable();
        chosen.dedup();
        let mut o = format!("<label>{role} <select id=\"{id}\"><option value=\"\">all</option>");
        for k in chosen {
            let _ = write!(o, "<option value=\"{}\">{}</option>", k + 1, k + 1);
        }
        o.push_str("</select></label>");
        o
    };
    let _ = writeln!(
        h,
        "<div id=\"pair-picker\">{}{}<label><input type=\"checkbox\" id=\"pair-collocated\"> collocated only</label><span id=\"pair-count\">{} shown</span></div>",
        options("Output", "pair-output", |f| f.output),
        options("Input", "pair-input", |f| f.input),
        overlays.len()
    );
    h.push_str("<div class=\"pairs\" id=\"pairs\">\n");
    // The title is drawn in each figure; the figure carries it as its label only.
    for pair in overlays {
        let _ = writeln!(
            h,
            "<figure class=\"plot overlay\" id=\"fig-pair-{}\" data-output=\"{}\" data-input=\"{}\" data-collocated=\"{}\" aria-label=\"{}\">{}</figure>",
            pair.output * p + pair.input + 1,
            pair.output + 1,
            pair.input + 1,
            u8::from(input.view.is_collocated(pair.output, pair.input)),
            escape(&pair.title).replace('"', "&quot;"),
            pair.svg
        );
    }
    let _ = writeln!(h, "</div>\n<script>{PAIR_PICKER_JS}</script>");
    h
}

/// ` ± σ` after a refined value (one standard deviation), empty otherwise.
fn plus_minus(std: Option<f64>) -> String {
    std.map_or(String::new(), |s| format!(" ± {s:.2e}"))
}

/// The paragraph on the refinement of a refined model: how the fit went, which modes
/// were dropped, and how to read `±`.
fn refinement_html(f: &era::data::identification::Identification) -> String {
    let Some(r) = &f.refinement else {
        return String::new();
    };
    let fit = &r.refinement;
    let mut h = format!(
        "<p id=\"refinement\">Refined model: poles, residues and residual terms fitted to the FRFs by maximum likelihood ({} model), starting from {} modes of ERA{}; {} kept. {} iterations, {}. Over the band, ‖G − Ĝ‖/‖G‖ went from {} to {}. The model, its FRFs and the table are the refined ones; ± is one standard deviation from the Gauss–Newton covariance at the optimum, with the noise variance taken from the residual.</p>\n",
        if fit.sample_time_s.is_some() { "z-domain, at the sample time" } else { "continuous" },
        r.start_modes(),
        match fit.added.len() {
            0 => String::new(),
            k => format!(" and {k} pole(s) added for modes it missed (below)"),
        },
        fit.modes.len(),
        fit.iterations,
        if fit.converged { "converged" } else { "<span class=\"suspect\">not converged</span>" },
        percent(fit.fit_before),
        percent(fit.fit_after),
    );
    let dropped = r.start_lines();
    if !dropped.is_empty() {
        h.push_str("<ul id=\"refinement-dropped\">");
        for d in dropped {
            let _ = write!(h, "<li>{}</li>", escape(&d));
        }
        h.push_str("</ul>\n");
    }
    h
}

/// The whole page: the title, a table of contents, a summary (modes, model, fit,
/// warnings), then the modes, the stabilization diagram and the shapes, the warnings,
/// the fit, the singular values, the pairs, and what went in.
pub fn report_html(input: &ReportInput<'_>) -> String {
    let f = input.found;
    let mut h = String::with_capacity(1 << 20);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><meta name=\"viewport\" content=\"width=device-width\"><title>{}</title>\n<style>{STYLE}</style></head><body>\n<h1>{}</h1>\n",
        escape(input.title),
        escape(input.title)
    );
    // The sections in reading order: what was found first (modes, stabilization,
    // shapes), then how well it fits and why, then the pairs, and what went in last.
    let warnings = f.warnings(era::params::Naming::Flag);
    let mut sections: Vec<(&str, &str, String)> = vec![
        ("modes", "Modes", modes_html(f, input.output_only)),
        (
            "stabilization",
            "Stabilization diagram",
            stabilization_html(input),
        ),
    ];
    // The shapes come right after the diagram (an output-only run's spectral singular
    // values, its quick look, before them); the figures that compare shapes follow.
    let (quick, others): (Vec<_>, Vec<_>) = input.sections.iter().partition(|s| s.id == "spectral");
    fn own<'s>(s: &'s ReportSection<'s>) -> (&'s str, &'s str, String) {
        (s.id, s.heading, sections_html(std::slice::from_ref(s)))
    }
    sections.extend(quick.into_iter().map(own));
    let shapes = crate::viewer::shapes_html(input.shapes);
    let shapes_heading = shapes.contains("id=\"shapes\"");
    sections.push((
        if shapes_heading { "shapes" } else { "" },
        "Mode shapes",
        shapes,
    ));
    sections.extend(others.into_iter().map(own));
    // Results to treat with care (era::identify::suspect): counted and named in the summary at
    // the top, listed in full here. The report is the CLI's: flags are named.
    if !warnings.is_empty() {
        let mut w = String::from(
            "<h2 id=\"warnings\">Warnings</h2>\n<ul id=\"warning-list\" class=\"suspect\">",
        );
        for line in &warnings {
            let _ = write!(w, "<li>{}</li>", escape(line));
        }
        w.push_str("</ul>\n");
        sections.push(("warnings", "Warnings", w));
    }
    sections.push(("fit", "Fit", fit_html(input)));
    sections.push((
        "singular-values",
        "Singular values",
        singular_values_html(input),
    ));
    if let Some(c) = &input.coherence {
        sections.push((
            "coherence",
            "Coherence",
            format!(
                "<h2 id=\"coherence\">Coherence</h2>\n<p>{}</p>\n<figure class=\"plot wide\" id=\"fig-coherence\">{}</figure>\n",
                escape(c.caption),
                c.svg
            ),
        ));
    }
    if input.grid_svg.is_some() {
        sections.push(("grid", "All pairs", grid_html(input)));
    }
    if !input.overlays.is_empty() {
        sections.push(("overlays", "Each pair", overlays_html(input)));
    }
    sections.push(("input", "Input", input_html(input.source)));
    sections.push((
        "parameters",
        "Parameters",
        format!(
            "<h2 id=\"parameters\">Parameters</h2>\n<pre>{}</pre>\n",
            escape(input.parameters)
        ),
    ));
    sections.retain(|(_, _, html)| !html.is_empty());
    h.push_str("<nav id=\"toc\"><b>Contents</b>");
    h.push_str("<a href=\"#summary\">Summary</a>");
    for (id, heading, _) in sections.iter().filter(|(id, _, _)| !id.is_empty()) {
        let _ = write!(h, "<a href=\"#{id}\">{}</a>", escape(heading));
    }
    h.push_str("</nav>\n");
    h.push_str(&summary_html(input, &warnings));
    for (_, _, html) in &sections {
        h.push_str(html);
    }
    h.push_str("</body></html>\n");
    h
}

/// The page's style: up to 1500 px wide, text in a readable measure, figures as wide
/// as they are drawn, the pairs in a grid of as many columns as fit.
const STYLE: &str = "body{font-family:sans-serif;margin:1.5em 2em;max-width:1500px;color:#222}\
h1{font-size:1.6em;margin-bottom:.3em} h2{margin-top:1.6em;border-bottom:1px solid #ccc}\
p,ul,dl{max-width:70em} table{border-collapse:collapse;margin:1em 0}\
td,th{border:1px solid #ccc;padding:3px 8px;text-align:right} th{background:#f3f3f3}\
pre{background:#f7f7f7;padding:1em;overflow-x:auto} figure{margin:1em 0} svg{max-width:100%;height:auto}\
.col{background:#eef6ff} .bad{background:#fff1f0} .suspect{color:#a8071a}\
dl{display:grid;grid-template-columns:max-content auto;gap:2px 1em} dt{font-weight:bold} dd{margin:0;font-family:monospace;overflow-wrap:anywhere}\
table.matrix{display:block;overflow-x:auto;max-width:100%} table.matrix td{font-size:.85em}\
#modal-table td{white-space:nowrap} #modal-table td:last-child{white-space:normal} table.matrix small{color:#666} figure.wide{width:calc(100vw - 5em);max-width:1500px}\
#toc{display:flex;flex-wrap:wrap;gap:.3em 1.2em;padding:.5em .8em;background:#f7f7f7;border:1px solid #ddd;border-radius:4px}\
#toc b{margin-right:.5em}\
#summary{border:1px solid #9bb7d4;background:#f4f8fc;border-radius:4px;padding:.2em 1.2em .8em;margin:1em 0}\
#summary h2{margin-top:.5em;border:0} #summary dd{font-family:inherit} #summary ul{margin:.2em 0;padding-left:1.2em}\
.pairs{display:grid;grid-template-columns:repeat(auto-fill,minmax(400px,1fr));gap:.5em 1em}\
.pairs figure{margin:0} #pair-picker{display:flex;flex-wrap:wrap;gap:.5em 1.5em;align-items:center;margin:.5em 0}";

/// A relative error as a percentage with the digits it needs: `29.4 %`, `4.98 %`,
/// `0.123 %`, `3.2e-3 %`.
pub fn percent(value: f64) -> String {
    let p = 100.0 * value;
    if !p.is_finite() {
        return "–".into();
    }
    let a = p.abs();
    if a >= 10.0 {
        format!("{p:.1} %")
    } else if a >= 1.0 {
        format!("{p:.2} %")
    } else if a >= 0.01 || a == 0.0 {
        format!("{p:.3} %")
    } else {
        format!("{p:.1e} %")
    }
}

/// The model in words: ERA at its order, or the refinement and where it started.
fn model_words(f: &Identification) -> String {
    let states = f.model.states();
    match &f.refinement {
        Some(r) => format!(
            "refined (maximum likelihood on the FRFs): {} modes, {states} states, from ERA's {} modes",
            r.refinement.modes.len(),
            r.start_modes()
        ),
        None => match &f.stabilization {
            Some(_) => format!("ERA, {states} states (order from the stabilization diagram)"),
            None => format!("ERA, {states} states"),
        },
    }
}

/// The summary at the top: the modes, the model, the fit and the warnings, each with
/// a link to its section.
fn summary_html(input: &ReportInput<'_>, warnings: &[String]) -> String {
    let f = input.found;
    let modes = f.modal.modes.len();
    let physical = f.quality.iter().filter(|q| q.physical).count();
    let (lo, hi) = f
        .modal
        .modes
        .iter()
        .map(|m| m.frequency_hz)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    let mut h = String::from("<section id=\"summary\"><h2>Summary</h2><dl>");
    let _ = write!(
        h,
        "<dt>Modes</dt><dd id=\"summary-modes\" data-modes=\"{modes}\" data-physical=\"{physical}\"><a href=\"#modes\">{modes} mode{}</a>, {physical} judged physical{}; fitted band {:.4} – {:.4} Hz</dd>",
        if modes == 1 { "" } else { "s" },
        if modes > 0 {
            format!(", from {lo:.4} to {hi:.4} Hz")
        } else {
            String::new()
        },
        f.band_hz.0,
        f.band_hz.1
    );
    let _ = write!(
        h,
        "<dt>Model</dt><dd id=\"summary-model\" data-states=\"{}\">{}</dd>",
        f.model.states(),
        escape(&model_words(f))
    );
    if input.output_only {
        let _ = write!(
            h,
            "<dt>Fit</dt><dd id=\"summary-fit\"><a href=\"#fit\">mean relative error</a> to the half spectrum of the output correlations (not an FRF): {}; each mode's ± says how well it is known</dd>",
            match pairs_mean(&f.fit, |_| true) {
                Some((e, db)) => format!("<span data-error=\"{e:e}\">{}</span> ({db:.2} dB)", percent(e)),
                None => "–".to_string(),
            }
        );
    } else {
        summary_fit(&mut h, input);
    }
    summary_warnings(&mut h, warnings);
    h
}

/// The summary's fit line of an input-output run: collocated and non-collocated means.
fn summary_fit(h: &mut String, input: &ReportInput<'_>) {
    let f = input.found;
    let (col, noncol) = (
        fit_means(&f.fit, input.view, true),
        fit_means(&f.fit, input.view, false),
    );
    let part = |name: &str, mean: (Option<f64>, Option<f64>)| match mean {
        (Some(e), Some(db)) => Some(format!(
            "{name} <span data-error=\"{e:e}\">{}</span> ({db:.2} dB)",
            percent(e)
        )),
        _ => None,
    };
    let fit: Vec<String> = [part("collocated", col), part("non-collocated", noncol)]
        .into_iter()
        .flatten()
        .collect();
    let _ = write!(
        h,
        "<dt>Fit</dt><dd id=\"summary-fit\"><a href=\"#fit\">mean relative error</a>: {}</dd>",
        if fit.is_empty() {
            "–".to_string()
        } else {
            fit.join(", ")
        }
    );
}

/// The summary's warnings: how many, the first few in brief, and its closing tags.
fn summary_warnings(h: &mut String, warnings: &[String]) {
    let _ = write!(
        h,
        "<dt>Warnings</dt><dd id=\"summary-warnings\" data-count=\"{}\">",
        warnings.len()
    );
    if warnings.is_empty() {
        h.push_str("none");
    } else {
        let _ = write!(
            h,
            "<a href=\"#warnings\" class=\"suspect\">{} warning{}</a><ul class=\"suspect\">",
            warnings.len(),
            if warnings.len() == 1 { "" } else { "s" }
        );
        const SHOWN: usize = 4;
        for w in warnings.iter().take(SHOWN) {
            let _ = write!(h, "<li>{}</li>", escape(&brief(w, 160)));
        }
        if warnings.len() > SHOWN {
            let _ = write!(
                h,
                "<li><a href=\"#warnings\">and {} more</a></li>",
                warnings.len() - SHOWN
            );
        }
        h.push_str("</ul>");
    }
    h.push_str("</dd></dl></section>\n");
}

/// `text` cut to about `chars` characters at a word, with an ellipsis when cut.
fn brief(text: &str, chars: usize) -> String {
    if text.chars().count() <= chars {
        return text.to_string();
    }
    let cut: String = text.chars().take(chars).collect();
    let at = cut.rfind(' ').unwrap_or(cut.len());
    format!("{}…", &cut[..at])
}

/// The singular-value section: which H0, which path, and the figure.
fn singular_values_html(input: &ReportInput<'_>) -> String {
    let f = input.found;
    // With a scan the figure shows the scan's H0 (factored once for every order), which
    // is larger than the one the fixed-order model alone would need.
    let ((rows, cols), whose) = match &f.stabilization {
        Some(st) => (
            st.hankel_size,
            "the scan's H0, factored once for every order,",
        ),
        None => (f.realization.hankel_size, "H0"),
    };
    format!(
        "<h2 id=\"singular-values\">Singular values</h2>\n<p>Shown: {whose} {rows} × {cols}, computed on the {} path; sample time {:.6e} s.</p>\n<figure class=\"plot\" id=\"fig-singular-values\">{}</figure>\n",
        f.realization.svd_path.name(),
        f.sample_time_s,
        input.singular_values_svg
    )
}

/// The stabilization section, when a scan ran.
fn stabilization_html(input: &ReportInput<'_>) -> String {
    let (Some(svg), Some(st)) = (input.stabilization_svg, input.found.stabilization.as_ref())
    else {
        return String::new();
    };
    format!(
        "<h2 id=\"stabilization\">Stabilization diagram</h2>\n<p>Every pole of the models of orders {} (all from one SVD of H0, {} × {}), against frequency. A pole is <em>new</em> (grey ×), or agrees with the previous order in frequency (blue ○), in frequency and damping (orange ▲), or in frequency, damping and shape (green ●). Physical modes stand as vertical columns of green; the dashed red lines are the modes judged physical. The grey curves are the CMIF, the singular values at each line of the FRF matrix the model is fitted to (for responses alone, the half spectrum of the output correlations; right axis): its peaks are the modes, and two curves peaking together are close modes.</p>\n<p>Rule: {}.{}</p>\n<figure class=\"plot\" id=\"fig-stabilization\">{}</figure>\n",
        escape(&st.range.to_string()),
        st.hankel_size.0,
        st.hankel_size.1,
        escape(&st.selection.rule()),
        st.model_note
            .as_ref()
            .map_or(String::new(), |n| format!(" Model: {}.", escape(n))),
        svg
    )
}

/// The modes section: the refinement paragraph, the modal table and the real poles.
fn modes_html(f: &Identification, output_only: bool) -> String {
    let mut h = format!("<h2 id=\"modes\">Modes</h2>\n<p>MPC: modal phase collinearity (1 for a real normal mode). EMAC: extended modal amplitude coherence, how consistently the mode appears over the record (1 = fully). CMI = MPC × EMAC. Share: the mode's part of the {}. Orders: scanned orders in which the mode's cluster has a pole. A mode not judged physical is marked, with the reason.</p>\n{}<table id=\"modal-table\"><tr><th>mode</th><th>frequency (Hz)</th><th>damping ratio (%)</th><th>|λ|</th><th>MPC</th><th>EMAC</th><th>CMI</th><th>share</th><th>orders</th><th>physical</th></tr>\n", if output_only { "output correlations' half spectrum" } else { "measured FRF" }, refinement_html(f));
    for (k, m) in f.modal.modes.iter().enumerate() {
        let q = f.quality.get(k);
        let i = q.map(|q| q.indicators);
        let trust = match q {
            Some(q) if q.physical => "yes".to_string(),
            Some(q) => format!(
                "<span class=\"suspect\">no: {}</span>",
                escape(q.reason.as_deref().unwrap_or("suspect"))
            ),
            None => String::new(),
        };
        let _ = writeln!(
            h,
            "<tr{}><td>{}</td><td>{:.4}{}</td><td>{:.4}{}</td><td>{:.6}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td style=\"text-align:left\">{}</td></tr>",
            if q.is_some_and(|q| !q.physical) { " class=\"bad\"" } else { "" },
            k + 1,
            m.frequency_hz,
            plus_minus(q.and_then(|q| q.frequency_std_hz)),
            100.0 * m.damping_ratio,
            plus_minus(q.and_then(|q| q.damping_ratio_std).map(|z| 100.0 * z)),
            m.eigenvalue.norm(),
            opt(i.map(|i| i.mpc), 3),
            opt(i.and_then(|i| i.emac), 3),
            opt(i.and_then(|i| i.cmi), 3),
            i.and_then(|i| i.contribution).map_or("–".into(), |c| format!("{c:.2e}")),
            q.and_then(|q| q.stable_orders).map_or("–".into(), |n| n.to_string()),
            trust
        );
    }
    h.push_str("</table>\n");
    if !f.modal.real_poles.is_empty() {
        h.push_str("<p>Real poles: ");
        for r in &f.modal.real_poles {
            let _ = write!(h, "{:.6e} ({:.4} Hz); ", r.eigenvalue, r.frequency_hz);
        }
        h.push_str("</p>\n");
    }
    h
}

/// The fit section: the means and the outputs × inputs matrix.
fn fit_html(input: &ReportInput<'_>) -> String {
    let f = input.found;
    let fit = &f.fit;
    let (col, noncol) = (
        fit_means(fit, input.view, true),
        fit_means(fit, input.view, false),
    );
    if input.output_only {
        let (e, db) = pairs_mean(fit, |_| true).unzip();
        let mut h = format!(
            "<h2 id=\"fit\">Fit</h2>\n<p>{} lines of the half spectrum of the output correlations: each output against each reference, what the model is fitted to when no force was measured. Mean relative error {}, mean RMS log-magnitude error {} dB. The correlations end at the last lag, so this half spectrum leaks around every lightly damped peak: its misfit is no measure of the modes' accuracy, which each mode's ± gives. Each cell: relative error ‖G − Ĝ‖/‖G‖ of the pair over the band, and below it the RMS log-magnitude error; rows are outputs, columns references.</p>\n",
            fit.lines,
            e.map_or("–".into(), percent),
            opt(db, 3),
        );
        h.push_str(&fit_matrix_html(
            fit,
            input.view,
            (f.measured.outputs(), f.measured.inputs()),
            "reference",
        ));
        return h;
    }
    let mut h = format!(
        "<h2 id=\"fit\">Fit</h2>\n<p>{} lines from line {} ({} FRFs). Mean relative error: collocated {}, non-collocated {}. Mean RMS log-magnitude error: collocated {} dB, non-collocated {} dB. Each cell: relative error ‖G − Ĝ‖/‖G‖ of the pair over the band, and below it the RMS log-magnitude error; rows are outputs, columns inputs, collocated pairs shaded.</p>\n",
        fit.lines,
        fit.first_line,
        f.processed.quantity(),
        col.0.map_or("–".into(), percent),
        noncol.0.map_or("–".into(), percent),
        opt(col.1, 3),
        opt(noncol.1, 3),
    );
    h.push_str(&fit_matrix_html(
        fit,
        input.view,
        (f.measured.outputs(), f.measured.inputs()),
        "input",
    ));
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_read_in_percent_with_the_digits_they_need() {
        assert_eq!(percent(0.2937), "29.4 %");
        assert_eq!(percent(0.04976), "4.98 %");
        assert_eq!(percent(0.001234), "0.123 %");
        assert_eq!(percent(0.0), "0.000 %");
        assert_eq!(percent(3.2e-5), "3.2e-3 %");
        assert_eq!(percent(f64::NAN), "–");
    }

    #[test]
    fn long_warnings_are_cut_at_a_word() {
        assert_eq!(brief("short", 10), "short");
        assert_eq!(brief("one two three four", 10), "one two…");
    }
}
