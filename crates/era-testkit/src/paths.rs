//! Files of the repository and the real data sets.

use std::path::{Path, PathBuf};

/// The workspace's root folder (the one holding `Cargo.toml`, `crates/` and `data/`).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .expect("the workspace root")
}

/// A file of the repository by its path from the root, e.g.
/// `crates/era-io/tests/fixtures/time_two.mat`. A missing file fails the test with its
/// path: a test never skips because a file it reads is absent.
#[track_caller]
pub fn repo_file(rel: &str) -> PathBuf {
    let p = workspace_root().join(rel);
    assert!(
        p.is_file(),
        "{} is missing: the repository should hold it",
        p.display()
    );
    p
}

/// A file of the real data sets (see data/README.md): under the workspace's `data/`, or
/// under `../shared/data` beside the workspace when that folder is present. A file in
/// neither fails the test naming both places: the data tests never skip silently.
#[track_caller]
pub fn data_file(rel: &str) -> PathBuf {
    let root = workspace_root();
    let places = [root.join("data"), root.join("../shared/data")];
    if let Some(p) = places.iter().map(|d| d.join(rel)).find(|p| p.is_file()) {
        return p;
    }
    panic!(
        "data file {rel} is missing: neither {} nor {} holds it (see data/README.md)",
        places[0].display(),
        places[1].display()
    );
}

/// A fixture of era-io's reader tests (`crates/era-io/tests/fixtures/NAME`).
#[track_caller]
pub fn io_fixture(name: &str) -> PathBuf {
    repo_file(&format!("crates/era-io/tests/fixtures/{name}"))
}

/// A golden UFF file of era-io's tests (`crates/era-io/tests/golden_uff/NAME`).
#[track_caller]
pub fn uff_golden(name: &str) -> PathBuf {
    repo_file(&format!("crates/era-io/tests/golden_uff/{name}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_sets_are_found_and_a_missing_one_fails() {
        assert!(data_file("README.md").ends_with("data/README.md"));
        let missing = std::panic::catch_unwind(|| data_file("no/such.file"));
        assert!(missing.is_err());
        let missing = std::panic::catch_unwind(|| repo_file("no/such.file"));
        assert!(missing.is_err());
        assert!(io_fixture("time_two.mat").is_file());
    }
}
