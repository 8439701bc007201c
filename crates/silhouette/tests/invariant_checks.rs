//! The closed-chain invariant and the result comparisons of `invariant`, on chains walked by
//! hand over an octahedron: a walk's open vertices are counted here from the walk itself (where
//! it enters a vertex a different number of times than it leaves it), independently of the
//! multiplicity sums that `open_vertices` forms.

use glam::{Affine3A, Vec3};
use shadowvol_mesh_topology::{EdgeTable, Mesh};
use shadowvol_silhouette::invariant::{
    check_split_batches, differing_edges, differing_signs, first_difference, open_vertices,
    open_vertices_scene,
};
use shadowvol_silhouette::{Accuracy, ExtractStats, Multiplicities, SceneObject, TopologyScene};
use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Duration;

/// A closed octahedron: vertices ±X (0, 1), ±Y (2, 3), ±Z (4, 5); 12 edges.
fn octahedron() -> EdgeTable {
    let p = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let t = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    EdgeTable::build(&Mesh::new(p, t).unwrap()).unwrap()
}

/// Multiplicities of walks (each a list of vertices, every step along an edge): edge `(a, b)`,
/// `a < b`, gets `+1` per step from `a` to `b` and `-1` per step from `b` to `a`. Returns them
/// with the walks' open vertices counted from the steps.
fn walks(table: &EdgeTable, walks: &[&[u32]]) -> (Vec<i32>, usize) {
    let mut m = vec![0; table.edges.len()];
    let mut balance: BTreeMap<u32, i32> = BTreeMap::new();
    for w in walks {
        for s in w.windows(2) {
            let (from, to) = (s[0], s[1]);
            let e = table
                .edges
                .iter()
                .position(|&e| e == [from.min(to), from.max(to)])
                .expect("a step along an edge");
            m[e] += if from < to { 1 } else { -1 };
            *balance.entry(from).or_default() -= 1;
            *balance.entry(to).or_default() += 1;
        }
    }
    (m, balance.values().filter(|&&b| b != 0).count())
}

#[test]
fn open_vertices_of_walks() {
    let t = octahedron();
    let cases: [(&[&[u32]], usize); 10] = [
        (&[], 0),
        // The equator, a closed cycle, once and twice.
        (&[&[0, 2, 1, 3, 0]], 0),
        (&[&[0, 2, 1, 3, 0, 2, 1, 3, 0]], 0),
        (&[&[0, 2, 1]], 2),
        // Steps that go up in vertex id twice in a row: 0 -> 2 -> 4 (a chain's middle vertex is
        // then the larger end of one edge and the smaller of the next).
        (&[&[0, 2, 4, 0]], 0),
        (&[&[0, 2, 4]], 2),
        (&[&[5, 3, 1, 5], &[1, 2, 0]], 2),
        (&[&[4, 0], &[4, 2]], 3),
        (&[&[4, 0], &[4, 2], &[4, 1], &[3, 5]], 6),
        // A closed walk through both poles, and one step back and forth (cancels).
        (&[&[4, 0, 5, 1, 4], &[2, 4, 2]], 0),
    ];
    for (w, want) in cases {
        let (m, open) = walks(&t, w);
        assert_eq!(open, want, "the test's own count of {w:?}");
        assert_eq!(open_vertices(&t, &m), want, "{w:?}: m = {m:?}");
        // Negating every multiplicity walks the chains backwards: the same open vertices.
        let neg: Vec<i32> = m.iter().map(|x| -x).collect();
        assert_eq!(open_vertices(&t, &neg), want, "{w:?} backwards");
    }
}

#[test]
fn open_vertices_of_a_scene_sum_over_objects() {
    let t = Arc::new(octahedron());
    let object = |name: &str, x: f32| SceneObject {
        name: name.to_owned(),
        table: Arc::clone(&t),
        world_from_object: Affine3A::from_translation(Vec3::new(x, 0.0, 0.0)),
    };
    let scene = TopologyScene {
        objects: vec![object("a", 0.0), object("b", 3.0), object("c", -3.0)],
    };
    let per_object = [
        walks(&t, &[&[0, 2, 1]]),                // 2 open
        walks(&t, &[&[0, 2, 1, 3, 0]]),          // closed
        walks(&t, &[&[4, 0], &[4, 2], &[4, 1]]), // 4 open
    ];
    let mut m = Multiplicities::zeroed(scene.total_edges(), 2);
    let values: Vec<i32> = per_object.iter().flat_map(|(m, _)| m.clone()).collect();
    m.values_mut(1).copy_from_slice(&values);
    let want: usize = per_object.iter().map(|(_, open)| open).sum();
    assert_eq!(want, 6);
    assert_eq!(open_vertices_scene(&scene, &m, 1), want);
    assert_eq!(open_vertices_scene(&scene, &m, 0), 0);
    // Object by object, from the scene's slices.
    let offsets = scene.edge_offsets();
    for (i, (_, open)) in per_object.iter().enumerate() {
        let slice = &m.values(1)[offsets[i]..offsets[i + 1]];
        assert_eq!(open_vertices(&t, slice), *open, "object {i}");
    }
}

/// Two lights over `edges` edges with the given values, compact lists rebuilt.
fn result(edges: usize, values: &[(usize, usize, i32)]) -> Multiplicities {
    let mut m = Multiplicities::zeroed(edges, 2);
    for &(l, e, v) in values {
        m.values_mut(l)[e] = v;
    }
    m.rebuild_silhouettes();
    m
}

#[test]
fn comparisons_count_and_locate_differences() {
    let a = result(
        10,
        &[(0, 1, 1), (0, 4, -1), (1, 2, 2), (1, 7, 1), (1, 9, -1)],
    );
    // Light 0: edge 1 changes value only, edge 4 changes sign, edge 6 appears.
    // Light 1: edge 2 changes sign (2 -> -3), edges 7 and 9 vanish.
    let b = result(10, &[(0, 1, 2), (0, 4, 1), (0, 6, -1), (1, 2, -3)]);
    assert_eq!(differing_edges(&a, &b, 0), 3);
    assert_eq!(differing_signs(&a, &b, 0), 2);
    assert_eq!(differing_edges(&a, &b, 1), 3);
    assert_eq!(differing_signs(&a, &b, 1), 3);
    assert_eq!(differing_edges(&a, &a, 1), 0);
    assert_eq!(differing_signs(&a, &a, 0), 0);
    assert_eq!(first_difference(&a, &a), None);
    assert_eq!(first_difference(&a, &b), Some((0, 1, 1, 2)));
    // The first difference is found light by light, then edge by edge.
    let c = result(
        10,
        &[(0, 1, 1), (0, 4, -1), (1, 2, 2), (1, 7, -4), (1, 9, -1)],
    );
    assert_eq!(first_difference(&a, &c), Some((1, 7, 1, -4)));
    assert_eq!(first_difference(&c, &a), Some((1, 7, -4, 1)));
    // Different shapes are a difference, with no position.
    let shape = Some((usize::MAX, usize::MAX, 0, 0));
    assert_eq!(first_difference(&a, &Multiplicities::zeroed(9, 2)), shape);
    assert_eq!(first_difference(&a, &Multiplicities::zeroed(10, 3)), shape);
    assert_eq!(
        first_difference(
            &Multiplicities::zeroed(10, 3),
            &Multiplicities::zeroed(10, 3)
        ),
        None
    );
}

#[test]
fn check_split_batches_catches_each_property() {
    let scene = TopologyScene::single(octahedron());
    let edges = scene.total_edges();
    let (closed, _) = walks(&scene.objects[0].table, &[&[0, 2, 1, 3, 0]]);
    let (open, _) = walks(&scene.objects[0].table, &[&[0, 2, 1]]);
    let with = |l0: &[i32], l1: &[i32]| {
        let mut m = Multiplicities::zeroed(edges, 2);
        m.values_mut(0).copy_from_slice(l0);
        m.values_mut(1).copy_from_slice(l1);
        m.rebuild_silhouettes();
        m
    };
    let good = with(&closed, &closed);
    // Every time set, the total above compute + upload.
    let stats = ExtractStats {
        upload: Duration::from_micros(7),
        compute: Duration::from_micros(3),
        readback: Duration::from_micros(2),
        host_resolve: Duration::from_micros(1),
        uncertain: 0,
    };
    let run = |mode, got: &Multiplicities, s: &ExtractStats, one: &Multiplicities, exact| {
        check_split_batches(&scene, mode, (got, s), (one, &stats), exact)
    };
    for mode in Accuracy::ALL {
        assert_eq!(
            run(mode, &good, &stats, &good, Some(&good)),
            Ok(()),
            "{mode:?}"
        );
    }

    // Open chains: an error in the consistent modes only.
    let opened = with(&closed, &open);
    for mode in Accuracy::ALL {
        let r = run(mode, &opened, &stats, &opened, Some(&opened));
        if mode.is_consistent() {
            let e = r.unwrap_err();
            assert!(e.contains("light 1 has open vertices"), "{mode:?}: {e}");
        } else {
            assert_eq!(r, Ok(()), "{mode:?}");
        }
    }

    // The exact reference is compared in exact mode only.
    let other = with(&closed, &[0; 12]);
    let e = run(Accuracy::Exact, &good, &stats, &good, Some(&other)).unwrap_err();
    assert!(e.contains("differs from the exact reference"), "{e}");
    assert!(e.contains("(1, "), "names light 1: {e}");
    assert_eq!(
        run(Accuracy::Robust, &good, &stats, &good, Some(&other)),
        Ok(())
    );
    assert_eq!(run(Accuracy::Exact, &good, &stats, &good, None), Ok(()));

    // Uncertain pairs outside exact mode, even when both batches agree on them.
    let unsure = ExtractStats {
        uncertain: 3,
        ..stats
    };
    let r = check_split_batches(
        &scene,
        Accuracy::Ordered,
        (&good, &unsure),
        (&good, &unsure),
        None,
    );
    assert!(r.unwrap_err().contains("3 uncertain outside exact mode"));
    let r = check_split_batches(
        &scene,
        Accuracy::Exact,
        (&good, &unsure),
        (&good, &unsure),
        Some(&good),
    );
    assert_eq!(r, Ok(()));

    // The same values with a different silhouette list in the one-batch result.
    let mut stale = good.clone();
    stale.set_silhouette(0, vec![0]);
    let e = run(Accuracy::Robust, &good, &stats, &stale, None).unwrap_err();
    assert!(e.contains("light 0: silhouette list differs"), "{e}");

    // A result for another scene's edge count, with the same light count.
    let short = Multiplicities::zeroed(edges - 1, 2);
    let e = run(Accuracy::Original, &short, &stats, &short, None).unwrap_err();
    assert!(e.contains("2 lights x 11 edges, expected 2 x 12"), "{e}");

    // Times: no compute time, or a total below compute + upload, is implausible.
    let no_compute = ExtractStats {
        compute: Duration::ZERO,
        ..stats
    };
    let e = run(Accuracy::Robust, &good, &no_compute, &good, None).unwrap_err();
    assert!(e.contains("implausible times"), "{e}");
    let only_compute = ExtractStats {
        compute: Duration::from_micros(1),
        ..ExtractStats::default()
    };
    assert_eq!(
        run(Accuracy::Robust, &good, &only_compute, &good, None),
        Ok(())
    );
}

/// `check_split_batches` accepts equal results and names each broken property.
#[test]
fn check_split_batches_names_what_differs_on_a_corpus_case() {
    let case = shadowvol_test_support::corpus::case("book-4").expect("corpus case");
    let scene = case.scene().unwrap();
    let (edges, lights) = (scene.total_edges(), 2);
    // Zero multiplicities: every chain is trivially closed.
    let mut one = Multiplicities::zeroed(edges, lights);
    one.rebuild_silhouettes();
    let stats = ExtractStats {
        compute: Duration::from_micros(5),
        ..ExtractStats::default()
    };
    let check = |got: &Multiplicities, s: &ExtractStats, mode| {
        check_split_batches(&scene, mode, (got, s), (&one, &stats), Some(&one))
    };
    assert_eq!(check(&one, &stats, Accuracy::Robust), Ok(()));

    let mut other = one.clone();
    other.values_mut(1)[3] = 1;
    other.rebuild_silhouettes();
    let e = check(&other, &stats, Accuracy::Robust).unwrap_err();
    assert!(e.contains("differs from one batch"), "{e}");

    let mut stale = one.clone();
    stale.values_mut(0)[0] = 1;
    let e = check(&stale, &stats, Accuracy::Robust).unwrap_err();
    assert!(e.contains("compact silhouette lists"), "{e}");

    let more = ExtractStats {
        uncertain: 2,
        ..stats
    };
    let e = check(&one, &more, Accuracy::Exact).unwrap_err();
    assert!(e.contains("uncertain: 2 split, 0"), "{e}");

    let e = check(&one, &ExtractStats::default(), Accuracy::Original).unwrap_err();
    assert!(e.contains("implausible times"), "{e}");

    let wrong = Multiplicities::zeroed(edges, 1);
    let e = check(&wrong, &stats, Accuracy::Ordered).unwrap_err();
    assert!(e.contains("expected 2 x"), "{e}");
}
