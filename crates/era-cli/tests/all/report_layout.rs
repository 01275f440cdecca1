//! The report's layout: a table of contents whose links resolve, a summary that says
//! what the model files say, the sections in reading order, the pairs chosen with
//! `--pairs`, the model named in the legends, and singular values past a fixed order.

use crate::common;

use common::{era, expect_input_error, read, s, simulate_modal};
use std::path::{Path, PathBuf};

/// A 3 x 3 acceleration set of 4 modes with a little noise.
fn small_set(dir: &Path) -> PathBuf {
    simulate_modal(
        dir,
        "small.csv",
        &[
            "--outputs",
            "3",
            "--inputs",
            "3",
            "--modes",
            "4",
            "--fmin",
            "1",
            "--fmax",
            "6",
            "--lines",
            "401",
            "--df",
            "0.025",
            "--collocated",
            "--noise",
            "0.02",
            "--seed",
            "5",
        ],
    )
}

/// The value of attribute `name` in the first element with `id`.
fn attribute(html: &str, id: &str, name: &str) -> String {
    let at = html
        .find(&format!("id=\"{id}\""))
        .unwrap_or_else(|| panic!("no {id}"));
    let tag = &html[at..at + html[at..].find('>').unwrap()];
    let key = format!("{name}=\"");
    let start = tag
        .find(&key)
        .unwrap_or_else(|| panic!("no {name} on {id}"))
        + key.len();
    tag[start..start + tag[start..].find('"').unwrap()].to_string()
}

#[test]
fn the_report_opens_with_contents_and_a_summary_that_agree_with_the_model() {
    let dir = tempfile::tempdir().unwrap();
    let file = small_set(dir.path());
    let out = dir.path().join("out");
    era()
        .args([
            "identify",
            s(&file),
            "--states",
            "auto",
            "--refine",
            "-q",
            "--out",
        ])
        .arg(&out)
        .assert()
        .success();
    let html = read(out.join("report.html"));
    // Every link of the contents leads to an element of the page, and the contents
    // name the sections the page has.
    let nav = &html[html.find("<nav id=\"toc\">").expect("contents")..];
    let nav = &nav[..nav.find("</nav>").unwrap()];
    let links: Vec<&str> = nav
        .split("href=\"#")
        .skip(1)
        .map(|l| &l[..l.find('"').unwrap()])
        .collect();
    for id in [
        "summary",
        "modes",
        "stabilization",
        "fit",
        "singular-values",
        "grid",
        "overlays",
        "input",
        "parameters",
    ] {
        assert!(
            links.contains(&id),
            "{id} missing from the contents: {links:?}"
        );
    }
    for id in &links {
        assert_eq!(
            html.matches(&format!("id=\"{id}\"")).count(),
            1,
            "the link #{id} leads to one element"
        );
    }
    // The reading order: contents, summary, modes, stabilization, fit, pairs, input.
    let at = |needle: &str| html.find(needle).unwrap_or_else(|| panic!("{needle}"));
    let order = [
        "id=\"toc\"",
        "id=\"summary\"",
        "id=\"modal-table\"",
        "id=\"fig-stabilization\"",
        "id=\"fit-table\"",
        "id=\"fig-singular-values\"",
        "id=\"fig-grid\"",
        "id=\"pairs\"",
        "id=\"input-facts\"",
        "id=\"parameters\"",
    ];
    for w in order.windows(2) {
        assert!(at(w[0]) < at(w[1]), "{} before {}", w[0], w[1]);
    }
    // The summary's numbers are the model's.
    let model: serde_json::Value = serde_json::from_str(&read(out.join("model.json"))).unwrap();
    let modes = model["modes"].as_array().unwrap();
    let physical = modes.iter().filter(|m| m["physical"] == true).count();
    assert_eq!(
        attribute(&html, "summary-modes", "data-modes"),
        modes.len().to_string()
    );
    assert_eq!(
        attribute(&html, "summary-modes", "data-physical"),
        physical.to_string()
    );
    assert_eq!(
        attribute(&html, "summary-model", "data-states"),
        model["states"].to_string()
    );
    let summary = &html[at("id=\"summary\"")..at("id=\"modes\"")];
    assert!(summary.contains("refined"), "{summary}");
    let fit: serde_json::Value = serde_json::from_str(&read(out.join("fit.json"))).unwrap();
    let expected = fit["collocated_mean_relative_error"]
        .as_f64()
        .expect("fit.json mean");
    let shown: f64 = summary
        .split("data-error=\"")
        .nth(1)
        .and_then(|t| t[..t.find('"')?].parse().ok())
        .expect("the collocated mean in the summary");
    assert!(
        (shown - expected).abs() <= 1e-12 * expected.abs(),
        "{shown} vs {expected}"
    );
    // Errors read in percent: the summary, the fit matrix and the refinement line.
    assert!(summary.contains(&format!("{:.2} %", 100.0 * expected)) || summary.contains(" %"));
    let table = &html[at("id=\"fit-table\"")..];
    let table = &table[..table.find("</table>").unwrap()];
    assert_eq!(table.matches(" %<br>").count(), 9, "each cell in percent");
    assert!(!table.contains("e-"), "no e-notation in the fit matrix");
    let refinement = &html[at("id=\"refinement\"")..];
    let refinement = &refinement[..refinement.find("</p>").unwrap()];
    assert!(refinement.contains(" % to "), "{refinement}");
    let warnings = attribute(&html, "summary-warnings", "data-count");
    assert_eq!(
        warnings,
        model["warnings"].as_array().unwrap().len().to_string()
    );
    // After --refine the legends and the grid's title name the refined model.
    let pair = read(out.join("pairs/pair_1_2.svg"));
    assert!(pair.contains("refined model") && !pair.contains("ERA model"));
    assert!(read(out.join("grid.svg")).contains("refined model (dashed)"));
    // The picker lists the outputs and inputs, and every pair is in the grid of pairs.
    assert_eq!(html.matches("class=\"plot overlay\"").count(), 9);
    assert!(html.contains("id=\"pair-picker\"") && html.contains("id=\"pair-collocated\""));
    assert_eq!(html.matches("data-collocated=\"1\"").count(), 3);
}

#[test]
fn pairs_writes_and_shows_only_the_chosen_pairs() {
    let dir = tempfile::tempdir().unwrap();
    let file = small_set(dir.path());
    let listed = |folder: &Path| {
        let mut names: Vec<String> = std::fs::read_dir(folder.join("pairs"))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    };
    let plot = dir.path().join("plot");
    era()
        .args([
            "plot",
            s(&file),
            "-q",
            "--pairs",
            "3:1, 1:2",
            "--out",
            s(&plot),
        ])
        .assert()
        .success();
    assert_eq!(
        listed(&plot),
        [
            "pair_1_2.png",
            "pair_1_2.svg",
            "pair_3_1.png",
            "pair_3_1.svg"
        ]
    );
    // The grid still shows every pair.
    assert!(read(plot.join("grid.svg")).contains("Y3 / F3"));
    let out = dir.path().join("out");
    era()
        .args([
            "identify",
            s(&file),
            "--states",
            "8",
            "--pairs",
            "collocated",
            "-q",
        ])
        .args(["--out", s(&out)])
        .assert()
        .success();
    assert_eq!(listed(&out).len(), 2 * 3);
    let html = read(out.join("report.html"));
    assert_eq!(html.matches("class=\"plot overlay\"").count(), 3);
    assert_eq!(html.matches("data-collocated=\"1\"").count(), 3);
    assert!(html.contains("3 of the 9 pairs"));
    let refined = dir.path().join("refined");
    era()
        .args([
            "refine",
            s(&out.join("model.json")),
            s(&file),
            "--pairs",
            "2:3",
            "-q",
        ])
        .args(["--out", s(&refined)])
        .assert()
        .success();
    assert_eq!(listed(&refined), ["pair_2_3.png", "pair_2_3.svg"]);
    // Bad values: exit 2, the flag and the value named, nothing written.
    for (verb, bad) in [
        ("plot", "1:x"),
        ("plot", "0:1"),
        ("plot", "4:1"),
        ("identify", "1:9"),
        ("identify", "diagonal"),
        ("refine", "3:4"),
    ] {
        let target = dir
            .path()
            .join(format!("bad-{verb}-{}", bad.replace(':', "_")));
        let model = out.join("model.json");
        let mut args = match verb {
            "plot" => vec!["plot", s(&file)],
            "identify" => vec!["identify", s(&file), "--states", "8"],
            _ => vec!["refine", s(&model), s(&file)],
        };
        args.extend(["--pairs", bad, "-q", "--out", s(&target)]);
        let stderr = expect_input_error(&args, "--pairs");
        assert!(stderr.contains(bad), "{verb} --pairs {bad}: {stderr}");
        assert!(!target.join("report.html").exists() && !target.join("pairs").exists());
    }
}
