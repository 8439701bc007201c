//! Procedural meshes: exact triangle counts, closed 2-manifolds, Loop subdivision, the town.

use glam::Vec3;
use shadowvol_cpu::CpuBackend;
use shadowvol_mesh_topology::{EdgeTable, Mesh};
use shadowvol_scenes::presets::bunny;
use shadowvol_scenes::procedural::{
    icosphere, loop_subdivide, loop_subdivide_levels, town, town_triangle_count, uv_sphere,
    TownParams,
};
use shadowvol_silhouette::{extract_once, invariant, Accuracy, Light, TopologyScene};

/// Asserts a closed, orientable-looking 2-manifold of genus 0: no boundary or non-manifold
/// edges, no degenerate triangles, Euler characteristic 2.
fn assert_closed_sphere(mesh: &Mesh, what: &str) {
    let t = EdgeTable::build(mesh).unwrap();
    let s = t.stats;
    assert_eq!(s.degenerate_triangles, 0, "{what}: {s:?}");
    assert_eq!(s.boundary_edges, 0, "{what}: {s:?}");
    assert_eq!(s.nonmanifold_edges, 0, "{what}: {s:?}");
    assert_eq!(s.edges * 2, s.triangles * 3, "{what}: {s:?}");
    let euler = s.welded_vertices as i64 - s.edges as i64 + s.triangles as i64;
    assert_eq!(euler, 2, "{what}: {s:?}");
    // Consistent winding: every directed edge appears once.
    let mut directed = std::collections::HashSet::new();
    for tri in &t.triangles {
        for k in 0..3 {
            assert!(
                directed.insert((tri[k], tri[(k + 1) % 3])),
                "{what}: inconsistent winding"
            );
        }
    }
}

/// Signed volume of a closed mesh (positive for outward winding).
fn volume(mesh: &Mesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

#[test]
fn uv_spheres_have_exactly_the_requested_count() {
    for target in [
        12, 14, 16, 20, 22, 26, 100, 998, 1_000, 1_002, 9_998, 10_000, 12_346, 65_000, 99_998,
    ] {
        let m = uv_sphere(target, 2.0);
        assert_eq!(m.triangles.len(), target, "uv_sphere({target})");
        assert_closed_sphere(&m, &format!("uv_sphere({target})"));
        for p in &m.positions {
            assert!((p.length() - 2.0).abs() < 1e-5, "{p} not on the sphere");
        }
        let v = volume(&m);
        assert!(
            v > 0.0 && v < 4.0 / 3.0 * std::f64::consts::PI * 8.0 + 1e-3,
            "{v}"
        );
    }
    // Odd counts round up to even (a closed triangle mesh has an even count).
    assert_eq!(uv_sphere(1_001, 1.0).triangles.len(), 1_002);
    assert_eq!(uv_sphere(0, 1.0).triangles.len(), 12);
}

#[test]
fn icospheres_have_exactly_the_requested_count() {
    for target in [320, 500, 998, 1_000, 10_000, 12_346, 65_000, 100_000] {
        let m = icosphere(target, 1.0);
        assert_eq!(m.triangles.len(), target, "icosphere({target})");
        assert_closed_sphere(&m, &format!("icosphere({target})"));
        assert!(volume(&m) > 0.0);
        for p in &m.positions {
            assert!((p.length() - 1.0).abs() < 1e-6);
        }
    }
    // Small targets: never above the target, at least the icosahedron.
    for target in [20, 80, 180, 200, 250, 300, 310] {
        let n = icosphere(target, 1.0).triangles.len();
        assert!((20..=target).contains(&n), "icosphere({target}) = {n}");
    }
}

#[test]
fn every_even_count_in_a_range_is_hit_exactly() {
    for target in (12..=800).step_by(2) {
        assert_eq!(uv_sphere(target, 1.0).triangles.len(), target, "uv_sphere");
    }
    for target in (320..=1_600).step_by(2) {
        assert_eq!(icosphere(target, 1.0).triangles.len(), target, "icosphere");
    }
    // Closed and manifold with edge splits at various remainders.
    for target in [322, 358, 502, 776, 1_178] {
        assert_closed_sphere(&icosphere(target, 1.0), &format!("icosphere({target})"));
        assert_closed_sphere(&uv_sphere(target, 1.0), &format!("uv_sphere({target})"));
    }
}

#[test]
fn loop_subdivision_quadruples_and_keeps_the_bunny_closed() {
    let b = bunny();
    assert_eq!(b.triangles.len(), 3_674);
    assert_closed_sphere(&b, "bunny");
    let one = loop_subdivide(&b);
    assert_eq!(one.triangles.len(), 4 * 3_674);
    assert_closed_sphere(&one, "bunny, 1 level");
    let two = loop_subdivide_levels(&b, 2);
    assert_eq!(two.triangles.len(), 16 * 3_674);
    assert_closed_sphere(&two, "bunny, 2 levels");
    // Loop subdivision is a smoothing approximating scheme: the volume shrinks a little.
    let (v0, v2) = (volume(&b), volume(&two));
    assert!(v2 < v0 && v2 > 0.9 * v0, "{v0} -> {v2}");
}

#[test]
fn loop_subdivision_keeps_boundaries_as_creases() {
    // A flat square of two triangles: boundary edges stay straight, the result stays planar.
    let m = Mesh::new(
        vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
        vec![[0, 1, 2], [0, 2, 3]],
    )
    .unwrap();
    let s = loop_subdivide_levels(&m, 2);
    assert_eq!(s.triangles.len(), 32);
    assert!(s.positions.iter().all(|p| p.z == 0.0));
    let t = EdgeTable::build(&s).unwrap();
    assert_eq!(t.stats.boundary_edges, 16);
    assert_eq!(t.stats.nonmanifold_edges, 0);
}

#[test]
fn town_size_walls_and_sun() {
    let p = TownParams::default();
    let n = town_triangle_count(&p);
    assert!(
        (n as f64 - 570_000.0).abs() <= 0.02 * 570_000.0,
        "town has {n} triangles"
    );
    // A small town to check the geometry (the full one is checked by the preset test).
    let small = TownParams { grid: 3, ..p };
    let m = town(&small);
    assert_eq!(m.triangles.len(), town_triangle_count(&small));
    let table = EdgeTable::build(&m).unwrap();
    assert_eq!(table.stats.boundary_edges, 0);
    assert_eq!(table.stats.nonmanifold_edges, 0);
    assert_eq!(table.stats.degenerate_triangles, 0);
    assert!(volume(&m) > 0.0);
    // Every triangle is axis-aligned; the walls (at least 2/3 of them here) are exactly
    // parallel to a sun along +Y: their normal has y == 0 exactly.
    let mut walls = 0;
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        let n = (b - a).cross(c - a);
        let nonzero = [n.x, n.y, n.z].iter().filter(|v| **v != 0.0).count();
        assert_eq!(nonzero, 1, "triangle not axis-aligned: {n}");
        if n.y == 0.0 {
            walls += 1;
        }
    }
    assert!(walls * 3 >= m.triangles.len() * 2, "{walls} walls");
    // The sun exactly along +Y: exact silhouettes close their chains, and the original f32
    // evaluation sees all walls as exactly edge-on too (integer coordinates: no rounding).
    let scene = TopologyScene::single(table);
    let sun = Light::directional(Vec3::Y);
    let (exact, _) = extract_once(&mut CpuBackend::new(), &scene, &[sun], Accuracy::Exact).unwrap();
    assert_eq!(invariant::open_vertices_scene(&scene, &exact, 0), 0);
    assert!(!exact.silhouette(0).is_empty());
    let (orig, _) =
        extract_once(&mut CpuBackend::new(), &scene, &[sun], Accuracy::Original).unwrap();
    assert_eq!(invariant::differing_edges(&exact, &orig, 0), 0);
}
