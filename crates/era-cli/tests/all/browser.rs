//! report.html in a real browser: headless Chromium (Debian's `chromium`, which `.ci/run`
//! installs when absent) renders the page from disk, with no network. The rendered DOM
//! must hold every figure and table, and a screenshot must not be blank.
//!
//! Without a Chromium on the machine the test says so on stderr and passes: a developer
//! without a browser can still run the suite, and CI always has one.

use crate::common;
use common::assert_success;

use common::era;
use std::path::{Path, PathBuf};
use std::process::Command;

fn chromium() -> Option<PathBuf> {
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .find_map(|name| {
            std::env::var_os("PATH")?
                .to_str()?
                .split(':')
                .map(|dir| Path::new(dir).join(name))
                .find(|p| p.is_file())
        })
}

/// Runs headless Chromium on `page` with the given extra flags (loopback only: no
/// background networking, no component updates, a fresh profile).
fn headless(browser: &Path, profile: &Path, page: &Path, extra: &[&str]) -> std::process::Output {
    Command::new("timeout")
        .arg("120")
        .arg(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--disable-dev-shm-usage",
            "--no-first-run",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(extra)
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("run chromium")
}

#[test]
fn report_renders_in_a_headless_browser() {
    let Some(browser) = chromium() else {
        eprintln!("SKIPPED report_renders_in_a_headless_browser: no chromium on PATH (.ci/run installs Debian's chromium)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    era()
        .args(["demo", "-q", "--out"])
        .arg(&out)
        .assert()
        .success();
    let page = out.join("noisy").join("report.html");

    let dom = headless(&browser, &dir.path().join("p1"), &page, &["--dump-dom"]);
    assert_success(&dom);
    let dom = String::from_utf8_lossy(&dom.stdout);
    // Singular values + AutoMAC + complexity + grid + 9 overlays, each a rendered <svg>
    // in its <figure>.
    assert_eq!(dom.matches("<svg").count(), 13, "rendered SVG elements");
    for id in [
        "fig-singular-values",
        "fig-grid",
        "modal-table",
        "fit-table",
        "parameters",
        "input-facts",
    ] {
        assert!(
            dom.contains(&format!("id=\"{id}\"")),
            "{id} missing from the rendered page"
        );
    }
    for k in 1..=9 {
        assert!(
            dom.contains(&format!("id=\"fig-pair-{k}\"")),
            "overlay {k} missing"
        );
    }
    // The pair picker's script ran in the page: it counts what it shows.
    assert!(dom.contains("9 of 9 shown"), "the pair picker did not run");
    // The modal table (a header and 4 modes) and the fit matrix (a header and one row
    // per output of the 3 x 3 set).
    assert_eq!(
        dom.matches("<tr>").count() + dom.matches("<tr class").count(),
        1 + 4 + 1 + 3,
        "table rows"
    );

    let shot = dir.path().join("shot.png");
    let run = headless(
        &browser,
        &dir.path().join("p2"),
        &page,
        &[
            "--window-size=1200,2400",
            &format!("--screenshot={}", shot.display()),
        ],
    );
    assert_success(&run);
    let img = image::open(&shot).expect("a PNG screenshot").to_rgb8();
    let total = (img.width() * img.height()) as f64;
    let inked = img
        .pixels()
        .filter(|p| p.0.iter().any(|c| *c < 200))
        .count() as f64;
    let mut colours: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    colours.sort_unstable();
    colours.dedup();
    assert!(
        inked / total > 0.02,
        "the page looks blank: {:.3} % inked",
        100.0 * inked / total
    );
    assert!(
        colours.len() > 50,
        "only {} colours: plots not drawn?",
        colours.len()
    );
}
