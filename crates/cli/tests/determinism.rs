//! Determinism of `shadowvol silhouette --format json`: the same input gives
//! byte-identical JSON across runs, across thread counts (`RAYON_NUM_THREADS=1` and `2` on
//! `simd`, in every mode) and across backends in exact mode, one trial per backend
//! (`::BACKEND`).
//!
//! Only the fields that describe the run rather than the result are cut out before comparing,
//! on the raw bytes: `"timings"` (durations, and the count of pairs a device's filter could not
//! certify, which depends on the device) and the memory figures (`"peak_rss_bytes"`,
//! `"table_bytes"`, `"table_bytes_parts"`: what the process and the backend held) always; `"device"` across thread counts (it names the
//! thread count); `"backend"` and `"device"` across backends. Everything else (mesh statistics,
//! lights as printed, every `[a, b, m]`, open vertices, key order, number formatting) must match
//! byte for byte.

#[macro_use]
mod common;

use common::BIN;
use std::process::Command;
use std::sync::OnceLock;

fn main() {
    let mut trials = shadowvol_test_support::trials![
        cut_removes_exactly_the_member,
        simd_gives_the_same_bytes_with_one_and_two_threads_in_every_mode,
    ];
    trials.extend(per_backend!(same_input_same_bytes_across_runs));
    trials.extend(per_backend!(same_bytes_as_cpu_in_exact_mode, |b| b != "cpu"));
    shadowvol_test_support::run(trials)
}

/// Scenes with degenerate and near-degenerate configurations, several objects, and the bunny.
const SCENES: [&str; 6] = [
    "hard-edge-on-tilted-grid",
    "hard-light-at-vertex",
    "hard-book-4",
    "hard-offset-1e4-sphere",
    "hard-multi-object-transforms",
    "bunny",
];

/// Runs `silhouette SCENE --format json` with `extra` arguments and environment; returns stdout.
fn silhouette(scene: &str, extra: &[&str], env: &[(&str, &str)]) -> String {
    let mut cmd = Command::new(BIN);
    cmd.args(["silhouette", scene, "--format", "json"])
        .args(extra);
    if scene == "bunny" {
        // The bunny preset has one light; add a directional one and one close to the surface.
        cmd.args([
            "--light",
            "0.3,10,0.2,1",
            "--light=-1,0.5,0.25,0",
            "--light=0,0.12,0.05,1",
        ]);
    }
    for (k, v) in env {
        cmd.env(k, v);
    }
    let out = cmd.output().expect("run shadowvol");
    assert!(
        out.status.success(),
        "silhouette {scene} {extra:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("UTF-8 JSON")
}

/// The members that describe the run rather than the result, cut from every comparison.
const RUN: [&str; 4] = [
    "timings",
    "peak_rss_bytes",
    "table_bytes",
    "table_bytes_parts",
];

/// Cuts the object member `"key":...` out of the top level of `json` (raw text; the value is a
/// string, a number, `null` or a flat object), with its separating comma. Panics if the key is
/// missing.
fn cut(json: &str, key: &str) -> String {
    let pat = format!("\"{key}\":");
    let start = json
        .find(&pat)
        .unwrap_or_else(|| panic!("{key} missing: {json}"));
    let rest = &json[start + pat.len()..];
    let len = if let Some(string) = rest.strip_prefix('"') {
        // A string without escaped quotes (backend and device names).
        1 + string.find('"').unwrap() + 1
    } else if rest.starts_with('{') {
        rest.find('}').unwrap() + 1
    } else {
        // A number or null: up to the next member or the end of the object.
        let n = rest.find([',', '}']).unwrap();
        assert!(
            !rest[..n].contains(['[', '{', '"']),
            "{key} is not flat: {rest}"
        );
        n
    };
    let end = start + pat.len() + len;
    // Remove one adjacent comma so the result stays valid JSON.
    if json[end..].starts_with(',') {
        format!("{}{}", &json[..start], &json[end + 1..])
    } else {
        let before = json[..start].trim_end_matches(',');
        format!("{before}{}", &json[end..])
    }
}

fn without(json: &str, keys: &[&str]) -> String {
    let mut s = json.to_owned();
    for k in keys {
        s = cut(&s, k);
    }
    let v: serde_json::Value = serde_json::from_str(&s).expect("still valid JSON");
    for k in keys {
        assert!(v.get(k).is_none(), "{k} left in {s}");
    }
    assert!(
        v["lights"]
            .as_array()
            .unwrap()
            .iter()
            .any(|l| !l["edges"].as_array().unwrap().is_empty()),
        "a trivial result proves nothing: {s}"
    );
    s
}

fn cut_removes_exactly_the_member() {
    let j = r#"{"backend":"simd","mode":"exact","lights":[{"edges":[[0,1,2]]}],"device":"x, 2 threads","timings":{"a":1.5,"uncertain":0},"peak_rss_bytes":8536064,"table_bytes":560,"table_bytes_parts":{"device":0,"host":96,"topology":464}}"#;
    assert_eq!(
        without(j, &[&RUN[..], &["backend", "device"]].concat()),
        r#"{"mode":"exact","lights":[{"edges":[[0,1,2]]}]}"#
    );
    let null = r#"{"peak_rss_bytes":null,"lights":[{"edges":[[0,1,2]]}]}"#;
    assert_eq!(
        without(null, &["peak_rss_bytes"]),
        r#"{"lights":[{"edges":[[0,1,2]]}]}"#
    );
}

/// Two runs of `exact` on `backend` give the same bytes.
fn same_input_same_bytes_across_runs(backend: &str) {
    for scene in ["hard-book-4", "bunny"] {
        let args = ["--backend", backend, "--mode", "exact"];
        let a = without(&silhouette(scene, &args, &[]), &RUN);
        let b = without(&silhouette(scene, &args, &[]), &RUN);
        assert_eq!(a, b, "{backend} {scene}: two runs differ");
    }
}

fn simd_gives_the_same_bytes_with_one_and_two_threads_in_every_mode() {
    for scene in ["bunny-subdivided", "hard-offset-1e4-sphere", "hard-book-5"] {
        for mode in ["original", "robust", "ordered", "exact"] {
            let args = ["--backend", "simd", "--mode", mode];
            let one = silhouette(scene, &args, &[("RAYON_NUM_THREADS", "1")]);
            let two = silhouette(scene, &args, &[("RAYON_NUM_THREADS", "2")]);
            assert!(one.contains("1 thread"), "{one}");
            assert!(two.contains("2 threads"), "{two}");
            let keys = [&RUN[..], &["device"]].concat();
            assert_eq!(
                without(&one, &keys),
                without(&two, &keys),
                "{scene} {mode}: 1 and 2 threads differ"
            );
        }
    }
}

/// The `exact` report of each of [`SCENES`] on `backend`, without the run's description.
fn exact_reports(backend: &str) -> Vec<String> {
    SCENES
        .iter()
        .map(|scene| {
            without(
                &silhouette(scene, &["--backend", backend, "--mode", "exact"], &[]),
                &[&RUN[..], &["backend", "device"]].concat(),
            )
        })
        .collect()
}

/// `exact` on `backend` gives the same bytes as on `cpu`, apart from the run's description.
/// The `cpu` reports are computed once for all the trials.
fn same_bytes_as_cpu_in_exact_mode(backend: &str) {
    static CPU: OnceLock<Vec<String>> = OnceLock::new();
    let reference = CPU.get_or_init(|| exact_reports("cpu"));
    for ((scene, got), want) in SCENES.iter().zip(exact_reports(backend)).zip(reference) {
        assert_eq!(&got, want, "{scene}: {backend} differs from cpu");
    }
}
