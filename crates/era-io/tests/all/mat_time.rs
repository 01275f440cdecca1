//! The real MAT v5 files of data/daisy-* read as time histories: shape and values
//! (samples and column sums from scipy.io.loadmat). A missing data file fails the test.

use crate::common;
use common::data_file;

use era_io::mat::read_mat_matrix;

#[test]
fn daisy_files_read_as_time_histories() {
    // (file, variable, rows, cols, first sample, last sample)
    let cases = [
        (
            "daisy-steel-subframe/flexible_structure_dat.mat",
            "flexible_structure_dat",
            8523,
            30,
            -0.60899,
            -0.902231,
        ),
        (
            "daisy-robot-arm-cd-player/CD_player_arm_dat.mat",
            "CD_player_arm_dat",
            2048,
            4,
            0.0531,
            0.1892,
        ),
        (
            "daisy-robot-arm-cd-player/robot_arm_dat.mat",
            "robot_arm_dat",
            1024,
            2,
            0.22183165,
            -0.1671642,
        ),
    ];
    for (rel, name, rows, cols, first, last) in cases {
        let path = data_file(rel);
        let m = read_mat_matrix(&path, None).unwrap();
        assert_eq!(
            (m.name.as_str(), m.rows, m.cols),
            (name, rows, cols),
            "{rel}"
        );
        assert_eq!(m.values[0], first, "{rel}");
        assert_eq!(*m.values.last().unwrap(), last, "{rel}");
        if name == "flexible_structure_dat" {
            // Interior samples and column sums, from scipy.io.loadmat.
            assert_eq!(m.column(5)[100], -2.58786);
            assert_eq!(m.column(29)[8000], -0.0677761);
            let sum = |j: usize| m.column(j).iter().sum::<f64>();
            assert!((sum(0) - 5276.16543131).abs() < 1e-6, "{}", sum(0));
            assert!((sum(29) - 56.545840778).abs() < 1e-6, "{}", sum(29));
        }
        let named = read_mat_matrix(&path, Some(name)).unwrap();
        assert_eq!(named, m);
        let e = read_mat_matrix(&path, Some("nope"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("no variable nope") && e.contains(name), "{e}");
    }
}
