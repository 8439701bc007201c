//! The memory measurements: each run its own process, so that its peak resident set is its own
//! (`peak_rss_bytes`, the kernel's high-water mark), with what the prepared scene held
//! (`table_bytes` and its parts): `silhouette` on every backend in exact mode, and `render` on
//! each pipeline, on spheres of 10^5 to 10^7 triangles.

use super::plan::{Plan, MEMORY_RENDERS, MEMORY_RENDER_SIZE};
use super::records::{Data, Key, Memory};
use super::runner::{render_args, Matrix};
use serde_json::Value;
use std::time::Instant;

impl Matrix {
    /// The memory table's runs (experiment `memory`).
    pub(super) fn memory_table(&mut self, plan: &Plan) {
        for scene in plan.memory_scenes.clone() {
            let mut triangles = None;
            for b in plan.backends.clone() {
                self.progress
                    .step(&format!("memory: {scene} silhouette {b}"));
                let args = [
                    "silhouette",
                    scene,
                    "--backend",
                    &b,
                    "--mode",
                    "exact",
                    "--format",
                    "json",
                ];
                if let Some(m) = self.memory_run(scene, &b, &args, None) {
                    triangles = triangles.or(m);
                }
            }
            for (key, flags) in MEMORY_RENDERS {
                self.progress.step(&format!("memory: {scene} {key}"));
                let png = self.render_png(&format!("memory-{scene}-{key}"));
                let mut args = render_args(scene, &png, MEMORY_RENDER_SIZE);
                args.extend_from_slice(flags);
                self.memory_run(scene, key, &args, triangles);
            }
        }
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
        let v = match self.cli.json::<Value>(args) {
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
