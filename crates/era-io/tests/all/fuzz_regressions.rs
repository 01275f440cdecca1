//! Inputs the fuzzers (fuzz/, `cargo fuzz run <target>`) found to crash a reader, kept
//! so the fix stays. Each must now be refused with an error naming the problem.

use std::path::{Path, PathBuf};

fn cases(prefix: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions");
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().unwrap().to_str().unwrap().starts_with(prefix))
        .collect();
    v.sort();
    v
}

#[test]
fn mat_allocation_bombs_are_refused_before_matrw_allocates() {
    // Found by the `mat` target: element sizes near 4 GiB in 600-byte files, and an
    // unknown top-level element that matrw tried to read as an object, made matrw
    // allocate gigabytes (libFuzzer's out-of-memory report). era-io's structural check
    // now refuses them. One more (mat_u32_count.mat) is a matrw quirk that no check
    // before it can rule out: it tries every array layout in turn, and a wrong layout
    // reads any 32-bit word as a count and reserves up to 4 GiB of address space,
    // never touched; such a file is refused like the others.
    let found = cases("mat_");
    assert!(found.len() >= 4);
    for path in found {
        let bytes = std::fs::read(&path).unwrap();
        let e = era_io::mat::parse_frf_mat(&bytes, &path)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("not a readable MAT v5 file"),
            "{}: {e}",
            path.display()
        );
        assert!(era_io::mat::parse_mat_matrix(&bytes, &path, None).is_err());
    }
}

#[test]
fn a_csv_header_asking_for_billions_of_pairs_is_refused_quickly() {
    // Found by the `frf_csv` target: a column named H02437545556649122914_2_im made the
    // reader list every missing column of a 2437545556649122914 x 2 set.
    for path in cases("csv_") {
        let text = String::from_utf8_lossy(&std::fs::read(&path).unwrap()).into_owned();
        let e = era_io::csv::parse_frf_csv(&text, &path, era::Quantity::Acceleration)
            .unwrap_err()
            .to_string();
        assert!(e.contains("missing column"), "{}: {e}", path.display());
        assert!(e.len() < 1000, "{e}");
    }
}
