//! `shadowvol render --pipeline` and `--frames`: the GPU pipeline is the default, reads nothing
//! back during timed frames and agrees with the host pipeline; `--backend` means host.

mod common;

use common::run;
use serde_json::Value;
use shadowvol_test_support::{main, Outcome, Skip};

main!(
    gpu_pipeline_is_the_default_and_timed_frames_read_nothing_back,
    backend_means_host_and_both_pipelines_agree,
    gpu_pipeline_with_a_backend_is_refused,
    a_scene_beyond_the_gpu_bindings_is_drawn_by_the_host_pipeline
);

fn scratch(name: &str) -> String {
    let dir =
        std::env::temp_dir().join(format!("shadowvol-render-pipeline-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name).display().to_string()
}

/// Runs `render ARGS --format json`; a visible skip (a failure under CI) without an adapter.
fn render(args: &[&str]) -> Result<Value, Skip> {
    let mut all = vec!["render"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--format", "json"]);
    let out = run(&all);
    let stderr = String::from_utf8_lossy(&out.stderr);
    common::no_adapter("render", &stderr)?;
    assert!(out.status.success(), "shadowvol {all:?} failed:\n{stderr}");
    Ok(serde_json::from_slice(&out.stdout).expect("JSON on stdout"))
}

fn gpu_pipeline_is_the_default_and_timed_frames_read_nothing_back() -> Outcome {
    let png = scratch("gpu.png");
    let v = render(&[
        "hard-book-3",
        "--size",
        "96x72",
        "--frames",
        "3",
        "--reference",
        "--out",
        &png,
    ])?;
    assert_eq!(v["pipeline"], "gpu", "{v}");
    // No silhouette backend runs on the GPU pipeline, and none is named.
    assert!(v["backend"].is_null(), "{v}");
    assert_eq!(v["uncertain_unit"], "triangle-light");
    assert!(v["timings"]["silhouette_ms"].is_null(), "{v}");
    assert_eq!(v["frame_readback_bytes"], 0);
    assert_eq!(v["frames"]["count"], 3);
    for k in ["median_ms", "p10_ms", "p90_ms"] {
        assert!(v["frames"][k].as_f64().unwrap() > 0.0, "{k}: {v}");
    }
    assert!(v["frames"]["p10_ms"].as_f64() <= v["frames"]["median_ms"].as_f64());
    assert!(v["frames"]["median_ms"].as_f64() <= v["frames"]["p90_ms"].as_f64());
    assert_eq!(v["host_resolved"], 0);
    assert!(v["uncertain"].as_u64().is_some());
    assert!(
        v.get("gpu_timings_ms").is_some(),
        "the key is part of the contract: {v}"
    );
    assert!(v["artifact_pixels"].as_u64().unwrap() <= 96 * 72 * 5 / 10_000);
    let plan = v["plan"].as_array().unwrap();
    assert!(
        plan.iter().any(|e| e["side_quads"].as_u64().unwrap() > 0),
        "{v}"
    );
    Ok(())
}

fn backend_means_host_and_both_pipelines_agree() -> Outcome {
    let (a, b) = (scratch("host.png"), scratch("gpu2.png"));
    let args = [
        "hard-double-sided-sheet",
        "--size",
        "80x60",
        "--backdrop",
        "--frames",
        "2",
    ];
    let host = render(&[&args[..], &["--backend", "simd", "--out", &a]].concat())?;
    assert_eq!(host["pipeline"], "host");
    assert_eq!(host["backend"], "simd");
    // 2 frames, every edge of every object and light as an i32.
    assert!(host["frame_readback_bytes"].as_u64().unwrap() > 0, "{host}");
    let gpu = render(&[&args[..], &["--pipeline", "gpu", "--out", &b]].concat()).unwrap();
    assert_eq!(gpu["pipeline"], "gpu");
    assert_eq!(host["shadow_pixels"], gpu["shadow_pixels"]);
    for (h, g) in host["plan"]
        .as_array()
        .unwrap()
        .iter()
        .zip(gpu["plan"].as_array().unwrap())
    {
        assert_eq!(h["technique"], g["technique"]);
        assert_eq!(
            h["side_quads"], g["side_quads"],
            "exact mode: the same silhouettes"
        );
    }
    let host_png = image::open(&a).unwrap().to_rgba8();
    let gpu_png = image::open(&b).unwrap().to_rgba8();
    let differ = host_png
        .pixels()
        .zip(gpu_png.pixels())
        .filter(|(p, q)| p.0.iter().zip(q.0).any(|(x, y)| x.abs_diff(y) > 3))
        .count();
    assert!(differ <= 80 * 60 * 5 / 10_000, "{differ} pixels differ");
    Ok(())
}

fn gpu_pipeline_with_a_backend_is_refused() -> Outcome {
    let out = run(&[
        "render",
        "hard-book-3",
        "--pipeline",
        "gpu",
        "--backend",
        "simd",
        "--out",
        &scratch("x.png"),
    ]);
    assert!(!out.status.success());
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(
        e.contains("--backend simd selects the host pipeline"),
        "{e}"
    );
    Ok(())
}

/// With every buffer capped at 64 KiB (`SHADOWVOL_MAX_BUFFER_BYTES`), sphere-10k's edge records
/// (240 KB) do not fit one binding: without `--pipeline` the host pipeline draws it, from
/// several buffers, with a warning and the same image as the host pipeline on the uncapped
/// device; `--pipeline gpu` fails naming both numbers.
fn a_scene_beyond_the_gpu_bindings_is_drawn_by_the_host_pipeline() -> Outcome {
    let capped = |args: &[&str]| {
        std::process::Command::new(common::BIN)
            .args(args)
            .env(shadowvol_renderer::BUFFER_CAP_ENV, "65536")
            .output()
            .expect("run shadowvol")
    };
    let (fallback, host) = (scratch("cap-fallback.png"), scratch("cap-host.png"));
    let base = [
        "render",
        "sphere-10k",
        "--size",
        "96x80",
        "--format",
        "json",
    ];
    let out = capped(&[&base[..], &["--out", &fallback]].concat());
    let stderr = String::from_utf8_lossy(&out.stderr);
    common::no_adapter("render", &stderr)?;
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("warning: using the host pipeline: the scene is too large")
            && stderr.contains("65536"),
        "{stderr}"
    );
    let v: Value = serde_json::from_slice(&out.stdout).expect("JSON on stdout");
    assert_eq!(v["pipeline"], "host");
    render(&[
        "sphere-10k",
        "--size",
        "96x80",
        "--pipeline",
        "host",
        "--out",
        &host,
    ])?;
    assert!(
        std::fs::read(&fallback).unwrap() == std::fs::read(&host).unwrap(),
        "the capped host pipeline's image differs from the uncapped one"
    );
    let out = capped(&[&base[..], &["--pipeline", "gpu", "--out", &fallback]].concat());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("too large for the device") && stderr.contains("at most 65536"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    Ok(())
}
