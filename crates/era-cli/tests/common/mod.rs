//! Helpers shared by the CLI tests.
#![allow(dead_code)]

use assert_cmd::Command;

/// The `era` binary under test.
pub fn era() -> Command {
    Command::cargo_bin("era").unwrap()
}

/// Runs `era` and expects exit code 2 with `needle` in stderr, and no panic.
pub fn expect_input_error(args: &[&str], needle: &str) {
    let out = era().args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(
        stderr.contains(needle),
        "{args:?}: expected '{needle}' in: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
}
