//! `era batch MANIFEST --out DIR`.

use super::common::CommonArgs;
use clap::Args;
use std::path::PathBuf;

/// What `era batch --help` shows before the flags.
const BATCH_EXAMPLES: &str = "\
Examples:
  era batch fleet.toml --out results
      every record of the manifest, one after another; results/modes.parquet (one row
      per record and mode) and results/records.jsonl (one line per record)
  era batch fleet.toml --out results --jobs 2
      two records side by side, one thread each
  era batch fleet.toml --out part-3 --shard 3/8 --resume
      every 8th record starting at the 3rd (a Slurm array task), skipping those an
      earlier run of this shard finished

A manifest:
  verb = \"oma\"                          # or \"identify\"
  args = [\"--outputs\", \"1-8\"]           # the verb's flags, without the files
  [[record]]
  id = \"r0001\"
  path = \"records/r0001.csv\"            # relative to the manifest; a list for several files
  time = 2026-05-01T10:00:00Z           # optional, RFC 3339";

#[derive(Debug, Args)]
#[command(before_help = BATCH_EXAMPLES)]
pub struct BatchArgs {
    /// The manifest (TOML): the verb, its flags and the records (see the examples).
    #[arg(value_name = "MANIFEST")]
    pub manifest: PathBuf,
    /// Folder for modes.parquet and records.jsonl (created if missing). A batch's
    /// progress is kept in DIR/.era-batch, for --resume.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Only every N-th record, starting at the I-th (1-based): I/N, for the tasks of a
    /// job array. Each shard writes its own --out folder.
    #[arg(long, value_name = "I/N", value_parser = parse_shard)]
    pub shard: Option<(usize, usize)>,
    /// Skip the records an earlier run into --out finished (with the same verb, flags
    /// and files); records that failed are tried again.
    #[arg(long)]
    pub resume: bool,
    /// Records processed side by side, one thread each.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub jobs: usize,
    /// Each record's model files (no figures) in DIR/records/<id>/.
    #[arg(long)]
    pub keep_models: bool,
    /// Accept record paths outside the manifest's folder (through .. or a link).
    #[arg(long)]
    pub allow_outside: bool,
    #[command(flatten)]
    pub common: CommonArgs,
}

/// The most shards a batch may be cut into.
pub const MAX_SHARDS: usize = 1_000_000;

/// `I/N` with 1 ≤ I ≤ N.
pub fn parse_shard(text: &str) -> Result<(usize, usize), String> {
    let bad = || format!("{text:?}: give I/N with 1 <= I <= N, such as 3/8");
    let (i, n) = text.split_once('/').ok_or_else(bad)?;
    let i: usize = i.trim().parse().map_err(|_| bad())?;
    let n: usize = n.trim().parse().map_err(|_| bad())?;
    if i == 0 || i > n || n > MAX_SHARDS {
        return Err(bad());
    }
    Ok((i, n))
}
