//! Writing and reading the small files of a test: text, JSON, golden CSV.

use std::path::{Path, PathBuf};

/// Writes `text` to `dir/name` and returns the path.
#[track_caller]
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    p
}

/// A text file's contents; a missing or unreadable file fails with its path.
#[track_caller]
pub fn read(path: impl AsRef<Path>) -> String {
    std::fs::read_to_string(path.as_ref())
        .unwrap_or_else(|e| panic!("{}: {e}", path.as_ref().display()))
}

/// A JSON file, parsed.
#[track_caller]
pub fn read_json(path: impl AsRef<Path>) -> serde_json::Value {
    let text = read(path.as_ref());
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.as_ref().display()))
}

/// A golden CSV (`#` lines and blank lines skipped): the header and the rows, as
/// trimmed strings.
#[track_caller]
pub fn read_golden_csv(path: impl AsRef<Path>) -> (Vec<String>, Vec<Vec<String>>) {
    let text = read(path.as_ref());
    let mut lines = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty());
    let header = lines
        .next()
        .unwrap_or_else(|| panic!("{}: no header", path.as_ref().display()))
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|c| c.trim().to_string()).collect())
        .collect();
    (header, rows)
}

/// (frequency Hz, damping ratio) of the modes of a JSON (`model.json`, or the truth that
/// `era simulate ... --json` prints), all of them or the physical ones.
pub fn modes_of(v: &serde_json::Value, only_physical: bool) -> Vec<(f64, f64)> {
    v["modes"]
        .as_array()
        .expect("a \"modes\" array")
        .iter()
        .filter(|m| !only_physical || m["physical"].as_bool().unwrap())
        .map(|m| {
            (
                m["frequency_hz"].as_f64().unwrap(),
                m["damping_ratio"].as_f64().unwrap(),
            )
        })
        .collect()
}
