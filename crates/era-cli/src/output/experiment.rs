//! What `era simulate experiment` writes: the FRF file and its coherence, the exact
//! FRFs, the time histories with a figure per run, and the summary.

use crate::config;
use crate::error::usage;
use crate::output::figures::write_figure;
use crate::output::{output_name, write_output};
use era::sim::experiment::{Experiment, ExperimentSpec};
use era_io::atomic::OutputSet;
use era_io::csv::FrfFile;
use era_io::format::FrfFormat;
use era_io::uff::UffWriteOptions;
use era_plot::{Figure, Panel, Series, SeriesKind, YScale};
use serde_json::json;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// The coherence as CSV ([`super::estimate::coherence_csv`]): `coh{i}_{j}`, the
/// ordinary coherence of output `i` with input `j`, from the run that excited input `j`.
pub fn coherence_csv(e: &Experiment, source: &str) -> String {
    let (p, lines) = (e.frf.inputs(), e.frf.lines());
    super::estimate::coherence_csv(
        source,
        "coh<i>_<j>: ordinary coherence of output i with input j (from the run exciting input j)",
        e.frf.frequency_hz(),
        (e.frf.outputs(), p),
        |i, j, k| e.coherence[(i * p + j) * lines + k],
        None,
    )
}

pub fn frf_file(frf: &era::FrfData, meta: &[(&str, String)]) -> FrfFile {
    FrfFile {
        frf: frf.clone(),
        quantity_given: true,
        metadata: meta
            .iter()
            .map(|(k, v)| (k.to_string(), v.clone()))
            .collect::<BTreeMap<_, _>>(),
        channels: None,
    }
}

pub fn write_frf(staged: &Path, file: &FrfFile) -> anyhow::Result<()> {
    match FrfFormat::from_extension(staged) {
        Some(FrfFormat::Csv) | None => {
            era_io::format::write_frf_csv_keeping(staged, file, |_| true)?
        }
        Some(_) => era_io::format::write_frf_file(staged, file, UffWriteOptions::default())?,
    }
    Ok(())
}

pub fn frf_format(flag: &str, path: &Path) -> anyhow::Result<()> {
    if FrfFormat::from_extension(path).is_none() {
        return usage(format!(
            "{flag} {}: cannot tell the format from the extension: use .csv, .uff (or .unv) or .mat",
            path.display()
        ));
    }
    Ok(())
}

/// One run's analyzer record as a time-history CSV `era frf` reads.
pub fn time_csv(e: &Experiment, run: usize, rate_hz: f64) -> String {
    let rec = &e.records[run];
    let a = rec.voltage.len();
    let q = rec.acceleration.len();
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# era simulate experiment: run {} (excited actuator(s) {})",
        run + 1,
        rec.excited
            .iter()
            .map(|j| (j + 1).to_string())
            .collect::<Vec<_>>()
            .join(" ")
    );
    out.push_str("time_s");
    for j in 1..=a {
        let _ = write!(out, ",volt{j}");
    }
    for i in 1..=q {
        let _ = write!(out, ",acc{i}");
    }
    for j in 1..=a {
        let _ = write!(out, ",stroke{j},lvt{j},comp{j}");
    }
    out.push('\n');
    for k in 0..rec.acceleration[0].len() {
        let _ = write!(out, "{}", k as f64 / rate_hz);
        for v in &rec.voltage {
            let _ = write!(out, ",{}", v[k]);
        }
        for v in &rec.acceleration {
            let _ = write!(out, ",{}", v[k]);
        }
        for j in 0..a {
            let _ = write!(
                out,
                ",{},{},{}",
                rec.stroke[j][k], rec.relative_velocity[j][k], rec.compensation_v[j][k]
            );
        }
        out.push('\n');
    }
    out
}

/// Seconds of each run drawn in its time-history figure.
pub const FIGURE_SPAN_S: f64 = 20.0;

/// The first [`FIGURE_SPAN_S`] of one run, for the first excited actuator: the drive and
/// compensation voltages, the LVT velocity against the compensator's dead zone, and the
/// stroke. It shows where the mass sticks and where the compensator acts at all.
pub fn time_figure(e: &Experiment, run: usize, rate_hz: f64, dead_zone: f64) -> Figure {
    let rec = &e.records[run];
    let j = rec.excited.first().copied().unwrap_or(0);
    let n = ((FIGURE_SPAN_S * rate_hz) as usize).min(rec.voltage[j].len());
    let t: Vec<f64> = (0..n).map(|k| k as f64 / rate_hz).collect();
    let series = |label: &str, y: &[f64], kind| Series {
        label: label.into(),
        x: t.clone(),
        y: y[..n].to_vec(),
        kind,
    };
    let range = |ys: &[&[f64]]| {
        let m = ys
            .iter()
            .flat_map(|y| y[..n].iter())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let m = if m > 0.0 { 1.1 * m } else { 1.0 };
        (-m, m)
    };
    let panel = |y_label: &str, series: Vec<Series>, y_range, guide| Panel {
        title: String::new(),
        x_label: "time (s)".into(),
        y_label: y_label.into(),
        y_scale: YScale::Linear,
        x_range: (0.0, FIGURE_SPAN_S),
        y_range,
        series,
        marker_x: None,
        guide_y: guide,
        legend: true,
    };
    let (v, c, z, s) = (
        &rec.voltage[j],
        &rec.compensation_v[j],
        &rec.relative_velocity[j],
        &rec.stroke[j],
    );
    let stuck = stuck_samples(&z[..n]);
    Figure {
        title: format!(
            "run {}: actuator {}, first {FIGURE_SPAN_S:.0} s (stuck {:.0} % of samples)",
            run + 1,
            j + 1,
            100.0 * stuck as f64 / n.max(1) as f64
        ),
        panels: vec![
            panel(
                "voltage (V)",
                vec![
                    series("excitation", v, SeriesKind::Measured),
                    series("compensation", c, SeriesKind::Model),
                ],
                range(&[v, c]),
                None,
            ),
            panel(
                "LVT velocity (in/s)",
                vec![series("relative velocity", z, SeriesKind::Measured)],
                range(&[z]),
                Some((dead_zone, format!("compensator dead zone {dead_zone} in/s"))),
            ),
            panel(
                "stroke (in)",
                vec![series("proof-mass stroke", s, SeriesKind::Measured)],
                range(&[s]),
                None,
            ),
        ],
        columns: 1,
        size: (1100, 900),
    }
}

/// Samples at which a proof mass is stuck: its LVT velocity (recorded without noise)
/// is exactly 0 only then.
pub fn stuck_samples(lvt: &[f64]) -> usize {
    lvt.iter().filter(|v| **v == 0.0).count()
}

/// Over all runs, for each run's excited actuator(s): the share of analyzer samples at
/// which the mass is stuck, and the share at which its speed is above the compensator's
/// dead zone (where compensation acts).
pub fn motion_shares(e: &Experiment, dead_zone: f64) -> (f64, f64) {
    let (mut stuck, mut above, mut total) = (0usize, 0usize, 0usize);
    for rec in &e.records {
        for &j in &rec.excited {
            let z = &rec.relative_velocity[j];
            stuck += stuck_samples(z);
            above += z.iter().filter(|x| x.abs() > dead_zone).count();
            total += z.len();
        }
    }
    let total = total.max(1) as f64;
    (stuck as f64 / total, above as f64 / total)
}

/// The output sets of `simulate experiment`, opened before the work so that a bad
/// output is refused first: the FRFs and their coherence, the exact FRFs, the time
/// histories.
pub struct Sets {
    /// The FRF file and its coherence, committed together.
    pub frf: OutputSet,
    /// The exact FRFs (`--exact-out`).
    pub exact: Option<OutputSet>,
    /// The time histories' folder (`--time-histories`).
    pub time_histories: Option<OutputSet>,
}

/// The output sets, opened (and the names checked) before the work.
pub fn prepare(a: &config::Experiment) -> anyhow::Result<Sets> {
    frf_format("--out", &a.out)?;
    if let Some(p) = &a.exact_out {
        frf_format("--exact-out", p)?;
    }
    let mut frf = OutputSet::beside(&a.out)?;
    frf.stage(output_name("--out", &a.out)?)?;
    let coherence = crate::output::coherence_path(&a.out);
    frf.stage(output_name("--out", &coherence)?)?;
    let exact = match &a.exact_out {
        Some(p) => {
            let mut s = OutputSet::beside(p)?;
            s.stage(output_name("--exact-out", p)?)?;
            Some(s)
        }
        None => None,
    };
    let time_histories = match &a.time_histories {
        Some(dir) => Some(OutputSet::new(dir).map_err(|e| {
            crate::error::UsageError(format!("--time-histories {}: {e}", dir.display()))
        })?),
        None => None,
    };
    Ok(Sets {
        frf,
        exact,
        time_histories,
    })
}

/// The FRFs and their coherence (committed together), then the exact FRFs.
pub fn write_frfs(
    a: &config::Experiment,
    mut set: OutputSet,
    exact_set: Option<OutputSet>,
    found: &Experiment,
    spec: &ExperimentSpec,
) -> anyhow::Result<()> {
    let coherence = crate::output::coherence_path(&a.out);
    let mut meta = vec![
        ("source", "era simulate experiment".to_string()),
        (
            "compensation",
            (if a.compensation { "on" } else { "off" }).to_string(),
        ),
        ("averages", a.averages.to_string()),
        ("seed", a.seed.to_string()),
        ("friction_scale", a.friction_scale.to_string()),
        ("excitation_rms_v", spec.excitation_rms_v.to_string()),
        ("input_unit", "V".to_string()),
        ("response_unit", "in/s^2".to_string()),
    ];
    let file = frf_file(&found.frf, &meta);
    write_output(&mut set, output_name("--out", &a.out)?, |staged| {
        write_frf(staged, &file)
    })?;
    let text = coherence_csv(found, &a.out.display().to_string());
    write_output(&mut set, output_name("--out", &coherence)?, |staged| {
        era_io::atomic::write_atomic(staged, text.as_bytes())?;
        Ok(())
    })?;
    set.commit()?;
    if let (Some(mut s), Some(p)) = (exact_set, &a.exact_out) {
        meta[0].1 = "era simulate experiment (exact FRFs of the linear system)".into();
        let exact = frf_file(&found.exact, &meta);
        write_output(&mut s, output_name("--exact-out", p)?, |staged| {
            write_frf(staged, &exact)
        })?;
        s.commit()?;
    }
    Ok(())
}

/// One CSV and one figure per run into the `--time-histories` folder.
pub fn write_time_histories(
    mut s: OutputSet,
    found: &Experiment,
    rate_hz: f64,
    dead_zone: f64,
) -> anyhow::Result<()> {
    for r in 0..found.records.len() {
        let text = time_csv(found, r, rate_hz);
        write_output(&mut s, format!("run{}.csv", r + 1), |staged| {
            era_io::atomic::write_atomic(staged, text.as_bytes())?;
            Ok(())
        })?;
        let figure = time_figure(found, r, rate_hz, dead_zone);
        write_figure(&mut s, Path::new(""), &format!("run{}", r + 1), &figure)?;
    }
    s.commit()?;
    Ok(())
}

/// What was written and what happened in the actuators.
pub fn summary_line(
    a: &config::Experiment,
    found: &Experiment,
    spec: &ExperimentSpec,
    runs: usize,
) -> String {
    let c = found.counts;
    format!(
        "wrote {} and {}: {} outputs x {} inputs, {} lines at {} Hz (acceleration per volt)\n  \
         {} run(s) of {} x 40 s, compensation {}, friction x{}: {} reversals, {} sticks, {} break-aways, {} end-stop impacts\n  \
         largest stroke per actuator (in): {}\n",
        a.out.display(),
        crate::output::coherence_path(&a.out).display(),
        found.frf.outputs(),
        found.frf.inputs(),
        found.frf.lines(),
        found.frf.spacing_hz(),
        runs,
        a.averages,
        if spec.compensation.is_some() { "on" } else { "off" },
        a.friction_scale,
        c.reversals,
        c.sticks,
        c.breakaways,
        c.impacts,
        found
            .max_stroke
            .iter()
            .map(|s| format!("{s:.3}"))
            .collect::<Vec<_>>()
            .join(" ")
    )
}

/// The run's summary, printed with `--json`: the files, the test's sizes and settings,
/// the actuators' events and, with time histories, the excited actuators' shares of
/// time stuck and above the dead zone.
pub fn summary_json(
    a: &config::Experiment,
    found: &Experiment,
    spec: &ExperimentSpec,
    geometry: &Path,
    shares: Option<(f64, f64)>,
) -> serde_json::Value {
    let coherence = crate::output::coherence_path(&a.out);
    let c = found.counts;
    json!({
        "file": a.out, "coherence_file": coherence, "exact_file": a.exact_out, "geometry": geometry,
        "time_histories": a.time_histories,
        "outputs": found.frf.outputs(), "inputs": found.frf.inputs(), "lines": found.frf.lines(),
        "spacing_hz": found.frf.spacing_hz(), "compensation": spec.compensation.is_some(),
        "averages": a.averages, "seed": a.seed, "friction_scale": a.friction_scale,
        "excitation_rms_v": spec.excitation_rms_v,
        "events": {"reversals": c.reversals, "sticks": c.sticks, "breakaways": c.breakaways, "impacts": c.impacts},
        "max_stroke_in": found.max_stroke,
        "excited_stuck_fraction": shares.map(|s| s.0),
        "excited_above_dead_zone_fraction": shares.map(|s| s.1),
    })
}
