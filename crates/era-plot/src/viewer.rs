//! The mode-shape viewer of `report.html`: each mode animated on the test geometry,
//! deformed over undeformed (trace lines, nodes as dots), with play and pause, an
//! amplitude slider, drag to rotate, standard views, and the mode picked from a list or
//! by clicking its row in the mode table.
//!
//! The page stays one self-contained file with no network. The drawing is a canvas
//! script of our own (`viewer.js`, a few hundred lines, inlined): an orthographic
//! camera and straight lines are all a trace-line model needs, and inlining a 3-D
//! library such as three.js would add some 600 kB of code we do not need (shaded
//! surfaces, lights, perspective) to every report, and a dependency to audit.
//!
//! The data: each channel placed on a node (its global direction, sign included) adds
//! `shape[channel] · direction` to the node's complex displacement `u`, so a node
//! with channels in several directions moves in 3-D. Each mode is scaled so that its
//! largest `|u|` is 1 and turned so that the largest component there is real; the
//! animation draws `Re(u e^{iφ})` with φ over one cycle (at a fixed pace, not the
//! mode's frequency; a reader whose system asks for reduced motion gets the still at
//! the largest deflection, and Play). A node without channels is drawn where it is, as a hollow dot:
//! nothing is interpolated or guessed. Channels that cannot be drawn are listed below
//! the viewer.

use era::data::identification::Identification;
use era::Complex64;
use std::fmt::Write as _;

/// The script, inlined into the page.
const SCRIPT: &str = include_str!("viewer.js");

/// A channel on a node: which output, which node (index), its global direction.
#[derive(Debug, Clone, PartialEq)]
pub struct Placement {
    /// Output index (0-based), the entry of each mode shape.
    pub channel: usize,
    /// Node index in [`ShapeView::nodes`].
    pub node: usize,
    /// Global direction of a positive value (a unit vector).
    pub direction: [f64; 3],
}

/// One mode on the geometry.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeMode {
    /// What the viewer's caption and list say (`Mode 2: 12.3456 Hz, 1.23 %`).
    pub label: String,
    /// Complex displacement (x, y, z) of each node, largest norm 1; `None` for a node
    /// without channels.
    pub displacement: Vec<Option<[Complex64; 3]>>,
}

/// What the viewer draws: the geometry and the modes on it.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeView {
    /// Node positions, global frame.
    pub nodes: Vec<[f64; 3]>,
    /// Trace-line segments, as node index pairs.
    pub segments: Vec<(usize, usize)>,
    /// Every mode of the table, in its order.
    pub modes: Vec<ShapeMode>,
    /// The channels not drawn, one sentence each (`output 3 (node 3 +Z): …`).
    pub not_drawn: Vec<String>,
}

impl ShapeView {
    /// The modes of `found` on a geometry of `nodes` and `segments`, each output placed
    /// as `placed` says.
    pub fn new(
        nodes: Vec<[f64; 3]>,
        segments: Vec<(usize, usize)>,
        placed: &[Placement],
        found: &Identification,
        not_drawn: Vec<String>,
    ) -> Self {
        let shapes: Vec<(String, &[Complex64])> = found
            .modal
            .modes
            .iter()
            .enumerate()
            .map(|(k, m)| {
                let q = found.quality.get(k);
                let label = mode_label(
                    k,
                    m.frequency_hz,
                    m.damping_ratio,
                    q.map(|q| (q.indicators.mpc, q.physical)),
                );
                (label, m.shape.as_slice())
            })
            .collect();
        Self::from_shapes(nodes, segments, placed, &shapes, not_drawn)
    }

    /// As [`ShapeView::new`], from each mode's label and shape (one entry per output).
    pub fn from_shapes(
        nodes: Vec<[f64; 3]>,
        segments: Vec<(usize, usize)>,
        placed: &[Placement],
        shapes: &[(String, &[Complex64])],
        not_drawn: Vec<String>,
    ) -> Self {
        let modes = shapes
            .iter()
            .map(|(label, shape)| ShapeMode {
                label: label.clone(),
                displacement: node_displacements(nodes.len(), placed, shape),
            })
            .collect();
        ShapeView {
            nodes,
            segments,
            modes,
            not_drawn,
        }
    }

    /// Whether any channel sits on node `k`.
    fn measured(&self, k: usize) -> bool {
        self.modes
            .first()
            .is_some_and(|m| m.displacement.get(k).is_some_and(Option::is_some))
    }

    /// The viewer's data, as JSON: `nodes`, `segments`, `measured` (0/1 per node) and
    /// `modes`, each with its `label` and `u`, one row per measured node
    /// `[node, Re x, Im x, Re y, Im y, Re z, Im z]`.
    pub fn json(&self) -> String {
        let mut s = String::from("{\"nodes\":[");
        for (k, p) in self.nodes.iter().enumerate() {
            let sep = if k > 0 { "," } else { "" };
            let _ = write!(s, "{sep}[{},{},{}]", num(p[0]), num(p[1]), num(p[2]));
        }
        s.push_str("],\"segments\":[");
        for (k, (a, b)) in self.segments.iter().enumerate() {
            let sep = if k > 0 { "," } else { "" };
            let _ = write!(s, "{sep}[{a},{b}]");
        }
        s.push_str("],\"measured\":[");
        for k in 0..self.nodes.len() {
            let sep = if k > 0 { "," } else { "" };
            let _ = write!(s, "{sep}{}", u8::from(self.measured(k)));
        }
        s.push_str("],\"modes\":[");
        for (k, m) in self.modes.iter().enumerate() {
            let sep = if k > 0 { "," } else { "" };
            let _ = write!(s, "{sep}{{\"label\":\"{}\",\"u\":[", json_text(&m.label));
            let mut first = true;
            for (n, u) in m.displacement.iter().enumerate() {
                let Some(u) = u else { continue };
                let sep = if first { "" } else { "," };
                first = false;
                let _ = write!(s, "{sep}[{n}");
                for c in u {
                    let _ = write!(s, ",{},{}", short(c.re), short(c.im));
                }
                s.push(']');
            }
            s.push_str("]}");
        }
        s.push_str("]}");
        s
    }
}

/// A mode's label in the viewer and the pictures: `Mode 2: 12.3456 Hz, damping
/// 1.234 %, MPC 0.998`, and ` (not judged physical)` when it is not.
pub fn mode_label(
    k: usize,
    frequency_hz: f64,
    damping_ratio: f64,
    quality: Option<(f64, bool)>,
) -> String {
    let mut label = format!(
        "Mode {}: {:.4} Hz, damping {:.3} %",
        k + 1,
        frequency_hz,
        100.0 * damping_ratio
    );
    if let Some((mpc, physical)) = quality {
        let _ = write!(label, ", MPC {mpc:.3}");
        if !physical {
            label.push_str(" (not judged physical)");
        }
    }
    label
}

/// Each node's complex displacement: `Σ shape[channel] · direction` over its channels,
/// scaled so that the largest norm is 1 and turned so that the largest component of
/// that node is real and positive. `None` for a node without channels.
pub fn node_displacements(
    nodes: usize,
    placed: &[Placement],
    shape: &[Complex64],
) -> Vec<Option<[Complex64; 3]>> {
    let mut u: Vec<Option<[Complex64; 3]>> = vec![None; nodes];
    for p in placed {
        let (Some(slot), Some(&v)) = (u.get_mut(p.node), shape.get(p.channel)) else {
            continue;
        };
        let v = if v.is_finite() {
            v
        } else {
            Complex64::new(0.0, 0.0)
        };
        let d = slot.get_or_insert([Complex64::new(0.0, 0.0); 3]);
        for (da, e) in d.iter_mut().zip(p.direction) {
            *da += v * e;
        }
    }
    let norm = |d: &[Complex64; 3]| d.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt();
    let largest = u
        .iter()
        .flatten()
        .max_by(|a, b| norm(a).total_cmp(&norm(b)))
        .copied();
    if let Some(d) = largest {
        let top = d
            .iter()
            .copied()
            .max_by(|a, b| a.norm().total_cmp(&b.norm()))
            .unwrap_or_default();
        let size = norm(&d);
        if size > 0.0 && top.norm() > 0.0 {
            let turn = top.conj() / (top.norm() * size);
            for d in u.iter_mut().flatten() {
                for c in d.iter_mut() {
                    *c *= turn;
                }
            }
        }
    }
    u
}

/// A coordinate in JSON: six significant digits.
fn num(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        "0".into()
    } else {
        format!("{x:.5e}")
    }
}

/// A displacement component in JSON (at most 1 in size): four decimals.
fn short(x: f64) -> String {
    let s = format!("{x:.4}");
    match s.as_str() {
        "0.0000" | "-0.0000" => "0".into(),
        _ => s,
    }
}

/// Text inside a JSON string inside a `<script>`: quotes, backslashes and control
/// characters escaped, and `<` written `\u003c` so that no `</script>` can close it.
fn json_text(text: &str) -> String {
    let mut s = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '"' => s.push_str("\\\""),
            '\\' => s.push_str("\\\\"),
            '<' => s.push_str("\\u003c"),
            c if (c as u32) < 0x20 => {
                let _ = write!(s, "\\u{:04x}", c as u32);
            }
            c => s.push(c),
        }
    }
    s
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The report's shapes section: the viewer when there is a geometry, otherwise one
/// line saying that there is none.
pub fn shapes_html(view: Option<&ShapeView>) -> String {
    let Some(v) = view else {
        return "<p id=\"shapes-none\">No test geometry was given, so the mode shapes are not drawn (identify, refine and oma take --geometry FILE).</p>\n".into();
    };
    if v.modes.is_empty() {
        return "<p id=\"shapes-none\">The model has no modes to draw on the test geometry.</p>\n"
            .into();
    }
    let mut h = String::from(
        "<h2 id=\"shapes\">Mode shapes</h2>\n<style>\
#shape-viewer canvas{width:100%;height:480px;border:1px solid #ccc;touch-action:none;cursor:grab;display:block}\
#shape-controls{display:flex;flex-wrap:wrap;gap:.4em 1em;align-items:center;margin:.5em 0}\
#modal-table tr.shape-pickable{cursor:pointer} #modal-table tr.shape-picked td{background:#e6efff}\
</style>\n",
    );
    let measured = (0..v.nodes.len()).filter(|&k| v.measured(k)).count();
    let _ = writeln!(
        h,
        "<p>Each mode on the test geometry ({} nodes, {} of them with channels, {} trace-line segments), animated over one cycle: the deformed structure (blue) over the undeformed one (grey, dashed). A hollow dot is a node without channels, drawn where it is. Drag to rotate; “three views” shows the front, side and top side by side (as the pictures shapes/mode_NN.svg and .png beside the report do); click a row of the mode table to show its mode. The amplitude is the largest displacement as a share of the structure's size.</p>",
        v.nodes.len(),
        measured,
        v.segments.len()
    );
    h.push_str("<div id=\"shape-viewer\"><div id=\"shape-controls\"><label>Mode <select id=\"shape-mode\">");
    for (k, m) in v.modes.iter().enumerate() {
        let _ = write!(h, "<option value=\"{k}\">{}</option>", escape(&m.label));
    }
    h.push_str("</select></label><button type=\"button\" id=\"shape-play\" aria-pressed=\"true\">Pause</button>\
<label>Amplitude <input type=\"range\" id=\"shape-amplitude\" min=\"0\" max=\"40\" step=\"1\" value=\"10\"> <span id=\"shape-amplitude-value\">10 %</span></label>\
<span>View <button type=\"button\" data-shape-view=\"iso\">3-D</button> <button type=\"button\" data-shape-view=\"front\">front (x–z)</button> <button type=\"button\" data-shape-view=\"side\">side (y–z)</button> <button type=\"button\" data-shape-view=\"top\">top (x–y)</button> <button type=\"button\" data-shape-view=\"three\">three views</button></span></div>\n");
    let _ = write!(
        h,
        "<canvas id=\"shape-canvas\" role=\"img\" aria-label=\"Animated mode shape\"></canvas>\n<p id=\"shape-caption\">{}</p></div>\n",
        escape(&v.modes[0].label)
    );
    if v.not_drawn.is_empty() {
        h.push_str("<p id=\"shapes-not-drawn\">Every output channel is drawn.</p>\n");
    } else {
        let _ = write!(
            h,
            "<p>{} output channel(s) not drawn:</p>\n<ul id=\"shapes-not-drawn\">",
            v.not_drawn.len()
        );
        for n in &v.not_drawn {
            let _ = write!(h, "<li>{}</li>", escape(n));
        }
        h.push_str("</ul>\n");
    }
    let _ = write!(
        h,
        "<script type=\"application/json\" id=\"era-shapes\">{}</script>\n<script>\n{}</script>\n",
        v.json(),
        SCRIPT
    );
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(re: f64, im: f64) -> Complex64 {
        Complex64::new(re, im)
    }

    #[test]
    fn channels_on_one_node_add_up_to_a_3d_displacement_scaled_to_one() {
        // Node 1 has +X and -Z channels; node 0 a +Y one; node 2 none.
        let placed = [
            Placement {
                channel: 0,
                node: 1,
                direction: [1.0, 0.0, 0.0],
            },
            Placement {
                channel: 1,
                node: 1,
                direction: [0.0, 0.0, -1.0],
            },
            Placement {
                channel: 2,
                node: 0,
                direction: [0.0, 1.0, 0.0],
            },
        ];
        // Shape rotated by 90°: the largest component (channel 1, -4i on -Z → +4i on
        // z) is made real and positive.
        let shape = [c(0.0, 3.0), c(0.0, -4.0), c(0.0, 1.0)];
        let u = node_displacements(3, &placed, &shape);
        assert!(u[2].is_none());
        let n1 = u[1].unwrap();
        let close = |a: Complex64, b: Complex64| (a - b).norm() < 1e-12;
        assert!(close(n1[0], c(0.6, 0.0)), "{:?}", n1);
        assert!(close(n1[1], c(0.0, 0.0)));
        assert!(close(n1[2], c(0.8, 0.0)));
        let n0 = u[0].unwrap();
        assert!(close(n0[1], c(0.2, 0.0)), "{:?}", n0);
    }

    #[test]
    fn json_text_cannot_close_the_script() {
        assert_eq!(
            json_text("a\"</script>\\\n"),
            "a\\\"\\u003c/script>\\\\\\u000a"
        );
    }

    #[test]
    fn without_geometry_one_line_and_no_script() {
        let h = shapes_html(None);
        assert_eq!(h.lines().count(), 1);
        assert!(!h.contains("<script"));
    }
}
