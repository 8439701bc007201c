//! Edge-table construction time (`EdgeTable::build`: validate, weld, counting-sort the edges,
//! CSR opposite vertices, connectivity) on procedural closed tori of 10^4, 10^5 and 10^6
//! triangles. Construction is linear: the time per triangle should stay about constant across
//! the three sizes (criterion reports throughput in triangles per second).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use shadowvol_mesh_topology::{EdgeTable, Mesh};
use std::hint::black_box;

/// A closed torus of `rows x cols` quads (2 triangles each), every vertex shared by 6 triangles.
/// Vertices are emitted three times over (per-corner, as loaders do for flat-shaded meshes), so
/// welding has real work to do.
fn torus(rows: u32, cols: u32) -> Mesh {
    let (big, small) = (3.0f32, 1.0f32);
    let vertex = |i: u32, j: u32| {
        let u = (i % rows) as f32 / rows as f32 * std::f32::consts::TAU;
        let v = (j % cols) as f32 / cols as f32 * std::f32::consts::TAU;
        let r = big + small * v.cos();
        Vec3::new(r * u.cos(), r * u.sin(), small * v.sin())
    };
    let mut positions = Vec::with_capacity((rows * cols * 6) as usize);
    let mut triangles = Vec::with_capacity((rows * cols * 2) as usize);
    for i in 0..rows {
        for j in 0..cols {
            let q = [
                vertex(i, j),
                vertex(i + 1, j),
                vertex(i + 1, j + 1),
                vertex(i, j + 1),
            ];
            for t in [[0, 1, 2], [0, 2, 3]] {
                let base = positions.len() as u32;
                positions.extend(t.map(|k| q[k]));
                triangles.push([base, base + 1, base + 2]);
            }
        }
    }
    Mesh::new(positions, triangles).expect("procedural torus is valid")
}

fn build_edge_table(c: &mut Criterion) {
    let mut group = c.benchmark_group("edge_table_build");
    group.sample_size(10);
    // rows x cols x 2 triangles: 10^4, ~10^5, 10^6.
    for (rows, cols) in [(100u32, 50u32), (320, 157), (1000, 500)] {
        let mesh = torus(rows, cols);
        let n = mesh.triangles.len() as u64;
        let table = EdgeTable::build(&mesh).expect("valid");
        assert_eq!(
            table.stats.manifold_edges, table.stats.edges,
            "closed manifold torus"
        );
        assert_eq!(table.stats.welded_vertices, (rows * cols) as usize);
        group.throughput(Throughput::Elements(n));
        group.bench_with_input(BenchmarkId::from_parameter(n), &mesh, |b, mesh| {
            b.iter(|| EdgeTable::build(black_box(mesh)).expect("valid"));
        });
    }
    group.finish();
}

criterion_group!(benches, build_edge_table);
criterion_main!(benches);
