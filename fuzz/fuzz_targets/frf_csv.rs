//! The FRF CSV reader on arbitrary text.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = era_io::csv::parse_frf_csv(text, Path::new("fuzz.csv"), era::Quantity::Acceleration);
    }
});
