//! Helpers shared by the CLI's integration tests: run the real binary, check it never panics,
//! and parse its JSON.
#![allow(dead_code)] // each test binary uses a subset

use serde_json::Value;
use std::process::{Command, Output};

/// The `shadowvol` binary built for these tests.
pub const BIN: &str = env!("CARGO_BIN_EXE_shadowvol");

/// Runs `shadowvol ARGS`; fails the test if it panicked.
pub fn run(args: &[&str]) -> Output {
    let out = Command::new(BIN)
        .args(args)
        .output()
        .expect("run shadowvol");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !stderr.contains("panicked"),
        "shadowvol {args:?} panicked:\n{stderr}"
    );
    out
}

/// Runs `shadowvol ARGS`, which must succeed, and parses its stdout as JSON.
pub fn json_of(args: &[&str]) -> Value {
    let out = run(args);
    assert!(
        out.status.success(),
        "shadowvol {args:?} failed ({:?}):\n{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("valid JSON on stdout")
}
