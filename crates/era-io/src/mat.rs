//! MATLAB MAT files (v7: zlib-compressed level-5 format, MATLAB's default), written with
//! the `matrw` crate so that MATLAB, Octave and scipy load them with one line.
//!
//! - [`write_model_mat`]: `a, b, c, d, Ts` (`Ts = 0` for a continuous model, as
//!   `ss(a,b,c,d,0)` reads it) and the modal table `freq_hz`, `damping_ratio` (columns),
//!   so that `load model.mat; sys = ss(a,b,c,d,Ts)` works;
//! - [`write_frf_mat`]: the thesis's layout, `FRF` (lines × q·p, complex, column
//!   `(j−1)·q + i` is output i from input j, output-fastest) and `FreqV` (lines × 1, Hz).
//!
//! Arrays are built with `matrw`'s `NumericArray::new` (column-major values and
//! dimensions), the one constructor it offers for arrays built at run time.

use crate::IoError;
use era::modal::ModalParameters;
use era::{FrfData, StateSpace};
use matrw::{save_matfile_v7, MatFile, MatVariable, MatlabType, NumericArray};
use std::path::Path;

fn real(rows: usize, cols: usize, f: impl Fn(usize, usize) -> f64) -> MatVariable {
    let mut v = Vec::with_capacity(rows * cols);
    for j in 0..cols {
        for i in 0..rows {
            v.push(f(i, j));
        }
    }
    MatVariable::NumericArray(
        NumericArray::new(vec![rows, cols], MatlabType::F64(v), None).expect("sizes agree"),
    )
}

fn complex(rows: usize, cols: usize, f: impl Fn(usize, usize) -> era::Complex64) -> MatVariable {
    let (mut re, mut im) = (
        Vec::with_capacity(rows * cols),
        Vec::with_capacity(rows * cols),
    );
    for j in 0..cols {
        for i in 0..rows {
            let z = f(i, j);
            re.push(z.re);
            im.push(z.im);
        }
    }
    MatVariable::NumericArray(
        NumericArray::new(
            vec![rows, cols],
            MatlabType::F64(re),
            Some(MatlabType::F64(im)),
        )
        .expect("sizes agree"),
    )
}

/// Saves through a temporary file in the same folder, then renames.
fn save_atomic(path: &Path, file: MatFile) -> Result<(), IoError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out.mat".into());
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let tmp_str = tmp
        .to_str()
        .ok_or_else(|| IoError::format(path, "", "the path is not valid UTF-8"))?;
    let result = save_matfile_v7(tmp_str, file, true)
        .map_err(|e| IoError::format(path, "", format!("cannot write the MAT file: {e}")))
        .and_then(|_| std::fs::rename(&tmp, path).map_err(|e| IoError::io(path, e)));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Writes `a, b, c, d, Ts, freq_hz, damping_ratio`.
///
/// # Errors
/// [`IoError`] naming the file.
pub fn write_model_mat(
    path: &Path,
    model: &StateSpace,
    modal: &ModalParameters,
) -> Result<(), IoError> {
    let mut file = MatFile::new();
    for (name, m) in [
        ("a", &model.a),
        ("b", &model.b),
        ("c", &model.c),
        ("d", &model.d),
    ] {
        file.insert(name, real(m.nrows(), m.ncols(), |i, j| m[(i, j)]));
    }
    file.insert(
        "Ts",
        real(1, 1, |_, _| model.sample_time_s().unwrap_or(0.0)),
    );
    let n = modal.modes.len();
    file.insert("freq_hz", real(n, 1, |i, _| modal.modes[i].frequency_hz));
    file.insert(
        "damping_ratio",
        real(n, 1, |i, _| modal.modes[i].damping_ratio),
    );
    save_atomic(path, file)
}

/// Writes FRFs as `FRF` + `FreqV` (the thesis's layout).
///
/// # Errors
/// [`IoError`] naming the file.
pub fn write_frf_mat(path: &Path, frf: &FrfData) -> Result<(), IoError> {
    let (q, p, lines) = (frf.outputs(), frf.inputs(), frf.lines());
    let mut file = MatFile::new();
    file.insert(
        "FRF",
        complex(lines, q * p, |k, col| frf.pair(col % q, col / q)[k]),
    );
    file.insert("FreqV", real(lines, 1, |k, _| frf.frequency_hz()[k]));
    save_atomic(path, file)
}

#[cfg(test)]
mod tests {
    use super::*;
    use era::identify::{identify, EraOptions};
    use era::sim::truth_model_frf;
    use matrw::load_matfile;

    fn values(file: &mut MatFile, name: &str) -> (Vec<usize>, Vec<f64>, Option<Vec<f64>>) {
        match file.take(name).unwrap_or_else(|| panic!("{name} missing")) {
            MatVariable::NumericArray(a) => (
                a.dim.clone(),
                a.real_to_vec::<f64>().unwrap(),
                a.comp_to_vec::<f64>(),
            ),
            other => panic!("{name}: {other:?}"),
        }
    }

    #[test]
    fn model_mat_reads_back_exactly() {
        let frf = truth_model_frf(None).unwrap();
        let found = identify(&frf, &EraOptions::thesis_truth_model()).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("model.mat");
        write_model_mat(&path, &found.model, &found.modal).unwrap();
        let mut file = load_matfile(path.to_str().unwrap()).unwrap();
        let (dim, a, _) = values(&mut file, "a");
        assert_eq!(dim, vec![8, 8]);
        for j in 0..8 {
            for i in 0..8 {
                assert_eq!(
                    a[j * 8 + i],
                    found.model.a[(i, j)],
                    "column-major a({i},{j})"
                );
            }
        }
        let (dim, b, _) = values(&mut file, "b");
        assert_eq!((dim, b[8 + 2]), (vec![8, 3], found.model.b[(2, 1)]));
        let (_, ts, _) = values(&mut file, "Ts");
        assert_eq!(ts, vec![1.0 / 25_600.0]);
        let (dim, f, _) = values(&mut file, "freq_hz");
        assert_eq!(dim, vec![4, 1]);
        assert_eq!(f[3], found.modal.modes[3].frequency_hz);
    }

    #[test]
    fn frf_mat_has_the_thesis_layout() {
        let frf = truth_model_frf(Some((0.15, 3))).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("frf.mat");
        write_frf_mat(&path, &frf).unwrap();
        let mut file = load_matfile(path.to_str().unwrap()).unwrap();
        let (dim, re, im) = values(&mut file, "FRF");
        assert_eq!(dim, vec![1025, 9]);
        let im = im.expect("complex");
        // Column (j−1)·q + i: output 2 from input 3 is column 3·… = (3−1)·3 + 2 = 8 (1-based).
        let (k, col) = (100, 7);
        assert_eq!(
            (re[col * 1025 + k], im[col * 1025 + k]),
            (frf.pair(1, 2)[k].re, frf.pair(1, 2)[k].im)
        );
        let (dim, freq, _) = values(&mut file, "FreqV");
        assert_eq!((dim, freq[1]), (vec![1025, 1], 12.5));
    }
}
