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

/// The backends that `shadowvol backends` reports available, by name.
///
/// Under CI (`shadowvol_silhouette::ci::is_ci`: `CI=true`, `CI=True`, `CI=1`) every backend it
/// lists must be available, so that a test looping over these never quietly tests fewer: an
/// unavailable one fails the test with its reason. Elsewhere each missing one is named on a
/// visible `SKIPPED` line.
pub fn available_backends() -> Vec<String> {
    let rows = json_of(&["backends", "--format", "json"]);
    let mut available = Vec::new();
    for r in rows.as_array().expect("an array") {
        let name = r["name"].as_str().expect("a name").to_owned();
        if r["available"] == Value::Bool(true) {
            available.push(name);
        } else {
            skip(&format!("backend {name}"), &r["reason"].to_string());
        }
    }
    available
}

/// A skip: fails the test under CI (`shadowvol_silhouette::ci::is_ci`), otherwise prints a
/// `SKIPPED` line with the reason (on stdout and stderr, so it shows with or without capture).
pub fn skip(what: &str, why: &str) {
    assert!(
        !shadowvol_silhouette::ci::is_ci(),
        "{what} is unavailable, and CI is set, so this fails: {why}"
    );
    eprintln!("SKIPPED {what}: {why}");
    println!("SKIPPED {what}: {why}");
}
