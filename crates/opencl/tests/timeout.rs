//! A device that does not finish in time: with a tiny `SHADOWVOL_GPU_TIMEOUT`, an extraction
//! that PoCL cannot finish within it is a `BackendError::Device` naming the variable (no panic,
//! no hang), the next extraction on the same backend is a clear error while the abandoned kernel
//! is still running, and with the limit back to its default the backend recovers, with results
//! identical to the `cpu` backend's. Dropping a backend with unfinished work does not hang.
//!
//! The limit is read from the environment at every extraction, and environment variables are
//! process-wide, so this is its own test binary with a single test that sets the variable only
//! between calls (no extraction is running on the test's side then; PoCL's worker threads
//! do not read the environment while they run a kernel).
//!
//! Without an OpenCL platform the test is ignored with the reason, except under `CI=true`, where
//! it fails (`shadowvol_test_support::skip`).

use shadowvol_cpu::CpuBackend;
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_opencl::OpenClBackend;
use shadowvol_silhouette::{
    extract_once, gpu::TIMEOUT_ENV, Accuracy, BackendError, Light, Multiplicities, PreparedId,
    SilhouetteBackend, TopologyScene,
};
use shadowvol_test_support::shapes;
use shadowvol_test_support::{main, Outcome};
use std::time::{Duration, Instant};

main!(a_device_that_does_not_finish_in_time_is_an_error_and_the_backend_recovers);

/// The attempts: (rings of the UV sphere, limit in seconds). The first limit is far below what
/// the kernel needs on 1.6·10^5 triangles with eight lights on PoCL (tens of milliseconds) and
/// well above what the light and counter writes before it need; later attempts grow the sphere
/// (up to 2.6·10^6 triangles) and then shrink the limit for fast GPUs, down to 1 µs, which no
/// device meets (a write alone takes longer), so an implementation that bounds its waits always
/// times out by the last attempt.
const ATTEMPTS: [(u32, &str); 5] = [
    (200, "0.001"),
    (400, "0.001"),
    (800, "0.0001"),
    (800, "0.00001"),
    (800, "0.000001"),
];

/// Eight point lights around the sphere.
fn lights() -> Vec<Light> {
    (0..8)
        .map(|i| {
            let a = i as f32 * 0.785;
            Light::point(glam::Vec3::new(
                3.0 * a.cos(),
                1.0 + 0.2 * i as f32,
                3.0 * a.sin(),
            ))
        })
        .collect()
}

/// The message of a `Device` error, or a panic naming what came instead.
fn device_message(r: Result<impl std::fmt::Debug, BackendError>, what: &str) -> String {
    match r {
        Err(BackendError::Device { message, .. }) => message,
        other => panic!("{what}: expected BackendError::Device, got {other:?}"),
    }
}

/// Extracts with a tiny limit until an extraction times out, going through [`ATTEMPTS`] after
/// each extraction that finished in time. Returns the prepared scene, the scene, the limit and
/// the timeout message.
fn time_out(cl: &mut OpenClBackend) -> (PreparedId, TopologyScene, &'static str, String) {
    let lights = lights();
    let mut out = Multiplicities::default();
    for (attempt, (rings, tiny)) in ATTEMPTS.into_iter().enumerate() {
        let mesh = shapes::uv_sphere_y(rings, 2 * rings, 1.0);
        let scene = TopologyScene::single(EdgeTable::build(&mesh).expect("a UV sphere is valid"));
        let id = cl.prepare(&scene).expect("prepare");
        std::env::set_var(TIMEOUT_ENV, tiny);
        let t = Instant::now();
        let r = cl.extract(id, &lights, Accuracy::Exact, &mut out);
        let took = t.elapsed();
        std::env::remove_var(TIMEOUT_ENV);
        match r {
            Err(BackendError::Device { message, .. }) if message.contains("did not finish") => {
                eprintln!(
                    "attempt {attempt}: {} triangles, 8 lights: timed out after {took:?}: {message}",
                    mesh.triangles.len()
                );
                // Bounded: the limit plus the enqueues, not the kernel's run time.
                assert!(
                    took < Duration::from_secs(5),
                    "the timed-out extract took {took:?}"
                );
                return (id, scene, tiny, message);
            }
            Ok(_) => {
                eprintln!(
                    "attempt {attempt}: {} triangles finished within {tiny} s ({took:?})",
                    mesh.triangles.len()
                );
                cl.release(id);
            }
            Err(e) => panic!("attempt {attempt}: expected a timeout, got {e}"),
        }
    }
    panic!("no extraction timed out, with {TIMEOUT_ENV} down to 1e-6 (see ATTEMPTS)");
}

fn a_device_that_does_not_finish_in_time_is_an_error_and_the_backend_recovers() -> Outcome {
    let mut cl = shadowvol_test_support::started("OpenCL", OpenClBackend::new())?;
    let lights = lights();

    // 1. The timeout: a Device error naming the variable and its value.
    let (id, scene, tiny, message) = time_out(&mut cl);
    assert!(
        message.contains(TIMEOUT_ENV) && message.contains(tiny),
        "{message}"
    );

    // 2. The next extraction, still with the tiny limit, while the abandoned kernel runs: a clear
    //    Device error naming the variable (that the earlier kernel has not finished; or, should
    //    PoCL have finished it meanwhile, that this extraction's own kernel did not).
    std::env::set_var(TIMEOUT_ENV, tiny);
    let mut out = Multiplicities::default();
    let t = Instant::now();
    let again = cl.extract(id, &lights, Accuracy::Exact, &mut out);
    let took = t.elapsed();
    std::env::remove_var(TIMEOUT_ENV);
    let again = device_message(again, "the extract after a timeout");
    eprintln!("next extract ({took:?}): {again}");
    assert!(again.contains(TIMEOUT_ENV), "{again}");
    assert!(took < Duration::from_secs(5), "took {took:?}");

    // 3. A malformed limit is invalid input, naming the variable.
    std::env::set_var(TIMEOUT_ENV, "soon");
    let bad = cl.extract(id, &lights, Accuracy::Exact, &mut out);
    std::env::remove_var(TIMEOUT_ENV);
    match bad {
        Err(BackendError::InvalidInput(m)) => {
            assert!(m.contains(TIMEOUT_ENV) && m.contains("soon"), "{m}");
        }
        other => panic!("expected InvalidInput for {TIMEOUT_ENV}=soon, got {other:?}"),
    }

    // 4. With the default limit the backend waits for the abandoned work, then recovers: the
    //    same scene gives exactly the cpu backend's results.
    let t = Instant::now();
    let stats = cl
        .extract(id, &lights, Accuracy::Exact, &mut out)
        .expect("the backend recovers once the abandoned work has finished");
    let full = t.elapsed();
    let (want, _) = extract_once(&mut CpuBackend::new(), &scene, &lights, Accuracy::Exact)
        .expect("cpu extraction");
    assert_eq!(out.light_count(), lights.len());
    for l in 0..lights.len() {
        assert!(
            out.values(l) == want.values(l),
            "light {l} differs from cpu"
        );
        assert!(!out.silhouette(l).is_empty(), "light {l}: no silhouette");
    }
    eprintln!("recovered: {full:?} ({stats:?})");
    // A second full extract on the recovered backend is fine too.
    let t = Instant::now();
    cl.extract(id, &lights, Accuracy::Exact, &mut out)
        .expect("extract after recovery");
    let kernel_time = t.elapsed();

    // 5. Dropping a backend whose work has timed out returns without waiting for the device.
    std::env::set_var(TIMEOUT_ENV, tiny);
    let r = cl.extract(id, &lights, Accuracy::Exact, &mut out);
    std::env::remove_var(TIMEOUT_ENV);
    let m = device_message(r, "the second timeout");
    assert!(m.contains(TIMEOUT_ENV), "{m}");
    let t = Instant::now();
    drop(cl);
    let dropped = t.elapsed();
    eprintln!("dropped with unfinished work in {dropped:?} (a full extract takes {kernel_time:?})");
    assert!(dropped < Duration::from_secs(1), "drop took {dropped:?}");
    // Let the abandoned kernel end before the process exits (the driver's exit-time destructors
    // should not race its worker threads).
    std::thread::sleep(kernel_time * 2 + Duration::from_millis(100));
    Ok(())
}
