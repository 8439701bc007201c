//! The whole conformance corpus on the `vulkan` backend: exact against the `cpu` reference, the
//! f32 modes against the independent reference of `tests/support/values.rs`.

mod common;
#[path = "../../../tests/support/values.rs"]
mod values;

use shadowvol_cpu::CpuBackend;
use shadowvol_silhouette::gpu::ExactFilter;
use shadowvol_silhouette::{extract_once, invariant, Accuracy, Multiplicities, SilhouetteBackend};
use shadowvol_test_support::corpus;
use shadowvol_test_support::{main, Outcome};
use shadowvol_vulkan_geometry::twin;
use shadowvol_vulkan_geometry::{VulkanBackend, VulkanOptions};
use values::Rule;

main!(
    corpus_on_vulkan_f64_filter,
    corpus_on_vulkan_f32_filter,
    twin_matches_cpu_on_corpus
);

fn run_corpus(vk: &mut VulkanBackend, test: &str) {
    let mut cpu = CpuBackend::new();
    let cases = corpus::cases();
    assert!(!cases.is_empty());
    let mut uncertain = 0;
    let rule = Rule::for_device(&vk.info().device);
    eprintln!("{test}: f32 modes compared by the {} rule", rule.name());
    for case in &cases {
        let scene = case.scene().unwrap();
        for mode in Accuracy::ALL {
            let (want, _) = extract_once(&mut cpu, &scene, &case.lights, mode).unwrap();
            let (got, stats) = extract_once(vk, &scene, &case.lights, mode)
                .unwrap_or_else(|e| panic!("{test}: {} {mode}: {e}", case.name));
            assert!(got.silhouettes_consistent(), "{} {mode}", case.name);
            for l in 0..case.lights.len() {
                if mode.is_consistent() {
                    assert_eq!(
                        invariant::open_vertices_scene(&scene, &got, l),
                        0,
                        "{test}: {} {mode} light {l}: open vertices on vulkan",
                        case.name
                    );
                }
            }
            if mode == Accuracy::Exact {
                uncertain += stats.uncertain;
                assert_eq!(
                    invariant::first_difference(&got, &want),
                    None,
                    "{test}: {} exact: vulkan differs from cpu (light, edge, vulkan, cpu); {} uncertain",
                    case.name,
                    stats.uncertain
                );
            } else {
                // The f32 modes run the same expression with `precise`: bit for bit against the
                // independent reference where the device does not contract (lavapipe), else on
                // the certified edges; the certified comparison holds everywhere.
                let reference = values::reference(&scene, &case.lights, mode);
                for r in [Rule::Certified, rule] {
                    values::check(&scene, &case.lights, mode, r, &reference, &got).unwrap_or_else(
                        |e| panic!("{test}: {} ({} rule): {e}", case.name, r.name()),
                    );
                }
            }
        }
    }
    eprintln!(
        "{test}: {} corpus cases; exact mode resolved {uncertain} uncertain pairs on the host",
        cases.len()
    );
}

fn corpus_on_vulkan_f64_filter() -> Outcome {
    let mut vk = common::backend(VulkanOptions::default())?;
    run_corpus(&mut vk, "default filter");
    Ok(())
}

fn corpus_on_vulkan_f32_filter() -> Outcome {
    let opts = VulkanOptions {
        force_f32_filter: true,
        ..VulkanOptions::default()
    };
    let mut vk = common::backend(opts)?;
    assert_eq!(vk.exact_filter(), ExactFilter::F32);
    run_corpus(&mut vk, "f32 filter");
    Ok(())
}

fn twin_matches_cpu_on_corpus() -> Outcome {
    let mut cpu = CpuBackend::new();
    for case in corpus::cases() {
        let scene = case.scene().unwrap();
        for mode in Accuracy::ALL {
            let (want, _) = extract_once(&mut cpu, &scene, &case.lights, mode).unwrap();
            for filter in [ExactFilter::F64, ExactFilter::F32] {
                let mut got = Multiplicities::default();
                twin::extract(&scene, &case.lights, mode, filter, &mut got).unwrap();
                assert_eq!(
                    invariant::first_difference(&got, &want),
                    None,
                    "{} {mode} {filter:?}",
                    case.name
                );
            }
        }
    }
    Ok(())
}
