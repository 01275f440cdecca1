//! MATLAB MAT files (v7: zlib-compressed level-5 format, MATLAB's default), written with
//! the `matrw` crate so that MATLAB, Octave and scipy load them with one line.
//!
//! - [`write_model_mat`]: `a, b, c, d, Ts` (`Ts = 0` for a continuous model, as
//!   `ss(a,b,c,d,0)` reads it) and the modal table `freq_hz`, `damping_ratio` (columns),
//!   so that `load model.mat; sys = ss(a,b,c,d,Ts)` works;
//! - [`write_frf_mat`]: the thesis's layout, `FRF` (lines × q·p, complex, column
//!   `(j−1)·q + i` is output i from input j, output-fastest) and `FreqV` (lines × 1, Hz),
//!   plus `outputs` and `inputs` so that the file says how to split the columns, and the
//!   facts the other formats carry: `quantity`, `response_unit`, `force_unit` (char) and
//!   the channel table as `output_nodes`, `output_directions`, `input_nodes`,
//!   `input_directions` (UFF direction codes: ±1..±3 translation X, Y, Z, ±4..±6
//!   rotation), so that CSV → MAT → UFF keeps what the file measured, in what units, where;
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
//!   The frequency variable is `FreqV` unless the caller names another
//!   ([`crate::frf_file::ReadOptions::frequency_variable`], `--freq-variable` in the CLI).
//!   The facts above are read back when present. Lines that start a whole number of
//!   increments above 0 Hz are padded with zero lines, as in every format
//!   ([`crate::frf_file::zero_start`]).
//!
//! Arrays are built with `matrw`'s `NumericArray::new` (column-major values and
//! dimensions), the one constructor it offers for arrays built at run time.

use crate::atomic::write_via;
use crate::frf_file::ReadOptions;
use crate::frf_file::{Channel, ChannelTable, Dof, FrfFile};
use crate::IoError;
use era::pipeline::modes::ModalParameters;
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

fn text(value: &str) -> MatVariable {
    let chars: Vec<char> = value.chars().collect();
    MatVariable::NumericArray(
        NumericArray::new(vec![1, chars.len()], MatlabType::UTF8(chars), None)
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
            .filter(|n| !back.numeric.contains_key(*n) && !back.text.contains_key(*n))
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

/// Writes FRFs as `FRF` + `FreqV` (the thesis's layout), with `outputs`, `inputs` and
/// `quantity`.
///
/// # Errors
/// [`IoError`] naming the file.
pub fn write_frf_mat(path: &Path, frf: &FrfData) -> Result<(), IoError> {
    save_atomic(path, frf_variables(frf))
}

/// Writes an FRF file's data and facts: [`write_frf_mat`]'s variables, plus
/// `response_unit` and `force_unit` when the metadata has them and the channel table
/// (`output_nodes`, `output_directions`, `input_nodes`, `input_directions`) when it has
/// one. Entity names are not kept (a UFF-only detail).
///
/// # Errors
/// [`IoError`] naming the file.
pub fn write_frf_mat_file(path: &Path, file: &FrfFile) -> Result<(), IoError> {
    let mut vars = frf_variables(&file.frf);
    for key in ["response_unit", "force_unit"] {
        if let Some(u) = file.metadata.get(key).filter(|u| !u.is_empty()) {
            vars.insert(key, text(u));
        }
    }
    if let Some(t) = &file.channels {
        let row = |cs: &[Channel], f: &dyn Fn(&Dof) -> i64| {
            let v: Vec<f64> = cs.iter().map(|c| f(&c.dof) as f64).collect();
            real(1, v.len(), |_, j| v[j])
        };
        vars.insert("output_nodes", row(&t.outputs, &|d| d.node));
        vars.insert("output_directions", row(&t.outputs, &|d| d.direction));
        vars.insert("input_nodes", row(&t.inputs, &|d| d.node));
        vars.insert("input_directions", row(&t.inputs, &|d| d.direction));
    }
    save_atomic(path, vars)
}

fn frf_variables(frf: &FrfData) -> MatFile {
    let (q, p, lines) = (frf.outputs(), frf.inputs(), frf.lines());
    let mut file = MatFile::new();
    file.insert(
        "FRF",
        complex(lines, q * p, |k, col| frf.pair(col % q, col / q)[k]),
    );
    file.insert("FreqV", real(lines, 1, |k, _| frf.frequency_hz()[k]));
    file.insert("outputs", real(1, 1, |_, _| q as f64));
    file.insert("inputs", real(1, 1, |_, _| p as f64));
    file.insert("quantity", text(frf.quantity().name()));
    file
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

/// The variables of a MAT file: numeric arrays, char arrays as text, and the others
/// (char arrays too) by name and class.
struct Variables {
    numeric: BTreeMap<String, Array>,
    text: BTreeMap<String, String>,
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
    let mut text = BTreeMap::new();
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
                None => {
                    if let MatlabType::UTF8(chars) | MatlabType::UTF16(chars) = &a.value {
                        text.insert(name.clone(), chars.iter().collect::<String>());
                    }
                    other.push((name, "char or logical"))
                }
            },
            Some(v) => other.push((name.clone(), class_of(&v))),
            None => {}
        }
    }
    Ok(Variables {
        numeric,
        text,
        other,
    })
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
        .chain(vars.other.iter().map(|(n, c)| match vars.text.get(n) {
            Some(t) => (
                n.clone(),
                format!("char '{}'", crate::text::escaped_message(t)),
            ),
            None => (n.clone(), format!("({c})")),
        }))
        .collect())
}

/// Parses MAT bytes as FRFs (for fuzzing and in-memory use); see [`read_frf_mat`].
///
/// # Errors
/// As [`read_frf_mat`].
pub fn parse_frf_mat(bytes: &[u8], path: &Path) -> Result<FrfFile, IoError> {
    parse_frf_mat_with(bytes, path, &ReadOptions::default())
}

/// [`read_frf_mat`] on bytes already read; `path` names them in messages.
///
/// # Errors
/// As [`read_frf_mat`].
pub fn parse_frf_mat_with(
    bytes: &[u8],
    path: &Path,
    opts: &ReadOptions,
) -> Result<FrfFile, IoError> {
    frf_from_variables(path, &frf_variables_of(bytes, path)?, opts)
}

/// The variables of MAT bytes; an error naming the other classes when none is numeric.
fn frf_variables_of(bytes: &[u8], path: &Path) -> Result<Variables, IoError> {
    let vars = parse_variables(bytes, path)?;
    if vars.numeric.is_empty() {
        return Err(unsupported_only(path, &vars));
    }
    Ok(vars)
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
    let opts = ReadOptions {
        default_quantity: quantity,
        outputs,
        ..ReadOptions::default()
    };
    parse_frf_mat_with(&bytes, path, &opts)
}

/// The channel table from `output_nodes`, `output_directions`, `input_nodes` and
/// `input_directions`; `None` when the file has none of them.
fn channels_of(
    path: &Path,
    vars: &BTreeMap<String, Array>,
    q: usize,
    p: usize,
) -> Result<Option<ChannelTable>, IoError> {
    const NAMES: [&str; 4] = [
        "output_nodes",
        "output_directions",
        "input_nodes",
        "input_directions",
    ];
    if NAMES.iter().all(|n| !vars.contains_key(*n)) {
        return Ok(None);
    }
    let whole = |name: &str, count: usize| -> Result<Vec<i64>, IoError> {
        let fail = |m: String| IoError::format(path, format!("variable {name}: "), m);
        let a = vars.get(name).ok_or_else(|| {
            IoError::format(
                path,
                "",
                format!("no {name} variable, though the file has part of a channel table ({}): write all four or none", NAMES.join(", ")),
            )
        })?;
        if a.re.len() != count {
            return Err(fail(format!(
                "has {} values, the FRFs have {count}",
                a.re.len()
            )));
        }
        a.re.iter()
            .map(|v| {
                (v.fract() == 0.0 && v.abs() < 1e15)
                    .then_some(*v as i64)
                    .ok_or_else(|| fail(format!("{v} is not a whole number")))
            })
            .collect()
    };
    let side = |nodes: &str, directions: &str, count: usize| -> Result<Vec<Channel>, IoError> {
        Ok(whole(nodes, count)?
            .into_iter()
            .zip(whole(directions, count)?)
            .map(|(node, direction)| Channel {
                dof: Dof { node, direction },
                entity: "NONE".into(),
            })
            .collect())
    };
    Ok(Some(ChannelTable {
        outputs: side(NAMES[0], NAMES[1], q)?,
        inputs: side(NAMES[2], NAMES[3], p)?,
    }))
}

/// An FRF error about one variable: `variable NAME: message`.
fn variable_error(path: &Path, variable: &str, message: String) -> IoError {
    IoError::format(path, format!("variable {variable}: "), message)
}

/// Every variable of the file, for messages: `FRF 100x4, FreqV 100x1, label (char)`.
fn listing(all: &Variables) -> String {
    all.numeric
        .iter()
        .map(|(n, a)| {
            let dims = a.dim.iter().map(usize::to_string).collect::<Vec<_>>();
            format!("{n} {}", dims.join("x"))
        })
        .chain(all.other.iter().map(|(n, c)| format!("{n} ({c})")))
        .collect::<Vec<_>>()
        .join(", ")
}

/// FRFs pair-major (pair `(i, j)` from `(i · p + j) · lines`), `q` outputs by `p`
/// inputs, with the layout they were read from (a note of the file).
struct Layout {
    q: usize,
    p: usize,
    values: Vec<Complex64>,
    note: String,
}

/// An FRF file from its variables: the frequencies, the FRFs in one of three layouts
/// (`FRF` matrix, `xferIJ` pairs, a `q x p x lines` array), lines from 0 Hz, then the
/// facts a file of ours carries (quantity, units, channel table).
fn frf_from_variables(
    path: &Path,
    all: &Variables,
    opts: &ReadOptions,
) -> Result<FrfFile, IoError> {
    let vars = &all.numeric;
    let (frequency_name, frequency_hz) = frequency_lines(path, all, opts)?;
    let lines = frequency_hz.len();
    let layout = if let Some(frf) = vars.get("FRF") {
        frf_matrix(path, vars, frf, lines, frequency_name, opts.outputs)?
    } else if vars.keys().any(|k| k.starts_with("xfer")) {
        xfer_pairs(path, vars, lines, frequency_name)?
    } else if let Some((name, cube)) = vars
        .iter()
        .find(|(_, a)| a.dim.len() == 3 && a.dim[2] == lines)
    {
        frf_cube(name, cube, lines)
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
    let Layout {
        q,
        p,
        mut values,
        note,
    } = layout;
    let mut notes = BTreeMap::new();
    notes.insert("layout".to_string(), note);
    // Lines from 0 Hz, as in every format.
    let mut frequency_hz = frequency_hz;
    let location = format!("variable {frequency_name}: ");
    if let Some(start) = crate::frf_file::zero_start(path, &location, &frequency_hz, q * p)? {
        values = start.pad_values(&values, q * p);
        crate::frf_file::add_note(&mut notes, start.note());
        frequency_hz = start.frequency_hz;
    }
    // The facts a file of ours carries.
    let (quantity, quantity_given) = quantity_of(path, all, opts.default_quantity)?;
    for key in ["response_unit", "force_unit"] {
        if let Some(u) = all.text.get(key) {
            notes.insert(key.to_string(), u.clone());
        }
    }
    let channels = channels_of(path, vars, q, p)?;
    let frf = FrfData::new(frequency_hz, q, p, values, quantity).map_err(|e| match e {
        EraError::NonUniformFrequencies { .. } | EraError::FirstLineNotZero { .. } => {
            variable_error(path, frequency_name, e.to_string())
        }
        other => IoError::format(path, "", other.to_string()),
    })?;
    Ok(FrfFile {
        frf,
        quantity_given,
        metadata: notes,
        channels,
    })
}

/// The frequency variable's name and its lines (Hz): `FreqV` unless the options name
/// another; when it is missing, the message says what the file looks like instead (a
/// state-space model, time histories, or FRFs under another name).
fn frequency_lines<'a>(
    path: &Path,
    all: &Variables,
    opts: &'a ReadOptions,
) -> Result<(&'a str, Vec<f64>), IoError> {
    let vars = &all.numeric;
    let frequency_name = opts.frequency_variable.as_deref().unwrap_or("FreqV");
    let freq = vars.get(frequency_name).ok_or_else(|| {
        IoError::format(
            path,
            "",
            match &opts.frequency_variable {
                Some(v) => format!("no numeric variable {v} (the file has: {})", listing(all)),
                None if ["a", "b", "c", "d"].iter().all(|k| vars.contains_key(*k)) => format!(
                    "holds a state-space model (the file has: {}), not FRFs: give the FRF file (FRF + FreqV, xferIJ + FreqV, or a q x p x lines array + FreqV)",
                    listing(all)
                ),
                // Only real arrays and no FRF name: time histories, most likely.
                None if vars.values().all(|a| a.im.is_none())
                    && !vars.contains_key("FRF")
                    && !vars.keys().any(|k| k.starts_with("xfer")) =>
                {
                    format!(
                        "no FreqV variable and no complex array (the file has: {}): real matrices like these are time histories; {}; if the file holds FRFs with the frequencies under another name, give it with --freq-variable NAME",
                        listing(all),
                        crate::frf_file::time_hint(path)
                    )
                }
                None => format!(
                    "no FreqV variable, the frequencies in Hz (the file has: {}): if they are under another name, give it with --freq-variable NAME",
                    listing(all)
                ),
            },
        )
    })?;
    if freq.im.is_some() || freq.dim.iter().filter(|d| **d > 1).count() > 1 {
        return Err(variable_error(
            path,
            frequency_name,
            format!(
                "is {}{:?}: the frequencies must be a real vector (Hz)",
                if freq.im.is_some() { "complex " } else { "" },
                freq.dim
            ),
        ));
    }
    Ok((frequency_name, freq.re.clone()))
}

/// The `FRF` matrix: `lines` rows, `q · p` columns with column `j · q + i` the pair
/// `(i, j)`; `q` from the file's `outputs`, else the options, else a square set.
fn frf_matrix(
    path: &Path,
    vars: &BTreeMap<String, Array>,
    frf: &Array,
    lines: usize,
    frequency_name: &str,
    outputs: Option<usize>,
) -> Result<Layout, IoError> {
    if frf.dim.len() != 2 || frf.dim[0] != lines {
        return Err(variable_error(
            path,
            "FRF",
            format!(
                "is {:?}, expected {lines} lines ({frequency_name}) x outputs·inputs columns",
                frf.dim
            ),
        ));
    }
    let cols = frf.dim[1];
    let mut square_note = None;
    let q = match (scalar(vars, "outputs"), outputs) {
        (Some(q), _) | (None, Some(q)) => q,
        (None, None) => {
            let r = (cols as f64).sqrt().round() as usize;
            if r * r != cols {
                return Err(variable_error(
                    path,
                    "FRF",
                    format!("has {cols} columns: say how many are outputs (--outputs)"),
                ));
            }
            square_note = Some(format!("FRF + FreqV, assumed square {r} x {r}"));
            r
        }
    };
    if q == 0 || !cols.is_multiple_of(q) {
        return Err(variable_error(
            path,
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
    let note = square_note.unwrap_or_else(|| format!("FRF + FreqV, {q} x {p}"));
    Ok(Layout { q, p, values, note })
}

/// One variable `xferIJ` (or `xferI_J`) per pair, every pair of the `q x p` set present.
fn xfer_pairs(
    path: &Path,
    vars: &BTreeMap<String, Array>,
    lines: usize,
    frequency_name: &str,
) -> Result<Layout, IoError> {
    let mut pairs = BTreeMap::new();
    let mut ambiguous = Vec::new();
    for (name, a) in vars.iter().filter(|(k, _)| k.starts_with("xfer")) {
        match xfer_indices(name) {
            Some(Ok(ij)) => {
                if a.re.len() != lines {
                    return Err(variable_error(
                        path,
                        name,
                        format!("has {} values, {frequency_name} has {lines}", a.re.len()),
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
    let note = format!("xferIJ + FreqV, {q} x {p}");
    Ok(Layout { q, p, values, note })
}

/// A `q x p x lines` array (MATLAB's column-major order: `i` fastest, then `j`, then `k`).
fn frf_cube(name: &str, cube: &Array, lines: usize) -> Layout {
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
    let note = format!("{name} ({q} x {p} x {lines}) + FreqV");
    Layout { q, p, values, note }
}

/// The file's `quantity` text variable, or the default (and whether the file said).
fn quantity_of(
    path: &Path,
    all: &Variables,
    default: Quantity,
) -> Result<(Quantity, bool), IoError> {
    match all.text.get("quantity") {
        Some(q) => Ok((
            Quantity::parse(q).ok_or_else(|| {
                variable_error(
                    path,
                    "quantity",
                    format!("unknown quantity '{q}' (acceleration, velocity or displacement)"),
                )
            })?,
            true,
        )),
        None => Ok((default, false)),
    }
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
    fn our_frf_files_keep_quantity_units_and_channels() {
        let frf = truth_model_frf(None)
            .unwrap()
            .with_quantity(Quantity::Velocity);
        let mut table = ChannelTable::numbered(3, 3);
        table.outputs[1].dof = Dof {
            node: 11,
            direction: -2,
        };
        table.inputs[2].dof = Dof {
            node: 101,
            direction: 5,
        };
        let metadata = [("response_unit", "m/s"), ("force_unit", "N")]
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        let file = FrfFile {
            frf: frf.clone(),
            quantity_given: true,
            metadata,
            channels: Some(table.clone()),
        };
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("frf.mat");
        write_frf_mat_file(&path, &file).unwrap();
        let back = read_frf_mat(&path, None, Quantity::Displacement).unwrap();
        assert_eq!(back.frf, frf);
        assert!(back.quantity_given);
        assert_eq!(back.metadata["response_unit"], "m/s");
        assert_eq!(back.metadata["force_unit"], "N");
        assert_eq!(back.channels, Some(table));
        let listed = list_variables(&path).unwrap();
        assert!(
            listed.contains(&("force_unit".to_string(), "char 'N'".to_string())),
            "{listed:?}"
        );
    }

    /// A MAT file of a 1 x 1 FRF `(k+1) + 0i` with the frequencies under `name`.
    fn frf_with_frequencies(dir: &std::path::Path, name: &str, hz: &[f64]) -> std::path::PathBuf {
        let mut file = MatFile::new();
        file.insert(
            "FRF",
            complex(hz.len(), 1, |k, _| Complex64::new(k as f64 + 1.0, 0.0)),
        );
        file.insert(name, real(hz.len(), 1, |k, _| hz[k]));
        let path = dir.join(format!("{name}.mat"));
        save_atomic(&path, file).unwrap();
        path
    }

    #[test]
    fn the_frequency_variable_can_be_named_and_late_starts_are_padded() {
        let dir = tempfile::tempdir().unwrap();
        let path = frf_with_frequencies(dir.path(), "f", &[2.0, 3.0, 4.0]);
        let e = read_frf_mat(&path, None, Quantity::Velocity)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("no FreqV variable") && e.contains("f 3x1") && e.contains("--freq-variable"),
            "{e}"
        );
        let opts = ReadOptions {
            frequency_variable: Some("f".into()),
            ..ReadOptions::default()
        };
        let bytes = std::fs::read(&path).unwrap();
        let f = parse_frf_mat_with(&bytes, &path, &opts).unwrap();
        assert_eq!(f.frf.frequency_hz(), &[0.0, 1.0, 2.0, 3.0, 4.0]);
        assert_eq!(f.frf.pair(0, 0)[1], Complex64::new(0.0, 0.0));
        assert_eq!(f.frf.pair(0, 0)[2], Complex64::new(1.0, 0.0));
        assert!(f.metadata["notes"].contains("2 lines below were added as zeros"));
        let named_wrong = ReadOptions {
            frequency_variable: Some("freq".into()),
            ..ReadOptions::default()
        };
        let e = parse_frf_mat_with(&bytes, &path, &named_wrong)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("no numeric variable freq") && e.contains("FRF 3x1"),
            "{e}"
        );
        // Off the grid: refused, with the remedy.
        let path = frf_with_frequencies(dir.path(), "FreqV", &[0.5, 1.25, 2.0]);
        let e = read_frf_mat(&path, None, Quantity::Velocity)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("variable FreqV: the first line is 0.5 Hz")
                && e.contains("export the FRFs from 0 Hz"),
            "{e}"
        );
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
