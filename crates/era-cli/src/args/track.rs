//! `era track DIR... --out DIR2`.

use super::common::CommonArgs;
use clap::Args;
use std::path::PathBuf;

/// What `era track --help` shows before the flags.
const TRACK_EXAMPLES: &str = "\
Examples:
  era track fleet --out tracks
      the physical modes of every record in fleet/modes.parquet (written by era batch)
      followed over time: tracks.parquet, tracks.json, the figures and report.html
  era track shard0 shard1 shard2 --out tracks --min-records 0.9
      three shards of one fleet; a track seen in fewer than 90 % of the records is sparse
  era track fleet --out tracks --all-modes --frequency-tolerance 0.03 --mac-min 0.8
      every mode, physical or not, within 3 % in frequency and a MAC of 0.8";

#[derive(Debug, Args)]
#[command(before_help = TRACK_EXAMPLES)]
pub struct TrackArgs {
    /// Folders written by era batch, each holding a modes.parquet (one row per record
    /// and mode); several folders are shards of one fleet (a record id in two of them
    /// is an error).
    #[arg(required = true, value_name = "DIR")]
    pub dirs: Vec<PathBuf>,
    /// Folder for tracks.parquet, tracks.json, the figures and report.html (created if
    /// missing).
    #[arg(long, value_name = "DIR2")]
    pub out: PathBuf,
    /// Track every mode, not only those the identification called physical.
    #[arg(long)]
    pub all_modes: bool,
    /// A track seen in fewer records than this is flagged sparse (kept in the table):
    /// a count such as 10, or a fraction of the records such as 0.5 (the default).
    #[arg(long, value_name = "N | FRACTION", default_value = "0.5")]
    pub min_records: String,
    /// A mode joins a track only within this fraction of the track's recent mean
    /// frequency (or three of the mode's standard deviations, if wider).
    #[arg(
        long,
        value_name = "F",
        default_value_t = 0.05,
        allow_negative_numbers = true
    )]
    pub frequency_tolerance: f64,
    /// A mode joins a track only when the MAC of its shape with the track's recent one
    /// (on the channels both records have) is at least this.
    #[arg(
        long,
        value_name = "M",
        default_value_t = 0.6,
        allow_negative_numbers = true
    )]
    pub mac_min: f64,
    #[command(flatten)]
    pub common: CommonArgs,
}
