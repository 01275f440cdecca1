//! `era identify FILE`: the pipeline of docs/design.md §1 on an FRF file.

use crate::args::{DirectTermArg, IdentifyArgs, QuantityArg, StatesArg, SvdArg, TimeDomainArg};
use crate::report::{
    identification_summary, parameter_echo_states, parameters, print_json, stabilization_summary,
    svd_path_line, timings_table, Human,
};
use anyhow::Context;
use era::identify::{
    identify_auto, identify_observed, identify_with_scan, EraOptions, ModelDomain, ScanOptions,
};
use era::modal::stabilization::OrderRange;
use era::params::Naming;
use era::realize::{DirectTerm, SvdPath};
use era::Quantity;
use era_io::atomic::OutputSet;
use era_io::format::{parse_frf_bytes, FrfFormat, ReadOptions};
use era_io::model_json::{timings_map, FitJson, ModelJson};
use std::path::Path;
use std::time::Instant;

/// Options from flags, with the checks clap cannot do (those of the library call are
/// [`EraOptions::check`], shared with the Python package; `--orders` is the CLI's own).
pub fn options(a: &IdentifyArgs) -> anyhow::Result<EraOptions> {
    let states = match a.states {
        StatesArg::Fixed(n) => n,
        // The scan sets its own orders; this is only echoed.
        StatesArg::Auto => 0,
    };
    let opts = EraOptions {
        states,
        hankel_factor: a.hankel_factor,
        integrations: a.integrations,
        lowpass: a.lowpass_hz.map(|hz| (a.lowpass_order, hz)),
        zero_lines: a.zero_lines,
        pad_to: a.pad_to,
        domain: match a.time_domain {
            TimeDomainArg::Discrete => ModelDomain::Discrete,
            TimeDomainArg::Continuous => ModelDomain::Continuous,
        },
        direct_term: match a.direct_term {
            DirectTermArg::Zero => DirectTerm::Zero,
            DirectTermArg::Markov0 => DirectTerm::FirstMarkov,
        },
        svd: match a.svd {
            SvdArg::Dense => SvdPath::Dense,
            SvdArg::MatrixFree => SvdPath::MatrixFree,
            SvdArg::Auto => SvdPath::Auto,
        },
    };
    // Sizes are checked against their limits here, under the flag's name, before anything
    // is read or allocated (the core checks them again for library users). With
    // --states auto every other parameter is checked as for one state.
    let checked = EraOptions {
        states: states.max(usize::from(a.states == StatesArg::Auto)),
        ..opts.clone()
    };
    checked.check(Naming::Flag)?;
    use era::limits::SAMPLES;
    if let Some(range) = scan_orders(a)? {
        SAMPLES.check_product(
            format!("--orders {} x --hankel-factor (Markov samples)", range.max),
            &[range.max as u64, a.hankel_factor as u64],
        )?;
    }
    Ok(opts)
}

/// `--orders` parsed, naming the flag in errors.
pub fn scan_orders(a: &IdentifyArgs) -> anyhow::Result<Option<OrderRange>> {
    match &a.orders {
        None => Ok(None),
        Some(text) => OrderRange::parse(text)
            .map(Some)
            .map_err(|e| crate::UsageError(format!("--orders {text}: {}", reason_of(&e))).into()),
    }
}

fn reason_of(e: &era::EraError) -> String {
    match e {
        era::EraError::InvalidParameter { reason, .. } => reason.clone(),
        other => other.to_string(),
    }
}

/// An FRF file as `identify`, `plot` and `convert` see it.
pub struct InputFrf {
    /// The file, its quantity set by `--quantity` when given.
    pub file: era_io::csv::FrfFile,
    /// Format found.
    pub format: FrfFormat,
    /// Where the quantity came from, and the layout found: for the summary line.
    pub note: String,
}

/// Reads an FRF file in any format, told apart by content (the extension is a hint).
/// `--quantity` overrides the file's tag; with neither, acceleration is assumed.
pub fn read_frf(
    path: &std::path::Path,
    quantity: Option<QuantityArg>,
    outputs: Option<usize>,
) -> anyhow::Result<InputFrf> {
    let bytes =
        era_io::input::read_input(path).with_context(|| format!("reading {}", path.display()))?;
    read_frf_bytes(&bytes, path, quantity, outputs)
}

/// [`read_frf`] on the bytes of a file already read once (`era info` looks at them
/// twice); `path` names them in messages.
pub fn read_frf_bytes(
    bytes: &[u8],
    path: &std::path::Path,
    quantity: Option<QuantityArg>,
    outputs: Option<usize>,
) -> anyhow::Result<InputFrf> {
    let opts = ReadOptions {
        default_quantity: Quantity::Acceleration,
        outputs,
    };
    let (mut file, format) = parse_frf_bytes(bytes, path, &opts)
        .with_context(|| format!("reading {}", path.display()))?;
    let layout = file
        .metadata
        .get("layout")
        .map(|l| format!(" [{l}]"))
        .unwrap_or_else(|| format!(" [{}]", format.name()));
    let note = match quantity {
        Some(q) => {
            file.frf = file.frf.with_quantity(q.into());
            file.quantity_given = true;
            format!(" (from --quantity){layout}")
        }
        None if file.quantity_given => layout,
        None => format!(" (assumed: the file does not say; set --quantity){layout}"),
    };
    Ok(InputFrf { file, format, note })
}

/// `8 outputs x 8 inputs, 801 lines, 0 .. 20 Hz at 0.025 Hz, acceleration`.
pub fn shape_line(frf: &era::FrfData) -> String {
    format!(
        "{} outputs x {} inputs, {} lines, 0 .. {} Hz at {} Hz, {}",
        frf.outputs(),
        frf.inputs(),
        frf.lines(),
        frf.frequency_hz()[frf.lines() - 1],
        frf.spacing_hz(),
        frf.quantity()
    )
}

/// The channel table and the notes of a file, as lines for the human summary.
pub fn describe_input(input: &InputFrf) -> String {
    let mut text = String::new();
    if let Some(table) = &input.file.channels {
        text.push_str("  channels:\n");
        for line in table.describe() {
            text.push_str(&format!("    {line}\n"));
        }
    }
    if let Some(notes) = input.file.metadata.get("notes") {
        for n in notes.split(" | ") {
            text.push_str(&format!("  note: {n}\n"));
        }
    }
    text
}

/// Creates `--out DIR` and opens the run's [`OutputSet`] there (a private staging
/// folder), before any long work: a folder that cannot take files is refused now.
pub fn prepare_out_dir(dir: &Path) -> anyhow::Result<OutputSet> {
    std::fs::create_dir_all(dir).map_err(|e| {
        crate::UsageError(format!(
            "--out {}: cannot create the folder: {e}",
            dir.display()
        ))
    })?;
    OutputSet::new(dir).map_err(|e| {
        crate::UsageError(format!("--out {}: cannot write there: {e}", dir.display())).into()
    })
}

/// Stages the output `name` of `set` and runs `write` on its staged path; an error
/// names the output's final place.
pub fn write_output(
    set: &mut OutputSet,
    name: impl AsRef<Path>,
    write: impl FnOnce(&Path) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let name = name.as_ref();
    let staged = set.stage(name)?;
    write(&staged).with_context(|| format!("writing {}", set.target(name).display()))
}

/// The file name of an output file given on the command line, for [`OutputSet::stage`].
pub fn output_name<'a>(flag: &str, path: &'a Path) -> anyhow::Result<&'a std::ffi::OsStr> {
    path.file_name().ok_or_else(|| {
        crate::UsageError(format!("{flag} {}: not a file name", path.display())).into()
    })
}

pub fn run(a: &IdentifyArgs) -> anyhow::Result<()> {
    let human = Human::new(&a.common);
    let opts = options(a)?;
    if !a.refine && crate::refine::any_given(&a.refine_fit) {
        return crate::usage(
            "--residuals, --reciprocal, --weighting and --max-iterations set the refinement: add --refine",
        );
    }
    let refine_options = crate::refine::options(&a.refine_fit)?;
    let mut outputs = match &a.out {
        Some(dir) => Some(prepare_out_dir(dir)?),
        None => None,
    };
    let mut frf_outputs = match &a.save_frf {
        Some(path) if a.from_time => Some(crate::frf::prepare_estimate(path, false)?),
        _ => None,
    };
    let clock = Instant::now();
    let mut estimate_s = None;
    let input = if a.from_time {
        let inputs = a.inputs.as_deref().unwrap_or_default();
        let Some(outputs) = a.outputs.as_deref() else {
            return crate::usage("--from-time needs --outputs CHANNELS (e.g. --outputs 3-30)");
        };
        let quantity = a.quantity.unwrap_or(QuantityArg::Acceleration);
        let found = crate::frf::estimate_from_time(
            std::slice::from_ref(&a.file),
            inputs,
            outputs,
            &a.welch,
            quantity,
            &a.common,
        )?;
        human.print(&format!(
            "era identify --from-time {}\n{}",
            a.file.display(),
            found.summary
        ));
        if let (Some(path), Some(set)) = (&a.save_frf, frf_outputs.take()) {
            let coherence = crate::frf::write_estimate(set, path, &found, false)?;
            human.print(&format!(
                "  wrote {} and {}\n",
                path.display(),
                coherence.display()
            ));
        }
        estimate_s = Some(found.timings.1);
        found.input
    } else {
        let outputs = match a.outputs.as_deref() {
            None => None,
            Some(text) => Some(text.trim().parse::<usize>().map_err(|_| {
                crate::UsageError(format!(
                    "--outputs {text}: expected the number of outputs of a MAT FRF matrix (channel lists apply with --from-time)"
                ))
            })?),
        };
        let input = read_frf(&a.file, a.quantity, outputs)?;
        human.print(&format!("era identify {}\n", a.file.display()));
        input
    };
    let read_s = clock.elapsed().as_secs_f64() - estimate_s.unwrap_or(0.0);
    let frf = &input.file.frf;
    if a.refine {
        crate::refine::check_shape(&refine_options, frf)?;
    }
    human.print(&format!("  {}{}\n", shape_line(frf), input.note));
    human.print(&describe_input(&input));
    let auto = a.states == StatesArg::Auto;
    let echo = parameter_echo_states(
        &opts,
        auto.then_some("auto (from the stabilization diagram)"),
    );
    human.print(&echo);

    let scan_options = ScanOptions {
        orders: scan_orders(a)?,
        ..ScanOptions::default()
    };
    let spinner = crate::progress::spinner(&a.common);
    let mut on_stage = |stage: era::Stage| spinner.set_message(stage.name());
    let mut on_order = |done: usize, total: usize| {
        spinner.set_message(format!("stabilization: order {done} of {total}"));
    };
    let found = if auto {
        identify_auto(frf, &opts, &scan_options, &mut on_stage, &mut on_order)
    } else if scan_options.orders.is_some() {
        identify_with_scan(frf, &opts, &scan_options, &mut on_stage, &mut on_order)
    } else {
        identify_observed(frf, &opts, &mut on_stage)
    }
    .map_err(|e| match e {
        era::EraError::InvalidParameter {
            name,
            value,
            reason,
        } if name == "orders" || (name == "states" && value == "auto") => {
            anyhow::Error::from(crate::UsageError(format!("--{name} {value}: {reason}")))
        }
        other => anyhow::Error::from(other),
    })
    .with_context(|| format!("identifying {}", a.file.display()));
    spinner.finish_and_clear();
    let mut found = found?;
    let states = found.model.states();
    let mut opts = opts;
    if auto {
        opts.states = states;
    }
    if a.refine {
        let era_fit = &found.fit;
        human.print(&format!(
            "\nERA model: {} states, {} modes; fit collocated {}, non-collocated {}\n",
            states,
            found.modal.modes.len(),
            era_fit
                .collocated_mean_relative_error
                .map_or("-".into(), |v| format!("{v:.3e}")),
            era_fit
                .noncollocated_mean_relative_error
                .map_or("-".into(), |v| format!("{v:.3e}"))
        ));
        found = crate::refine::refine_found(found, frf, &refine_options, &a.common)
            .with_context(|| format!("refining the model of {}", a.file.display()))?;
        human.print(&crate::refine::summary(&found));
    }
    human.print(&identification_summary(&found, states));
    human.print(&pair_fit_table(&found.fit, frf.outputs(), frf.inputs()));
    if let Some(st) = &found.stabilization {
        human.print(&stabilization_summary(st));
    }

    let mut timings = timings_map(&found.timings);
    timings.insert("read".into(), read_s);
    if let Some(t) = estimate_s {
        timings.insert("frf_estimate".into(), t);
    }
    let mut params = parameters(&opts);
    if auto {
        params.insert("states".into(), serde_json::json!("auto"));
        params.insert("model_states".into(), serde_json::json!(states));
    }
    if let Some(st) = &found.stabilization {
        params.insert("orders".into(), serde_json::json!(st.range.to_string()));
    }
    if a.refine {
        timings.insert("refine".into(), found.timings.refine);
        params.insert("refine".into(), serde_json::json!(true));
        params.insert(
            "residuals".into(),
            serde_json::json!(format!("{:?}", refine_options.residuals).to_lowercase()),
        );
        params.insert(
            "reciprocal".into(),
            serde_json::json!(refine_options.reciprocal),
        );
        params.insert(
            "weighting".into(),
            serde_json::json!(match refine_options.weighting {
                era::refine::Weighting::Uniform => "uniform",
                _ => "pair-noise",
            }),
        );
        params.insert(
            "max_iterations".into(),
            serde_json::json!(refine_options.max_iterations),
        );
        params.insert(
            "model_states".into(),
            serde_json::json!(found.model.states()),
        );
    }
    let mut model = ModelJson::from_identification(&found, params, None);
    let fit = FitJson::from_report(&found.fit);
    if let Some(set) = outputs.as_mut() {
        let clock = Instant::now();
        let title = format!("era identify {}", a.file.display());
        write_identification(
            set,
            &found,
            &model,
            &fit,
            input.file.channels.as_ref(),
            &title,
            &echo,
            states,
            &a.common,
        )?;
        timings.insert("write".into(), clock.elapsed().as_secs_f64());
    }
    if a.common.timings {
        human.print(&timings_table(&timings));
        human.print(&svd_path_line(&found.realization));
        model.timings_s = Some(timings);
        if let Some(set) = outputs.as_mut() {
            write_output(set, "model.json", |p| Ok(model.write(p)?))?;
        }
    }
    // Every output is in the staging folder: they all take their place now, or none.
    if let (Some(dir), Some(set)) = (&a.out, outputs) {
        set.commit()?;
        human.print(&format!(
            "\nwrote {0}/model.json, {0}/model.mat, {0}/modes.uff, {0}/model_frf.uff, {0}/fit.json, {0}/report.html and figures (singular_values, grid, pairs/)\n",
            dir.display()
        ));
    }
    if a.common.json {
        print_json(&model)?;
    }
    Ok(())
}

/// Every output of one identification into `set`: model.json, fit.json, model.mat,
/// model_frf.uff (the model's FRFs on the measurement's lines, after the same
/// integrations), modes.uff, the figures and report.html. All of them show
/// `found.model`, refined or not, and use the compared data kept in `found`.
#[allow(clippy::too_many_arguments)]
pub fn write_identification(
    set: &mut OutputSet,
    found: &era::Identification,
    model: &ModelJson,
    fit: &FitJson,
    channels: Option<&era_io::uff::ChannelTable>,
    title: &str,
    echo: &str,
    states: usize,
    common: &crate::args::CommonArgs,
) -> anyhow::Result<()> {
    write_output(set, "model.json", |p| Ok(model.write(p)?))?;
    write_output(set, "fit.json", |p| Ok(fit.write(p)?))?;
    write_output(set, "model.mat", |p| {
        Ok(era_io::mat::write_model_mat(p, &found.model, &found.modal)?)
    })?;
    let synthesised = found.model_frf()?;
    write_output(set, "model_frf.uff", |p| {
        Ok(era_io::uff::write_uff58(
            p,
            &synthesised,
            channels,
            (None, None),
            era_io::uff::UffWriteOptions {
                binary: true,
                single: false,
            },
        )?)
    })?;
    write_output(set, "modes.uff", |p| {
        Ok(era_io::uff::write_uff55(
            p,
            &found.modal,
            channels,
            // The shapes are of the integrated quantity, as the model is.
            found.processed.quantity(),
        )?)
    })?;
    let q = found.measured.outputs() * found.measured.inputs();
    let bar = crate::progress::bar(common, q as u64, "figures");
    crate::figures::write_all(set, Path::new(""), title, echo, found, states, &bar)?;
    bar.finish_and_clear();
    Ok(())
}

/// Per-pair relative fit error as an outputs × inputs grid (up to 64 pairs).
fn pair_fit_table(fit: &era::response::FitReport, q: usize, p: usize) -> String {
    use std::fmt::Write as _;
    if q * p > 64 {
        return format!("  per-pair fit: {} pairs, see fit.json (--out)\n", q * p);
    }
    let mut s = String::from(
        "relative fit error per pair (rows: outputs, columns: inputs; * collocated)\n",
    );
    let _ = write!(s, "{:>8}", "");
    for j in 1..=p {
        let _ = write!(s, " {:>10}", format!("in {j}"));
    }
    s.push('\n');
    for i in 0..q {
        let _ = write!(s, "{:>8}", format!("out {}", i + 1));
        for j in 0..p {
            match fit.pairs.iter().find(|f| f.output == i && f.input == j) {
                Some(f) => {
                    let mark = if f.collocated { "*" } else { " " };
                    let _ = write!(s, " {:>9.3e}{mark}", f.relative_error);
                }
                None => {
                    let _ = write!(s, " {:>10}", "-");
                }
            }
        }
        s.push('\n');
    }
    s
}
