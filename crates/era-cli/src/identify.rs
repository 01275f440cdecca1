//! `era identify FILE`: the pipeline of docs/design.md §1 on an FRF file.

use crate::args::{DirectTermArg, IdentifyArgs, QuantityArg, SvdArg, TimeDomainArg};
use crate::report::{
    identification_summary, parameter_echo, parameters, print_json, svd_path_line, timings_table,
    Human,
};
use crate::usage;
use anyhow::Context;
use era::identify::{identify_observed, EraOptions, ModelDomain};
use era::params::Naming;
use era::realize::{DirectTerm, SvdPath};
use era::Quantity;
use era_io::atomic::OutputSet;
use era_io::format::{parse_frf_bytes, FrfFormat, ReadOptions};
use era_io::model_json::{timings_map, FitJson, ModelJson};
use std::path::Path;
use std::time::Instant;

/// The most `--orders` one run identifies.
const MAX_ORDERS: usize = 64;

/// Options from flags, with the checks clap cannot do (those of the library call are
/// [`EraOptions::check`], shared with the Python package; `--orders` is the CLI's own).
pub fn options(a: &IdentifyArgs) -> anyhow::Result<EraOptions> {
    let opts = EraOptions {
        states: a.states,
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
    // is read or allocated (the core checks them again for library users).
    opts.check(Naming::Flag)?;
    use era::limits::{SAMPLES, STATES};
    if a.orders.len() > MAX_ORDERS {
        return usage(format!(
            "--orders: {} orders given, at most {MAX_ORDERS} (each is a whole identification)",
            a.orders.len()
        ));
    }
    for &order in &a.orders {
        if order == 0 {
            return usage("--orders: an order of 0 states is not a model");
        }
        STATES.check(format!("--orders {order}"), order as u64)?;
        SAMPLES.check_product(
            format!("--orders {order} x --hankel-factor (Markov samples)"),
            &[order as u64, a.hankel_factor as u64],
        )?;
    }
    Ok(opts)
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
    human.print(&format!("  {}{}\n", shape_line(frf), input.note));
    human.print(&describe_input(&input));
    human.print(&parameter_echo(&opts));

    let spinner = crate::progress::spinner(&a.common);
    let found = identify_observed(frf, &opts, &mut |stage| spinner.set_message(stage.name()))
        .with_context(|| format!("identifying {}", a.file.display()));
    spinner.finish_and_clear();
    let found = found?;
    human.print(&identification_summary(&found, opts.states));
    human.print(&pair_fit_table(&found.fit, frf.outputs(), frf.inputs()));
    let stability = if a.orders.is_empty() {
        None
    } else {
        let (text, value) = stability_check(frf, &opts, &a.orders, &found)?;
        human.print(&text);
        Some(value)
    };

    let mut timings = timings_map(&found.timings);
    timings.insert("read".into(), read_s);
    if let Some(t) = estimate_s {
        timings.insert("frf_estimate".into(), t);
    }
    let mut model = ModelJson::from_identification(&found, parameters(&opts), None);
    if let Some(v) = stability {
        model.stability = Some(v);
    }
    let fit = FitJson::from_report(&found.fit);
    if let Some(set) = outputs.as_mut() {
        let clock = Instant::now();
        write_output(set, "model.json", |p| Ok(model.write(p)?))?;
        write_output(set, "fit.json", |p| Ok(fit.write(p)?))?;
        write_output(set, "model.mat", |p| {
            Ok(era_io::mat::write_model_mat(p, &found.model, &found.modal)?)
        })?;
        // The model's synthesised FRFs on the measurement's lines, after the same
        // integrations, for tools that overlay them on the measurement.
        let processed = &found.processed;
        let synthesised = era::FrfData::new(
            processed.frequency_hz().to_vec(),
            processed.outputs(),
            processed.inputs(),
            found.model_response.clone(),
            processed.quantity(),
        )?;
        write_output(set, "model_frf.uff", |p| {
            Ok(era_io::uff::write_uff58(
                p,
                &synthesised,
                input.file.channels.as_ref(),
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
                input.file.channels.as_ref(),
                // The shapes are of the integrated quantity, as the model is.
                found.processed.quantity(),
            )?)
        })?;
        let title = format!("era identify {}", a.file.display());
        let bar = crate::progress::bar(&a.common, (frf.outputs() * frf.inputs()) as u64, "figures");
        crate::figures::write_all(
            set,
            Path::new(""),
            &title,
            &parameter_echo(&opts),
            &found,
            opts.zero_lines,
            opts.states,
            &bar,
        )?;
        bar.finish_and_clear();
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

/// Identifies at the other `orders` and matches the modes (era::stability).
fn stability_check(
    frf: &era::FrfData,
    opts: &EraOptions,
    orders: &[usize],
    found: &era::Identification,
) -> anyhow::Result<(String, serde_json::Value)> {
    use era::stability::{stability, StabilityCriteria};
    use std::fmt::Write as _;
    let mut others = Vec::new();
    for &order in orders {
        if order == 0 {
            return usage("--orders: an order of 0 states is not a model");
        }
        let mut o = opts.clone();
        o.states = order;
        let other =
            era::identify(frf, &o).with_context(|| format!("identifying at --orders {order}"))?;
        others.push(other.modal.modes);
    }
    let lists: Vec<&[era::modal::Mode]> = others.iter().map(Vec::as_slice).collect();
    let criteria = StabilityCriteria::default();
    let table = stability(&found.modal.modes, &lists, &criteria);
    let mut s = format!(
        "\nstability of the {} modes of the {}-state model across orders {} (0.5 % in f, 30 % in zeta, MAC >= 0.9, zeta < 10 %)\n",
        table.len(),
        opts.states,
        orders.iter().map(ToString::to_string).collect::<Vec<_>>().join(", ")
    );
    let _ = write!(s, "{:>5} {:>12} {:>9}", "mode", "f (Hz)", "zeta (%)");
    for o in orders {
        let _ = write!(s, " {:>11}", format!("{o} states"));
    }
    let _ = writeln!(s, "  stable");
    let mut rows = Vec::new();
    for t in &table {
        let m = &found.modal.modes[t.mode];
        let _ = write!(
            s,
            "{:>5} {:>12.4} {:>9.4}",
            t.mode + 1,
            m.frequency_hz,
            100.0 * m.damping_ratio
        );
        for (k, hit) in t.matches.iter().enumerate() {
            match hit {
                Some((j, mac)) => {
                    let f = others[k][*j].frequency_hz;
                    let _ = write!(s, " {:>11}", format!("{f:.2} {mac:.2}"));
                }
                None => {
                    let _ = write!(s, " {:>11}", "-");
                }
            }
        }
        let _ = writeln!(s, "  {}", if t.stable { "yes" } else { "" });
        rows.push(serde_json::json!({
            "mode": t.mode + 1, "frequency_hz": m.frequency_hz, "damping_ratio": m.damping_ratio,
            "stable": t.stable,
            "matches": t.matches.iter().enumerate().map(|(k, h)| serde_json::json!({
                "states": orders[k],
                "frequency_hz": h.map(|(j, _)| others[k][j].frequency_hz),
                "mac": h.map(|(_, mac)| mac),
            })).collect::<Vec<_>>(),
        }));
    }
    let stable = table.iter().filter(|t| t.stable).count();
    let _ = writeln!(
        s,
        "{stable} of {} modes stable (columns: the matching mode's f in Hz and its MAC)",
        table.len()
    );
    Ok((
        s,
        serde_json::json!({"orders": orders, "modes": rows, "stable": stable}),
    ))
}
