//! Runs the conformance corpus and a few timings on whatever Vulkan device is here, and prints a
//! report: exact identical to cpu, open vertices in robust/ordered, uncertain pairs, and median
//! extraction times (upload / compute / readback) against the cpu backend.
//!
//! `cargo run -p shadowvol-vulkan-geometry --example device_report [-- PRESET ...]`

use shadowvol_cpu::CpuBackend;
use shadowvol_silhouette::{
    extract_once, invariant, Accuracy, ExtractStats, Multiplicities, SilhouetteBackend,
    TopologyScene,
};
use shadowvol_test_support::corpus;
use shadowvol_vulkan_geometry::{VulkanBackend, VulkanOptions};
use std::time::{Duration, Instant};

fn corpus_report(vk: &mut VulkanBackend, label: &str) -> bool {
    let mut cpu = CpuBackend::new();
    let (mut exact_diff, mut open, mut f32_diff, mut uncertain, mut cases) = (0, 0, 0, 0u64, 0);
    for case in corpus::cases() {
        cases += 1;
        let scene = case.scene().expect("corpus scene");
        for mode in Accuracy::ALL {
            let (want, _) = extract_once(&mut cpu, &scene, &case.lights, mode).expect("cpu");
            let (got, stats) = extract_once(vk, &scene, &case.lights, mode).expect("vulkan");
            for l in 0..case.lights.len() {
                let d = invariant::differing_edges(&got, &want, l);
                match mode {
                    Accuracy::Exact => exact_diff += d,
                    _ => f32_diff += d,
                }
                if matches!(mode, Accuracy::Robust | Accuracy::Ordered) {
                    open += invariant::open_vertices_scene(&scene, &got, l);
                }
            }
            uncertain += stats.uncertain;
        }
    }
    println!(
        "[{label}] corpus: {cases} cases; exact edges differing from cpu: {exact_diff}; open vertices \
         (robust+ordered): {open}; f32-mode edges differing from cpu: {f32_diff}; uncertain pairs \
         resolved on the host: {uncertain}"
    );
    exact_diff == 0 && open == 0
}

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

fn time(
    b: &mut dyn SilhouetteBackend,
    scene: &TopologyScene,
    lights: &[shadowvol_silhouette::Light],
    mode: Accuracy,
    frames: usize,
) -> (Duration, ExtractStats) {
    let id = b.prepare(scene).expect("prepare");
    let mut out = Multiplicities::default();
    for _ in 0..3 {
        b.extract(id, lights, mode, &mut out).expect("extract");
    }
    let mut totals = Vec::new();
    let mut parts = Vec::new();
    for _ in 0..frames {
        let t = Instant::now();
        let s = b.extract(id, lights, mode, &mut out).expect("extract");
        totals.push(t.elapsed());
        parts.push(s);
    }
    b.release(id);
    parts.sort_by_key(|s| s.compute);
    (median(totals), parts[parts.len() / 2])
}

fn main() {
    // No `error: XDG_RUNTIME_DIR ...` line from Mesa on a machine without a display.
    shadowvol_silhouette::gpu::quiet_without_display();
    let mut vk = match VulkanBackend::new(VulkanOptions::from_env()) {
        Ok(v) => v,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    println!("device: {}", vk.info().device);
    println!("details: {:?}", vk.info().details);
    let label = format!("{} filter", vk.exact_filter().name());
    let mut ok = corpus_report(&mut vk, &label);
    let mut vk32 = VulkanBackend::new(VulkanOptions {
        force_f32_filter: true,
        ..VulkanOptions::from_env()
    })
    .expect("second device");
    ok &= corpus_report(&mut vk32, "f32 filter");
    drop(vk32);

    let presets: Vec<String> = std::env::args().skip(1).collect();
    let presets = if presets.is_empty() {
        vec!["sphere-100k".to_owned()]
    } else {
        presets
    };
    let mut cpu = CpuBackend::new();
    for name in presets {
        let s = shadowvol_scenes::preset(&name).expect("preset");
        let scene = &s.geometry;
        let lights = s.light_positions();
        println!(
            "{name}: {} objects, {} triangles, {} edges, {} lights",
            scene.objects.len(),
            scene.total_triangles(),
            scene.total_edges(),
            s.lights.len()
        );
        for mode in Accuracy::ALL {
            let (vt, vs) = time(&mut vk, scene, &lights, mode, 15);
            let (ct, _) = time(&mut cpu, scene, &lights, mode, 3);
            println!(
                "  {mode:8} vulkan median {:8.3} ms (upload {:.3}, compute {:.3}, readback {:.3}, host resolve {:.3} ms, {} uncertain) | cpu {:8.3} ms | cpu/vulkan {:.1}x",
                vt.as_secs_f64() * 1e3,
                vs.upload.as_secs_f64() * 1e3,
                vs.compute.as_secs_f64() * 1e3,
                vs.readback.as_secs_f64() * 1e3,
                vs.host_resolve.as_secs_f64() * 1e3,
                vs.uncertain,
                ct.as_secs_f64() * 1e3,
                ct.as_secs_f64() / vt.as_secs_f64()
            );
        }
    }
    let msgs = vk.validation_messages();
    if !msgs.is_empty() {
        println!("validation messages:\n{}", msgs.join("\n"));
        ok = false;
    }
    if !ok {
        std::process::exit(1);
    }
}
