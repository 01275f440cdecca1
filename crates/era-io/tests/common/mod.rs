//! Helpers shared by the era-io integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// A file under ../shared/data (beside the checkout), or None with a message saying the
/// test is skipped because it is absent.
pub fn shared(rel: &str) -> Option<PathBuf> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(rel);
    if p.is_file() {
        Some(p)
    } else {
        eprintln!("skipped: {} is absent", p.display());
        None
    }
}
