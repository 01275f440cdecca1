//! `era simulate experiment`: the thesis's FRF test (§4.5) simulated in the time domain
//! (`era::sim::experiment`), written as an FRF file with its coherence beside it.

use crate::config;
use crate::output::experiment::{
    motion_shares, prepare, summary_json, summary_line, write_frfs, write_time_histories,
};
use crate::output::report::{finish_output, Human};
use era::sim::experiment::{run_experiment, Compensation, Drive};
use std::time::Instant;

pub fn run(a: &config::Experiment) -> anyhow::Result<()> {
    let settings = a.settings;
    let human = Human::new(&settings);
    // Refuse bad outputs before the work.
    let sets = prepare(a)?;
    let spec = crate::config::experiment::spec(a)?;
    let runs = match spec.drive {
        Drive::OneAtATime => spec.actuators.len(),
        Drive::Simultaneous => 1,
    };
    let clock = Instant::now();
    let bar = crate::output::progress::bar(&settings, runs as u64, "simulating runs");
    let found = run_experiment(&spec, a.time_histories.is_some(), &|done| {
        bar.set_position(done as u64)
    })?;
    bar.finish_and_clear();
    let simulate_s = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    write_frfs(a, sets.frf, sets.exact, &found, &spec)?;
    let geometry = crate::output::geometry::beside(&a.out);
    crate::output::geometry::write_dta_like(&human, &geometry, found.frf.outputs())?;
    let dead_zone = spec
        .compensation
        .as_ref()
        .map_or(Compensation::thesis().dead_zone, |c| c.dead_zone);
    let shares = a
        .time_histories
        .as_ref()
        .map(|dir| (dir, motion_shares(&found, dead_zone)));
    if let Some(s) = sets.time_histories {
        write_time_histories(s, &found, spec.analyzer_rate_hz, dead_zone)?;
    }
    let write_s = clock.elapsed().as_secs_f64();
    human.print(&summary_line(a, &found, &spec, runs));
    if let Some((dir, (stuck, above))) = shares {
        human.print(&format!(
            "  excited actuators: stuck {:.1} % of the time, faster than the {dead_zone} in/s dead zone {:.1} % (time histories and figures in {})\n",
            100.0 * stuck,
            100.0 * above,
            dir.display()
        ));
    }
    let summary = summary_json(a, &found, &spec, &geometry, shares.map(|(_, s)| s));
    finish_output(
        &human,
        &settings,
        summary,
        &[("simulate", simulate_s), ("write", write_s)],
    )
}
