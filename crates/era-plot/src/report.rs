//! `report.html`: one self-contained file (inline SVG, inline CSS, no script, no
//! network) with the parameters, singular values, modal and fit tables, the overview
//! grid and every pair's overlay.

use era::identify::Identification;
use std::fmt::Write as _;

/// What goes into a report besides the identification itself.
pub struct ReportInput<'a> {
    /// Page title.
    pub title: &'a str,
    /// The parameter echo, as printed before the run.
    pub parameters: &'a str,
    /// The identification.
    pub found: &'a Identification,
    /// Singular-value figure, SVG.
    pub singular_values_svg: &'a str,
    /// Stabilization diagram, SVG, when a scan ran.
    pub stabilization_svg: Option<&'a str>,
    /// Overview grid, SVG.
    pub grid_svg: &'a str,
    /// One (title, SVG) per pair.
    pub overlays: &'a [(String, String)],
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("–".into(), |x| format!("{x:.digits$}"))
}

/// The whole page.
/// ` ± σ` after a refined value (one standard deviation), empty otherwise.
fn plus_minus(std: Option<f64>) -> String {
    std.map_or(String::new(), |s| format!(" ± {s:.2e}"))
}

/// The paragraph on the refinement of a refined model: how the fit went, which modes
/// were dropped, and how to read `±`.
fn refinement_html(f: &era::identify::Identification) -> String {
    let Some(r) = &f.refinement else {
        return String::new();
    };
    let fit = &r.refinement;
    let mut h = format!(
        "<p id=\"refinement\">Refined model: poles, residues and residual terms fitted to the FRFs by maximum likelihood ({} model), starting from {} modes of ERA; {} kept. {} iterations, {}. Over the band, ‖G − Ĝ‖/‖G‖ went from {:.3e} to {:.3e}. The model, its FRFs and the table are the refined ones; ± is one standard deviation from the Gauss–Newton covariance at the optimum, with the noise variance taken from the residual.</p>\n",
        if fit.sample_time_s.is_some() { "z-domain, at the sample time" } else { "continuous" },
        r.start_frequency_hz.len(),
        fit.modes.len(),
        fit.iterations,
        if fit.converged { "converged" } else { "<span class=\"suspect\">not converged</span>" },
        fit.fit_before,
        fit.fit_after,
    );
    let dropped = r.dropped_lines();
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
</style></head><body>\n<h1>{}</h1>\n",
        escape(input.title),
        escape(input.title)
    );
    let _ = write!(
        h,
        "<h2 id=\"parameters\">Parameters</h2>\n<pre>{}</pre>\n",
        escape(input.parameters)
    );
    let (rows, cols) = f.realization.hankel_size;
    let _ = write!(
        h,
        "<h2 id=\"singular-values\">Singular values</h2>\n<p>H0 is {rows} × {cols}, computed on the {} path; sample time {:.6e} s.</p>\n<figure class=\"plot\" id=\"fig-singular-values\">{}</figure>\n",
        f.realization.svd_path.name(),
        f.sample_time_s,
        input.singular_values_svg
    );
    if let (Some(svg), Some(st)) = (input.stabilization_svg, f.stabilization.as_ref()) {
        let _ = write!(
            h,
            "<h2 id=\"stabilization\">Stabilization diagram</h2>\n<p>Every pole of the models of orders {} (all from one SVD of H0, {} × {}), against frequency. A pole is <em>new</em> (grey ×), or agrees with the previous order in frequency (blue ○), in frequency and damping (orange ▲), or in frequency, damping and shape (green ●). Physical modes stand as vertical columns of green; the dashed red lines are the modes judged physical. The grey curves are the CMIF, the singular values of the FRF matrix at each line (right axis): its peaks are the modes, and two curves peaking together are close modes.</p>\n<p>Rule: {}.{}</p>\n<figure class=\"plot\" id=\"fig-stabilization\">{}</figure>\n",
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
    let fit = &f.fit;
    let _ = write!(
        h,
        "<h2 id=\"fit\">Fit</h2>\n<p>{} lines from line {} ({} FRFs). Mean relative error: collocated {}, non-collocated {}. Mean RMS log-magnitude error: collocated {} dB, non-collocated {} dB.</p>\n<table id=\"fit-table\"><tr><th>output</th><th>input</th><th>collocated</th><th>relative error</th><th>RMS log-magnitude (dB)</th></tr>\n",
        fit.lines,
        fit.first_line,
        f.processed.quantity(),
        opt(fit.collocated_mean_relative_error, 4),
        opt(fit.noncollocated_mean_relative_error, 4),
        opt(fit.collocated_mean_db, 3),
        opt(fit.noncollocated_mean_db, 3),
    );
    for p in &fit.pairs {
        let _ = writeln!(
            h,
            "<tr{}><td>{}</td><td>{}</td><td>{}</td><td>{:.4e}</td><td>{:.3}</td></tr>",
            if p.collocated { " class=\"col\"" } else { "" },
            p.output + 1,
            p.input + 1,
            if p.collocated { "yes" } else { "" },
            p.relative_error,
            p.rms_log_magnitude_db
        );
    }
    h.push_str("</table>\n");
    let _ = write!(
        h,
        "<h2 id=\"grid\">All pairs</h2>\n<figure class=\"plot\" id=\"fig-grid\">{}</figure>\n",
        input.grid_svg
    );
    h.push_str("<h2 id=\"overlays\">Each pair</h2>\n");
    for (k, (title, svg)) in input.overlays.iter().enumerate() {
        let _ = writeln!(h, "<figure class=\"plot overlay\" id=\"fig-pair-{}\"><figcaption>{}</figcaption>{}</figure>", k + 1, escape(title), svg);
    }
    h.push_str("</body></html>\n");
    h
}
