//! Progress on stderr (indicatif): a spinner for the pipeline stages and a bar for the
//! pair figures. Hidden with `--quiet` and whenever stderr is not a terminal (indicatif
//! draws nothing then), so pipes, files and CI logs stay clean.

use crate::config::Settings;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::time::Duration;

fn target(settings: &Settings) -> ProgressDrawTarget {
    if !settings.progress {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    }
}

/// A spinner whose message names the current stage.
pub fn spinner(settings: &Settings) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(None, target(settings));
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg} [{elapsed}]").expect("static template"),
    );
    bar.enable_steady_tick(Duration::from_millis(120));
    bar
}

/// A bar over `len` items.
pub fn bar(settings: &Settings, len: u64, message: &str) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(len), target(settings));
    bar.set_style(
        ProgressStyle::with_template("{msg} {bar:30} {pos}/{len} [{elapsed}]")
            .expect("static template"),
    );
    bar.set_message(message.to_string());
    bar
}

/// A bar over a batch's records: done, failed (the message) and the time left.
pub fn records_bar(settings: &Settings, len: u64) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(len), target(settings));
    bar.set_style(
        ProgressStyle::with_template(
            "records {bar:30} {pos}/{len}, {msg} [{elapsed} elapsed, {eta} left]",
        )
        .expect("static template"),
    );
    bar.set_message("0 failed");
    bar.enable_steady_tick(Duration::from_millis(250));
    bar
}
