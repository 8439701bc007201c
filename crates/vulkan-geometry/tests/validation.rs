//! The corpus under `VK_LAYER_KHRONOS_validation`: no validation message allowed.
//!
//! Needs the layer (Debian/Ubuntu: `apt-get install vulkan-validationlayers`). Without it the
//! test fails under `CI=true` and is ignored with the reason otherwise.

mod common;

use shadowvol_cpu::CpuBackend;
use shadowvol_silhouette::{extract_once, invariant, Accuracy};
use shadowvol_test_support::corpus;
use shadowvol_test_support::{main, Outcome};
use shadowvol_vulkan_geometry::VulkanOptions;

main!(
    corpus_under_validation_layers,
    validation_layer_reports_misuse
);

fn corpus_under_validation_layers() -> Outcome {
    let opts = VulkanOptions {
        validation: true,
        ..VulkanOptions::default()
    };
    let mut vk = common::backend(opts)?;
    assert!(vk.validation_enabled());
    let mut cpu = CpuBackend::new();
    let cases = corpus::cases();
    for case in &cases {
        let scene = case.scene().unwrap();
        for mode in Accuracy::ALL {
            let (got, _) = extract_once(&mut vk, &scene, &case.lights, mode).unwrap();
            if mode == Accuracy::Exact {
                let (want, _) = extract_once(&mut cpu, &scene, &case.lights, mode).unwrap();
                assert_eq!(
                    invariant::first_difference(&got, &want),
                    None,
                    "{}",
                    case.name
                );
            }
        }
    }
    let messages = vk.validation_messages();
    assert!(
        messages.is_empty(),
        "validation messages:\n{}",
        messages.join("\n")
    );
    Ok(())
}

/// The layer reports real misuse: a deliberately wrong call produces a message, so an empty log
/// above means something.
fn validation_layer_reports_misuse() -> Outcome {
    let opts = VulkanOptions {
        validation: true,
        ..VulkanOptions::default()
    };
    let vk = common::backend(opts)?;
    assert!(vk.provoke_validation_error_for_tests());
    assert!(!vk.validation_messages().is_empty());
    Ok(())
}
