//! A wait limit the device cannot meet (`SHADOWVOL_GPU_TIMEOUT` = 1 µs) turns into a clear
//! `BackendError::Device` naming the variable: no panic, no hang. While the late work is still
//! running the backend refuses new work; once it has finished (with a normal limit) the backend
//! recovers and gives the `cpu` result; dropping a backend whose work is still pending returns
//! at once (the device is leaked, not destroyed under the running work).
//!
//! The environment is process-wide, so this file is its own test binary with a single test.

mod common;

use shadowvol_cpu::CpuBackend;
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_silhouette::{
    extract_once, gpu::TIMEOUT_ENV, invariant, Accuracy, BackendError, Light, Multiplicities,
    PreparedId, SilhouetteBackend, TopologyScene,
};
use shadowvol_test_support::shapes::uv_sphere_y;
use shadowvol_test_support::{main, Outcome};
use shadowvol_vulkan_geometry::{VulkanBackend, VulkanOptions};
use std::time::{Duration, Instant};

main!(tiny_wait_limit_times_out_refuses_work_then_recovers);

const TINY: &str = "0.000001";

fn lights() -> Vec<Light> {
    vec![
        Light::point(glam::Vec3::new(3.0, 2.0, 1.0)),
        Light::point(glam::Vec3::new(-2.0, 3.0, 2.5)),
        Light::point(glam::Vec3::new(0.5, -3.0, -2.0)),
        Light::directional(glam::Vec3::new(1.0, 2.0, 3.0)),
    ]
}

fn sphere(segments: u32) -> TopologyScene {
    TopologyScene::single(EdgeTable::build(&uv_sphere_y(segments / 2, segments, 1.0)).unwrap())
}

/// True for the timeout error this test expects: a device error naming the variable.
fn is_timeout_error(e: &BackendError) -> bool {
    matches!(e, BackendError::Device { message, .. } if message.contains(TIMEOUT_ENV))
}

/// Extracts scenes of growing size under the tiny limit until one times out. Returns the backend
/// and scene with the pending work, or fails when even the largest finishes in time.
fn provoke_timeout(vk: &mut VulkanBackend) -> (PreparedId, TopologyScene) {
    std::env::set_var(TIMEOUT_ENV, TINY);
    for segments in [64, 128, 256, 512] {
        let scene = sphere(segments);
        let id = vk.prepare(&scene).unwrap();
        let mut m = Multiplicities::default();
        let t = Instant::now();
        match vk.extract(id, &lights(), Accuracy::Exact, &mut m) {
            Err(e) => {
                assert!(
                    is_timeout_error(&e),
                    "expected a Device error naming {TIMEOUT_ENV}, got: {e}"
                );
                let BackendError::Device { message, .. } = &e else {
                    unreachable!()
                };
                assert!(
                    message.contains("did not finish within"),
                    "the message should say the device did not finish in time: {message}"
                );
                assert!(
                    t.elapsed() < Duration::from_secs(5),
                    "a 1 µs limit must not wait for seconds ({:?})",
                    t.elapsed()
                );
                eprintln!("{segments} segments timed out: {e}");
                return (id, scene);
            }
            Ok(_) => {
                eprintln!("{segments} segments finished within {TINY} s; trying a larger one");
                vk.release(id);
            }
        }
    }
    panic!("no extraction timed out under {TIMEOUT_ENV}={TINY}: the limit is not applied");
}

fn tiny_wait_limit_times_out_refuses_work_then_recovers() -> Outcome {
    std::env::remove_var(TIMEOUT_ENV);
    let mut vk = common::backend(VulkanOptions::from_env())?;
    let (id, scene) = provoke_timeout(&mut vk);

    // The submission is (almost certainly) still running: new work is refused with a clear
    // error, or, if the late work did finish, the new submission times out the same way.
    let mut m = Multiplicities::default();
    let e = vk
        .extract(id, &lights(), Accuracy::Exact, &mut m)
        .expect_err("a backend with pending work must refuse (or time out on) new work");
    assert!(is_timeout_error(&e), "{e}");
    eprintln!("second extract: {e}");

    // An invalid limit is an input error, not a device error.
    std::env::set_var(TIMEOUT_ENV, "soon");
    let e = vk
        .extract(id, &lights(), Accuracy::Exact, &mut m)
        .expect_err("an invalid limit must be refused");
    assert!(
        matches!(&e, BackendError::InvalidInput(msg) if msg.contains(TIMEOUT_ENV)),
        "{e}"
    );

    // Releasing the scene the late work still reads defers freeing its buffers until that work
    // has finished (under validation, freeing them now would be reported as a buffer in use).
    std::env::set_var(TIMEOUT_ENV, TINY);
    vk.release(id);

    // With a normal limit the late work is waited for, the backend recovers (and frees the
    // released scene), and the result is the cpu backend's, in every mode.
    std::env::remove_var(TIMEOUT_ENV);
    let id = vk.prepare(&scene).unwrap();
    let mut cpu = CpuBackend::new();
    for mode in Accuracy::ALL {
        let stats = vk
            .extract(id, &lights(), mode, &mut m)
            .unwrap_or_else(|e| panic!("{mode} after recovery: {e}"));
        let (want, _) = extract_once(&mut cpu, &scene, &lights(), mode).unwrap();
        if mode == Accuracy::Exact {
            assert_eq!(
                invariant::first_difference(&m, &want),
                None,
                "after recovery vulkan differs from cpu (light, edge, vulkan, cpu)"
            );
        }
        if mode.is_consistent() {
            for l in 0..lights().len() {
                assert_eq!(invariant::open_vertices_scene(&scene, &m, l), 0, "{mode}");
            }
        }
        assert!(stats.compute > Duration::ZERO);
    }
    vk.release(id);
    let messages = vk.validation_messages();
    assert!(messages.is_empty(), "validation:\n{}", messages.join("\n"));

    // Timing of one full extraction, to let leaked work finish before the process exits.
    let (full_scene_id, full) = {
        let scene = sphere(512);
        (vk.prepare(&scene).unwrap(), scene)
    };
    let t = Instant::now();
    vk.extract(full_scene_id, &lights(), Accuracy::Exact, &mut m)
        .unwrap();
    let full_time = t.elapsed();
    vk.release(full_scene_id);
    drop(full);

    // Dropping with work still pending does not hang: it waits the (tiny) limit and leaks.
    let (_id, _scene) = provoke_timeout(&mut vk);
    let t = Instant::now();
    drop(vk);
    assert!(
        t.elapsed() < Duration::from_secs(5),
        "drop with pending work took {:?}",
        t.elapsed()
    );
    std::env::remove_var(TIMEOUT_ENV);
    // The leaked device still runs the late work on the driver's threads; let it finish before
    // the process exits (exit-time destructors of the driver must not race it).
    std::thread::sleep(full_time + Duration::from_millis(200));
    Ok(())
}
