//! `era track`'s flags checked into its settings and the core's `TrackOptions`.

use crate::config::Settings;
use std::path::PathBuf;
/// `era track`: the folders to read, where to write, and the core's
/// [`era::modal::track::TrackOptions`].
#[derive(Debug, Clone)]
pub struct Track {
    /// Folders holding a modes.parquet each (shards of one fleet).
    pub dirs: Vec<PathBuf>,
    /// Folder for the outputs.
    pub out: PathBuf,
    /// The core's options.
    pub options: era::modal::track::TrackOptions,
    /// The output switches.
    pub settings: Settings,
}

impl Track {
    /// The settings of `era track`'s flags, each checked under its flag's name: the
    /// tolerance a fraction, the MAC from 0 to below 1, the minimum records a count of
    /// at least 1 or a fraction in (0, 1].
    pub fn new(a: &crate::args::TrackArgs) -> anyhow::Result<Self> {
        use era::modal::track::{MinRecords, TrackOptions};
        let f = a.frequency_tolerance;
        if !(f.is_finite() && f > 0.0 && f < 1.0) {
            return crate::error::usage(format!(
                "--frequency-tolerance {f}: must be a fraction between 0 and 1 (0.05 is 5 %)"
            ));
        }
        if !(0.0..1.0).contains(&a.mac_min) {
            return crate::error::usage(format!(
                "--mac-min {}: must be from 0 to below 1",
                a.mac_min
            ));
        }
        let text = a.min_records.trim();
        let min_records = if let Ok(n) = text.parse::<usize>() {
            if n == 0 {
                return crate::error::usage(
                    "--min-records 0: must be a count of at least 1 or a fraction such as 0.5",
                );
            }
            MinRecords::Count(n)
        } else {
            match text.parse::<f64>() {
                Ok(v) if v > 0.0 && v <= 1.0 => MinRecords::Fraction(v),
                _ => {
                    return crate::error::usage(format!(
                        "--min-records {text}: must be a count of records (10) or a fraction of them above 0 and at most 1 (0.5)"
                    ))
                }
            }
        };
        let mut options = TrackOptions::default();
        options.all_modes = a.all_modes;
        options.frequency_tolerance = f;
        options.mac_min = a.mac_min;
        options.min_records = min_records;
        Ok(Track {
            dirs: a.dirs.clone(),
            out: a.out.clone(),
            options,
            settings: Settings::from(&a.common),
        })
    }
}
