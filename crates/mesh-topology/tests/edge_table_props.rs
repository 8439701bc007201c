//! Properties of welding and the edge table on random meshes, checked against naive
//! reference computations (quadratic welding, a `BTreeMap` of edges).

use glam::Vec3;
use proptest::prelude::*;
use shadowvol_mesh_topology::{weld, EdgeTable, Mesh, MeshError, NO_NEIGHBOR};
use std::collections::BTreeMap;

/// Naive weld: the name of vertex `i` is the smallest `j` with `p[j] == p[i]` (IEEE equality,
/// so `-0.0 == +0.0`).
fn naive_names(p: &[Vec3]) -> Vec<u32> {
    (0..p.len())
        .map(|i| (0..=i).find(|&j| p[j] == p[i]).unwrap() as u32)
        .collect()
}

/// Reference edge map: `(name_a, name_b)` (a < b) -> OV names, in input-triangle order.
fn naive_edges(mesh: &Mesh, names: &[u32]) -> (BTreeMap<(u32, u32), Vec<u32>>, usize) {
    let mut map: BTreeMap<(u32, u32), Vec<u32>> = BTreeMap::new();
    let mut kept = 0;
    for t in &mesh.triangles {
        let n = t.map(|v| names[v as usize]);
        if n[0] == n[1] || n[1] == n[2] || n[0] == n[2] {
            continue;
        }
        kept += 1;
        for i in 0..3 {
            let (a, b, o) = (n[i], n[(i + 1) % 3], n[(i + 2) % 3]);
            map.entry((a.min(b), a.max(b))).or_default().push(o);
        }
    }
    (map, kept)
}

/// Checks every structural property of `table` against the naive references.
fn check_table(mesh: &Mesh, table: &EdgeTable) {
    let names = naive_names(&mesh.positions);
    // Welding: names are the smallest index of each group, strictly increasing, positions kept.
    let mut expected_names: Vec<u32> = names.clone();
    expected_names.sort_unstable();
    expected_names.dedup();
    assert_eq!(table.vertex_names.to_vec(), expected_names);
    assert_eq!(
        table.vertex_names.is_identity(),
        expected_names
            .iter()
            .enumerate()
            .all(|(i, &n)| n == i as u32),
        "names are stored exactly when they are not the identity"
    );
    for (c, name) in table.vertex_names.iter().enumerate() {
        assert_eq!(table.positions[c], mesh.positions[name as usize]);
    }
    let compact_of_name = |name: u32| table.vertex_names.position(name).unwrap() as u32;

    // Kept triangles and their sources.
    let (map, kept) = naive_edges(mesh, &names);
    assert_eq!(table.triangles.len(), kept);
    assert_eq!(table.triangle_sources.len(), kept);
    let sources = table.triangle_sources.to_vec();
    assert!(sources.windows(2).all(|w| w[0] < w[1]));
    assert_eq!(
        table.triangle_sources.is_identity(),
        kept == mesh.triangles.len()
    );
    for (t, &src) in table.triangles.iter().zip(&sources) {
        let want = mesh.triangles[src as usize].map(|v| compact_of_name(names[v as usize]));
        assert_eq!(*t, want, "kept triangle keeps its winding, in compact ids");
    }

    // Edges: sorted, a < b, exactly the reference set, OVs in triangle order.
    assert!(
        table.edges.windows(2).all(|w| w[0] < w[1]),
        "edges sorted, unique"
    );
    assert!(table.edges.iter().all(|&[a, b]| a < b));
    assert_eq!(table.edges.len(), map.len());
    // CSR well-formed.
    assert_eq!(table.ov_offsets.len(), table.edges.len() + 1);
    assert_eq!(table.ov_offsets[0], 0);
    assert_eq!(
        *table.ov_offsets.last().unwrap() as usize,
        table.ov_refs.len()
    );
    assert!(
        table.ov_offsets.windows(2).all(|w| w[0] < w[1]),
        "every edge has an OV"
    );
    assert_eq!(
        table.ov_refs.len(),
        3 * kept,
        "OV count is 3 x kept triangles"
    );
    for (e, ((&(na, nb), ovs), &[a, b])) in map.iter().zip(&table.edges).enumerate() {
        assert_eq!((na, nb), table.edge_names(e));
        assert_eq!((compact_of_name(na), compact_of_name(nb)), (a, b));
        let got: Vec<u32> = table
            .ovs_of(e)
            .map(|o| table.vertex_names.get(o as usize))
            .collect();
        assert_eq!(&got, ovs, "OVs of edge ({na}, {nb})");
        assert!(table.ovs_of(e).all(|o| o != a && o != b));
        // Each reference `4 t + rank` names a triangle with this edge, whose vertex of that rank
        // is the opposite one; rank 1 (between the ends) is the odd parity.
        for &r in table.ov_refs_of(e) {
            let (t, rank) = ((r >> 2) as usize, (r & 3) as usize);
            let mut sorted = table.triangles[t];
            sorted.sort_unstable();
            let o = sorted[rank];
            let mut ids = [a, b, o];
            ids.sort_unstable();
            assert_eq!(ids, sorted, "reference {r} of edge {e}");
            assert_eq!(table.ov_vertex(r), o);
            assert_eq!(EdgeTable::ov_triangle(r) as usize, t);
            assert_eq!(EdgeTable::ov_odd(r), a < o && o < b, "reference {r}");
        }
    }
    // Every triangle's three edges are present and point back to the triangle.
    let tri_edges = table.tri_edges();
    assert_eq!(tri_edges.len(), table.triangles.len());
    for (t, tri) in table.triangles.iter().enumerate() {
        for i in 0..3 {
            let (a, b) = (tri[i], tri[(i + 1) % 3]);
            let e = tri_edges[t][i] as usize;
            assert_eq!(table.edge_index(b, a), Some(e as u32));
            assert_eq!(table.edges[e], [a.min(b), a.max(b)]);
            let o = tri[(i + 2) % 3];
            let rank = tri.iter().filter(|&&v| v < o).count() as u32;
            assert!(table.ov_refs_of(e).contains(&(4 * t as u32 + rank)));
        }
    }

    // Stats add up.
    let s = &table.stats;
    assert_eq!(s.vertices, mesh.positions.len());
    assert_eq!(s.welded_vertices, table.positions.len());
    assert_eq!(s.triangles, mesh.triangles.len());
    assert_eq!(s.degenerate_triangles, mesh.triangles.len() - kept);
    assert_eq!(s.edges, table.edges.len());
    assert_eq!(
        s.boundary_edges + s.manifold_edges + s.nonmanifold_edges,
        s.edges
    );
    let count = |k: fn(usize) -> bool| map.values().filter(|v| k(v.len())).count();
    assert_eq!(s.boundary_edges, count(|n| n == 1));
    assert_eq!(s.manifold_edges, count(|n| n == 2));
    assert_eq!(s.nonmanifold_edges, count(|n| n >= 3));
    assert_eq!(s.opposite_vertices, table.ov_refs.len());

    check_connectivity(table);
}

/// Neighbours: across a manifold edge the other triangle (and symmetric), else NO_NEIGHBOR.
fn check_connectivity(table: &EdgeTable) {
    let tri_edges = table.tri_edges();
    let neighbors = table.manifold_neighbors();
    assert_eq!(neighbors.len(), table.triangles.len());
    for t in 0..table.triangles.len() {
        for i in 0..3 {
            let e = tri_edges[t][i] as usize;
            let n = neighbors[t][i];
            if table.ovs_of(e).len() == 2 {
                assert_ne!(n, NO_NEIGHBOR);
                assert_ne!(n as usize, t);
                let j = tri_edges[n as usize]
                    .iter()
                    .position(|&x| x as usize == e)
                    .expect("the neighbour shares the edge");
                assert_eq!(neighbors[n as usize][j] as usize, t, "symmetric");
            } else {
                assert_eq!(n, NO_NEIGHBOR);
            }
        }
    }
}

/// Random meshes over a small coordinate pool: duplicates weld, `-0.0`/`+0.0` meet, triangles
/// over few vertices make non-manifold edges and degenerate triangles.
fn mesh_strategy() -> impl Strategy<Value = Mesh> {
    let coord = proptest::sample::select(vec![0.0f32, -0.0, 1.0, -1.0, 0.5, 1e-45, 3.0]);
    (1usize..24)
        .prop_flat_map(move |n| {
            let positions = proptest::collection::vec(
                (coord.clone(), coord.clone(), coord.clone())
                    .prop_map(|(x, y, z)| Vec3::new(x, y, z)),
                n,
            );
            let tri = proptest::array::uniform3(0..n as u32);
            (positions, proptest::collection::vec(tri, 0..60))
        })
        .prop_map(|(positions, triangles)| Mesh::new(positions, triangles).unwrap())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn prop_edge_table_matches_reference(mesh in mesh_strategy()) {
        let table = EdgeTable::build(&mesh).unwrap();
        check_table(&mesh, &table);
    }

    #[test]
    fn prop_weld_names_smallest_index(mesh in mesh_strategy()) {
        let w = weld(&mesh.positions);
        let names = naive_names(&mesh.positions);
        for (i, &c) in w.compact_of_input.iter().enumerate() {
            prop_assert_eq!(w.names[c as usize], names[i]);
        }
        prop_assert!(w.names.windows(2).all(|x| x[0] < x[1]));
    }

    #[test]
    fn prop_append_keeps_both(a in mesh_strategy(), b in mesh_strategy()) {
        let mut m = a.clone();
        m.append(&b).unwrap();
        prop_assert_eq!(m.positions.len(), a.positions.len() + b.positions.len());
        prop_assert_eq!(m.triangles.len(), a.triangles.len() + b.triangles.len());
        prop_assert!(m.validate().is_ok());
        // `a` unchanged, then `b` with its indices offset by `a`'s vertex count.
        let base = a.positions.len() as u32;
        prop_assert_eq!(&m.positions[..a.positions.len()], &a.positions[..]);
        prop_assert_eq!(&m.positions[a.positions.len()..], &b.positions[..]);
        prop_assert_eq!(&m.triangles[..a.triangles.len()], &a.triangles[..]);
        for (got, t) in m.triangles[a.triangles.len()..].iter().zip(&b.triangles) {
            prop_assert_eq!(*got, [t[0] + base, t[1] + base, t[2] + base]);
            prop_assert_eq!(got.map(|v| m.positions[v as usize]), t.map(|v| b.positions[v as usize]));
        }
        let table = EdgeTable::build(&m).unwrap();
        check_table(&m, &table);
    }
}

#[test]
fn negative_zero_welds_with_positive_zero() {
    let mesh = Mesh::new(
        vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(-0.0, -0.0, -0.0),
            Vec3::new(1.0, -0.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        ],
        vec![[0, 1, 2], [3, 4, 5]],
    )
    .unwrap();
    let t = EdgeTable::build(&mesh).unwrap();
    assert_eq!(t.vertex_names.to_vec(), vec![0, 1, 2, 5]);
    // Both triangles share the welded edge (0, 1): it is manifold.
    assert_eq!(t.edges[0], [0, 1]);
    assert!(t.ovs_of(0).eq([2, 3]));
    assert_eq!(t.stats.manifold_edges, 1);
    check_table(&mesh, &t);
}

#[test]
fn connectivity_of_a_closed_octahedron() {
    let p = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let tris = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    let mesh = Mesh::new(p, tris).unwrap();
    let t = EdgeTable::build(&mesh).unwrap();
    assert_eq!(t.stats.edges, 12);
    assert_eq!(t.stats.manifold_edges, 12);
    // Every triangle has three neighbours, all different, and the relation is symmetric.
    let neighbors = t.manifold_neighbors();
    for (i, n) in neighbors.iter().enumerate() {
        assert!(n.iter().all(|&x| x != NO_NEIGHBOR && x as usize != i));
        assert!(n[0] != n[1] && n[1] != n[2] && n[0] != n[2]);
    }
    // Triangle 0 = [0, 2, 4]: edge 0 (0-2) borders [2, 0, 5] (4), edge 1 (2-4) borders
    // [2, 1, 4] (1), edge 2 (4-0) borders [3, 0, 4] (3).
    assert_eq!(neighbors[0], [4, 1, 3]);
    check_table(&mesh, &t);
}

#[test]
fn connectivity_of_books_and_boundaries() {
    // A quad (two triangles, one shared edge) plus a third page on the shared edge makes it
    // non-manifold: then nobody has a neighbour across it.
    let p = vec![
        Vec3::ZERO,
        Vec3::X,
        Vec3::Y,
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::Z,
    ];
    let quad = vec![[0, 1, 2], [1, 3, 2]];
    let t = EdgeTable::build(&Mesh::new(p.clone(), quad.clone()).unwrap()).unwrap();
    let neighbors = t.manifold_neighbors();
    assert_eq!(neighbors[0], [NO_NEIGHBOR, 1, NO_NEIGHBOR]);
    assert_eq!(neighbors[1], [NO_NEIGHBOR, NO_NEIGHBOR, 0]);
    let mut book = quad;
    book.push([1, 2, 4]);
    let mesh = Mesh::new(p, book).unwrap();
    let t = EdgeTable::build(&mesh).unwrap();
    assert_eq!(t.stats.nonmanifold_edges, 1);
    assert!(t
        .manifold_neighbors()
        .iter()
        .flatten()
        .all(|&n| n == NO_NEIGHBOR));
    check_table(&mesh, &t);
}

#[test]
fn duplicate_triangles_are_kept_as_a_manifold_pair() {
    // The same triangle twice (a double-sided sheet): every edge has the same OV twice.
    let p = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
    let mesh = Mesh::new(p, vec![[0, 1, 2], [0, 2, 1]]).unwrap();
    let t = EdgeTable::build(&mesh).unwrap();
    assert_eq!(t.stats.manifold_edges, 3);
    assert!(t.ovs_of(0).eq([2, 2]));
    check_table(&mesh, &t);
}

#[test]
fn invalid_meshes_are_rejected_with_the_place() {
    let e = Mesh::new(vec![Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0)], vec![]).unwrap_err();
    assert_eq!(
        e,
        MeshError::NonFinitePosition {
            vertex: 1,
            axis: 'x',
            value: f32::INFINITY
        }
    );
    let bad = Mesh {
        positions: vec![Vec3::ZERO; 3],
        triangles: vec![[0, 1, 2], [0, 3, 1]],
    };
    assert!(matches!(
        EdgeTable::build(&bad),
        Err(MeshError::IndexOutOfRange {
            triangle: 1,
            corner: 1,
            index: 3,
            vertices: 3
        })
    ));
}

#[test]
fn empty_mesh_gives_empty_table() {
    let t = EdgeTable::build(&Mesh::default()).unwrap();
    assert_eq!(t.edges.len(), 0);
    assert_eq!(t.ov_offsets, vec![0]);
    assert_eq!(t.stats, Default::default());
}

#[test]
fn counts_and_streamed_bytes_of_a_tetrahedron() {
    let mesh = Mesh::new(
        vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
        vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    )
    .unwrap();
    assert_eq!(mesh.triangle_count(), 4);
    let t = EdgeTable::build(&mesh).unwrap();
    assert_eq!(t.edge_count(), 6);
    assert_eq!(t.edge_count(), t.edges.len());
    // One pass reads the edge records, offsets, OVs and positions: their sizes in memory.
    use std::mem::size_of_val;
    let want = size_of_val(&t.edges[..]) + size_of_val(&t.ov_offsets[..]);
    let want = want + size_of_val(&t.ov_refs[..]) + size_of_val(&t.positions[..]);
    assert_eq!(t.streamed_bytes(), want);
    // 6 edges x 8 + 7 offsets x 4 + 12 OVs x 4 + 4 positions x 12.
    assert_eq!(t.streamed_bytes(), 48 + 28 + 48 + 48);
    check_table(&mesh, &t);
}

#[test]
fn index_limits_are_exact_and_named() {
    let limit = u64::from(u32::MAX) - 1;
    // 4 x triangles >= 2^32 - 1 is too many references; one triangle less fits.
    let t = u64::from(u32::MAX) / 4 + 1;
    assert_eq!(4 * t, u64::from(u32::MAX) + 1);
    assert_eq!(
        EdgeTable::check_size(t, 3),
        Err(MeshError::TooLarge {
            what: "opposite-vertex references (4 x triangles)",
            count: 4 * t,
            limit,
        })
    );
    assert!(!matches!(
        EdgeTable::check_size(t - 1, 3),
        Err(MeshError::TooLarge { .. })
    ));
    assert_eq!(
        EdgeTable::check_size(1, u64::from(u32::MAX)),
        Err(MeshError::TooLarge {
            what: "vertices",
            count: u64::from(u32::MAX),
            limit,
        })
    );
    assert!(!matches!(
        EdgeTable::check_size(1, limit),
        Err(MeshError::TooLarge { .. })
    ));
}

#[test]
fn append_refuses_only_beyond_u32() {
    // 2 x 70 000 vertices fit easily (the product of the two counts would not).
    let strip = |n: u32| Mesh {
        positions: (0..n).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect(),
        triangles: vec![[0, 1, n - 1]],
    };
    let mut m = strip(70_000);
    m.append(&strip(70_000)).unwrap();
    assert_eq!(m.positions.len(), 140_000);
    assert_eq!(m.triangles, vec![[0, 1, 69_999], [70_000, 70_001, 139_999]]);
    assert!(m.validate().is_ok());
}
