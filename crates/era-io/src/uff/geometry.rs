//! Reading a test geometry from UFF: nodes (datasets 15 and 2411), trace lines (82)
//! and coordinate systems (18 and 2420), in ASCII. Records of other datasets, binary
//! ones (58b) included, are skipped and counted in the geometry's notes.
//!
//! Each line is read at the columns of the definition first (`4I10,1P3E13.5` for a
//! node of dataset 15, `1P3D25.16` for a 2411 position, `8I10` for the nodes of a trace
//! line); when a field does not parse at its columns and the line splits at blanks into
//! exactly the numbers expected, that reading is used (free-format writers). Otherwise
//! the error names the line, the field and its columns.
//!
//! - Dataset 15 gives each node in its *definition* system, converted here to global.
//! - Dataset 2411 gives positions "in the part coordinate system", which is the global
//!   frame; its export system number is not applied again.
//! - Dataset 18 (method 1) defines a system by its origin, a point on +x and a point
//!   in the +xz plane, given in a reference system (resolved in turn, cycles refused).
//! - Dataset 2420 gives a 4 × 3 matrix: rows 1–3 the x, y, z axes, row 4 the origin, in
//!   the part frame.
//! - Dataset 82: a trace line's node list, where 0 lifts the pen (a move, not a line).

use super::parse::{closing_after, columns, is_delimiter, parse_int, parse_real};
use super::trim_bytes;
use crate::geometry::{CoordinateSystem, Geometry, Node, Origins, SystemKind, TraceLine};
use crate::IoError;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// A record's line: 1-based number and text.
type Line<'a> = (usize, &'a [u8]);

/// The lines of one ASCII record of a geometry dataset.
struct Record<'a> {
    dataset: i64,
    /// Line of its opening `-1`.
    open: usize,
    lines: Vec<Line<'a>>,
}

const GEOMETRY_DATASETS: [i64; 5] = [15, 2411, 82, 18, 2420];

/// Lines of a file, numbered from 1.
struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    number: usize,
}

impl<'a> Cursor<'a> {
    fn next(&mut self) -> Option<Line<'a>> {
        let rest = self.bytes.get(self.pos..).filter(|r| !r.is_empty())?;
        let (text, advance) = match memchr::memchr(b'\n', rest) {
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        self.pos += advance;
        self.number += 1;
        Some((self.number, text.strip_suffix(b"\r").unwrap_or(text)))
    }
}

/// Splits the file into records, keeping the lines of geometry datasets only.
fn records<'a>(
    bytes: &'a [u8],
    path: &Path,
    skipped: &mut BTreeMap<i64, usize>,
) -> Result<Vec<Record<'a>>, IoError> {
    let mut c = Cursor {
        bytes,
        pos: 0,
        number: 0,
    };
    let mut out = Vec::new();
    loop {
        let open = loop {
            match c.next() {
                None => return Ok(out),
                Some((_, t)) if trim_bytes(t).is_empty() => continue,
                Some(l) => break l,
            }
        };
        if !is_delimiter(open.1) {
            return Err(IoError::at(
                path,
                open.0,
                "",
                format!(
                    "expected '    -1' to open a record, found '{}'",
                    super::parse::shorten(open.1)
                ),
            ));
        }
        let Some(id) = c.next() else {
            return Err(IoError::at(
                path,
                open.0,
                "",
                "the file ends after a record's opening -1".into(),
            ));
        };
        let dataset = parse_int(columns(id.1, 0, 6)).ok_or_else(|| {
            IoError::at(
                path,
                id.0,
                "",
                format!(
                    "expected a dataset number in columns 1-6, found '{}'",
                    super::parse::shorten(id.1)
                ),
            )
        })?;
        if matches!(id.1.get(6), Some(b'b' | b'B')) {
            // A binary record: its byte count (columns 32-43), then a closing -1 after
            // that many bytes from the start of some line of its ASCII header.
            let announced = parse_int(columns(id.1, 31, 12))
                .and_then(|n| usize::try_from(n).ok())
                .unwrap_or(0);
            let mut at = c.pos;
            let end = loop {
                if at >= bytes.len() {
                    return Err(IoError::at(
                        path,
                        open.0,
                        "",
                        format!("the binary record of dataset {dataset} has no closing -1 (truncated record)"),
                    ));
                }
                if let Some(end) = closing_after(bytes, at.saturating_add(announced)) {
                    break end;
                }
                match memchr::memchr(b'\n', &bytes[at..]) {
                    Some(i) => at += i + 1,
                    None => at = bytes.len(),
                }
            };
            c.number += memchr::memchr_iter(b'\n', &bytes[c.pos..end]).count();
            c.pos = end;
            *skipped.entry(dataset).or_insert(0) += 1;
            continue;
        }
        let keep = GEOMETRY_DATASETS.contains(&dataset);
        let mut lines = Vec::new();
        loop {
            match c.next() {
                None => {
                    return Err(IoError::at(
                        path,
                        open.0,
                        "",
                        format!(
                            "the record of dataset {dataset} has no closing -1 (truncated record)"
                        ),
                    ))
                }
                Some((_, t)) if is_delimiter(t) => break,
                Some(l) if keep => lines.push(l),
                Some(_) => {}
            }
        }
        if keep {
            out.push(Record {
                dataset,
                open: open.0,
                lines,
            });
        } else {
            *skipped.entry(dataset).or_insert(0) += 1;
        }
    }
}

/// A field of a fixed-format line.
#[derive(Clone, Copy)]
enum Field {
    Int(&'static str, usize),
    Real(&'static str, usize),
}

/// The integers and reals of one line, in order of their kind.
struct Numbers {
    ints: Vec<i64>,
    reals: Vec<f64>,
}

/// Where a fixed-column reading failed: start, width, field, what was expected, text.
type Misfit = (usize, usize, &'static str, &'static str, String);

fn fixed(text: &[u8], spec: &[Field]) -> Result<Numbers, Misfit> {
    let mut n = Numbers {
        ints: Vec::new(),
        reals: Vec::new(),
    };
    let mut at = 0;
    for f in spec {
        let (name, width) = match *f {
            Field::Int(name, w) | Field::Real(name, w) => (name, w),
        };
        let cell = columns(text, at, width);
        let (ok, want) = match f {
            Field::Int(..) => (parse_int(cell).map(|v| n.ints.push(v)), "an integer"),
            Field::Real(..) => (parse_real(cell).map(|v| n.reals.push(v)), "a real number"),
        };
        if ok.is_none() {
            let found = String::from_utf8_lossy(cell).into_owned();
            return Err((at, width, name, want, found));
        }
        at += width;
    }
    let rest = text.get(at..).unwrap_or_default();
    if !trim_bytes(rest).is_empty() {
        let found = String::from_utf8_lossy(rest).into_owned();
        return Err((at, rest.len(), "end of the line", "nothing more", found));
    }
    Ok(n)
}

fn free(text: &[u8], spec: &[Field]) -> Option<Numbers> {
    let tokens: Vec<&[u8]> = text
        .split(|b| b.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
        .collect();
    if tokens.len() != spec.len() {
        return None;
    }
    let mut n = Numbers {
        ints: Vec::new(),
        reals: Vec::new(),
    };
    for (t, f) in tokens.iter().zip(spec) {
        match f {
            Field::Int(..) => n.ints.push(parse_int(t)?),
            Field::Real(..) => n.reals.push(parse_real(t)?),
        }
    }
    Some(n)
}

/// The numbers of `line` by `spec`: at the fixed columns, or split at blanks.
fn numbers(path: &Path, line: Line, spec: &[Field], what: &str) -> Result<Numbers, IoError> {
    match fixed(line.1, spec) {
        Ok(n) => Ok(n),
        Err((at, width, name, want, found)) => free(line.1, spec).ok_or_else(|| {
            IoError::at(
                path,
                line.0,
                "",
                format!(
                    "{what} ({name}), columns {}-{}: expected {want}, found '{}' (check the field widths)",
                    at + 1,
                    at + width,
                    crate::text::escaped(found.trim())
                ),
            )
        }),
    }
}

/// `count` lines from `lines[at..]`, or an error naming the record as truncated.
fn take<'l, 'a>(
    path: &Path,
    r: &'l Record<'a>,
    at: usize,
    count: usize,
    what: &str,
) -> Result<&'l [Line<'a>], IoError> {
    r.lines.get(at..at + count).ok_or_else(|| {
        IoError::at(
            path,
            r.open,
            "",
            format!(
                "dataset {}: the record ends inside {what} (truncated record)",
                r.dataset
            ),
        )
    })
}

fn xyz(r: &[f64]) -> [f64; 3] {
    [r[0], r[1], r[2]]
}

/// A node as read: its id, definition system, coordinates there, displacement system,
/// line, and whether the coordinates are global already (2411).
struct RawNode {
    node: Node,
    definition: i64,
    global: bool,
    line: usize,
}

/// A dataset-18 system before its reference is resolved.
struct Raw18 {
    id: i64,
    kind: SystemKind,
    reference: i64,
    name: String,
    points: [[f64; 3]; 3],
    line: usize,
}

const NODE15: [Field; 7] = [
    Field::Int("node label", 10),
    Field::Int("definition coordinate system", 10),
    Field::Int("displacement coordinate system", 10),
    Field::Int("color", 10),
    Field::Real("x", 13),
    Field::Real("y", 13),
    Field::Real("z", 13),
];
const NODE2411: [Field; 4] = [
    Field::Int("node label", 10),
    Field::Int("export coordinate system", 10),
    Field::Int("displacement coordinate system", 10),
    Field::Int("color", 10),
];
const XYZ25: [Field; 3] = [
    Field::Real("x", 25),
    Field::Real("y", 25),
    Field::Real("z", 25),
];
const XYZ13: [Field; 3] = [
    Field::Real("x", 13),
    Field::Real("y", 13),
    Field::Real("z", 13),
];
const SIX13: [Field; 6] = [
    Field::Real("origin x", 13),
    Field::Real("origin y", 13),
    Field::Real("origin z", 13),
    Field::Real("+x point x", 13),
    Field::Real("+x point y", 13),
    Field::Real("+x point z", 13),
];

fn nodes15(path: &Path, r: &Record, out: &mut Vec<RawNode>) -> Result<(), IoError> {
    for &line in r.lines.iter().filter(|l| !trim_bytes(l.1).is_empty()) {
        let n = numbers(path, line, &NODE15, "dataset 15 node")?;
        out.push(RawNode {
            node: Node {
                id: n.ints[0],
                xyz: xyz(&n.reals),
                displacement_system: n.ints[2],
            },
            definition: n.ints[1],
            global: false,
            line: line.0,
        });
    }
    Ok(())
}

fn nodes2411(path: &Path, r: &Record, out: &mut Vec<RawNode>) -> Result<(), IoError> {
    let lines: Vec<Line> = r
        .lines
        .iter()
        .copied()
        .filter(|l| !trim_bytes(l.1).is_empty())
        .collect();
    if !lines.len().is_multiple_of(2) {
        let last = lines.last().map_or(r.open, |l| l.0);
        return Err(IoError::at(
            path,
            last,
            "",
            "dataset 2411: a node label line without its coordinate line (truncated record)".into(),
        ));
    }
    for pair in lines.chunks_exact(2) {
        let head = numbers(path, pair[0], &NODE2411, "dataset 2411 node")?;
        let at = numbers(path, pair[1], &XYZ25, "dataset 2411 coordinates")?;
        out.push(RawNode {
            node: Node {
                id: head.ints[0],
                xyz: xyz(&at.reals),
                displacement_system: head.ints[2],
            },
            definition: head.ints[1],
            global: true,
            line: pair[0].0,
        });
    }
    Ok(())
}

/// The trace lines of a dataset-82 record (usually one; several are read in turn).
fn traces82(
    path: &Path,
    r: &Record,
    out: &mut Vec<TraceLine>,
    at_line: &mut Vec<usize>,
) -> Result<(), IoError> {
    const HEAD: [Field; 3] = [
        Field::Int("trace line number", 10),
        Field::Int("number of nodes", 10),
        Field::Int("color", 10),
    ];
    let mut k = 0;
    while k < r.lines.len() {
        if trim_bytes(r.lines[k].1).is_empty() {
            k += 1;
            continue;
        }
        let head = numbers(path, r.lines[k], &HEAD, "dataset 82 record 1")?;
        let (id, count) = (head.ints[0], head.ints[1]);
        let name_line = take(path, r, k + 1, 1, "the trace line's name")?[0];
        let name = String::from_utf8_lossy(trim_bytes(name_line.1)).into_owned();
        // At most 8 nodes a line: a count beyond what the record holds is refused
        // before anything is allocated for it.
        let room = (r.lines.len() - k - 2) * 8;
        let count = usize::try_from(count)
            .ok()
            .filter(|c| *c <= room)
            .ok_or_else(|| {
                IoError::at(
                    path,
                    r.lines[k].0,
                    "",
                    format!(
                        "dataset 82: trace line {id} announces {count} nodes; the record holds at most {room}"
                    ),
                )
            })?;
        let mut ids = Vec::with_capacity(count);
        let mut j = k + 2;
        while ids.len() < count {
            let line = take(path, r, j, 1, "the trace line's nodes")?[0];
            let want = (count - ids.len()).min(8);
            // Simcenter Testlab pads the last line with zeros past the count: pen
            // lifts, which draw nothing, so they are read and dropped.
            let present = line
                .1
                .split(|b| b.is_ascii_whitespace())
                .filter(|t| !t.is_empty())
                .count()
                .clamp(want, 8);
            let spec: Vec<Field> = (0..present).map(|_| Field::Int("node", 10)).collect();
            let values = numbers(path, line, &spec, "dataset 82 nodes")?.ints;
            if values[want..].iter().any(|v| *v != 0) {
                return Err(IoError::at(
                    path,
                    line.0,
                    "",
                    format!(
                        "dataset 82: trace line {id} has more nodes than the {count} it announces"
                    ),
                ));
            }
            ids.extend_from_slice(&values[..want]);
            j += 1;
        }
        if let Some(bad) = ids.iter().find(|v| **v < 0) {
            return Err(IoError::at(
                path,
                r.lines[k].0,
                "",
                format!("dataset 82: trace line {id} names node {bad}; node numbers are positive (0 lifts the pen)"),
            ));
        }
        let strokes: Vec<Vec<i64>> = ids
            .split(|v| *v == 0)
            .filter(|s| !s.is_empty())
            .map(<[i64]>::to_vec)
            .collect();
        out.push(TraceLine { id, name, strokes });
        at_line.push(r.lines[k].0);
        k = j;
    }
    Ok(())
}

fn systems18(path: &Path, r: &Record, out: &mut Vec<Raw18>) -> Result<(), IoError> {
    const HEAD: [Field; 5] = [
        Field::Int("coordinate system number", 10),
        Field::Int("coordinate system type", 10),
        Field::Int("reference coordinate system", 10),
        Field::Int("color", 10),
        Field::Int("method of definition", 10),
    ];
    let lines: Vec<Line> = r.lines.to_vec();
    let mut k = 0;
    while k < lines.len() {
        if trim_bytes(lines[k].1).is_empty() {
            k += 1;
            continue;
        }
        let group = take(path, r, k, 4, "a coordinate system")?;
        let head = numbers(path, group[0], &HEAD, "dataset 18 record 1")?;
        let [id, code, reference, _, method] = head.ints[..] else {
            unreachable!("five integers were parsed")
        };
        let kind = SystemKind::from_code(code).ok_or_else(|| {
            IoError::at(
                path,
                group[0].0,
                "",
                format!("dataset 18: coordinate system {id} has type {code}; expected 0 (Cartesian), 1 (cylindrical) or 2 (spherical)"),
            )
        })?;
        if method != 1 {
            return Err(IoError::at(
                path,
                group[0].0,
                "",
                format!("dataset 18: coordinate system {id} has method of definition {method}; only 1 (origin, +x axis, +xz plane) is defined"),
            ));
        }
        let name = String::from_utf8_lossy(trim_bytes(group[1].1)).into_owned();
        let a = numbers(path, group[2], &SIX13, "dataset 18 record 3")?;
        let b = numbers(path, group[3], &XYZ13, "dataset 18 record 3 (+xz point)")?;
        out.push(Raw18 {
            id,
            kind,
            reference,
            name,
            points: [xyz(&a.reals), xyz(&a.reals[3..]), xyz(&b.reals)],
            line: group[0].0,
        });
        k += 4;
    }
    Ok(())
}

fn systems2420(
    path: &Path,
    r: &Record,
    out: &mut Vec<(CoordinateSystem, usize)>,
) -> Result<(), IoError> {
    const HEAD: [Field; 3] = [
        Field::Int("coordinate system label", 10),
        Field::Int("coordinate system type", 10),
        Field::Int("color", 10),
    ];
    let part = take(path, r, 0, 2, "the part UID and name")?;
    numbers(
        path,
        part[0],
        &[Field::Int("part UID", 10)],
        "dataset 2420 record 1",
    )?;
    let mut k = 2;
    while k < r.lines.len() {
        if trim_bytes(r.lines[k].1).is_empty() {
            k += 1;
            continue;
        }
        let group = take(path, r, k, 6, "a coordinate system")?;
        let head = numbers(path, group[0], &HEAD, "dataset 2420 record 3")?;
        let (id, code) = (head.ints[0], head.ints[1]);
        let kind = SystemKind::from_code(code).ok_or_else(|| {
            IoError::at(
                path,
                group[0].0,
                "",
                format!("dataset 2420: coordinate system {id} has type {code}; expected 0 (Cartesian), 1 (cylindrical) or 2 (spherical)"),
            )
        })?;
        let name = String::from_utf8_lossy(trim_bytes(group[1].1)).into_owned();
        let mut rows = [[0.0; 3]; 4];
        for (row, line) in rows.iter_mut().zip(&group[2..6]) {
            *row = xyz(&numbers(path, *line, &XYZ25, "dataset 2420 transformation matrix")?.reals);
        }
        out.push((
            CoordinateSystem {
                id,
                name,
                kind,
                origin: rows[3],
                axes: [rows[0], rows[1], rows[2]],
            },
            group[0].0,
        ));
        k += 6;
    }
    Ok(())
}

/// Dataset-18 systems in the global frame: each reference resolved first.
fn resolve18(
    path: &Path,
    raw: &[Raw18],
    known: &mut HashMap<i64, CoordinateSystem>,
) -> Result<(), IoError> {
    let by_id: HashMap<i64, usize> = raw.iter().enumerate().map(|(k, s)| (s.id, k)).collect();
    for start in 0..raw.len() {
        // Follow the references to a known system, then resolve back down the chain.
        let mut chain = vec![start];
        let mut on_chain = std::collections::HashSet::from([start]);
        loop {
            let s = &raw[*chain.last().expect("not empty")];
            if s.reference == 0 || known.contains_key(&s.reference) || known.contains_key(&s.id) {
                break;
            }
            let Some(&next) = by_id.get(&s.reference) else {
                return Err(IoError::at(
                    path,
                    s.line,
                    "",
                    format!(
                        "dataset 18: coordinate system {} refers to system {}, which is not defined",
                        s.id, s.reference
                    ),
                ));
            };
            if !on_chain.insert(next) {
                return Err(IoError::at(
                    path,
                    s.line,
                    "",
                    format!(
                        "dataset 18: coordinate system {} refers to itself through its references",
                        s.id
                    ),
                ));
            }
            chain.push(next);
        }
        for &k in chain.iter().rev() {
            let s = &raw[k];
            if known.contains_key(&s.id) {
                continue;
            }
            let place = |p: [f64; 3]| match known.get(&s.reference) {
                Some(r) => r.to_global(p),
                None => p,
            };
            let [o, x, xz] = s.points.map(place);
            let system = CoordinateSystem::from_points(s.id, s.name.clone(), s.kind, o, x, xz)
                .ok_or_else(|| {
                    IoError::at(
                        path,
                        s.line,
                        "",
                        format!("dataset 18: coordinate system {}: its origin, +x point and +xz point do not span a plane", s.id),
                    )
                })?;
            known.insert(s.id, system);
        }
    }
    Ok(())
}

/// Parses the geometry datasets of a UFF file (see the module doc).
///
/// # Errors
/// [`IoError`] naming the file and line.
pub fn parse_uff_geometry(bytes: &[u8], path: &Path) -> Result<Geometry, IoError> {
    let mut skipped = BTreeMap::new();
    let records = records(bytes, path, &mut skipped)?;
    let mut nodes = Vec::new();
    let mut traces = Vec::new();
    let mut trace_lines = Vec::new();
    let mut raw18 = Vec::new();
    let mut direct = Vec::new();
    for r in &records {
        match r.dataset {
            15 => nodes15(path, r, &mut nodes)?,
            2411 => nodes2411(path, r, &mut nodes)?,
            82 => traces82(path, r, &mut traces, &mut trace_lines)?,
            18 => systems18(path, r, &mut raw18)?,
            _ => systems2420(path, r, &mut direct)?,
        }
    }
    let mut known: HashMap<i64, CoordinateSystem> = HashMap::new();
    let mut defined_at: HashMap<i64, usize> = HashMap::new();
    for line in direct
        .iter()
        .map(|(s, l)| (s.id, *l))
        .chain(raw18.iter().map(|s| (s.id, s.line)))
    {
        if let Some(first) = defined_at.insert(line.0, line.1) {
            return Err(IoError::at(
                path,
                line.1,
                "",
                format!(
                    "coordinate system {} is defined twice (lines {first} and {})",
                    line.0, line.1
                ),
            ));
        }
    }
    for (s, line) in direct {
        s.check().map_err(|m| IoError::at(path, line, "", m))?;
        known.insert(s.id, s);
    }
    resolve18(path, &raw18, &mut known)?;
    let mut g = Geometry::default();
    let mut origins = Origins::default();
    for raw in nodes {
        let mut node = raw.node;
        if !raw.global && raw.definition != 0 {
            let system = known.get(&raw.definition).ok_or_else(|| {
                IoError::at(
                    path,
                    raw.line,
                    "",
                    format!(
                        "node {}: its definition coordinate system {} is not defined in the file",
                        node.id, raw.definition
                    ),
                )
            })?;
            node.xyz = system.to_global(node.xyz);
        }
        origins.nodes.push(raw.line);
        g.nodes.push(node);
    }
    let missing: Vec<String> = {
        let mut m: Vec<i64> = g
            .nodes
            .iter()
            .map(|n| n.displacement_system)
            .filter(|d| *d != 0 && !known.contains_key(d))
            .collect();
        m.sort_unstable();
        m.dedup();
        m.iter().map(i64::to_string).collect()
    };
    if !missing.is_empty() {
        g.notes.push(format!(
            "displacement coordinate systems {} are not defined in the file; the directions of their nodes are taken as global",
            crate::frf_file::listed(&missing)
        ));
    }
    let mut systems: Vec<CoordinateSystem> = known.into_values().collect();
    systems.sort_by_key(|s| s.id);
    g.coordinate_systems = systems;
    g.trace_lines = traces;
    origins.trace_lines = trace_lines;
    if !skipped.is_empty() {
        let list: Vec<String> = skipped
            .iter()
            .map(|(d, n)| format!("{n} × dataset {d}"))
            .collect();
        g.notes
            .push(format!("skipped: {}", crate::frf_file::listed(&list)));
    }
    if g.nodes.is_empty() {
        return Err(IoError::format(
            path,
            "",
            "no nodes: a geometry needs dataset 15 or 2411",
        ));
    }
    g.check(&origins)
        .map_err(|m| IoError::format(path, "", m))?;
    Ok(g)
}
