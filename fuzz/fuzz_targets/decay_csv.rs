//! The free-decay CSV reader on arbitrary text.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = era_io::decay_csv::parse_decay_csv(text, Path::new("fuzz.csv"));
    }
});
