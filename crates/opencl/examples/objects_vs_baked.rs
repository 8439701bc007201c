//! Per-object overhead of the `opencl` backend: a preset scene as separate objects (one enqueue
//! for all of them) against the same scene baked into one mesh.
//!
//! ```text
//! cargo run --release -p shadowvol-opencl --example objects_vs_baked -- [PRESET] [FRAMES]
//! ```
//!
//! Defaults: `spheres-100x1k`, 50 frames. With `EXPORT_BAKED=FILE.glb` it only writes the
//! baked scene (for `shadowvol bench --scene FILE.glb`). Prints, per mode, the median / p10 / p90 of the total
//! extraction time and its upload / compute / readback / host split, and the individual/baked
//! ratio. Also checks that exact results equal the `cpu` backend's.

use shadowvol_opencl::OpenClBackend;
use shadowvol_silhouette::{
    Accuracy, ExtractStats, Multiplicities, SilhouetteBackend, TopologyScene,
};
use std::time::Duration;

fn percentile(sorted: &[Duration], p: f64) -> f64 {
    let i = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted[i].as_secs_f64() * 1e3
}

struct Summary {
    median: f64,
    p10: f64,
    p90: f64,
    parts: [f64; 4],
}

/// Extracts `frames` times from each prepared scene, interleaved frame by frame (so that drift in
/// machine load affects both alike), after 3 warm-up frames each.
fn measure(
    cl: &mut OpenClBackend,
    scenes: [&TopologyScene; 2],
    lights: &[shadowvol_silhouette::Light],
    mode: Accuracy,
    frames: usize,
) -> Result<([Summary; 2], Multiplicities), Box<dyn std::error::Error>> {
    let ids = [cl.prepare(scenes[0])?, cl.prepare(scenes[1])?];
    let mut outs = [Multiplicities::default(), Multiplicities::default()];
    let mut stats: [Vec<ExtractStats>; 2] = [Vec::new(), Vec::new()];
    for frame in 0..frames + 3 {
        for k in 0..2 {
            let s = cl.extract(ids[k], lights, mode, &mut outs[k])?;
            if frame >= 3 {
                stats[k].push(s);
            }
        }
    }
    for id in ids {
        cl.release(id);
    }
    let summary = |stats: &[ExtractStats]| {
        let med = |f: &dyn Fn(&ExtractStats) -> Duration| {
            let mut v: Vec<Duration> = stats.iter().map(f).collect();
            v.sort();
            percentile(&v, 0.5)
        };
        let mut totals: Vec<Duration> = stats.iter().map(ExtractStats::total).collect();
        totals.sort();
        Summary {
            median: percentile(&totals, 0.5),
            p10: percentile(&totals, 0.1),
            p90: percentile(&totals, 0.9),
            parts: [
                med(&|s| s.upload),
                med(&|s| s.compute),
                med(&|s| s.readback),
                med(&|s| s.host_resolve),
            ],
        }
    };
    let [first, _] = outs;
    Ok(([summary(&stats[0]), summary(&stats[1])], first))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let name = args.next().unwrap_or_else(|| "spheres-100x1k".to_owned());
    let frames: usize = args.next().map_or(Ok(50), |s| s.parse())?;
    let scene = shadowvol_scenes::preset(&name)?;
    if let Ok(path) = std::env::var("EXPORT_BAKED") {
        // For `shadowvol bench --scene FILE.glb`: the same scene baked into one mesh.
        shadowvol_scenes::export_glb(&scene.baked()?, &path)?;
        println!("wrote the baked scene to {path}");
        return Ok(());
    }
    let individual = scene.geometry.clone();
    let baked = scene.baked()?.geometry;
    let lights = scene.light_positions();
    let mut cl = OpenClBackend::with_options(shadowvol_opencl::OpenClOptions::from_env())?;
    println!("device: {}", cl.info().device);
    println!(
        "scene {name}: {} objects, {} triangles, {} edges, {} lights; {frames} frames",
        individual.objects.len(),
        individual.total_triangles(),
        individual.total_edges(),
        lights.len()
    );
    println!("mode      layout      median_ms  p10_ms  p90_ms | upload compute readback host (median ms)");
    for mode in Accuracy::ALL {
        let ([ind, bak], m_ind) = measure(&mut cl, [&individual, &baked], &lights, mode, frames)?;
        for (layout, s) in [("individual", &ind), ("baked", &bak)] {
            println!(
                "{:<9} {layout:<11} {:>9.3} {:>7.3} {:>7.3} | {:>6.3} {:>7.3} {:>8.3} {:>5.3}",
                mode.name(),
                s.median,
                s.p10,
                s.p90,
                s.parts[0],
                s.parts[1],
                s.parts[2],
                s.parts[3]
            );
        }
        println!(
            "{:<9} individual/baked = {:.3}",
            mode.name(),
            ind.median / bak.median
        );
        if mode == Accuracy::Exact {
            let (want, _) = shadowvol_silhouette::extract_once(
                &mut shadowvol_cpu::CpuBackend::new(),
                &individual,
                &lights,
                mode,
            )?;
            assert_eq!(m_ind, want, "exact result differs from cpu");
            println!("exact: identical to cpu");
        }
    }
    Ok(())
}
