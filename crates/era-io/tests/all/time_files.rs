//! Time-history files of data/ read by `time::read_time_file`: the LADISK plate (HDF5,
//! pure-Rust reader) and the DaISy steel subframe (MAT v5). A missing data file fails the
//! test.

use crate::common;
use common::data_file;

use era_io::time::{parse_channels, read_time_file, TimeFormat, TimeSelection};

#[test]
fn ladisk_hdf5_reads_channels_names_and_sample_rate() {
    let path = data_file("ladisk-plate-sweep/view_0.hdf5");
    let h = read_time_file(&path, &TimeSelection::default()).unwrap();
    assert_eq!(h.format, TimeFormat::Hdf5);
    assert_eq!(h.channels(), 3);
    assert_eq!(h.samples(), 51_200);
    assert_eq!(
        h.names.as_deref().unwrap(),
        &["force".to_string(), "acc".into(), "trigger".into()]
    );
    let (rate, from) = h.sample_rate.clone().unwrap();
    assert_eq!(rate, 25_600.0);
    assert_eq!(from, "dataset InputTask/sample_rate");
    // First row as h5py prints it.
    assert_eq!(h.columns[0][0], -0.07932337807606263);
    assert_eq!(h.columns[1][0], 0.011573828187435634);
    assert_eq!(h.columns[2][0], 1.067375194272);
    assert_eq!(h.columns[0][1], -0.08553763982102908);
    assert_eq!(parse_channels("force", &h).unwrap(), vec![0]);
    assert_eq!(parse_channels("acc", &h).unwrap(), vec![1]);

    // 1-D datasets are channels of their own, named after the dataset.
    let sel = TimeSelection {
        datasets: vec!["/InputTask/time".into()],
        ..Default::default()
    };
    let t = read_time_file(&path, &sel).unwrap();
    assert_eq!(t.names.as_deref().unwrap(), &["time".to_string()]);
    assert_eq!(t.samples(), 51_200);
    assert!((t.columns[0][1] - t.columns[0][0] - 1.0 / 25_600.0).abs() < 1e-12);

    // Unknown dataset, misplaced flag, truncated file.
    let sel = TimeSelection {
        datasets: vec!["InputTask/force".into()],
        ..Default::default()
    };
    let e = read_time_file(&path, &sel).unwrap_err().to_string();
    assert!(
        e.contains("no dataset InputTask/force") && e.contains("InputTask/data [51200, 3]"),
        "{e}"
    );
    let sel = TimeSelection {
        variables: vec!["x".into()],
        ..Default::default()
    };
    let e = read_time_file(&path, &sel).unwrap_err().to_string();
    assert!(
        e.contains("--variable applies to MAT files; this is a HDF5 file"),
        "{e}"
    );
    let dir = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    for cut in [100, 2_000, 40_000] {
        let short = dir.path().join(format!("cut{cut}.hdf5"));
        std::fs::write(&short, &bytes[..cut]).unwrap();
        let e = read_time_file(&short, &TimeSelection::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains(&*short.to_string_lossy()), "{e}");
    }
}

#[test]
fn daisy_mat_reads_as_thirty_unnamed_channels() {
    let path = data_file("daisy-steel-subframe/flexible_structure_dat.mat");
    let h = read_time_file(&path, &TimeSelection::default()).unwrap();
    assert_eq!(h.format, TimeFormat::Mat);
    assert_eq!((h.channels(), h.samples()), (30, 8523));
    assert!(h.names.is_none() && h.sample_rate.is_none());
    assert_eq!(h.columns[0][0], -0.60899);
    assert_eq!(
        parse_channels("3-30", &h).unwrap(),
        (2..30).collect::<Vec<_>>()
    );
    let e = parse_channels("force", &h).unwrap_err();
    assert!(
        e.contains("has no channel names; use column numbers 1 to 30"),
        "{e}"
    );
    // The same variable twice: 60 channels side by side.
    let sel = TimeSelection {
        variables: vec![
            "flexible_structure_dat".into(),
            "flexible_structure_dat".into(),
        ],
        ..Default::default()
    };
    assert_eq!(read_time_file(&path, &sel).unwrap().channels(), 60);
}
