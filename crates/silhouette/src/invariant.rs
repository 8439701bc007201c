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
    // Only the silhouette's vertices can be open: sum over them, not over every vertex (a
    // per-vertex array would be 8 bytes a vertex for a few thousand silhouette edges).
    let mut ends: Vec<(u32, i64)> = Vec::new();
    for (&[a, b], &mult) in table.edges.iter().zip(m) {
        if mult != 0 {
            ends.push((a, -i64::from(mult)));
            ends.push((b, i64::from(mult)));
        }
    }
    ends.sort_unstable_by_key(|&(v, _)| v);
    ends.chunk_by(|x, y| x.0 == y.0)
        .filter(|run| run.iter().map(|&(_, d)| d).sum::<i64>() != 0)
        .count()
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

/// Checks a result a backend computed with its lights split into several batches (launches,
/// passes) against the same backend's result for all lights at once, and the closed-chain
/// invariant. `split` and `whole` are each a result with its stats; `exact` is an independent
/// exact reference (for example the `cpu` backend in [`Accuracy::Exact`](crate::Accuracy)), compared
/// in exact mode only.
///
/// The properties, in order: the same light and edge counts; consistent compact lists; the same
/// multiplicities and the same silhouette list per light as `whole`; the same uncertain count
/// (each (edge, OV, light) is certified or not regardless of its batch), and none outside exact
/// mode; in exact mode the values of `exact`; in the consistent modes no open vertex for any
/// light; a non-zero compute time, within the total.
///
/// # Errors
/// A message naming the first property that does not hold (with the light and edge of the first
/// differing value where there is one).
pub fn check_split_batches(
    scene: &TopologyScene,
    mode: crate::Accuracy,
    split: (&Multiplicities, &crate::ExtractStats),
    whole: (&Multiplicities, &crate::ExtractStats),
    exact: Option<&Multiplicities>,
) -> Result<(), String> {
    let ((got, stats), (one, one_stats)) = (split, whole);
    if got.light_count() != one.light_count() || got.edge_count() != scene.total_edges() {
        return Err(format!(
            "{} lights x {} edges, expected {} x {}",
            got.light_count(),
            got.edge_count(),
            one.light_count(),
            scene.total_edges()
        ));
    }
    if !got.silhouettes_consistent() {
        return Err("compact silhouette lists disagree with the multiplicities".to_owned());
    }
    if let Some(d) = first_difference(got, one) {
        return Err(format!(
            "split result differs from one batch (light, edge, split, one batch): {d:?}"
        ));
    }
    if let Some(l) = (0..got.light_count()).find(|&l| got.silhouette(l) != one.silhouette(l)) {
        return Err(format!("light {l}: silhouette list differs from one batch"));
    }
    if stats.uncertain != one_stats.uncertain {
        return Err(format!(
            "uncertain: {} split, {} in one batch",
            stats.uncertain, one_stats.uncertain
        ));
    }
    if mode == crate::Accuracy::Exact {
        if let Some(d) = exact.and_then(|want| first_difference(got, want)) {
            return Err(format!(
                "differs from the exact reference (light, edge, got, reference): {d:?}"
            ));
        }
    } else if stats.uncertain != 0 {
        return Err(format!("{} uncertain outside exact mode", stats.uncertain));
    }
    if mode.is_consistent() {
        if let Some(l) = (0..got.light_count()).find(|&l| open_vertices_scene(scene, got, l) > 0) {
            return Err(format!("light {l} has open vertices"));
        }
    }
    if stats.compute.is_zero() || stats.total() < stats.compute + stats.upload {
        return Err(format!("implausible times: {stats:?}"));
    }
    Ok(())
}
