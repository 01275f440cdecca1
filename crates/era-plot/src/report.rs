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
pub fn report_html(input: &ReportInput<'_>) -> String {
    let f = input.found;
    let mut h = String::with_capacity(1 << 20);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\n<style>\
body{{font-family:sans-serif;margin:2em;max-width:1100px;color:#222}} h1{{font-size:1.6em}} h2{{margin-top:2em;border-bottom:1px solid #ccc}}\
table{{border-collapse:collapse;margin:1em 0}} td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}} th{{background:#f3f3f3}}\
pre{{background:#f7f7f7;padding:1em}} figure{{margin:1em 0}} svg{{max-width:100%;height:auto}} .col{{background:#eef6ff}}\
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
    let _ = write!(h, "<h2 id=\"modes\">Modes</h2>\n<table id=\"modal-table\"><tr><th>mode</th><th>frequency (Hz)</th><th>damping ratio (%)</th><th>|λ|</th></tr>\n");
    for (k, m) in f.modal.modes.iter().enumerate() {
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{:.4}</td><td>{:.4}</td><td>{:.6}</td></tr>",
            k + 1,
            m.frequency_hz,
            100.0 * m.damping_ratio,
            m.eigenvalue.norm()
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
