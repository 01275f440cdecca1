//! The time-history readers (CSV, MAT v5, HDF5, told apart by content) and the
//! `model.json` reader on arbitrary bytes. matrw panics on some malformed MAT input and
//! era-io contains those panics (a malformed-file error); libfuzzer's hook would abort
//! on a contained panic too, so a silent hook is set, as in the `mat` target. A panic
//! that escapes era-io still aborts.
#![no_main]
use era_io::input::InputBytes;
use era_io::time::{parse_time_input, TimeSelection};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    std::panic::set_hook(Box::new(|_| {}));
    // The first byte chooses the selection, so the MAT variable and HDF5 dataset paths
    // are reached too.
    let (choice, bytes) = match data.split_first() {
        Some((c, rest)) => (*c, rest),
        None => (0, data),
    };
    let selection = match choice % 4 {
        0 => TimeSelection::default(),
        1 => TimeSelection {
            variables: vec!["u".into(), "y".into()],
            ..TimeSelection::default()
        },
        2 => TimeSelection {
            datasets: vec!["data".into()],
            ..TimeSelection::default()
        },
        _ => TimeSelection {
            datasets: vec!["a".into(), "b".into()],
            ..TimeSelection::default()
        },
    };
    let _ = parse_time_input(
        InputBytes::Owned(bytes.to_vec()),
        Path::new("fuzz.bin"),
        &selection,
    );
    if let Ok(text) = std::str::from_utf8(bytes) {
        let _ = era_io::model_json::ModelJson::parse(text, Path::new("model.json"));
    }
});
