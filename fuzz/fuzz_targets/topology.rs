//! Arbitrary meshes into validation, welding and the edge table; checks the table's structure.
#![no_main]
use arbitrary::Arbitrary;
use glam::Vec3;
use libfuzzer_sys::fuzz_target;
use shadowvol_mesh_topology::{EdgeTable, Mesh};

#[derive(Arbitrary, Debug)]
struct Input {
    /// Coordinates drawn from a small palette (so welding and shared edges happen) or raw bits.
    coords: Vec<(u8, u32)>,
    triangles: Vec<[u16; 3]>,
}

fuzz_target!(|input: Input| {
    const PALETTE: [f32; 6] = [0.0, -0.0, 1.0, -1.0, 0.5, 1e-40];
    let vals: Vec<f32> = input
        .coords
        .iter()
        .map(|&(sel, bits)| {
            if sel < 200 {
                PALETTE[usize::from(sel) % PALETTE.len()]
            } else {
                f32::from_bits(bits)
            }
        })
        .collect();
    let positions: Vec<Vec3> = vals
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect();
    let triangles: Vec<[u32; 3]> = input
        .triangles
        .iter()
        .map(|t| t.map(u32::from))
        .collect();
    let mesh = Mesh {
        positions,
        triangles,
    };
    let Ok(table) = EdgeTable::build(&mesh) else {
        assert!(mesh.validate().is_err());
        return;
    };
    let s = table.stats;
    assert_eq!(s.triangles, mesh.triangles.len());
    assert_eq!(table.triangles.len() + s.degenerate_triangles, s.triangles);
    assert_eq!(table.ov_refs.len(), 3 * table.triangles.len());
    assert_eq!(s.boundary_edges + s.manifold_edges + s.nonmanifold_edges, s.edges);
    assert_eq!(table.ov_offsets.len(), table.edges.len() + 1);
    assert!(table.edges.windows(2).all(|w| w[0] < w[1]));
    assert!(table.edges.iter().all(|e| e[0] < e[1]));
    assert!(table.vertex_names.to_vec().windows(2).all(|w| w[0] < w[1]));
    assert_eq!(table.vertex_names.len(), table.positions.len());
    let sources = table.triangle_sources.to_vec();
    assert!(sources.windows(2).all(|w| w[0] < w[1]));
    assert_eq!(sources.len(), table.triangles.len());
    // Each triangle's edges, built on demand, are its edges.
    for (tri, te) in table.triangles.iter().zip(table.tri_edges()) {
        for i in 0..3 {
            let (u, v) = (tri[i], tri[(i + 1) % 3]);
            assert_eq!(table.edges[te[i] as usize], [u.min(v), u.max(v)]);
        }
    }
    // Each OV reference names a triangle with the edge, and the OV's rank in it.
    for (e, &[a, b]) in table.edges.iter().enumerate() {
        for &r in table.ov_refs_of(e) {
            let mut tri = table.triangles[EdgeTable::ov_triangle(r) as usize];
            tri.sort_unstable();
            let o = table.ov_vertex(r);
            assert!(o != a && o != b);
            let mut ids = [a, b, o];
            ids.sort_unstable();
            assert_eq!(ids, tri);
            assert_eq!(EdgeTable::ov_odd(r), a < o && o < b);
        }
    }
});
