//! The README's example: a box on a floor under a point light, rendered with stencil shadow
//! volumes, compared with the ray-traced reference, plan printed.
//!
//! ```text
//! cargo run -p shadowvol-renderer --example cube_on_floor -- out.png
//! ```

use glam::{Affine3A, Vec3};
use shadowvol_mesh_topology::Mesh;
use shadowvol_renderer::{Camera, RenderOptions, Renderer, Scene};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_scenes::Receiver;

#[path = "../../cli/src/shot.rs"]
mod shot;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // No `error: XDG_RUNTIME_DIR ...` line from Mesa on a machine without a display.
    shadowvol_silhouette::gpu::quiet_without_display();
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "cube_on_floor.png".to_owned());
    // A unit cube (closed, 12 triangles) and a floor quad.
    let cube = Mesh::new(
        (0..8u32)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect(),
        vec![
            [0, 2, 3],
            [0, 3, 1],
            [4, 5, 7],
            [4, 7, 6],
            [0, 1, 5],
            [0, 5, 4],
            [2, 6, 7],
            [2, 7, 3],
            [0, 4, 6],
            [0, 6, 2],
            [1, 3, 7],
            [1, 7, 5],
        ],
    )?;
    // The scene model: the cube's edge table placed by a transform, a floor that receives
    // shadows but casts none, two unit lights, a camera.
    let mut scene = Scene::new("cube on floor");
    let table = scene.add_mesh("cube", &cube)?;
    scene.add_object(
        "cube",
        table,
        Affine3A::from_translation(Vec3::new(-0.5, 0.7, -0.5)),
    );
    scene
        .receivers
        .push(Receiver::plane("floor", Vec3::ZERO, Vec3::Y, 6.0));
    scene.add_unit_lights([
        Light::point(Vec3::new(1.5, 6.0, 1.0)),
        Light::directional(Vec3::new(-1.0, 2.0, 0.5)),
    ]);
    scene.camera = Some(Camera::look_at(
        Vec3::new(4.0, 5.0, 7.0),
        Vec3::new(0.0, 0.5, 0.0),
    ));
    scene.effects.ambient = 0.15;
    let mut options = RenderOptions::new(256, 256);
    options.mode = Accuracy::Exact;
    // The host pipeline over the scalar CPU backend (`Renderer::gpu` runs no backend at all).
    let backend = Box::new(shadowvol_cpu::CpuBackend::new());
    let mut renderer = Renderer::host(backend, options)?;
    let frame = renderer.render(&scene)?;
    frame.save_png(&out)?;
    print!("{}", frame.report.explain());
    let cmp = shadowvol_reference::compare(&shot::shot(&frame, &scene)?);
    println!(
        "{out}: {} shadow pixels, {} artifact pixels against the ray-traced reference",
        cmp.shadow_pixels, cmp.artifact_pixels
    );
    // A second frame with nothing moved reuses every silhouette.
    let again = renderer.render(&scene)?;
    println!(
        "second frame: silhouette {:.3} ms (reused)",
        again.report.timings.silhouette_ms.unwrap_or_default()
    );
    Ok(())
}
