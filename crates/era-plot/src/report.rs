//! `report.html`: one self-contained file (inline SVG, inline CSS, no network) with
//! what went in (file, format, units, channel table, command line, version, date), the
//! parameters, singular values, modal table, the modes on the geometry when one is given
//! (the one script, [`crate::viewer`]), the fit as an outputs × inputs matrix, the
//! coherence when the input carries it, the overview grid and every pair's overlay.
//!
//! Size: each figure appears once, its elements share style rules
//! ([`crate::render::compact_svg`]) and its curves are thinned to what a pixel shows
//! ([`crate::render::visible_points`], which keeps every peak), so an 8 × 8 set of 801
//! lines stays well under 2 MB.

use crate::figures::FrfView;
use era::identification::Identification;
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
    /// One (title, SVG) per pair.
    pub overlays: &'a [(String, String)],
    /// The modes on the test geometry, when one was given ([`crate::viewer`]).
    pub shapes: Option<&'a crate::viewer::ShapeView>,
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
        ("Units", &s.units),
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
    q: usize,
    p: usize,
) -> String {
    let mut h =
        String::from("<table id=\"fit-table\" class=\"matrix\"><tr><th>output \\ input</th>");
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
                        "<td{}>{:.3e}<br><small>{:.2} dB</small></td>",
                        if view.is_collocated(i, j) {
                            " class=\"col\""
                        } else {
                            ""
                        },
                        f.relative_error,
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
    let chosen: Vec<_> = fit
        .pairs
        .iter()
        .filter(|f| view.is_collocated(f.output, f.input) == collocated)
        .collect();
    if chosen.is_empty() {
        return (None, None);
    }
    let n = chosen.len() as f64;
    (
        Some(chosen.iter().map(|f| f.relative_error).sum::<f64>() / n),
        Some(chosen.iter().map(|f| f.rms_log_magnitude_db).sum::<f64>() / n),
    )
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

/// The overview grid (when there is one) and every pair's overlay.
fn pairs_html(input: &ReportInput<'_>) -> String {
    let mut h = String::new();
    if let Some(grid) = input.grid_svg {
        let _ = write!(
            h,
            "<h2 id=\"grid\">All pairs</h2>\n<p>|G| in {}.</p>\n<figure class=\"plot wide\" id=\"fig-grid\">{}</figure>\n",
            escape(&input.view.unit),
            grid
        );
    }
    if !input.overlays.is_empty() {
        h.push_str("<h2 id=\"overlays\">Each pair</h2>\n");
    }
    // The title is drawn in each figure; the figure carries it as its label only.
    for (k, (title, svg)) in input.overlays.iter().enumerate() {
        let _ = writeln!(
            h,
            "<figure class=\"plot overlay\" id=\"fig-pair-{}\" aria-label=\"{}\">{}</figure>",
            k + 1,
            escape(title).replace('"', "&quot;"),
            svg
        );
    }
    h
}

/// The whole page.
/// ` ± σ` after a refined value (one standard deviation), empty otherwise.
fn plus_minus(std: Option<f64>) -> String {
    std.map_or(String::new(), |s| format!(" ± {s:.2e}"))
}

/// The paragraph on the refinement of a refined model: how the fit went, which modes
/// were dropped, and how to read `±`.
fn refinement_html(f: &era::identification::Identification) -> String {
    let Some(r) = &f.refinement else {
        return String::new();
    };
    let fit = &r.refinement;
    let mut h = format!(
        "<p id=\"refinement\">Refined model: poles, residues and residual terms fitted to the FRFs by maximum likelihood ({} model), starting from {} modes of ERA{}; {} kept. {} iterations, {}. Over the band, ‖G − Ĝ‖/‖G‖ went from {:.3e} to {:.3e}. The model, its FRFs and the table are the refined ones; ± is one standard deviation from the Gauss–Newton covariance at the optimum, with the noise variance taken from the residual.</p>\n",
        if fit.sample_time_s.is_some() { "z-domain, at the sample time" } else { "continuous" },
        r.start_modes(),
        match fit.added.len() {
            0 => String::new(),
            k => format!(" and {k} pole(s) added for modes it missed (below)"),
        },
        fit.modes.len(),
        fit.iterations,
        if fit.converged { "converged" } else { "<span class=\"suspect\">not converged</span>" },
        fit.fit_before,
        fit.fit_after,
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

pub fn report_html(input: &ReportInput<'_>) -> String {
    let f = input.found;
    let mut h = String::with_capacity(1 << 20);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\n<style>\
body{{font-family:sans-serif;margin:2em;max-width:1100px;color:#222}} h1{{font-size:1.6em}} h2{{margin-top:2em;border-bottom:1px solid #ccc}}\
table{{border-collapse:collapse;margin:1em 0}} td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}} th{{background:#f3f3f3}}\
pre{{background:#f7f7f7;padding:1em}} figure{{margin:1em 0}} svg{{max-width:100%;height:auto}} .col{{background:#eef6ff}} .bad{{background:#fff1f0}} .suspect{{color:#a8071a}}\
dl{{display:grid;grid-template-columns:max-content auto;gap:2px 1em}} dt{{font-weight:bold}} dd{{margin:0;font-family:monospace;overflow-wrap:anywhere}}\
table.matrix td{{font-size:.85em}} table.matrix small{{color:#666}} figure.wide{{width:calc(100vw - 4em)}}\
</style></head><body>\n<h1>{}</h1>\n",
        escape(input.title),
        escape(input.title)
    );
    h.push_str(&input_html(input.source));
    // Results to treat with care (era::suspect) come before anything else of the run: a
    // reader who skims should not miss them. The report is the CLI's: flags are named.
    let warnings = f.warnings(era::params::Naming::Flag);
    if !warnings.is_empty() {
        h.push_str("<h2 id=\"warnings\">Warnings</h2>\n<ul id=\"warning-list\" class=\"suspect\">");
        for w in &warnings {
            let _ = write!(h, "<li>{}</li>", escape(w));
        }
        h.push_str("</ul>\n");
    }
    let _ = write!(
        h,
        "<h2 id=\"parameters\">Parameters</h2>\n<pre>{}</pre>\n",
        escape(input.parameters)
    );
    // With a scan the figure shows the scan's H0 (factored once for every order), which
    // is larger than the one the fixed-order model alone would need.
    let ((rows, cols), whose) = match &f.stabilization {
        Some(st) => (
            st.hankel_size,
            "the scan's H0, factored once for every order,",
        ),
        None => (f.realization.hankel_size, "H0"),
    };
    let _ = write!(
        h,
        "<h2 id=\"singular-values\">Singular values</h2>\n<p>Shown: {whose} {rows} × {cols}, computed on the {} path; sample time {:.6e} s.</p>\n<figure class=\"plot\" id=\"fig-singular-values\">{}</figure>\n",
        f.realization.svd_path.name(),
        f.sample_time_s,
        input.singular_values_svg
    );
    if let (Some(svg), Some(st)) = (input.stabilization_svg, f.stabilization.as_ref()) {
        let _ = write!(
            h,
            "<h2 id=\"stabilization\">Stabilization diagram</h2>\n<p>Every pole of the models of orders {} (all from one SVD of H0, {} × {}), against frequency. A pole is <em>new</em> (grey ×), or agrees with the previous order in frequency (blue ○), in frequency and damping (orange ▲), or in frequency, damping and shape (green ●). Physical modes stand as vertical columns of green; the dashed red lines are the modes judged physical. The grey curves are the CMIF, the singular values at each line of the FRF matrix the model is fitted to (for responses alone, the half spectrum of the output correlations; right axis): its peaks are the modes, and two curves peaking together are close modes.</p>\n<p>Rule: {}.{}</p>\n<figure class=\"plot\" id=\"fig-stabilization\">{}</figure>\n",
            escape(&st.range.to_string()),
            st.hankel_size.0,
            st.hankel_size.1,
            escape(&st.selection.rule()),
            st.model_note
                .as_ref()
                .map_or(String::new(), |n| format!(" Model: {}.", escape(n))),
            svg
        );
    }
    h.push_str(&sections_html(input.sections));
    let _ = write!(h, "<h2 id=\"modes\">Modes</h2>\n<p>MPC: modal phase collinearity (1 for a real normal mode). EMAC: extended modal amplitude coherence, how consistently the mode appears over the record (1 = fully). CMI = MPC × EMAC. Share: the mode's part of the measured FRF. Orders: scanned orders in which the mode's cluster has a pole. A mode not judged physical is marked, with the reason.</p>\n{}<table id=\"modal-table\"><tr><th>mode</th><th>frequency (Hz)</th><th>damping ratio (%)</th><th>|λ|</th><th>MPC</th><th>EMAC</th><th>CMI</th><th>share</th><th>orders</th><th>physical</th></tr>\n", refinement_html(f));
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
    h.push_str(&crate::viewer::shapes_html(input.shapes));
    let fit = &f.fit;
    let (col, noncol) = (
        fit_means(fit, input.view, true),
        fit_means(fit, input.view, false),
    );
    let _ = write!(
        h,
        "<h2 id=\"fit\">Fit</h2>\n<p>{} lines from line {} ({} FRFs). Mean relative error: collocated {}, non-collocated {}. Mean RMS log-magnitude error: collocated {} dB, non-collocated {} dB. Each cell: relative error ‖G − Ĝ‖/‖G‖ of the pair over the band, and below it the RMS log-magnitude error; rows are outputs, columns inputs, collocated pairs shaded.</p>\n",
        fit.lines,
        fit.first_line,
        f.processed.quantity(),
        opt(col.0, 4),
        opt(noncol.0, 4),
        opt(col.1, 3),
        opt(noncol.1, 3),
    );
    h.push_str(&fit_matrix_html(
        fit,
        input.view,
        f.measured.outputs(),
        f.measured.inputs(),
    ));
    if let Some(c) = &input.coherence {
        let _ = write!(
            h,
            "<h2 id=\"coherence\">Coherence</h2>\n<p>{}</p>\n<figure class=\"plot wide\" id=\"fig-coherence\">{}</figure>\n",
            escape(c.caption),
            c.svg
        );
    }
    h.push_str(&pairs_html(input));
    h.push_str("</body></html>\n");
    h
}
