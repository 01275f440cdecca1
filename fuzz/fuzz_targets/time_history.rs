//! The time-history readers (CSV, MAT v5, HDF5, told apart by content) and the
//! `model.json` reader on arbitrary bytes.
#![no_main]
use era_io::input::InputBytes;
use era_io::time::{parse_time_input, TimeSelection};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
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
