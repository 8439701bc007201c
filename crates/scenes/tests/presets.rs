//! Every preset has the size DESIGN.md gives it, lights, a camera, and a valid topology.

use shadowvol_mesh_topology::EdgeTable;
use shadowvol_scenes::presets::{BUNNY_LEVELS, SPHERE_10_TRIANGLES};
use shadowvol_scenes::{is_preset, preset, presets, Scene};
use std::sync::Arc;

fn within(n: usize, target: usize, tolerance: f64) -> bool {
    (n as f64 - target as f64).abs() <= tolerance * target as f64
}

fn common_checks(scene: &Scene) {
    assert!(!scene.lights.is_empty(), "{}: no lights", scene.name);
    let cam = scene.camera.expect("preset has a camera");
    assert!(cam.eye.is_finite() && cam.target.is_finite() && cam.eye != cam.target);
    assert!(cam.fov_y > 0.0 && cam.near > 0.0);
    // The camera looks at the scene: the bounds' centre is in front of it.
    let (lo, hi) = scene.bounds().unwrap();
    let centre = (lo + hi) * 0.5;
    assert!((centre - cam.eye).dot(cam.target - cam.eye) > 0.0);
}

/// (name, objects, triangles per object, all objects share one mesh)
const GRIDS: &[(&str, usize, usize)] = &[
    ("bunnies-10-individual", 10, 3_674 * 16),
    ("spheres-10-individual", 10, SPHERE_10_TRIANGLES),
    ("sphere-1m", 1, 1_000_000),
    ("sphere-100k", 1, 100_000),
    ("spheres-100x10k", 100, 10_000),
    ("spheres-100x1k", 100, 1_000),
    ("sphere-10k", 1, 10_000),
    ("sphere-1k", 1, 1_000),
    ("bunny", 1, 3_674),
    ("bunny-subdivided", 1, 3_674 * 16),
];

#[test]
fn instanced_presets_match_their_sizes() {
    assert_eq!(BUNNY_LEVELS, 2);
    for &(name, objects, per) in GRIDS {
        let scene = preset(name).unwrap();
        assert_eq!(scene.name, name);
        assert_eq!(scene.geometry.objects.len(), objects, "{name}");
        for o in &scene.geometry.objects {
            assert_eq!(o.table.triangles.len(), per, "{name}: {}", o.name);
            assert!(
                Arc::ptr_eq(&o.table, &scene.geometry.objects[0].table),
                "{name}: one shared mesh"
            );
        }
        assert_eq!(scene.triangle_count(), objects * per);
        common_checks(&scene);
        // Objects do not overlap: their world bounds are disjoint boxes in x/z.
        let topo = &scene.geometry;
        assert_eq!(topo.objects.len(), objects);
        assert!(topo
            .objects
            .iter()
            .all(|o| Arc::ptr_eq(&o.table, &topo.objects[0].table)));
        let s = topo.objects[0].table.stats;
        assert_eq!(
            (
                s.boundary_edges,
                s.nonmanifold_edges,
                s.degenerate_triangles
            ),
            (0, 0, 0),
            "{name}"
        );
    }
}

#[test]
fn paper_table_2_scenes_have_about_650k_triangles() {
    for (name, objects) in [
        ("bunnies-10-individual", 10),
        ("bunnies-10-baked", 1),
        ("spheres-10-individual", 10),
        ("spheres-10-baked", 1),
    ] {
        let scene = preset(name).unwrap();
        assert_eq!(scene.geometry.objects.len(), objects, "{name}");
        let n = scene.triangle_count();
        // Bunnies: 10 * 3,674 * 16 = 587,840 (two Loop levels, -9.6 % from 6.5e5).
        assert!(within(n, 650_000, 0.10), "{name}: {n}");
        common_checks(&scene);
    }
}

#[test]
fn baked_presets_equal_their_individual_scenes_baked() {
    for base in ["bunnies-10", "spheres-10"] {
        let individual = preset(&format!("{base}-individual")).unwrap();
        let baked = preset(&format!("{base}-baked")).unwrap();
        assert_eq!(
            *baked.geometry.objects[0].table,
            *individual.baked_table().unwrap()
        );
        assert_eq!(baked.lights, individual.lights);
        let stats = baked.geometry.objects[0].table.stats;
        assert_eq!(stats.triangles, individual.triangle_count());
        // The instances stand apart: baking merges no vertices.
        assert_eq!(stats.welded_vertices, individual.geometry.total_vertices());
    }
}

#[test]
fn town_matches_its_size_and_sun() {
    let scene = preset("town").unwrap();
    let n = scene.triangle_count();
    assert!(within(n, 570_000, 0.02), "town: {n}");
    assert_eq!(scene.lights.len(), 1);
    let [x, y, z, w] = scene.lights[0].light.to_array();
    assert_eq!((x, z, w), (0.0, 0.0, 0.0), "sun exactly along an axis");
    assert!(y > 0.0);
    common_checks(&scene);
}

#[test]
fn hard_presets_are_the_hard_cases() {
    let cases = shadowvol_scenes::hard::cases();
    for case in &cases {
        let name = format!("hard-{}", case.name);
        assert!(is_preset(&name));
        let scene = preset(&name).unwrap();
        assert_eq!(scene.geometry.objects.len(), case.objects.len());
        for (o, (mesh, t)) in scene.geometry.objects.iter().zip(&case.objects) {
            assert_eq!(*o.table, EdgeTable::build(mesh).unwrap());
            assert_eq!(o.world_from_object, *t);
        }
        assert_eq!(scene.light_positions(), case.lights);
        common_checks(&scene);
    }
    let listed = presets()
        .iter()
        .filter(|p| p.name.starts_with("hard-"))
        .count();
    assert_eq!(listed, cases.len());
}

#[test]
fn every_listed_preset_builds_and_names_resolve() {
    let names: Vec<String> = presets().into_iter().map(|p| p.name).collect();
    for required in [
        "bunnies-10-individual",
        "bunnies-10-baked",
        "spheres-10-individual",
        "spheres-10-baked",
        "sphere-1m",
        "sphere-100k",
        "spheres-100x10k",
        "spheres-100x1k",
        "town",
        "sphere-1k",
        "sphere-10k",
        "bunny",
        "bunny-subdivided",
    ] {
        assert!(names.iter().any(|n| n == required), "{required} missing");
    }
    let mut unique = names.clone();
    unique.sort();
    unique.dedup();
    assert_eq!(unique.len(), names.len(), "duplicate names");
    assert!(!is_preset("hard-no-such-case"));
    assert!(preset("hard-no-such-case").is_err());
    let s = Scene::from_name_or_path("spheres-100x1k").unwrap();
    assert_eq!(s.geometry.objects.len(), 100);
}
