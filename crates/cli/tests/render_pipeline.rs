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
    a_scene_beyond_the_device_bindings_is_drawn_in_parts,
    pulled_and_buffered_surface_vertices_draw_the_same_image
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
/// (240 KB) do not fit one storage binding: the GPU pipeline uploads the scene in parts and
/// draws the same image as uncapped (with the same pixel ids, so the same comparison with the
/// reference), and the host pipeline draws from several vertex buffers, also the same image as
/// uncapped.
fn a_scene_beyond_the_device_bindings_is_drawn_in_parts() -> Outcome {
    let run_with = |cap: Option<&str>, args: &[&str]| {
        let mut c = std::process::Command::new(common::BIN);
        c.args(args);
        if let Some(cap) = cap {
            c.env(shadowvol_renderer::BUFFER_CAP_ENV, cap);
        }
        c.output().expect("run shadowvol")
    };
    for pipeline in ["gpu", "host"] {
        let mut images = Vec::new();
        for cap in [None, Some("65536")] {
            let png = scratch(&format!("cap-{pipeline}-{}.png", cap.unwrap_or("none")));
            let args = [
                "render",
                "sphere-10k",
                "--size",
                "96x80",
                "--pipeline",
                pipeline,
                "--out",
                &png,
                "--reference",
                "--format",
                "json",
            ];
            let out = run_with(cap, &args);
            let stderr = String::from_utf8_lossy(&out.stderr);
            common::no_adapter("render", &stderr)?;
            assert!(out.status.success(), "{pipeline} {cap:?}: {stderr}");
            assert!(!stderr.contains("panicked"), "{stderr}");
            let v: Value = serde_json::from_slice(&out.stdout).expect("JSON on stdout");
            assert_eq!(v["pipeline"], pipeline);
            let parts = v["scene_parts"].as_u64().expect("scene_parts");
            match (pipeline, cap) {
                ("gpu", Some(_)) => assert!(parts > 1, "the GPU pipeline in one part"),
                _ => assert_eq!(parts, 1, "{pipeline} {cap:?}"),
            }
            // The reference reads the pixel ids `[surface + 1, triangle]`: a part's ids must
            // name the scene's triangles.
            let counts =
                ["artifact_pixels", "covered_pixels", "shadow_pixels"].map(|k| v[k].clone());
            images.push((std::fs::read(&png).unwrap(), counts));
        }
        assert!(
            images[0] == images[1],
            "{pipeline}: the capped image or its comparison differs from the uncapped one: {:?} {:?}",
            images[0].1,
            images[1].1
        );
    }
    Ok(())
}

/// `SHADOWVOL_SURFACE_VERTICES`: sphere-10k (below 2^22 triangles) gets the vertex buffer by
/// default; `pull` draws it by vertex pulling, whole and in parts (a 64 KiB cap), with the same
/// image and comparison; `buffer` is the default's; any other value is refused, by name.
fn pulled_and_buffered_surface_vertices_draw_the_same_image() -> Outcome {
    let env = shadowvol_renderer::resident::SurfaceVertices::ENV;
    let run_with = |choice: Option<&str>, cap: Option<&str>, png: &str| {
        let mut c = std::process::Command::new(common::BIN);
        c.args(["render", "sphere-10k", "--size", "96x80", "--out", png]);
        c.args(["--reference", "--format", "json"]);
        if let Some(choice) = choice {
            c.env(env, choice);
        }
        if let Some(cap) = cap {
            c.env(shadowvol_renderer::BUFFER_CAP_ENV, cap);
        }
        c.output().expect("run shadowvol")
    };
    let mut images = Vec::new();
    for (choice, cap, want) in [
        (None, None, "buffer"),
        (Some("pull"), None, "pulled"),
        (Some("pull"), Some("65536"), "pulled"),
        (Some("buffer"), None, "buffer"),
    ] {
        let png = scratch(&format!("surfaces-{choice:?}-{cap:?}.png"));
        let out = run_with(choice, cap, &png);
        let stderr = String::from_utf8_lossy(&out.stderr);
        common::no_adapter("render", &stderr)?;
        assert!(out.status.success(), "{choice:?} {cap:?}: {stderr}");
        let v: Value = serde_json::from_slice(&out.stdout).expect("JSON on stdout");
        assert_eq!(v["surface_vertices"], want, "{choice:?} {cap:?}");
        assert_eq!(v["scene_parts"].as_u64().unwrap() > 1, cap.is_some());
        let counts = ["artifact_pixels", "covered_pixels", "shadow_pixels"].map(|k| v[k].clone());
        images.push((std::fs::read(&png).unwrap(), counts));
    }
    for (k, other) in images.iter().enumerate().skip(1) {
        assert!(
            other == &images[0],
            "run {k} differs: {:?} {:?}",
            other.1,
            images[0].1
        );
    }
    let out = run_with(Some("sometimes"), None, &scratch("bad.png"));
    assert!(!out.status.success());
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(e.contains(env) && e.contains("auto, buffer or pull"), "{e}");
    Ok(())
}
