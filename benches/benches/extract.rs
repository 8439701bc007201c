//! Silhouette extraction at 10^3 .. 10^6 triangles (icospheres from
//! `shadowvol_scenes::procedural`): every backend of the registry (`shadowvol_registry::backends()`) that
//! starts here, in every mode; the `simd` backend also at the `wide` compile-time level; the
//! seeds' baselines; and the memory floor (`shadowvol_registry::MemoryFloor`) for the same scene.
//!
//! ```text
//! cargo bench -p shadowvol-benches --bench extract
//! cargo bench -p shadowvol-benches --bench extract -- 'simd/ordered'   # a filter
//! ```
//!
//! A backend that can't start here is skipped with a line on stderr saying why. Criterion
//! reports absolute times; `shadowvol bench` gives the ratios (backend / floor, mode / original).

use criterion::measurement::WallTime;
use criterion::{criterion_group, BenchmarkGroup, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use shadowvol_cpu::baselines::{Baseline, ClosedMesh};
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_registry::MemoryFloor;
use shadowvol_silhouette::{Accuracy, Light, Multiplicities, SilhouetteBackend, TopologyScene};
use shadowvol_simd::{SimdBackend, SimdLevel};
use std::hint::black_box;
use std::time::Duration;

const SIZES: [usize; 4] = [1_000, 10_000, 100_000, 1_000_000];

fn scene(triangles: usize) -> TopologyScene {
    let mesh = shadowvol_scenes::procedural::icosphere(triangles, 1.0);
    TopologyScene::single(EdgeTable::build(&mesh).expect("icosphere is valid"))
}

fn light() -> Light {
    Light::point(Vec3::new(2.3, 3.1, -1.7))
}

/// A benchmark group of 10 samples, 300 ms warm-up and 2 s of measurement.
fn short_group(c: &mut Criterion, name: impl Into<String>) -> BenchmarkGroup<'_, WallTime> {
    let mut group = c.benchmark_group(name);
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2));
    group
}

fn bench_backend(c: &mut Criterion, group_name: &str, backend: &mut dyn SilhouetteBackend) {
    for mode in Accuracy::ALL {
        let mut group = short_group(c, format!("{group_name}/{mode}"));
        for n in SIZES {
            let s = scene(n);
            let id = backend.prepare(&s).expect("prepare");
            let mut out = Multiplicities::default();
            group.throughput(Throughput::Elements(s.total_triangles() as u64));
            group.bench_function(BenchmarkId::from_parameter(n), |b| {
                b.iter(|| {
                    backend
                        .extract(id, &[light()], mode, &mut out)
                        .expect("extract");
                    black_box(out.silhouette(0).len())
                });
            });
            backend.release(id);
        }
        group.finish();
    }
}

/// Every registered backend that starts, then `simd` at the `wide` level when the detected level
/// is another.
fn extract(c: &mut Criterion) {
    for entry in shadowvol_registry::backends() {
        match entry.start() {
            Ok(mut backend) => bench_backend(c, entry.name, backend.as_mut()),
            Err(e) => eprintln!("extract: skipping {}: {e}", entry.name),
        }
    }
    if SimdLevel::detect() != SimdLevel::Wide {
        let mut wide = SimdBackend::with_level(SimdLevel::Wide, None).expect("simd");
        bench_backend(c, "simd-wide", &mut wide);
    }
}

fn floor(c: &mut Criterion) {
    let mut group = short_group(c, "floor");
    for n in SIZES {
        let s = scene(n);
        let mut f = MemoryFloor::new(&s, 1);
        group.throughput(Throughput::Bytes(
            (f.bytes_read() + f.bytes_written()) as u64,
        ));
        group.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| black_box(f.run_once()));
        });
    }
    group.finish();
}

fn baselines(c: &mut Criterion) {
    for which in [
        Baseline::TwoStep,
        Baseline::Connectivity,
        Baseline::FastHash { columns: 64 },
        Baseline::FastHash { columns: 8 },
        Baseline::Classic,
    ] {
        let mut group = short_group(c, format!("baseline/{}", which.name()));
        for n in SIZES {
            // The classic list is quadratic in the silhouette length: stop at 10^5.
            if which == Baseline::Classic && n > 100_000 {
                continue;
            }
            let s = scene(n);
            let closed = ClosedMesh::new(&s.objects[0].table).expect("closed icosphere");
            // Icosphere valence is at most 6: 8 columns always suffice.
            if closed.run(which, light().to_array()).is_err() {
                continue;
            }
            group.throughput(Throughput::Elements(s.total_triangles() as u64));
            group.bench_function(BenchmarkId::from_parameter(n), |b| {
                b.iter(|| black_box(closed.run(which, light().to_array())));
            });
        }
        group.finish();
    }
}

criterion_group!(benches, extract, floor, baselines);

/// `criterion_main!(benches)`, with Mesa's device-select layer turned off first where there is
/// no display (no `error: XDG_RUNTIME_DIR ...` line when the GPU backends start).
fn main() {
    shadowvol_silhouette::gpu::quiet_without_display();
    benches();
    Criterion::default().configure_from_args().final_summary();
}
