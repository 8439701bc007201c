//! The frame plan: z-fail inside a shadow volume, z-pass outside, culling, silhouette reuse.
//! Every image is checked against the ray-traced reference.
mod common;

use glam::{Affine3A, Vec3};
use shadowvol_cpu::CpuBackend;
use shadowvol_renderer::{
    Camera, PlanPolicy, RenderOptions, Renderer, Scene, SilhouetteSource, Technique,
};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::{
    BackendError, BackendInfo, ExtractStats, Multiplicities, PreparedBytes, PreparedId,
    SilhouetteBackend, TopologyScene,
};
use shadowvol_test_support::{main, Outcome};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

main!(
    camera_inside_a_shadow_volume_gets_zfail_and_a_correct_image,
    camera_outside_gets_zpass,
    directional_light_has_no_back_cap,
    off_screen_caster_is_culled_unless_its_shadow_reaches_the_view,
    static_light_reuses_silhouettes_and_a_moving_one_re_extracts,
    moved_objects_eye_and_albedo_draw_as_a_fresh_renderer_does,
    many_objects_several_lights_match_the_reference,
    a_light_with_a_size_is_extracted_in_one_call_per_light
);

fn entry<'a>(
    frame: &'a shadowvol_renderer::Frame,
    light: usize,
    name: &str,
) -> &'a shadowvol_renderer::PlanEntry {
    frame
        .report
        .plan
        .iter()
        .find(|e| e.light == light && e.object_name == name)
        .unwrap_or_else(|| panic!("no plan entry for light {light}, {name}"))
}

fn with_policy(r: &mut Renderer, policy: PlanPolicy) {
    let mut o = r.options();
    o.policy = policy;
    r.set_options(o).unwrap();
}

/// A camera standing on the floor under the box, in its shadow, looking out sideways.
fn camera_in_shadow() -> Camera {
    let mut c = Camera::look_at(Vec3::new(0.0, 0.35, 0.0), Vec3::new(3.0, 0.0, 1.0));
    c.fov_y = 70f32.to_radians();
    c
}

fn camera_inside_a_shadow_volume_gets_zfail_and_a_correct_image() -> Outcome {
    let mut r = common::renderer(128, 128, Accuracy::Exact)?;
    let scene = common::box_on_floor(Light::point(Vec3::new(0.0, 6.0, 0.0)), camera_in_shadow());
    let frame = r.render(&scene).unwrap();
    assert_eq!(
        entry(&frame, 0, "box").technique,
        Technique::ZFail,
        "{}",
        frame.report.explain()
    );
    assert!(entry(&frame, 0, "box").back_cap);
    assert!(entry(&frame, 0, "box").cap_triangles > 0);
    let cmp = common::compare(&frame, &scene);
    assert!(
        cmp.reference_shadow_pixels > 500,
        "the camera sees shadow: {}",
        cmp.reference_shadow_pixels
    );
    assert!(
        cmp.covered_pixels - cmp.reference_shadow_pixels > 500,
        "and lit floor"
    );
    assert_eq!(cmp.artifact_pixels, 0, "{}", frame.report.explain());

    // The same view forced to z-pass is wrong: the test can tell.
    with_policy(&mut r, PlanPolicy::AlwaysZPass);
    let wrong = common::compare(&r.render(&scene).unwrap(), &scene);
    assert!(
        wrong.artifact_pixels > 1000,
        "z-pass inside the volume: {} artifacts",
        wrong.artifact_pixels
    );
    Ok(())
}

fn camera_outside_gets_zpass() -> Outcome {
    let mut r = common::renderer(128, 128, Accuracy::Exact)?;
    let scene = common::box_on_floor(
        Light::point(Vec3::new(1.5, 6.0, 1.0)),
        Camera::look_at(Vec3::new(4.0, 5.0, 7.0), Vec3::new(0.0, 0.5, 0.0)),
    );
    let frame = r.render(&scene).unwrap();
    assert!(
        frame
            .report
            .plan
            .iter()
            .all(|e| e.technique == Technique::ZPass),
        "{}",
        frame.report.explain()
    );
    let cmp = common::compare(&frame, &scene);
    assert!(cmp.reference_shadow_pixels > 200);
    assert_eq!(cmp.artifact_pixels, 0);
    // z-fail everywhere gives the same shadow.
    with_policy(&mut r, PlanPolicy::AlwaysZFail);
    let zfail = r.render(&scene).unwrap();
    let a: Vec<bool> = frame.image.as_ref().unwrap().stencil[0]
        .iter()
        .map(|&s| s != 0)
        .collect();
    let b: Vec<bool> = zfail.image.as_ref().unwrap().stencil[0]
        .iter()
        .map(|&s| s != 0)
        .collect();
    let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    assert!(
        differ <= 2,
        "z-pass and z-fail shadow masks differ in {differ} pixels"
    );
    Ok(())
}

fn directional_light_has_no_back_cap() -> Outcome {
    let mut r = common::renderer(128, 128, Accuracy::Exact)?;
    let scene = common::box_on_floor(
        Light::directional(Vec3::new(-0.3, 1.0, -0.1)),
        camera_in_shadow(),
    );
    let frame = r.render(&scene).unwrap();
    let e = entry(&frame, 0, "box");
    assert_eq!(e.technique, Technique::ZFail, "{}", frame.report.explain());
    assert!(!e.back_cap);
    let cmp = common::compare(&frame, &scene);
    assert!(cmp.reference_shadow_pixels > 300);
    assert_eq!(cmp.artifact_pixels, 0);
    Ok(())
}

fn off_screen_caster_is_culled_unless_its_shadow_reaches_the_view() -> Outcome {
    let mut r = common::renderer(128, 128, Accuracy::Exact)?;
    let light = Light::point(Vec3::new(0.0, 6.0, 0.0));
    let camera = Camera::look_at(Vec3::new(0.0, 4.0, 6.0), Vec3::new(0.0, 0.0, 0.0));
    let mut scene = common::box_on_floor(light, camera);
    // Far behind the camera, with the light in front of it: its shadow goes further away.
    add(
        &mut scene,
        "behind",
        common::cuboid(Vec3::splat(-0.5), Vec3::splat(0.5)),
        Affine3A::from_translation(Vec3::new(0.0, 3.0, 14.0)),
    );
    // Off to the side and out of view, but its shadow falls on the visible floor.
    add(
        &mut scene,
        "side",
        common::cuboid(Vec3::splat(-0.3), Vec3::splat(0.3)),
        Affine3A::from_translation(Vec3::new(-0.6, 4.5, 0.3)),
    );
    let frame = r.render(&scene).unwrap();
    let behind = entry(&frame, 0, "behind");
    assert_eq!(
        behind.technique,
        Technique::Culled,
        "{}",
        frame.report.explain()
    );
    assert_eq!(behind.silhouette, SilhouetteSource::Skipped);
    assert_ne!(
        entry(&frame, 0, "side").technique,
        Technique::Culled,
        "{}",
        frame.report.explain()
    );
    assert_ne!(entry(&frame, 0, "box").technique, Technique::Culled);
    let cmp = common::compare(&frame, &scene);
    assert_eq!(cmp.artifact_pixels, 0, "{}", frame.report.explain());
    // The side caster really is off-screen and its shadow really is visible: without it the
    // shadowed area shrinks.
    let side_ids = frame
        .image
        .as_ref()
        .unwrap()
        .ids
        .iter()
        .filter(|id| id[0] == 4)
        .count();
    assert_eq!(side_ids, 0, "the side caster must be off-screen");
    scene.geometry.objects.pop();
    let without = common::compare(&r.render(&scene).unwrap(), &scene);
    assert!(cmp.reference_shadow_pixels > without.reference_shadow_pixels + 20);
    Ok(())
}

/// A real backend (the scalar CPU one) that counts its `extract` calls.
struct Counting {
    inner: CpuBackend,
    extracts: Arc<AtomicUsize>,
    lights: Arc<AtomicUsize>,
    /// The light count of each call, in order.
    sizes: Arc<std::sync::Mutex<Vec<usize>>>,
}

impl SilhouetteBackend for Counting {
    fn info(&self) -> BackendInfo {
        self.inner.info()
    }
    fn prepare(&mut self, scene: &TopologyScene) -> Result<PreparedId, BackendError> {
        self.inner.prepare(scene)
    }
    fn extract(
        &mut self,
        id: PreparedId,
        lights: &[Light],
        mode: Accuracy,
        out: &mut Multiplicities,
    ) -> Result<ExtractStats, BackendError> {
        self.extracts.fetch_add(1, Ordering::SeqCst);
        self.lights.fetch_add(lights.len(), Ordering::SeqCst);
        self.sizes.lock().unwrap().push(lights.len());
        self.inner.extract(id, lights, mode, out)
    }
    fn prepared_bytes(&self, id: PreparedId) -> Result<PreparedBytes, BackendError> {
        self.inner.prepared_bytes(id)
    }
    fn release(&mut self, id: PreparedId) {
        self.inner.release(id);
    }
}

fn static_light_reuses_silhouettes_and_a_moving_one_re_extracts() -> Outcome {
    let extracts = Arc::new(AtomicUsize::new(0));
    let lights = Arc::new(AtomicUsize::new(0));
    let backend = Counting {
        inner: CpuBackend::new(),
        extracts: extracts.clone(),
        lights: lights.clone(),
        sizes: Arc::default(),
    };
    // Same policy as common::renderer.
    let mut r = common::started(Renderer::host(
        Box::new(backend),
        RenderOptions::new(96, 96),
    ))?;
    let camera = Camera::look_at(Vec3::new(4.0, 5.0, 7.0), Vec3::new(0.0, 0.5, 0.0));
    let mut scene = common::box_on_floor(Light::point(Vec3::new(1.5, 6.0, 1.0)), camera);
    scene.add_unit_lights([Light::directional(Vec3::new(-0.5, 1.0, 0.3))]);
    let first = r.render(&scene).unwrap();
    assert!(first
        .report
        .plan
        .iter()
        .all(|e| e.silhouette == SilhouetteSource::Extracted));
    let (calls, n) = (
        extracts.load(Ordering::SeqCst),
        lights.load(Ordering::SeqCst),
    );
    assert_eq!((calls, n), (2, 4), "one call per object, both lights");

    // Nothing moved: everything is reused, the backend is not called, the image is the same.
    let second = r.render(&scene).unwrap();
    assert!(
        second
            .report
            .plan
            .iter()
            .all(|e| e.silhouette == SilhouetteSource::Reused),
        "{}",
        second.report.explain()
    );
    assert_eq!(extracts.load(Ordering::SeqCst), 2);
    assert_eq!(
        second.image.as_ref().unwrap().rgba,
        first.image.as_ref().unwrap().rgba
    );

    // Light 0 moves: only light 0 is re-extracted, for both objects.
    scene.lights[0].light = Light::point(Vec3::new(-1.0, 6.0, 1.5));
    let third = r.render(&scene).unwrap();
    for e in &third.report.plan {
        let expected = if e.light == 0 {
            SilhouetteSource::Extracted
        } else {
            SilhouetteSource::Reused
        };
        assert_eq!(e.silhouette, expected, "{e}");
    }
    // No object moved: one call over the whole scene, for light 0 only.
    assert_eq!(extracts.load(Ordering::SeqCst), 3, "one batched call");
    assert_eq!(lights.load(Ordering::SeqCst), 5, "for light 0 only");
    assert_eq!(common::compare(&third, &scene).artifact_pixels, 0);

    // The box moves: only the box is re-extracted, for both lights.
    scene.geometry.objects[1].world_from_object =
        Affine3A::from_translation(Vec3::new(0.7, 0.8, 0.0));
    let fourth = r.render(&scene).unwrap();
    for e in &fourth.report.plan {
        let expected = if e.object_name == "box" {
            SilhouetteSource::Extracted
        } else {
            SilhouetteSource::Reused
        };
        assert_eq!(e.silhouette, expected, "{e}");
    }
    assert_eq!(extracts.load(Ordering::SeqCst), 4, "one call for the box");
    assert_eq!(lights.load(Ordering::SeqCst), 7, "with both lights");
    assert_eq!(common::compare(&fourth, &scene).artifact_pixels, 0);
    let mut fresh =
        Renderer::host(Box::new(CpuBackend::new()), RenderOptions::new(96, 96)).unwrap();
    assert_eq!(fourth.image, fresh.render(&scene).unwrap().image);

    // Both lights move, nothing else: one batched call again, and the image equals a fresh
    // renderer's (the batched multiplicities are the per-object ones).
    scene.lights[0].light = Light::point(Vec3::new(0.5, 5.0, -1.0));
    scene.lights[1].light = Light::directional(Vec3::new(0.5, 1.0, -0.2));
    let moved = r.render(&scene).unwrap();
    assert_eq!(extracts.load(Ordering::SeqCst), 5);
    assert_eq!(lights.load(Ordering::SeqCst), 9);
    let mut fresh =
        Renderer::host(Box::new(CpuBackend::new()), RenderOptions::new(96, 96)).unwrap();
    let fresh = fresh.render(&scene).unwrap();
    assert_eq!(moved.image, fresh.image);

    // Switching the mode invalidates everything.
    let mut o = r.options();
    o.mode = Accuracy::Robust;
    r.set_options(o).unwrap();
    let fifth = r.render(&scene).unwrap();
    assert!(fifth
        .report
        .plan
        .iter()
        .all(|e| e.silhouette == SilhouetteSource::Extracted));
    Ok(())
}

/// The host pipeline keeps its surface vertices between frames: after each change (an object
/// moved, the eye moved, a receiver's colour, a receiver added), the kept renderer's image,
/// ids and stencils equal those of a renderer that draws the scene for the first time.
fn moved_objects_eye_and_albedo_draw_as_a_fresh_renderer_does() -> Outcome {
    let opts = RenderOptions::new(96, 96);
    let mut kept = common::renderer_with(opts)?;
    let camera = Camera::look_at(Vec3::new(4.0, 5.0, 7.0), Vec3::new(0.0, 0.5, 0.0));
    let mut scene = common::box_on_floor(Light::point(Vec3::new(1.5, 6.0, 1.0)), camera);
    let mut step = |scene: &Scene, what: &str| {
        let image = kept.render(scene).unwrap().image;
        let mut fresh = common::renderer_with(opts).unwrap();
        let expected = fresh.render(scene).unwrap().image;
        assert!(
            image == expected,
            "after {what}, the image differs from a fresh renderer's"
        );
    };
    step(&scene, "the first frame");
    step(&scene, "a still frame");
    scene.geometry.objects[1].world_from_object =
        Affine3A::from_translation(Vec3::new(0.7, 0.8, -0.4));
    step(&scene, "the box moved");
    scene.camera = Some(Camera::look_at(
        Vec3::new(-3.0, 4.0, 6.0),
        Vec3::new(0.0, 0.5, 0.0),
    ));
    step(&scene, "the eye moved");
    scene.receivers.push(shadowvol_scenes::Receiver::plane(
        "wall",
        Vec3::new(0.0, 1.0, -3.0),
        Vec3::Z,
        3.0,
    ));
    step(&scene, "a receiver was added");
    scene.receivers[0].albedo = [0.9, 0.2, 0.1];
    step(&scene, "the receiver's colour changed");
    scene.geometry.objects[0].world_from_object = Affine3A::from_translation(Vec3::Y * -0.1);
    step(&scene, "the floor moved");
    Ok(())
}

fn many_objects_several_lights_match_the_reference() -> Outcome {
    let mut r = common::renderer(128, 128, Accuracy::Exact)?;
    let mut scene = common::scene_of(
        vec![("floor", common::floor(6.0, 6), Affine3A::IDENTITY)],
        &[
            Light::point(Vec3::new(2.0, 7.0, 1.0)),
            Light::point(Vec3::new(-3.0, 5.0, -1.0)),
            Light::directional(Vec3::new(0.4, 1.0, -0.3)),
        ],
        Camera::look_at(Vec3::new(5.0, 7.0, 8.0), Vec3::ZERO),
        0.1,
    );
    let cube = scene
        .add_mesh(
            "cube",
            &common::cuboid(Vec3::splat(-0.35), Vec3::splat(0.35)),
        )
        .unwrap();
    for i in 0..3 {
        for j in 0..3 {
            scene.add_object(
                format!("cube{i}{j}"),
                cube.clone(),
                Affine3A::from_rotation_translation(
                    glam::Quat::from_rotation_y(0.3 * (i + j) as f32),
                    Vec3::new(
                        i as f32 * 1.6 - 1.6,
                        0.6 + 0.3 * j as f32,
                        j as f32 * 1.6 - 1.6,
                    ),
                ),
            );
        }
    }
    for policy in [PlanPolicy::Auto, PlanPolicy::AlwaysZFail] {
        with_policy(&mut r, policy);
        let frame = r.render(&scene).unwrap();
        assert_eq!(frame.report.plan.len(), 3 * 10);
        let cmp = common::compare(&frame, &scene);
        assert!(
            cmp.reference_shadow_pixels > 1000,
            "{}",
            cmp.reference_shadow_pixels
        );
        assert!(
            cmp.artifact_pixels <= 2,
            "{policy:?}: {} artifacts",
            cmp.artifact_pixels
        );
    }
    Ok(())
}

/// Adds `mesh` to `scene` as an object of its own.
fn add(scene: &mut Scene, name: &str, mesh: shadowvol_mesh_topology::Mesh, t: Affine3A) {
    let table = scene.add_mesh(name, &mesh).unwrap();
    scene.add_object(name, table, t);
}

/// The host pipeline gives a backend the samples of one light with a size in one `extract`
/// call of their own (so that it can share the signs of triangles whose plane misses their
/// box), and the other lights together, as before; the light itself, drawn after its samples,
/// is never extracted.
fn a_light_with_a_size_is_extracted_in_one_call_per_light() -> Outcome {
    let sizes: Arc<std::sync::Mutex<Vec<usize>>> = Arc::default();
    let backend = Counting {
        inner: CpuBackend::new(),
        extracts: Arc::default(),
        lights: Arc::default(),
        sizes: sizes.clone(),
    };
    let mut opts = RenderOptions::new(64, 64);
    opts.light_samples = Some(8);
    let mut r = common::started(Renderer::host(Box::new(backend), opts))?;
    let camera = Camera::look_at(Vec3::new(4.0, 5.0, 7.0), Vec3::new(0.0, 0.5, 0.0));
    let mut scene = common::box_on_floor(Light::point(Vec3::new(1.5, 6.0, 1.0)), camera);
    scene.add_unit_lights([
        Light::directional(Vec3::new(-0.5, 1.0, 0.3)),
        Light::point(Vec3::new(-2.0, 5.0, 0.0)),
    ]);
    scene.lights[0].radius = 0.3;
    r.render(&scene).unwrap();
    // Two objects, each on its own (the first frame): the samples, then the two others.
    assert_eq!(*sizes.lock().unwrap(), [8, 2, 8, 2]);
    // The light with a size moves, nothing else: one call over the whole scene, its samples.
    scene.lights[0].light = Light::point(Vec3::new(-1.0, 6.0, 1.5));
    r.render(&scene).unwrap();
    assert_eq!(*sizes.lock().unwrap(), [8, 2, 8, 2, 8]);
    Ok(())
}
