//! `era identify FILE`: the pipeline of DESIGN.md §1 on an FRF file.

use crate::args::{DirectTermArg, IdentifyArgs, QuantityArg, SvdArg, TimeDomainArg};
use crate::report::{
    identification_summary, parameter_echo, parameters, print_json, svd_path_line, timings_table,
    Human,
};
use crate::usage;
use anyhow::Context;
use era::identify::{identify_observed, EraOptions, ModelDomain};
use era::realize::{DirectTerm, SvdPath};
use era::Quantity;
use era_io::csv::read_frf_csv;
use era_io::model_json::{timings_map, FitJson, ModelJson};
use std::path::Path;
use std::time::Instant;

/// Options from flags, with the checks clap cannot do.
pub fn options(a: &IdentifyArgs) -> anyhow::Result<EraOptions> {
    if a.states == 0 {
        return usage("--states 0: the model needs at least one state");
    }
    if a.hankel_factor == 0 {
        return usage("--hankel-factor 0: must be at least 1");
    }
    let lowpass = match a.lowpass_hz {
        Some(hz) if !(hz.is_finite() && hz > 0.0) => {
            return usage(format!("--lowpass-hz {hz}: must be a positive frequency"))
        }
        Some(hz) => Some((a.lowpass_order, hz)),
        None => None,
    };
    Ok(EraOptions {
        states: a.states,
        hankel_factor: a.hankel_factor,
        integrations: a.integrations,
        lowpass,
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
    })
}

/// Reads an FRF file for `identify` and `plot`: MAT v5 when the file starts like one,
/// CSV otherwise. `--quantity` overrides the file's tag; with neither, acceleration is
/// assumed. The note says which (and, for MAT, the layout found).
pub fn read_frf(
    path: &std::path::Path,
    quantity: Option<QuantityArg>,
    outputs: Option<usize>,
) -> anyhow::Result<(era::FrfData, String)> {
    let file = if era_io::mat::looks_like_mat(path) {
        era_io::mat::read_frf_mat(path, outputs, Quantity::Acceleration)
    } else {
        read_frf_csv(path, Quantity::Acceleration)
    }
    .with_context(|| format!("reading {}", path.display()))?;
    let layout = file
        .metadata
        .get("layout")
        .map(|l| format!(" [{l}]"))
        .unwrap_or_default();
    Ok(match quantity {
        Some(q) => (
            file.frf.with_quantity(q.into()),
            format!(" (from --quantity){layout}"),
        ),
        None if file.quantity_given => (file.frf, layout),
        None => (
            file.frf,
            format!(" (assumed: the file does not say; set --quantity){layout}"),
        ),
    })
}

/// Creates `--out DIR` and checks that it takes files, before any long work.
pub fn prepare_out_dir(dir: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| {
        crate::UsageError(format!(
            "--out {}: cannot create the folder: {e}",
            dir.display()
        ))
    })?;
    let probe = dir.join(format!(".era-probe-{}", std::process::id()));
    std::fs::write(&probe, b"").map_err(|e| {
        crate::UsageError(format!("--out {}: cannot write there: {e}", dir.display()))
    })?;
    let _ = std::fs::remove_file(probe);
    Ok(())
}

pub fn run(a: &IdentifyArgs) -> anyhow::Result<()> {
    let human = Human::new(&a.common);
    let opts = options(a)?;
    if let Some(dir) = &a.out {
        prepare_out_dir(dir)?;
    }
    let clock = Instant::now();
    let (frf, quantity_note) = read_frf(&a.file, a.quantity, a.outputs)?;
    let read_s = clock.elapsed().as_secs_f64();
    let last = frf.frequency_hz()[frf.lines() - 1];
    human.print(&format!(
        "era identify {}\n  {} outputs x {} inputs, {} lines, 0 .. {last} Hz at {} Hz, {}{}\n",
        a.file.display(),
        frf.outputs(),
        frf.inputs(),
        frf.lines(),
        frf.spacing_hz(),
        frf.quantity(),
        quantity_note,
    ));
    human.print(&parameter_echo(&opts));

    let spinner = crate::progress::spinner(&a.common);
    let found = identify_observed(&frf, &opts, &mut |stage| spinner.set_message(stage.name()))
        .with_context(|| format!("identifying {}", a.file.display()));
    spinner.finish_and_clear();
    let found = found?;
    human.print(&identification_summary(&found, opts.states));

    let mut timings = timings_map(&found.timings);
    timings.insert("read".into(), read_s);
    let mut model = ModelJson::from_identification(&found, parameters(&opts), None);
    let fit = FitJson::from_report(&found.fit);
    if let Some(dir) = &a.out {
        let clock = Instant::now();
        model.write(&dir.join("model.json"))?;
        fit.write(&dir.join("fit.json"))?;
        era_io::mat::write_model_mat(&dir.join("model.mat"), &found.model, &found.modal)?;
        let title = format!("era identify {}", a.file.display());
        let bar = crate::progress::bar(&a.common, (frf.outputs() * frf.inputs()) as u64, "figures");
        crate::figures::write_all(
            dir,
            &title,
            &parameter_echo(&opts),
            &found,
            opts.zero_lines,
            opts.states,
            &bar,
        )?;
        bar.finish_and_clear();
        timings.insert("write".into(), clock.elapsed().as_secs_f64());
        human.print(&format!(
            "\nwrote {0}/model.json, {0}/model.mat, {0}/fit.json, {0}/report.html and figures (singular_values, grid, pairs/)\n",
            dir.display()
        ));
    }
    if a.common.timings {
        human.print(&timings_table(&timings));
        human.print(&svd_path_line(&found.realization));
        model.timings_s = Some(timings);
        if let Some(dir) = &a.out {
            model.write(&dir.join("model.json"))?;
        }
    }
    if a.common.json {
        print_json(&model)?;
    }
    Ok(())
}
