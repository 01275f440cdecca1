//! `era track DIR... --out DIR2`: the modes of a fleet followed over time. The shards
//! `era batch` wrote are read by [`crate::input::fleet`], [`era::modal::track::track`] clusters the
//! modes into tracks, and [`crate::output::track`] writes the table, the JSON, the
//! figures and the report.

use crate::config::Track;
use crate::input::fleet::read_fleet;
use crate::output::prepare_out_dir;
use crate::output::report::{print_json, Human};
use crate::output::track::{track_table, tracks_json, write_track, TrackRun};
use anyhow::Context as _;
use era::modal::track::track;

/// `era track`.
pub fn run(a: &Track) -> anyhow::Result<()> {
    let settings = a.settings;
    let human = Human::new(&settings);
    let mut set = prepare_out_dir(&a.out)?;
    let fleet = read_fleet(&a.dirs)?;
    let tracking = track(&fleet.records, &a.options).context("tracking the modes")?;
    let run = TrackRun {
        dirs: &a.dirs,
        fleet: &fleet,
        tracking: &tracking,
        options: &a.options,
    };
    let dirs = crate::input::time::joined(&a.dirs, " ");
    human.print(&format!("era track {dirs}\n"));
    human.print(&run.summary());
    human.print(&track_table(&run));
    let json = tracks_json(&run);
    write_track(&mut set, &run, &json)?;
    set.commit()?;
    human.print(&format!(
        "\nwrote {0}/tracks.parquet, {0}/tracks.json, {0}/report.html and figures (frequency, damping)\n",
        a.out.display()
    ));
    if settings.json {
        print_json(&json)?;
    }
    Ok(())
}
