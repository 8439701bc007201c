//! The `simd` backend against the scalar `cpu` reference.
//!
//! * The whole conformance corpus, every supported SIMD level, both layouts (a copy, and the
//!   table read in place), every mode, all lights of a case in one call: results bit-identical
//!   to `cpu` (exact is required; the `f32` modes evaluate the
//!   same IEEE operations, so they must match too), and 0 open vertices in consistent modes.
//! * Procedural meshes that exercise partial blocks, the general CSR path (boundary and
//!   non-manifold edges), many objects with transforms and shared tables, thread counts.
//! * Degenerate lights (on a face plane, at a vertex) that the `f64` filter cannot certify:
//!   counted in `uncertain`, decided exactly.

use glam::{Affine3A, Quat, Vec3};
use shadowvol_cpu::CpuBackend;
use shadowvol_mesh_topology::{EdgeTable, Mesh};
use shadowvol_silhouette::{
    extract_once, invariant, Accuracy, Light, Multiplicities, SceneObject, SilhouetteBackend,
    TopologyScene,
};
use shadowvol_simd::{LayoutChoice, SimdBackend, SimdLevel};
use shadowvol_test_support::{corpus, shapes::uv_sphere_y};
use std::sync::Arc;

/// The two layouts every check runs on.
const LAYOUTS: [LayoutChoice; 2] = [LayoutChoice::Copy, LayoutChoice::InPlace];

fn levels() -> Vec<SimdLevel> {
    [SimdLevel::Wide, SimdLevel::Avx2]
        .into_iter()
        .filter(|l| l.is_supported())
        .collect()
}

/// Runs cpu and simd (every level and layout, 1 and 3 threads; all lights in one call and each
/// light alone) and checks equality and consistency.
/// Returns the total `uncertain` count of the exact runs (per level and thread count).
fn check_scene(name: &str, scene: &TopologyScene, lights: &[Light]) -> u64 {
    let mut uncertain = 0;
    for mode in Accuracy::ALL {
        let (reference, _) = extract_once(&mut CpuBackend::new(), scene, lights, mode).unwrap();
        for (level, layout) in levels().into_iter().flat_map(|l| LAYOUTS.map(|y| (l, y))) {
            for threads in [Some(1), Some(3)] {
                let mut simd = SimdBackend::with_level(level, threads)
                    .unwrap()
                    .with_layout(layout);
                let (m, stats) = extract_once(&mut simd, scene, lights, mode).unwrap();
                assert_eq!(
                    invariant::first_difference(&m, &reference),
                    None,
                    "{name}: simd {level:?} {layout:?} {threads:?} differs from cpu in mode \
                     {mode} (light, edge, simd, cpu)"
                );
                assert!(m.silhouettes_consistent(), "{name}: compact lists wrong");
                for l in 0..lights.len() {
                    assert_eq!(m.silhouette(l), reference.silhouette(l));
                    if mode.is_consistent() {
                        assert_eq!(
                            invariant::open_vertices_scene(scene, &m, l),
                            0,
                            "{name}: {mode} light {l} has open vertices"
                        );
                    }
                }
                if mode == Accuracy::Exact {
                    uncertain += stats.uncertain;
                } else {
                    assert_eq!(stats.uncertain, 0);
                }
                // One light per call takes the kernels' single-light paths: the same bits.
                for (l, light) in lights.iter().enumerate() {
                    let (one, _) = extract_once(&mut simd, scene, &[*light], mode).unwrap();
                    assert_eq!(
                        one.values(0),
                        reference.values(l),
                        "{name}: simd {level:?} {layout:?} {threads:?}, light {l} alone, \
                         differs from cpu in mode {mode}"
                    );
                    assert_eq!(one.silhouette(0), reference.silhouette(l));
                }
            }
        }
    }
    uncertain
}

#[test]
fn corpus_matches_cpu_in_every_mode_and_level() {
    let cases = corpus::cases();
    assert!(!cases.is_empty());
    for case in &cases {
        let scene = case.scene().unwrap();
        check_scene(case.name, &scene, &case.lights);
    }
}

#[test]
fn corpus_lights_one_at_a_time_equal_batched() {
    // Many lights in one call must equal one call per light.
    let mut simd = SimdBackend::with_level(SimdLevel::detect(), None).unwrap();
    for case in corpus::cases() {
        let scene = case.scene().unwrap();
        let id = simd.prepare(&scene).unwrap();
        for mode in Accuracy::ALL {
            let mut all = Multiplicities::default();
            simd.extract(id, &case.lights, mode, &mut all).unwrap();
            for (l, light) in case.lights.iter().enumerate() {
                let mut one = Multiplicities::default();
                simd.extract(id, &[*light], mode, &mut one).unwrap();
                assert_eq!(
                    one.values(0),
                    all.values(l),
                    "{} {mode} light {l}",
                    case.name
                );
                assert_eq!(one.silhouette(0), all.silhouette(l));
            }
        }
        simd.release(id);
    }
}

/// An open height-field grid (boundary edges) on a lattice, so many points are coplanar.
fn grid(n: u32) -> Mesh {
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let h = if (i + j) % 3 == 0 { 0.5 } else { 0.0 };
            p.push(Vec3::new(i as f32, h, j as f32));
        }
    }
    let id = |i: u32, j: u32| j * (n + 1) + i;
    let mut t = Vec::new();
    for j in 0..n {
        for i in 0..n {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    Mesh::new(p, t).unwrap()
}

/// A non-manifold "book": one spine shared by `pages` triangles, plus a pseudo-random soup.
fn book_and_soup(pages: u32, soup: u32) -> Mesh {
    let mut p = vec![Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0)];
    let mut t = Vec::new();
    for k in 0..pages {
        let a = k as f32 * 0.7;
        p.push(Vec3::new(a.cos(), a.sin(), 0.5));
        t.push([0, 1, 2 + k]);
    }
    let mut x = 12345u32;
    let mut rnd = || {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        (x % 2001) as f32 / 1000.0 - 1.0
    };
    let base = p.len() as u32;
    for _ in 0..soup + 2 {
        p.push(Vec3::new(rnd(), rnd(), rnd()));
    }
    for k in 0..soup {
        // Triangles sharing vertices in a strip, with some repeated edges.
        t.push([base + k, base + k + 1, base + (k * 7 + 2) % (soup + 2)]);
    }
    // Drop the degenerate ones the strip may make (repeated vertex): EdgeTable drops them too.
    Mesh::new(p, t).unwrap()
}

fn single(mesh: &Mesh) -> TopologyScene {
    TopologyScene::single(EdgeTable::build(mesh).unwrap())
}

fn lights() -> Vec<Light> {
    vec![
        Light::point(Vec3::new(3.1, 4.7, -2.3)),
        Light::directional(Vec3::new(-0.3, 1.0, 0.45)),
        Light::point(Vec3::new(0.2, -0.1, 0.05)),
        Light::directional(Vec3::new(0.0, 1.0, 0.0)),
    ]
}

#[test]
fn sphere_all_block_shapes() {
    // Sizes chosen so triangle and edge counts are not multiples of 8 (partial blocks).
    for (rings, segs) in [(3, 3), (5, 7), (17, 23)] {
        let mesh = uv_sphere_y(rings, segs, 1.5);
        check_scene(&format!("sphere {rings}x{segs}"), &single(&mesh), &lights());
    }
}

#[test]
fn open_grid_with_coplanar_lights() {
    let mesh = grid(13);
    // A directional light along the plane y = 0 and a point light on it: many exact zeros and
    // uncertain filter results.
    let mut ls = lights();
    ls.push(Light::directional(Vec3::new(1.0, 0.0, 0.0)));
    ls.push(Light::point(Vec3::new(3.0, 0.0, 4.0)));
    ls.push(Light::point(Vec3::new(2.0, 0.5, 3.0)));
    check_scene("grid", &single(&mesh), &ls);
}

#[test]
fn nonmanifold_book_and_soup() {
    let mesh = book_and_soup(5, 61);
    check_scene("book+soup", &single(&mesh), &lights());
}

#[test]
fn many_objects_transforms_and_shared_tables() {
    let sphere = Arc::new(EdgeTable::build(&uv_sphere_y(6, 9, 1.0)).unwrap());
    let grid = Arc::new(EdgeTable::build(&grid(5)).unwrap());
    let book = Arc::new(EdgeTable::build(&book_and_soup(4, 13)).unwrap());
    let mut objects = Vec::new();
    for i in 0..7 {
        let table = match i % 3 {
            0 => Arc::clone(&sphere),
            1 => Arc::clone(&grid),
            _ => Arc::clone(&book),
        };
        objects.push(SceneObject {
            name: format!("o{i}"),
            table,
            world_from_object: Affine3A::from_scale_rotation_translation(
                Vec3::splat(1.0 + 0.25 * i as f32),
                Quat::from_rotation_y(0.3 * i as f32),
                Vec3::new(2.5 * i as f32, 0.1 * i as f32, -1.0),
            ),
        });
    }
    let scene = TopologyScene { objects };
    check_scene("many objects", &scene, &lights());
}

/// A grid in the tilted plane `y = -(x + z) / 2` (exactly representable lattice points).
fn tilted_grid(n: u32) -> Mesh {
    let mut m = grid(n);
    for p in &mut m.positions {
        p.y = -(p.x + p.z) * 0.5;
    }
    m
}

#[test]
fn uncertain_lanes_are_counted_and_decided_exactly() {
    // Lights exactly in the plane of a tilted flat grid: every determinant is exactly 0 but its
    // terms are not, so the f64 filter cannot certify and the lanes go to the exact predicate.
    let mesh = tilted_grid(6);
    let ls = vec![
        Light::point(Vec3::new(0.25, -0.5, 0.75)),
        Light::directional(Vec3::new(1.0, -0.5, 0.0)),
        Light::point(Vec3::new(3.0, 1.0, 1.0)),
    ];
    let uncertain = check_scene("tilted grid, lights in its plane", &single(&mesh), &ls);
    assert!(
        uncertain > 0,
        "expected uncertain lanes on a coplanar light"
    );
    // Exact zeros everywhere for the in-plane lights: no silhouette at all.
    let (m, _) = extract_once(
        &mut SimdBackend::with_level(SimdLevel::detect(), None).unwrap(),
        &single(&mesh),
        &ls,
        Accuracy::Exact,
    )
    .unwrap();
    assert!(m.silhouette(0).is_empty() && m.silhouette(1).is_empty());
    assert!(!m.silhouette(2).is_empty());
}

#[test]
fn empty_lights_and_unknown_scene_are_errors() {
    let mut simd = SimdBackend::with_level(SimdLevel::Wide, Some(1)).unwrap();
    let scene = single(&uv_sphere_y(3, 3, 1.0));
    let id = simd.prepare(&scene).unwrap();
    let mut out = Multiplicities::default();
    assert!(simd.extract(id, &[], Accuracy::Exact, &mut out).is_err());
    simd.release(id);
    let err = simd
        .extract(id, &lights(), Accuracy::Exact, &mut out)
        .unwrap_err();
    assert!(err.to_string().contains("unknown prepared scene"), "{err}");
}

#[test]
fn info_reports_the_level() {
    for level in levels() {
        let simd = SimdBackend::with_level(level, Some(2)).unwrap();
        let info = simd.info();
        assert_eq!(info.name, "simd");
        assert_eq!(info.modes, Accuracy::ALL.to_vec());
        let reported = info
            .details
            .iter()
            .find(|(k, _)| k == "simd_level")
            .map(|(_, v)| v.clone());
        assert_eq!(reported.as_deref(), Some(level.name()));
        assert_eq!(simd.threads(), 2);
    }
}

#[test]
fn info_reports_the_layout_the_scene_got() {
    let scene = single(&uv_sphere_y(5, 4, 1.0));
    let layout_of = |simd: &SimdBackend| {
        simd.info()
            .details
            .into_iter()
            .find(|(k, _)| k == "simd_layout")
            .map(|(_, v)| v)
    };
    for (choice, before, after) in [
        (LayoutChoice::Auto, "auto", "copy"),
        (LayoutChoice::Copy, "copy", "copy"),
        (LayoutChoice::InPlace, "in-place", "in-place"),
    ] {
        let mut simd = SimdBackend::with_level(SimdLevel::detect(), Some(1))
            .unwrap()
            .with_layout(choice);
        assert_eq!(layout_of(&simd).as_deref(), Some(before));
        let id = simd.prepare(&scene).unwrap();
        assert_eq!(layout_of(&simd).as_deref(), Some(after), "{choice:?}");
        // The copy holds tens of bytes a triangle; in place, under one.
        let host = simd.prepared_bytes(id).unwrap().host;
        let triangles = scene.total_triangles() as u64;
        assert_eq!(
            host >= 16 * triangles,
            after == "copy",
            "{choice:?}: {host}"
        );
    }
}

#[test]
fn reused_output_is_fully_overwritten() {
    // The backend skips zeroing when the output already has the right shape; a stale result
    // from another mode / light must not leak through.
    let scene = single(&uv_sphere_y(9, 11, 1.0));
    let mut simd = SimdBackend::with_level(SimdLevel::detect(), None).unwrap();
    let mut cpu = CpuBackend::new();
    let (sid, cid) = (simd.prepare(&scene).unwrap(), cpu.prepare(&scene).unwrap());
    let mut out = Multiplicities::default();
    let mut reference = Multiplicities::default();
    let ls = lights();
    for (mode, light) in [
        (Accuracy::Original, ls[0]),
        (Accuracy::Exact, ls[1]),
        (Accuracy::Robust, ls[2]),
        (Accuracy::Ordered, ls[0]),
    ] {
        simd.extract(sid, &[light], mode, &mut out).unwrap();
        cpu.extract(cid, &[light], mode, &mut reference).unwrap();
        assert_eq!(out, reference, "{mode}");
    }
}

#[test]
fn many_small_objects_with_partial_blocks_and_one_backend_across_scenes() {
    // Objects whose edge counts are not multiples of 8 (the last block of each is partial and
    // manifold, so it takes the padded fast path), many of them with transforms, and one
    // backend alternating between scenes with different numbers of work items and lights (its
    // scratch is reused between calls).
    let small = Arc::new(EdgeTable::build(&uv_sphere_y(5, 7, 1.0)).unwrap());
    assert_ne!(small.edges.len() % 8, 0);
    let large = Arc::new(EdgeTable::build(&uv_sphere_y(60, 97, 2.0)).unwrap());
    let objects: Vec<SceneObject> = (0..37)
        .map(|i| SceneObject {
            name: format!("s{i}"),
            table: Arc::clone(&small),
            world_from_object: Affine3A::from_rotation_translation(
                Quat::from_rotation_x(0.1 * i as f32),
                Vec3::new(3.0 * (i % 6) as f32, 0.5, 3.0 * (i / 6) as f32),
            ),
        })
        .collect();
    let many = TopologyScene { objects };
    let one = TopologyScene::single((*large).clone());
    check_scene("37 small spheres", &many, &lights());
    let mut simd = SimdBackend::with_level(SimdLevel::detect(), Some(2)).unwrap();
    let mut cpu = CpuBackend::new();
    let ids: Vec<_> = [&many, &one]
        .iter()
        .map(|s| (simd.prepare(s).unwrap(), cpu.prepare(s).unwrap()))
        .collect();
    let ls = lights();
    for round in 0..6 {
        let (sid, cid) = ids[round % 2];
        let lights = if round % 3 == 0 { &ls[..1] } else { &ls[..] };
        for mode in Accuracy::ALL {
            let (mut out, mut reference) = (Multiplicities::default(), Multiplicities::default());
            simd.extract(sid, lights, mode, &mut out).unwrap();
            cpu.extract(cid, lights, mode, &mut reference).unwrap();
            assert_eq!(out, reference, "round {round} {mode}");
        }
    }
}
