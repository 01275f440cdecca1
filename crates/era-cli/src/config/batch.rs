//! `era batch`'s settings ([`Batch`]), and its records checked before any work: the
//! shard's records of the manifest, each distinct list of flags parsed as its verb's,
//! and the fingerprint that says whether an earlier run's result still holds.

use crate::config::Settings;
use crate::error::UsageError;
use crate::input::manifest::{Manifest, Record};
use std::path::PathBuf;

/// `era batch`'s settings.
#[derive(Debug, Clone)]
pub struct Batch {
    /// The manifest.
    pub manifest: PathBuf,
    /// The tables' folder.
    pub out: PathBuf,
    /// `(I, N)`: every N-th record from the I-th (1-based).
    pub shard: Option<(usize, usize)>,
    /// Skip the records an earlier run finished.
    pub resume: bool,
    /// Records side by side.
    pub jobs: usize,
    /// Each record's model files in `out/records/<id>/`.
    pub keep_models: bool,
    /// Accept record files outside the manifest's folder.
    pub allow_outside: bool,
    /// The output switches.
    pub settings: Settings,
}

impl From<&crate::args::BatchArgs> for Batch {
    fn from(a: &crate::args::BatchArgs) -> Self {
        Batch {
            manifest: a.manifest.clone(),
            out: a.out.clone(),
            shard: a.shard,
            resume: a.resume,
            jobs: a.jobs,
            keep_models: a.keep_models,
            allow_outside: a.allow_outside,
            settings: (&a.common).into(),
        }
    }
}

/// A record to run.
pub struct Planned {
    /// The record.
    pub record: Record,
    /// What its result depends on ([`fingerprint`]).
    pub fingerprint: String,
}

/// A record's flags parsed as its verb's (with the files and, with `--keep-models`, its
/// model folder) and their values checked: what the verb's own run would refuse.
pub fn parse(verb: &str, r: &Record, a: &Batch) -> Result<crate::args::Cli, String> {
    let mut argv: Vec<std::ffi::OsString> = vec!["era".into(), verb.into()];
    argv.extend(r.files.iter().map(|f| f.clone().into_os_string()));
    argv.extend(r.args.iter().map(Into::into));
    if a.keep_models {
        argv.push("--out".into());
        argv.push(a.out.join("records").join(&r.id).into_os_string());
        if !r.args.iter().any(|x| x == "--no-figures") {
            argv.push("--no-figures".into());
        }
    }
    let cli = <crate::args::Cli as clap::Parser>::try_parse_from(&argv).map_err(|e| {
        let text = e.render().to_string();
        let first = text.lines().next().unwrap_or_default();
        first.strip_prefix("error: ").unwrap_or(first).to_string()
    })?;
    let checked = match &cli.command {
        crate::args::Command::Oma(x) => crate::config::Oma::new(x).map(drop),
        crate::args::Command::Identify(x) => crate::config::Identify::new(x).map(drop),
        _ => unreachable!("the manifest's verb is identify or oma"),
    };
    checked.map_err(|e| crate::message(&e))?;
    Ok(cli)
}

/// The verb, the flags and each file's path, size and modification time: what a
/// record's result depends on.
pub fn fingerprint(verb: &str, args: &[String], files: &[PathBuf]) -> String {
    let mut f = format!("{verb} {}", serde_json::to_string(args).unwrap_or_default());
    for file in files {
        let (len, modified) = std::fs::metadata(file)
            .map(|m| {
                let t = m
                    .modified()
                    .ok()
                    .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
                    .map_or(0, |d| d.as_nanos());
                (m.len(), t)
            })
            .unwrap_or_default();
        f.push_str(&format!(" | {} {len} {modified}", file.display()));
    }
    f
}

/// The records of the shard (`--shard I/N`: every Nth from the Ith), each distinct list
/// of flags parsed as its verb's before any work (a problem names the manifest's line),
/// each with its fingerprint.
pub fn plan(a: &Batch, manifest: &Manifest) -> anyhow::Result<Vec<Planned>> {
    let chosen: Vec<&Record> = manifest
        .records
        .iter()
        .enumerate()
        .filter(|(k, _)| a.shard.is_none_or(|(i, n)| k % n == i - 1))
        .map(|(_, r)| r)
        .collect();
    let mut checked = std::collections::HashSet::new();
    for r in &chosen {
        if checked.insert(&r.args) {
            parse(&manifest.verb, r, a).map_err(|m| {
                UsageError(format!(
                    "{}: line {}: record {:?}: args of era {}: {m}",
                    manifest.path.display(),
                    r.args_line,
                    r.id,
                    manifest.verb
                ))
            })?;
        }
    }
    Ok(chosen
        .iter()
        .map(|r| Planned {
            record: (*r).clone(),
            fingerprint: fingerprint(&manifest.verb, &r.args, &r.files),
        })
        .collect())
}
