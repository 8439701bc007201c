//! The JSON's memory figures (`peak_rss_bytes`, `table_bytes` and its parts) on `silhouette`,
//! `bench` and `render`: present, consistent, and no smaller than what the prepared scene must
//! hold by its contents.

#[macro_use]
mod common;

use common::json_of;
use serde_json::Value;
use shadowvol_test_support::Outcome;

/// A closed mesh of about 10^5 triangles: its table is megabytes, far above allocator noise.
const SCENE: &str = "sphere-100k";

fn main() {
    let mut trials = shadowvol_test_support::trials![
        bench_records_carry_their_backends_table,
        simd_reads_the_table_in_place_when_asked,
        bench_build_runs_time_the_table_against_a_read,
        render_counts_each_pipelines_device_buffers,
    ];
    trials.extend(per_backend!(
        silhouette_reports_what_the_prepared_scene_holds
    ));
    shadowvol_test_support::run(trials)
}

/// `shadowvol bench`: one exact frame without warm-up of [`SCENE`] on `backend`, as JSON.
fn one_frame_bench(backend: &str) -> Vec<&str> {
    common::exact_bench(SCENE, backend, "1", "0")
}

fn u(v: &Value, key: &str) -> u64 {
    v[key]
        .as_u64()
        .unwrap_or_else(|| panic!("{key} is not a number in {v}"))
}

/// `table_bytes` is the sum of its parts; returns the parts `(topology, host, device)`.
fn parts(v: &Value) -> (u64, u64, u64) {
    let p = &v["table_bytes_parts"];
    let (t, h, d) = (u(p, "topology"), u(p, "host"), u(p, "device"));
    assert_eq!(u(v, "table_bytes"), t + h + d, "parts do not add up: {p}");
    (t, h, d)
}

/// The least an edge table of a closed mesh of `triangles` triangles can hold with 32-bit
/// indices and `f32` positions: 3 opposite vertices (12 B) and 1.5 edge records (12 B) per
/// triangle, 1.5 CSR offsets (6 B), half a vertex (6 B).
fn table_floor(triangles: u64) -> u64 {
    36 * triangles
}

fn silhouette_reports_what_the_prepared_scene_holds(backend: &str) {
    let v = json_of(&[
        "silhouette",
        SCENE,
        "--backend",
        backend,
        "--format",
        "json",
    ]);
    let triangles = u(&v["mesh"], "triangles");
    let (topology, host, device) = parts(&v);
    assert!(
        topology >= table_floor(triangles),
        "{backend}: topology {topology} B for {triangles} triangles is less than the table's contents"
    );
    match backend {
        // The scalar kernel reads the table itself, and a scene this small keeps each OV
        // slot's vertex id (3 slots a triangle, 4 B each).
        "cpu" => assert!(
            (12 * triangles..12 * triangles + 4096).contains(&host) && device == 0,
            "cpu copies only the OV vertex ids: {host}, {device}"
        ),
        // A scene this small gets the copy layout: canonical triangles (12 B/triangle) and more.
        "simd" => assert!(
            host >= 12 * triangles && device == 0,
            "simd: {host}, {device}"
        ),
        // The opposite vertices alone are 12 B/triangle on the device.
        _ => assert!(device >= 12 * triangles, "{backend}: device {device} B"),
    }
    // The process held the table and the backend's host layout at the same time.
    let peak = u(&v, "peak_rss_bytes");
    assert!(
        peak >= topology + host,
        "{backend}: peak {peak} < {topology} + {host}"
    );
}

/// `bench --build-runs` times the scene's table build next to a read of its input, and says
/// so only when asked.
fn bench_build_runs_time_the_table_against_a_read() -> Outcome {
    let run = |extra: &[&str]| {
        let mut args = one_frame_bench("cpu");
        args.extend_from_slice(extra);
        json_of(&args)
    };
    assert!(
        run(&[]).get("build").is_none(),
        "no build timing unless asked"
    );
    let v = run(&["--build-runs", "2"]);
    let b = &v["build"];
    let triangles = v["records"][0]["triangles"].as_u64().expect("triangles");
    assert_eq!(u(b, "triangles"), triangles);
    assert_eq!(u(b, "runs"), 2);
    // The mesh the build reads: 12 bytes a vertex (half a vertex a triangle) and a triangle.
    assert_eq!(u(b, "input_bytes"), 12 * (u(b, "vertices") + triangles));
    let f = |k: &str| b[k].as_f64().unwrap_or_else(|| panic!("{k} in {b}"));
    assert!(f("min_ms") <= f("median_ms") && f("read_ms") > 0.0, "{b}");
    assert!(
        (f("ratio") - f("median_ms") / f("read_ms")).abs() < 1e-6 * f("ratio"),
        "{b}"
    );
    // Building is sorting and hashing: it cannot be as fast as reading its input once.
    assert!(f("ratio") > 1.0, "{b}");
    Ok(())
}

/// `SHADOWVOL_SIMD_LAYOUT=in-place`: the bench record says so, and the backend holds under a
/// byte a triangle of its own; the default (a scene this small is copied) holds tens.
fn simd_reads_the_table_in_place_when_asked() -> Outcome {
    let record = |layout: Option<&str>| {
        let mut cmd = std::process::Command::new(common::BIN);
        cmd.args(one_frame_bench("simd"));
        if let Some(layout) = layout {
            cmd.env("SHADOWVOL_SIMD_LAYOUT", layout);
        }
        let out = cmd.output().expect("run shadowvol");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: Value = serde_json::from_slice(&out.stdout).expect("JSON");
        v["records"][0].clone()
    };
    for (layout, name) in [(None, "copy"), (Some("in-place"), "in-place")] {
        let r = record(layout);
        assert_eq!(r["details"]["simd_layout"], name, "{r}");
        let (_, host, _) = parts(&r);
        let triangles = u(&r, "triangles");
        assert_eq!(
            host < triangles,
            name == "in-place",
            "{name}: {host} B host"
        );
    }
    // An unknown layout is refused, naming the variable.
    let out = std::process::Command::new(common::BIN)
        .args(["silhouette", SCENE, "--backend", "simd"])
        .env("SHADOWVOL_SIMD_LAYOUT", "sideways")
        .output()
        .expect("run shadowvol");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("SHADOWVOL_SIMD_LAYOUT"),
        "{stderr}"
    );
    Ok(())
}

fn bench_records_carry_their_backends_table() -> Outcome {
    let v = json_of(&common::exact_bench(SCENE, "cpu,simd", "2", "1"));
    let records = v["records"].as_array().expect("records");
    let table = |b: &str| {
        let r = records
            .iter()
            .find(|r| r["backend"] == b)
            .expect("a record");
        (parts(r), u(r, "peak_rss_bytes"), u(r, "triangles"))
    };
    let ((ct, ch, _), cpu_peak, triangles) = table("cpu");
    let ((st, sh, _), simd_peak, _) = table("simd");
    assert_eq!(ct, st, "one scene, one table");
    assert!(ct >= table_floor(triangles));
    assert!(
        sh > ch + 12 * triangles,
        "simd lays out its own copy: {sh} vs {ch}"
    );
    // A high-water mark: not lower for a later backend, and the run's is the highest, within
    // the slack of the kernel's per-CPU RSS counters (batches of pages per CPU).
    let slack = 1 << 20;
    let run_peak = u(&v, "peak_rss_bytes");
    assert!(
        cpu_peak <= simd_peak + slack && simd_peak <= run_peak + slack,
        "cpu {cpu_peak}, simd {simd_peak}, run {run_peak}"
    );
    Ok(())
}

fn render_counts_each_pipelines_device_buffers() -> Outcome {
    let png = std::env::temp_dir().join(format!("shadowvol-memory-{}.png", std::process::id()));
    let png = png.display().to_string();
    for flags in [
        &["--pipeline", "gpu"][..],
        &["--shadows", "map"],
        &["--backend", "simd"],
    ] {
        let mut args = vec![
            "render", SCENE, "--size", "64x48", "--out", &png, "--format", "json",
        ];
        args.extend_from_slice(flags);
        let out = common::run(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        common::no_adapter("render", &stderr)?;
        assert!(out.status.success(), "{args:?}: {stderr}");
        let v: Value = serde_json::from_slice(&out.stdout).expect("JSON");
        let (topology, host, device) = parts(&v);
        // The sphere and its ground.
        let triangles = 100_000;
        assert!(topology >= table_floor(triangles), "{flags:?}: {topology}");
        match flags[1] {
            // Edge records, opposite vertices and triangles stay on the device.
            "gpu" => assert!(device >= 24 * triangles, "{flags:?}: device {device}"),
            // The surface vertices (3 a triangle) and at least one map.
            "map" => assert!(device >= 36 * triangles, "{flags:?}: device {device}"),
            // The host pipeline's backend keeps its layout on the host, the pipeline its
            // surface vertices on the device (3 of 64 bytes a triangle).
            _ => assert!(
                host >= 12 * triangles && device >= 192 * triangles,
                "{flags:?}: {host} {device}"
            ),
        }
        assert!(u(&v, "peak_rss_bytes") >= topology + host);
    }
    let _ = std::fs::remove_file(&png);
    Ok(())
}
