//! Shared support of the command line's tests: running the binary, and what a clean error is.
#![allow(dead_code)]

// Not every test binary uses both.
#[allow(unused_imports)]
pub use raypipe_test_support::{self as harness, models};

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A fresh, empty folder for a test's files ([`harness::fresh_dir`]).
pub fn test_dir(name: &str) -> PathBuf {
    harness::fresh_dir(PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name))
}

/// Runs the raypipe binary with `args`.
pub fn raypipe(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raypipe")).args(args).output().unwrap()
}

/// raypipe run on a terminal, as a user runs it (util-linux's `script` gives it a pseudo-terminal):
/// what the terminal showed, carriage returns as line breaks, and whether it succeeded.
pub fn raypipe_on_a_terminal(args: &[&str]) -> (bool, String) {
    let quoted: Vec<String> = std::iter::once(env!("CARGO_BIN_EXE_raypipe"))
        .chain(args.iter().copied())
        .map(|a| format!("'{}'", a.replace('\'', "'\\''")))
        .collect();
    let output = Command::new("script")
        .args(["-qec", &quoted.join(" "), "/dev/null"])
        .stdin(std::process::Stdio::null())
        .output()
        .expect("util-linux's script runs");
    let shown = String::from_utf8_lossy(&output.stdout).replace('\r', "\n");
    (output.status.success(), shown)
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

/// `scene` at `width` x `height` on the CPU, written to `path`.
pub fn render_on_cpu(scene: &str, path: &Path, width: u32, height: u32) {
    let (w, h) = (width.to_string(), height.to_string());
    let args = [
        "render",
        scene,
        "--device",
        "cpu",
        "--width",
        &w,
        "--height",
        &h,
        "-q",
        "-o",
        path.to_str().unwrap(),
    ];
    let output = raypipe(&args);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
}
