//! A frame's stencil read back on a device that cannot copy a stencil aspect (OpenGL) goes
//! through a colour target, one draw per bit. Those bytes must equal the direct copy's on a
//! device that has both paths, for every pipeline, with stencil values of several bits; and
//! frames drawn on an OpenGL adapter must agree with the exact reference.

mod common;

main!(
    the_stencil_read_through_colour_equals_the_direct_copy,
    opengl_frames_agree_with_the_reference,
);

use common::{compare, cuboid, floor, scene_of, started};
use glam::{Affine3A, Vec3};
use shadowvol_renderer::{
    Camera, FrameImage, GpuPipeline, HostPipeline, MapPipeline, MapSettings, RenderDevice,
    RenderError, RenderOptions, Renderer, Scene, ShadowPipeline,
};
use shadowvol_robust_math::Light;
use shadowvol_test_support::{main, skip, Outcome};

/// Five boxes stacked under a point light over a floor: the floor under the stack lies in all
/// five shadow volumes, each box in those of the boxes above it, so the stencil counts to
/// several bits.
fn stacked_boxes() -> Scene {
    let mut objects = vec![("floor", floor(6.0, 4), Affine3A::IDENTITY)];
    for k in 0..5 {
        let y = 0.6 + 0.9 * k as f32;
        let lo = Vec3::new(-0.5, y, -0.5);
        objects.push((
            "box",
            cuboid(lo, lo + Vec3::new(1.0, 0.5, 1.0)),
            Affine3A::IDENTITY,
        ));
    }
    scene_of(
        objects,
        &[Light::point(Vec3::new(0.1, 9.0, 0.2))],
        Camera::look_at(Vec3::new(0.0, 7.0, 8.0), Vec3::new(0.0, 1.0, 0.0)),
        0.15,
    )
}

/// Every pipeline `device` runs: the host pipeline over `cpu`, the GPU pipeline where the
/// adapter supports it, shadow maps of 4096 texels.
fn pipelines(device: &RenderDevice) -> Vec<(&'static str, Box<dyn ShadowPipeline>)> {
    let mut all: Vec<(&'static str, Box<dyn ShadowPipeline>)> = vec![(
        "host",
        Box::new(HostPipeline::new(
            Box::new(shadowvol_cpu::CpuBackend::new()),
        )),
    )];
    if device.gpu_pipeline_unsupported.is_none() {
        all.push(("gpu", Box::new(GpuPipeline::new())));
    }
    all.push((
        "maps",
        Box::new(MapPipeline::new(MapSettings {
            size: Some(4096),
            ..MapSettings::default()
        })),
    ));
    all
}

/// `scene` drawn with `pipeline` on `device` at 160 x 120, read back.
fn draw(device: RenderDevice, pipeline: Box<dyn ShadowPipeline>, scene: &Scene) -> FrameImage {
    let mut r = Renderer::new(device, pipeline, RenderOptions::new(160, 120)).expect("renderer");
    r.render(scene).expect("render").image.expect("read back")
}

fn the_stencil_read_through_colour_equals_the_direct_copy() -> Outcome {
    let device = match RenderDevice::open() {
        Ok(d) => d,
        Err(e) => {
            started(Err(e))?;
            unreachable!("started turns an error into a skip or a panic")
        }
    };
    if !device.stencil_copies {
        return Err(skip(format!(
            "{} cannot copy a stencil aspect, so there is no direct copy to compare with",
            device.description
        )));
    }
    let scene = stacked_boxes();
    let mut through_colour = device.clone();
    through_colour.stencil_copies = false;
    let pairs = pipelines(&device)
        .into_iter()
        .zip(pipelines(&through_colour));
    for ((name, direct), (_, via)) in pairs {
        let a = draw(device.clone(), direct, &scene);
        let b = draw(through_colour.clone(), via, &scene);
        let values: std::collections::BTreeSet<u8> = a.stencil[0].iter().copied().collect();
        if name != "maps" {
            // Volumes count: the stack's shadow sets several bits of the stencil at once.
            assert!(
                values.iter().any(|v| v.count_ones() >= 2),
                "{name}: stencil values {values:?}"
            );
        } else {
            assert!(values.contains(&1), "{name}: stencil values {values:?}");
        }
        assert!(a.stencil == b.stencil, "{name}: stencils differ");
        assert!(a.rgba == b.rgba, "{name}: images differ");
    }
    Ok(())
}

fn opengl_frames_agree_with_the_reference() -> Outcome {
    let device = match RenderDevice::open_with(wgpu::Backends::GL) {
        Ok(d) => d,
        Err(RenderError::NoAdapter(why)) => {
            return Err(skip(format!(
                "no OpenGL adapter ({why}); install Mesa's EGL and llvmpipe (libegl-mesa0, \
                 libgl1-mesa-dri) to run this test"
            )))
        }
        Err(e) => panic!("the OpenGL device failed to open: {e}"),
    };
    let scene = stacked_boxes();
    for (name, pipeline) in pipelines(&device) {
        let mut r = Renderer::new(device.clone(), pipeline, RenderOptions::new(160, 120))
            .expect("renderer");
        let frame = r
            .render(&scene)
            .unwrap_or_else(|e| panic!("{name} on OpenGL: {e}"));
        let c = compare(&frame, &scene);
        let counts = (
            c.artifact_pixels,
            c.boundary_pixels,
            c.reference_shadow_pixels,
        );
        assert!(c.reference_shadow_pixels > 500, "{name}: {counts:?}");
        assert_eq!(
            c.artifact_pixels, 0,
            "{name} on {}: (artifacts, boundary, reference shadow) {counts:?}",
            device.description
        );
    }
    Ok(())
}
