//! Light splitting: `extract` with at most 1, 2 or 3 lights per geometry-shader pass gives the
//! same result as one pass: `exact` bit-identical to the `cpu` backend, 0 open vertices in
//! `robust` and `ordered`, and the statistics summed over the passes. A scene whose static
//! buffers exceed the (pretended) `maxStorageBufferRange` is prepared in parts, with the same
//! results as the whole scene.

mod common;

use shadowvol_cpu::CpuBackend;
use shadowvol_silhouette::{extract_once, invariant, Accuracy, Multiplicities, SilhouetteBackend};
use shadowvol_test_support::corpus;
use shadowvol_test_support::{main, Outcome};
use shadowvol_vulkan_geometry::VulkanOptions;
use std::num::NonZeroUsize;

main!(
    corpus_split_into_light_batches_matches_one_pass_and_cpu,
    uncertain_pairs_resolve_into_their_own_light_across_batches,
    scene_beyond_the_storage_range_is_prepared_in_parts
);

fn corpus_split_into_light_batches_matches_one_pass_and_cpu() -> Outcome {
    let mut whole = common::backend(VulkanOptions::from_env())?;
    let mut cpu = CpuBackend::new();
    let cases = corpus::multi_light_cases(3);
    let mut split_runs = 0;
    for per_pass in [1, 2, 3] {
        let opts = VulkanOptions {
            max_lights_per_batch: NonZeroUsize::new(per_pass),
            ..VulkanOptions::from_env()
        };
        let mut vk = common::backend(opts)?;
        for case in &cases {
            let scene = case.scene().unwrap();
            let n = case.lights.len();
            let id = vk.prepare(&scene).unwrap();
            for mode in Accuracy::ALL {
                let what = format!("{} {mode}, {per_pass} light(s) per pass", case.name);
                let mut got = Multiplicities::default();
                let stats = vk
                    .extract(id, &case.lights, mode, &mut got)
                    .unwrap_or_else(|e| panic!("{what}: {e}"));
                assert_eq!(
                    vk.passes_of_last_extract_for_tests(),
                    n.div_ceil(per_pass),
                    "{what}: {n} lights should take that many passes"
                );
                split_runs += usize::from(n > per_pass);
                let (one, one_stats) = extract_once(&mut whole, &scene, &case.lights, mode)
                    .unwrap_or_else(|e| panic!("{what} (one pass): {e}"));
                assert_eq!(whole.passes_of_last_extract_for_tests(), 1, "{what}");
                let want = (mode == Accuracy::Exact).then(|| {
                    extract_once(&mut cpu, &scene, &case.lights, mode)
                        .unwrap()
                        .0
                });
                invariant::check_split_batches(
                    &scene,
                    mode,
                    (&got, &stats),
                    (&one, &one_stats),
                    want.as_ref(),
                )
                .unwrap_or_else(|e| panic!("{what}: {e}"));
            }
            vk.release(id);
        }
        assert!(
            vk.validation_messages().is_empty(),
            "validation messages:\n{}",
            vk.validation_messages().join("\n")
        );
    }
    assert!(split_runs > 0, "no extraction was actually split");
    Ok(())
}

/// Uncertain pairs of a later batch land in that batch's lights: a case whose exact mode needs
/// host resolution for several lights, one light per pass.
fn uncertain_pairs_resolve_into_their_own_light_across_batches() -> Outcome {
    let opts = VulkanOptions {
        max_lights_per_batch: NonZeroUsize::new(1),
        ..VulkanOptions::from_env()
    };
    let mut vk = common::backend(opts)?;
    let mut cpu = CpuBackend::new();
    let mut uncertain_in_split = 0;
    for case in corpus::cases().iter().filter(|c| c.lights.len() >= 2) {
        let scene = case.scene().unwrap();
        // Reverse the lights too, so a light's uncertain pairs come from a different batch index.
        let mut lights = case.lights.clone();
        lights.reverse();
        for lights in [&case.lights, &lights] {
            let (got, stats) = extract_once(&mut vk, &scene, lights, Accuracy::Exact).unwrap();
            let (want, _) = extract_once(&mut cpu, &scene, lights, Accuracy::Exact).unwrap();
            assert_eq!(
                invariant::first_difference(&got, &want),
                None,
                "{}: one light per pass differs from cpu",
                case.name
            );
            uncertain_in_split += stats.uncertain;
        }
    }
    assert!(
        uncertain_in_split > 0,
        "the corpus should need host resolution somewhere (degenerate lights)"
    );
    Ok(())
}

/// With static buffers pretended to exceed `maxStorageBufferRange` above a third of a scene's
/// edge records, the scene is cut into parts; every mode gives the bits of the whole scene on
/// the same device (and, exact, of `cpu`), silhouettes included.
fn scene_beyond_the_storage_range_is_prepared_in_parts() -> Outcome {
    let mut whole = common::backend(VulkanOptions::from_env())?;
    let mut cut = common::backend(VulkanOptions::from_env())?;
    shadowvol_test_support::parts::check_parts_equal_whole(
        &mut cut,
        &mut whole,
        &mut CpuBackend::new(),
        |cut, scene, limit| {
            cut.set_part_limit_for_tests(limit);
            cut.prepare(scene).unwrap()
        },
    );
    Ok(())
}
