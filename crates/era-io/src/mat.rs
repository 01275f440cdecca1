//! MATLAB MAT files (v7: zlib-compressed level-5 format, MATLAB's default), written with
//! the `matrw` crate so that MATLAB, Octave and scipy load them with one line.
//!
//! - [`write_model_mat`]: `a, b, c, d, Ts` (`Ts = 0` for a continuous model, as
//!   `ss(a,b,c,d,0)` reads it) and the modal table `freq_hz`, `damping_ratio` (columns),
//!   so that `load model.mat; sys = ss(a,b,c,d,Ts)` works;
//! - [`write_frf_mat`]: the thesis's layout, `FRF` (lines × q·p, complex, column
//!   `(j−1)·q + i` is output i from input j, output-fastest) and `FreqV` (lines × 1, Hz),
//!   plus `outputs` and `inputs` so that the file says how to split the columns;
//! - [`read_frf_mat`]: FRFs from MAT v5 files, compressed (MATLAB's default `-v7`) or
//!   not, single or double precision, in three layouts:
//!   1. `FRF` + `FreqV` as above; the split of the q·p columns comes from the file's
//!      `outputs`, else from the caller, else a square set is assumed when q·p is a
//!      perfect square (and the caller is told);
//!   2. the thesis's `xferIJ` + `FreqV` (Appendix L.2), I the measurement and J the
//!      actuator. With two digits, each is one index. Longer names are ambiguous
//!      (`xfer110`: 1 and 10, or 11 and 0?) and refused unless written `xferI_J`;
//!   3. one q×p×L complex array + `FreqV`.
//!
//! Arrays are built with `matrw`'s `NumericArray::new` (column-major values and
//! dimensions), the one constructor it offers for arrays built at run time.

use crate::atomic::write_via;
use crate::frf_file::FrfFile;
use crate::IoError;
use era::modal::ModalParameters;
use era::{Complex64, EraError, FrfData, Quantity, StateSpace};
use matrw::{save_matfile_v7, MatFile, MatVariable, MatlabType, NumericArray};
use std::collections::BTreeMap;
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

/// Saves through [`write_via`] (a temporary file, then a rename). `matrw` does not
/// report write errors (it discards them), so the temporary file is read back and
/// must hold every variable before it replaces the destination.
fn save_atomic(path: &Path, file: MatFile) -> Result<(), IoError> {
    let expected: Vec<String> = file.iter().map(|(k, _)| k.clone()).collect();
    write_via(path, |tmp| {
        let tmp_text = tmp
            .to_str()
            .ok_or_else(|| IoError::format(path, "", "the path is not valid UTF-8"))?;
        save_matfile_v7(tmp_text, file, true)
            .map_err(|e| IoError::format(path, "", format!("cannot write the MAT file: {e}")))?;
        let bytes = std::fs::read(tmp).map_err(|e| IoError::io(path, e))?;
        let back = parse_variables(&bytes, path).map_err(|e| {
            IoError::format(
                path,
                "",
                format!("the written file does not read back: {e}"),
            )
        })?;
        let missing: Vec<&String> = expected
            .iter()
            .filter(|n| !back.numeric.contains_key(*n))
            .collect();
        if !missing.is_empty() {
            return Err(IoError::format(
                path,
                "",
                format!("the written file lacks {missing:?} (disk full?)"),
            ));
        }
        Ok(())
    })
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
    file.insert("outputs", real(1, 1, |_, _| q as f64));
    file.insert("inputs", real(1, 1, |_, _| p as f64));
    save_atomic(path, file)
}

/// True when the file starts like a MAT v5 file ("MATLAB 5.0 MAT-file").
pub fn looks_like_mat(path: &Path) -> bool {
    use std::io::Read;
    let mut head = [0u8; 19];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut head))
        .is_ok()
        && &head == b"MATLAB 5.0 MAT-file"
}

/// A numeric variable: dimensions, real and imaginary parts (column-major, as f64).
struct Array {
    dim: Vec<usize>,
    re: Vec<f64>,
    im: Option<Vec<f64>>,
}

/// Any numeric MATLAB type as f64 (`matrw`'s typed accessors panic on a type mismatch,
/// so the stored type is matched here).
fn to_f64(t: &MatlabType) -> Option<Vec<f64>> {
    Some(match t {
        MatlabType::F64(v) => v.clone(),
        MatlabType::F32(v) => v.iter().map(|x| f64::from(*x)).collect(),
        MatlabType::I8(v) => v.iter().map(|x| f64::from(*x)).collect(),
        MatlabType::U8(v) => v.iter().map(|x| f64::from(*x)).collect(),
        MatlabType::I16(v) => v.iter().map(|x| f64::from(*x)).collect(),
        MatlabType::U16(v) => v.iter().map(|x| f64::from(*x)).collect(),
        MatlabType::I32(v) => v.iter().map(|x| f64::from(*x)).collect(),
        MatlabType::U32(v) => v.iter().map(|x| f64::from(*x)).collect(),
        MatlabType::I64(v) => v.iter().map(|x| *x as f64).collect(),
        MatlabType::U64(v) => v.iter().map(|x| *x as f64).collect(),
        _ => return None,
    })
}

/// The variables of a MAT file: numeric arrays, and the others by name and class.
struct Variables {
    numeric: BTreeMap<String, Array>,
    /// Variables that are not numeric arrays: (name, class).
    other: Vec<(String, &'static str)>,
}

thread_local! {
    static CONTAINING: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// True while this thread runs `matrw`'s parser inside one of this module's readers: a
/// panic hook can stay silent, as the panic becomes an [`IoError`].
pub fn containing_panic() -> bool {
    CONTAINING.with(|c| c.get())
}

/// Runs a third-party parser, turning a panic into `Err` with [`containing_panic`] true
/// meanwhile (the CLI's hook stays silent).
pub(crate) fn contain<T>(f: impl FnOnce() -> T + std::panic::UnwindSafe) -> std::thread::Result<T> {
    CONTAINING.with(|c| c.set(true));
    let result = std::panic::catch_unwind(f);
    CONTAINING.with(|c| c.set(false));
    result
}

fn class_of(v: &MatVariable) -> &'static str {
    match v {
        MatVariable::NumericArray(a) if to_f64(&a.value).is_none() => "char or logical",
        MatVariable::NumericArray(_) => "numeric",
        MatVariable::SparseArray(_) => "sparse",
        MatVariable::StructureArray(_) | MatVariable::Structure(_) => "struct",
        MatVariable::CellArray(_) => "cell",
        _ => "unsupported",
    }
}

/// Parses MAT bytes with `matrw`. Its parser can panic on malformed input (an index
/// out of range, an allocation of a size read from the file); the panic is contained
/// here and reported as a malformed file.
/// matrw only reads a header text that starts `MATLAB 5.0 MAT-file, ` (with the
/// comma); the format leaves that text free, and `scipy.io.savemat` writes
/// `MATLAB 5.0 MAT-file Platform: posix, …`. The text carries nothing era uses, so a
/// copy with the comma put in (over the first two characters after `MAT-file`) is
/// given to matrw. `None` when the header is already in matrw's form.
fn matrw_header(bytes: &[u8]) -> Option<Vec<u8>> {
    const MAGIC: &[u8] = b"MATLAB 5.0 MAT-file";
    let after = bytes.strip_prefix(MAGIC)?;
    if after.starts_with(b", ") || bytes.len() < 128 {
        return None;
    }
    let mut copy = bytes.to_vec();
    copy[MAGIC.len()..MAGIC.len() + 2].copy_from_slice(b", ");
    Some(copy)
}

fn parse_variables(bytes: &[u8], path: &Path) -> Result<Variables, IoError> {
    if bytes.is_empty() {
        return Err(IoError::format(path, "", "the file is empty"));
    }
    if bytes.len() < 128 || !bytes.starts_with(b"MATLAB") {
        return Err(IoError::format(
            path,
            "",
            "not a MAT v5 file (no 128-byte 'MATLAB 5.0 MAT-file' header)",
        ));
    }
    if bytes.starts_with(b"MATLAB 7.3 MAT-file") {
        return Err(IoError::format(
            path,
            "",
            "MAT v7.3 (HDF5) files are not read: save with -v7 (the default) or -v6",
        ));
    }
    crate::mat_check::check(bytes)
        .map_err(|e| IoError::format(path, "", format!("not a readable MAT v5 file: {e}")))?;
    let patched = matrw_header(bytes);
    let bytes: &[u8] = patched.as_deref().unwrap_or(bytes);
    let parsed = contain(|| matrw::load_matfile_from_u8(bytes).map_err(|e| e.to_string()));
    let mut file =
        match parsed {
            Ok(Ok(file)) => file,
            Ok(Err(e)) => {
                return Err(IoError::format(
                    path,
                    "",
                    format!("not a readable MAT v5 file: {}", first_error_line(&e)),
                ))
            }
            Err(_) => return Err(IoError::format(
                path,
                "",
                "not a readable MAT v5 file: a variable is malformed (corrupt or truncated data)",
            )),
        };
    let names: Vec<String> = file.iter().map(|(k, _)| k.clone()).collect();
    let mut numeric = BTreeMap::new();
    let mut other = Vec::new();
    for name in names {
        match file.take(&name) {
            Some(MatVariable::NumericArray(a)) => match to_f64(&a.value) {
                Some(re) => {
                    let im = a.value_cmp.as_ref().and_then(to_f64);
                    numeric.insert(
                        name,
                        Array {
                            dim: a.dim.clone(),
                            im,
                            re,
                        },
                    );
                }
                None => other.push((name, "char or logical")),
            },
            Some(v) => other.push((name.clone(), class_of(&v))),
            None => {}
        }
    }
    Ok(Variables { numeric, other })
}

/// The first informative line of a `matrw`/`binrw` error (which spans many lines
/// with terminal colour codes).
fn first_error_line(text: &str) -> String {
    let mut plain = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        if c == '\u{1b}' {
            // Skip "ESC [ ... letter".
            for d in chars.by_ref() {
                if d.is_ascii_alphabetic() {
                    break;
                }
            }
        } else {
            plain.push(c);
        }
    }
    let line = plain
        .lines()
        .map(|l| l.trim_start_matches(|c: char| !c.is_alphanumeric()).trim())
        .find(|l| l.contains("Error:") || l.contains("error:"))
        .or_else(|| plain.lines().map(str::trim).find(|l| !l.is_empty()))
        .unwrap_or("unreadable")
        .trim_start_matches("0: ")
        .to_string();
    line.replace("Error: ", "")
}

/// The numeric arrays of MAT bytes; an error naming the other classes when there are
/// none.
fn numeric_arrays(bytes: &[u8], path: &Path) -> Result<BTreeMap<String, Array>, IoError> {
    let vars = parse_variables(bytes, path)?;
    if vars.numeric.is_empty() {
        return Err(unsupported_only(path, &vars));
    }
    Ok(vars.numeric)
}

fn unsupported_only(path: &Path, vars: &Variables) -> IoError {
    let listed = vars
        .other
        .iter()
        .map(|(n, c)| format!("{n} ({c})"))
        .collect::<Vec<_>>()
        .join(", ");
    IoError::format(
        path,
        "",
        if listed.is_empty() {
            "the file holds no variables".to_string()
        } else {
            format!("no numeric arrays; unsupported class: {listed}")
        },
    )
}

/// A real matrix from a MAT file: time histories, samples × channels.
#[derive(Debug, Clone, PartialEq)]
pub struct MatMatrix {
    /// The variable's name.
    pub name: String,
    /// Rows (samples).
    pub rows: usize,
    /// Columns (channels).
    pub cols: usize,
    /// Column-major values.
    pub values: Vec<f64>,
}

impl MatMatrix {
    /// Column `j` (0-based).
    pub fn column(&self, j: usize) -> &[f64] {
        &self.values[j * self.rows..(j + 1) * self.rows]
    }
}

/// Reads a real 2-D numeric variable (any numeric class, as f64): `variable` names it,
/// else the file must hold exactly one matrix (scalars and vectors of fewer than 2
/// rows aside).
///
/// # Errors
/// [`IoError`] naming the file and the variable: a missing name (with the list), several
/// candidates and no name, a complex, N-D or non-numeric variable, NaN or infinity
/// (row and column given).
pub fn read_mat_matrix(path: &Path, variable: Option<&str>) -> Result<MatMatrix, IoError> {
    let bytes = crate::input::read_input(path)?;
    parse_mat_matrix(&bytes, path, variable)
}

/// [`read_mat_matrix`] on bytes already read (`path` names them in messages).
///
/// # Errors
/// As [`read_mat_matrix`].
pub fn parse_mat_matrix(
    bytes: &[u8],
    path: &Path,
    variable: Option<&str>,
) -> Result<MatMatrix, IoError> {
    let vars = parse_variables(bytes, path)?;
    let describe = |vars: &Variables| {
        vars.numeric
            .iter()
            .map(|(n, a)| format!("{n} {:?}", a.dim))
            .chain(vars.other.iter().map(|(n, c)| format!("{n} ({c})")))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let name = match variable {
        Some(v) => {
            if let Some((_, class)) = vars.other.iter().find(|(n, _)| n == v) {
                return Err(IoError::format(
                    path,
                    format!("variable {v}: "),
                    format!("unsupported class {class}: a numeric matrix is needed"),
                ));
            }
            if !vars.numeric.contains_key(v) {
                return Err(IoError::format(
                    path,
                    "",
                    format!("no variable {v} (the file has: {})", describe(&vars)),
                ));
            }
            v.to_string()
        }
        None => {
            let candidates: Vec<&String> = vars
                .numeric
                .iter()
                .filter(|(_, a)| a.dim.len() == 2 && a.dim[0] >= 2)
                .map(|(n, _)| n)
                .collect();
            match candidates.as_slice() {
                [one] => (*one).clone(),
                [] if vars.numeric.is_empty() => return Err(unsupported_only(path, &vars)),
                [] => {
                    return Err(IoError::format(
                        path,
                        "",
                        format!(
                            "no matrix with 2 or more rows (the file has: {})",
                            describe(&vars)
                        ),
                    ))
                }
                _ => {
                    return Err(IoError::format(
                        path,
                        "",
                        format!(
                            "several matrices; name one with --variable (the file has: {})",
                            describe(&vars)
                        ),
                    ))
                }
            }
        }
    };
    let a = &vars.numeric[&name];
    let fail = |m: String| IoError::format(path, format!("variable {name}: "), m);
    if a.im.is_some() {
        return Err(fail("is complex: time histories must be real".into()));
    }
    if a.dim.len() != 2 {
        return Err(fail(format!(
            "has {} dimensions {:?}: a matrix is needed",
            a.dim.len(),
            a.dim
        )));
    }
    let (rows, cols) = (a.dim[0], a.dim[1]);
    if let Some(k) = a.re.iter().position(|v| !v.is_finite()) {
        return Err(fail(format!(
            "row {}, column {} is {} (samples must be finite)",
            k % rows.max(1) + 1,
            k / rows.max(1) + 1,
            a.re[k]
        )));
    }
    Ok(MatMatrix {
        name: name.clone(),
        rows,
        cols,
        values: a.re.clone(),
    })
}

/// Name, dimensions and class of every variable, for `era info`.
///
/// # Errors
/// [`IoError`] when the file is not a readable MAT v5 file.
pub fn list_variables(path: &Path) -> Result<Vec<(String, String)>, IoError> {
    let bytes = crate::input::read_input(path)?;
    list_variables_in(&bytes, path)
}

/// [`list_variables`] on bytes already read.
///
/// # Errors
/// As [`list_variables`].
pub fn list_variables_in(bytes: &[u8], path: &Path) -> Result<Vec<(String, String)>, IoError> {
    let vars = parse_variables(bytes, path)?;
    Ok(vars
        .numeric
        .iter()
        .map(|(n, a)| {
            let dims = a
                .dim
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join("x");
            (
                n.clone(),
                format!("{dims} {}", if a.im.is_some() { "complex" } else { "real" }),
            )
        })
        .chain(
            vars.other
                .iter()
                .map(|(n, c)| (n.clone(), format!("({c})"))),
        )
        .collect())
}

/// Parses MAT bytes as FRFs (for fuzzing and in-memory use); see [`read_frf_mat`].
///
/// # Errors
/// As [`read_frf_mat`].
pub fn parse_frf_mat(bytes: &[u8], path: &Path) -> Result<FrfFile, IoError> {
    parse_frf_mat_with(bytes, path, None, Quantity::Acceleration)
}

/// [`read_frf_mat`] on bytes already read; `path` names them in messages.
///
/// # Errors
/// As [`read_frf_mat`].
pub fn parse_frf_mat_with(
    bytes: &[u8],
    path: &Path,
    outputs: Option<usize>,
    quantity: Quantity,
) -> Result<FrfFile, IoError> {
    frf_from_arrays(path, &numeric_arrays(bytes, path)?, outputs, quantity)
}

fn scalar(vars: &BTreeMap<String, Array>, name: &str) -> Option<usize> {
    let a = vars.get(name)?;
    (a.re.len() == 1 && a.re[0] >= 1.0 && a.re[0].fract() == 0.0).then(|| a.re[0] as usize)
}

/// `xferIJ` or `xferI_J` → (I, J), 1-based; `Err(name)` when ambiguous.
fn xfer_indices(name: &str) -> Option<Result<(usize, usize), String>> {
    let rest = name.strip_prefix("xfer")?;
    if let Some((i, j)) = rest.split_once('_') {
        return match (i.parse::<usize>(), j.parse::<usize>()) {
            (Ok(i), Ok(j)) if i > 0 && j > 0 => Some(Ok((i, j))),
            _ => None,
        };
    }
    if !rest.chars().all(|c| c.is_ascii_digit()) || rest.is_empty() {
        return None;
    }
    if rest.len() == 2 {
        let d: Vec<usize> = rest.chars().map(|c| c as usize - '0' as usize).collect();
        return (d[0] > 0 && d[1] > 0).then_some(Ok((d[0], d[1])));
    }
    Some(Err(name.to_string()))
}

/// Reads FRFs from a MAT file (see the module doc for the layouts). `outputs` splits a
/// non-square `FRF` matrix when the file does not say; FRFs are tagged `quantity`.
///
/// # Errors
/// [`IoError`] naming the file and the variable: no recognised layout, missing or
/// duplicate pairs, ambiguous `xfer` names, lengths that disagree with `FreqV`, and the
/// frequency checks of [`FrfData`].
pub fn read_frf_mat(
    path: &Path,
    outputs: Option<usize>,
    quantity: Quantity,
) -> Result<FrfFile, IoError> {
    let bytes = crate::input::read_input(path)?;
    frf_from_arrays(path, &numeric_arrays(&bytes, path)?, outputs, quantity)
}

fn frf_from_arrays(
    path: &Path,
    vars: &BTreeMap<String, Array>,
    outputs: Option<usize>,
    quantity: Quantity,
) -> Result<FrfFile, IoError> {
    let fail = |variable: &str, message: String| {
        IoError::format(path, format!("variable {variable}: "), message)
    };
    let freq = vars.get("FreqV").ok_or_else(|| {
        IoError::format(
            path,
            "",
            format!(
                "no FreqV variable (the file has: {})",
                vars.keys().cloned().collect::<Vec<_>>().join(", ")
            ),
        )
    })?;
    let lines = freq.re.len();
    let frequency_hz = freq.re.clone();
    let mut notes = BTreeMap::new();
    let (q, p, values): (usize, usize, Vec<Complex64>) = if let Some(frf) = vars.get("FRF") {
        if frf.dim.len() != 2 || frf.dim[0] != lines {
            return Err(fail(
                "FRF",
                format!(
                    "is {:?}, expected {lines} lines (FreqV) x outputs·inputs columns",
                    frf.dim
                ),
            ));
        }
        let cols = frf.dim[1];
        let q = match (scalar(vars, "outputs"), outputs) {
            (Some(q), _) | (None, Some(q)) => q,
            (None, None) => {
                let r = (cols as f64).sqrt().round() as usize;
                if r * r != cols {
                    return Err(fail(
                        "FRF",
                        format!("has {cols} columns: say how many are outputs (--outputs)"),
                    ));
                }
                notes.insert(
                    "layout".to_string(),
                    format!("FRF + FreqV, assumed square {r} x {r}"),
                );
                r
            }
        };
        if q == 0 || cols % q != 0 {
            return Err(fail(
                "FRF",
                format!("has {cols} columns, not a multiple of {q} outputs"),
            ));
        }
        let p = cols / q;
        let mut values = vec![Complex64::new(0.0, 0.0); q * p * lines];
        for j in 0..p {
            for i in 0..q {
                let col = j * q + i;
                for k in 0..lines {
                    let at = col * lines + k;
                    values[(i * p + j) * lines + k] =
                        Complex64::new(frf.re[at], frf.im.as_ref().map_or(0.0, |v| v[at]));
                }
            }
        }
        notes
            .entry("layout".to_string())
            .or_insert_with(|| format!("FRF + FreqV, {q} x {p}"));
        (q, p, values)
    } else if vars.keys().any(|k| k.starts_with("xfer")) {
        let mut pairs = BTreeMap::new();
        let mut ambiguous = Vec::new();
        for (name, a) in vars.iter().filter(|(k, _)| k.starts_with("xfer")) {
            match xfer_indices(name) {
                Some(Ok(ij)) => {
                    if a.re.len() != lines {
                        return Err(fail(
                            name,
                            format!("has {} values, FreqV has {lines}", a.re.len()),
                        ));
                    }
                    pairs.insert(ij, a);
                }
                Some(Err(n)) => ambiguous.push(n),
                None => {}
            }
        }
        if !ambiguous.is_empty() {
            return Err(IoError::format(
                path,
                "",
                format!(
                    "ambiguous xfer names {} (indices of 10 and over need an underscore, e.g. xfer1_10)",
                    ambiguous.join(", ")
                ),
            ));
        }
        let q = pairs.keys().map(|k| k.0).max().unwrap_or(0);
        let p = pairs.keys().map(|k| k.1).max().unwrap_or(0);
        let missing: Vec<String> = (1..=q)
            .flat_map(|i| (1..=p).map(move |j| (i, j)))
            .filter(|ij| !pairs.contains_key(ij))
            .map(|(i, j)| format!("xfer{i}{j}"))
            .collect();
        if !missing.is_empty() {
            return Err(IoError::format(
                path,
                "",
                format!("missing pairs for a {q} x {p} set: {}", missing.join(", ")),
            ));
        }
        let mut values = vec![Complex64::new(0.0, 0.0); q * p * lines];
        for ((i, j), a) in &pairs {
            for k in 0..lines {
                values[((i - 1) * p + (j - 1)) * lines + k] =
                    Complex64::new(a.re[k], a.im.as_ref().map_or(0.0, |v| v[k]));
            }
        }
        notes.insert("layout".to_string(), format!("xferIJ + FreqV, {q} x {p}"));
        (q, p, values)
    } else if let Some((name, cube)) = vars
        .iter()
        .find(|(_, a)| a.dim.len() == 3 && a.dim[2] == lines)
    {
        let (q, p) = (cube.dim[0], cube.dim[1]);
        let mut values = vec![Complex64::new(0.0, 0.0); q * p * lines];
        for k in 0..lines {
            for j in 0..p {
                for i in 0..q {
                    let at = i + q * (j + p * k);
                    values[(i * p + j) * lines + k] =
                        Complex64::new(cube.re[at], cube.im.as_ref().map_or(0.0, |v| v[at]));
                }
            }
        }
        notes.insert(
            "layout".to_string(),
            format!("{name} ({q} x {p} x {lines}) + FreqV"),
        );
        (q, p, values)
    } else {
        return Err(IoError::format(
            path,
            "",
            format!(
                "no FRF layout found: expected FRF + FreqV, xferIJ + FreqV, or a q x p x lines array + FreqV (the file has: {})",
                vars.keys().cloned().collect::<Vec<_>>().join(", ")
            ),
        ));
    };
    let frf = FrfData::new(frequency_hz, q, p, values, quantity).map_err(|e| match e {
        EraError::NonUniformFrequencies { .. } | EraError::FirstLineNotZero { .. } => {
            fail("FreqV", e.to_string())
        }
        other => IoError::format(path, "", other.to_string()),
    })?;
    Ok(FrfFile {
        frf,
        quantity_given: false,
        metadata: notes,
        channels: None,
    })
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

    fn fixture(name: &str) -> std::path::PathBuf {
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures")
            .join(name)
    }

    /// The fixtures' FRF: column c (0-based, output-fastest), line k: (1 + k + 5c) + i(21 + k + 5c).
    fn expected(cols_offset_im: f64, i: usize, j: usize, q: usize, k: usize) -> Complex64 {
        let c = (j * q + i) as f64;
        Complex64::new(
            1.0 + k as f64 + 5.0 * c,
            cols_offset_im + 1.0 + k as f64 + 5.0 * c,
        )
    }

    #[test]
    fn reads_octave_files_in_every_layout() {
        for name in [
            "frf_v6.mat",
            "frf_v7.mat",
            "xfer_v7.mat",
            "cube_v7.mat",
            "frf_single.mat",
        ] {
            let f = read_frf_mat(&fixture(name), None, Quantity::Velocity)
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(
                (f.frf.outputs(), f.frf.inputs(), f.frf.lines()),
                (2, 2, 5),
                "{name}"
            );
            assert_eq!(f.frf.spacing_hz(), 0.5);
            for (i, j, k) in [(0, 0, 0), (1, 0, 3), (0, 1, 2), (1, 1, 4)] {
                assert_eq!(
                    f.frf.pair(i, j)[k],
                    expected(20.0, i, j, 2, k),
                    "{name} ({i},{j},{k})"
                );
            }
        }
        // A 3 x 2 set needs the split, from the caller when the file does not say.
        let err = read_frf_mat(&fixture("frf_3x2.mat"), None, Quantity::Velocity)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("frf_3x2.mat") && err.contains("6 columns") && err.contains("--outputs"),
            "{err}"
        );
        let f = read_frf_mat(&fixture("frf_3x2.mat"), Some(3), Quantity::Velocity).unwrap();
        assert_eq!((f.frf.outputs(), f.frf.inputs()), (3, 2));
        assert_eq!(f.frf.pair(2, 1)[4], expected(30.0, 2, 1, 3, 4));
    }

    #[test]
    fn refuses_ambiguous_missing_and_uneven() {
        let cases = [
            ("xfer_ambiguous.mat", "ambiguous xfer names xfer110"),
            ("xfer_missing.mat", "missing pairs for a 2 x 2 set: xfer22"),
            (
                "frf_uneven.mat",
                "variable FreqV: frequencies are not uniformly spaced",
            ),
        ];
        for (name, needle) in cases {
            let err = read_frf_mat(&fixture(name), None, Quantity::Velocity)
                .unwrap_err()
                .to_string();
            assert!(err.contains(name) && err.contains(needle), "{name}: {err}");
        }
        assert!(!looks_like_mat(&fixture("../../src/mat.rs")));
        assert!(looks_like_mat(&fixture("frf_v6.mat")));
    }

    #[test]
    fn our_frf_files_read_back_with_their_split() {
        let frf = truth_model_frf(None).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("frf.mat");
        write_frf_mat(&path, &frf).unwrap();
        let back = read_frf_mat(&path, None, Quantity::Displacement).unwrap();
        assert_eq!(back.frf, frf);
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
