//! Shared helpers for the renderer's integration tests.
#![allow(dead_code)]

use glam::{Affine3A, Vec3};
use shadowvol_mesh_topology::Mesh;
use shadowvol_reference::Comparison;
use shadowvol_renderer::{Camera, Frame, RenderError, RenderOptions, Renderer, Scene};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_test_support::Skip;

/// A renderer on the `cpu` backend, or a visible skip without a GPU adapter (see [`started`]).
pub fn renderer(width: u32, height: u32, mode: Accuracy) -> Result<Renderer, Skip> {
    let mut opts = RenderOptions::new(width, height);
    opts.mode = mode;
    renderer_with(opts)
}

/// A renderer on the `cpu` backend with `opts`, or a skip as [`renderer`].
pub fn renderer_with(opts: RenderOptions) -> Result<Renderer, Skip> {
    started(Renderer::host(
        Box::new(shadowvol_cpu::CpuBackend::new()),
        opts,
    ))
}

/// A renderer on the GPU pipeline with `opts`, or a visible skip without an adapter or when
/// the adapter cannot run the GPU pipeline (a failure under CI).
pub fn gpu_renderer(opts: RenderOptions) -> Result<Renderer, Skip> {
    match Renderer::gpu(opts) {
        Err(RenderError::Unsupported(why)) => Err(shadowvol_test_support::skip(format!(
            "the adapter cannot run the GPU pipeline: {why}"
        ))),
        other => started(other),
    }
}

/// The reference's comparison of `frame`, a render of `scene`.
pub fn compare(frame: &Frame, scene: &Scene) -> Comparison {
    shadowvol_reference::compare(&shot(frame, scene))
}

/// `frame`, a render of `scene`, as the reference reads it.
///
/// # Panics
/// Panics if the frame was not read back.
pub fn shot<'a>(frame: &'a Frame, scene: &'a Scene) -> shadowvol_reference::Shot<'a> {
    shot::shot(frame, scene).expect("a frame read back")
}

#[path = "../../../cli/src/shot.rs"]
mod shot;

/// A scene of `objects` (name, mesh, world transform; each its own table), lit by unit
/// `lights`, seen from `camera`, with ambient `ambient`.
pub fn scene_of(
    objects: Vec<(&str, Mesh, Affine3A)>,
    lights: &[Light],
    camera: Camera,
    ambient: f32,
) -> Scene {
    let mut scene = Scene::new("test");
    for (name, mesh, t) in objects {
        let table = scene.add_mesh(name, &mesh).expect("valid mesh");
        scene.add_object(name, table, t);
    }
    scene.add_unit_lights(lights.iter().copied());
    scene.camera = Some(camera);
    scene.effects.ambient = ambient;
    scene
}

/// The renderer `result`, or a visible skip ([`shadowvol_test_support::skip`]: `ignored (no GPU
/// adapter ...)`, a failure under CI) on [`RenderError::NoAdapter`]. Any other error fails the
/// test.
pub fn started(result: Result<Renderer, RenderError>) -> Result<Renderer, Skip> {
    match result {
        Ok(r) => Ok(r),
        Err(RenderError::NoAdapter(why)) => Err(shadowvol_test_support::skip(format!(
            "no GPU adapter ({why}); install Mesa lavapipe to run this test"
        ))),
        Err(e) => panic!("renderer failed to start: {e}"),
    }
}

/// An axis-aligned box `lo..hi` as 12 triangles (closed, outward winding).
pub fn cuboid(lo: Vec3, hi: Vec3) -> Mesh {
    shadowvol_test_support::shapes::cuboid(lo, hi)
}

/// A square floor at `y = 0`, half-size `s`, split into `n × n` cells.
pub fn floor(s: f32, n: u32) -> Mesh {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let x = -s + 2.0 * s * i as f32 / n as f32;
            let z = -s + 2.0 * s * j as f32 / n as f32;
            positions.push(Vec3::new(x, 0.0, z));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            let b = a + 1;
            let c = a + n + 1;
            let d = c + 1;
            triangles.push([a, c, b]);
            triangles.push([b, c, d]);
        }
    }
    Mesh::new(positions, triangles).expect("valid floor")
}

/// A floor and a box standing above it, one light.
pub fn box_on_floor(light: Light, camera: Camera) -> Scene {
    scene_of(
        vec![
            ("floor", floor(6.0, 4), Affine3A::IDENTITY),
            (
                "box",
                cuboid(Vec3::new(-0.5, 0.0, -0.5), Vec3::new(0.5, 1.0, 0.5)),
                Affine3A::from_translation(Vec3::new(0.0, 0.8, 0.0)),
            ),
        ],
        &[light],
        camera,
        0.15,
    )
}
