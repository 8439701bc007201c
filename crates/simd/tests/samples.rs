//! Lights with a size: the samples of one light in one `exact` call, on `cpu` and `simd`,
//! against the `cpu` backend's one-light call for each sample.
//!
//! Both backends classify each triangle once against the box of the call's lights and compute an
//! edge whose triangles share one sign once for every light; the multiplicities of every sample
//! must still be those of that sample extracted as its own point light, bit for bit. Sample sets
//! of several radii around lights near and far from spheres, the `hard-*` presets and a soup,
//! and sets whose box touches a triangle's plane exactly (where only the corner test can tell).

use glam::Vec3;
use shadowvol_cpu::{extract_table_shared, CpuBackend};
use shadowvol_mesh_topology::{EdgeTable, Mesh};
use shadowvol_scenes::{preset, preset_names, Scene, SceneLight};
use shadowvol_silhouette::{
    object_lights, Accuracy, Light, Multiplicities, SceneObject, SilhouetteBackend, TopologyScene,
};
use shadowvol_simd::{LayoutChoice, SimdBackend, SimdLevel};
use shadowvol_test_support::shapes::{uv_sphere_y, Rng};
use std::sync::Arc;

/// Radii of the sample disks, as fractions of the scene's size (radians for directional lights).
const RADII: [f32; 4] = [1e-4, 1e-2, 0.1, 0.5];

/// Samples per light.
const SAMPLES: u32 = 16;

/// What the checks saw: triangles shared by the box and cut by it (the `cpu` classification,
/// summed over objects and sample sets), and sample sets checked.
#[derive(Debug, Default)]
struct Seen {
    shared: usize,
    cut: usize,
    sets: usize,
}

/// One light's multiplicities from a one-light call on `cpu`.
fn one_light(cpu: &mut CpuBackend, scene: &TopologyScene, light: Light) -> Vec<i32> {
    let id = cpu.prepare(scene).unwrap();
    let mut m = Multiplicities::default();
    cpu.extract(id, &[light], Accuracy::Exact, &mut m).unwrap();
    cpu.release(id);
    m.values(0).to_vec()
}

fn simd_backends() -> Vec<(String, SimdBackend)> {
    let mut v = Vec::new();
    for level in [SimdLevel::Wide, SimdLevel::Avx2] {
        if !level.is_supported() {
            continue;
        }
        for layout in [LayoutChoice::Copy, LayoutChoice::InPlace] {
            for threads in [Some(1), Some(3)] {
                v.push((
                    format!("simd {level:?} {layout:?} {threads:?}"),
                    SimdBackend::with_level(level, threads)
                        .unwrap()
                        .with_layout(layout),
                ));
            }
        }
    }
    v
}

/// Checks one sample set on `scene`: every sample's multiplicities from one multi-light call on
/// `cpu` and on every `simd` level, layout and thread count equal `cpu`'s one-light call for
/// that sample, with the compact lists. Returns the per-sample reference.
fn check_set(
    name: &str,
    scene: &TopologyScene,
    samples: &[Light],
    seen: &mut Seen,
) -> Vec<Vec<i32>> {
    let mut cpu = CpuBackend::new();
    let singles: Vec<Vec<i32>> = samples
        .iter()
        .map(|&l| one_light(&mut cpu, scene, l))
        .collect();
    let mut backends: Vec<(String, Box<dyn SilhouetteBackend>)> =
        vec![("cpu".to_owned(), Box::new(CpuBackend::new()))];
    for (n, b) in simd_backends() {
        backends.push((n, Box::new(b)));
    }
    for (backend, b) in &mut backends {
        let id = b.prepare(scene).unwrap();
        let mut m = Multiplicities::default();
        b.extract(id, samples, Accuracy::Exact, &mut m).unwrap();
        b.release(id);
        assert!(
            m.silhouettes_consistent(),
            "{name}: {backend}: compact lists"
        );
        for (l, want) in singles.iter().enumerate() {
            if let Some(e) = (0..want.len()).find(|&e| m.values(l)[e] != want[e]) {
                panic!(
                    "{name}: {backend}: sample {l} ({}) of {}: edge {e} has {} in the \
                     {}-light call, {} alone",
                    samples[l],
                    samples.len(),
                    m.values(l)[e],
                    samples.len(),
                    want[e]
                );
            }
        }
    }
    // The classification itself, on `cpu`: what the box shared and cut.
    let per_object = object_lights(scene.transforms(), samples);
    for (o, lights) in scene.objects.iter().zip(&per_object) {
        let mut rows = vec![vec![0; o.table.edges.len()]; lights.len()];
        let mut refs: Vec<&mut [i32]> = rows.iter_mut().map(Vec::as_mut_slice).collect();
        if let Some(cut) = extract_table_shared(&o.table, lights, &mut refs) {
            seen.cut += cut;
            seen.shared += o.table.triangles.len() - cut;
        }
    }
    seen.sets += 1;
    singles
}

/// The scene's size: the diagonal of its bounds (1 without vertices).
fn size_of(scene: &Scene) -> f32 {
    scene
        .bounds()
        .map_or(1.0, |(lo, hi)| (hi - lo).length().max(1e-6))
}

/// Sample sets of every radius of [`RADII`] around each light of `scene`, and around a point
/// light near the scene (inside its bounds' corner region) and one far from it.
fn check_scene(scene: &Scene, seen: &mut Seen) {
    let size = size_of(scene);
    let aim = scene.light_aim();
    let mut lights: Vec<Light> = scene.light_positions();
    lights.push(Light::point(aim + Vec3::new(0.31, 0.47, -0.23) * size));
    lights.push(Light::point(aim + Vec3::new(-6.0, 9.0, 4.0) * size));
    for light in lights {
        for r in RADII {
            let mut sl = SceneLight::unit(light);
            sl.radius = if light.is_directional() { r } else { r * size };
            let samples = sl.samples(SAMPLES, aim);
            assert_eq!(samples.len(), SAMPLES as usize);
            check_set(
                &format!("{} light {light} radius {}", scene.name, sl.radius),
                &scene.geometry,
                &samples,
                seen,
            );
        }
    }
}

#[test]
fn samples_of_sphere_lights_equal_their_one_light_calls() {
    let mut seen = Seen::default();
    for (rings, segments) in [(9, 13), (24, 31)] {
        let mut scene = Scene::single(
            format!("sphere {rings}x{segments}"),
            &uv_sphere_y(rings, segments, 1.5),
        )
        .unwrap();
        scene.add_unit_lights([
            Light::point(Vec3::new(3.0, 4.0, -2.0)),
            Light::directional(Vec3::new(-0.3, 1.0, 0.45)),
        ]);
        check_scene(&scene, &mut seen);
    }
    assert!(seen.shared > 0 && seen.cut > 0, "{seen:?}");
}

#[test]
fn samples_on_every_hard_preset_equal_their_one_light_calls() {
    let mut seen = Seen::default();
    for name in preset_names().iter().filter(|n| n.starts_with("hard-")) {
        check_scene(&preset(name).unwrap(), &mut seen);
    }
    assert!(
        seen.sets > 100 && seen.shared > 0 && seen.cut > 0,
        "{seen:?}"
    );
}

#[test]
fn samples_around_a_soup_equal_their_one_light_calls() {
    let mut rng = Rng::new(0x50_0b);
    let mut p = Vec::new();
    let mut t = Vec::new();
    for k in 0..400u32 {
        for _ in 0..3 {
            p.push(Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 2.0 - Vec3::ONE);
        }
        t.push([3 * k, 3 * k + 1, 3 * k + 2]);
    }
    let mut scene = Scene::single("soup", &Mesh::new(p, t).unwrap()).unwrap();
    scene.add_unit_lights([Light::point(Vec3::new(0.1, 0.2, 0.05))]);
    let mut seen = Seen::default();
    check_scene(&scene, &mut seen);
    assert!(seen.shared > 0 && seen.cut > 0, "{seen:?}");
}

/// Sample sets whose box has a corner exactly on a triangle's plane, the rest on one side: the
/// filter cannot tell (the value at that corner is 0), only the corner test can, and the sample
/// at the corner has sign 0 where the others have one sign. Vertices of a sphere in turn, with
/// the box on the outer side of the vertex's octant, so that it touches the planes of the
/// vertex's triangles there: large boxes on a coarse sphere, and boxes small enough on a fine
/// sphere that the touching triangles' neighbours are shared (then a touching triangle taken for
/// shared changes the multiplicities of the edges between them).
#[test]
fn boxes_touching_a_plane_at_a_corner_equal_one_light_calls() {
    let mut seen = Seen::default();
    for (rings, segments, step, scale) in [(7, 11, 3, 1.0f32), (40, 57, 13, 1e-3)] {
        let table = Arc::new(EdgeTable::build(&uv_sphere_y(rings, segments, 1.0)).unwrap());
        let scene = TopologyScene {
            objects: vec![SceneObject {
                name: "sphere".to_owned(),
                table: Arc::clone(&table),
                world_from_object: glam::Affine3A::IDENTITY,
            }],
        };
        for (i, v) in table.positions.iter().enumerate().step_by(step) {
            let out = v.signum() * scale;
            let samples: Vec<Light> = [0.0f32, 0.25, 0.5, 1.0]
                .iter()
                .flat_map(|&s| {
                    [
                        *v + out * Vec3::new(s, s * 0.5, s * 0.75),
                        *v + out * Vec3::new(s * 0.5, s, 0.0),
                    ]
                })
                .map(Light::point)
                .collect();
            check_set(
                &format!("sphere {rings}x{segments} vertex {i}"),
                &scene,
                &samples,
                &mut seen,
            );
        }
    }
    assert!(seen.cut > 0 && seen.shared > 0, "{seen:?}");
}

/// The samples of a light with a size are distinct points, and on a sphere their silhouettes
/// differ: a sampler that put every sample at the light's centre would give one hard shadow N
/// times.
#[test]
fn samples_are_distinct_and_their_silhouettes_differ() {
    let mut scene = Scene::single("sphere", &uv_sphere_y(24, 31, 1.0)).unwrap();
    scene.add_unit_lights([
        Light::point(Vec3::new(0.0, 4.0, 0.0)),
        Light::directional(Vec3::new(0.2, 1.0, 0.1)),
    ]);
    let aim = scene.light_aim();
    for (light, radius) in scene.light_positions().into_iter().zip([0.5, 0.1]) {
        let mut sl = SceneLight::unit(light);
        sl.radius = radius;
        let samples = sl.samples(SAMPLES, aim);
        for (i, a) in samples.iter().enumerate() {
            for b in &samples[..i] {
                assert_ne!(a, b, "{light}: two samples at one place");
            }
        }
        let singles = check_set("distinct", &scene.geometry, &samples, &mut Seen::default());
        let distinct = {
            let mut s = singles.clone();
            s.sort();
            s.dedup();
            s.len()
        };
        assert!(
            distinct > SAMPLES as usize / 2,
            "{light}: only {distinct} different silhouettes among {SAMPLES} samples"
        );
    }
}

/// One output reused across calls: sample sets of one size (the shared pass clears the previous
/// result by its compact lists), sets of another size, other modes, and a result changed by hand
/// in between (its lists are then no longer known to be complete, so it is cleared in full).
#[test]
fn a_reused_output_is_cleared_by_its_lists_or_in_full() {
    let scene = Scene::single("sphere", &uv_sphere_y(30, 41, 1.0)).unwrap();
    let aim = scene.light_aim();
    let mut cpu = CpuBackend::new();
    let cid = cpu.prepare(&scene.geometry).unwrap();
    for (name, mut simd) in simd_backends() {
        let id = simd.prepare(&scene.geometry).unwrap();
        let mut out = Multiplicities::default();
        let mut reference = Multiplicities::default();
        for (k, (x, radius, n, mode)) in [
            (3.0, 0.05, 16, Accuracy::Exact),
            (-2.0, 0.1, 16, Accuracy::Exact),
            (2.5, 0.02, 16, Accuracy::Ordered),
            (-3.0, 0.05, 16, Accuracy::Exact),
            (0.5, 0.2, 8, Accuracy::Exact),
            (1.5, 0.01, 8, Accuracy::Exact),
        ]
        .into_iter()
        .enumerate()
        {
            let mut sl = SceneLight::unit(Light::point(Vec3::new(x, 2.0, 1.0)));
            sl.radius = radius;
            let samples = sl.samples(n, aim);
            if k == 4 {
                // Garbage outside the lists.
                out.values_mut(3).iter_mut().for_each(|v| *v = 7);
            }
            simd.extract(id, &samples, mode, &mut out).unwrap();
            cpu.extract(cid, &samples, mode, &mut reference).unwrap();
            assert_eq!(out, reference, "{name}: call {k}");
            assert!(out.zero_elsewhere() && out.silhouettes_consistent());
        }
    }
}
