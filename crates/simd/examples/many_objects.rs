//! Many small objects against one large one: a 10x10 grid of UV spheres of about 1k triangles
//! (one shared table, one transform each) against one UV sphere of the same total, the scenes'
//! frames interleaved in turns so that a busy host slows both alike.
//!
//! ```text
//! cargo run --release -p shadowvol-simd --example many_objects -- [FRAMES] [MODES]
//! ```
//!
//! `MODES` is a comma-separated list of mode names (default `original,robust`). With
//! `ONLY=grid` or `ONLY=one` only that scene runs (for a profiler).

use glam::{Affine3A, Vec3};
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_silhouette::{
    Accuracy, Light, Multiplicities, SceneObject, SilhouetteBackend, TopologyScene,
};
use shadowvol_simd::{SimdBackend, SimdLevel};
use shadowvol_test_support::shapes::uv_sphere_y;
use std::sync::Arc;
use std::time::{Duration, Instant};

fn median(mut v: Vec<Duration>) -> f64 {
    v.sort();
    v[v.len() / 2].as_secs_f64() * 1e3
}

/// A UV sphere of about `n` triangles as a table.
fn sphere(n: usize) -> Arc<EdgeTable> {
    let rings = ((n / 4) as f64).sqrt().round().max(3.0) as u32;
    Arc::new(EdgeTable::build(&uv_sphere_y(rings, 2 * rings, 1.0)).expect("table"))
}

/// `cols x rows` instances of `table`, 3 units apart, standing on y = 0, and the light of the
/// scene presets' sphere grids.
fn grid(table: &Arc<EdgeTable>, cols: u32, rows: u32) -> (TopologyScene, Light) {
    let mut objects = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            objects.push(SceneObject {
                name: format!("sphere-{r}-{c}"),
                table: Arc::clone(table),
                world_from_object: Affine3A::from_translation(Vec3::new(
                    3.0 * c as f32,
                    1.0,
                    3.0 * r as f32,
                )),
            });
        }
    }
    let extent = 3.0 * cols.max(rows) as f32;
    let light = Light::point(Vec3::new(-0.6 * extent, 2.0 * extent + 4.0, 0.5 * extent));
    (TopologyScene { objects }, light)
}

fn main() {
    let mut args = std::env::args().skip(1);
    let frames: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(200);
    let modes: Vec<Accuracy> = args
        .next()
        .unwrap_or_else(|| "original,robust".to_owned())
        .split(',')
        .map(|m| {
            Accuracy::ALL
                .into_iter()
                .find(|a| a.name() == m)
                .expect("mode name")
        })
        .collect();
    let only = std::env::var("ONLY").unwrap_or_default();
    let scenes = [
        ("grid", grid(&sphere(1_000), 10, 10)),
        ("one", grid(&sphere(100_000), 1, 1)),
    ];
    let mut b = SimdBackend::with_level(SimdLevel::detect(), None).expect("backend");
    let mut runs = Vec::new();
    for (name, (scene, light)) in &scenes {
        if !only.is_empty() && only != *name {
            continue;
        }
        let id = b.prepare(scene).expect("prepare");
        for &mode in &modes {
            runs.push((*name, id, *light, mode, Vec::new(), scene.total_triangles()));
        }
    }
    let mut out = Multiplicities::default();
    let turn = 10;
    let mut done = 0;
    while done < frames {
        for (_, id, light, mode, times, _) in &mut runs {
            b.extract(*id, &[*light], *mode, &mut out).expect("extract");
            for _ in 0..turn {
                let t = Instant::now();
                b.extract(*id, &[*light], *mode, &mut out).expect("extract");
                times.push(t.elapsed());
            }
        }
        done += turn;
    }
    for (name, _, _, mode, times, tris) in runs {
        println!(
            "{name:>5} {:>9} ({tris} triangles): {:.4} ms",
            mode.name(),
            median(times)
        );
    }
}
