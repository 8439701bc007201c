//! Quick throughput check of the `simd` backend: a UV sphere of about `N` triangles (default
//! 10^6), every mode, every supported SIMD level, 1 and 4 lights, against the measured memory
//! floor (`shadowvol_registry::MemoryFloor`, the floor `shadowvol bench` reports).
//!
//! ```text
//! cargo run --release -p shadowvol-benches --example throughput -- 1000000
//! LEVEL=avx2 THREADS=1 MODE=exact LIGHTS=1,4 cargo run --release -p shadowvol-benches --example throughput
//! ```

use glam::Vec3;
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_registry::MemoryFloor;
use shadowvol_silhouette::{Accuracy, Light, Multiplicities, SilhouetteBackend, TopologyScene};
use shadowvol_simd::{SimdBackend, SimdLevel};
use shadowvol_test_support::shapes::uv_sphere_y;
use std::time::Duration;

fn median(mut v: Vec<Duration>) -> f64 {
    v.sort();
    v[v.len() / 2].as_secs_f64() * 1e3
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let rings = ((n / 4) as f64).sqrt().max(3.0) as u32;
    let mesh = uv_sphere_y(rings, 2 * rings, 1.0);
    let scene = TopologyScene::single(EdgeTable::build(&mesh).expect("table"));
    println!(
        "triangles {} edges {}",
        scene.total_triangles(),
        scene.total_edges()
    );
    let lights: Vec<Light> = (0..4)
        .map(|i| Light::point(Vec3::new(3.0 + i as f32, 2.0, 1.5 - i as f32)))
        .collect();
    let frames = 30;
    let light_counts: Vec<usize> = std::env::var("LIGHTS").ok().map_or(vec![1, 4], |s| {
        s.split(',').filter_map(|x| x.parse().ok()).collect()
    });
    for nl in light_counts {
        let mut floor = MemoryFloor::new(&scene, nl);
        let f = median((0..frames).map(|_| floor.run_once()).collect());
        println!("lights {nl}: floor {f:.3} ms");
        for level in [SimdLevel::Wide, SimdLevel::Avx2] {
            if !level.is_supported() {
                continue;
            }
            if std::env::var("LEVEL").is_ok_and(|l| l != level.name()) {
                continue;
            }
            let threads = std::env::var("THREADS").ok().and_then(|t| t.parse().ok());
            let mut b = SimdBackend::with_level(level, threads).expect("backend");
            let id = b.prepare(&scene).expect("prepare");
            let mut out = Multiplicities::default();
            for mode in Accuracy::ALL {
                if std::env::var("MODE").is_ok_and(|m| m != mode.name()) {
                    continue;
                }
                let mut times = Vec::new();
                let mut unc = 0;
                for _ in 0..frames + 3 {
                    let s = b
                        .extract(id, &lights[..nl], mode, &mut out)
                        .expect("extract");
                    times.push(s.compute);
                    unc = s.uncertain;
                }
                let t = median(times[3..].to_vec());
                println!(
                    "  {:>10} {:>9}: {t:8.3} ms  ({:.2}x floor, uncertain {unc})",
                    level.name(),
                    mode.name(),
                    t / f
                );
            }
        }
    }
}
