//! A frame whose readback outlasts `SHADOWVOL_GPU_TIMEOUT` is a `RenderError::Device` naming
//! the limit, not a hang; with the limit lifted the same renderer renders again.
//!
//! Its own test binary: it sets a process-wide environment variable.
mod common;

use glam::Vec3;
use shadowvol_renderer::RenderError;
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::gpu::TIMEOUT_ENV;
use shadowvol_test_support::{main, Outcome};

main!(frame_past_the_wait_limit_is_a_device_error_and_the_renderer_recovers);

fn frame_past_the_wait_limit_is_a_device_error_and_the_renderer_recovers() -> Outcome {
    let mut r = common::renderer(512, 512, Accuracy::Exact)?;
    let scene = common::box_on_floor(
        Light::point(Vec3::new(0.5, 6.0, 0.3)),
        shadowvol_renderer::Camera::look_at(Vec3::new(4.0, 3.0, 5.0), Vec3::ZERO),
    );
    // Warm up (pipelines, prepared silhouettes), so the limited frame is only GPU work.
    r.render(&scene).unwrap();
    let mut saw_timeout = false;
    for _ in 0..5 {
        std::env::set_var(TIMEOUT_ENV, "0.000001");
        let result = r.render(&scene);
        std::env::remove_var(TIMEOUT_ENV);
        match result {
            Err(RenderError::Device(m)) => {
                assert!(m.contains(TIMEOUT_ENV), "{m}");
                saw_timeout = true;
                break;
            }
            Ok(_) => eprintln!("a 512x512 frame finished within 1 µs; trying again"),
            Err(e) => panic!("expected a timeout, got {e}"),
        }
    }
    assert!(saw_timeout, "no frame ever exceeded a 1 µs wait limit");
    let frame = r
        .render(&scene)
        .expect("renders again with the default limit");
    let cmp = common::compare(&frame, &scene);
    assert_eq!(cmp.artifact_pixels, 0, "{}", frame.report.explain());
    Ok(())
}
