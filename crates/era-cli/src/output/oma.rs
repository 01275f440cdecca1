//! The outputs of `era oma`: the summary and mode table on the terminal, the JSON, and
//! with `--out` the model files (the bundle writer's, model.json with the output-only
//! facts added), the figures (Hankel singular values, stabilization diagram, spectral
//! singular values with the modes marked, the MAC matrix of the physical modes) and
//! report.html.

use super::figures::{write_figure, write_png_with, write_shape_figures, write_stabilization};
use super::identification::{write_bundle, Bundle};
use super::{stamped, write_output, RunInput};
use crate::input::oma::Records;
use era::identify::oma::Oma;
use era_io::atomic::{write_atomic, OutputSet};
use era_io::model_json::{FitJson, ModelJson, ModelParameters, OutputOnlyJson};
use era_plot::oma::{mac_png, mac_svg, spectral_png, spectral_svg, MacPlot, SpectralPlot};
use era_plot::report::{report_html, InputSection, ReportInput, ReportSection};
use era_plot::{singular_value_figure, FrfUnits, FrfView, PhaseView};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One `era oma` run: the files, the records as read, the result and whether the order
/// was automatic.
pub struct OmaRun<'a> {
    /// The time files.
    pub files: &'a [PathBuf],
    /// The records.
    pub records: &'a Records,
    /// The identification.
    pub oma: &'a Oma,
    /// The options run (the sample rate and references set).
    pub options: &'a era::identify::oma::OmaOptions,
    /// `--states auto`.
    pub auto: bool,
    /// The test geometry (`--geometry`): its file and nodes.
    pub geometry: Option<&'a (String, era_io::geometry::Geometry)>,
}

/// The most channels listed by label in the summary.
const LISTED: usize = 12;

impl OmaRun<'_> {
    /// The labels of `indices` among the outputs: every one up to [`LISTED`], else the
    /// first and last.
    fn labels(&self, indices: &[usize]) -> String {
        let l = &self.records.labels;
        if indices.len() <= LISTED {
            indices
                .iter()
                .map(|&k| l[k].clone())
                .collect::<Vec<_>>()
                .join(", ")
        } else {
            format!(
                "{} channels, {} .. {}",
                indices.len(),
                l[indices[0]],
                l[indices[indices.len() - 1]]
            )
        }
    }

    /// The lines before the mode table: the records, the outputs, how the correlations
    /// were taken, the order, and that the shapes are unscaled.
    pub fn summary(&self) -> String {
        let (r, o) = (self.records, self.oma);
        let all: Vec<usize> = (0..r.labels.len()).collect();
        let mut s = String::new();
        let _ = writeln!(
            s,
            "  time histories: {} record(s) ({}), sample rate {} Hz from {}",
            r.channels.len(),
            r.format,
            r.rate,
            r.rate_from
        );
        let _ = writeln!(s, "  outputs: {}", self.labels(&all));
        let _ = writeln!(s, "{}", self.correlation_line());
        let asked = self.options.blocks;
        if o.blocks != asked {
            let _ = writeln!(
                s,
                "  note: --blocks {asked} asked; {} taken, as many as the records hold at twice the {} lags each{}",
                o.blocks,
                o.lags,
                if o.blocks < 2 { " (no standard deviations)" } else { "" }
            );
        }
        let order = if self.auto {
            "auto (from the stabilization diagram)".to_string()
        } else {
            format!("{} states", o.identification.realization.model.states())
        };
        let _ = writeln!(s, "  order: {order}");
        let spread = if o.blocks >= 2 {
            "± is one standard deviation from the delete-one-block jackknife"
        } else {
            "no standard deviations with --blocks 1"
        };
        let _ = writeln!(
            s,
            "  shapes: unscaled (no measured input, so no modal mass); {spread}"
        );
        s
    }

    /// How the correlations were taken, one line.
    fn correlation_line(&self) -> String {
        let o = self.oma;
        let refs = if o.references.len() == self.records.labels.len() {
            format!("every output ({})", o.references.len())
        } else {
            format!("{} ({})", o.references.len(), self.labels(&o.references))
        };
        format!(
            "  correlations: {} method, references {refs}, {} lags ({:.3} s), {} jackknife block(s), {} samples per channel",
            o.method,
            o.lags,
            o.lags as f64 / self.records.rate,
            o.blocks,
            o.samples
        )
    }
}

/// The mode table: frequency ± std, damping ± std, MPC, physical or not; the reasons
/// for the modes not judged physical below it.
pub fn oma_table(o: &Oma) -> String {
    let found = &o.identification;
    let mut s = String::new();
    let pm = |v: Option<f64>, scale: f64| {
        v.map_or(format!("{:>10}", "-"), |x| format!("± {:>8.4}", scale * x))
    };
    let _ = writeln!(
        s,
        "{:>5} {:>12} {:>10} {:>10} {:>10} {:>6}  physical",
        "mode", "f (Hz)", "± (Hz)", "zeta (%)", "± (%)", "MPC"
    );
    let mut reasons = Vec::new();
    for (k, m) in found.modal.modes.iter().enumerate() {
        let q = found.quality.get(k);
        let physical = super::report::verdict(k, m, q, &mut reasons, ("yes", "no", "-"));
        let _ = writeln!(
            s,
            "{:>5} {:>12.4} {} {:>10.4} {} {:>6}  {physical}",
            k + 1,
            m.frequency_hz,
            pm(q.and_then(|q| q.frequency_std_hz), 1.0),
            100.0 * m.damping_ratio,
            pm(q.and_then(|q| q.damping_ratio_std), 100.0),
            q.map_or("-".into(), |q| format!("{:.3}", q.indicators.mpc)),
        );
    }
    let physical = found.quality.iter().filter(|q| q.physical).count();
    let _ = writeln!(
        s,
        "{physical} of {} modes physical",
        found.modal.modes.len()
    );
    if !reasons.is_empty() {
        let _ = writeln!(s, "not physical:");
        for r in reasons {
            let _ = writeln!(s, "{r}");
        }
    }
    s
}

/// The run's model.json: the model's fields, each mode's `shape_std` and `blocks_found`,
/// and the output-only facts ([`era_io::model_json::OutputOnlyJson`]): `method`,
/// `outputs_columns` and `references` (the files' 1-based columns), `lags`, `blocks`,
/// `samples`, `sample_rate_hz`, `records` and `"shapes": "unscaled"`.
pub fn oma_json(run: &OmaRun) -> ModelJson {
    let o = run.oma;
    let found = &o.identification;
    let mut era_options = run.options.era.clone();
    // As the core ran it: the method's realizer.
    era_options.realizer = match o.method {
        era::identify::oma::OmaMethod::NextEra => era::identify::Realizer::Era,
        _ => era::identify::Realizer::Shift,
    };
    if !run.auto {
        era_options.order = era::Order::Fixed(found.realization.model.states());
    }
    let mut params = ModelParameters::new(&era_options);
    params.automatic_order = run.auto;
    params.model_states = Some(found.model.states());
    params.orders = found.stabilization.as_ref().map(|st| st.range.to_string());
    let mut model = ModelJson::from_run(found, &params);
    for (mode, spread) in model.modes.iter_mut().zip(&o.spread) {
        mode.shape_std = Some(spread.as_ref().map(|s| s.shape_std.clone()));
        mode.blocks_found = Some(spread.as_ref().map(|s| s.blocks_found));
    }
    let columns = &run.records.columns;
    model.output_only = Some(OutputOnlyJson {
        method: o.method.to_string(),
        outputs_columns: columns.iter().map(|c| c + 1).collect(),
        references: o.references.iter().map(|&k| columns[k] + 1).collect(),
        lags: o.lags,
        blocks: o.blocks,
        samples: o.samples,
        sample_rate_hz: run.records.rate,
        records: run.files.to_vec(),
        shapes: "unscaled".into(),
    });
    model
}

/// model.json ([`oma_json`]) into `set`: written last, with the timings when they were
/// asked for. Its keys are in alphabetical order, as `era oma` has always written them.
pub fn write_model_json(set: &mut OutputSet, model: &ModelJson) -> anyhow::Result<()> {
    let json = serde_json::to_value(model)?;
    write_output(set, "model.json", |p| {
        Ok(era_io::model_json::write_json(p, &json)?)
    })
}

/// Every output of the run but model.json into `set`: fit.json, model.mat,
/// model_frf.uff and modes.uff (the bundle writer's), and with `figures` the figures and
/// report.html.
pub fn write_oma(
    set: &mut OutputSet,
    run: &OmaRun,
    figures: bool,
    settings: &crate::config::Settings,
) -> anyhow::Result<()> {
    let found = &run.oma.identification;
    let here = Path::new("");
    let fit = FitJson::from_report(&found.fit);
    let source = run_input(run);
    let title = format!(
        "era oma {}",
        run.files
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(" ")
    );
    let echo = run.summary();
    let states = found.realization.model.states();
    let bundle = Bundle {
        found,
        fit: &fit,
        source: &source,
        title: &title,
        echo: &echo,
        states,
        figures: false,
    };
    write_bundle(set, here, &bundle, settings)?;
    if !figures {
        return Ok(());
    }
    let singular_values = match &found.stabilization {
        Some(st) => &st.singular_values,
        None => &found.realization.singular_values,
    };
    let sv_svg = write_figure(
        set,
        here,
        "singular_values",
        &singular_value_figure(singular_values, states),
    )?;
    let stabilization_svg = write_stabilization(set, here, found)?;
    let mut sections_svg: Vec<(&str, &str, String, String)> = Vec::new();
    let spectral = spectral_plot(run);
    let svg = spectral_svg(&spectral)?;
    write_output(set, "spectral.svg", |p| {
        Ok(write_atomic(p, svg.as_bytes())?)
    })?;
    write_output(set, "spectral.png", |p| {
        Ok(write_png_with(p, |tmp| spectral_png(&spectral, tmp))?)
    })?;
    sections_svg.push((
        "spectral",
        "Spectral singular values",
        "The singular values of the output spectral matrix at each line (Welch: Hann-windowed segments, half overlapping), largest first: the quick look of frequency-domain decomposition. Peaks of the first are the modes; two curves peaking together are close modes. The dashed red lines are the modes judged physical, the orange ones the others.".into(),
        svg,
    ));
    if let Some(mac) = mac_plot(run) {
        let svg = mac_svg(&mac)?;
        write_output(set, "mac.svg", |p| Ok(write_atomic(p, svg.as_bytes())?))?;
        write_output(set, "mac.png", |p| {
            Ok(write_png_with(p, |tmp| mac_png(&mac, tmp))?)
        })?;
        sections_svg.push((
            "mac",
            "MAC of the physical modes",
            "The modal assurance criterion between the shapes of the physical modes (AutoMAC): 1 on the diagonal; an entry near 1 off it says two modes look alike at these sensors (too few sensors to tell them apart, or one mode found twice).".into(),
            svg,
        ));
    }
    let shapes = super::geometry::shape_view(&source, found);
    let bar = super::progress::bar(settings, 0, "figures");
    let own = write_shape_figures(set, here, found, shapes.as_ref(), false, &bar)?;
    bar.finish_and_clear();
    let mut sections: Vec<ReportSection> = sections_svg
        .iter()
        .map(|(id, heading, caption, svg)| ReportSection {
            id,
            heading,
            caption,
            svg,
        })
        .collect();
    sections.extend(own.iter().map(super::shapes::Section::view));
    let view = FrfView::by_index(found.measured.outputs(), found.measured.inputs());
    let html = report_html(&ReportInput {
        title: &title,
        source: &source.section,
        view: &view,
        coherence: None,
        parameters: &echo,
        found,
        singular_values_svg: &sv_svg,
        stabilization_svg: stabilization_svg.as_deref(),
        sections: &sections,
        grid_svg: None,
        overlays: &[],
        shapes: shapes.as_ref(),
        output_only: true,
    });
    write_output(set, "report.html", |p| {
        Ok(write_atomic(p, html.as_bytes())?)
    })
}

/// The singular values of the output spectral matrix (the core's Welch estimate), with
/// every mode marked.
fn spectral_plot(run: &OmaRun) -> SpectralPlot {
    let found = &run.oma.identification;
    let spectrum = &run.oma.spectrum;
    let modes = found
        .modal
        .modes
        .iter()
        .zip(&found.quality)
        .map(|(m, q)| (m.frequency_hz, q.physical))
        .collect();
    SpectralPlot::new(
        &format!(
            "Spectral singular values (Welch, {} averages of {} samples), modes marked",
            spectrum.averages, spectrum.segment
        ),
        &spectrum.frequency_hz,
        &spectrum.singular_values,
        modes,
        6,
    )
}

/// The AutoMAC of the physical modes, when there are two or more.
fn mac_plot(run: &OmaRun) -> Option<MacPlot> {
    let found = &run.oma.identification;
    let (labels, shapes): (Vec<String>, Vec<Vec<era::Complex64>>) = found
        .modal
        .modes
        .iter()
        .zip(&found.quality)
        .filter(|(_, q)| q.physical)
        .map(|(m, _)| (format!("{:.1}", m.frequency_hz), m.shape.clone()))
        .unzip();
    (labels.len() >= 2).then(|| MacPlot::auto("MAC of the physical modes", labels, &shapes))
}

/// What went into the run, for the report.
fn run_input(run: &OmaRun) -> RunInput {
    let r = run.records;
    let o = run.oma;
    let source = RunInput {
        section: InputSection {
            file: run
                .files
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
            format: format!("time histories ({}), output only", r.format),
            quantity: "output correlations: their half spectrum stands for the FRFs (outputs × references)".into(),
            units: "unscaled".into(),
            notes: vec![
                format!("outputs: {}", r.labels.join(", ")),
                format!(
                    "references: {}",
                    o.references
                        .iter()
                        .map(|&k| r.labels[k].clone())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
                format!("sample rate {} Hz from {}", r.rate, r.rate_from),
                "the mode shapes are unscaled: with no measured input there is no modal mass".into(),
            ],
            ..stamped()
        },
        quantity: o.identification.measured.quantity(),
        units: FrfUnits::default(),
        channels: None,
        coherence: None,
        phase: PhaseView::Wrapped,
        pairs: era_plot::PairSelection::All,
        hankel: None,
        geometry: None,
    };
    let outputs = o.identification.measured.outputs();
    super::geometry::attach(source, run.geometry.cloned(), outputs)
}

/// What the run wrote, for the closing line.
pub fn written_list(dir: &Path, figures: bool, shapes: bool) -> String {
    let files = format!(
        "{0}/model.json, {0}/model.mat, {0}/modes.uff, {0}/model_frf.uff, {0}/fit.json",
        dir.display()
    );
    if figures {
        format!(
            "{files}, {}/report.html and figures (singular_values, stabilization, spectral, mac, complexity{})",
            dir.display(),
            if shapes { ", shapes/" } else { "" }
        )
    } else {
        format!("{files} (no figures)")
    }
}

/// The terminal's summary, the JSON (on stdout too with `--json`) and, with `--out`, the
/// run's files, which take their place together; the verb's result for `era batch`.
pub fn hand_on(
    a: &crate::config::Oma,
    mut outputs: Option<OutputSet>,
    run: &OmaRun,
    read_s: f64,
    human: &super::report::Human,
) -> anyhow::Result<super::Done> {
    use super::report::{print_json, stabilization_summary, timings_table, PART, WALL};
    let found = run.oma;
    let settings = &a.settings;
    human.print(&format!(
        "era oma {}\n",
        crate::input::time::joined(&a.files, " ")
    ));
    human.print(&run.summary());
    human.print(&oma_table(found));
    if let Some(st) = &found.identification.stabilization {
        human.print(&stabilization_summary(st));
    }
    let mut timings = era_io::model_json::timings_map(&found.identification.timings);
    timings.insert("read".into(), read_s);
    // The correlations are the Markov stage's work: a part of it, not added again.
    timings.insert(
        format!("markov{PART}correlations"),
        found.correlation_seconds,
    );
    timings.insert("uncertainty".into(), found.uncertainty_seconds);
    let mut model = oma_json(run);
    if let Some(set) = outputs.as_mut() {
        let clock = std::time::Instant::now();
        write_oma(set, run, !a.no_figures, settings)?;
        timings.insert("write".into(), clock.elapsed().as_secs_f64());
    }
    if settings.timings {
        if let Some(wall) = super::report::process_seconds() {
            timings.insert(WALL.into(), wall);
        }
        human.print(&timings_table(&timings));
        model.timings_s = Some(timings);
    }
    if let Some(set) = outputs.as_mut() {
        write_model_json(set, &model)?;
    }
    if let (Some(dir), Some(set)) = (&a.out, outputs) {
        set.commit()?;
        human.print(&format!(
            "\nwrote {}\n",
            written_list(dir, !a.no_figures, a.geometry.is_some())
        ));
    }
    if settings.json {
        print_json(&serde_json::to_value(&model)?)?;
    }
    Ok(super::Done {
        model,
        channels: run.records.names.clone(),
    })
}
