//! A glTF scene (objects with node transforms, KHR_lights_punctual lights, a camera) rendered
//! as loaded (the renderer borrows the scene model) and checked against the reference.
mod common;

use glam::{Affine3A, Quat, Vec3};
use shadowvol_renderer::Technique;
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_scenes::{Camera, Effects, Scene};
use shadowvol_test_support::{main, Outcome};

main!(glb_scene_with_lights_and_camera_matches_the_reference);

fn glb_scene_with_lights_and_camera_matches_the_reference() -> Outcome {
    let mut r = common::renderer(128, 96, Accuracy::Exact)?;
    let mut scene = common::scene_of(
        vec![("floor", common::floor(5.0, 2), Affine3A::IDENTITY)],
        &[
            Light::point(Vec3::new(0.5, 5.0, 2.0)),
            Light::directional(Vec3::new(-0.3, 1.0, 0.4)),
        ],
        Camera {
            eye: Vec3::new(3.0, 4.0, 6.0),
            target: Vec3::new(0.0, 0.5, 0.0),
            up: Vec3::Y,
            fov_y: 50f32.to_radians(),
            near: 0.05,
        },
        Effects::default().ambient,
    );
    let cube = scene
        .add_mesh("cube", &common::cuboid(Vec3::splat(-0.5), Vec3::splat(0.5)))
        .unwrap();
    scene.add_object(
        "cube-a",
        cube.clone(),
        Affine3A::from_rotation_translation(Quat::from_rotation_y(0.5), Vec3::new(-1.0, 1.0, 0.0)),
    );
    scene.add_object(
        "cube-b",
        cube,
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(0.7),
            Quat::from_rotation_x(0.4),
            Vec3::new(1.2, 1.5, 0.5),
        ),
    );
    let dir = std::env::temp_dir().join(format!("shadowvol-renderer-gltf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("scene.glb");
    shadowvol_scenes::export_glb(&scene, &path).unwrap();
    let loaded = Scene::load(&path).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(
        loaded.lights.len(),
        2,
        "KHR_lights_punctual lights survive the round trip"
    );
    assert!(
        loaded.camera.is_some(),
        "the camera survives the round trip"
    );

    assert_eq!(loaded.surfaces().len(), 3);
    let frame = r.render(&loaded).unwrap();
    assert_eq!(frame.report.plan.len(), 6);
    assert!(
        frame
            .report
            .plan
            .iter()
            .all(|e| e.technique != Technique::Culled),
        "{}",
        frame.report.explain()
    );
    let cmp = common::compare(&frame, &loaded);
    assert!(
        cmp.reference_shadow_pixels > 300,
        "{}",
        cmp.reference_shadow_pixels
    );
    assert!(
        cmp.artifact_pixels <= 1,
        "{} artifacts\n{}",
        cmp.artifact_pixels,
        frame.report.explain()
    );
    Ok(())
}
