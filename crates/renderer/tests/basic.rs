//! Basic rendering against the ray-traced reference.
mod common;

use glam::Vec3;
use shadowvol_renderer::{Camera, PlanPolicy, Technique};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_test_support::{main, Outcome};

main!(
    box_on_floor_matches_reference_zpass_and_zfail,
    vertex_buffers_beyond_the_device_are_drawn_in_parts_or_refused
);

fn box_on_floor_matches_reference_zpass_and_zfail() -> Outcome {
    let mut r = common::renderer(128, 128, Accuracy::Exact)?;
    let scene = common::box_on_floor(
        Light::point(Vec3::new(1.5, 6.0, 1.0)),
        Camera::look_at(Vec3::new(4.0, 5.0, 7.0), Vec3::new(0.0, 0.5, 0.0)),
    );
    for policy in [
        PlanPolicy::Auto,
        PlanPolicy::AlwaysZFail,
        PlanPolicy::AlwaysZPass,
    ] {
        let mut o = r.options();
        o.policy = policy;
        r.set_options(o).unwrap();
        let frame = r.render(&scene).unwrap();
        let cmp = common::compare(&frame, &scene);
        println!("{policy:?}: {}", frame.report.explain());
        println!(
            "artifacts {} differing {} shadow {} ref shadow {} covered {}",
            cmp.artifact_pixels,
            cmp.differing_pixels,
            cmp.shadow_pixels,
            cmp.reference_shadow_pixels,
            cmp.covered_pixels
        );
        frame
            .save_png(format!("/tmp/sv_box_{policy:?}.png"))
            .unwrap();
        shadowvol_reference::diff_image(&common::shot(&frame, &scene), &cmp)
            .save(format!("/tmp/sv_box_{policy:?}_diff.png"))
            .unwrap();
        assert!(
            cmp.reference_shadow_pixels > 200,
            "the box casts a visible shadow"
        );
        assert_eq!(cmp.artifact_pixels, 0, "{policy:?}");
        // The count without the reference, each pixel's point dropped in turn, and each
        // triangle computed alone, are the comparison's, bit for bit.
        let shot = common::shot(&frame, &scene);
        assert_eq!(shadowvol_reference::shadow_pixels(&shot), cmp.shadow_pixels);
        for (i, tris) in shot.triangles().iter().enumerate() {
            for (t, tri) in tris.iter().enumerate() {
                assert_eq!(
                    shot.triangle(i, t).as_ref(),
                    Some(tri),
                    "surface {i} triangle {t}"
                );
            }
        }
        if policy == PlanPolicy::Auto {
            assert!(frame
                .report
                .plan
                .iter()
                .all(|e| e.technique == Technique::ZPass));
        }
    }
    Ok(())
}

/// On a device whose buffers are smaller than a scene's surface vertices, the host pipeline
/// draws them from several buffers (the same image as from one), and the map pipeline refuses
/// the frame with the numbers. Both used to panic inside wgpu, which could not map the buffer:
/// `render bunny-10m --pipeline host` on lavapipe, 2.9 GB of vertices.
fn vertex_buffers_beyond_the_device_are_drawn_in_parts_or_refused() -> Outcome {
    use shadowvol_renderer::{
        HostPipeline, MapPipeline, MapSettings, RenderDevice, RenderError, RenderOptions, Renderer,
        ShadowPipeline,
    };
    let adapter = RenderDevice::headless_adapter().map_err(shadowvol_test_support::skip)?;
    // 64 KiB buffers: the 96 x 80 image's targets and staging fit (its ids, 8 bytes a pixel,
    // are the largest: 61,440 bytes); a scene of 10,000 triangles (168 bytes of surface
    // vertices each) takes 26 buffers.
    const CAP: u64 = 64 << 10;
    let open = |cap: Option<u64>| {
        let (features, mut limits) = RenderDevice::requirements(&adapter);
        if let Some(cap) = cap {
            limits.max_buffer_size = cap;
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("small buffers"),
            required_features: features,
            required_limits: limits,
            ..Default::default()
        }))
        .expect("a device with smaller limits than the adapter's");
        RenderDevice::on_device(adapter.clone(), device, queue)
    };
    let scene = shadowvol_scenes::preset("sphere-10k").expect("sphere-10k");
    let host = || -> Box<dyn ShadowPipeline> {
        Box::new(HostPipeline::new(
            Box::new(shadowvol_cpu::CpuBackend::new()),
        ))
    };
    let image = |cap: Option<u64>| {
        let mut r = Renderer::new(open(cap), host(), RenderOptions::new(96, 80)).unwrap();
        let frame = r
            .render(&scene)
            .expect("the host pipeline draws in several buffers");
        let i = frame.read_image().unwrap();
        (i.rgba.clone(), i.ids.clone())
    };
    let (whole, chunked) = (image(None), image(Some(CAP)));
    assert!(whole.1.iter().any(|id| id[0] != 0), "the sphere is in view");
    assert!(
        whole == chunked,
        "drawn from 64 KiB buffers, the image differs"
    );
    let maps = Box::new(MapPipeline::new(MapSettings::default()));
    let mut r = Renderer::new(open(Some(CAP)), maps, RenderOptions::new(96, 80)).unwrap();
    match r.render(&scene) {
        Err(RenderError::TooLarge(m)) => {
            assert!(
                m.contains("max_buffer_size") && m.contains(&CAP.to_string()),
                "{m}"
            );
        }
        Err(e) => panic!("maps: expected the buffer-size error, got {e}"),
        Ok(_) => panic!("maps: a frame whose vertices exceed {CAP} bytes was drawn"),
    }
    Ok(())
}
