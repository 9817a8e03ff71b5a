//! The runner the CLI tests share: the `glint` binary cargo built for them, run with
//! arguments, and the two outcomes tests check (success with its stdout, failure with
//! one line on stderr).

// Each test binary uses some of these.
#![allow(dead_code)]

use std::process::{Command, Output};

/// Runs `glint ARGS`, waiting for it; its status and output.
pub fn glint(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(args)
        .output()
        .expect("run glint")
}

/// `glint ARGS`, which must succeed; its stdout.
pub fn ok(args: &[&str]) -> String {
    let out = glint(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("UTF-8 on stdout")
}

/// `glint ARGS`, which must fail with one line on stderr; that line.
pub fn fails(args: &[&str]) -> String {
    let out = glint(args);
    assert!(!out.status.success(), "{args:?} succeeded");
    let err = String::from_utf8(out.stderr).expect("UTF-8 on stderr");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    err
}
