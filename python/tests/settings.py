"""Argument lists the Python tests share: the thesis's settings for the 8-state truth
model and for the DTA-like set at 80 states, as Python keywords and as CLI flags (the
Rust tests' `era_testkit::cli::TRUTH_SETTINGS` and `DTA_SETTINGS`)."""

TRUTH_SETTINGS = dict(hankel_factor=4, pad_to=1024)
TRUTH_FLAGS = ["--hankel-factor", "4", "--pad-to", "1024"]

DTA_SETTINGS = dict(hankel_factor=5, integrations=1, zero_lines=3, pad_to=1024)
DTA_FLAGS = ["--hankel-factor", "5", "--integrations", "1", "--zero-lines", "3", "--pad-to", "1024"]
