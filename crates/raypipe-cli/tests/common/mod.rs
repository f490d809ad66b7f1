//! Shared support of the command line's tests: running the binary, and what a clean error is.
#![allow(dead_code)]

#[path = "../../../raypipe/tests/common/harness.rs"]
pub mod harness;
#[path = "../../../raypipe/tests/common/models.rs"]
pub mod models;

use std::process::{Command, Output};

/// Runs the raypipe binary with `args`.
pub fn raypipe(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raypipe")).args(args).output().unwrap()
}

/// Exit code 2, exactly one line on stderr that starts with `error:` and contains every `needle`.
pub fn assert_clean_error(output: &Output, needles: &[&str]) {
    let stderr = String::from_utf8_lossy(&output.stderr);
    let lines: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(output.status.code(), Some(2), "stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(lines.len(), 1, "one error line expected: {stderr}");
    for needle in needles {
        assert!(lines[0].contains(needle), "{needle:?} not in {:?}", lines[0]);
    }
}
