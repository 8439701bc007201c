//! Helpers shared by the CLI's integration tests: run the real binary, check it never panics,
//! and parse its JSON.
#![allow(dead_code)] // each test binary uses a subset

use serde_json::Value;
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_test_support::{Skip, Trial};
use std::process::{Command, Output};
use std::sync::OnceLock;

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

/// The arguments of `shadowvol bench` on `scene` with `backends` (comma-separated) in exact mode:
/// `frames` timed frames after `warmup`, JSON output.
pub fn exact_bench<'a>(
    scene: &'a str,
    backends: &'a str,
    frames: &'a str,
    warmup: &'a str,
) -> Vec<&'a str> {
    let mut args = vec!["bench", "--scene", scene, "--backend", backends];
    args.extend(["--mode", "exact", "--frames", frames]);
    args.extend(["--warmup", warmup, "--format", "json"]);
    args
}

/// The arguments of `shadowvol silhouette` on `input` (a file or preset) with `backend` in exact
/// mode, JSON output; lights may follow.
pub fn exact_silhouette<'a>(input: &'a str, backend: &'a str) -> Vec<&'a str> {
    let mut args = vec!["silhouette", input, "--backend", backend];
    args.extend(["--mode", "exact", "--format", "json"]);
    args
}

/// The rows of `shadowvol backends --format json`, read once per test binary.
fn backend_rows() -> &'static [Value] {
    static ROWS: OnceLock<Vec<Value>> = OnceLock::new();
    ROWS.get_or_init(|| {
        json_of(&["backends", "--format", "json"])
            .as_array()
            .expect("an array")
            .clone()
    })
}

/// Every backend that `shadowvol backends` lists, available or not, in its order.
pub fn backend_names() -> Vec<String> {
    backend_rows()
        .iter()
        .map(|r| r["name"].as_str().expect("a name").to_owned())
        .collect()
}

/// One trial per listed backend that `keep` accepts, named `NAME::BACKEND`
/// ([`shadowvol_test_support::per_backend`]), each running `test(backend)` once
/// [`backend_available`] says the backend can start.
pub fn per_backend(name: &str, keep: fn(&str) -> bool, test: fn(&str)) -> Vec<Trial> {
    let names = backend_names().into_iter().filter(|b| keep(b));
    shadowvol_test_support::per_backend(name, names, move |b| -> Result<(), Skip> {
        backend_available(b)?;
        test(b);
        Ok(())
    })
}

/// [`per_backend`] trials of the test function `test` (`fn(&str)`), named after it:
/// `per_backend!(test)` for every backend, `per_backend!(test, keep)` for those `keep` accepts.
#[allow(unused_macros)] // each test binary uses a subset
macro_rules! per_backend {
    ($test:ident) => {
        common::per_backend(::std::stringify!($test), |_| true, $test)
    };
    ($test:ident, $keep:expr) => {
        common::per_backend(::std::stringify!($test), $keep, $test)
    };
}

/// The `[a, b, m]` rows of a light in a `silhouette` report, as `(a, b, m)`.
///
/// # Panics
///
/// If a row is not three integers.
pub fn edges_of(light: &Value) -> Vec<(u64, u64, i64)> {
    light["edges"]
        .as_array()
        .expect("edges is an array")
        .iter()
        .map(|e| {
            let e = e.as_array().expect("an edge is an array");
            assert_eq!(e.len(), 3, "edges are [a, b, m]");
            (
                e[0].as_u64().unwrap(),
                e[1].as_u64().unwrap(),
                e[2].as_i64().unwrap(),
            )
        })
        .collect()
}

/// The rows a report must list for one light: each edge of `table` with `m != 0` in `values`
/// (indexed by edge), named by its welded vertices, in the table's order.
pub fn nonzero_edges(table: &EdgeTable, values: &[i32]) -> Vec<(u64, u64, i64)> {
    values
        .iter()
        .enumerate()
        .filter(|(_, &m)| m != 0)
        .map(|(e, &m)| {
            let (a, b) = table.edge_names(e);
            (u64::from(a), u64::from(b), i64::from(m))
        })
        .collect()
}

/// Whether `backend` is available: `Ok`, or a visible skip naming the reason `shadowvol
/// backends` gives (a failure under CI, see [`shadowvol_test_support::skip`]).
pub fn backend_available(backend: &str) -> Result<(), Skip> {
    let row = backend_rows()
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

/// `shadowvol ARGS` with `--format json` among them, which must succeed: its JSON and stderr. A
/// visible skip where it found no GPU adapter ([`no_adapter`]).
///
/// # Panics
/// When the command fails otherwise or prints no JSON.
pub fn json_ok(args: &[&str]) -> Result<(Value, String), Skip> {
    let out = run(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    if !out.status.success() {
        no_adapter(args[0], &stderr)?;
    }
    assert!(out.status.success(), "{args:?} failed:\n{stderr}");
    let v = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{args:?}: {e}"));
    Ok((v, stderr))
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
