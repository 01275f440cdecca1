//! What the figures and report.html say about the data: units from the input file,
//! wrapped phase, collocation from the channel table, the input section, the fit
//! matrix, the dashed legend, coherence, and the size of an 8 x 8 report.

use crate::common;

use common::{era, read, s, simulate_modal, DTA_SETTINGS};
use std::path::{Path, PathBuf};

/// A 2 x 2 acceleration set (3 modes) with SI units and a channel table in which
/// output 1 (node 11) and input 1 (node 101) are not collocated, but output 2 and
/// input 2 (node 5, +Z) are.
fn si_set(dir: &Path) -> PathBuf {
    let plain = simulate_modal(
        dir,
        "plain.csv",
        &[
            "--outputs",
            "2",
            "--inputs",
            "2",
            "--modes",
            "3",
            "--fmin",
            "1",
            "--fmax",
            "4",
            "--lines",
            "201",
            "--df",
            "0.05",
            "--collocated",
            "--seed",
            "3",
        ],
    );
    let text = std::fs::read_to_string(&plain).unwrap();
    let file = dir.join("si.csv");
    std::fs::write(
        &file,
        format!(
            "# response_unit: m/s^2\n# force_unit: N\n# output_1: node 11 +Z\n# output_2: node 5 +Z\n# input_1: node 101 +Z\n# input_2: node 5 +Z\n{text}"
        ),
    )
    .unwrap();
    file
}

#[test]
fn si_units_channel_table_and_input_section_reach_figures_and_report() {
    let dir = tempfile::tempdir().unwrap();
    let file = si_set(dir.path());
    // Plotted as read: (m/s^2)/N, never imperial.
    let plots = dir.path().join("plots");
    era()
        .args(["plot", s(&file), "-q", "--out", s(&plots)])
        .assert()
        .success();
    for svg in ["grid.svg", "pairs/pair_1_2.svg"] {
        let text = read(plots.join(svg));
        assert!(text.contains("(m/s²)/N"), "{svg}: units typeset");
        assert!(!text.contains("lbf") && !text.contains("in/s"), "{svg}");
    }
    assert!(read(plots.join("pairs/pair_1_2.svg")).contains("Phase (deg, wrapped)"));
    // Unwrapped only when asked.
    let unwrapped = dir.path().join("unwrapped");
    era()
        .args([
            "plot",
            s(&file),
            "-q",
            "--phase",
            "unwrapped",
            "--out",
            s(&unwrapped),
        ])
        .assert()
        .success();
    assert!(read(unwrapped.join("pairs/pair_1_2.svg")).contains("Phase (deg, unwrapped)"));
    // Identified after one integration: the figures say (m/s)/N.
    let out = dir.path().join("out");
    era()
        .args([
            "identify",
            s(&file),
            "--states",
            "6",
            "--integrations",
            "1",
            "-q",
            "--out",
            s(&out),
        ])
        .assert()
        .success();
    let pair = read(out.join("pairs/pair_1_1.svg"));
    assert!(pair.contains("|G| (m/s)/N") && !pair.contains("lbf"));
    assert!(pair.contains("Phase (deg, wrapped)"));
    let html = read(out.join("report.html"));
    // The input section: file, format, quantity, units, channel table, command line,
    // version and date.
    let input = &html[html.find("id=\"input\"").expect("input section")
        ..html.find("id=\"parameters\"").unwrap()];
    for needle in [
        s(&file),
        "CSV",
        "acceleration",
        "(m/s²)/N",
        "--integrations 1",
        env!("CARGO_PKG_VERSION"),
        " UTC",
        "<td>101</td>",
        "<td>11</td>",
        "+Z",
    ] {
        assert!(input.contains(needle), "{needle} missing from: {input}");
    }
    // Collocation from the channel table: 2/2 (node 5 with node 5), not 1/1 (11 vs 101).
    // Neutral words, with where each channel is.
    assert!(html.contains("output 2 (node 5 +Z) / input 2 (node 5 +Z) (collocated)"));
    assert!(html.contains("output 1 (node 11 +Z) / input 1 (node 101 +Z)"));
    assert!(!html.contains("output 1 (node 11 +Z) / input 1 (node 101 +Z) (collocated)"));
    assert!(!html.contains("Excitation Actuator"));
    // fit.json and model.json's run say the same: one collocated pair, 2/2.
    let fit: serde_json::Value = serde_json::from_str(&read(out.join("fit.json"))).unwrap();
    let collocated: Vec<(u64, u64)> = fit["pairs"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["collocated"] == true)
        .map(|p| (p["output"].as_u64().unwrap(), p["input"].as_u64().unwrap()))
        .collect();
    assert_eq!(collocated.len(), 1, "{fit}");
    assert!(
        collocated[0] == (2, 2) || collocated[0] == (1, 1),
        "{collocated:?}"
    );
    let first = &fit["pairs"][0];
    assert_eq!(
        first["collocated"], false,
        "output 1 (node 11) with input 1 (node 101)"
    );
    // The refinement keeps the table's collocation in its fit.
    let refined = dir.path().join("refined");
    era()
        .args([
            "identify",
            s(&file),
            "--states",
            "6",
            "--refine",
            "-q",
            "--out",
        ])
        .arg(&refined)
        .assert()
        .success();
    let fit: serde_json::Value = serde_json::from_str(&read(refined.join("fit.json"))).unwrap();
    let flags: Vec<bool> = fit["pairs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["collocated"].as_bool().unwrap())
        .collect();
    assert_eq!(flags, [false, false, false, true], "{fit}");
    // The fit is a 2 x 2 matrix: a header with the inputs, one row per output, the
    // collocated cell shaded.
    let table = &html[html
        .find("<table id=\"fit-table\" class=\"matrix\">")
        .unwrap()..];
    let table = &table[..table.find("</table>").unwrap()];
    assert_eq!(table.matches("<tr>").count(), 1 + 2);
    assert!(table.contains("<th>1</th><th>2</th>"));
    assert_eq!(table.matches("<td class=\"col\">").count(), 1);
    assert_eq!(table.matches("<td").count(), 4);
    let rows: Vec<&str> = table.split("<tr>").collect();
    assert!(
        rows[3].contains("class=\"col\""),
        "output 2's row holds the shaded cell"
    );
    // Each pair's title once: drawn in its figure, not repeated as a caption.
    assert!(!html.contains("<figcaption>"));
    assert_eq!(
        html.matches("\noutput 1 (node 11 +Z) / input 2 (node 5 +Z)\n")
            .count(),
        1
    );
    // The legend and curve of the model are dashed (a dashed style, no solid copy).
    assert!(html.contains("stroke-dasharray:6 4"));
    // The grid has axis titles with units.
    let grid = read(out.join("grid.svg"));
    assert!(grid.contains("|G| (m/s)/N") && grid.contains("Frequency (Hz)"));
}

#[test]
fn the_demo_says_its_units_are_inches_and_pounds_force() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    era()
        .args(["demo", "-q", "--out", s(&out)])
        .assert()
        .success();
    assert!(read(out.join("truth_frf.csv")).contains("# response_unit: in"));
    assert!(read(out.join("noisy/pairs/pair_1_2.svg")).contains("|G| in/lbf"));
    let html = read(out.join("noisy/report.html"));
    assert!(html.contains("<dd>in/lbf</dd>"));
    assert!(html.contains("synthetic"));
}

#[test]
fn an_8x8_report_stays_under_2_mb() {
    let dir = tempfile::tempdir().unwrap();
    let file = simulate_modal(
        dir.path(),
        "dta.csv",
        &["--collocated", "--seed", "3", "--noise", "0.15"],
    );
    let out = dir.path().join("out");
    era()
        .args(["identify", s(&file), "-q", "--states", "80"])
        .args(DTA_SETTINGS)
        .args(["--out", s(&out)])
        .assert()
        .success();
    let size = std::fs::metadata(out.join("report.html")).unwrap().len();
    // It was 7.2-7.7 MB before the styles were shared and the curves thinned.
    assert!(size < 2_000_000, "report.html is {size} bytes");
    let html = read(out.join("report.html"));
    assert_eq!(html.matches("class=\"plot overlay\"").count(), 64);
    // Each figure once: 64 overlays, the grid, the singular values, the AutoMAC and the
    // complexity.
    assert_eq!(html.matches("<svg").count(), 68);
    // The fixed order's H0 (1592 x 1592) went matrix-free, which computes its 80 values
    // only: the figure shows more of the same H0, so that the gap after the order
    // shows; the model keeps the run's values.
    let svg = read(out.join("singular_values.svg"));
    let title = &svg[svg.find("Hankel singular values (").expect("title")..];
    let shown: usize = title["Hankel singular values (".len()..]
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let model: serde_json::Value = serde_json::from_str(&read(out.join("model.json"))).unwrap();
    let kept = model["singular_values"].as_array().unwrap().len();
    assert!(html.contains("matrix-free path"));
    assert!(
        shown > 80 && kept <= 80,
        "{shown} shown, {kept} in model.json"
    );
    assert!(title.contains("order 80)"));
}

#[test]
fn from_time_reports_the_coherence() {
    let dir = tempfile::tempdir().unwrap();
    // One force, one response of a lightly damped resonance, 4096 samples at 1 kHz.
    let mut csv = String::from("time_s,f,y\n");
    let (mut y1, mut y2, mut state) = (0.0f64, 0.0f64, 7u64);
    for k in 0..4096 {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let f = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
        let y = 1.8 * y1 - 0.95 * y2 + f;
        csv.push_str(&format!("{},{f},{y}\n", k as f64 * 1e-3));
        (y2, y1) = (y1, y);
    }
    let time = dir.path().join("time.csv");
    std::fs::write(&time, csv).unwrap();
    let out = dir.path().join("out");
    era()
        .args([
            "identify",
            "--from-time",
            s(&time),
            "--inputs",
            "f",
            "--outputs",
            "y",
            "--frame",
            "256",
            "--states",
            "2",
            "-q",
            "--out",
            s(&out),
        ])
        .assert()
        .success();
    assert!(out.join("coherence.svg").is_file() && out.join("coherence.png").is_file());
    let html = read(out.join("report.html"));
    assert!(html.contains("id=\"fig-coherence\""));
    assert!(html.contains("time histories"));
    // The time file says nothing of units: unknown, not assumed.
    assert!(html.contains("<dd>unit/unit</dd>"));
    // In two steps: `era frf` writes the coherence beside the FRF file, and identify
    // shows it from there.
    let frf = dir.path().join("frf.csv");
    era()
        .args([
            "frf",
            s(&time),
            "--inputs",
            "f",
            "--outputs",
            "y",
            "--frame",
            "256",
            "-q",
            "--out",
            s(&frf),
        ])
        .assert()
        .success();
    assert!(dir.path().join("frf.coherence.csv").is_file());
    // The report of `frf` identified at 2 states into the folder `name`.
    let report_of = |name: &str| {
        let out = dir.path().join(name);
        era()
            .args(["identify", s(&frf), "--states", "2", "-q", "--out", s(&out)])
            .assert()
            .success();
        read(out.join("report.html"))
    };
    let html = report_of("out2");
    assert!(html.contains("id=\"fig-coherence\""));
    assert!(html.contains("frf.coherence.csv"));
    // A companion that does not fit the FRF file is left out, with a note.
    let bad = dir.path().join("frf.coherence.csv");
    let text = read(&bad);
    std::fs::write(&bad, text.lines().take(10).collect::<Vec<_>>().join("\n")).unwrap();
    let html = report_of("out3");
    assert!(!html.contains("id=\"fig-coherence\""));
    assert!(html.contains("coherence file ignored"));
}
