//! A wait that runs past `SHADOWVOL_GPU_TIMEOUT` is a device error naming the limit, never a
//! hang or a panic; with the limit lifted, the same backend goes on and matches `cpu`.
//!
//! Its own test binary: it sets a process-wide environment variable. Without an adapter it is
//! ignored with the reason, except under `CI=true`, where it fails.

mod common;

use shadowvol_cpu::CpuBackend;
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_robust_math::Accuracy;
use shadowvol_silhouette::{
    extract_once, gpu::TIMEOUT_ENV, BackendError, Light, Multiplicities, SilhouetteBackend,
    TopologyScene,
};
use shadowvol_test_support::shapes;
use shadowvol_test_support::{main, Outcome};
use shadowvol_wgpu_compute::WgpuOptions;

main!(gpu_wait_past_the_limit_is_a_device_error_and_the_backend_recovers);

fn gpu_wait_past_the_limit_is_a_device_error_and_the_backend_recovers() -> Outcome {
    let mut b = common::backend(
        "gpu_wait_past_the_limit_is_a_device_error_and_the_backend_recovers",
        WgpuOptions::default(),
    )?;
    let lights: Vec<Light> = (0..8)
        .map(|i| Light::point(glam::Vec3::new(3.0 + i as f32, 2.0, -1.5 * i as f32)))
        .collect();
    // Grow the scene until one extraction outlasts a 1 µs limit (the first try nearly always
    // does; the bound keeps a very fast device from looping forever).
    let mut timed_out = None;
    for segments in [256u32, 1024, 2048] {
        let mesh = shapes::uv_sphere_y(segments / 2, segments, 1.0);
        let scene = TopologyScene::single(EdgeTable::build(&mesh).unwrap());
        let id = b.prepare(&scene).unwrap();
        std::env::set_var(TIMEOUT_ENV, "0.000001");
        let mut m = Multiplicities::default();
        let r = b.extract(id, &lights, Accuracy::Exact, &mut m);
        std::env::remove_var(TIMEOUT_ENV);
        match r {
            Err(BackendError::Device { message, .. }) => {
                assert!(
                    message.contains(TIMEOUT_ENV) && message.contains("did not finish"),
                    "{message}"
                );
                timed_out = Some((scene, id));
                break;
            }
            Ok(_) => eprintln!("{segments} segments finished within 1 µs; trying a larger one"),
            Err(e) => panic!("expected a timeout, got {e}"),
        }
    }
    let (scene, id) = timed_out.expect("no extraction ever exceeded a 1 µs limit");
    // A bad limit is refused, not ignored.
    std::env::set_var(TIMEOUT_ENV, "soon");
    let r = b.extract(id, &lights, Accuracy::Exact, &mut Multiplicities::default());
    std::env::remove_var(TIMEOUT_ENV);
    assert!(
        matches!(&r, Err(BackendError::InvalidInput(m)) if m.contains(TIMEOUT_ENV)),
        "{r:?}"
    );
    // With the default limit the backend works again and agrees with cpu bit for bit.
    let (expected, _) =
        extract_once(&mut CpuBackend::new(), &scene, &lights, Accuracy::Exact).unwrap();
    let mut got = Multiplicities::default();
    b.extract(id, &lights, Accuracy::Exact, &mut got)
        .expect("the backend recovers once the limit is lifted");
    assert_eq!(got, expected);
    Ok(())
}
