//! Human-readable output: the parameter echo (like the thesis's `parm.m`), modal and fit
//! tables, timings. Human text goes to stdout, or to stderr when `--json` owns stdout;
//! `--quiet` silences it.

use crate::config::{Settings, Verbosity};
use era::data::identification::Identification;
use era::identify::{EraOptions, ModelDomain};
use era::pipeline::realize::DirectTerm;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::Write as _;

/// Where human text goes.
pub struct Human {
    to_stderr: bool,
    quiet: bool,
}

impl Human {
    pub fn new(settings: &Settings) -> Self {
        Human {
            to_stderr: settings.json,
            quiet: settings.verbosity == Verbosity::Quiet,
        }
    }
    pub fn print(&self, text: &str) {
        if self.quiet {
            return;
        }
        // A closed pipe (`era demo | head`) is not an error worth reporting.
        if self.to_stderr {
            let _ = std::io::stderr().write_all(text.as_bytes());
        } else {
            let _ = std::io::stdout().write_all(text.as_bytes());
        }
    }
}

/// Prints JSON on stdout; a reader that closed the pipe early is not an error.
pub fn print_json(value: &impl serde::Serialize) -> anyhow::Result<()> {
    let mut text = serde_json::to_string_pretty(value)?;
    text.push('\n');
    let mut stdout = std::io::stdout().lock();
    match stdout
        .write_all(text.as_bytes())
        .and_then(|_| stdout.flush())
    {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}

/// The modal table: frequency, damping, the indicators and whether to trust each mode
/// (docs/src/design.md §10). Suspect modes are marked `?` with the reason below the table;
/// negative damping is always called out.
pub fn mode_table(found: &Identification) -> String {
    let mut s = String::new();
    let num = |v: Option<f64>, w: usize| v.map_or(format!("{:>w$}", "-"), |x| format!("{x:>w$.2}"));
    // A refined model's modes carry standard deviations: shown as `± σ` columns.
    let refined = found.refinement.is_some();
    let pm = |v: Option<f64>| v.map_or(format!("{:>11}", "-"), |x| format!("± {x:>9.2e}"));
    let _ = writeln!(
        s,
        "{:>5} {:>14}{} {:>10}{} {:>6} {:>6} {:>6} {:>9} {:>7}  trust",
        "mode",
        "f (Hz)",
        if refined {
            format!(" {:>11}", "± (Hz)")
        } else {
            String::new()
        },
        "zeta (%)",
        if refined {
            format!(" {:>11}", "± (%)")
        } else {
            String::new()
        },
        "MPC",
        "EMAC",
        "CMI",
        "share",
        "orders"
    );
    let mut reasons = Vec::new();
    for (k, m) in found.modal.modes.iter().enumerate() {
        let q = found.quality.get(k);
        let mark = verdict(k, m, q, &mut reasons, ("yes", "?", ""));
        let i = q.map(|q| q.indicators);
        let (f_std, z_std) = if refined {
            (
                format!(" {}", pm(q.and_then(|q| q.frequency_std_hz))),
                format!(
                    " {}",
                    pm(q.and_then(|q| q.damping_ratio_std).map(|z| 100.0 * z))
                ),
            )
        } else {
            (String::new(), String::new())
        };
        let _ = writeln!(
            s,
            "{:>5} {:>14.4}{f_std} {:>10.4}{z_std} {} {} {} {:>9} {:>7}  {mark}",
            k + 1,
            m.frequency_hz,
            100.0 * m.damping_ratio,
            num(i.map(|i| i.mpc), 6),
            num(i.and_then(|i| i.emac), 6),
            num(i.and_then(|i| i.cmi), 6),
            i.and_then(|i| i.contribution)
                .map_or("-".into(), |c| format!("{c:.2e}")),
            q.and_then(|q| q.stable_orders)
                .map_or("-".into(), |n| n.to_string()),
        );
    }
    let negative = found
        .modal
        .modes
        .iter()
        .filter(|m| m.damping_ratio <= 0.0)
        .count();
    if !reasons.is_empty() {
        let _ = writeln!(
            s,
            "{} of {} modes are suspect (?), not to be trusted as modes of the structure:",
            reasons.len(),
            found.modal.modes.len()
        );
        for r in reasons {
            let _ = writeln!(s, "{r}");
        }
    }
    if negative > 0 {
        let _ = writeln!(
            s,
            "warning: {negative} mode(s) with zero or negative damping: the model is unstable there; no passive structure has such a mode"
        );
    }
    let _ = writeln!(
        s,
        "(MPC: phase collinearity of the shape, 1 = real mode; EMAC: consistency over the record; CMI = MPC x EMAC; share: the mode's part of the measured FRF; orders: scanned orders with the mode)"
    );
    s
}

/// The scan's summary: the diagram's extent, the rule and how many modes it kept.
pub fn stabilization_summary(st: &era::data::identification::Stabilization) -> String {
    let mut s = String::new();
    let physical = st.selection.physical().count();
    let candidates = st
        .selection
        .clusters
        .iter()
        .filter(|c| c.members.len() >= st.selection.criteria.min_poles)
        .count();
    let _ = writeln!(
        s,
        "\nstabilization: {} orders ({}) from one SVD of a {} x {} H0 in {:.2} s ({:.2} s with the scan); {} poles, {} clusters of 3+ poles, {} physical",
        st.scan.orders.len(),
        st.range,
        st.hankel_size.0,
        st.hankel_size.1,
        st.factor_seconds,
        st.seconds,
        st.scan.poles.len(),
        candidates,
        physical
    );
    if !st.scan.skipped.is_empty() {
        let _ = writeln!(
            s,
            "  orders {:?} skipped: above the numerical rank of H0",
            st.scan.skipped
        );
    }
    let _ = writeln!(s, "  rule: {}", st.selection.rule());
    if let Some(note) = &st.model_note {
        let _ = writeln!(s, "  model: {note}");
    }
    s
}

/// The parameter echo printed before a run.
pub fn parameter_echo(o: &EraOptions) -> String {
    parameter_echo_states(o, None)
}

/// [`parameter_echo`], with the states line replaced by `states` when given (`auto`).
pub fn parameter_echo_states(o: &EraOptions, states: Option<&str>) -> String {
    let ns = o.order.states().unwrap_or(0);
    let markov = ns * o.hankel_factor / 4 * 4;
    let lowpass = match o.lowpass {
        Some((order, hz)) => format!("order {order}, {hz} Hz (zero phase)"),
        None => "off".into(),
    };
    let mut s = String::new();
    let _ = writeln!(s, "ERA parameters");
    match states {
        Some(text) => {
            let _ = writeln!(s, "  states (ns)             {text}");
            let _ = writeln!(s, "  hankel factor (lh)      {}", o.hankel_factor);
        }
        None => {
            let _ = writeln!(s, "  states (ns)             {}", ns);
            let _ = writeln!(
                s,
                "  hankel factor (lh)      {}  (M = {markov} Markov samples)",
                o.hankel_factor
            );
        }
    }
    let _ = writeln!(s, "  integrations (ni)       {}", o.integrations);
    let _ = writeln!(s, "  low-pass (ford, Hz)     {lowpass}");
    let _ = writeln!(s, "  zero lines (nz)         {}", o.zero_lines);
    let pad = if o.pad_to == 0 {
        "none".to_string()
    } else {
        format!("{} lines", o.pad_to + 1)
    };
    let _ = writeln!(s, "  pad to (ndpts)          {} ({pad})", o.pad_to);
    let domain = match o.domain {
        ModelDomain::Discrete => "discrete",
        ModelDomain::Continuous => "continuous",
    };
    let _ = writeln!(s, "  time domain (cord)      {domain}");
    let d = match o.direct_term {
        DirectTerm::Zero => "zero",
        DirectTerm::FirstMarkov => "Y0",
    };
    let _ = writeln!(s, "  direct term D           {d}");
    let _ = writeln!(s, "  SVD                     {}", o.svd.name());
    if o.realizer == era::identify::Realizer::EraDc {
        let _ = writeln!(
            s,
            "  realization             ERA/DC (shifted correlations of the Hankel blocks)"
        );
    }
    s
}

/// `x` with `decimals` decimals while that stays short (`1e-3 ≤ |x| < 1e7`, or 0), in
/// scientific notation with as many digits after the point otherwise: no number prints
/// as a row of hundreds of digits.
pub fn fixed(x: f64, decimals: usize) -> String {
    let a = x.abs();
    if !x.is_finite() || a == 0.0 || (1e-3..1e7).contains(&a) {
        format!("{x:.decimals$}")
    } else {
        format!("{x:.decimals$e}")
    }
}

/// Singular values, modes, real poles, fit and warnings of one identification.
pub fn identification_summary(found: &Identification, states: usize) -> String {
    let mut s = String::new();
    let sv = &found.realization.singular_values;
    let (rows, cols) = found.realization.hankel_size;
    let _ = writeln!(
        s,
        "\nHankel H0 {rows} x {cols}, sample time {:.6e} s",
        found.sample_time_s
    );
    let _ = write!(
        s,
        "singular values: s1 = {:.4e}, s{states} = {:.4e}",
        sv[0],
        sv[states - 1]
    );
    if let Some(next) = sv.get(states) {
        let _ = write!(
            s,
            ", s{} = {:.4e} (s{}/s{states} = {:.2e})",
            states + 1,
            next,
            states + 1,
            next / sv[states - 1]
        );
    }
    let _ = writeln!(s);
    let modes = &found.modal.modes;
    let _ = writeln!(
        s,
        "\n{} modes{}",
        modes.len(),
        if found.modal.real_poles.is_empty() {
            String::new()
        } else {
            format!(", {} real poles", found.modal.real_poles.len())
        }
    );
    s.push_str(&mode_table(found));
    for r in &found.modal.real_poles {
        let _ = writeln!(
            s,
            "  real pole {:+.6e} ({:.4} Hz)",
            r.eigenvalue, r.frequency_hz
        );
    }
    let fit = &found.fit;
    let fmt = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.3e}"));
    let fdb = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.3}"));
    let _ = writeln!(
        s,
        "\nfit over {} lines from line {} ({} FRFs): relative error collocated {}, non-collocated {}; RMS log-magnitude error collocated {} dB, non-collocated {} dB",
        fit.lines,
        fit.first_line,
        found.processed.quantity(),
        fmt(fit.collocated_mean_relative_error),
        fmt(fit.noncollocated_mean_relative_error),
        fdb(fit.collocated_mean_db),
        fdb(fit.noncollocated_mean_db),
    );
    for w in found.warnings(era::params::Naming::Flag) {
        let _ = writeln!(s, "warning: {w}");
    }
    s
}

/// Timing table: the pipeline stages in their order, then any other stage.
pub fn timings_table(t: &BTreeMap<String, f64>) -> String {
    let order = [
        "simulate",
        "read",
        "frf_estimate",
        "okid",
        "preprocess",
        "markov",
        "hankel_svd",
        "realize",
        "scan",
        "selection",
        "modes",
        "fit",
        "zero_start",
        "refine",
        "frame_check",
        "write",
    ];
    let mut s = String::from("\ntimings (s)\n");
    let part = |k: &str| k.contains(PART);
    let others = t
        .keys()
        .map(String::as_str)
        .filter(|k| !order.contains(k) && *k != WALL && !part(k));
    for key in order.into_iter().chain(others) {
        if let Some(v) = t.get(key) {
            let _ = writeln!(s, "  {key:<12} {v:.6}");
            // The stage's parts, under it (in the order of their keys' numbers).
            let prefix = format!("{key}{PART}");
            let mut parts: Vec<(&str, f64)> = t
                .iter()
                .filter_map(|(k, v)| k.strip_prefix(&prefix).map(|name| (name, *v)))
                .collect();
            parts.sort_by_key(|(name, _)| {
                let digits: String = name.chars().filter(char::is_ascii_digit).collect();
                digits.parse::<usize>().unwrap_or(0)
            });
            for (name, v) in parts {
                let _ = writeln!(s, "    {name:<10} {v:.6}");
            }
        }
    }
    let total: f64 = t
        .iter()
        .filter(|(k, _)| *k != WALL && !part(k))
        .map(|(_, v)| v)
        .sum();
    let _ = writeln!(s, "  {:<12} {total:.6}", "total");
    if let Some(&wall) = t.get(WALL) {
        let _ = writeln!(
            s,
            "  {:<12} {wall:.6}  (the process so far; {:.1} % of it in no stage above)",
            WALL,
            100.0 * (wall - total).max(0.0) / wall.max(f64::MIN_POSITIVE)
        );
    }
    s
}

/// The key of the process's wall time in a timings map: not a stage, not in the total.
pub const WALL: &str = "wall";

/// Between a stage and the name of one of its parts in a timings key (`refine.round 1`):
/// a part is printed under its stage and is not added to the total.
pub const PART: &str = ".";

static START: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();

/// Marks the start of the process (the first thing `main` does).
pub fn mark_start() {
    let _ = START.set(std::time::Instant::now());
}

/// Seconds since [`mark_start`].
pub fn process_seconds() -> Option<f64> {
    START.get().map(|t| t.elapsed().as_secs_f64())
}

/// The end of a verb: with `--timings`, the table and `timings_s` in the JSON; with
/// `--json`, the JSON on stdout.
pub fn finish_output(
    human: &Human,
    settings: &Settings,
    mut out: serde_json::Value,
    timings: &[(&str, f64)],
) -> anyhow::Result<()> {
    if settings.timings {
        let t: BTreeMap<String, f64> = timings.iter().map(|(k, v)| (k.to_string(), *v)).collect();
        human.print(&timings_table(&t));
        out["timings_s"] = serde_json::json!(t);
    }
    if settings.json {
        print_json(&out)?;
    }
    Ok(())
}

/// Which SVD path ran, for the timings.
pub fn svd_path_line(r: &era::pipeline::realize::Realization) -> String {
    match r.svd_iterations {
        Some(it) => format!(
            "  hankel_svd path: {} ({} iterations)\n",
            r.svd_path.name(),
            it
        ),
        None => format!("  hankel_svd path: {}\n", r.svd_path.name()),
    }
}

/// A mode's mark in a modal table: `marks.0` when physical, `marks.1` (and its reason,
/// a line in `reasons`) when not, `marks.2` without a judgement.
pub(crate) fn verdict(
    k: usize,
    m: &era::pipeline::modes::Mode,
    q: Option<&era::data::identification::ModeQuality>,
    reasons: &mut Vec<String>,
    marks: (&'static str, &'static str, &'static str),
) -> &'static str {
    match q {
        Some(q) if q.physical => marks.0,
        Some(q) => {
            reasons.push(format!(
                "  mode {} ({:.4} Hz): {}",
                k + 1,
                m.frequency_hz,
                q.reason.as_deref().unwrap_or("suspect")
            ));
            marks.1
        }
        None => marks.2,
    }
}
