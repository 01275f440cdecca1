//! The outputs of `era track`: the summary and the table of tracks on the terminal,
//! and in `--out` tracks.parquet (one row per tracked mode, era-io's
//! [`era_io::tracks`]), tracks.json (per track), the figures of frequency and damping
//! against time per track (frequency.png/svg, damping.png/svg) and report.html.

use super::figures::write_png_with;
use super::write_output;
use crate::input::fleet::Fleet;
use era::modal::track::{trend, Track, TrackOptions, Tracking, TrendUnit};
use era_io::atomic::{write_atomic, OutputSet};
use era_io::tracks::{write_tracks, TrackRow};
use era_plot::track::{
    track_html, track_png, track_svg, trend_text, TrackPage, TrackPanel, TrackPlot,
};
use serde_json::json;
use std::fmt::Write as _;
use std::path::PathBuf;

/// One `era track` run: the folders, the fleet as read, the tracks and the options.
pub struct TrackRun<'a> {
    /// The folders given.
    pub dirs: &'a [PathBuf],
    /// The fleet as read.
    pub fleet: &'a Fleet,
    /// The tracks.
    pub tracking: &'a Tracking,
    /// The options run.
    pub options: &'a TrackOptions,
}

/// The most panels a figure draws (the table lists every track).
const MAX_PANELS: usize = 24;

impl TrackRun<'_> {
    /// The lines before the table: what was read, the options, how many tracks.
    pub fn summary(&self) -> String {
        let f = self.fleet;
        let t = self.tracking;
        let mut s = String::new();
        for (path, rows, records) in &f.shards {
            let _ = writeln!(
                s,
                "  {}: {rows} mode rows of {records} records",
                path.display()
            );
        }
        if !f.statuses.is_empty() {
            let counts: Vec<String> = f.statuses.iter().map(|(k, v)| format!("{v} {k}")).collect();
            let _ = writeln!(s, "  records.jsonl: {}", counts.join(", "));
        }
        let times = match t.unit {
            TrendUnit::Day => "every record has a time: trends per day".to_string(),
            TrendUnit::Record => {
                let missing = f.times_us.iter().filter(|t| t.is_none()).count();
                format!(
                    "{missing} record(s) without a time: records in id order, trends per record"
                )
            }
        };
        let _ = writeln!(s, "  {} records; {times}", f.records.len());
        let o = self.options;
        let _ = writeln!(
            s,
            "  {} modes; frequency tolerance {} %, MAC at least {}, sparse below {} records",
            if o.all_modes { "all" } else { "physical" },
            100.0 * o.frequency_tolerance,
            o.mac_min,
            t.min_records
        );
        let sparse = t.tracks.iter().filter(|t| t.sparse).count();
        let _ = writeln!(
            s,
            "  {} tracks ({sparse} sparse) of {} modes",
            t.tracks.len(),
            t.members.len()
        );
        if let Some(line) = self.change_line() {
            let _ = writeln!(s, "  {line}");
        }
        s
    }

    /// The first record after the change's split: its id and time.
    fn first_after(&self, split: f64) -> Option<(String, Option<i64>)> {
        let t = self.tracking;
        let m = t
            .members
            .iter()
            .filter(|m| m.x > split)
            .min_by(|a, b| a.x.total_cmp(&b.x))?;
        let f = self.fleet;
        Some((f.records[m.record].id.clone(), f.times_us[m.record]))
    }

    /// What the change test found, in a line.
    pub fn change_line(&self) -> Option<String> {
        let c = self.tracking.change.as_ref()?;
        let (id, time) = self.first_after(c.split)?;
        let when = time
            .map(|us| format!(" ({})", era_io::fleet::format_time(us)))
            .unwrap_or_default();
        let steps: Vec<f64> = c
            .steps
            .iter()
            .flatten()
            .map(|s| 100.0 * s.relative)
            .collect();
        let lo = steps.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = steps.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Some(if c.significant {
            format!(
                "a change from record {id}{when}: the frequencies step by {lo:+.2} to {hi:+.2} % beyond their trend (sum of t^2 {:.1} over {} tracks, above {:.1} at a 0.1 % false-alarm rate)",
                c.score,
                steps.len(),
                c.threshold
            )
        } else {
            format!(
                "no change found: the largest step, from record {id}{when}, has a sum of t^2 of {:.1} over {} tracks, below {:.1} (0.1 % false-alarm rate)",
                c.score,
                steps.len(),
                c.threshold
            )
        })
    }

    /// The rows of tracks.parquet, one per tracked mode, in time order.
    fn rows(&self) -> Vec<TrackRow> {
        let f = self.fleet;
        let t = self.tracking;
        t.members
            .iter()
            .map(|m| {
                let mode = &f.records[m.record].modes[m.mode];
                TrackRow {
                    record_id: f.records[m.record].id.clone(),
                    time_us: f.times_us[m.record],
                    track: m.track as u32,
                    mode: f.mode_numbers[m.record][m.mode],
                    frequency_hz: mode.frequency_hz,
                    damping_ratio: mode.damping_ratio,
                    frequency_std_hz: mode.frequency_std_hz,
                    damping_ratio_std: mode.damping_ratio_std,
                    mac_to_track: m.mac_to_track,
                    physical: mode.physical,
                    sparse: t.tracks[m.track - 1].sparse,
                    x: m.x,
                }
            })
            .collect()
    }
}

/// The table of tracks for the terminal.
pub fn track_table(run: &TrackRun) -> String {
    let unit = run.tracking.unit.name();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:>5} {:>7} {:>11} {:>10} {:>9} {:>9} {:>22}",
        "track",
        "records",
        "f (Hz)",
        "std (Hz)",
        "zeta (%)",
        "std (%)",
        format!("trend (%/{unit})")
    );
    for t in &run.tracking.tracks {
        let _ = writeln!(
            s,
            "{:>5} {:>7} {:>11.4} {:>10.4} {:>9.3} {:>9.3} {:>22}{}",
            t.id,
            t.records,
            t.frequency_mean_hz,
            t.frequency_std_hz,
            100.0 * t.damping_mean,
            100.0 * t.damping_std,
            trend_text(t),
            if t.sparse { "  sparse" } else { "" }
        );
    }
    s
}

/// tracks.json (and the `--json` output): the fleet, the options and every track with
/// its mean, spread, trend and sparse flag.
pub fn tracks_json(run: &TrackRun) -> serde_json::Value {
    let t = run.tracking;
    let o = run.options;
    let unit = t.unit.name();
    let tracks: Vec<serde_json::Value> = t
        .tracks
        .iter()
        .map(|k| {
            json!({
                "track": k.id,
                "records": k.records,
                "sparse": k.sparse,
                "frequency_mean_hz": k.frequency_mean_hz,
                "frequency_std_hz": k.frequency_std_hz,
                "damping_ratio_mean": k.damping_mean,
                "damping_ratio_std": k.damping_std,
                "trend": k.trend.map(|tr| json!({
                    "per": unit,
                    "relative_slope": tr.relative,
                    "relative_slope_std_error": tr.relative_std_error,
                    "slope_hz": tr.slope_hz,
                    "intercept_hz": tr.intercept_hz,
                })),
            })
        })
        .collect();
    json!({
        "records": run.fleet.records.len(),
        "shards": run.fleet.shards.iter().map(|s| s.0.display().to_string()).collect::<Vec<_>>(),
        "trend_per": unit,
        "origin": t.origin_s.map(|s| era_io::fleet::format_time((s * 1e6).round() as i64)),
        "options": {
            "all_modes": o.all_modes,
            "frequency_tolerance": o.frequency_tolerance,
            "mac_min": o.mac_min,
            "min_records": t.min_records,
        },
        "tracks": tracks,
        "change": t.change.as_ref().map(|c| {
            let first = run.first_after(c.split);
            json!({
                "significant": c.significant,
                "first_record": first.as_ref().map(|f| f.0.clone()),
                "time": first.and_then(|f| f.1).map(era_io::fleet::format_time),
                "split": c.split,
                "score": c.score,
                "threshold": c.threshold,
                "steps": t.tracks.iter().zip(&c.steps).filter_map(|(k, st)| st.map(|st| json!({
                    "track": k.id,
                    "relative_step": st.relative,
                    "step_hz": st.step_hz,
                    "t": st.t,
                }))).collect::<Vec<_>>(),
            })
        }),
    })
}

/// The panels of the tracks to draw (the non-sparse ones, or all when every track is
/// sparse, at most [`MAX_PANELS`]): frequency (Hz) or damping (%).
fn panels(run: &TrackRun, damping: bool) -> Vec<TrackPanel> {
    let t = run.tracking;
    let shown: Vec<&Track> = if t.tracks.iter().any(|k| !k.sparse) {
        t.tracks.iter().filter(|k| !k.sparse).collect()
    } else {
        t.tracks.iter().collect()
    };
    let unit = t.unit.name();
    shown
        .into_iter()
        .take(MAX_PANELS)
        .map(|k| {
            let mine: Vec<_> = t.members.iter().filter(|m| m.track == k.id).collect();
            let mode = |m: &era::modal::track::Member| &run.fleet.records[m.record].modes[m.mode];
            let x: Vec<f64> = mine.iter().map(|m| m.x).collect();
            let (y, std): (Vec<f64>, Vec<Option<f64>>) = if damping {
                mine.iter()
                    .map(|m| {
                        let md = mode(m);
                        (
                            100.0 * md.damping_ratio,
                            md.damping_ratio_std.map(|s| 100.0 * s),
                        )
                    })
                    .unzip()
            } else {
                mine.iter()
                    .map(|m| (mode(m).frequency_hz, mode(m).frequency_std_hz))
                    .unzip()
            };
            let mean = y.iter().sum::<f64>() / y.len().max(1) as f64;
            let line = trend(&x, &y, mean).map(|tr| (tr.intercept_hz, tr.slope_hz));
            let title = if damping {
                format!(
                    "Track {} ({:.3} Hz): ζ {:.3} ± {:.3} %",
                    k.id,
                    k.frequency_mean_hz,
                    100.0 * k.damping_mean,
                    100.0 * k.damping_std
                )
            } else {
                format!(
                    "Track {}: {:.4} Hz, {} records, trend {} %/{unit}",
                    k.id,
                    k.frequency_mean_hz,
                    k.records,
                    trend_text(k)
                )
            };
            // With a change found, the frequency panel draws the model of the change
            // test (trend, daily cycle, step) instead of the straight trend.
            let curve = (!damping).then(|| step_curve(t, k.id, &x)).flatten();
            TrackPanel {
                title,
                x,
                y,
                std,
                line,
                curve,
            }
        })
        .collect()
}

/// The fitted model of a significant change for track `id`, sampled across `x`'s span
/// (each side of the split reaching it, so the step shows as a step).
fn step_curve(t: &Tracking, id: usize, x: &[f64]) -> Option<Vec<(f64, f64)>> {
    let change = t.change.as_ref().filter(|c| c.significant)?;
    let k = t.tracks.iter().position(|tr| tr.id == id)?;
    let model = change.steps.get(k).copied().flatten()?.model;
    let lo = x.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = x.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let n = 400;
    let mut points: Vec<f64> = (0..=n)
        .map(|j| lo + (hi - lo) * j as f64 / n as f64)
        .collect();
    let eps = 1e-9 * (hi - lo).max(1.0);
    points.extend([model.split - eps, model.split + eps]);
    points.sort_by(f64::total_cmp);
    Some(points.into_iter().map(|v| (v, model.at(v))).collect())
}

/// tracks.parquet, tracks.json, the figures and report.html into `set`.
pub fn write_track(
    set: &mut OutputSet,
    run: &TrackRun,
    json: &serde_json::Value,
) -> anyhow::Result<()> {
    let rows = run.rows();
    write_output(set, "tracks.parquet", |p| Ok(write_tracks(p, &rows)?))?;
    write_output(set, "tracks.json", |p| {
        Ok(era_io::model_json::write_json(p, json)?)
    })?;
    let unit = run.tracking.unit.name();
    let sparse_note = if run.tracking.tracks.iter().any(|k| k.sparse) {
        " Sparse tracks are left out of the figures (they are in the table)."
    } else {
        ""
    };
    let figures = [
        (
            "frequency",
            "Frequency of each track over time",
            "Natural frequency (Hz)",
            format!("Each record's frequency of the track (dots) with ± one standard deviation where the identification estimated one (bars), and the least-squares trend (red line; its slope relative to the mean, % per {unit}, in the panel's title). When the fleet's step test found a change, a dashed line marks it and the red curve is that test's model: trend, daily cycle and step.{sparse_note}"),
        ),
        (
            "damping",
            "Damping of each track over time",
            "Damping ratio (%)",
            format!("Each record's damping ratio of the track with ± one standard deviation (bars) and its least-squares line. Damping scatters far more than frequency from record to record: read its level, not each point.{sparse_note}"),
        ),
    ];
    let mut sections = Vec::new();
    for (stem, heading, y_label, caption) in figures {
        let mut plot = TrackPlot::new(
            heading,
            y_label,
            run.tracking.origin_s,
            panels(run, stem == "damping"),
        );
        plot.change = run
            .tracking
            .change
            .as_ref()
            .filter(|c| c.significant)
            .map(|c| c.split);
        let svg = track_svg(&plot)?;
        write_output(set, format!("{stem}.svg"), |p| {
            Ok(write_atomic(p, svg.as_bytes())?)
        })?;
        write_output(set, format!("{stem}.png"), |p| {
            Ok(write_png_with(p, |tmp| track_png(&plot, tmp))?)
        })?;
        sections.push((stem.to_string(), heading.to_string(), caption, svg));
    }
    let title = format!(
        "era track {}",
        run.dirs
            .iter()
            .map(|d| d.display().to_string())
            .collect::<Vec<_>>()
            .join(" ")
    );
    let notes = format!(
        "{}\nera {}, {}",
        run.summary(),
        env!("CARGO_PKG_VERSION"),
        super::utc_now()
    );
    let first = run
        .tracking
        .change
        .as_ref()
        .filter(|c| c.significant)
        .and_then(|c| run.first_after(c.split).map(|f| (f.0, c)));
    let html = track_html(&TrackPage {
        title: &title,
        notes: &notes,
        tracks: &run.tracking.tracks,
        unit: run.tracking.unit,
        figures: &sections,
        change: first.as_ref().map(|(id, c)| {
            let steps = c
                .steps
                .iter()
                .map(|s| s.map(|s| (s.relative, s.t)))
                .collect();
            (id.as_str(), steps)
        }),
    });
    write_output(set, "report.html", |p| {
        Ok(write_atomic(p, html.as_bytes())?)
    })
}
