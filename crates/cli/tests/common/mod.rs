//! Helpers shared by the CLI's integration tests: run the real binary, check it never panics,
//! and parse its JSON.
#![allow(dead_code)] // each test binary uses a subset

use serde_json::Value;
use shadowvol_test_support::Skip;
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
/// Only for tests on the standard harness that loop over [`available_backends`]; a test that
/// skips as a whole returns a [`Skip`] instead ([`shadowvol_test_support::skip`]).
pub fn skip(what: &str, why: &str) {
    assert!(
        !shadowvol_silhouette::ci::is_ci(),
        "{what} is unavailable, and CI is set, so this fails: {why}"
    );
    eprintln!("SKIPPED {what}: {why}");
    println!("SKIPPED {what}: {why}");
}

/// Whether `backend` is available: `Ok`, or a visible skip naming the reason `shadowvol
/// backends` gives (a failure under CI, see [`shadowvol_test_support::skip`]).
pub fn backend_available(backend: &str) -> Result<(), Skip> {
    let rows = json_of(&["backends", "--format", "json"]);
    let row = rows
        .as_array()
        .expect("an array")
        .iter()
        .find(|r| r["name"] == backend)
        .unwrap_or_else(|| panic!("`shadowvol backends` does not list {backend}"));
    if row["available"] == Value::Bool(true) {
        Ok(())
    } else {
        Err(shadowvol_test_support::skip(format!(
            "backend {backend} unavailable: {}",
            row["reason"]
        )))
    }
}

/// A visible skip ([`shadowvol_test_support::skip`]: ignored with the reason, a failure under
/// CI) when a command's `stderr` says it found no GPU adapter; `what` names the command.
pub fn no_adapter(what: &str, stderr: &str) -> Result<(), Skip> {
    match stderr.lines().find(|l| l.contains("no GPU adapter")) {
        Some(line) => Err(shadowvol_test_support::skip(format!(
            "{what}: {}",
            line.trim()
        ))),
        None => Ok(()),
    }
}
