//! The UFF reader on arbitrary bytes: headers only and with data, then the FRF
//! matrix. Errors are fine; a panic, a hang or a crash is not.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.uff");
    let _ = era_io::uff::parse_uff(data, path, false);
    if let Ok(contents) = era_io::uff::parse_uff(data, path, true) {
        let _ = era_io::uff::frf_from_uff(path, &contents, era::Quantity::Acceleration);
    }
});
