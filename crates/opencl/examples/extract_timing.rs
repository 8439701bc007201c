//! Extraction timings of the `opencl` backend on UV spheres of growing size: the median and p10 /
//! p90 of the whole `extract` and of its compute and readback parts, per size and mode. Used to
//! check that the bounded device waits (polling with `SHADOWVOL_GPU_TIMEOUT` as the limit) cost no
//! more than `clFinish` did.
//!
//! ```text
//! cargo run --release -p shadowvol-opencl --example extract_timing -- [FRAMES] [LIGHTS]
//! ```
//!
//! Defaults: 30 frames (after 3 warm-up frames), 1 light. With `SIZES=small` only the 10^4
//! triangle sphere runs, `SIZES=large` only 10^5 and 10^6.

use shadowvol_mesh_topology::EdgeTable;
use shadowvol_opencl::OpenClBackend;
use shadowvol_silhouette::{Accuracy, Light, Multiplicities, SilhouetteBackend, TopologyScene};
use shadowvol_test_support::shapes;
use std::time::{Duration, Instant};

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let frames: usize = args.next().map_or(Ok(30), |a| a.parse())?;
    let num_lights: usize = args.next().map_or(Ok(1), |a| a.parse())?;
    let mut cl = OpenClBackend::new()?;
    println!("device: {}", cl.device().describe());
    println!(
        "triangles  lights  mode      total median (p10-p90) ms   upload   compute   readback   (medians, ms)"
    );
    let sizes: &[(u32, u32)] = match std::env::var("SIZES").as_deref() {
        Ok("small") => &[(50, 100)],
        Ok("large") => &[(200, 250), (500, 1000)],
        _ => &[(50, 100), (200, 250), (500, 1000)],
    };
    for &(rings, segments) in sizes {
        let mesh = shapes::uv_sphere_y(rings, segments, 1.0);
        let triangles = mesh.triangles.len();
        let scene = TopologyScene::single(EdgeTable::build(&mesh)?);
        let lights: Vec<Light> = (0..num_lights)
            .map(|i| Light::point(glam::Vec3::new(3.0 + i as f32, 2.0, 1.5 - i as f32)))
            .collect();
        let id = cl.prepare(&scene)?;
        for mode in [Accuracy::Robust, Accuracy::Exact] {
            let mut out = Multiplicities::default();
            let mut total = Vec::new();
            let mut compute = Vec::new();
            let mut upload = Vec::new();
            let mut readback = Vec::new();
            for f in 0..frames + 3 {
                let t = Instant::now();
                let s = cl.extract(id, &lights, mode, &mut out)?;
                let el = t.elapsed();
                if f >= 3 {
                    total.push(el);
                    compute.push(s.compute);
                    upload.push(s.upload);
                    readback.push(s.readback);
                }
            }
            for v in [&mut total, &mut upload, &mut compute, &mut readback] {
                v.sort();
            }
            let q = |v: &[Duration], p: f64| ms(v[((v.len() - 1) as f64 * p).round() as usize]);
            println!(
                "{triangles:>9}  {num_lights:>6}  {:<8}  {:>8.3} ({:.3}-{:.3})   {:>7.3}  {:>8.3}  {:>8.3}",
                format!("{mode:?}"),
                q(&total, 0.5),
                q(&total, 0.1),
                q(&total, 0.9),
                q(&upload, 0.5),
                q(&compute, 0.5),
                q(&readback, 0.5),
            );
        }
        cl.release(id);
    }
    Ok(())
}
