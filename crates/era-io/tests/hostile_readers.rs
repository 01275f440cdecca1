//! Hostile input for every reader's parse-from-bytes entry: seeded bit flips and
//! truncations of valid files, huge declared sizes, absurd counts, byte-order marks and
//! control characters. Each must give `Err` (or a sane `Ok`), never a panic, and no
//! single allocation may be large: a counting allocator below records the largest.

use era::Quantity;
use era_io::csv::parse_frf_csv;
use era_io::decay_csv::parse_decay_csv;
use era_io::mat::{parse_frf_mat, parse_mat_matrix};
use era_io::time::{parse_time_csv, read_time_file, TimeSelection};
use era_io::uff::{frf_from_uff, parse_uff};
use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The largest single allocation any test of this file made.
static LARGEST: AtomicUsize = AtomicUsize::new(0);

struct Counting;

// SAFETY: forwards to the system allocator; only records sizes.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LARGEST.fetch_max(new_size, Ordering::Relaxed);
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// No input here is bigger than a few kB: 64 MB in one allocation means a size from
/// the file was trusted.
const MAX_ALLOCATION: usize = 64 << 20;

fn assert_bounded(what: &str) {
    let largest = LARGEST.load(Ordering::Relaxed);
    assert!(
        largest <= MAX_ALLOCATION,
        "{what}: an allocation of {largest} bytes"
    );
}

/// xorshift64*: seeded, so every failure can be replayed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// `count` copies of `bytes`, each with 1 to 4 random bits flipped.
fn flips(bytes: &[u8], seed: u64, count: usize) -> Vec<Vec<u8>> {
    let mut rng = Rng(seed);
    (0..count)
        .map(|_| {
            let mut b = bytes.to_vec();
            for _ in 0..1 + rng.below(4) {
                let at = rng.below(b.len());
                b[at] ^= 1 << rng.below(8);
            }
            b
        })
        .collect()
}

/// Every prefix of `bytes` at `count` seeded cut points (and the empty one).
fn cuts(bytes: &[u8], seed: u64, count: usize) -> Vec<Vec<u8>> {
    let mut rng = Rng(seed);
    let mut out = vec![Vec::new()];
    out.extend((0..count).map(|_| bytes[..rng.below(bytes.len())].to_vec()));
    out
}

/// One random digit string replaced by a huge number (declared sizes, counts).
fn huge_numbers(text: &str, seed: u64, count: usize) -> Vec<Vec<u8>> {
    let digits: Vec<(usize, usize)> = {
        let b = text.as_bytes();
        let mut spans = Vec::new();
        let mut k = 0;
        while k < b.len() {
            if b[k].is_ascii_digit() {
                let s = k;
                while k < b.len() && b[k].is_ascii_digit() {
                    k += 1;
                }
                spans.push((s, k));
            } else {
                k += 1;
            }
        }
        spans
    };
    let huge = [
        "18446744073709551615",
        "4294967295",
        "99999999999",
        "100000000",
        "1e308",
        "-1",
    ];
    let mut rng = Rng(seed);
    (0..count)
        .map(|_| {
            let (s, e) = digits[rng.below(digits.len())];
            let mut t = text.to_string();
            t.replace_range(s..e, huge[rng.below(huge.len())]);
            t.into_bytes()
        })
        .collect()
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

const FRF_CSV: &str = "# quantity: velocity\n# output_1: node 12 +Z\nfrequency_hz,H1_1_re,H1_1_im,H2_1_re,H2_1_im\n0,1,0,2,0\n0.5,1.5,-0.5,2,1\n1,2,-1,3,0.25\n1.5,0.5,0.5,1,1\n";
const TIME_CSV: &str =
    "# sample_rate_hz: 10\ntime_s,force,acc\n0,1,0\n0.1,0.5,1\n0.2,-1,2\n0.3,0,0.5\n";
const DECAY_CSV: &str =
    "# mass_kg: 1\ntime_s,velocity,displacement\n0,1,0\n0.1,0.5,0.1\n0.2,-0.2,0.12\n0.3,-0.4,0.05\n";

fn uff_bytes(binary: bool) -> Vec<u8> {
    let frf = era::FrfData::from_fn(
        era::data::frf::uniform_lines(6, 0.5),
        2,
        1,
        Quantity::Acceleration,
        |i, _, k| era::Complex64::new(i as f64 + k as f64, -(k as f64)),
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("f.uff");
    era_io::uff::write_uff58(
        &path,
        &frf,
        None,
        (None, None),
        era_io::uff::UffWriteOptions {
            binary,
            single: false,
        },
    )
    .unwrap();
    std::fs::read(path).unwrap()
}

fn uff_to_frf(bytes: &[u8]) -> Result<(), String> {
    let path = Path::new("hostile.uff");
    let contents = parse_uff(bytes, path, true).map_err(|e| e.to_string())?;
    frf_from_uff(path, &contents, Quantity::Acceleration)
        .map(drop)
        .map_err(|e| e.to_string())
}

#[test]
fn mutated_frf_csvs_are_refused_or_read_never_panic() {
    let base = FRF_CSV.as_bytes();
    let mut cases = flips(base, 1, 300);
    cases.extend(cuts(base, 2, 60));
    cases.extend(huge_numbers(FRF_CSV, 3, 200));
    for c in &cases {
        let _ = parse_frf_csv(&text(c), Path::new("h.csv"), Quantity::Acceleration);
    }
    assert_bounded("FRF CSV");
}

#[test]
fn mutated_time_and_decay_csvs_never_panic() {
    for (base, seed) in [(TIME_CSV, 10), (DECAY_CSV, 20)] {
        let mut cases = flips(base.as_bytes(), seed, 300);
        cases.extend(cuts(base.as_bytes(), seed + 1, 60));
        cases.extend(huge_numbers(base, seed + 2, 200));
        for c in &cases {
            let _ = parse_time_csv(&text(c), Path::new("h.csv"));
            let _ = parse_decay_csv(&text(c), Path::new("h.csv"));
        }
    }
    assert_bounded("time and decay CSV");
}

#[test]
fn mutated_uff_ascii_and_binary_never_panic() {
    for (binary, seed) in [(false, 30), (true, 40)] {
        let base = uff_bytes(binary);
        assert!(uff_to_frf(&base).is_ok());
        let mut cases = flips(&base, seed, 400);
        cases.extend(cuts(&base, seed + 1, 80));
        if !binary {
            cases.extend(huge_numbers(&text(&base), seed + 2, 300));
        }
        for c in &cases {
            let _ = uff_to_frf(c);
            let _ = parse_uff(c, Path::new("h.uff"), false);
        }
    }
    assert_bounded("UFF");
}

/// A geometry with every dataset the reader knows: systems (18, 2420), nodes (15,
/// 2411) and a trace line (82).
const GEOMETRY_UFF: &str = "    -1
    18
         1         1         0         8         1
SYS1
 -2.40000e+00 -9.50000e-01  0.00000e+00 -3.40000e+00 -9.50000e-01  0.00000e+00
 -3.40000e+00 -9.50000e-01 -1.00000e+00
    -1
    -1
  2420
         1
Part1
         2         0         2
CS2
   1.0000000000000000D+00   0.0000000000000000D+00   0.0000000000000000D+00
   0.0000000000000000D+00   1.0000000000000000D+00   0.0000000000000000D+00
   0.0000000000000000D+00   0.0000000000000000D+00   1.0000000000000000D+00
   0.0000000000000000D+00   0.0000000000000000D+00   5.0000000000000000D+00
    -1
    -1
    15
         1         1         2         0  1.00000E+00  4.50000E+01  0.00000E+00
         2         2         1         0  1.00000E+00  2.00000E+00  3.00000E+00
    -1
    -1
  2411
         3         0         0         0
   1.0000000000000000D+00   2.0000000000000000D+00   3.0000000000000000D+00
    -1
    -1
    82
         1         4         0
lines
         1         2         3         1
    -1
";

#[test]
fn mutated_geometry_files_never_panic() {
    let path = Path::new("h.uff");
    let base = GEOMETRY_UFF.as_bytes();
    let g = era_io::geometry::parse_geometry(base, path).unwrap();
    assert_eq!((g.nodes.len(), g.segments().len()), (3, 3));
    let csv = b"node,x,y,z\n1,0,0,0\n2,1,0,0\n3,1,1,0\nfrom,to\n1,2\n2,3\n";
    assert!(era_io::geometry::parse_geometry(csv, path).is_ok());
    for (base, seed) in [(base, 50), (&csv[..], 60)] {
        let mut cases = flips(base, seed, 400);
        cases.extend(cuts(base, seed + 1, 80));
        cases.extend(huge_numbers(&text(base), seed + 2, 300));
        for c in &cases {
            let _ = era_io::geometry::parse_geometry(c, path);
        }
    }
    assert_bounded("geometry");
}

#[test]
fn mutated_mat_files_never_panic() {
    let base = std::fs::read(fixture("frf_3x2.mat")).unwrap();
    let mut cases = flips(&base, 50, 300);
    cases.extend(cuts(&base, 51, 60));
    let scipy = std::fs::read(fixture("scipy_frf.mat")).unwrap();
    cases.extend(flips(&scipy, 52, 200));
    for c in &cases {
        let _ = parse_frf_mat(c, Path::new("h.mat"));
        let _ = parse_mat_matrix(c, Path::new("h.mat"), None);
    }
    assert_bounded("MAT");
}

use era_testkit::paths::io_fixture as fixture;

/// Rewrites the abscissa minimum and increment of every record 7 of an ASCII UFF.
fn uff_starting_at(start_hz: f64, inc_hz: f64) -> Vec<u8> {
    let base = text(&uff_bytes(false));
    let mut out = String::new();
    let mut after_header = 0;
    for line in base.lines() {
        if line.trim() == "58" {
            after_header = 1;
        } else if after_header > 0 {
            after_header += 1;
        }
        if after_header == 8 {
            // Record 7: (3I10, 3E13.5): type, points, even, min, increment, z.
            out.push_str(&format!(
                "{}{:13.6e}{:13.6e}{}\n",
                &line[..30],
                start_hz,
                inc_hz,
                &line[56..]
            ));
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    out.into_bytes()
}

#[test]
fn a_uff_starting_far_above_zero_is_refused_before_padding() {
    // 1e7 Hz at 1 Hz spacing would pad ten million zero lines per pair.
    for (start, inc) in [(1e7, 1.0), (4.5e7, 0.5), (2.0e9, 2.0)] {
        let e = uff_to_frf(&uff_starting_at(start, inc)).unwrap_err();
        assert!(e.contains("ERA_MAX_LINES"), "{start} Hz: {e}");
    }
    // A modest start is still padded.
    assert!(uff_to_frf(&uff_starting_at(2.0, 0.5)).is_ok());
    assert_bounded("UFF padding");
}

#[test]
fn an_hdf5_declaring_an_unwritten_huge_dataset_is_refused() {
    let path = fixture("hdf5_declared_1e8x2.hdf5");
    let e = read_time_file(&path, &TimeSelection::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("declares shape") && e.contains("100000000"),
        "{e}"
    );
    assert_bounded("HDF5");
}

#[test]
fn a_mat_file_written_by_scipy_is_read() {
    let file =
        era_io::mat::read_frf_mat(&fixture("scipy_frf.mat"), Some(2), Quantity::Velocity).unwrap();
    assert_eq!(
        (file.frf.outputs(), file.frf.inputs(), file.frf.lines()),
        (2, 1, 5)
    );
    assert_eq!(file.frf.pair(1, 0)[4], era::Complex64::new(-2.0, 1.0));
    assert_eq!(file.frf.spacing_hz(), 0.5);
}

#[test]
fn a_byte_order_mark_is_accepted_by_every_text_reader() {
    let bom = |s: &str| format!("\u{feff}{s}");
    let p = Path::new("bom.csv");
    parse_frf_csv(&bom(FRF_CSV), p, Quantity::Acceleration).unwrap();
    parse_time_csv(&bom(TIME_CSV), p).unwrap();
    parse_decay_csv(&bom(DECAY_CSV), p).unwrap();
    // Through the file readers too (bytes, not text).
    let dir = tempfile::tempdir().unwrap();
    for (name, body) in [
        ("f.csv", FRF_CSV),
        ("t.csv", TIME_CSV),
        ("d.csv", DECAY_CSV),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, bom(body)).unwrap();
        match name {
            "f.csv" => drop(era_io::csv::read_frf_csv(&path, Quantity::Acceleration).unwrap()),
            "t.csv" => drop(read_time_file(&path, &TimeSelection::default()).unwrap()),
            _ => drop(era_io::decay_csv::read_decay_csv(&path).unwrap()),
        }
    }
}

#[test]
fn control_characters_from_a_file_are_escaped_in_messages() {
    let cases = [
        "frequency_hz,H1_1_re,\u{1b}[2J\u{1b}]0;pwned\u{7}\n0,1,0\n".to_string(),
        "# quantity: \u{1b}[31mred\u{9b}\nfrequency_hz,H1_1_re,H1_1_im\n0,1,0\n".to_string(),
        "frequency_hz,H1_1_re,H1_1_im\n0,1,\u{1b}[1m\u{200b}x\n".to_string(),
    ];
    for c in &cases {
        let e = parse_frf_csv(c, Path::new("esc.csv"), Quantity::Acceleration)
            .unwrap_err()
            .to_string();
        assert!(
            !e.chars()
                .any(|ch| ch.is_control() || ch == '\u{200b}' || ch == '\u{9b}'),
            "raw control character in {e:?}"
        );
        assert!(e.contains("\\u{1b}"), "{e}");
    }
    let e = parse_time_csv("time_s,\u{1b}[0m\n0,x\n", Path::new("t.csv"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("\\u{1b}") && !e.contains('\u{1b}'), "{e}");
}

#[test]
fn too_many_channels_in_a_csv_header_are_refused() {
    let mut header = String::from("time_s");
    for k in 0..5000 {
        header.push_str(&format!(",c{k}"));
    }
    let e = parse_time_csv(&format!("{header}\n"), Path::new("wide.csv"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("ERA_MAX_CHANNELS"), "{e}");
    let mut header = String::from("frequency_hz");
    for i in 1..=4097 {
        header.push_str(&format!(",H{i}_1_re,H{i}_1_im"));
    }
    let e = parse_frf_csv(
        &format!("{header}\n"),
        Path::new("wide.csv"),
        Quantity::Acceleration,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("ERA_MAX_CHANNELS"), "{e}");
}

#[test]
fn a_folder_and_an_endless_device_are_refused_as_input() {
    let dir = tempfile::tempdir().unwrap();
    let e = era_io::input::read_input(dir.path())
        .unwrap_err()
        .to_string();
    assert!(e.contains("folder"), "{e}");
    #[cfg(target_os = "linux")]
    {
        let limit = era::params::limits::Limit {
            what: "bytes",
            default: 1 << 20,
            env: "ERA_HOSTILE_READERS_NEVER_SET",
        };
        let e = era_io::input::read_input_limited(Path::new("/dev/zero"), limit)
            .unwrap_err()
            .to_string();
        assert!(e.contains("1048576"), "{e}");
    }
    assert_bounded("input");
}
