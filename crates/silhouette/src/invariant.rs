//! The closed-chain invariant and result comparisons.
//!
//! For every vertex `v`, the sum over silhouette edges `(a, b)` of `+m` if `v = b` and `-m` if
//! `v = a` is 0 whenever every triangle's three evaluations agree. `open_vertices` counts the
//! vertices where it is not.

use crate::{Multiplicities, TopologyScene};
use shadowvol_mesh_topology::EdgeTable;

/// Number of vertices of one edge table whose signed multiplicity sum is non-zero.
///
/// # Panics
/// Panics if `m.len() != table.edges.len()`.
#[must_use]
pub fn open_vertices(table: &EdgeTable, m: &[i32]) -> usize {
    assert_eq!(m.len(), table.edges.len(), "one multiplicity per edge");
    let mut sum = vec![0i64; table.positions.len()];
    for (&[a, b], &mult) in table.edges.iter().zip(m) {
        sum[a as usize] -= i64::from(mult);
        sum[b as usize] += i64::from(mult);
    }
    sum.iter().filter(|&&s| s != 0).count()
}

/// Open vertices of the whole scene for `light` (summed over objects).
///
/// # Panics
/// Panics if `m` does not match the scene's edge count or `light` is out of range.
#[must_use]
pub fn open_vertices_scene(scene: &TopologyScene, m: &Multiplicities, light: usize) -> usize {
    let offsets = scene.edge_offsets();
    let values = m.values(light);
    scene
        .objects
        .iter()
        .enumerate()
        .map(|(i, o)| open_vertices(&o.table, &values[offsets[i]..offsets[i + 1]]))
        .sum()
}

/// Number of edges whose multiplicity differs between `a` and `b` for `light`.
///
/// # Panics
/// Panics if the two results have different shapes.
#[must_use]
pub fn differing_edges(a: &Multiplicities, b: &Multiplicities, light: usize) -> usize {
    assert_eq!(a.edge_count(), b.edge_count());
    a.values(light)
        .iter()
        .zip(b.values(light))
        .filter(|(x, y)| x != y)
        .count()
}

/// Number of edges whose *sign* of `m` differs between `a` and `b` for `light`
/// (the accuracy table's "edges whose sign differs from exact").
///
/// # Panics
/// Panics if the two results have different shapes.
#[must_use]
pub fn differing_signs(a: &Multiplicities, b: &Multiplicities, light: usize) -> usize {
    assert_eq!(a.edge_count(), b.edge_count());
    a.values(light)
        .iter()
        .zip(b.values(light))
        .filter(|(x, y)| x.signum() != y.signum())
        .count()
}

/// The first difference between two results, as `(light, global edge, a, b)`, or `None` when
/// they are identical. For test messages.
#[must_use]
pub fn first_difference(
    a: &Multiplicities,
    b: &Multiplicities,
) -> Option<(usize, usize, i32, i32)> {
    if a.edge_count() != b.edge_count() || a.light_count() != b.light_count() {
        return Some((usize::MAX, usize::MAX, 0, 0));
    }
    (0..a.light_count()).find_map(|l| {
        a.values(l)
            .iter()
            .zip(b.values(l))
            .position(|(x, y)| x != y)
            .map(|e| (l, e, a.values(l)[e], b.values(l)[e]))
    })
}
