//! The memory measurements: each run its own process, so that its peak resident set is its own
//! (`peak_rss_bytes`, the kernel's high-water mark), with what the prepared scene held
//! (`table_bytes` and its parts): `silhouette` on every backend in exact mode, and `render` on
//! each pipeline, on spheres of 10^5 to 10^7 triangles; in a full run also `bunny-10m`
//! (`silhouette` everywhere, `render` on the GPU pipeline) and `sphere-100m` on the CPU
//! backends, each only when the machine has the memory for it.

use super::plan::{
    Plan, BUILD_RUNS, MEMORY_BUNNY, MEMORY_HUGE, MEMORY_HUGE_BACKENDS, MEMORY_HUGE_FROM,
    MEMORY_RENDERS, MEMORY_RENDER_SIZE,
};
use super::records::{Data, Key, Memory};
use super::runner::{render_args, Matrix};
use serde_json::Value;
use std::time::Instant;

/// Every memory run compiles its shaders as on a fresh machine: Mesa's shader cache off, so
/// that a cache an earlier run filled does not lower the peak (the compiler's memory is some
/// 40 MB of `wgpu`'s exact pipelines on lavapipe).
const COLD_SHADERS: &[(&str, &str)] = &[("MESA_SHADER_CACHE_DISABLE", "true")];

impl Matrix {
    /// The memory table's runs (experiment `memory`).
    pub(super) fn memory_table(&mut self, plan: &Plan) {
        for scene in plan.memory_scenes.clone() {
            let mut triangles = None;
            for b in plan.backends.clone() {
                self.progress
                    .step(&format!("memory: {scene} silhouette {b}"));
                if let Some(m) = self.memory_run(scene, &b, &silhouette_args(scene, &b), None) {
                    triangles = triangles.or(m);
                }
            }
            for (key, flags) in MEMORY_RENDERS {
                self.memory_render(scene, key, flags, triangles);
            }
        }
        if plan.memory_large {
            self.memory_large(plan);
        }
        if let Some(scene) = plan.memory_scenes.last() {
            self.build_timing(scene);
        }
    }

    /// `EdgeTable::build` on `scene`'s table against reading its input from memory
    /// (`shadowvol bench --build-runs`), as a `memory` record of backend `build`.
    fn build_timing(&mut self, scene: &str) {
        self.progress
            .step(&format!("memory: {scene} edge-table build"));
        let args = [
            "bench",
            "--scene",
            scene,
            "--backend",
            "cpu",
            "--mode",
            "exact",
            "--frames",
            "1",
            "--warmup",
            "0",
            "--build-runs",
            BUILD_RUNS,
            "--format",
            "json",
        ];
        let v = match self.cli.json::<Value>(&args) {
            Ok(v) => v,
            Err(e) => {
                self.fail(format!("memory: {scene} build: {e}"));
                return;
            }
        };
        let b = &v["build"];
        let m = Memory {
            triangles: b["triangles"].as_u64(),
            build_ms: b["median_ms"].as_f64(),
            build_read_ms: b["read_ms"].as_f64(),
            build_threads: b["threads"].as_u64(),
            ..Memory::default()
        };
        let key = Key {
            scene: scene.to_owned(),
            backend: "build".to_owned(),
            mode: None,
        };
        self.push("memory", key, "cpu".to_owned(), Data::Memory(m));
    }

    /// `bunny-10m` on every backend and the GPU pipeline, then `sphere-100m` on the CPU
    /// backends where the memory suffices (a skip that says why where it does not).
    fn memory_large(&mut self, plan: &Plan) {
        let mut triangles = None;
        for b in plan.backends.clone() {
            self.progress
                .step(&format!("memory: {MEMORY_BUNNY} silhouette {b}"));
            if let Some(m) =
                self.memory_run(MEMORY_BUNNY, &b, &silhouette_args(MEMORY_BUNNY, &b), None)
            {
                triangles = triangles.or(m);
            }
        }
        let (key, flags) = MEMORY_RENDERS[0];
        self.memory_render(MEMORY_BUNNY, key, flags, triangles);
        for b in MEMORY_HUGE_BACKENDS {
            self.progress
                .step(&format!("memory: {MEMORY_HUGE} silhouette {b}"));
            if !plan.backends.iter().any(|x| x == b) {
                continue;
            }
            match self.huge_fits(b) {
                Ok(()) => {
                    self.memory_run(MEMORY_HUGE, b, &silhouette_args(MEMORY_HUGE, b), None);
                }
                Err(why) => {
                    let what = format!("memory: {MEMORY_HUGE} on {b} skipped: {why}");
                    eprintln!("\nmatrix: {what}");
                    self.results.skips.push(what);
                }
            }
        }
    }

    /// Whether [`MEMORY_HUGE`] fits on backend `b`: its peak per triangle on
    /// [`MEMORY_HUGE_FROM`] in this run, times 10^8 triangles and the margin, against
    /// `MemAvailable` now.
    fn huge_fits(&self, b: &str) -> Result<(), String> {
        let (from, margin) = MEMORY_HUGE_FROM;
        let per_tri = self
            .results
            .records
            .iter()
            .filter(|r| r.experiment == "memory" && r.key.scene == from && r.key.backend == b)
            .find_map(|r| r.memory().and_then(|m| m.per_triangle(m.peak_rss_bytes)))
            .ok_or_else(|| format!("no {from} peak on {b} in this run to size it from"))?;
        let needed = per_tri * 1e8 * margin;
        let available = mem_available()
            .ok_or_else(|| "MemAvailable is not readable (/proc/meminfo)".to_owned())?;
        if needed > available as f64 {
            return Err(format!(
                "needs about {:.1} GB ({per_tri:.0} B/triangle on {from} x 10^8 x {margin}), \
                 {:.1} GB available",
                needed / 1e9,
                available as f64 / 1e9
            ));
        }
        Ok(())
    }

    /// One `render` of `scene` on a pipeline (`key`, `flags`) into the memory table.
    fn memory_render(&mut self, scene: &str, key: &str, flags: &[&str], triangles: Option<u64>) {
        self.progress.step(&format!("memory: {scene} {key}"));
        let png = self.render_png(&format!("memory-{scene}-{key}"));
        let mut args = render_args(scene, &png, MEMORY_RENDER_SIZE);
        args.extend_from_slice(flags);
        self.memory_run(scene, key, &args, triangles);
    }

    /// Runs `args` and records its memory figures under `backend`; `triangles` when the JSON
    /// does not say (render). Returns the triangles the JSON named, if any.
    fn memory_run(
        &mut self,
        scene: &str,
        backend: &str,
        args: &[&str],
        triangles: Option<u64>,
    ) -> Option<Option<u64>> {
        let start = Instant::now();
        let v = match self.cli.json_with_env::<Value>(args, COLD_SHADERS) {
            Ok(v) => v,
            Err(e) => {
                self.fail(format!("memory: {scene} {backend}: {e}"));
                return None;
            }
        };
        let wall_s = start.elapsed().as_secs_f64();
        let named = v["mesh"]["triangles"].as_u64();
        let parts = &v["table_bytes_parts"];
        let m = Memory {
            triangles: named.or(triangles),
            peak_rss_bytes: v["peak_rss_bytes"].as_u64(),
            table_bytes: v["table_bytes"].as_u64(),
            topology_bytes: parts["topology"].as_u64(),
            host_bytes: parts["host"].as_u64(),
            device_bytes: parts["device"].as_u64(),
            wall_s: Some(wall_s),
            ..Memory::default()
        };
        let device = v["device"]
            .as_str()
            .or(v["adapter"].as_str())
            .unwrap_or_default()
            .to_owned();
        let key = Key {
            scene: scene.to_owned(),
            backend: backend.to_owned(),
            mode: Some("exact".to_owned()),
        };
        self.push("memory", key, device, Data::Memory(m));
        Some(named)
    }
}

/// `silhouette SCENE --backend B --mode exact --format json`.
fn silhouette_args<'a>(scene: &'a str, backend: &'a str) -> [&'a str; 8] {
    [
        "silhouette",
        scene,
        "--backend",
        backend,
        "--mode",
        "exact",
        "--format",
        "json",
    ]
}

/// `MemAvailable` from `/proc/meminfo`, bytes.
fn mem_available() -> Option<u64> {
    std::fs::read_to_string("/proc/meminfo")
        .ok()?
        .lines()
        .find_map(|l| l.strip_prefix("MemAvailable:"))?
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse::<u64>()
        .ok()
        .map(|kb| kb * 1024)
}
