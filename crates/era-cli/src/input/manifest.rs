//! The manifest of `era batch`: a TOML file naming the verb, its flags and the records.
//! Everything is checked before any record is processed, and a problem names the
//! manifest's line: a malformed TOML, an unknown verb or flag, a duplicate or unusable
//! id, a missing file, a path that leaves the manifest's folder.

use crate::error::UsageError;
use serde::Deserialize;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// The verbs a batch runs.
pub const VERBS: [&str; 2] = ["identify", "oma"];

/// The most records a manifest may list (a larger fleet is several manifests: each
/// record costs about 2 kB while the manifest is checked).
pub const MAX_RECORDS: usize = 1_000_000;

/// The largest manifest read: about a million records.
pub const MANIFEST_BYTES: era::params::limits::Limit = era::params::limits::Limit {
    what: "bytes of a batch manifest",
    default: 64 << 20,
    env: "ERA_MAX_MANIFEST_BYTES",
};

/// The longest record id (it names a folder with `--keep-models`).
const MAX_ID: usize = 200;

/// Flags a batch sets itself, refused in `args`.
const OWNED_FLAGS: [(&str, &str); 5] = [
    (
        "--out",
        "the batch writes DIR/records/<id>/ with --keep-models",
    ),
    (
        "--save-frf",
        "each record's files stay in the batch's --out",
    ),
    (
        "--threads",
        "give era batch --jobs; each record runs on one thread",
    ),
    ("--json", "the batch's tables hold the results"),
    ("--help", "run era VERB --help"),
];

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawManifest {
    verb: Spanned<String>,
    #[serde(default)]
    args: Option<Spanned<Vec<String>>>,
    #[serde(default)]
    record: Vec<Spanned<RawRecord>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRecord {
    id: Spanned<String>,
    path: Spanned<Paths>,
    #[serde(default)]
    time: Option<Spanned<toml::Value>>,
    #[serde(default)]
    args: Option<Spanned<Vec<String>>>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum Paths {
    One(String),
    Many(Vec<String>),
}

/// One record of the manifest, checked.
#[derive(Debug, Clone)]
pub struct Record {
    /// Its id (letters, digits and `-_.:+`).
    pub id: String,
    /// Its files, resolved against the manifest's folder.
    pub files: Vec<PathBuf>,
    /// Its start, µs since 1970 UTC.
    pub time_us: Option<i64>,
    /// The verb's flags for this record (the manifest's, or the record's own).
    pub args: Vec<String>,
    /// The manifest line of those flags.
    pub args_line: usize,
}

/// A manifest, checked.
#[derive(Debug, Clone)]
pub struct Manifest {
    /// The manifest file.
    pub path: PathBuf,
    /// `identify` or `oma`.
    pub verb: String,
    /// The records in the manifest's order.
    pub records: Vec<Record>,
}

/// The newlines of a text, to find the line of a byte offset by bisection (a manifest of
/// a million records asks a million times).
struct Lines(Vec<usize>);

impl Lines {
    fn new(text: &str) -> Self {
        Lines(newlines(text.as_bytes()))
    }

    /// The 1-based line of byte `offset`.
    fn of(&self, offset: usize) -> usize {
        self.0.partition_point(|&n| n < offset) + 1
    }
}

fn newlines(bytes: &[u8]) -> Vec<usize> {
    bytes
        .iter()
        .enumerate()
        .filter_map(|(k, &b)| (b == b'\n').then_some(k))
        .collect()
}

/// Reads and checks the manifest at `path`. `allow_outside` accepts record files
/// outside the manifest's folder.
pub fn read(path: &Path, allow_outside: bool) -> anyhow::Result<Manifest> {
    let bytes = era_io::input::read_input_limited(path, MANIFEST_BYTES)?.into_vec();
    MANIFEST_BYTES.check(
        format!("{}: split the manifest", path.display()),
        bytes.len() as u64,
    )?;
    let text = String::from_utf8(bytes).map_err(|e| {
        UsageError(format!(
            "{}: not UTF-8 text (byte {}): a manifest is a TOML file",
            path.display(),
            e.utf8_error().valid_up_to() + 1
        ))
    })?;
    let lines = Lines::new(&text);
    let at = |offset: usize, message: String| -> anyhow::Error {
        UsageError(format!(
            "{}: line {}: {message}",
            path.display(),
            lines.of(offset)
        ))
        .into()
    };
    let raw: RawManifest = toml::from_str(&text).map_err(|e| {
        let line = e.span().map(|s| lines.of(s.start));
        let message = e.message().trim().to_string();
        UsageError(match line {
            Some(l) => {
                // The line itself, so a type error says which key it is about.
                let quoted: String = text
                    .lines()
                    .nth(l - 1)
                    .unwrap_or_default()
                    .trim()
                    .chars()
                    .take(80)
                    .collect();
                format!("{}: line {l} ({:?}): {message}", path.display(), quoted)
            }
            None => format!("{}: {message}", path.display()),
        })
    })?;
    let verb = raw.verb.get_ref().clone();
    if !VERBS.contains(&verb.as_str()) {
        return Err(at(
            raw.verb.span().start,
            format!(
                "verb {verb:?}: era batch runs {}",
                VERBS.map(|v| format!("{v:?}")).join(" or ")
            ),
        ));
    }
    if raw.record.is_empty() {
        return Err(UsageError(format!(
            "{}: no [[record]]: a manifest lists its records as [[record]] tables with an id and a path",
            path.display()
        ))
        .into());
    }
    if raw.record.len() > MAX_RECORDS {
        return Err(UsageError(format!(
            "{}: {} records, at most {MAX_RECORDS}: split the manifest",
            path.display(),
            raw.record.len()
        ))
        .into());
    }
    let folder = folder_of(path)?;
    let shared_args = raw
        .args
        .as_ref()
        .map(|a| a.get_ref().clone())
        .unwrap_or_default();
    let shared_line = raw.args.as_ref().map_or(1, |a| lines.of(a.span().start));
    if let Some(a) = &raw.args {
        check_args(a.get_ref()).map_err(|m| at(a.span().start, m))?;
    }
    let mut seen: std::collections::HashMap<String, usize> = Default::default();
    let mut records = Vec::with_capacity(raw.record.len());
    for r in &raw.record {
        let r = r.get_ref();
        let id = r.id.get_ref().clone();
        check_id(&id).map_err(|m| at(r.id.span().start, m))?;
        if let Some(first) = seen.insert(id.clone(), lines.of(r.id.span().start)) {
            return Err(at(
                r.id.span().start,
                format!("record id {id:?} is given twice (first on line {first}): ids name the rows of the tables"),
            ));
        }
        let names = match r.path.get_ref() {
            Paths::One(p) => vec![p.clone()],
            Paths::Many(p) => p.clone(),
        };
        if names.is_empty() {
            return Err(at(
                r.path.span().start,
                format!("record {id:?}: path is an empty list"),
            ));
        }
        let mut files = Vec::with_capacity(names.len());
        for name in &names {
            let file = resolve(&folder, name, allow_outside)
                .map_err(|m| at(r.path.span().start, format!("record {id:?}: {m}")))?;
            files.push(file);
        }
        if verb == "identify" && files.len() != 1 {
            return Err(at(
                r.path.span().start,
                format!(
                    "record {id:?}: era identify takes one file, {} are given",
                    files.len()
                ),
            ));
        }
        let time_us = match &r.time {
            None => None,
            Some(t) => Some(
                time_of(t.get_ref())
                    .map_err(|m| at(t.span().start, format!("record {id:?}: {m}")))?,
            ),
        };
        let (args, args_line) = match &r.args {
            None => (shared_args.clone(), shared_line),
            Some(a) => {
                check_args(a.get_ref()).map_err(|m| at(a.span().start, m))?;
                (a.get_ref().clone(), lines.of(a.span().start))
            }
        };
        records.push(Record {
            id,
            files,
            time_us,
            args,
            args_line,
        });
    }
    Ok(Manifest {
        path: path.to_path_buf(),
        verb,
        records,
    })
}

/// The manifest's folder, resolved (links followed).
fn folder_of(path: &Path) -> anyhow::Result<PathBuf> {
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    parent.canonicalize().map_err(|e| {
        UsageError(format!(
            "{}: its folder cannot be resolved: {e}",
            path.display()
        ))
        .into()
    })
}

/// A record file: relative to the manifest's folder, existing, a regular file, and
/// inside that folder (after links) unless `allow_outside`.
fn resolve(folder: &Path, name: &str, allow_outside: bool) -> Result<PathBuf, String> {
    if name.is_empty() {
        return Err("an empty path".into());
    }
    let joined = folder.join(name);
    let real = joined.canonicalize().map_err(|e| format!("{name}: {e}"))?;
    if !allow_outside && !real.starts_with(folder) {
        return Err(format!(
            "{name} is outside the manifest's folder {} (it resolves to {}): give --allow-outside to accept it",
            folder.display(),
            real.display()
        ));
    }
    let meta = std::fs::metadata(&real).map_err(|e| format!("{name}: {e}"))?;
    if !meta.is_file() {
        return Err(format!("{name} is not a regular file"));
    }
    Ok(joined)
}

/// An id usable as a folder name and a table key.
fn check_id(id: &str) -> Result<(), String> {
    let ok_char = |c: char| c.is_ascii_alphanumeric() || "-_.:+".contains(c);
    if id.is_empty() || id.len() > MAX_ID || id.starts_with('.') || !id.chars().all(ok_char) {
        return Err(format!(
            "record id {:?}: give 1 to {MAX_ID} letters, digits or -_.:+, not starting with a dot",
            id.chars().take(MAX_ID + 1).collect::<String>()
        ));
    }
    Ok(())
}

/// A record's time: an RFC 3339 string or a TOML date-time with an offset.
fn time_of(value: &toml::Value) -> Result<i64, String> {
    match value {
        toml::Value::String(s) => era_io::fleet::parse_time(s),
        toml::Value::Datetime(d) => era_io::fleet::parse_time(&d.to_string()),
        other => Err(format!(
            "time is a {}, give an RFC 3339 time such as 2026-05-01T10:00:00Z",
            other.type_str()
        )),
    }
}

/// The verb's flags as given: none a batch sets itself, no file.
fn check_args(args: &[String]) -> Result<(), String> {
    for a in args {
        let flag = a.split('=').next().unwrap_or(a);
        if let Some((_, why)) = OWNED_FLAGS.iter().find(|(f, _)| *f == flag) {
            return Err(format!("args: {flag} is the batch's own ({why})"));
        }
        if flag == "-h" {
            return Err("args: -h: run era VERB --help".into());
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn manifest(dir: &Path, text: &str) -> anyhow::Result<Manifest> {
        let path = dir.join("m.toml");
        std::fs::write(&path, text).unwrap();
        read(&path, false)
    }

    #[test]
    fn a_manifest_is_read_and_every_problem_names_its_line() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("sub");
        std::fs::create_dir(&dir).unwrap();
        // `../a.csv` exists, outside the manifest's folder.
        for f in [
            root.path().join("a.csv"),
            dir.join("a.csv"),
            dir.join("b.csv"),
        ] {
            std::fs::write(f, "x").unwrap();
        }
        let good = "verb = \"oma\"\nargs = [\"--outputs\", \"1-3\"]\n\n[[record]]\nid = \"a\"\npath = \"a.csv\"\ntime = 2026-05-01T10:00:00Z\n\n[[record]]\nid = \"b\"\npath = [\"a.csv\", \"b.csv\"]\n";
        let m = manifest(&dir, good).unwrap();
        assert_eq!(m.records.len(), 2);
        assert_eq!(m.records[1].files.len(), 2);
        assert_eq!(m.records[0].args, ["--outputs", "1-3"]);
        assert_eq!(m.records[0].time_us, Some(1_777_629_600_000_000));
        assert_eq!(m.records[1].args_line, 2);
        let cases = [
            (good.replace("id = \"b\"", "id = \"a\""), "line 10", "twice"),
            (good.replace("\"oma\"", "\"fly\""), "line 1", "verb"),
            (good.replace("b.csv\"]", "c.csv\"]"), "line 11", "c.csv"),
            (
                good.replace("\"a.csv\"\ntime", "\"../a.csv\"\ntime"),
                "line 6",
                "outside",
            ),
            (
                good.replace("\"1-3\"]", "\"1-3\", \"--out\", \"x\"]"),
                "line 2",
                "--out",
            ),
            (
                good.replace("id = \"a\"", "id = \"a/b\""),
                "line 5",
                "record id",
            ),
            (
                good.replace("2026-05-01T10:00:00Z", "\"soon\""),
                "line 7",
                "RFC 3339",
            ),
            (
                good.replace("\"--outputs\",", "\"--outputs\""),
                "line 2",
                "comma",
            ),
            (
                good.replace("path = \"a.csv\"", "pth = \"a.csv\""),
                "line",
                "pth",
            ),
        ];
        for (text, line, word) in cases {
            let e = format!("{:#}", manifest(&dir, &text).unwrap_err());
            assert!(e.contains(line) && e.contains(word), "{e}\n---\n{text}");
            assert!(e.contains("m.toml"), "{e}");
        }
    }

    #[test]
    fn a_link_out_of_the_folder_is_refused_unless_allowed() {
        let outside = tempfile::tempdir().unwrap();
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(outside.path().join("x.csv"), "x").unwrap();
        std::os::unix::fs::symlink(outside.path().join("x.csv"), dir.path().join("x.csv")).unwrap();
        let text = "verb = \"oma\"\n[[record]]\nid = \"x\"\npath = \"x.csv\"\n";
        let e = format!("{:#}", manifest(dir.path(), text).unwrap_err());
        assert!(
            e.contains("outside") && e.contains("--allow-outside"),
            "{e}"
        );
        let path = dir.path().join("m.toml");
        assert!(read(&path, true).is_ok());
    }
}
