//! Exact results do not change when the tables are compacted: a digest of every exact-mode
//! `silhouette` result (the mesh counts, and per light the listed edges with their multiplicities
//! and the open vertices) on each hard-* preset and on sphere-1m, compared with
//! `data/exact_digests.txt`.
//!
//! That file was written by this test at `2a9f67a`, the last revision before the memory
//! compaction, with `SHADOWVOL_WRITE_DIGESTS=<file>` (each trial appends its line instead of
//! comparing; sort the file afterwards). Exact mode is exact, so no later change should ever
//! need to rewrite it: a mismatch is a changed result, not a stale file.
//!
//! The hard-* presets run on every backend (exact mode is bit-identical everywhere); sphere-1m
//! on the host backends, where a debug build takes seconds.

#[macro_use]
mod common;

use common::json_of;
use serde_json::Value;
use std::hash::Hasher;
use std::io::Write;

/// Environment variable naming a file to append `scene digest` lines to, instead of comparing.
const WRITE_ENV: &str = "SHADOWVOL_WRITE_DIGESTS";

/// The digests written before the compaction.
const EXPECTED: &str = include_str!("data/exact_digests.txt");

fn main() {
    let mut trials = per_backend!(hard_presets_keep_their_exact_digests);
    trials.extend(per_backend!(sphere_1m_keeps_its_exact_digest, |b| {
        b == "cpu" || b == "simd"
    }));
    shadowvol_test_support::run(trials)
}

/// FNV-1a 64 of the canonical JSON (sorted keys) of the result's `mesh` and `lights`.
fn digest(v: &Value) -> String {
    let canonical = serde_json::to_string(&serde_json::json!({
        "mesh": v["mesh"],
        "lights": v["lights"],
    }))
    .expect("serialisable");
    let mut h = fnv::FnvHasher::default();
    h.write(canonical.as_bytes());
    format!("{:016x}", h.finish())
}

/// The expected digest of `scene`, from [`EXPECTED`].
fn expected(scene: &str) -> Option<&'static str> {
    EXPECTED.lines().find_map(|l| {
        let (s, d) = l.split_once(' ')?;
        (s == scene).then_some(d.trim())
    })
}

/// Runs `silhouette SCENE --backend BACKEND --mode exact` and compares (or writes) its digest.
fn check(scene: &str, backend: &str) {
    let v = json_of(&common::exact_silhouette(scene, backend));
    let d = digest(&v);
    if let Ok(path) = std::env::var(WRITE_ENV) {
        let mut f = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)
            .unwrap_or_else(|e| panic!("open {path}: {e}"));
        f.write_all(format!("{scene} {d}\n").as_bytes())
            .unwrap_or_else(|e| panic!("write {path}: {e}"));
        return;
    }
    let want = expected(scene)
        .unwrap_or_else(|| panic!("{scene} has no line in tests/data/exact_digests.txt"));
    assert_eq!(
        d,
        want,
        "{scene} on {backend}: the exact result's digest changed (mesh and lights: {})",
        serde_json::json!({"mesh": v["mesh"], "lights_listed": v["lights"].as_array().map(|l| l
            .iter()
            .map(|x| x["edges"].as_array().map_or(0, Vec::len))
            .collect::<Vec<_>>())})
    );
}

fn hard_presets_keep_their_exact_digests(backend: &str) {
    for case in shadowvol_test_support::corpus::cases() {
        check(&format!("hard-{}", case.name), backend);
    }
}

fn sphere_1m_keeps_its_exact_digest(backend: &str) {
    check("sphere-1m", backend);
}
