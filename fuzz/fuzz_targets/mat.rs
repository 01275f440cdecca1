//! The MAT readers on arbitrary bytes. matrw's parser panics on some malformed input;
//! era-io contains those panics and reports a malformed file. libfuzzer's panic hook
//! would abort on the contained panic, so a silent hook is set: a panic that escapes
//! era-io still aborts (libfuzzer-sys aborts on any panic that reaches it).
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    std::panic::set_hook(Box::new(|_| {}));
    let path = Path::new("fuzz.mat");
    let _ = era_io::mat::parse_frf_mat(data, path);
    let _ = era_io::mat::parse_mat_matrix(data, path, None);
});
