//! Helpers shared by the era-io integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// A file under the workspace's `data/` folder (the real data sets shipped with the repo,
/// see data/README.md). A missing file fails the test with its path: the data tests never
/// skip silently.
#[track_caller]
pub fn data_file(rel: &str) -> PathBuf {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data")
        .join(rel);
    assert!(
        p.is_file(),
        "data file {} is missing: the repository's data/ folder should hold it (see data/README.md)",
        p.display()
    );
    p
}
