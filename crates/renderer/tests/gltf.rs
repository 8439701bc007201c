//! A glTF scene (objects with node transforms, KHR_lights_punctual lights, a camera) rendered
//! through `RenderScene::from_scene` and checked against the reference.
mod common;

use glam::{Affine3A, Quat, Vec3};
use shadowvol_renderer::{reference, RenderScene, Technique};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_scenes::{Camera, Effects, Object, Scene};
use shadowvol_test_support::{main, Outcome};
use std::sync::Arc;

main!(glb_scene_with_lights_and_camera_matches_the_reference);

fn glb_scene_with_lights_and_camera_matches_the_reference() -> Outcome {
    let mut r = common::renderer(128, 96, Accuracy::Exact)?;
    let cube = Arc::new(common::cuboid(Vec3::splat(-0.5), Vec3::splat(0.5)));
    let scene = Scene {
        name: "glb-test".into(),
        objects: vec![
            Object {
                name: "floor".into(),
                mesh: Arc::new(common::floor(5.0, 2)),
                transform: Affine3A::IDENTITY,
            },
            Object {
                name: "cube-a".into(),
                mesh: cube.clone(),
                transform: Affine3A::from_rotation_translation(
                    Quat::from_rotation_y(0.5),
                    Vec3::new(-1.0, 1.0, 0.0),
                ),
            },
            Object {
                name: "cube-b".into(),
                mesh: cube,
                transform: Affine3A::from_scale_rotation_translation(
                    Vec3::splat(0.7),
                    Quat::from_rotation_x(0.4),
                    Vec3::new(1.2, 1.5, 0.5),
                ),
            },
        ],
        emission: Vec::new(),
        lights: vec![
            Light::point(Vec3::new(0.5, 5.0, 2.0)),
            Light::directional(Vec3::new(-0.3, 1.0, 0.4)),
        ],
        camera: Some(Camera {
            eye: Vec3::new(3.0, 4.0, 6.0),
            target: Vec3::new(0.0, 0.5, 0.0),
            up: Vec3::Y,
            fov_y: 50f32.to_radians(),
            near: 0.05,
        }),
        effects: Effects::default(),
    };
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

    let rs = RenderScene::from_scene(&loaded).unwrap();
    assert_eq!(rs.objects.len(), 3);
    let frame = r.render(&rs).unwrap();
    assert_eq!(frame.plan.len(), 6);
    assert!(
        frame.plan.iter().all(|e| e.technique != Technique::Culled),
        "{}",
        frame.explain()
    );
    let cmp = reference::compare(&frame);
    assert!(
        cmp.reference_shadow_pixels > 300,
        "{}",
        cmp.reference_shadow_pixels
    );
    assert!(
        cmp.artifact_pixels <= 1,
        "{} artifacts\n{}",
        cmp.artifact_pixels,
        frame.explain()
    );
    Ok(())
}
