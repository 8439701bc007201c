//! Times the wgpu backend on paper scenes: one dispatch for many objects versus the same
//! triangles baked into one object, and the upload / compute / readback split.
//!
//! ```text
//! cargo run --release -p shadowvol-wgpu-compute --example batching -- [FRAMES] [SCENE ...]
//! ```
//!
//! Scenes are `shadowvol-scenes` presets; `NAME` alone runs the preset as is, `NAME@baked` its
//! baked version. Default: `spheres-100x1k spheres-100x1k@baked sphere-100k`. Needs a wgpu
//! adapter. The official numbers come from `shadowvol bench`; this is for checking batching.

use shadowvol_silhouette::{Accuracy, ExtractStats, Multiplicities, SilhouetteBackend};
use shadowvol_wgpu_compute::{WgpuBackend, WgpuOptions};
use std::time::{Duration, Instant};

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    let i = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted[i]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // No `error: XDG_RUNTIME_DIR ...` line from Mesa on a machine without a display.
    shadowvol_silhouette::gpu::quiet_without_display();
    let mut args = std::env::args().skip(1);
    let frames: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(30);
    let mut names: Vec<String> = args.collect();
    if names.is_empty() {
        names = ["spheres-100x1k", "spheres-100x1k@baked", "sphere-100k"]
            .map(String::from)
            .to_vec();
    }
    let mut backend = WgpuBackend::new(WgpuOptions::default())?;
    let info = backend.info();
    println!("device: {}", info.device);
    println!("details: {:?}", info.details);
    println!("scene,mode,objects,triangles,edges,lights,silhouette_edges,median_ms,p10_ms,p90_ms,upload_ms,compute_ms,readback_ms,host_ms,uncertain");
    for name in &names {
        let (preset, baked) = match name.strip_suffix("@baked") {
            Some(p) => (p, true),
            None => (name.as_str(), false),
        };
        let mut scene = shadowvol_scenes::preset(preset)?;
        if baked {
            scene = scene.baked()?;
        }
        let topo = &scene.geometry;
        let lights = scene.light_positions();
        let id = backend.prepare(topo)?;
        let mut out = Multiplicities::default();
        for mode in Accuracy::ALL {
            for _ in 0..3 {
                backend.extract(id, &lights, mode, &mut out)?;
            }
            let mut times = Vec::with_capacity(frames);
            let mut sum = ExtractStats::default();
            for _ in 0..frames {
                let t = Instant::now();
                let s = backend.extract(id, &lights, mode, &mut out)?;
                times.push(ms(t.elapsed()));
                sum.upload += s.upload;
                sum.compute += s.compute;
                sum.readback += s.readback;
                sum.host_resolve += s.host_resolve;
                sum.uncertain += s.uncertain;
            }
            times.sort_by(f64::total_cmp);
            let n = frames as f64;
            println!(
                "{name},{mode},{},{},{},{},{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{}",
                topo.objects.len(),
                topo.total_triangles(),
                topo.total_edges(),
                lights.len(),
                (0..lights.len())
                    .map(|l| out.silhouette(l).len())
                    .sum::<usize>(),
                percentile(&times, 0.5),
                percentile(&times, 0.1),
                percentile(&times, 0.9),
                ms(sum.upload) / n,
                ms(sum.compute) / n,
                ms(sum.readback) / n,
                ms(sum.host_resolve) / n,
                sum.uncertain / frames as u64,
            );
        }
        backend.release(id);
    }
    Ok(())
}
