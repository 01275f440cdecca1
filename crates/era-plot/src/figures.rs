//! Figure specifications: series and axis ranges computed from the data.
//!
//! **Magnitude** is `|G(f_k)|` on a log axis whose decades cover the data
//! ([`log_range`]), labelled in the FRF's units. The units are the file's
//! (`response_unit / force_unit`, [`FrfUnits`]); an FRF integrated `n` times over time
//! has its response unit multiplied by `sⁿ` (`m/s² → m/s → m`), since
//! `∫ a dt = v`. Unknown units read `unit/unit`: nothing is assumed.
//!
//! **Phase** is `φ_k = arg G(f_k)` in degrees. Wrapped ([`PhaseView::Wrapped`], the
//! default) it is shown as it is, in (−180°, 180°], cut where it passes ±180°
//! ([`gaps_at_wraps`]). Unwrapping adds `360° · m_k` so that the curve is continuous, but
//! `m_k` is only known where the true change between lines is well under 180°: across a
//! resonance narrower than the line spacing `Δf` (half-power bandwidth `2ζf_r < Δf`)
//! the phase turns by nearly 180° between two lines and the fold is a guess. Classic
//! unwrapping guesses at every such line and drifts by multiples of 360°.
//! [`unwrapped_phase_deg`] only folds the certain steps (a raw step over 270°, a true
//! change under 90°); the measurement is then shown on the model's branch
//! ([`phase_on_branch_of`]: `φ + 360°·round((φ_model − φ)/360°)`), so measurement noise
//! never picks a branch.
//!
//! **Collocation** (output and input at one node and direction) marks a pair's title;
//! the caller says which pairs are ([`FrfView`]), from a channel table when there is one.

use era::{Complex64, FrfData};

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SeriesKind {
    /// Measured data: solid.
    Measured,
    /// Model: dashed, contrasting colour.
    Model,
    /// Singular values: points joined by a line.
    Values,
}

/// One curve.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Ordinates (positive for a log axis; non-positive points are skipped there).
    pub y: Vec<f64>,
    /// Style.
    pub kind: SeriesKind,
}

/// Ordinate scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum YScale {
    /// Linear.
    Linear,
    /// Base-10 logarithmic.
    Log,
}

/// One chart.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Title above the chart (may be empty).
    pub title: String,
    /// Abscissa label with unit.
    pub x_label: String,
    /// Ordinate label with unit.
    pub y_label: String,
    /// Ordinate scale.
    pub y_scale: YScale,
    /// Abscissa range.
    pub x_range: (f64, f64),
    /// Ordinate range.
    pub y_range: (f64, f64),
    /// Curves.
    pub series: Vec<Series>,
    /// A vertical marker (e.g. the chosen model order), with its label.
    pub marker_x: Option<(f64, String)>,
    /// A horizontal guide (e.g. the noise floor), with its label.
    pub guide_y: Option<(f64, String)>,
    /// Draw a legend.
    pub legend: bool,
}

/// A figure: panels laid out in a grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// Overall title (may be empty).
    pub title: String,
    /// Panels, row by row.
    pub panels: Vec<Panel>,
    /// Panels per row.
    pub columns: usize,
    /// Size in pixels.
    pub size: (u32, u32),
}

/// Decade-rounded range covering the positive values (at least one decade).
pub fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for v in values.filter(|v| v.is_finite() && *v > 0.0) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if hi.is_nan() || hi <= 0.0 {
        return (0.1, 1.0);
    }
    // Decades clamped to ±MAX_DECADE, so that 1.7e308 cannot round up to 1e309 = inf
    // (plotters then loops forever looking for tick marks), and at most
    // MAX_LOG_SPAN_DECADES of them: values far below the top are clipped, not drawn.
    let b = hi.log10().ceil().clamp(-MAX_DECADE + 1.0, MAX_DECADE);
    let a = lo.log10().floor().clamp(-MAX_DECADE, MAX_DECADE - 1.0);
    let a = a.max(b - MAX_LOG_SPAN_DECADES);
    let b = if b <= a { a + 1.0 } else { b };
    (10f64.powf(a), 10f64.powf(b))
}

/// The largest decade a log axis reaches: `1e300`, well inside `f64` after plotters
/// rounds outwards.
pub const MAX_DECADE: f64 = 300.0;

/// The most decades one log axis spans.
pub const MAX_LOG_SPAN_DECADES: f64 = 60.0;

/// Range rounded outwards to multiples of `step` (at least one step).
pub fn stepped_range(values: impl Iterator<Item = f64>, step: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return (-step, step);
    }
    // Values beyond ±1e300 are clamped, so the rounded range stays finite.
    let (lo, hi) = (lo.clamp(-1e300, 1e300), hi.clamp(-1e300, 1e300));
    let (a, b) = ((lo / step).floor() * step, (hi / step).ceil() * step);
    (a, if b <= a { a + step } else { b })
}

/// `phase` moved, line by line, to the multiple of 360° nearest `reference`: a noisy
/// measured phase shown on the model's branch, where unwrapping the noise on its own
/// would wander off in 360° steps.
pub fn phase_on_branch_of(phase: &[f64], reference: &[f64]) -> Vec<f64> {
    phase
        .iter()
        .zip(reference)
        .map(|(p, r)| p + 360.0 * ((r - p) / 360.0).round())
        .collect()
}

/// Phase in degrees on the principal branch, −180° … 180° (the argument of each value).
pub fn wrapped_phase_deg(values: &[Complex64]) -> Vec<f64> {
    values.iter().map(|v| v.arg().to_degrees()).collect()
}

/// The smallest raw step between two lines, in degrees, that [`unwrapped_phase_deg`]
/// takes for a wrap: the true change is then under 360° − 270° = 90°, so the 360° jump
/// is certain. A raw step between 180° and 270° is ambiguous and left alone.
pub const UNAMBIGUOUS_WRAP_DEG: f64 = 270.0;

/// Phase in degrees, unwrapped along the lines where that is unambiguous.
///
/// Classic unwrapping folds every step `Δ = φₖ − φₖ₋₁` into (−180°, 180°]. Across a
/// resonance narrower than one line, the true step is itself close to ±180° and the
/// fold picks a side by the noise: each resonance then adds or removes 360° at random
/// and the curve drifts (a collocated velocity FRF, whose phase stays within ±90°,
/// drew down to −3000°). Here a step is folded only when `|Δ| >` [`UNAMBIGUOUS_WRAP_DEG`]
/// (the true change is then below 90°, a certain wrap); other steps are kept as they
/// are, so an ambiguous jump shows as a jump and never shifts the rest of the curve.
pub fn unwrapped_phase_deg(values: &[Complex64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(values.len());
    let mut offset = 0.0;
    let mut previous_raw: Option<f64> = None;
    for v in values {
        let raw = v.arg().to_degrees();
        if let Some(p) = previous_raw {
            let step = raw - p;
            if step > UNAMBIGUOUS_WRAP_DEG {
                offset -= 360.0;
            } else if step < -UNAMBIGUOUS_WRAP_DEG {
                offset += 360.0;
            }
        }
        out.push(raw + offset);
        previous_raw = Some(raw);
    }
    out
}

/// How the phase panels draw the phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PhaseView {
    /// −180° … 180°, each line's own argument: nothing is inferred (the default).
    #[default]
    Wrapped,
    /// The model's phase unwrapped where unambiguous ([`unwrapped_phase_deg`]), the
    /// measurement shown on the model's branch ([`phase_on_branch_of`]); without a
    /// model, the measurement unwrapped where unambiguous.
    Unwrapped,
}

/// The units of an FRF: response unit over force unit, as the input file states them
/// (UFF axis records, `# response_unit:` / `# force_unit:` lines of a CSV, MAT
/// variables, `--units`). Unknown units stay unknown: the label then says `unit`, never
/// an assumed system of units.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct FrfUnits {
    /// Response unit (e.g. `m/s^2`), when known.
    pub response: Option<String>,
    /// Force unit (e.g. `N`), when known.
    pub force: Option<String>,
}

impl FrfUnits {
    /// The units of the metadata keys `response_unit` and `force_unit`; blank, `NONE`
    /// and `unknown` values count as unknown.
    pub fn from_metadata(metadata: &std::collections::BTreeMap<String, String>) -> Self {
        let get = |key: &str| {
            metadata
                .get(key)
                .map(|v| v.trim())
                .filter(|v| {
                    !v.is_empty()
                        && !v.eq_ignore_ascii_case("none")
                        && !v.eq_ignore_ascii_case("unknown")
                })
                .map(str::to_string)
        };
        FrfUnits {
            response: get("response_unit"),
            force: get("force_unit"),
        }
    }

    /// The units after `times` integrations over time (`m/s^2` → `m/s` → `m`): a
    /// trailing `/s^2`, `/s²` becomes `/s`, a trailing `/s` goes, and any other unit
    /// gains a factor `·s`.
    pub fn integrated(&self, times: usize) -> FrfUnits {
        let once = |u: &str| -> String {
            for square in ["/s^2", "/s²", "/s**2"] {
                if let Some(stem) = u.strip_suffix(square) {
                    return format!("{stem}/s");
                }
            }
            match u.strip_suffix("/s") {
                Some(stem) if !stem.is_empty() => stem.to_string(),
                _ => format!("{}·s", parenthesised(u)),
            }
        };
        let mut response = self.response.clone();
        for _ in 0..times {
            response = response.map(|u| once(&u));
        }
        FrfUnits {
            response,
            force: self.force.clone(),
        }
    }

    /// The FRF's unit as a label: `(m/s^2)/N`, `in/lbf`; `unit` for an unknown side
    /// (`unit/unit` when neither is known).
    pub fn label(&self) -> String {
        let side = |u: &Option<String>| u.as_deref().map_or("unit".to_string(), parenthesised);
        format!("{}/{}", side(&self.response), side(&self.force))
    }
}

/// The superscript of a decimal digit or a minus sign, if it has one.
fn superscript(c: char) -> Option<char> {
    Some(match c {
        '0' => '⁰',
        '1' => '¹',
        '2' => '²',
        '3' => '³',
        '4' => '⁴',
        '5' => '⁵',
        '6' => '⁶',
        '7' => '⁷',
        '8' => '⁸',
        '9' => '⁹',
        '-' => '⁻',
        _ => return None,
    })
}

/// `n` in superscript digits (`-2` → `⁻²`).
pub fn superscript_number(n: i64) -> String {
    n.to_string().chars().filter_map(superscript).collect()
}

/// A unit label as it is printed: powers written `^2` or `**2` (`m/s^2`, `s**-1`)
/// become superscripts (`m/s²`, `s⁻¹`); anything else is left as it is.
pub fn typeset_units(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(at) = rest.find(['^', '*']) {
        let (head, tail) = rest.split_at(at);
        out.push_str(head);
        let marker = if tail.starts_with("**") {
            2
        } else if tail.starts_with('^') {
            1
        } else {
            0
        };
        let power = &tail[marker..];
        let digits = power
            .char_indices()
            .take_while(|(k, c)| c.is_ascii_digit() || (*k == 0 && *c == '-'))
            .count();
        let exponent = &power[..digits];
        if marker > 0 && exponent.chars().any(|c| c.is_ascii_digit()) {
            out.extend(exponent.chars().filter_map(superscript));
            rest = &power[digits..];
        } else {
            // A lone `*` (a product) or a `^` with no number after it stays.
            let one = tail.chars().next().map_or(1, char::len_utf8);
            out.push_str(&tail[..one]);
            rest = &tail[one..];
        }
    }
    out.push_str(rest);
    out
}

/// A tick label of a log axis: `10⁻²` at a decade, `2×10⁻³` between decades (the
/// mantissa to one digit), `0` for zero.
pub fn log_tick_label(value: f64) -> String {
    if !(value.is_finite() && value > 0.0) {
        return format!("{value}");
    }
    let mut exponent = value.log10().floor();
    let mut mantissa = value / 10f64.powf(exponent);
    // 9.9999… is the next decade, not 10×10ⁿ.
    if mantissa.round() >= 10.0 {
        exponent += 1.0;
        mantissa /= 10.0;
    }
    let power = format!("10{}", superscript_number(exponent as i64));
    if (mantissa - 1.0).abs() < 1e-6 {
        power
    } else {
        format!("{}×{power}", mantissa.round())
    }
}

/// `u` in parentheses when it is compound (`m/s^2` → `(m/s^2)`), so that `… / N`
/// reads unambiguously.
fn parenthesised(u: &str) -> String {
    if u.contains(['/', '·', '*', ' ']) && !(u.starts_with('(') && u.ends_with(')')) {
        format!("({u})")
    } else {
        u.to_string()
    }
}

/// What an FRF figure shows besides the data: the unit of |G|, the phase view and
/// which pairs are collocated.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfView {
    /// Unit label of |G| (see [`FrfUnits::label`]).
    pub unit: String,
    /// How phase is drawn.
    pub phase: PhaseView,
    /// Whether pair (i, j) is collocated, at `i · inputs + j`.
    pub collocated: Vec<bool>,
    /// Inputs (columns of the FRF matrix), to index `collocated`.
    pub inputs: usize,
    /// The legend of the model's curve: `ERA model`, or `refined model` after a
    /// refinement.
    pub model: String,
    /// Where each output is (`node 11 +Z`), from the channel table; empty without one.
    pub output_names: Vec<String>,
    /// Where each input is, as `output_names`.
    pub input_names: Vec<String>,
}

impl FrfView {
    /// Unknown units, wrapped phase, and collocation by index (output i with input i)
    /// for a square set, none otherwise: the fallback when no channel table says.
    pub fn by_index(outputs: usize, inputs: usize) -> Self {
        let square = outputs == inputs;
        FrfView {
            unit: FrfUnits::default().label(),
            phase: PhaseView::Wrapped,
            collocated: (0..outputs * inputs)
                .map(|k| square && k / inputs.max(1) == k % inputs.max(1))
                .collect(),
            inputs,
            model: "ERA model".into(),
            output_names: Vec::new(),
            input_names: Vec::new(),
        }
    }

    /// Whether pair (output, input) is collocated.
    pub fn is_collocated(&self, output: usize, input: usize) -> bool {
        self.collocated
            .get(output * self.inputs + input)
            .copied()
            .unwrap_or(false)
    }

    /// The title of a pair ([`pair_title`]).
    pub fn pair_title(&self, output: usize, input: usize) -> String {
        pair_title(
            output,
            input,
            self.output_names.get(output).map(String::as_str),
            self.input_names.get(input).map(String::as_str),
            self.is_collocated(output, input),
        )
    }
}

/// Which pairs get an overlay of their own (`--pairs`): all of them, the collocated
/// ones, or a list of `output:input` pairs (1-based).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum PairSelection {
    /// Every pair (the default).
    #[default]
    All,
    /// The collocated pairs only.
    Collocated,
    /// These pairs, 1-based `(output, input)`, in the order given.
    List(Vec<(usize, usize)>),
}

impl std::str::FromStr for PairSelection {
    type Err = String;

    /// `all`, `collocated`, or `OUT:IN[,OUT:IN…]` with 1-based indices (`1:1,2:3`).
    fn from_str(text: &str) -> Result<Self, String> {
        match text.trim() {
            "all" => return Ok(PairSelection::All),
            "collocated" => return Ok(PairSelection::Collocated),
            _ => {}
        }
        let mut pairs = Vec::new();
        for item in text.split(',') {
            let item = item.trim();
            let parsed = item.split_once(':').and_then(|(o, i)| {
                Some((
                    o.trim().parse::<usize>().ok()?,
                    i.trim().parse::<usize>().ok()?,
                ))
            });
            match parsed {
                Some((o, i)) if o >= 1 && i >= 1 => {
                    if !pairs.contains(&(o, i)) {
                        pairs.push((o, i));
                    }
                }
                _ => {
                    return Err(format!(
                        "'{item}' is not a pair: give all, collocated, or OUTPUT:INPUT pairs counted from 1, comma-separated (e.g. 1:1,2:3)"
                    ))
                }
            }
        }
        Ok(PairSelection::List(pairs))
    }
}

impl std::fmt::Display for PairSelection {
    /// As it is written on the command line: `all`, `collocated`, `1:1,2:3`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PairSelection::All => f.write_str("all"),
            PairSelection::Collocated => f.write_str("collocated"),
            PairSelection::List(list) => {
                let items: Vec<String> = list.iter().map(|(o, i)| format!("{o}:{i}")).collect();
                f.write_str(&items.join(","))
            }
        }
    }
}

impl PairSelection {
    /// The chosen pairs of a `outputs × inputs` set, 0-based, row by row for `All` and
    /// `Collocated` (collocation as `view` says), in the given order for a list.
    ///
    /// # Errors
    /// A message naming the first pair outside the set.
    pub fn pairs(
        &self,
        outputs: usize,
        inputs: usize,
        view: &FrfView,
    ) -> Result<Vec<(usize, usize)>, String> {
        let every = (0..outputs).flat_map(|i| (0..inputs).map(move |j| (i, j)));
        match self {
            PairSelection::All => Ok(every.collect()),
            PairSelection::Collocated => Ok(every.filter(|&(i, j)| view.is_collocated(i, j)).collect()),
            PairSelection::List(list) => list
                .iter()
                .map(|&(o, i)| {
                    if o <= outputs && i <= inputs {
                        Ok((o - 1, i - 1))
                    } else {
                        Err(format!(
                            "pair {o}:{i} is not in the set, which has {outputs} output(s) and {inputs} input(s)"
                        ))
                    }
                })
                .collect(),
        }
    }
}

/// The title of a pair (1-based) in words that suit any test (shaker, hammer,
/// actuator): `output 2 / input 3`, each with where it is when the channel table says
/// (`output 2 (node 11 +Z) / input 3 (node 5 +Z)`), marked when collocated.
pub fn pair_title(
    output: usize,
    input: usize,
    output_name: Option<&str>,
    input_name: Option<&str>,
    collocated: bool,
) -> String {
    let side = |role: &str, k: usize, name: Option<&str>| match name.filter(|n| !n.is_empty()) {
        Some(n) => format!("{role} {} ({n})", k + 1),
        None => format!("{role} {}", k + 1),
    };
    let base = format!(
        "{} / {}",
        side("output", output, output_name),
        side("input", input, input_name)
    );
    if collocated {
        format!("{base} (collocated)")
    } else {
        base
    }
}

/// The phase panel's curves and range: the model's and the measurement's phase in the
/// chosen [`PhaseView`].
pub fn phase_curves(
    measured: &[Complex64],
    model: Option<&[Complex64]>,
    view: PhaseView,
) -> (Vec<f64>, Option<Vec<f64>>, (f64, f64)) {
    match view {
        PhaseView::Wrapped => {
            let pm = wrapped_phase_deg(measured);
            let px = model.map(wrapped_phase_deg);
            (pm, px, (-180.0, 180.0))
        }
        PhaseView::Unwrapped => {
            let px = model.map(unwrapped_phase_deg);
            let pm = match &px {
                Some(p) => phase_on_branch_of(&wrapped_phase_deg(measured), p),
                None => unwrapped_phase_deg(measured),
            };
            let range = stepped_range(pm.iter().chain(px.iter().flatten()).copied(), 90.0);
            (pm, px, range)
        }
    }
}

/// `(x, y)` with a NaN point (a gap) inserted wherever consecutive values jump by more
/// than 180°: a wrapped phase passing ±180° is drawn as two pieces, not as a vertical
/// stroke across the panel.
pub fn gaps_at_wraps(x: &[f64], y: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let mut xs = Vec::with_capacity(x.len() + 8);
    let mut ys = Vec::with_capacity(y.len() + 8);
    for k in 0..x.len().min(y.len()) {
        if k > 0 && (y[k] - y[k - 1]).abs() > 180.0 {
            xs.push(0.5 * (x[k - 1] + x[k]));
            ys.push(f64::NAN);
        }
        xs.push(x[k]);
        ys.push(y[k]);
    }
    (xs, ys)
}

/// The phase series of a panel: in the wrapped view, cut at the ±180° jumps
/// ([`gaps_at_wraps`]).
pub fn phase_series(
    x: &[f64],
    y: &[f64],
    label: &str,
    kind: SeriesKind,
    view: PhaseView,
) -> Series {
    let (x, y) = match view {
        PhaseView::Wrapped => gaps_at_wraps(x, y),
        PhaseView::Unwrapped => (x.to_vec(), y.to_vec()),
    };
    Series {
        label: label.into(),
        x,
        y,
        kind,
    }
}

/// Measured and model FRF of one pair: log magnitude over frequency in the data's
/// units, and phase in degrees (thesis `plotfrfs.m`), wrapped unless `view` asks for
/// [`PhaseView::Unwrapped`]. `measured` should be the processed measurement (after the
/// same integrations as the model); lines whose measured value is exactly zero (the
/// zeroed low end) are left out.
///
/// # Panics
/// If the two FRF sets differ in shape or the pair is out of range.
#[track_caller]
pub fn frf_overlay(
    measured: &FrfData,
    model: Option<&FrfData>,
    output: usize,
    input: usize,
    view: &FrfView,
) -> Figure {
    if let Some(m) = model {
        assert_eq!(
            (measured.outputs(), measured.inputs(), measured.lines()),
            (m.outputs(), m.inputs(), m.lines()),
            "model and measurement shapes"
        );
    }
    let f = measured.frequency_hz();
    let keep: Vec<usize> = (0..f.len())
        .filter(|&k| measured.pair(output, input)[k].norm() > 0.0)
        .collect();
    let pick = |g: &[Complex64]| -> Vec<Complex64> { keep.iter().map(|&k| g[k]).collect() };
    let gm = pick(measured.pair(output, input));
    let gx = model.map(|m| pick(m.pair(output, input)));
    let x: Vec<f64> = keep.iter().map(|&k| f[k]).collect();
    let x_range = (0.0, f[f.len() - 1]);
    let mag = |g: &[Complex64]| g.iter().map(|v| v.norm()).collect::<Vec<f64>>();
    let mm = mag(&gm);
    let mx = gx.as_deref().map(mag);
    let (pm, px, phase_range) = phase_curves(&gm, gx.as_deref(), view.phase);
    let series = |a: &[f64], b: Option<&Vec<f64>>| {
        let mut out = vec![Series {
            label: "measured".into(),
            x: x.clone(),
            y: a.to_vec(),
            kind: SeriesKind::Measured,
        }];
        if let Some(b) = b {
            out.push(Series {
                label: view.model.clone(),
                x: x.clone(),
                y: b.clone(),
                kind: SeriesKind::Model,
            });
        }
        out
    };
    let magnitude = Panel {
        title: String::new(),
        x_label: "Frequency (Hz)".into(),
        y_label: format!("|G| {}", view.unit),
        y_scale: YScale::Log,
        x_range,
        y_range: log_range(mm.iter().chain(mx.iter().flatten()).copied()),
        series: series(&mm, mx.as_ref()),
        marker_x: None,
        guide_y: None,
        legend: true,
    };
    let phase = Panel {
        title: String::new(),
        x_label: "Frequency (Hz)".into(),
        y_label: match view.phase {
            PhaseView::Wrapped => "Phase (deg, wrapped)".into(),
            PhaseView::Unwrapped => "Phase (deg, unwrapped)".into(),
        },
        y_scale: YScale::Linear,
        x_range,
        y_range: phase_range,
        series: std::iter::once(phase_series(
            &x,
            &pm,
            "measured",
            SeriesKind::Measured,
            view.phase,
        ))
        .chain(
            px.as_ref()
                .map(|p| phase_series(&x, p, &view.model, SeriesKind::Model, view.phase)),
        )
        .collect(),
        marker_x: None,
        guide_y: None,
        legend: false,
    };
    Figure {
        title: view.pair_title(output, input),
        panels: vec![magnitude, phase],
        columns: 1,
        size: OVERLAY_SIZE,
    }
}

/// Pixel size of a pair's overlay: three side by side in a 1400 px page.
pub const OVERLAY_SIZE: (u32, u32) = (720, 540);

/// The most panel columns an overview grid takes.
pub const MAX_GRID_COLUMNS: usize = 10;

/// Columns of a grid of `rows × cols` small panels: the matrix's own columns, with
/// several of its rows side by side while the grid would be over twice as tall (in
/// panels) as wide — a 28 × 2 set is laid out 6 wide and 10 high, not 2 × 28 — and at
/// most [`MAX_GRID_COLUMNS`].
pub fn grid_columns(rows: usize, cols: usize) -> usize {
    let cols = cols.max(1);
    if cols >= MAX_GRID_COLUMNS {
        return MAX_GRID_COLUMNS;
    }
    let mut per_row = 1;
    while rows.div_ceil(per_row) > 2 * per_row * cols && (per_row + 1) * cols <= MAX_GRID_COLUMNS {
        per_row += 1;
    }
    per_row * cols
}

/// Pixel size of one grid cell.
const GRID_CELL: (u32, u32) = (280, 210);

/// A grid figure of small panels, laid out [`grid_columns`] wide; the left column
/// keeps its ordinate label and the bottom panel of each column its abscissa label.
fn small_multiples(title: String, mut panels: Vec<Panel>, matrix_columns: usize) -> Figure {
    let n = panels.len();
    let columns = grid_columns(n.div_ceil(matrix_columns.max(1)), matrix_columns).min(n.max(1));
    let rows = n.div_ceil(columns).max(1);
    for (k, panel) in panels.iter_mut().enumerate() {
        panel.legend = false;
        if k % columns != 0 {
            panel.y_label = String::new();
        }
        if k + columns < n {
            panel.x_label = String::new();
        }
    }
    Figure {
        title,
        panels,
        columns,
        size: (
            GRID_CELL.0 * columns as u32 + 40,
            GRID_CELL.1 * rows as u32 + 60,
        ),
    }
}

/// A q×p overview: magnitude of every pair, measured and (when given) model, with
/// axis titles in the data's units on the outer panels.
///
/// # Panics
/// As [`frf_overlay`].
#[track_caller]
pub fn frf_grid(measured: &FrfData, model: Option<&FrfData>, view: &FrfView) -> Figure {
    let (q, p) = (measured.outputs(), measured.inputs());
    let mut panels = Vec::with_capacity(q * p);
    for i in 0..q {
        for j in 0..p {
            let mut panel = frf_overlay(measured, model, i, j, view)
                .panels
                .swap_remove(0);
            panel.title = format!(
                "Y{} / F{}{}",
                i + 1,
                j + 1,
                if view.is_collocated(i, j) {
                    " (col.)"
                } else {
                    ""
                }
            );
            panel.y_label = format!("|G| {}", view.unit);
            panels.push(panel);
        }
    }
    let title = if model.is_some() {
        format!(
            "All pairs: measured (solid) and {} (dashed), magnitude",
            view.model
        )
    } else {
        "All pairs: measured magnitude".into()
    };
    small_multiples(title, panels, p)
}

/// Coherence (0 … 1) over frequency, one small panel per curve: `curves` holds each
/// curve's title and values on `frequency_hz`. `era identify --from-time` shows the
/// multiple coherence of each output (the part of its power the inputs explain).
pub fn coherence_grid(title: &str, frequency_hz: &[f64], curves: &[(String, Vec<f64>)]) -> Figure {
    let x_range = (0.0, frequency_hz.last().copied().unwrap_or(1.0));
    let panels = curves
        .iter()
        .map(|(name, values)| Panel {
            title: name.clone(),
            x_label: "Frequency (Hz)".into(),
            y_label: "Coherence".into(),
            y_scale: YScale::Linear,
            x_range,
            y_range: (0.0, 1.0),
            series: vec![Series {
                label: "coherence".into(),
                x: frequency_hz.to_vec(),
                y: values.clone(),
                kind: SeriesKind::Measured,
            }],
            marker_x: None,
            guide_y: None,
            legend: false,
        })
        .collect();
    small_multiples(title.into(), panels, 1)
}

/// The noise floor of a singular-value tail when one is evident: at least 5 values
/// after the order, spread within one decade (10th to 90th percentile); the median.
pub fn noise_floor(singular_values: &[f64], order: usize) -> Option<f64> {
    let mut tail: Vec<f64> = singular_values
        .iter()
        .skip(order)
        .copied()
        .filter(|v| *v > 0.0)
        .collect();
    if tail.len() < 5 {
        return None;
    }
    tail.sort_by(f64::total_cmp);
    let at = |q: f64| tail[((tail.len() - 1) as f64 * q).round() as usize];
    (at(0.9) / at(0.1) < 10.0).then(|| at(0.5))
}

/// Singular values on a log scale, the chosen order marked, and the noise floor where
/// one is evident ([`noise_floor`]).
pub fn singular_value_figure(singular_values: &[f64], order: usize) -> Figure {
    let x: Vec<f64> = (1..=singular_values.len()).map(|k| k as f64).collect();
    let floor = noise_floor(singular_values, order);
    let panel = Panel {
        title: String::new(),
        x_label: "Index (states)".into(),
        y_label: "Singular value of H0".into(),
        y_scale: YScale::Log,
        // Room past the order marker, so it never sits on the right border.
        x_range: (
            0.0,
            singular_values
                .len()
                .max(order + (order / 10).max(2))
                .max(1) as f64
                + 1.0,
        ),
        y_range: log_range(singular_values.iter().copied().chain(floor)),
        series: vec![Series {
            label: "singular values".into(),
            x,
            y: singular_values.to_vec(),
            kind: SeriesKind::Values,
        }],
        marker_x: Some((order as f64 + 0.5, format!("{order} states"))),
        guide_y: floor.map(|v| (v, "noise floor".into())),
        legend: false,
    };
    Figure {
        title: format!(
            "Hankel singular values ({} shown, order {order})",
            singular_values.len()
        ),
        panels: vec![panel],
        columns: 1,
        size: (900, 520),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use era::data::frf::uniform_lines;
    use era::Quantity;

    fn sample() -> FrfData {
        FrfData::from_fn(
            uniform_lines(50, 1.0),
            2,
            3,
            Quantity::Velocity,
            |i, j, k| {
                if k == 0 {
                    Complex64::new(0.0, 0.0)
                } else {
                    Complex64::from_polar((1 + i + j) as f64 / k as f64, -0.2 * k as f64)
                }
            },
        )
        .unwrap()
    }

    #[test]
    fn overlay_has_two_panels_two_series_and_ranges_from_the_data() {
        let m = sample();
        let view = FrfView::by_index(2, 3);
        let fig = frf_overlay(&m, Some(&m), 1, 2, &view);
        assert_eq!(fig.title, "output 2 / input 3");
        assert!(fig.panels[0].series[1].label == "ERA model");
        // After a refinement the legend names the refined model, and the channel
        // table's nodes name the pair.
        let named = FrfView {
            model: "refined model".into(),
            output_names: vec!["node 1 +Z".into(), "node 2 +Z".into()],
            input_names: vec!["node 7 -X".into(); 3],
            ..view.clone()
        };
        let fig = frf_overlay(&m, Some(&m), 1, 2, &named);
        assert_eq!(fig.title, "output 2 (node 2 +Z) / input 3 (node 7 -X)");
        assert!(fig
            .panels
            .iter()
            .all(|p| p.series[1].label == "refined model"));
        assert!(frf_grid(&m, Some(&m), &named)
            .title
            .contains("refined model (dashed)"));
        assert_eq!(fig.panels.len(), 2);
        for p in &fig.panels {
            assert_eq!(p.series.len(), 2);
            // The zero line is left out (the phase has NaN gaps at its wraps).
            assert_eq!(p.series[0].y.iter().filter(|y| y.is_finite()).count(), 49);
            assert_eq!(p.x_range, (0.0, 49.0));
        }
        // |G| runs from 4/49 to 4: decades 0.01 .. 10.
        assert_eq!(fig.panels[0].y_range, (0.01, 10.0));
        assert_eq!(fig.panels[0].y_scale, YScale::Log);
        // Wrapped phase by default: the principal branch.
        assert_eq!(fig.panels[1].y_range, (-180.0, 180.0));
        // Phase −0.2 k rad, unwrapped: −11.5° down to −561°: −630 .. 0 in 90° steps.
        let unwrapped = FrfView {
            phase: PhaseView::Unwrapped,
            ..view.clone()
        };
        let fig = frf_overlay(&m, Some(&m), 1, 2, &unwrapped);
        assert_eq!(fig.panels[1].y_range, (-630.0, 0.0));
        // Square sets are collocated on the diagonal by index; a 2 x 3 set is not.
        assert!(!frf_overlay(&m, Some(&m), 0, 0, &view)
            .title
            .ends_with("(collocated)"));
        let mut marked = view.clone();
        marked.collocated[0] = true;
        assert!(frf_overlay(&m, Some(&m), 0, 0, &marked)
            .title
            .ends_with("(collocated)"));
    }

    #[test]
    fn pair_selections_parse_and_pick_their_pairs() {
        let view = FrfView::by_index(3, 3);
        let all: PairSelection = "all".parse().unwrap();
        assert_eq!(all.pairs(3, 3, &view).unwrap().len(), 9);
        let col: PairSelection = "collocated".parse().unwrap();
        assert_eq!(
            col.pairs(3, 3, &view).unwrap(),
            vec![(0, 0), (1, 1), (2, 2)]
        );
        let list: PairSelection = "2:3, 1:1,2:3".parse().unwrap();
        assert_eq!(list, PairSelection::List(vec![(2, 3), (1, 1)]));
        assert_eq!(list.pairs(3, 3, &view).unwrap(), vec![(1, 2), (0, 0)]);
        let err = list.pairs(2, 2, &view).unwrap_err();
        assert!(err.contains("2:3") && err.contains("2 input"), "{err}");
        for bad in ["", "1", "0:1", "1:x", "1:2,", "some", "1:-2", "1:2:3"] {
            let e = bad.parse::<PairSelection>().unwrap_err();
            assert!(e.contains("is not a pair"), "{bad}: {e}");
        }
    }

    #[test]
    fn log_ticks_and_units_are_typeset() {
        assert_eq!(log_tick_label(1e-2), "10⁻²");
        assert_eq!(log_tick_label(1.0), "10⁰");
        assert_eq!(log_tick_label(1000.0), "10³");
        assert_eq!(log_tick_label(0.099_999_999_9), "10⁻¹");
        assert_eq!(log_tick_label(2e-3), "2×10⁻³");
        assert_eq!(log_tick_label(1e-12), "10⁻¹²");
        assert_eq!(superscript_number(-305), "⁻³⁰⁵");
        assert_eq!(typeset_units("|G| (m/s^2)/N"), "|G| (m/s²)/N");
        assert_eq!(typeset_units("s**-1"), "s⁻¹");
        assert_eq!(typeset_units("kg*m^"), "kg*m^");
        assert_eq!(typeset_units("unit/unit"), "unit/unit");
    }

    #[test]
    fn measured_phase_follows_the_model_branch() {
        let model = [0.0, -100.0, -200.0, -300.0];
        let noisy = [2.0, -95.0 + 360.0, -210.0 - 720.0, -290.0 + 360.0];
        assert_eq!(
            phase_on_branch_of(&noisy, &model),
            vec![2.0, -95.0, -210.0, -290.0]
        );
    }

    #[test]
    fn phase_unwraps_across_the_branch_cut() {
        let g: Vec<Complex64> = (0..40)
            .map(|k| Complex64::from_polar(1.0, -0.3 * k as f64))
            .collect();
        let p = unwrapped_phase_deg(&g);
        for w in p.windows(2) {
            assert!((w[1] - w[0] + 0.3f64.to_degrees()).abs() < 1e-9);
        }
    }

    #[test]
    fn without_a_model_each_panel_has_the_measurement_only() {
        let m = sample();
        let view = FrfView::by_index(2, 3);
        let fig = frf_overlay(&m, None, 0, 1, &view);
        assert!(fig.panels.iter().all(|p| p.series.len() == 1));
        assert_eq!(fig.panels[0].y_range, (0.01, 10.0));
        assert_eq!(
            frf_grid(&m, None, &view).title,
            "All pairs: measured magnitude"
        );
    }

    #[test]
    fn grid_has_one_panel_per_pair() {
        let m = sample();
        let fig = frf_grid(&m, Some(&m), &FrfView::by_index(2, 3));
        assert_eq!((fig.panels.len(), fig.columns), (6, 3));
        assert_eq!(fig.panels[5].title, "Y2 / F3");
        // Axis titles on the outer panels only: the left column and the bottom row.
        assert_eq!(fig.panels[0].y_label, "|G| unit/unit");
        assert!(fig.panels[1].y_label.is_empty() && fig.panels[0].x_label.is_empty());
        assert_eq!(fig.panels[4].x_label, "Frequency (Hz)");
    }

    #[test]
    fn tall_grids_wrap_into_a_reasonable_shape() {
        // 28 x 2 (DaISy): three output rows side by side, 6 x 10 panels, not 2 x 28.
        assert_eq!(grid_columns(28, 2), 6);
        assert_eq!(grid_columns(8, 8), 8);
        assert_eq!(grid_columns(2, 2), 2);
        assert_eq!(grid_columns(30, 1), 4);
        assert_eq!(grid_columns(3, 40), MAX_GRID_COLUMNS);
        let m = FrfData::from_fn(
            uniform_lines(10, 1.0),
            28,
            2,
            Quantity::Velocity,
            |_, _, k| Complex64::new(1.0 + k as f64, 0.0),
        )
        .unwrap();
        let fig = frf_grid(&m, None, &FrfView::by_index(28, 2));
        let (w, h) = fig.size;
        assert!((0.5..=2.0).contains(&(h as f64 / w as f64)), "{w} x {h} px");
    }

    #[test]
    fn units_come_from_the_metadata_and_follow_integration() {
        let meta = |r: &str, f: &str| {
            [("response_unit", r), ("force_unit", f)]
                .into_iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect::<std::collections::BTreeMap<_, _>>()
        };
        let si = FrfUnits::from_metadata(&meta("m/s^2", "N"));
        assert_eq!(si.label(), "(m/s^2)/N");
        assert_eq!(si.integrated(1).label(), "(m/s)/N");
        assert_eq!(si.integrated(2).label(), "m/N");
        assert_eq!(
            FrfUnits::from_metadata(&meta("in/s²", "lbf"))
                .integrated(1)
                .label(),
            "(in/s)/lbf"
        );
        assert_eq!(
            FrfUnits::from_metadata(&meta("g", "N"))
                .integrated(1)
                .label(),
            "(g·s)/N"
        );
        // Unknown stays unknown, never imperial by assumption.
        assert_eq!(
            FrfUnits::from_metadata(&meta("NONE", "")).label(),
            "unit/unit"
        );
        assert_eq!(FrfUnits::default().integrated(2).label(), "unit/unit");
        assert_eq!(FrfView::by_index(1, 1).unit, "unit/unit");
    }

    /// A collocated velocity FRF of 20 lightly damped modes (ζ = 0.2 %) on lines
    /// coarser than their half-power bandwidths, clean (true phase within ±90°) and
    /// with seeded additive noise of 15 % of its RMS (random phase at the
    /// antiresonances).
    fn collocated_velocity() -> (FrfData, FrfData) {
        let modes: Vec<f64> = (0..20)
            .map(|k| 1.3 + 0.71 * k as f64 + 0.2 * (1.7 * k as f64).sin())
            .collect();
        let mut state = 12345u64;
        let mut noise = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let lines = uniform_lines(400, 0.13);
        let clean: Vec<Complex64> = lines
            .iter()
            .map(|&f| {
                let w = 2.0 * std::f64::consts::PI * f;
                modes
                    .iter()
                    .map(|fr| {
                        let wr = 2.0 * std::f64::consts::PI * fr;
                        Complex64::new(0.0, w)
                            / Complex64::new(wr * wr - w * w, 2.0 * 0.002 * wr * w)
                    })
                    .sum()
            })
            .collect();
        let rms = (clean.iter().map(|v| v.norm_sqr()).sum::<f64>() / clean.len() as f64).sqrt();
        let noisy: Vec<Complex64> = clean
            .iter()
            .map(|v| v + 0.15 * rms * Complex64::new(noise(), noise()))
            .collect();
        let set =
            |v: Vec<Complex64>| FrfData::new(lines.clone(), 1, 1, v, Quantity::Velocity).unwrap();
        (set(clean), set(noisy))
    }

    #[test]
    fn collocated_phase_is_drawn_wrapped_and_does_not_drift_when_unwrapped() {
        let (model, measured) = collocated_velocity();
        let view = FrfView::by_index(1, 1);
        let fig = frf_overlay(&measured, Some(&model), 0, 0, &view);
        let phase = &fig.panels[1];
        assert_eq!(phase.y_range, (-180.0, 180.0));
        for s in &phase.series {
            // Every drawn point (NaN marks the gap at a wrap).
            assert!(s
                .y
                .iter()
                .filter(|p| !p.is_nan())
                .all(|p| (-180.0..=180.0).contains(p)));
            assert!(s.y.iter().filter(|p| !p.is_nan()).count() >= 399);
        }
        // Folding every step into ±180° drifts here (the noise makes each jump at an
        // antiresonance a coin toss); the model's unambiguous unwrapping, with the
        // measurement on its branch, does not.
        let mut naive: Vec<f64> = vec![];
        let mut offset = 0.0f64;
        for (k, p) in wrapped_phase_deg(measured.pair(0, 0)).iter().enumerate() {
            if k > 0 {
                let d = p + offset - naive[k - 1];
                offset -= 360.0 * (d / 360.0).round();
            }
            naive.push(p + offset);
        }
        let spread = |v: &[f64]| {
            v.iter().cloned().fold(f64::MIN, f64::max) - v.iter().cloned().fold(f64::MAX, f64::min)
        };
        assert!(
            spread(&naive) > 1000.0,
            "the case is not hard: {}",
            spread(&naive)
        );
        let unwrapped = FrfView {
            phase: PhaseView::Unwrapped,
            ..view
        };
        let fig = frf_overlay(&measured, Some(&model), 0, 0, &unwrapped);
        let (m, x) = (&fig.panels[1].series[0].y, &fig.panels[1].series[1].y);
        assert!(spread(x) <= 360.0, "model: {}", spread(x));
        assert!(m.iter().zip(x).all(|(m, x)| (m - x).abs() <= 180.0));
        assert!(fig.panels[1].y_range.1 - fig.panels[1].y_range.0 <= 720.0);
    }

    #[test]
    fn singular_values_mark_the_order_and_an_evident_floor() {
        let mut sv: Vec<f64> = (0..8).map(|k| 10f64.powi(-k)).collect();
        sv.extend([2e-9, 1.5e-9, 1.2e-9, 1e-9, 0.9e-9, 0.8e-9]);
        let fig = singular_value_figure(&sv, 8);
        let p = &fig.panels[0];
        assert_eq!(p.series[0].y.len(), 14);
        assert_eq!(p.marker_x.as_ref().unwrap().0, 8.5);
        let floor = p.guide_y.as_ref().unwrap().0;
        assert!((0.9e-9..=1.2e-9).contains(&floor));
        assert_eq!(p.y_range, (1e-10, 1.0));
        // A tail spread over decades has no evident floor.
        let steep: Vec<f64> = (0..20).map(|k| 10f64.powi(-k)).collect();
        assert!(noise_floor(&steep, 8).is_none());
    }
}
